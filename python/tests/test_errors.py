"""Every refusal: ValueError naming the Python keyword, then the CLI's own
text (compared with the CLI's stderr for the same flags where the CLI has
them), SolverError for a computation that fails, and no panic across the
boundary."""

import re

import pytest

import fricctl
from conftest import flags

PAPER = dict(mu0=0.3, kz=2e6, kx=1.5e6, uz0=5e-6, duz=2e-6, dux=0.7e-6, freq=40e3, phi_deg=50.0)


def as_python(cli_stderr):
    """The Python message of a CLI refusal: the keyword of the flag it
    starts with, then the CLI's text (`error: --phi-deg: …` → `phi_deg:
    --phi-deg: …`)."""
    text = cli_stderr.removeprefix("error: ")
    m = re.match(r"--([a-z0-9-]+):", text)
    assert m, cli_stderr
    return m.group(1).replace("-", "_") + ": " + text


def without(*keys, **extra):
    d = {k: v for k, v in PAPER.items() if k not in keys}
    d.update(extra)
    return d


# Scene keywords whose refusal the CLI gives for the same flags (`fricctl mu`).
SCENE_CASES = [
    dict(PAPER, mu0=-1.0),
    dict(PAPER, mu0=0.0),
    dict(PAPER, kz=0.0),
    dict(PAPER, kx=-2.0),
    dict(PAPER, uz0=-5e-06),
    dict(PAPER, duz=-1.0),
    dict(PAPER, dux=-1.0),
    dict(PAPER, freq=0.0),
    dict(PAPER, mu0=1e200),
    dict(PAPER, kz=1e-200),
    dict(PAPER, phi_deg=1e6),
    without("kx"),
    without("mu0"),
    without("freq"),
    dict(PAPER, omega=1.0),
    dict(PAPER, phi_rad=1.0),
    dict(PAPER, duz_rel=0.5),
    dict(duz_rel=0.5),
    dict(dux_rel=0.5),
    dict(duz_rel=0.5, dux_rel=0.5, ratio=1.0),
    dict(duz_rel=0.0, ratio=1.0),
    dict(duz_rel=-1.0, dux_rel=1.0),
    dict(PAPER, exponent=2.0),
    dict(PAPER, profile="power"),
    dict(PAPER, profile="sphere", exponent=2.0),
    dict(PAPER, profile="power", exponent=-1.0),
    dict(PAPER, profile="blob"),
    dict(PAPER, dux=100.0),  # kx·dux/(mu0·kz·uz0) beyond what f64 resolves
]


@pytest.mark.parametrize("kw", SCENE_CASES, ids=lambda kw: ",".join(f"{k}={v}" for k, v in kw.items()))
def test_scene_refusals_are_the_clis(cli, kw):
    status, _, err = cli("mu", *flags(**kw), "--v0", "0.01")
    assert status == 2, err
    with pytest.raises(ValueError) as e:
        fricctl.Scene(**kw)
    assert str(e.value) == as_python(err)


MU_CASES = [
    (dict(method="blob"), ["--method", "blob"]),
    (dict(tol=-1.0), ["--tol", "-1"]),
    (dict(tol=0.0), ["--tol", "0"]),
    (dict(method="exact", tol=1e-3), ["--method", "exact", "--tol", "0.001"]),
    (dict(steps_per_period=100), ["--steps-per-period", "100"]),
    (dict(method="approx"), ["--method", "approx"]),
    (dict(method="fixed", steps_per_period=3), ["--method", "fixed", "--steps-per-period", "3"]),
]


@pytest.mark.parametrize("kw,args", MU_CASES, ids=lambda x: str(x))
def test_mu_refusals_are_the_clis(cli, kw, args):
    status, _, err = cli("mu", *flags(**PAPER), "--v0", "0.01", *args)
    assert status == 2, err
    with pytest.raises(ValueError) as e:
        fricctl.Scene(**PAPER).mu(0.01, **kw)
    assert str(e.value) == as_python(err)


def test_fixed_at_rest_and_approx_at_rest(cli):
    s = fricctl.Scene(**dict(PAPER, dux=0.0))
    for method in ["fixed", "approx"]:
        _, _, err = cli("mu", *flags(**dict(PAPER, dux=0.0)), "--v0", "0", "--method", method)
        with pytest.raises(ValueError) as e:
            s.mu(0.0, method=method)
        assert str(e.value) == as_python(err)


def test_bad_errors_policy():
    with pytest.raises(ValueError, match=r"^errors: invalid value 'ignore' \(one of: raise, nan\)$"):
        fricctl.Scene(**PAPER).mu(0.01, errors="ignore")


def test_tolerance_no_method_meets_is_a_solver_error(cli):
    _, _, err = cli("mu", *flags(**PAPER), "--v0", "0.01", "--tol", "1e-30")
    with pytest.raises(fricctl.SolverError) as e:
        fricctl.Scene(**PAPER).mu(0.01, tol=1e-30)
    assert str(e.value) == as_python(err)
    assert isinstance(e.value, RuntimeError)
    with pytest.warns(RuntimeWarning, match="tighter than"):
        import math
        assert math.isnan(fricctl.Scene(**PAPER).mu(0.01, tol=1e-30, errors="nan"))


def test_liftoff_false_refuses_a_lifting_drive():
    with pytest.raises(ValueError, match=r"^duz: --duz: must be < uz0 for this command"):
        fricctl.Scene(**dict(PAPER, duz=7e-6), liftoff=False)


TUNE_CASES = [
    (dict(adjust="duz", target_mu_rel=0.2), ["--adjust", "duz", "--target-mu-rel", "0.2"]),
    (dict(adjust="duz", target_mu_rel=0.2, v0=0.0), ["--adjust", "duz", "--target-mu-rel", "0.2", "--v0", "0"]),
    (dict(adjust="duz", target_mu_rel=1.5, v0=0.01), ["--adjust", "duz", "--target-mu-rel", "1.5", "--v0", "0.01"]),
    (dict(adjust="duz", target_mu=0.5, v0=0.01), ["--adjust", "duz", "--target-mu", "0.5", "--v0", "0.01"]),
    (dict(adjust="duz", target_mu_rel=0.99, v0=0.01), ["--adjust", "duz", "--target-mu-rel", "0.99", "--v0", "0.01"]),
    (dict(adjust="dux", target_mu_rel=0.2, v0=0.01, max_duz=1e-6), ["--adjust", "dux", "--target-mu-rel", "0.2", "--v0", "0.01", "--max-duz", "1e-6"]),
    (dict(adjust="phase", maximize="asymmetry", v0=0.01), ["--adjust", "phase", "--maximize", "asymmetry", "--v0", "0.01"]),
    (dict(adjust="duz", maximize="stall-force", liftoff_margin=1.5), ["--adjust", "duz", "--maximize", "stall-force", "--liftoff-margin", "1.5"]),
]


@pytest.mark.parametrize("kw,args", TUNE_CASES, ids=lambda x: str(x))
def test_tune_refusals_are_the_clis(cli, kw, args):
    status, _, err = cli("tune", *flags(**PAPER), *args)
    assert status == 2, err
    with pytest.raises(ValueError) as e:
        fricctl.tune(fricctl.Scene(**PAPER), **kw)
    assert str(e.value) == as_python(err)


MOTION_CASES = [
    dict(mass=0.0, force_amp_rel=0.5, force_omega=1e6),
    dict(mass=-1.0, force_amp_rel=0.5, force_omega=100.0),
    dict(mass=0.0, force_amp_rel=20.0, force_omega=100.0),
    dict(mass=0.0, force_amp_rel=0.8, force_omega=100.0, force_offset_rel=0.5),
    dict(mass=0.0, force_amp_rel=0.5, force_omega=100.0, method="resolved"),
    dict(mass=0.0, force_amp_rel=0.5, force_omega=100.0, tol=2.0),
    dict(mass=0.0, force_amp_rel=0.5, force_omega=100.0, duration=1e-9),
]


@pytest.mark.parametrize("kw", MOTION_CASES, ids=str)
def test_motion_refusals_are_the_clis(cli, kw):
    status, _, err = cli("motion", *flags(**PAPER), *flags(**kw))
    assert status == 2, err
    with pytest.raises(ValueError) as e:
        fricctl.motion(fricctl.Scene(**PAPER), **kw)
    assert str(e.value) == as_python(err)


def test_fit_refusals():
    with pytest.raises(ValueError, match=r"^data: missing column 'amp_z'"):
        fricctl.fit({"freq_hz": [1.0]})
    with pytest.raises(ValueError, match=r"^params: --params: unknown parameter 'kz'"):
        fricctl.fit({}, params="kz")
    with pytest.raises(ValueError, match=r"^data: --data: the sweep file has no rows$"):
        fricctl.fit({k: [] for k in ["freq_hz", "amp_z", "amp_x", "offset_z", "phi_deg", "v0",
                                     "model_mu0", "model_kz", "model_kx", "measured_mu"]})


def test_a_panic_becomes_a_solver_error():
    with pytest.raises(fricctl.SolverError, match="internal error"):
        fricctl._panic_for_tests()
