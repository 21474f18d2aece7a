"""Shared fixtures: the CLI binary the package is compared with."""

import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def _find_cli():
    env = os.environ.get("FRICCTL_BIN")
    if env:
        if not pathlib.Path(env).is_file():
            raise RuntimeError(f"FRICCTL_BIN={env} is not a file")
        return env
    for profile in ("release", "debug"):
        p = ROOT / "target" / profile / "fricctl"
        if p.is_file():
            return str(p)
    return None


CLI = _find_cli()


@pytest.fixture(scope="session")
def cli():
    """Runs `fricctl ARGS`: (exit status, parsed JSON or None, stderr)."""
    if CLI is None:
        pytest.skip("the fricctl binary is not built (cargo build -p host-cli, or set FRICCTL_BIN)")

    def run(*args):
        p = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=300)
        out = None
        if p.stdout.strip().startswith("{"):
            out = json.loads(p.stdout)
        return p.returncode, out, p.stderr.strip()

    return run


def short(x):
    """A number as the CLI's messages write it (Rust `args::short`): the
    shortest round-trip text, plain within [1e-4, 1e9), else `5e-6`."""
    import math

    x = float(x)
    if x == 0.0 or not math.isfinite(x) or 1e-4 <= abs(x) < 1e9:
        r = repr(x)
        return r[:-2] if r.endswith(".0") else r
    m, e = repr(x).split("e") if "e" in repr(x) else (f"{x:e}".split("e"))
    m = m[:-2] if m.endswith(".0") else m
    return f"{m}e{int(e)}"


def flags(**kw):
    """Keywords as CLI flags, numbers as the CLI echoes them: phi_deg=50.0 ->
    ["--phi-deg", "50"]."""
    out = []
    for k, v in kw.items():
        out += ["--" + k.replace("_", "-"), short(v) if isinstance(v, float) else str(v)]
    return out
