"""The synthetic accelerogram of ``scenes/building_quake.toml`` and the README figure.

No package on the registries we checked ships a real strong-motion record as data (``eqsig``,
``pyrotd`` and ``pyexsi`` hold code and pickled test fixtures, no El Centro), so the record is
synthetic and documented here:

* white noise (``numpy.random.default_rng(1940)``, dt = 0.01 s) filtered by the Kanai–Tajimi
  ground filter (ω_g = 5π rad/s, ζ_g = 0.6: firm soil), held constant over each sample and filtered exactly (matrix exponential);
* a Jennings–Housner–Tsai envelope: (t/2)² rising to 1 at 2 s, 1 until 10 s, exp(−0.3 (t − 10))
  after, cut at 20 s, and the last row set to 0 (the table is zero outside its rows);
* scaled to a peak ground acceleration of 0.3 g = 2.942 m/s².

Run from the repository root::

    python docs/building_quake.py            # writes scenes/quake-record.csv and the figure
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.linalg

ROOT = Path(__file__).resolve().parent.parent
DT, T_END, PGA = 0.01, 20.0, 0.3 * 9.80665
OMEGA_G, ZETA_G = 5 * np.pi, 0.6


def record(seed: int = 1940) -> tuple[np.ndarray, np.ndarray]:
    """Times (R,) and ground acceleration (R,) in m/s²."""
    steps = int(round(T_END / DT))
    t = np.arange(steps + 1) * DT
    w = np.random.default_rng(seed).standard_normal(steps + 1) / np.sqrt(DT)
    # filter: y'' + 2 ζ ω y' + ω² y = -w;  a_g = -(2 ζ ω y' + ω² y)  (Kanai–Tajimi)
    A = np.array([[0.0, 1.0], [-OMEGA_G**2, -2 * ZETA_G * OMEGA_G]])
    E = scipy.linalg.expm(A * DT)
    G = np.linalg.solve(A, (E - np.eye(2)) @ np.array([0.0, -1.0]))  # zero-order hold of w
    z = np.zeros(2)
    a = np.empty(steps + 1)
    for i in range(steps + 1):  # loop over samples of the record (not over masses)
        a[i] = -(2 * ZETA_G * OMEGA_G * z[1] + OMEGA_G**2 * z[0])
        z = E @ z + G * w[i]
    env = np.where(t < 2.0, (t / 2.0) ** 2, np.where(t <= 10.0, 1.0, np.exp(-0.3 * (t - 10.0))))
    a = a * env
    a[-1] = 0.0
    return t, a * (PGA / np.max(np.abs(a)))


def write_record(path: Path) -> None:
    t, a = record()
    lines = ["t,a"] + [f"{ti:.2f},{round(ai, 6) + 0.0:.6f}" for ti, ai in zip(t, a)]
    path.write_text("\n".join(lines) + "\n")


def figure(out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import springchain as sc

    run = sc.simulate("building_quake", progress=False)
    scene = run.scene
    tt, ag = scene.ground.table.t, scene.ground.table.y
    fig, axes = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
    axes[0].plot(tt, ag, color="0.3", lw=0.8)
    axes[0].set_ylabel("a_g (m/s²)")
    axes[0].set_title("building_quake: 3 storeys under a synthetic Kanai–Tajimi record (PGA 0.3 g)")
    for j, name in enumerate(scene.mass_names):
        axes[1].plot(run.t, 100 * run.x["modal"][:, j], lw=0.9, label=f"{name} (exact)")
    axes[1].plot(run.t, 100 * run.x["verlet"][:, -1], "k:", lw=0.8, label="floor3 (Verlet)")
    axes[1].set_ylabel("drift from ground (cm)")
    axes[1].legend(loc="upper right", fontsize=8)
    axes[2].plot(run.t, run.extra["aabs_modal"][:, -1], lw=0.9, label="floor3 absolute")
    axes[2].plot(tt, ag, color="0.6", lw=0.6, label="ground")
    axes[2].set_ylabel("absolute acc. (m/s²)")
    axes[2].set_xlabel("t (s)")
    axes[2].legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    d = np.max(np.abs(run.x["verlet"] - run.x["modal"]))
    print(f"max |x_verlet - x_exact| = {d:.3e} m; peak roof drift {np.max(np.abs(run.x['modal'][:, -1])):.4f} m; "
          f"peak roof absolute acceleration {np.max(np.abs(run.extra['aabs_modal'][:, -1])):.3f} m/s²")


if __name__ == "__main__":
    write_record(ROOT / "scenes" / "quake-record.csv")
    figure(ROOT / "docs" / "figures" / "building-quake.png")
