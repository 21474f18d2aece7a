"""One Scene from many threads: the results are those of serial calls (the
Scene is immutable; array calls run without the GIL)."""

from concurrent.futures import ThreadPoolExecutor

import numpy as np

import fricctl


def test_same_scene_from_threads():
    s = fricctl.Scene(mu0=0.3, kz=2e6, kx=1.5e6, uz0=5e-6, duz=2e-6, dux=0.7e-6, freq=40e3, phi_deg=50)
    v = np.linspace(0.001, 0.4, 2000)
    serial_arr = s.mu(v)
    serial_pts = [s.mu(float(x)) for x in v[:50]]
    jobs = []
    with ThreadPoolExecutor(max_workers=8) as ex:
        for k in range(16):
            if k % 2:
                jobs.append(("arr", ex.submit(s.mu, v)))
            else:
                jobs.append(("pts", ex.submit(lambda: [s.mu(float(x)) for x in v[:50]])))
        jobs.append(("lim", ex.submit(s.mu_limits)))
    for kind, f in jobs:
        r = f.result()
        if kind == "arr":
            np.testing.assert_array_equal(r, serial_arr)
        elif kind == "pts":
            assert r == serial_pts
        else:
            assert r == s.mu_limits()
