"""The paper's Fig. 5: μ/μ0 against v0/(ωW0) for five phase shifts, with
k_xΔu_x/(μ0 k_z Δu_z) = 1 and Δu_z/u_z0 = 0.5 (eq. 26 groups).

    python python/examples/fig5.py [out.png]
"""

import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import fricctl

DUZ_REL, RATIO = 0.5, 1.0
vmax = 1.25 * DUZ_REL * (1 + RATIO)  # 1.25 (a + b): beyond both critical velocities
v = np.linspace(-vmax, vmax, 2001)
v = v[v != 0.0]  # μ is two-sided at rest: mu_limits() gives both ends

# The Rust figures' palette (Okabe–Ito, sky blue fifth): told apart in print
# and by colour-blind readers.
COLORS = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#56B4E9"]

fig, ax = plt.subplots(figsize=(7.5, 4.8), dpi=150)
for phi, color in zip([0, 45, 90, 135, 180], COLORS):
    s = fricctl.Scene(duz_rel=DUZ_REL, ratio=RATIO, phi_deg=phi)
    lo, hi = s.mu_limits()
    vv = np.concatenate([v[v < 0], [0.0, 0.0], v[v > 0]])
    mu = np.concatenate([s.mu(v[v < 0]), [lo, hi], s.mu(v[v > 0])])
    regime = s.classify().regime.replace("_", " ")
    ax.plot(vv, mu, lw=1.6, color=color, label=f"$\\varphi$ = {phi}°  ({regime})")
ax.axhline(0, color="0.6", lw=0.6)
ax.axvline(0, color="0.6", lw=0.6)
# Subscripts through matplotlib's mathtext, not raw underscores.
ax.set_xlabel(r"$v_0\,/\,(\omega W_0)$,   $W_0 = \mu_0 k_z u_{z0} / k_x$")
ax.set_ylabel(r"$\mu\,/\,\mu_0$")
ax.set_ylim(-1.1, 1.1)
ax.set_title(
    rf"Fig. 5: $\Delta u_z/u_{{z0}}$ = {DUZ_REL:g}, "
    rf"$k_x \Delta u_x/(\mu_0 k_z \Delta u_z)$ = {RATIO:g} (exact steady state)"
)
ax.legend(loc="lower right", fontsize=8)
fig.tight_layout()
out = sys.argv[1] if len(sys.argv) > 1 else "fig5.png"
fig.savefig(out)
print(f"wrote {out}")
