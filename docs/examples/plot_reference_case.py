"""
The reference case: m, 3m, m
============================

Three masses m, 3m, m joined by two springs k. The closed-form modes are
ω² = 0, k/m and 5k/(3m); the exact solution is compared with velocity Verlet.
"""

import springchain as sc

m = sc.modes("seed")
print(m.omega2)
print(m.omega2_values)

# %%
# Simulate with the exact (modal) method and Verlet, and plot the positions.
run = sc.simulate("seed", steps=500, progress=False)
fig = run.plot()
