"""Peak RSS growth of Scene.mu over N velocities (default 1e7), in a fresh
process: ru_maxrss before and after the call, the input already allocated.
`python python/bench/mu_memory.py 1e7 [bound]` (python/README.md, Memory)."""
import resource, sys
import numpy as np
import fricctl
n = int(float(sys.argv[1])) if len(sys.argv) > 1 else 10**7
bound = len(sys.argv) > 2 and sys.argv[2] == "bound"
s = fricctl.Scene(mu0=0.3, kz=2e6, kx=1.5e6, uz0=5e-6, duz=2e-6, dux=0.7e-6, freq=40e3, phi_deg=50)
v = np.linspace(-0.5, 0.5, n)
v[n // 2] = 0.5  # no v0 = 0 (its warning)
s.mu(v[:1000])   # thread pool and module warmed up
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
r = s.mu(v, return_bound=bound)
after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
res = r[0].nbytes + r[1].nbytes if bound else r.nbytes
print(f"n={n} return_bound={bound} result {res/1e6:.1f} MB, peak RSS growth {(after-before)/1e3:.1f} MB (ratio {(after-before)*1e3/res:.2f})")
