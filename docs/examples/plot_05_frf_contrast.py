"""
Frequency response at wide stiffness contrast
=============================================

Four unit masses in a line from a wall, joined by springs log-spaced over twelve decades —
1e-6 N/m at the wall, then 1e-2, 1e2 and 1e6 N/m — with a dashpot from the last mass to the
wall. Forming K − ω²M + iωC in float64 rounds the weak springs away next to the strong ones;
springchain's frequency response never forms it: it solves in the accurate modal basis and
certifies each frequency (refining it in extended precision where float64 cannot be certified).
We compare both with a 50-digit solve written here.
"""

import mpmath
import numpy as np
from matplotlib.figure import Figure

import springchain as sc

k = [1e-6, 1e-2, 1e2, 1e6]
scene = sc.scene_from_dict({
    "name": "contrast",
    "parameters": {"m": 1.0, "c": 0.01},
    "masses": {"p": "m", "q": "m", "r": "m", "s": "m"},
    "springs": [{"between": ["wall", "p"], "k": repr(k[0])}, {"between": ["p", "q"], "k": repr(k[1])},
                {"between": ["q", "r"], "k": repr(k[2])}, {"between": ["r", "s"], "k": repr(k[3])}],
    "dampers": [{"between": ["s", "wall"], "c": "c"}],
})
h = sc.frf(scene, input="s", output="s", points=100, transfer=False)
print(h.to_text())
bode = h.plot()

# %%
# The reference: Z = K − ω²M + iωC assembled element by element in 50-digit arithmetic and solved
# by mpmath. Beside it, the textbook float64 route (assemble Z in float64, then LU).
mpmath.mp.dps = 50
K = mpmath.zeros(4, 4)
for (a, b), kk in zip(((-1, 0), (0, 1), (1, 2), (2, 3)), k):
    kk = mpmath.mpf(kk)
    for i in (a, b):
        if i >= 0:
            K[i, i] += kk
    if a >= 0:
        K[a, b] -= kk
        K[b, a] -= kk
e = mpmath.matrix([0, 0, 0, 1])
reference = []
for w in h.omega:
    w = mpmath.mpf(w)
    Z = K - w**2 * mpmath.eye(4)
    Z[3, 3] += 1j * w * mpmath.mpf("0.01")
    reference.append(complex(mpmath.lu_solve(Z, e)[3]))
reference = np.array(reference)

Kf = np.array(K.tolist(), dtype=float)
C = np.zeros((4, 4))
C[3, 3] = 0.01
naive = np.array([np.linalg.solve(Kf - w**2 * np.eye(4) + 1j * w * C, np.eye(4)[3])[3] for w in h.omega])
H = h.magnitude * np.exp(1j * np.radians(h.phase))
err_sc = np.abs(H - reference) / np.abs(reference)
err_naive = np.abs(naive - reference) / np.abs(reference)
print(f"worst relative error over {len(h.omega)} frequencies: springchain {err_sc.max():.1e}, "
      f"float64 assembly and LU {err_naive.max():.1e}")

errors = Figure(figsize=(7, 3.2), layout="constrained")
ax = errors.subplots()
ax.loglog(h.omega, err_naive, label="float64 K − ω²M + iωC, LU")
ax.loglog(h.omega, np.maximum(err_sc, 1e-17), label="springchain")
ax.set(xlabel="ω [rad/s]", ylabel="relative error vs 50 digits", title="receptance at 12 decades of stiffness")
ax.legend()
