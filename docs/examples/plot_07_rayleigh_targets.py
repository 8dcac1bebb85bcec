"""
Rayleigh damping from targets
=============================

Rayleigh damping C = αM + βK gives every mode the damping ratio ζ(ω) = α/(2ω) + βω/2. Given
two target ratios at two modes, springchain solves for α and β (in closed form, in the scene's
parameters) — here 2 % at modes 1 and 3 of the three-storey ``building``.
"""

import numpy as np
from matplotlib.figure import Figure

import springchain as sc

fit = sc.rayleigh_coefficients("building", zeta=(0.02, 0.02), modes=(1, 3))
print(f"alpha = {fit.alpha:.6g} 1/s, beta = {fit.beta:.6g} s")
print("zeta of every elastic mode:", fit.zeta)

# %%
# The curve ζ(ω) and the three modes on it: modes 1 and 3 meet the targets, mode 2 lies below.
w = np.sqrt(np.asarray(sc.modes("building").omega2_values, dtype=float))
grid = np.geomspace(w.min() / 2, w.max() * 2, 200)
curve = Figure(figsize=(7, 3.5), layout="constrained")
ax = curve.subplots()
ax.plot(grid, fit.alpha / (2 * grid) + fit.beta * grid / 2, label="α/(2ω) + βω/2")
ax.plot(w, fit.alpha / (2 * w) + fit.beta * w / 2, "o", label="the building's modes")
ax.axhline(0.02, color="k", lw=0.5)
ax.set(xscale="log", xlabel="ω [rad/s]", ylabel="ζ", title="Rayleigh damping from targets: 2 % at modes 1 and 3")
ax.legend()

# %%
# In a scene file the same is one line, ``rayleigh_targets = {zeta = [0.02, 0.02], modes = [1, 3]}``
# in ``[damping]``; the bundled ``shear_building`` uses it.
print(sc.load("shear_building").source["damping"])
