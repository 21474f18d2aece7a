"""Issue 41 §6: bad input from Python is refused by keyword.

* `Scene.mu` refuses what is not a number (None, strings, bools, complex,
  arrays of strings or objects) with a TypeError naming `v0`, instead of
  numpy's reading ("0.01" → 0.01, None → NaN);
* integers out of range (`steps_per_period=-5`, `2**70`) name the keyword
  (pyo3's own OverflowError did not);
* `fit(None)`, `fit(5)` and a `params` that is not text are TypeErrors
  naming the keyword (they were `AttributeError: '__contains__'`);
* every library refusal leads with the Python keyword, then the CLI's text;
* `Scene.mu` over many velocities grows the peak memory by no more than twice
  its result (measured in a fresh process: ru_maxrss, which sees Rust's
  allocations, unlike tracemalloc).
"""

import math
import pathlib
import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest

import fricctl

PAPER = dict(mu0=0.3, kz=2e6, kx=1.5e6, uz0=5e-6, duz=2e-6, dux=0.7e-6, freq=40e3, phi_deg=50.0)
S = fricctl.Scene(**PAPER)


@pytest.mark.parametrize("bad", [None, "0.01", b"0.01", True, np.bool_(True), 1j, np.complex128(1),
                                 [0.01, "a"], [0.01, None], {"v": 0.01}, {0.01}, object(),
                                 np.array(["0.01"]), np.array([0.01], dtype=object)],
                         ids=lambda v: type(v).__name__ + ":" + repr(v)[:20])
def test_mu_refuses_what_is_not_a_number(bad):
    with pytest.raises(TypeError, match=r"^v0: expected a number or an array of numbers, got "):
        S.mu(bad)
    with pytest.raises(TypeError, match=r"^v0: "):
        S.mu(bad, errors="nan")


def test_mu_takes_numbers_of_every_kind_and_keeps_the_shape():
    want = S.mu(0.01)
    assert S.mu(np.float32(0.01)) == S.mu(float(np.float32(0.01)))
    assert S.mu(1) == S.mu(1.0) == S.mu(np.int64(1))
    # A 0-d array stays 0-d; lists, tuples, F-ordered and strided arrays give
    # the same μ at the same places.
    z = S.mu(np.array(0.01))
    assert isinstance(z, np.ndarray) and z.shape == () and z[()] == want
    v = np.linspace(0.001, 0.2, 12).reshape(3, 4)
    c = S.mu(v)
    assert c.shape == (3, 4)
    assert np.array_equal(S.mu(np.asfortranarray(v)), c)
    assert np.array_equal(S.mu(v.T), c.T)
    assert np.array_equal(S.mu(v.tolist()), c)
    assert np.array_equal(S.mu(np.arange(1, 5, dtype=np.int32)), S.mu(np.arange(1.0, 5.0)))
    assert S.mu([]).shape == (0,)


def test_mu_reports_the_first_bad_element_in_order():
    # Two bad elements far apart in a long array: the first (C order) is the
    # one named, whichever thread met it first.
    v = np.full(50_000, 0.01)
    v[41_000] = np.inf
    v[7] = np.nan
    with pytest.raises(ValueError, match=r"^v0: --v0: 'NaN' is not a number \(at v0\[7\]\)$"):
        S.mu(v)
    with pytest.warns(RuntimeWarning, match=r"NaN returned at 2 point\(s\); the first: v0: --v0: 'NaN'"):
        out = S.mu(v, errors="nan")
    assert np.isnan(out[7]) and np.isnan(out[41_000])
    assert np.count_nonzero(np.isnan(out)) == 2 and out[0] == S.mu(0.01)


@pytest.mark.parametrize("n,exc,text", [
    (-5, ValueError, "steps_per_period: must be ≥ 1 (got -5)"),
    (0, ValueError, "steps_per_period: must be ≥ 1 (got 0)"),
    (2**70, OverflowError, f"steps_per_period: must be ≤ 4294967295 (got {2**70})"),
    (-(2**70), ValueError, f"steps_per_period: must be ≥ 1 (got {-(2**70)})"),
])
def test_steps_per_period_out_of_range_names_the_keyword(n, exc, text):
    with pytest.raises(exc) as e:
        S.mu(0.01, method="fixed", steps_per_period=n)
    assert str(e.value) == text


@pytest.mark.parametrize("bad", [2.0, True, "100", [100]], ids=repr)
def test_steps_per_period_must_be_an_integer(bad):
    with pytest.raises(TypeError, match=r"steps_per_period"):
        S.mu(0.01, method="fixed", steps_per_period=bad)


def test_steps_per_period_takes_numpy_integers():
    assert S.mu(0.01, method="fixed", steps_per_period=np.int64(2000)) == \
        S.mu(0.01, method="fixed", steps_per_period=2000)


@pytest.mark.parametrize("bad", [None, 5, 2.5, [1, 2], (), b"sweep.csv"], ids=repr)
def test_fit_refuses_data_that_is_not_a_sweep(bad):
    with pytest.raises(TypeError, match=r"^data: expected a sweep file path, a dict of arrays or a pandas DataFrame, got "):
        fricctl.fit(bad)


def test_fit_refuses_columns_that_are_not_numbers():
    cols = {k: [1.0, 2.0] for k in ["freq_hz", "amp_z", "amp_x", "offset_z", "phi_deg", "v0",
                                    "model_mu0", "model_kz", "model_kx", "measured_mu"]}
    cols["amp_z"] = ["2e-6", "2e-6"]
    with pytest.raises(TypeError, match=r"^data: column 'amp_z' must hold numbers \(got dtype <U4\)$"):
        fricctl.fit(cols)
    cols["amp_z"] = [None, 2e-6]
    with pytest.raises(TypeError, match=r"^data: column 'amp_z' must hold numbers \(got dtype object\)$"):
        fricctl.fit(cols)


@pytest.mark.parametrize("bad", [5, [1], ["mu0", 5], {"mu0"}], ids=repr)
def test_fit_refuses_params_that_are_not_names(bad):
    with pytest.raises(TypeError, match=r"^params: expected a string or a list of strings, got "):
        fricctl.fit({}, params=bad)


@pytest.mark.parametrize("kw,msg", [
    (dict(PAPER, mu0=-1.0), "mu0: --mu0: must be > 0 (got -1)"),
    (dict(PAPER, phi_deg=math.inf), "phi_deg: --phi-deg: must be of magnitude ≤ 1e100 (got inf)"),
    (dict(PAPER, kz=math.nan), "kz: --kz: 'NaN' is not a number"),
    (dict(PAPER, profile="blob"), "profile: --profile: invalid value 'blob' (one of: flat, sphere, cone, power)"),
])
def test_messages_lead_with_the_keyword_then_the_clis_text(kw, msg):
    with pytest.raises(ValueError) as e:
        fricctl.Scene(**kw)
    assert str(e.value) == msg


def test_keyword_type_errors_name_the_keyword():
    with pytest.raises(TypeError, match=r"argument 'mu0'"):
        fricctl.Scene(**dict(PAPER, mu0="0.3"))
    with pytest.raises(TypeError, match=r"argument 'liftoff'"):
        fricctl.Scene(**PAPER, liftoff="yes")
    with pytest.raises(TypeError, match=r"argument 'method'"):
        S.mu(0.01, method=5)


# ---- fit: rows of absurd values, and the goodness-of-fit verdict (§5) ----

def _rows(n=8, **override):
    """A sweep whose measured μ is the model's own (μ0 0.3, kx/kz 0.75) at
    phases 0…315°, σ = 1e-3."""
    phis = np.linspace(0.0, 315.0, n)
    cols = dict(value=phis, freq_hz=np.full(n, 40e3), amp_z=np.full(n, 2e-6),
                amp_x=np.full(n, 0.7e-6), offset_z=np.full(n, 5e-6), phi_deg=phis,
                v0=np.full(n, 0.01), model_mu0=np.full(n, 0.3), model_kz=np.full(n, 2e6),
                model_kx=np.full(n, 1.5e6), std_error=np.full(n, 1e-3))
    cols["measured_mu"] = np.array([fricctl.Scene(**dict(PAPER, phi_deg=float(p))).mu(0.01) for p in phis])
    for k, (i, v) in override.items():
        cols[k] = cols[k].copy()
        cols[k][i] = v
    return cols


def test_fit_refuses_a_row_of_absurd_values_by_name():
    with pytest.raises(ValueError, match=r"^data: --data: line 4: v0 must be of magnitude ≤ 1e100 \(got 1e300\)$"):
        fricctl.fit(_rows(v0=(2, 1e300)), params="mu0")
    # The 1e-300 was "not identifiable" (its weight overflowed JᵀJ):
    # beyond the flags' magnitude; 1e-20 is within it, but below what the
    # model resolves (1e-12·μ0: analysis::fit::STD_ERROR_FLOOR_OVER_MU0).
    with pytest.raises(ValueError, match=r"^data: --data: line 3: std_error must be 0 or of magnitude ≥ 1e-100 \(got 1e-300\)$"):
        fricctl.fit(_rows(std_error=(1, 1e-300)), params="mu0")
    with pytest.raises(ValueError, match=r"^data: --data: line 3: std_error 1e-20 is below what the model resolves \(3e-13 = 1e-12·model_mu0; 0 = unknown\)$"):
        fricctl.fit(_rows(std_error=(1, 1e-20)), params="mu0")
    # v0 1e50 is in the domain: the row slides (μ = μ0 there), 0.3 − 0.11
    # off at σ = 1e-3: χ² in the tens of thousands on 7 degrees of freedom,
    # flagged (the CLI: exit 1).
    with pytest.warns(RuntimeWarning, match=r"^doubtful: chi2 "):
        r = fricctl.fit(_rows(v0=(2, 1e50)), params="mu0")
    assert r.doubtful and r.chi2_p_value < 1e-6 and r.reduced_chi2 > 1000
    # At the floor the fit runs (the weight is finite).
    r = fricctl.fit(_rows(std_error=(1, 3e-13)), params="mu0")
    assert abs(r.mu0 - 0.3) <= 1e-9


def test_fit_of_data_the_model_describes_is_not_doubtful():
    # Measured = the model's μ at μ0 0.3: χ² ≈ 0 (the solver's error over
    # σ = 1e-3), p ≈ 1.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = fricctl.fit(_rows(), params="mu0")
    assert r.doubtful is None
    assert abs(r.mu0 - 0.3) <= 1e-9 and r.chi2 < 1e-12 and r.chi2_p_value > 0.999


def test_fit_with_a_chi2_beyond_its_quantile_is_doubtful():
    # One row 0.05 off with σ = 1e-3: χ² ≈ (50)²·(1 − 1/8) ≈ 2188 on 7
    # degrees of freedom (its 1 − 1e-6 quantile is 40.5): flagged.
    cols = _rows()
    cols["measured_mu"] = cols["measured_mu"].copy()
    cols["measured_mu"][3] += 0.05
    with pytest.warns(RuntimeWarning, match=r"^doubtful: chi2 .* on 7 degrees of freedom .* exceeds its 0\.999999 quantile 40\.52: the model does not describe the data within their standard errors"):
        r = fricctl.fit(cols, params="mu0")
    assert r.doubtful.startswith("doubtful: chi2 ")
    assert r.chi2_p_value < 1e-6
    # χ² of the one outlier: the least-squares μ0 moves to share it among the
    # rows (residual ≈ 0.05·(1 − 1/8) at the outlier), so χ² lies between
    # (0.05·7/8/σ)² and (0.05/σ)².
    assert (0.05 * 7 / 8 / 1e-3) ** 2 * 0.9 < r.chi2 < (0.05 / 1e-3) ** 2
    # Unweighted (no standard errors): no scale to judge χ² against.
    cols["std_error"] = np.zeros(8)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = fricctl.fit(cols, params="mu0")
    assert r.doubtful is None and r.chi2_p_value is None


# ---- memory (§6) ----

MEMORY_SCRIPT = textwrap.dedent("""
    import resource, sys
    import numpy as np
    import fricctl
    n = int(sys.argv[1])
    s = fricctl.Scene(mu0=0.3, kz=2e6, kx=1.5e6, uz0=5e-6, duz=2e-6, dux=0.7e-6, freq=40e3, phi_deg=50)
    v = np.linspace(-0.5, 0.5, n)
    v[n // 2] = 0.5
    s.mu(v[:1000])
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    r = s.mu(v, return_bound=sys.argv[2] == "1")
    after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    size = sum(a.nbytes for a in r) if isinstance(r, tuple) else r.nbytes
    print((after - before) * 1024, size)
""")


@pytest.mark.skipif(sys.platform != "linux", reason="ru_maxrss in KiB is Linux's")
@pytest.mark.parametrize("bound", ["0", "1"])
def test_mu_peak_memory_is_at_most_twice_the_result(bound):
    # 4e6 velocities: a 32 MB result (64 MB with the bounds), far above the
    # allocator's and the thread pool's own noise (a few MB).
    p = subprocess.run([sys.executable, "-c", MEMORY_SCRIPT, "4000000", bound],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    grown, size = map(int, p.stdout.split())
    assert grown <= 2 * size, f"peak RSS grew {grown / 1e6:.1f} MB for a {size / 1e6:.1f} MB result"
