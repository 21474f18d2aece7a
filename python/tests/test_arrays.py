"""Array and scalar calls: same values, same shapes; NaN and inf inputs."""

import warnings

import numpy as np
import pytest

import fricctl

S = fricctl.Scene(mu0=0.3, kz=2e6, kx=1.5e6, uz0=5e-6, duz=2e-6, dux=0.7e-6, freq=40e3, phi_deg=50)


def test_array_equals_scalar_calls_elementwise():
    v = np.linspace(-0.6, 0.6, 61)
    v = v[v != 0.0]
    arr = S.mu(v)
    assert arr.shape == v.shape and arr.dtype == np.float64
    assert all(arr[i] == S.mu(float(x)) for i, x in enumerate(v))
    mu, bound = S.mu(v, return_bound=True)
    assert mu.shape == bound.shape == v.shape
    assert np.all(bound >= 0) and np.all(np.abs(mu) <= 0.3)


@pytest.mark.parametrize("shape", [(0,), (1,), (7,), (3, 4), (2, 3, 2)])
def test_shapes_are_kept(shape):
    v = np.linspace(0.01, 0.5, int(np.prod(shape))).reshape(shape)
    out = S.mu(v)
    assert isinstance(out, np.ndarray) and out.shape == shape
    np.testing.assert_array_equal(out.ravel(), S.mu(v.ravel()))


def test_array_likes_and_scalars():
    assert isinstance(S.mu(0.01), float)
    assert isinstance(S.mu(1), float)  # an int is a number
    assert isinstance(S.mu(np.float64(0.01)), float)
    assert S.mu([0.01, 0.02]).shape == (2,)
    assert S.mu((0.01,)).shape == (1,)
    zero_d = S.mu(np.array(0.01))
    assert isinstance(zero_d, np.ndarray) and zero_d.shape == ()
    assert S.mu(np.array([0.01], dtype=np.float32))[0] == S.mu(float(np.float32(0.01)))
    # Non-contiguous input.
    v = np.linspace(0.01, 0.2, 20)[::3]
    np.testing.assert_array_equal(S.mu(v), S.mu(v.copy()))
    mu, b = S.mu(0.01, return_bound=True)
    assert isinstance(mu, float) and isinstance(b, float) and b >= 0


def test_zero_velocity_is_nan_with_a_pointer_to_mu_limits():
    with pytest.warns(RuntimeWarning, match=r"mu_limits\(\)"):
        assert np.isnan(S.mu(0.0))
    with pytest.warns(RuntimeWarning, match=r"mu_limits\(\)"):
        out = S.mu([0.01, 0.0, -0.0])
    assert not np.isnan(out[0]) and np.isnan(out[1]) and np.isnan(out[2])
    lo, hi = S.mu_limits()
    # μ(0±) are the limits of μ(v): μ(±1e-9) lies within the bound of them
    # (the law is continuous at 0⁺ and 0⁻ with slope O(1/v_c)).
    assert abs(S.mu(1e-9) - hi) < 1e-6 and abs(S.mu(-1e-9) - lo) < 1e-6
    lifting = fricctl.Scene(mu0=0.3, kz=2e6, kx=1.5e6, uz0=5e-6, duz=7e-6, dux=0.7e-6, freq=40e3, phi_deg=50)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m0 = lifting.mu(0.0)  # unique with lift-off: no warning, no NaN
    assert m0 == lifting.mu_limits()[0] == lifting.mu_limits()[1]


@pytest.mark.parametrize("bad,msg", [
    (float("nan"), "v0: --v0: 'NaN' is not a number"),
    (float("inf"), "v0: --v0: must be of magnitude ≤ 1e100 (got inf)"),
    (float("-inf"), "v0: --v0: must be of magnitude ≤ 1e100 (got -inf)"),
    (1e200, "v0: --v0: must be of magnitude ≤ 1e100 (got 1e200)"),
])
def test_nan_and_inf_inputs(bad, msg):
    with pytest.raises(ValueError) as e:
        S.mu(bad)
    assert str(e.value) == msg
    with pytest.raises(ValueError) as e:
        S.mu(np.array([[0.01, 0.02], [bad, 0.03]]))
    assert str(e.value) == msg + " (at v0[1, 0])"
    with pytest.warns(RuntimeWarning, match="NaN returned"):
        out = S.mu(np.array([0.01, bad]), errors="nan")
    assert out[0] == S.mu(0.01) and np.isnan(out[1])
    with pytest.warns(RuntimeWarning):
        assert np.isnan(S.mu(bad, errors="nan"))
