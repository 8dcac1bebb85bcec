"""
A Toda soliton
==============

The bundled ``toda`` scene: 128 free masses joined by springs of energy
V(d) = (a/b)·exp(−b d) + a d (the Toda lattice), started with one exact soliton (κ = 1) at site
32. The soliton travels without changing shape. We plot the compression −d of the springs at a
few times, and follow its peak.
"""

import tempfile

import numpy as np
from matplotlib.figure import Figure

import springchain as sc

frames = tempfile.TemporaryDirectory()  # [chain] runs stream their frames to an NPZ in `out`
run = sc.simulate("toda", methods=["verlet"], progress=False, out=frames.name)
x = run.x["verlet"]
compression = -(x[:, 1:] - x[:, :-1])  # -d of spring i, between masses i and i+1

snapshots = Figure(figsize=(8, 4), layout="constrained")
ax = snapshots.subplots()
for frame in np.linspace(0, len(run.t) - 1, 5).astype(int):
    ax.plot(compression[frame], lw=1, label=f"t = {run.t[frame]:.0f}")
ax.set(xlabel="spring i", ylabel="compression −d", title="Toda lattice: one soliton (Verlet, dt = 0.05)")
ax.legend()

# %%
# The soliton's speed: its peak position against time, beside the exact speed
# sinh(κ)/κ (in sites per unit time, for a = b = m = 1).
peak = compression.argmax(axis=1)
speed = np.polyfit(run.t, peak, 1)[0]
print(f"measured speed {speed:.3f} sites per unit time; exact sinh(1)/1 = {np.sinh(1.0):.3f}")
print(f"peak height at start {compression[0].max():.4f}, at the end {compression[-1].max():.4f}")
