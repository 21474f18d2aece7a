"""μ and the other analyses against the CLI's JSON for the same scenes.

The package and the CLI call the same library, so agreement is expected to
the last bit; the stated tolerance (1e-10 absolute on μ, the issue's) leaves
room only for a decimal round trip of the inputs, which `repr` makes exact.
"""

import math

import numpy as np
import pytest

import fricctl
from conftest import flags

PAPER = dict(mu0=0.3, kz=2e6, kx=1.5e6, uz0=5e-6, duz=2e-6, dux=0.7e-6, freq=40e3, phi_deg=50.0)

SCENES = [
    PAPER,
    dict(PAPER, phi_deg=180.0),
    dict(PAPER, dux=0.0),  # normal only (eq. 21 applies)
    dict(PAPER, duz=0.0, dux=0.4e-6),  # tangential only (eq. 24 applies)
    dict(PAPER, duz=7e-6),  # lifts off once per period
    dict(duz_rel=0.5, dux_rel=0.8, phi_deg=90.0),  # dimensionless
    dict(PAPER, profile="sphere"),
    dict(PAPER, profile="power", exponent=1.5),
]

VELOCITIES = [1e-4, 0.01, -0.02, 0.1, -0.1, 0.3, 2.0]


def scene(kw):
    return fricctl.Scene(**kw)


@pytest.mark.parametrize("kw", SCENES, ids=lambda kw: ",".join(f"{k}={v}" for k, v in kw.items()))
@pytest.mark.parametrize("method", ["auto", "exact"])
def test_mu_matches_cli(cli, kw, method):
    s = scene(kw)
    mus = s.mu(np.array(VELOCITIES), method=method, return_bound=True)
    for i, v in enumerate(VELOCITIES):
        status, out, err = cli("mu", *flags(**kw), "--v0", repr(v), "--method", method, "--json")
        assert status == 0, err
        assert abs(mus[0][i] - out["mu"]) <= 1e-10, (v, mus[0][i], out["mu"])
        assert abs(mus[1][i] - out["error_bound_over_mu0"] * s.mu0) <= 1e-10
        assert abs(s.mu(v, method=method) - out["mu"]) <= 1e-10


@pytest.mark.parametrize("kw", [SCENES[2], SCENES[3]])
def test_approx_and_fixed_match_cli(cli, kw):
    s = scene(kw)
    for method in ["approx", "fixed"]:
        for v in [0.01, -0.05]:
            status, out, err = cli("mu", *flags(**kw), "--v0", repr(v), "--method", method, "--json")
            assert status == 0, err
            assert abs(s.mu(v, method=method) - out["mu"]) <= 1e-10


def test_tolerance_matches_cli(cli):
    s = scene(PAPER)
    for v in [0.01, 0.2]:
        _, out, _ = cli("mu", *flags(**PAPER), "--v0", repr(v), "--tol", "1e-3", "--json")
        assert abs(s.mu(v, tol=1e-3) - out["mu"]) <= 1e-10


@pytest.mark.parametrize("kw", SCENES[:5], ids=str)
def test_statics_match_cli(cli, kw):
    s = scene(kw)
    status, out, err = cli("static", *flags(**kw), "--json")
    assert status == 0, err
    fwd, bwd = s.critical_velocity()
    assert math.isclose(fwd, out["vc_forward"], rel_tol=0, abs_tol=1e-15)
    assert math.isclose(bwd, out["vc_backward"], rel_tol=0, abs_tol=1e-15)
    lo, hi = s.mu_limits()
    if out["lifts_off"]:
        assert s.static_interval() is None
        assert abs(lo - out["mu_at_rest_over_mu0"] * s.mu0) <= 1e-10
        assert lo == hi
    else:
        assert abs(lo - out["mu_0minus_over_mu0"] * s.mu0) <= 1e-10
        assert abs(hi - out["mu_0plus_over_mu0"] * s.mu0) <= 1e-10
        iv = s.static_interval()
        if out["interval_lo_m"] is None:
            assert iv is None
        else:
            assert iv == pytest.approx((out["interval_lo_m"], out["interval_hi_m"]), abs=1e-18)


def test_curve_matches_cli(cli, tmp_path):
    """`fricctl curve` writes v0 as `linspace_at` computes it; the package
    over the same velocities gives the same μ."""
    path = tmp_path / "c.csv"
    n, lo, hi = 101, -0.5, 0.5
    status, _, err = cli("curve", *flags(**PAPER), "--v-min", lo, "--v-max", hi, "--points", n, "--csv", path)
    assert status == 0, err
    rows = np.genfromtxt(path, delimiter=",", names=True, dtype=None, encoding="utf-8")
    v = lo + (hi - lo) * np.arange(n) / (n - 1)
    v[-1] = hi
    moving = rows["v0"] != 0.0
    np.testing.assert_array_equal(v[v != 0.0], rows["v0"][moving])
    s = scene(PAPER)
    np.testing.assert_allclose(s.mu(v[v != 0.0]), rows["mu"][moving], rtol=0, atol=1e-10)
    # At v0 = 0 the curve has two rows, μ(0⁻) then μ(0⁺): mu_limits().
    np.testing.assert_allclose(rows["mu"][~moving], s.mu_limits(), rtol=0, atol=1e-10)


def test_regime_and_classify(cli):
    s = scene(PAPER)
    fwd, bwd = s.critical_velocity()
    assert s.regime(0.0) == "rest"
    assert s.regime(0.5 * fwd) == "stick_slip"
    assert s.regime(fwd) == "sliding"
    assert s.regime(-1.01 * bwd) == "sliding"
    # μ = ±μ0 exactly when sliding (eq. 8), by any method.
    assert s.mu(fwd * 1.5) == 0.3 and s.mu(-bwd * 1.5) == -0.3
    _, out, _ = cli("classify", *flags(**PAPER), "--json")
    c = s.classify()
    assert c.regime == out["regime"]
    assert abs(c.asymmetry - out["asymmetry"]) <= 1e-12


def test_tune_matches_cli(cli):
    s = scene(PAPER)
    r = fricctl.tune(s, adjust="duz", target_mu_rel=0.2, v0=0.01)
    _, out, _ = cli("tune", *flags(**PAPER), "--adjust", "duz", "--target-mu-rel", "0.2", "--v0", "0.01", "--json")
    assert r.to_dict() == out
    # The drive found gives the target: an independent evaluation by a new scene.
    s2 = fricctl.Scene(**dict(PAPER, duz=r.duz))
    assert abs(s2.mu(0.01) / 0.3 - 0.2) <= r.error_bound_over_mu0
    m = fricctl.tune(s, adjust="phase", maximize="asymmetry")
    _, out, _ = cli("tune", *flags(**PAPER), "--adjust", "phase", "--maximize", "asymmetry", "--json")
    assert m.to_dict() == out


def test_tune_on_a_curved_profile_matches_cli(cli):
    kw = dict(PAPER, profile="sphere")
    r = fricctl.tune(scene(kw), adjust="dux", target_mu_rel=0.2, v0=0.01)
    _, out, _ = cli("tune", *flags(**kw), "--adjust", "dux", "--target-mu-rel", "0.2", "--v0", "0.01", "--json")
    assert r.to_dict() == out
    assert (r.profile, r.method) == ("sphere", "mdr")
    # The drive found gives the target: a new scene's own MDR evaluation.
    s2 = fricctl.Scene(**dict(kw, dux=r.dux))
    assert abs(s2.mu(0.01) / 0.3 - 0.2) <= 2 * r.error_bound_over_mu0


@pytest.mark.parametrize("kw", [PAPER, dict(PAPER, phi_deg=-90.0), dict(PAPER, duz=7e-6, phi_deg=-90.0)])
def test_load_line_matches_cli(cli, kw):
    r = fricctl.load_line(scene(kw))
    _, out, _ = cli("load-line", *flags(**kw), "--json")
    assert r.to_dict() == out


def test_motion_matches_cli(cli):
    kw = dict(PAPER, phi_deg=-90.0)
    args = dict(mass=0.0, force_amp_rel=0.5, force_omega=100.0)
    r = fricctl.motion(scene(kw), **args)
    _, out, err = cli("motion", *flags(**kw), *flags(**args), "--json")
    out.pop("wall_time")
    got = r.to_dict()
    got.pop("wall_time")
    for k in ["doubtful", "t", "x", "v", "force", "stuck"]:
        got.pop(k)
    assert got == out
    assert r.t.shape == r.x.shape == r.v.shape == r.force.shape == r.stuck.shape
    assert r.stuck.dtype == bool and r.t.size > 0


def _sweep(tmp_path, mu0_true=0.27, ratio_true=0.6):
    """A synthetic sweep over the phase: measured μ = the exact solver's μ for
    the true contact (computed here through the package), device model
    (0.3, kz, 0.75 kz)."""
    kz = 2e6
    phis = np.linspace(0.0, 330.0, 12)
    cols = dict(
        param=["phase-deg"] * 12, value=phis, freq_hz=np.full(12, 40e3), amp_z=np.full(12, 2e-6),
        amp_x=np.full(12, 0.7e-6), offset_z=np.full(12, 5e-6), phi_deg=phis, v0=np.full(12, 0.01),
        model_mu0=np.full(12, 0.3), model_kz=np.full(12, kz), model_kx=np.full(12, 0.75 * kz),
    )
    cols["measured_mu"] = np.array([
        fricctl.Scene(mu0=mu0_true, kz=kz, kx=ratio_true * kz, uz0=5e-6, duz=2e-6, dux=0.7e-6,
                      freq=40e3, phi_deg=float(p)).mu(0.01) for p in phis])
    cols["std_error"] = np.full(12, 1e-3)
    cols["predicted_mu"] = cols["measured_mu"]
    cols["valid"] = np.full(12, True)
    cols["reasons"] = [""] * 12
    path = tmp_path / "sweep.csv"
    keys = list(cols)
    with open(path, "w") as f:
        f.write(",".join(keys) + "\n")
        for i in range(12):
            f.write(",".join(repr(float(cols[k][i])) if k not in ("param", "reasons", "valid")
                             else ("true" if k == "valid" else str(cols[k][i])) for k in keys) + "\n")
    return cols, path


def test_fit_matches_cli_and_recovers_the_contact(cli, tmp_path):
    pd = pytest.importorskip("pandas")
    cols, path = _sweep(tmp_path)
    _, out, err = cli("fit", "--data", path, "--json")
    assert out is not None, err
    from_path = fricctl.fit(str(path))
    from_dict = fricctl.fit(cols)
    from_df = fricctl.fit(pd.DataFrame(cols))
    d = from_path.to_dict()
    for k in ["residual_value", "residual_mu", "residual_std_error"]:
        d.pop(k)
    assert d == out
    for r in [from_dict, from_df]:
        assert abs(r.mu0 - out["mu0"]) <= 1e-10 and abs(r.kx_over_kz - out["kx_over_kz"]) <= 1e-10
    # Noise-free data: the truth, within the solver's bound propagated (1e-6 is generous).
    assert abs(from_df.mu0 - 0.27) <= 1e-6 and abs(from_df.kx_over_kz - 0.6) <= 1e-6
    assert from_df.mu0_ci95_low <= from_df.mu0 <= from_df.mu0_ci95_high
    assert from_df.residual_mu.shape == (12,)
