"""
A hanging chain under gravity
=============================

The bundled ``hanging`` scene: three masses hung from a ceiling by springs, under gravity,
released at rest from the springs' rest lengths. The chain oscillates about its static sag
x_eq = K⁻¹Mg. We compute the sag by hand from the scene's numbers and compare it with the
equilibrium springchain prints and with the centre of the exact motion.
"""

import numpy as np

import springchain as sc

m = sc.modes("hanging")
print(m.to_text()[:1200])

# %%
# The sag by hand: m = 0.5 kg, k = 50 N/m, g = 9.81 m/s², masses m, m, 2m. Each spring carries
# the weight below it, so the extensions are (4m, 3m, 2m)·g/k, summed from the ceiling down.
mass, k, g = 0.5, 50.0, 9.81
extensions = np.array([4, 3, 2]) * mass * g / k
sag = np.cumsum(extensions)
print("sag by hand:", sag)

# %%
# The exact motion oscillates about the sag: its time average over many periods approaches it.
run = sc.simulate("hanging", methods=["modal"], steps=20000, progress=False)
fig = run.plot()
print("time average of the exact motion:", run.x["modal"].mean(axis=0))
