"""The README's "Structural dynamics" figures and numbers: `python docs/structural.py` from the repository root.

Writes docs/figures/quake-record-spectrum.png (response spectra of the synthetic record) and
docs/figures/shear-building-rsa.png (RSA by SRSS and CQC beside the peaks of the exact time
history), and prints the comparison table the README quotes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import springchain as sc
from springchain.numeric.plots import new_figure, save

ROOT = Path(__file__).resolve().parent.parent
FIGURES = ROOT / "docs" / "figures"
RECORD = ROOT / "scenes" / "quake-record.csv"


def main() -> None:
    spec = sc.response_spectrum(RECORD, zeta=[0.02, 0.05])
    save(spec.plot(), FIGURES / "quake-record-spectrum.png")
    rsa = sc.rsa("shear_building", spectrum=RECORD)
    run = sc.simulate("shear_building", methods=["modal", "newmark", "hht"], springs=True, progress=False)
    srss, cqc = rsa.combined("srss"), rsa.combined("cqc")
    peaks = {m: {"x": np.max(np.abs(run.x[m]), axis=0), "drift": np.max(np.abs(run.drifts(m)), axis=0),
                 "force": np.max(np.abs(run.spring_forces(m)), axis=0),
                 "base": float(np.max(np.abs(run.base_shear(m))))} for m in run.methods}
    th = peaks["modal"]
    print(f"{'quantity':<26}{'RSA SRSS':>12}{'RSA CQC':>12}{'time history':>14}{'CQC / TH':>10}")
    names = list(run.scene.mass_names)
    for i, nm in enumerate(names):
        print(f"{'peak x ' + nm + ' [mm]':<26}{1e3 * srss['displacement'][i]:>12.2f}{1e3 * cqc['displacement'][i]:>12.2f}"
              f"{1e3 * th['x'][i]:>14.2f}{cqc['displacement'][i] / th['x'][i]:>10.3f}")
    for s, lab in enumerate(rsa.labels):
        print(f"{'drift ' + lab + ' [mm]':<26}{1e3 * srss['drift'][s]:>12.2f}{1e3 * cqc['drift'][s]:>12.2f}"
              f"{1e3 * th['drift'][s]:>14.2f}{cqc['drift'][s] / th['drift'][s]:>10.3f}")
    for s, lab in enumerate(rsa.labels):
        print(f"{'shear ' + lab + ' [kN]':<26}{1e-3 * srss['spring_force'][s]:>12.1f}{1e-3 * cqc['spring_force'][s]:>12.1f}"
              f"{1e-3 * th['force'][s]:>14.1f}{cqc['spring_force'][s] / th['force'][s]:>10.3f}")
    print(f"{'base shear [kN]':<26}{1e-3 * srss['base_shear']:>12.1f}{1e-3 * cqc['base_shear']:>12.1f}"
          f"{1e-3 * th['base']:>14.1f}{cqc['base_shear'] / th['base']:>10.3f}")
    for m in ("newmark", "hht"):
        dx = float(np.max(np.abs(run.x[m] - run.x["modal"])))
        db = abs(peaks[m]["base"] - th["base"]) / th["base"]
        print(f"{m} (dt = {run.summary['dt']:g}): max |x - x_exact| = {dx:.2e} m, peak base shear off by {db:.1e}")
    fig, axes = new_figure(1, 2, figsize=(12, 4.5))
    for ax, key, th_key, unit, scale, title in ((axes[0], "drift", "drift", "mm", 1e3, "inter-storey drift"),
                                                (axes[1], "spring_force", "force", "kN", 1e-3, "storey shear")):
        x = np.arange(len(rsa.labels))
        w = 0.27
        ax.bar(x - w, scale * srss[key], w, label="RSA, SRSS")
        ax.bar(x, scale * cqc[key], w, label="RSA, CQC")
        ax.bar(x + w, scale * th[th_key], w, label="time history (exact), peak")
        ax.set_xticks(x, rsa.labels)
        ax.set_ylabel(f"peak {title} [{unit}]")
        ax.set_xlabel("storey spring")
        ax.set_title(f"shear_building under quake-record: {title}")
        ax.grid(alpha=0.3, axis="y")
        ax.legend(fontsize=8)
    save(fig, FIGURES / "shear-building-rsa.png")


if __name__ == "__main__":
    main()
