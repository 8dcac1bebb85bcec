"""
Units and the forms of a frequency response
===========================================

A two-storey building on base isolation, written in engineering units (the ``units`` extra): floors
of 30 t on a 40 t base slab, isolators of 3 MN/m with 120 kN·s/m of damping, storeys of 60 MN/m.
Values are converted to SI once, when the scene is loaded. From the accurate receptance, springchain
gives the forms a test lab reads — mobility, accelerance, dynamic stiffness, transmissibility — in Hz,
dB and the units asked for. The transmissibility is summed over the isolators' couplings, so it stays
accurate where the isolation works best and the textbook form 1 + Z/X_g cancels to nothing; a
40-digit solve written here is the reference.
"""

import contextlib
import io
import tempfile
from pathlib import Path

import mpmath
import numpy as np
from matplotlib.figure import Figure

import springchain as sc
from springchain.cli import main

folder = Path(tempfile.mkdtemp())
toml = folder / "isolated.toml"
toml.write_text('''\
name = "isolated"
description = "Two storeys on base isolation, in engineering units"

[parameters]
mb = "40 t"            # base slab
m = "30 t"             # each floor
k_iso = "3 MN/m"       # isolators
c_iso = "120 kN*s/m"   # their damping
k = "60 MN/m"          # each storey

[masses]
base = "mb"
floor1 = "m"
floor2 = "m"

[[springs]]
between = ["wall", "base"]
k = "k_iso"

[[springs]]
between = ["base", "floor1"]
k = "k"

[[springs]]
between = ["floor1", "floor2"]
k = "k"

[[dampers]]
between = ["wall", "base"]
c = "c_iso"
''')
scene = sc.load(toml)
print("in SI:", scene.parameters)

# %%
# The command line in engineering units: the roof's accelerance in g per kN against frequency in Hz.
out = io.StringIO()
with contextlib.redirect_stdout(out):
    main(["frf", str(toml), "--input", "floor2", "--output", "floor2", "--form", "accelerance", "--hz",
          "--units", "mm,kN,g", "--out", str(folder)])
print(out.getvalue())
accelerance_png = folder / "isolated-frf-accelerance-floor2-floor2.png"

# %%
# The four force-input forms from one receptance (``sc.frf_form`` reuses its grid and values), in Hz
# and dB re 1 SI unit:
h = sc.frf(scene, input="floor2", output="floor2")
forms = Figure(figsize=(8, 5.5), layout="constrained")
axes = forms.subplots(2, 2, sharex=True).ravel()
for ax, name in zip(axes, ("receptance", "mobility", "accelerance", "dynamic-stiffness")):
    f = sc.frf_form(h, name, hz=True, db=True)
    ax.semilogx(f.frequency, f.magnitude(), lw=1.2)
    ax.set(title=f"{name}: {f.unit}", ylabel=f"dB re 1 {f.unit}")
    ax.grid(alpha=0.3, which="both")
for ax in axes[2:]:
    ax.set_xlabel("frequency [Hz]")

# %%
# Transmissibility from the ground to the roof, far above the isolation frequency, against a 40-digit
# solve of (K − ω²M + iωC) x = (k_iso + iω c_iso) x_g assembled here from the SI values. The textbook
# route, 1 + Z/X_g from the relative transmissibility, loses the digits the isolation removes.
T = sc.frf_form(scene, "transmissibility", output="floor2", hz=True, omega_min=0.5, omega_max=2000.0, points=300)
Trel = sc.frf_form(scene, "relative-transmissibility", output="floor2", hz=True, omega_min=0.5,
                   omega_max=2000.0, points=300)
textbook = 1 + Trel.values

mpmath.mp.dps = 40
p = {name: mpmath.mpf(v) for name, v in scene.parameters.items()}
mass = [p["mb"], p["m"], p["m"]]
stiff = mpmath.matrix([[p["k_iso"] + p["k"], -p["k"], 0], [-p["k"], 2 * p["k"], -p["k"]], [0, -p["k"], p["k"]]])


def reference(w):
    s = 1j * mpmath.mpf(w)
    Z = mpmath.matrix(3, 3)
    for i in range(3):
        for j in range(3):
            Z[i, j] = stiff[i, j] + (s * s * mass[i] if i == j else 0) + (s * p["c_iso"] if i == j == 0 else 0)
    return complex(mpmath.lu_solve(Z, mpmath.matrix([p["k_iso"] + s * p["c_iso"], 0, 0]))[2])


ref = np.array([reference(w) for w in T.omega])
err_ours = np.abs(T.values - ref) / np.abs(ref)
err_textbook = np.abs(textbook - ref) / np.abs(ref)
print(f"|T| from {np.abs(ref).max():.3g} down to {np.abs(ref).min():.2e}; worst relative error: springchain "
      f"{err_ours.max():.1e}, textbook 1 + Z/X_g {err_textbook.max():.1e}")

trans = Figure(figsize=(8, 5.5), layout="constrained")
top, bottom = trans.subplots(2, 1, sharex=True)
top.loglog(T.frequency, np.abs(T.values), lw=1.2, label="|X_roof / X_g|")
top.set(ylabel="transmissibility [-]", title="base-isolated building: ground to roof")
top.grid(alpha=0.3, which="both")
bottom.loglog(T.frequency, np.maximum(err_textbook, 1e-17), lw=1, label="textbook 1 + Z/X_g")
bottom.loglog(T.frequency, np.maximum(err_ours, 1e-17), lw=1, label="springchain (sum over the isolators)")
bottom.set(xlabel="frequency [Hz]", ylabel="relative error vs 40 digits")
bottom.grid(alpha=0.3, which="both")
bottom.legend(fontsize=8)
