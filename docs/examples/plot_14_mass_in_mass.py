"""
A mass-in-mass metamaterial: a local-resonance gap
==================================================

Every cell's outer mass m1 = 1 (joined to the next by k1 = 1) carries a resonator m2 = 0.5 on a
spring k2 = 0.3 — the bundled ``mass_in_mass``, a ``[cell]`` scene. Its gap is not the Bragg gap of a
diatomic chain: it opens around the resonator's own frequency sqrt(k2/m2), where the resonators
swing against the outer masses and hold them still, and it does not move when the cells get larger or
smaller. Below it the outer chain's acoustic branch flattens against the resonance; above it the
optical branch starts at sqrt(k2/m1 + k2/m2) (q = 0).
"""

import tomllib
from pathlib import Path

import mpmath
import numpy as np
from matplotlib.figure import Figure

import springchain as sc

b = sc.bands("mass_in_mass")
print(b.to_text().split("\nThe finite chain")[0])
bands_figure = b.plot()

# %%
# The edges from the cell's own formulas: D(q) = [[(k2 + 4k1 sin²(q/2))/m1, −k2/sqrt(m1m2)],
# [−k2/sqrt(m1m2), k2/m2]]. At q = 0 the optical edge is ω² = k2/m1 + k2/m2; at q = π the acoustic
# edge is the lower root of the 2 × 2 problem there. Both at 50 digits:
mpmath.mp.dps = 50
m1, m2, k1, k2 = (mpmath.mpf(v) for v in ("1", "0.5", "1", "0.3"))
upper = mpmath.sqrt(k2 / m1 + k2 / m2)
tr, det = (4 * k1 + k2) / m1 + k2 / m2, 4 * k1 * k2 / (m1 * m2)
lower = mpmath.sqrt(det / (tr / 2 + mpmath.sqrt(tr * tr / 4 - det)))
gap = b.gaps[0]
print(f"gap {gap.omega_lower:.15f} ... {gap.omega_upper:.15f} rad/s; resonator sqrt(k2/m2) = "
      f"{float(mpmath.sqrt(k2 / m2)):.15f}")
print(f"relative error of the edges: {float(abs(gap.omega_lower - lower) / lower):.1e}, "
      f"{float(abs(gap.omega_upper - upper) / upper):.1e}")

# %%
# Waves inside the gap decay by e^{−Im q} per cell, fastest at the resonance itself (Im q → ∞ at
# sqrt(k2/m2): the outer mass does not move). The finite chain shows it: the receptance from the first
# outer mass to the last of a 10-cell copy (the same cell, ``cells = 10``) drops by many decades
# inside the gap, following e^{−9 Im q} across nine cells. (For the 30-cell scene the transmission in
# the gap falls below what float64 can certify, and ``frf`` refuses those frequencies rather than
# print them.)
data = tomllib.loads(Path(sc.load("mass_in_mass").file).read_text())  # the bundled scene, as a dict
data["cell"]["cells"] = 10
data.pop("initial")
short = sc.scene_from_dict(data)
h = sc.frf(short, input="a_0", output="a_9", omega_min=0.2, omega_max=1.6, points=200, transfer=False)
imag_q, _ = b.attenuation(h.omega)

transmission = Figure(figsize=(7, 3.6), layout="constrained")
ax = transmission.subplots()
ax.axvspan(gap.omega_lower, gap.omega_upper, color="0.85", label="gap of the infinite chain")
ax.semilogy(h.omega, h.magnitude, lw=0.8, label="|H| from a_0 to a_9 (10 cells)")
inside = (h.omega > gap.omega_lower) & (h.omega < gap.omega_upper)
scale = np.median(h.magnitude[inside] / np.exp(-9 * imag_q[inside]))
ax.semilogy(h.omega[inside], scale * np.exp(-9 * imag_q[inside]), "k--", lw=1, label="∝ exp(−9 Im q)")
ax.axvline(float(mpmath.sqrt(k2 / m2)), color="C3", lw=0.8, label="sqrt(k2/m2)")
ax.set(xlabel="ω [rad/s]", ylabel="|H| [m/N]", title="mass-in-mass: transmission through 10 cells")
ax.legend(fontsize=8, loc="lower left")
