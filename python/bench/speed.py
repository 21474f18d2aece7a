"""Speed: one `Scene.mu` call over 10^6 velocities against `fricctl curve`
over the same 10^6 points written to /dev/null (release builds of both).

    python python/bench/speed.py [--fricctl target/release/fricctl] [--runs 5]

Prints the median wall time of each over the runs, their ratio, and the
command lines. The velocities are those `fricctl curve --v-min A --v-max B
--points N` computes (v_i = A + (B − A)·i/(N − 1)), and the first run checks
that the two agree within 1e-10.
"""

import argparse
import pathlib
import statistics
import subprocess
import tempfile
import time

import numpy as np

import fricctl

SCENE = dict(mu0=0.3, kz=2e6, kx=1.5e6, uz0=5e-6, duz=2e-6, dux=0.7e-6, freq=40e3, phi_deg=50.0)
ROOT = pathlib.Path(__file__).resolve().parents[2]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--fricctl", default=str(ROOT / "target" / "release" / "fricctl"))
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--v-min", type=float, default=-0.5)
    ap.add_argument("--v-max", type=float, default=0.5)
    a = ap.parse_args()
    n, lo, hi = a.points, a.v_min, a.v_max
    flags = []
    for k, v in SCENE.items():
        flags += ["--" + k.replace("_", "-"), repr(v)]
    cmd = [a.fricctl, "curve", *flags, "--v-min", repr(lo), "--v-max", repr(hi), "--points", str(n), "--csv", "/dev/null"]
    v = lo + (hi - lo) * np.arange(n) / (n - 1)
    v[-1] = hi
    s = fricctl.Scene(**SCENE)

    with tempfile.TemporaryDirectory() as d:
        check = pathlib.Path(d) / "c.csv"
        subprocess.run(cmd[:-1] + [str(check)], check=True, capture_output=True)
        rows = np.genfromtxt(check, delimiter=",", names=True, dtype=None, encoding="utf-8", usecols=(0, 2))
        mu = s.mu(v)
        assert np.array_equal(rows["v0"], v), "velocities differ"
        diff = np.nanmax(np.abs(mu - rows["mu"]))
        assert diff <= 1e-10, diff

    t_py, t_cli = [], []
    for _ in range(a.runs):
        t0 = time.perf_counter()
        s.mu(v)
        t_py.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        t_cli.append(time.perf_counter() - t0)
    mp, mc = statistics.median(t_py), statistics.median(t_cli)
    print(f"points {n}, runs {a.runs}, max |mu_py - mu_cli| = {diff:.1e}")
    print(f"python  Scene.mu(v)            median {mp:.3f} s  (runs: {', '.join(f'{t:.3f}' for t in t_py)})")
    print(f"cli     {' '.join(cmd[1:2])} … > /dev/null  median {mc:.3f} s  (runs: {', '.join(f'{t:.3f}' for t in t_cli)})")
    print(f"ratio   cli/python = {mc / mp:.2f}")
    print("command: " + " ".join(cmd))


if __name__ == "__main__":
    main()
