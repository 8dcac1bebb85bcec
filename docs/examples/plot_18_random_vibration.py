"""
Random vibration: RMS by the exact modal integral
=================================================

``sc.random_response`` (``springchain psd``) gives the RMS response to a random input described by its
one-sided PSD per Hz — the form of vibration-test profiles — as the exact integral of G(f)|H|² over the
band: in closed form per segment of the PSD, with no frequency grid. Two checks: a single oscillator
on a shaking base against Miles' equation and a 30-digit quadrature written here, and the three-storey
``building_rayleigh`` against the integral sampled on ever finer grids, which converges to it slowly
because the resonances are sharp.
"""

import math
import tempfile
from pathlib import Path

import mpmath
import numpy as np
import scipy.signal
from matplotlib.figure import Figure

import springchain as sc

# %%
# One mass on a spring and a dashpot to a shaking base: f_n = 10 Hz, ζ = 5 %, under a flat base
# acceleration PSD G = 0.01 g²/Hz from 0.1 to 1000 Hz. Miles' equation gives the absolute acceleration
# over an infinite band, a_rms² = (π/2)·f_n·Q·G·(1 + 4ζ²) with Q = 1/(2ζ); the band-limited integral is
# smaller by its two tails, about G·(f1 + (2ζf_n)²/f2).
fn, zeta, mass = 10.0, 0.05, 100.0
wn = 2 * math.pi * fn
oscillator = sc.scene_from_dict({
    "name": "oscillator", "parameters": {"m": mass, "k": mass * wn**2, "c": 2 * zeta * mass * wn},
    "masses": {"a": "m"}, "springs": [{"between": ["wall", "a"], "k": "k"}],
    "dampers": [{"between": ["wall", "a"], "c": "c"}]})
g0 = 9.80665
G, f1, f2 = 0.01 * g0**2, 0.1, 1000.0  # (m/s^2)^2/Hz
r = sc.random_response(oscillator, {"f": [f1, f2], "psd": [G, G]})
ours = r.rms("a", "acceleration")

mpmath.mp.dps = 30
W, Z = mpmath.mpf(wn), mpmath.mpf(zeta)


def h2(f):  # |absolute acceleration / base acceleration|^2 of the oscillator
    w = 2 * mpmath.pi * f
    return (W**4 + (2 * Z * W * w) ** 2) / ((W**2 - w**2) ** 2 + (2 * Z * W * w) ** 2)


quad = float(mpmath.sqrt(mpmath.mpf(G) * mpmath.quad(h2, [f1, fn * 0.9, fn, fn * 1.1, f2])))
miles = math.sqrt(math.pi / 2 * fn * (1 / (2 * zeta)) * G * (1 + 4 * zeta**2))
tails = math.sqrt(miles**2 - G * (f1 + (2 * zeta * fn) ** 2 / f2))
print(f"a_rms springchain {ours / g0:.12f} g; 30-digit quadrature {quad / g0:.12f} g "
      f"(relative difference {abs(ours / quad - 1):.1e})")
print(f"Miles (infinite band) {miles / g0:.12f} g; less the two tails {tails / g0:.12f} g")

# %%
# The three-storey building with Rayleigh damping (2 % in modes 1 and 3) under a test profile in
# g²/Hz (a CSV with the units in its header), rising 3 dB/octave to a plateau from 4 to 20 Hz: every
# floor's response, accelerations in g because the input is.
profile = {"f": [1.0, 4.0, 20.0, 50.0], "psd": [0.005, 0.02, 0.02, 0.004]}  # g^2/Hz
spec = Path(tempfile.mkdtemp()) / "profile.csv"
spec.write_text("f [Hz], psd [g^2/Hz]\n" + "".join(f"{f}, {v}\n" for f, v in zip(profile["f"], profile["psd"])))
building = sc.random_response("building_rayleigh", spec)
print(building.to_text())
psd_figure = building.plot("acceleration")

# %%
# The RMS displacement of the top floor relative to the base, again by sampling: H from the state-space
# model (``sc.state_space``, the ground acceleration in, floor3's displacement out) on N log-spaced
# frequencies, and the trapezoidal rule. With 2 % damping the half-power width of the first resonance
# is 4 % of its frequency: the sampled integral needs hundreds of points for three digits.
exact = building.rms("floor3", "displacement")
model = sc.state_space("building_rayleigh", inputs="ground", outputs="floor3")
counts = np.array([25, 50, 100, 200, 400, 800, 1600, 3200])
errors = []
for count in counts:
    f = np.geomspace(profile["f"][0], profile["f"][-1], count)
    Gf = np.exp(np.interp(np.log(f), np.log(profile["f"]), np.log(profile["psd"]))) * g0**2
    _, H = scipy.signal.freqresp(model, 2 * np.pi * f)
    errors.append(abs(math.sqrt(np.trapezoid(Gf * np.abs(H) ** 2, f)) / exact - 1))
print(f"floor3 displacement relative to the base: {1e3 * exact:.6f} mm RMS (exact integral)")
print("sampled: " + ", ".join(f"N={n}: {e:.1e}" for n, e in zip(counts, errors)))

sampling = Figure(figsize=(6, 3.8), layout="constrained")
ax = sampling.subplots()
ax.loglog(counts, errors, "o-")
ax.set(xlabel="frequencies sampled (log-spaced, trapezoidal rule)", ylabel="relative error of the RMS",
       title="sampling the PSD integral vs the exact one")
ax.grid(alpha=0.3, which="both")
