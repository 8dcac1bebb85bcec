"""
Work–precision and plan
=======================

For a linear scene the exact answer is known, so every method's error is measured, not
estimated. ``sc.bench`` runs each method over a sweep of steps (or tolerances) against the
exact solution; ``sc.plan`` predicts, from closed-form error models, the step each method needs
for a tolerance and what it costs, and recommends the cheapest. (``quick=True``: a short sweep.)
"""

from collections import defaultdict

from matplotlib.figure import Figure

import springchain as sc

result = sc.bench("seed", quick=True, methods=["verlet", "yoshida4", "blanes-moan6", "rk4", "dop853"])
curves = defaultdict(list)
for r in result.records:
    curves[r.method].append((r.error, r.force_evals, r.seconds))

# force evaluations (deterministic) and seconds (this machine, now) against the error
work = Figure(figsize=(10, 4), layout="constrained")
axes = work.subplots(1, 2, sharey=True)
for name, pts in curves.items():
    err, evals, secs = zip(*sorted(pts, reverse=True))
    axes[0].loglog(evals, err, "o-", label=name)
    axes[1].loglog(secs, err, "o-", label=name)
axes[0].set(xlabel="force evaluations", ylabel="largest position error over t ∈ [0, 100]")
axes[1].set(xlabel="seconds")
axes[0].legend()
work.suptitle("seed: work–precision (quick bench)")

# %%
# The plan for a tolerance of 1e-6 over the scene's horizon: every candidate with its step,
# predicted error and predicted cost; the exact method needs no step at all.
p = sc.plan("seed", tol=1e-6)
for c in p.candidates[:6]:
    step = "no step" if c.dt is None else f"dt = {c.dt:.4g}"
    print(f"{c.name:14s} {step:>14}  predicted error {c.predicted_error:.2e}  predicted {c.predicted_seconds:.2e} s")
print("recommended:", p.recommended.name)
