"""
A shear building under an accelerogram
======================================

The bundled ``shear_building``: three storeys (floors 10 t, storeys 4 MN/m) with Rayleigh
damping of 5 % at modes 1 and 3, whose base follows the synthetic accelerogram
``quake-record`` (``docs/building_quake.py`` says how it was made). We compute the record's
response spectra, a response-spectrum analysis (RSA) of the building, and the exact time history,
and compare the RSA peaks with the time history's.
"""

import numpy as np
from matplotlib.figure import Figure

import springchain as sc

spectrum = sc.response_spectrum("quake-record", zeta=[0.02, 0.05])
spectrum_figure = spectrum.plot()

# %%
# The response-spectrum analysis: per mode its period, damping ratio, participation factor,
# effective mass and spectral values; then the peaks combined by SRSS and CQC.
r = sc.rsa("shear_building", spectrum="quake-record")
print(r.to_text())

# %%
# The exact time history of the same scene and record (augmented matrix exponential with
# first-order hold: exact for the piecewise-linear record), with spring forces.
run = sc.simulate("shear_building", methods=["modal"], springs=True, progress=False)
peak_x = np.abs(run.x["modal"]).max(axis=0)
peak_drift = np.abs(run.drifts("modal")).max(axis=0)
peak_force = np.abs(run.spring_forces("modal")).max(axis=0)
peak_base = np.abs(run.base_shear("modal")).max()
srss, cqc = r.combined("srss"), r.combined("cqc")
print(f"{'quantity':<28}{'SRSS':>10}{'CQC':>10}{'history':>10}{'CQC/TH':>8}")
for i, name in enumerate(run.scene.mass_names):
    print(f"{'peak x ' + name + ' [mm]':<28}{1e3 * srss['displacement'][i]:>10.2f}{1e3 * cqc['displacement'][i]:>10.2f}"
          f"{1e3 * peak_x[i]:>10.2f}{cqc['displacement'][i] / peak_x[i]:>8.3f}")
for s, lab in enumerate(r.labels):
    print(f"{'drift ' + lab + ' [mm]':<28}{1e3 * srss['drift'][s]:>10.2f}{1e3 * cqc['drift'][s]:>10.2f}"
          f"{1e3 * peak_drift[s]:>10.2f}{cqc['drift'][s] / peak_drift[s]:>8.3f}")
print(f"{'base shear [kN]':<28}{1e-3 * srss['base_shear']:>10.1f}{1e-3 * cqc['base_shear']:>10.1f}"
      f"{1e-3 * peak_base:>10.1f}{cqc['base_shear'] / peak_base:>8.3f}")

# %%
# RSA estimates peaks that do not occur at the same instant. It is close for the quantities the
# first mode dominates and lower where a higher mode reinforces the first more than SRSS and CQC
# assume (the top storey's drift).
comparison = Figure(figsize=(10, 4), layout="constrained")
axes = comparison.subplots(1, 2)
for ax, key, th, unit, scale, title in ((axes[0], "drift", peak_drift, "mm", 1e3, "inter-storey drift"),
                                        (axes[1], "spring_force", peak_force, "kN", 1e-3, "storey shear")):
    x = np.arange(len(r.labels))
    ax.bar(x - 0.27, scale * srss[key], 0.27, label="RSA, SRSS")
    ax.bar(x, scale * cqc[key], 0.27, label="RSA, CQC")
    ax.bar(x + 0.27, scale * th, 0.27, label="time history (exact)")
    ax.set_xticks(x, r.labels)
    ax.set(ylabel=f"peak {title} [{unit}]", title=title)
axes[0].legend()

# %%
# The roof's displacement relative to the ground over the record:
history = Figure(figsize=(8, 3), layout="constrained")
ax = history.subplots()
ax.plot(run.t, 1e3 * run.x["modal"][:, -1], lw=0.8)
ax.set(xlabel="t [s]", ylabel="roof x [mm]", title="shear_building under quake-record (exact)")
