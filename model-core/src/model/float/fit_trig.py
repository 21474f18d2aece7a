#!/usr/bin/env python3
"""Minimax coefficients of the `FastF32` backend (model-core/src/model/float/trig.rs).

Each kernel is `f(x) ≈ lead(x) + x^k·P(x²)`; P is fitted by the Remez exchange
algorithm in 60-digit arithmetic (mpmath) for the *relative* error of sin,
asin, atan and the *absolute* error of cos on the reduced interval, then its
coefficients are rounded to f32 and the error of that rounded polynomial (exact
arithmetic) is re-measured on a dense grid with local refinement. The printed
bound is the polynomial's own error; the rounding of the f32 evaluation comes on
top and is measured exhaustively by `tests/tests/trig.rs`.

Run: `python3 model-core/src/model/float/fit_trig.py` (needs mpmath, numpy).
"""
import mpmath as mp
import numpy as np

mp.mp.dps = 60


def f32(x):
    return mp.mpf(float(np.float32(float(x))))


def remez(target, weight, n, a, b, iters=30):
    """Coefficients c[0..n) of P(z) = sum c_i z^i minimising max |w (g - P)| on [a, b]."""
    m = n + 1
    # Chebyshev extrema as the first reference.
    ref = [a + (b - a) * (1 - mp.cos(mp.pi * i / (m - 1))) / 2 for i in range(m)]
    grid = [a + (b - a) * (1 - mp.cos(mp.pi * i / 4000)) / 2 for i in range(4001)]
    gvals = [(z, target(z), weight(z)) for z in grid]
    E = mp.mpf(0)
    for _ in range(iters):
        A = mp.matrix(m, m)
        rhs = mp.matrix(m, 1)
        for i, z in enumerate(ref):
            w = weight(z)
            for j in range(n):
                A[i, j] = w * z**j
            A[i, n] = (-1) ** i
            rhs[i] = w * target(z)
        sol = mp.lu_solve(A, rhs)
        c = [sol[j] for j in range(n)]
        E = sol[n]
        err = [w * (g - mp.polyval(c[::-1], z)) for z, g, w in gvals]
        # One extremum per sign run.
        ext = []
        i = 0
        while i < len(err):
            j = i
            best = i
            while j < len(err) and mp.sign(err[j]) == mp.sign(err[i]):
                if abs(err[j]) > abs(err[best]):
                    best = j
                j += 1
            ext.append(best)
            i = j
        while len(ext) > m:
            # Drop the smaller end.
            if abs(err[ext[0]]) < abs(err[ext[-1]]):
                ext.pop(0)
            else:
                ext.pop()
        if len(ext) < m:
            break
        new = [grid[k] for k in ext]
        if max(abs(x - y) for x, y in zip(new, ref)) < mp.mpf(10) ** -40:
            break
        ref = new
    return c, abs(E)


def max_err(target, weight, c, a, b):
    zs = [a + (b - a) * (1 - mp.cos(mp.pi * i / 20000)) / 2 for i in range(20001)]
    best = mp.mpf(0)
    for z in zs:
        e = abs(weight(z) * (target(z) - mp.polyval(c[::-1], z)))
        best = max(best, e)
    return best


def kernel(name, target, weight, n, a, b):
    c, e = remez(target, weight, n, a, b)
    c32 = [f32(x) for x in c]
    e32 = max_err(target, weight, c32, a, b)
    print(f"{name}: {n} coefficients on z ∈ [{mp.nstr(a, 3)}, {mp.nstr(b, 8)}]")
    print(f"  minimax error {mp.nstr(e, 4)}, with f32 coefficients {mp.nstr(e32, 4)}")
    for x in c32:
        print(f"    {float(x)!r:>26}_f32 = {mp.nstr(x, 12)}")
    return c32, e32


Z0 = mp.mpf(10) ** -30
# Reduced argument |r| ≤ π/4 + 1e-3 (margin for the rounding of k = round(2x/π)).
R = mp.pi / 4 + mp.mpf("1e-3")
kernel(
    "sin(r) = r + r^3 S(r^2), relative",
    lambda z: (mp.sin(mp.sqrt(z)) - mp.sqrt(z)) / z**mp.mpf(1.5),
    lambda z: z**mp.mpf(1.5) / mp.sin(mp.sqrt(z)),
    3, Z0, R**2,
)
kernel(
    "cos(r) = 1 - r^2/2 + r^4 C(r^2), absolute",
    lambda z: (mp.cos(mp.sqrt(z)) - 1 + z / 2) / z**2,
    lambda z: z**2,
    3, Z0, R**2,
)
kernel(
    "asin(x) = x + x^3 P(x^2), x ∈ [0, 1/2], relative",
    lambda z: (mp.asin(mp.sqrt(z)) - mp.sqrt(z)) / z**mp.mpf(1.5),
    lambda z: z**mp.mpf(1.5) / mp.asin(mp.sqrt(z)),
    5, Z0, mp.mpf(1) / 4,
)
T8 = mp.tan(mp.pi / 8) * (1 + mp.mpf("1e-6"))
kernel(
    "atan(u) = u + u^3 A(u^2), |u| ≤ tan(π/8), relative",
    lambda z: (mp.atan(mp.sqrt(z)) - mp.sqrt(z)) / z**mp.mpf(1.5),
    lambda z: z**mp.mpf(1.5) / mp.atan(mp.sqrt(z)),
    5, Z0, T8**2,
)
