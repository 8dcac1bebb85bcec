"""
Animations: a mode and a run
============================

``sc.animate`` writes a GIF of a mode oscillating through one period, or of a simulated run.
Masses are dots (area ∝ mass) on a line joined by springs; displacements are scaled to be
visible. The figure is not pyplot's, so a notebook's backend is never touched.
"""

import tempfile

import springchain as sc

out = tempfile.mkdtemp()
mode2 = sc.animate("seed", mode=2, frames=16, out=out)
print(mode2.describe())

# %%
# The ring of four masses (a repeated ω² = 2k/m), simulated by Verlet:
ring = sc.animate("ring4", method="verlet", frames=16, out=out)
print(ring.describe())
