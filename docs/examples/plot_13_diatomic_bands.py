"""
Bands of the diatomic chain
===========================

The textbook periodic chain: masses m1 = 1 and m2 = 3 alternating, springs k1 = 1 inside a cell and
k2 = 2 between cells (the bundled ``diatomic``, a ``[chain]`` whose expressions repeat in ``i``).
``springchain bands diatomic`` finds the period from the expressions, derives the Bloch matrix D(q)
and the two branches in closed form, and computes the gap between the acoustic and the optical
branch, the attenuation inside it, the density of states and the modes of the scene's own free
chain of 40 cells — one of which sits inside the gap, at the chain's end.
"""

import mpmath
import numpy as np
from matplotlib.figure import Figure

import springchain as sc

b = sc.bands("diatomic")
print(b.to_text().split("\nThe finite chain")[0])
bands_figure = b.plot()

# %%
# The band edges against the textbook formula
# ω²∓(q) = (k1 + k2)(1/m1 + 1/m2)/2 ∓ sqrt(((k1 + k2)(1/m1 + 1/m2)/2)² − 4k1k2 sin²(q/2)/(m1m2)),
# evaluated here at 50 digits: the gap runs from ω−(π) to ω+(π).
mpmath.mp.dps = 50
m1, m2, k1, k2 = (mpmath.mpf(v) for v in (1, 3, 1, 2))


def textbook(q):
    a = (k1 + k2) * (1 / m1 + 1 / m2) / 2
    r = mpmath.sqrt(a * a - 4 * k1 * k2 * mpmath.sin(mpmath.mpf(q) / 2) ** 2 / (m1 * m2))
    return a - r, a + r


lo, hi = (mpmath.sqrt(w2) for w2 in textbook(mpmath.pi))
gap = b.gaps[0]
print(f"gap {gap.omega_lower:.15f} ... {gap.omega_upper:.15f} rad/s")
print(f"relative error of the edges: {float(abs(gap.omega_lower - lo) / lo):.1e}, "
      f"{float(abs(gap.omega_upper - hi) / hi):.1e}")

# %%
# The free chain's gap mode is an edge mode: it decays into the chain by e^{−Im q} per cell, Im q
# the attenuation of the complex band structure at its frequency.
edge = next(m for m in b.finite if m.kind != "band")
print(f"{edge.kind} mode at omega = {edge.omega:.12f} rad/s (inside the gap), localisation length "
      f"{edge.localisation:.6f} cells = 1/Im q = {1 / b.attenuation([edge.omega])[0][0]:.6f}")

# %%
# At contrast: the heavy mass 10⁸ times the light one. The acoustic branch near q = 0 is a small
# difference of two large numbers in the textbook formula and in D(q) formed in float64;
# springchain's route (elimination on the cell's elements, one-sided Jacobi) keeps it to a few ulps,
# exactly 0 at q = 0.
heavy = sc.load("diatomic").with_parameters(m2=1e8)
q = np.concatenate([-np.logspace(-8, np.log10(np.pi), 60)[::-1], [0.0], np.logspace(-8, np.log10(np.pi), 60)])
ours = sc.bands(heavy, q=q, finite=False, density=False).omega2[:, 0]
M2 = mpmath.mpf(10) ** 8
reference = []
for x in q:
    a = (k1 + k2) * (1 / m1 + 1 / M2) / 2
    s2 = mpmath.sin(mpmath.mpf(x) / 2) ** 2
    reference.append(4 * k1 * k2 * s2 / (m1 * M2) / (a + mpmath.sqrt(a * a - 4 * k1 * k2 * s2 / (m1 * M2))))


def float64_D(x):
    """D(q) formed in float64 and handed to eigvalsh: the textbook numeric route."""
    kq = np.array([[3.0, -1.0 - 2.0 * np.exp(-1j * x)], [-1.0 - 2.0 * np.exp(1j * x), 3.0]])
    s = 1 / np.sqrt([1.0, 1e8])
    return np.linalg.eigvalsh(kq * s[:, None] * s[None, :])[0]


naive = np.array([float64_D(x) for x in q])
err = lambda got: np.array([float(abs(g - r) / r) if r else abs(g) for g, r in zip(got, reference)])  # noqa: E731
print(f"acoustic branch at m2/m1 = 1e8: worst relative error springchain {err(ours).max():.1e}, "
      f"float64 D(q) + eigvalsh {err(naive).max():.1e}; omega^2(0) = {float(ours[q == 0][0])!r}")

errors = Figure(figsize=(7, 3.2), layout="constrained")
ax = errors.subplots()
pos = q > 0
ax.loglog(q[pos], np.maximum(err(naive)[pos], 1e-18), label="float64 D(q), eigvalsh")
ax.loglog(q[pos], np.maximum(err(ours)[pos], 1e-18), label="springchain")
ax.set(xlabel="q [rad per cell]", ylabel="relative error vs 50 digits",
       title="acoustic branch of the diatomic chain, m2/m1 = 1e8")
ax.legend()
