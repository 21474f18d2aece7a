"""Bad input, generatively (issue 41 §6): every keyword of every public
function, method and constructor in ``fricctl.pyi`` gets hostile values for
its type — None (where None is not the keyword's "not given"), a string, NaN,
±inf, a negative number, 0, 2**70, ±10**400 (an int beyond a float), a
container of the right element, and for text an unknown word — each in a valid call that differs only there.

The table is generated from the stub (``ast``): a new keyword is tested
without being listed here. Every call must

* raise TypeError, ValueError or OverflowError (or ``DeviceRefused``, the
  device's own refusal) whose message names the keyword, or
* be one of the ADMITTED cases below — a value inside the keyword's
  documented domain (phi_deg = −1°, dux = 0, …) — and then return a result
  with no NaN, raise a documented ``SolverError``/``DeviceError``, or be
  refused as a combination by a message naming the keyword it blames.

Never a pyo3 ``PanicException`` (a BaseException), never another exception
type, never a silent result for a value outside the domain.
"""

import ast
import inspect
import math
import pathlib
import re

import numpy as np
import pytest

import fricctl

STUB = pathlib.Path(__file__).resolve().parents[1] / "fricctl.pyi"
PAPER = dict(mu0=0.3, kz=2e6, kx=1.5e6, uz0=5e-6, duz=2e-6, dux=0.7e-6, freq=40e3, phi_deg=50.0)
NAN, INF = float("nan"), float("inf")
REQUIRED = object()


def signatures(defaults_out=None):
    """{qualified name: [(keyword, annotation text, optional)]} of the stub's
    public callables (overloads and properties skipped: the implementation
    signature is the one after the overloads). With `defaults_out` a dict, it
    also receives {qualified name: {keyword: default value or REQUIRED}}."""
    tree = ast.parse(STUB.read_text())
    out = {}

    def add(qual, fn):
        names = {d.id for d in fn.decorator_list if isinstance(d, ast.Name)}
        if names & {"overload", "property"}:
            return
        a = fn.args
        positional = a.posonlyargs + a.args
        defaults = [None] * (len(positional) - len(a.defaults)) + list(a.defaults)
        params = []
        for arg, d in list(zip(positional, defaults)) + list(zip(a.kwonlyargs, a.kw_defaults)):
            if arg.arg == "self":
                continue
            ann = ast.unparse(arg.annotation) if arg.annotation is not None else "Any"
            none_is_default = d is not None and isinstance(d, ast.Constant) and d.value is None
            params.append((arg.arg, ann, none_is_default or ann.startswith("Optional[")))
            if defaults_out is not None:
                defaults_out.setdefault(qual, {})[arg.arg] = REQUIRED if d is None else ast.literal_eval(d)
        if params:
            out[qual] = params

    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and not node.name.startswith("_"):
            add(node.name, node)
        elif isinstance(node, ast.ClassDef):
            for f in node.body:
                if isinstance(f, ast.FunctionDef) and (f.name == "__init__" or not f.name.startswith("_")):
                    add(f"{node.name}.{f.name}", f)
    return out


def category(ann):
    """The kind of value a keyword takes, from its annotation."""
    if ann == "Scene":
        return "scene"
    if ann.startswith("Union[str, PathLike"):
        return "data"
    if ann == "Optional[Union[str, PathLike[str]]]":
        return "path"
    if "Sequence[str]" in ann:
        return "names"
    if "Mapping[" in ann:
        return "mapping"
    if ann == "Any":
        return "array"
    inner = ann.removeprefix("Optional[").removesuffix("]") if ann.startswith("Optional[") else ann
    if inner == "int":
        return "int"
    if inner == "float":
        return "float"
    if inner == "bool":
        return "bool"
    if inner == "str" or "Literal" in inner or inner in ("Method", "Errors", "SweepParam"):
        return "text"
    raise AssertionError(f"no category for the annotation {ann!r}: add one")


HOSTILE = {
    "float": [("str", "0.5"), ("nan", NAN), ("inf", INF), ("-inf", -INF), ("negative", -1.0),
              ("zero", 0.0), ("2**70", 2**70), ("10**400", 10**400), ("-10**400", -10**400),
              ("list", [0.5])],
    "int": [("str", "5"), ("nan", NAN), ("inf", INF), ("negative", -5), ("zero", 0),
            ("2**70", 2**70), ("10**400", 10**400), ("list", [5]), ("float", 2.5), ("bool", True)],
    "bool": [("str", "yes"), ("nan", NAN), ("list", [True]), ("int", 2)],
    "text": [("int", 5), ("nan", NAN), ("list", ["auto"]), ("unknown", "bogus")],
    "scene": [("str", "scene"), ("int", 5), ("dict", {})],
    "array": [("str", "0.01"), ("nan", NAN), ("inf", INF), ("-inf", -INF), ("2**70", 2**70),
              ("10**400", 10**400),
              ("list-of-str", ["0.01"]), ("dict", {"v0": 0.01}), ("bool", True)],
    "data": [("int", 5), ("nan", NAN), ("list", [1.0]), ("missing-file", "no/such/sweep.csv")],
    "path": [("int", 5), ("nan", NAN), ("list", ["s.toml"]), ("missing-file", "no/such/scene.toml")],
    "names": [("int", 5), ("list-of-int", [5]), ("unknown", "kz"), ("empty", "")],
    "mapping": [("str", "mu0"), ("int", 5), ("list", [1.0]), ("unknown-key", {"bogus": 1.0}),
                ("nan-value", {"mu0": NAN}), ("str-value", {"mu0": "0.3"})],
}


def sweep_columns():
    """A valid sweep (the model's own μ at eight phases, σ = 1e-3)."""
    phis = np.linspace(0.0, 315.0, 8)
    n = len(phis)
    cols = dict(value=phis, freq_hz=np.full(n, 40e3), amp_z=np.full(n, 2e-6),
                amp_x=np.full(n, 0.7e-6), offset_z=np.full(n, 5e-6), phi_deg=phis,
                v0=np.full(n, 0.01), model_mu0=np.full(n, 0.3), model_kz=np.full(n, 2e6),
                model_kx=np.full(n, 1.5e6), std_error=np.full(n, 1e-3))
    cols["measured_mu"] = np.array([fricctl.Scene(**dict(PAPER, phi_deg=float(p))).mu(0.01) for p in phis])
    return cols


def device_for(qual):
    """A fresh virtual device for a Device method: driven and running, or
    for identify (which drives each transducer alone) with the drive set
    and stopped; None for the constructors."""
    if not qual.startswith("Device.") or qual in ("Device.virtual", "Device.open"):
        return None
    if qual == "Device.identify":
        # Transducers that ring near 20 kHz (python/tests/test_device.py).
        dev = fricctl.Device.virtual(plant=dict(resonance_z=20300.0, q_z=300.0, resonance_x=19700.0, q_x=200.0))
        dev.drive(freq=20000, amp_z=0, amp_x=0, offset_z=4e-6, open_loop=True)
        return dev
    dev = fricctl.Device.virtual(plant=dict(ideal_transducers=True))
    dev.drive(freq=20000, amp_z=2e-6, amp_x=3e-7, offset_z=4e-6, phase_deg=40, open_loop=True)
    dev.start()
    return dev


S = fricctl.Scene(**PAPER)
DIMENSIONLESS = dict(duz_rel=0.5, phi_deg=0.0)

# (callable factory, valid keywords): the call each hostile value is put into.
# The factory gets a fresh device for Device methods.
CALLS = {
    "Scene.__init__": (lambda dev: fricctl.Scene, PAPER),
    "Scene.mu": (lambda dev: S.mu, dict(v0=0.01)),
    "Scene.regime": (lambda dev: S.regime, dict(v0=0.01)),
    "tune": (lambda dev: fricctl.tune, dict(scene=S, adjust="duz", target_mu_rel=0.2, v0=0.01)),
    "fit": (lambda dev: fricctl.fit, dict(data=sweep_columns(), params="mu0")),
    "load_line": (lambda dev: fricctl.load_line, dict(scene=S)),
    "motion": (lambda dev: fricctl.motion, dict(scene=S, mass=0.0, force_amp_rel=0.5, force_omega=100.0)),
    "Device.virtual": (lambda dev: fricctl.Device.virtual, {}),
    "Device.open": (lambda dev: fricctl.Device.open, dict(tcp="127.0.0.1:1", timeout_ms=50, attempts=1)),
    "Device.drive": (lambda dev: dev.drive, dict(freq=20000, amp_z=2e-6, amp_x=3e-7, offset_z=4e-6, open_loop=True)),
    "Device.scene": (lambda dev: dev.scene, dict(mu0=0.3, kz=1e7, kx=1e7)),
    "Device.predict": (lambda dev: dev.predict, dict(v0=0.004)),
    "Device.measure": (lambda dev: dev.measure, dict(periods=100)),
    "Device.identify": (lambda dev: dev.identify, dict(store=False)),
    "Device.sweep": (lambda dev: dev.sweep, dict(param="phase_deg", start=0.0, end=90.0, points=2, periods=50, v0=0.004)),
    "Device.control": (lambda dev: dev.control, dict(target_mu=0.1, v0=0.004, periods=50)),
    "Device.watch": (lambda dev: dev.watch, dict(periods=100, count=1)),
}

# A keyword that needs a different valid call (the flags it excludes or
# needs), with a valid value of its own (which the hostile value replaces).
BASE_FOR = {
    ("Scene.__init__", "omega"): dict({k: v for k, v in PAPER.items() if k != "freq"}, omega=2.5e5),
    ("Scene.__init__", "phi_rad"): dict({k: v for k, v in PAPER.items() if k != "phi_deg"}, phi_rad=0.8),
    ("Scene.__init__", "duz_rel"): dict(dux_rel=0.5, phi_deg=0.0, duz_rel=0.5),
    ("Scene.__init__", "dux_rel"): dict(DIMENSIONLESS, dux_rel=0.5),
    ("Scene.__init__", "ratio"): dict(DIMENSIONLESS, ratio=1.0),
    ("Scene.__init__", "exponent"): dict(PAPER, profile="power", exponent=2.0),
    ("Scene.mu", "steps_per_period"): dict(v0=0.01, method="fixed", steps_per_period=2000),
    ("tune", "target_mu"): dict(scene=S, adjust="duz", v0=0.01, target_mu=0.06),
    ("tune", "maximize"): dict(scene=S, adjust="phase", maximize="asymmetry"),
    ("tune", "v_rel"): dict(scene=S, adjust="duz", target_mu_rel=0.6, v_rel=0.5),
    ("tune", "max_dux"): dict(scene=S, adjust="dux", target_mu_rel=0.2, v0=0.01, max_dux=2e-6),
    ("Device.open", "port"): dict(timeout_ms=50, attempts=1, port="/no/such/tty"),
    ("Device.open", "tcp"): dict(timeout_ms=50, attempts=1, tcp="127.0.0.1:1"),
}

# Values inside the keyword's documented domain (the stub's text, the CLI's
# flags): the call may return (no NaN in the result) or fail as a
# computation (SolverError, DeviceError).
ADMITTED = {
    # Scene: φ any angle, amplitudes ≥ 0, magnitudes up to 1e100.
    ("Scene.__init__", "phi_deg", "negative"), ("Scene.__init__", "phi_deg", "zero"),
    ("Scene.__init__", "phi_rad", "negative"), ("Scene.__init__", "phi_rad", "zero"),
    ("Scene.__init__", "dux", "zero"), ("Scene.__init__", "duz", "zero"),
    ("Scene.__init__", "dux_rel", "zero"), ("Scene.__init__", "ratio", "zero"),
    ("Scene.__init__", "duz_rel", "zero"),
    ("Scene.__init__", "kz", "2**70"),
    ("Scene.__init__", "kx", "2**70"),  # refused as the drive's reach, by dux
    ("Scene.__init__", "freq", "2**70"), ("Scene.__init__", "omega", "2**70"),
    ("Scene.__init__", "mu0", "2**70"), ("Scene.__init__", "uz0", "2**70"),
    ("Scene.__init__", "exponent", "2**70"),
    # mu: v0 any real (0: two-sided, NaN with a warning; checked apart).
    ("Scene.mu", "v0", "2**70"),
    ("Scene.mu", "tol", "2**70"),  # a bound every method meets
    ("Scene.regime", "v0", "negative"), ("Scene.regime", "v0", "zero"), ("Scene.regime", "v0", "2**70"),
    # tune: v0 any non-zero real, targets as documented.
    ("tune", "v0", "negative"), ("tune", "v_rel", "negative"), ("tune", "v_rel", "2**70"),
    ("tune", "target_mu_rel", "zero"),
    ("tune", "target_mu", "zero"),
    # motion: offsets and springs as documented.
    ("motion", "force_offset_rel", "negative"), ("motion", "force_offset_rel", "zero"),
    ("motion", "spring", "zero"), ("motion", "mass", "zero"), ("motion", "force_amp_rel", "zero"),
    ("motion", "mass", "2**70"),
    # Device: the virtual plant's and the drive's domains.
    ("Device.virtual", "v0", "negative"), ("Device.virtual", "v0", "zero"),
    ("Device.virtual", "noise", "zero"), ("Device.virtual", "offset", "negative"),
    ("Device.virtual", "offset", "zero"), ("Device.virtual", "seed", "zero"),
    ("Device.drive", "amp_z", "zero"), ("Device.drive", "amp_x", "zero"),
    ("Device.drive", "offset_z", "zero"),  # refused as amp_z's lift-off
    ("Device.drive", "phase_deg", "negative"), ("Device.drive", "phase_deg", "zero"),
    ("Device.predict", "v0", "negative"), ("Device.predict", "v0", "zero"),
    ("Device.sweep", "start", "negative"), ("Device.sweep", "start", "zero"),
    ("Device.sweep", "end", "negative"), ("Device.sweep", "end", "zero"),
    ("Device.sweep", "settle_periods", "zero"),
    ("Device.sweep", "start", "2**70"), ("Device.sweep", "end", "2**70"),  # the device's range
    ("Device.sweep", "v0", "negative"), ("Device.sweep", "v0", "zero"),
    ("Device.scene", "mu0", "2**70"),  # as `device scene set --mu0` (an f32)
    ("Device.control", "target_mu", "zero"),
    ("Device.control", "v0", "negative"),
}


def cases():
    out = []
    for qual, params in signatures().items():
        assert qual in CALLS, f"{qual} is public in fricctl.pyi: give it a valid call in CALLS"
        for kw, ann, optional in params:
            cat = category(ann)
            values = list(HOSTILE[cat])
            if not optional:
                values.insert(0, ("None", None))
            for label, value in values:
                out.append(pytest.param(qual, kw, label, value, id=f"{qual}-{kw}-{label}"))
    return out


def names(kw, msg):
    return re.search(rf"(?<![A-Za-z0-9_]){re.escape(kw)}(?![A-Za-z0-9_])", msg) is not None


def no_nan(result):
    """Every float the result holds is a number (NaN would be a silent
    failure)."""
    if isinstance(result, fricctl.Record):
        result = result.to_dict()
    if isinstance(result, dict):
        return all(no_nan(v) for v in result.values())
    if isinstance(result, (list, tuple)):
        return all(no_nan(v) for v in result)
    if isinstance(result, np.ndarray) and result.dtype.kind == "f":
        return not np.isnan(result).any()
    if isinstance(result, float):
        return not math.isnan(result)
    return True


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
@pytest.mark.parametrize("qual,kw,label,value", cases())
def test_hostile_keyword(qual, kw, label, value):
    dev = device_for(qual)
    try:
        factory, base = CALLS[qual]
        kwargs = dict(BASE_FOR.get((qual, kw), base))
        kwargs[kw] = value
        admitted = (qual, kw, label) in ADMITTED
        try:
            result = factory(dev)(**kwargs)
        except (TypeError, ValueError, OverflowError, fricctl.DeviceRefused) as e:
            if admitted and not names(kw, str(e)):
                # A value in the domain whose combination with the others is
                # refused: the message names the keyword it blames (or, for
                # a sweep, the swept parameter).
                others = [k for k in kwargs if k != kw] + ([kwargs["param"]] if "param" in kwargs else [])
                assert any(names(k, str(e)) for k in others), f"{type(e).__name__} names no keyword: {e}"
                return
            assert names(kw, str(e)), f"{type(e).__name__} does not name {kw!r}: {e}"
            return
        except (fricctl.SolverError, fricctl.DeviceError) as e:
            assert admitted, f"{type(e).__name__} for a value outside {kw!r}'s domain: {e}"
            return
        except BaseException as e:  # a PanicException is a BaseException
            pytest.fail(f"{type(e).__name__}: {e}")
        assert admitted, f"{qual}({kw}={value!r}) returned {result!r}: a silent result"
        assert no_nan(result), f"{qual}({kw}={value!r}) returned NaN: {result!r}"
        if isinstance(result, fricctl.Device):
            result.close()
        if hasattr(result, "close") and qual == "Device.watch":
            result.close()
    finally:
        if dev is not None:
            dev.close()


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
@pytest.mark.parametrize("qual,kw", [(q, None) for q in CALLS] + list(BASE_FOR), ids=str)
def test_every_base_call_is_valid(qual, kw):
    """The calls the hostile values are put into succeed as they stand (else
    a refusal could be the base's, not the value's); Device.open's fails
    only to connect (nothing listens on port 1)."""
    factory, base = CALLS[qual]
    kwargs = BASE_FOR.get((qual, kw), base)
    dev = device_for(qual)
    try:
        if qual == "Device.open":
            # Nothing listens on port 1; the tty does not exist (ValueError).
            with pytest.raises((fricctl.LinkError, ValueError), match=r"^(tcp: --tcp|port: --port): "):
                factory(dev)(**kwargs)
            return
        result = factory(dev)(**kwargs)
        assert no_nan(result), result
        if hasattr(result, "close"):
            result.close()
    finally:
        if dev is not None:
            dev.close()


def test_the_stub_is_the_modules_signature():
    """Every public callable's keywords and defaults in fricctl.pyi are those
    the module reports (``inspect.signature`` of pyo3's text signature)."""
    defaults = {}
    signatures(defaults)
    for qual, stub in defaults.items():
        obj = fricctl
        for part in qual.split("."):
            obj = getattr(obj, part)
        target = getattr(fricctl, qual.split(".")[0]) if qual.endswith(".__init__") else obj
        sig = inspect.signature(target)
        got = {name: (REQUIRED if p.default is inspect.Parameter.empty else p.default)
               for name, p in sig.parameters.items() if name not in ("self", "args")}
        assert set(got) == set(stub), (qual, set(got) ^ set(stub))
        for name, d in stub.items():
            assert got[name] is d if d is REQUIRED else got[name] == d, (qual, name, got[name], d)


def test_the_table_covers_the_stub():
    """Every public callable is in the table, and the table names nothing the
    stub does not (a renamed keyword is noticed)."""
    sigs = signatures()
    assert set(CALLS) == set(sigs), set(CALLS) ^ set(sigs)
    for qual, kw, _ in ADMITTED:
        assert kw in {p[0] for p in sigs[qual]}, (qual, kw)
    for qual, kw in BASE_FOR:
        assert kw in {p[0] for p in sigs[qual]}, (qual, kw)
