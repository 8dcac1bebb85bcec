"""
FPUT recurrence and modal energies
==================================

The 1955 Fermi–Pasta–Ulam–Tsingou problem: 32 masses between walls joined by springs of
energy V(d) = k d²/2 + α d³/3 (α = 0.25), all the energy initially in the lowest mode. The
bundled ``fput_alpha`` scene records each linear mode's harmonic energy
E_j = ½(q̇_j² + ω_j² q_j²) (``modal_energy=True``): mode 1 gives its energy to modes 2, 3, 4, …
and takes almost all of it back.
"""

import tempfile

from matplotlib.figure import Figure

import springchain as sc

frames = tempfile.TemporaryDirectory()  # [chain] runs stream their frames to an NPZ in `out`
run = sc.simulate("fput_alpha", methods=["verlet"], record_every=200, modal_energy=True, progress=False,
                  out=frames.name)
E = run.extra["modal_energy_verlet"]  # (S, N), ascending omega
print("frames x modes:", E.shape, " t_end =", run.t[-1])

energies = Figure(figsize=(8, 4), layout="constrained")
ax = energies.subplots()
for j in range(5):
    ax.plot(run.t, E[:, j], lw=0.9, label=f"mode {j + 1}")
ax.set(xlabel="t", ylabel="E_j", title="FPUT-α, N = 32: energy of the lowest modes (Verlet, dt = 0.1)")
ax.legend()

# %%
# The largest share of the energy back in mode 1 after it first left:
share = E[:, 0] / E[0, 0]
later = run.t > 1000
print(f"mode 1 returns to {share[later].max():.1%} of its initial energy at t = {run.t[later][share[later].argmax()]:.0f}")
