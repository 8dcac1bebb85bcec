"""``springchain.frf``: the receptance H(iω) = X_out / F_in of a scene, its Bode figure and, for small
scenes, its transfer function in closed form. The numbers come from :mod:`springchain.numeric.frf.response`,
the algebra from :mod:`springchain.derive.transfer`; this module checks inputs and packages results.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from ._modules import check_linear_outputs
from ._defaults import DEFAULT_OUT
from .derive.scene import Scene

#: Most base grid points accepted.
MAX_POINTS = 1_000_000


@dataclass(frozen=True)
class FrequencyResponse:
    """A receptance on a grid refined at every resonance.

    Attributes
    ----------
    scene : Scene
    input, output : str
        Mass names (``[chain]`` scenes: the index as text).
    omega : ndarray, shape (W,)
        Angular frequencies [rad/s], ascending, never exactly on an undamped ω_j.
    H : ndarray, shape (W,), complex
        ``X_out / F_in`` [m/N].
    resonances : list of springchain.numeric.frf.response.Resonance
        Each damped one with the local maximum of |H| attributed to it (or None: none near it).
    transfer : springchain.derive.transfer.TransferFunction or None
        ``H(s)`` as a ratio of polynomials (``[masses]`` scenes of at most 6 masses).
    notes : list of str
    connected : bool
        False when input and output are on pieces no spring or dashpot joins (H ≡ 0).
    extra_peaks : list of (float, float)
        Local maxima (ω, |H|) of |H| attributed to no single resonance.
    """

    scene: Scene
    input: str
    output: str
    omega: object = field(repr=False)
    H: object = field(repr=False)
    resonances: list = field(default_factory=list, repr=False)
    transfer: object = field(default=None, repr=False)
    notes: list = field(default_factory=list, repr=False)
    #: False when no spring or dashpot joins input and output: H ≡ 0.
    connected: bool = True
    #: Local maxima ``(ω, |H|)`` attributed to no resonance.
    extra_peaks: list = field(default_factory=list, repr=False)
    #: arg H [rad] per frequency (None: from H): right also where |H| is below float64's range and H is 0.
    angle: object = field(default=None, repr=False)

    @property
    def magnitude(self):
        """|H| [m/N], ndarray, shape (W,)."""
        import numpy as np

        return np.abs(self.H)

    @property
    def phase(self):
        """Phase of H [degrees], unwrapped along ω, ndarray, shape (W,) (where |H| is below float64's range and
        printed as 0, the phase of the exact H)."""
        import numpy as np

        return np.degrees(np.unwrap(np.angle(self.H) if self.angle is None else self.angle))

    def to_json(self) -> dict:
        """Exactly what ``springchain frf ... --json`` prints."""
        return {"scene": self.scene.name, "input": self.input, "output": self.output,
                "omega": self.omega.tolist(), "magnitude": self.magnitude.tolist(), "phase": self.phase.tolist(),
                "units": {"omega": "rad/s", "magnitude": "m/N", "phase": "deg"},
                "resonances": [r.as_json() for r in self.resonances if r.participates],
                "connected": self.connected,
                "other_peaks": [{"omega": w, "magnitude": h} for w, h in self.extra_peaks],
                "transfer_function": None if self.transfer is None else self.transfer.as_json(),
                "notes": list(self.notes)}

    def to_text(self) -> str:
        """What ``springchain frf`` prints (without the ``wrote`` lines)."""
        w = self.omega
        lines = [f"frequency response of {self.scene.name!r}: H = X_{self.output} / F_{self.input} "
                 f"(receptance, m/N), {w.shape[0]} frequencies from {w[0]:.6g} to {w[-1]:.6g} rad/s"]
        if not self.connected:
            lines.append(f"no transfer: input {self.input} and output {self.output} are not connected (no chain of "
                         "springs or dashpots joins their pieces): H ≡ 0 at every ω, no resonance")
        seen = [r for r in self.resonances if r.participates]
        if seen:
            lines.append("resonances in range (undamped ω_n, damping ratio ζ, damped ω_d; the local maximum of |H| "
                         "near each, exact):")
        for r in seen:
            lines.append(_resonance_line(r))
        for r in self.resonances:
            if not r.participates:
                lines.append(f"  ω = {r.omega_n:.8g} rad/s: a mode with a node at the input or output (no resonance "
                             "in this H: |H| is finite there)")
        for wk, hk in self.extra_peaks:
            lines.append(f"  local maximum |H| = {hk:.6e} m/N at ω = {wk:.8g} rad/s (no listed damped resonance's own "
                         "peak)")
        if self.transfer is not None:
            lines += ["transfer function (adj(M s² + C s + K)[out, in] / det(M s² + C s + K), cancelled):",
                      self.transfer.text().rstrip("\n"), "LaTeX:", self.transfer.latex().rstrip("\n")]
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines) + "\n"

    def plot(self):
        """The Bode figure (a matplotlib Figure: |H| log-log, phase in degrees, resonances marked)."""
        from .numeric.plots import figures as plots

        peaks = tuple((r.peak_omega, r.peak_magnitude) for r in self.resonances
                      if r.participates and r.peak_omega is not None) + tuple(self.extra_peaks)
        infinite = tuple(r.omega_n for r in self.resonances if r.singular)
        hidden = tuple(r.omega_n for r in self.resonances if not r.participates)
        empty = None if self.connected else (f"H ≡ 0: input {self.input} and output {self.output} are not "
                                             "connected (no transfer)")
        return plots.bode(self.omega, self.magnitude, self.phase,
                          f"{self.scene.name}: receptance X_{self.output} / F_{self.input}",
                          peaks=tuple(sorted(peaks)), infinite=infinite[:200], hidden=hidden[:200], empty=empty)

    def save(self, out: str | Path = DEFAULT_OUT) -> Path:
        """Write the Bode figure as ``OUT/<scene>-frf-<input>-<output>.png``; returns its path."""
        from .numeric.plots import figures as plots

        path = Path(out) / f"{self.scene.name}-frf-{self.input}-{self.output}.png"
        plots.save(self.plot(), path)
        return path

    def __repr__(self) -> str:
        return (f"FrequencyResponse(scene={self.scene.name!r}, input={self.input!r}, output={self.output!r}, "
                f"frequencies={len(self.omega)})")

    def to_dataframe(self):
        """A ``pandas.DataFrame``: ``omega`` [rad/s], ``H`` (complex) [m/N], ``magnitude``, ``phase_deg``."""
        from ._data import frf_dataframe

        return frf_dataframe(self)

    def _repr_html_(self) -> str:  # the resonance table and the Bode figure
        from ._display import frf_html

        return frf_html(self)

    def _repr_png_(self) -> bytes:
        from ._display import frf_png

        return frf_png(self)

    def _repr_mimebundle_(self, include=None, exclude=None) -> dict:  # both, from one drawing
        from ._display import frf_bundle

        return frf_bundle(self)


def _resonance_line(r) -> str:
    """One row of the resonance table (a participating resonance)."""
    if math.isnan(r.zeta):
        return (f"  ω_n = {r.omega_n:.8g} rad/s (damped [chain]: ζ not computed, as `modes`; grid refined here)"
                + ("" if r.peak_omega is None else f"   local maximum |H| = {r.peak_magnitude:.6e} m/N at "
                   f"ω = {r.peak_omega:.8g} rad/s"))
    line = f"  ω_n = {r.omega_n:.8g} rad/s   ζ = {r.zeta:.4g}   ω_d = {r.omega_d:.8g} rad/s"
    if r.multiplicity > 1:
        line += f" ({r.multiplicity} modes: a repeated frequency)"
    if r.undamped:
        return line + "   |H| = ∞ at ω_n (undamped; the grid stops 1e-4 short on each side)"
    if r.narrow:
        return line + ("   peak narrower than float64 resolves in ω (relative width 2ζ): not located; the grid "
                       "stops 1e-4 short on each side")
    if r.peak_omega is None:
        return line + "   no local maximum of |H| near it (masked by a neighbouring mode, or damped out)"
    line += f"   peak |H| = {r.peak_magnitude:.6e} m/N at ω = {r.peak_omega:.8g} rad/s"
    if r.shifted:
        line += f" ({100 * r.shift:+.3g} % from ω_d: shifted by the neighbouring modes)"
    return line


def mass_index(scene: Scene, value, what: str) -> int:
    """The 0-based index of the mass ``value`` names (a name; an index for ``[chain]`` scenes)."""
    from .numeric.errors import RunRefused

    if scene.chain is not None:
        n = scene.chain.n
        text = str(value).strip() if isinstance(value, str | int) and not isinstance(value, bool) else None
        if text is not None and text.lstrip("-").isdigit() and 0 <= int(text) < n:
            return int(text)
        raise RunRefused(f"{what} {value!r}: not a mass of the [chain] scene {scene.name!r}; accepted: an "
                         f"index 0 ... {n - 1}", quantity=what)
    names = scene.mass_names
    if isinstance(value, str) and value in names:
        return names.index(value)
    from .derive.scene_loader import did_you_mean

    shown = ", ".join(repr(m) for m in names[:12]) + (", ..." if len(names) > 12 else "")
    raise RunRefused(f"{what} {value!r}: not a mass of scene {scene.name!r}; accepted: {shown}"
                     f"{did_you_mean(value, names)}", quantity=what)


def _check_omega(value, what: str):
    from .numeric.errors import RunRefused

    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, float | int) or not math.isfinite(value) or value <= 0:
        raise RunRefused(f"{what} {value!r}: accepted: a finite number > 0 [rad/s]", quantity=what)
    return float(value)


def frf(scene: str | Path | Scene, input, output, omega_min: float | None = None,
        omega_max: float | None = None, points: int = 400, *, transfer: bool = True) -> FrequencyResponse:
    """Receptance ``H(iω) = X_output / F_input`` of ``(K − ω²M + iωC) X = F``.

    Parameters
    ----------
    scene : str, Path or Scene
        As for :func:`springchain.load`.
    input, output : str or int
        Mass names; for ``[chain]`` scenes mass indices (0-based).
    omega_min, omega_max : float, optional
        Range [rad/s]; default the smallest nonzero natural frequency / 10 to the largest · 3.
    points : int
        Log-spaced base points; every resonance adds its refinement (and its exact peak).
    transfer : bool
        Also derive ``H(s)`` in closed form (SymPy) for ``[masses]`` scenes of at most 6 masses.

    Returns
    -------
    FrequencyResponse
        ``.omega``, ``.magnitude``, ``.phase`` (degrees), ``.to_json()``, ``.plot()``, ``.save(dir)``.

    Notes
    -----
    An undamped resonance has |H| = ∞ at ω_j: the grid stays 1e-4 (relative) away from it on both
    sides and the figure marks ω_j by a line. Cubic springs enter by their linear part; forces,
    gravity and ground motion do not change H.
    """
    from ._modules import system_of as _system
    from ._scenes import load
    from .numeric.errors import RunRefused
    from .numeric.frf.response import frequency_response

    sc = load(scene)
    check_linear_outputs(sc)  # a cubic [chain] under a constant load: one line
    i, o = mass_index(sc, input, "input"), mass_index(sc, output, "output")
    lo, hi = _check_omega(omega_min, "omega_min"), _check_omega(omega_max, "omega_max")
    if isinstance(points, bool) or not isinstance(points, int) or not 2 <= points <= MAX_POINTS:
        raise RunRefused(f"points {points!r}: accepted: a whole number 2 ... {MAX_POINTS}", quantity="points")
    system, _ = _system(sc)
    model, modes, zeta_note = None, None, None
    if sc.chain is None and system.damped:  # the resonance table from the damped modes `modes` prints
        from .derive.damping_report import damped_modes
        from .derive.model import Model

        from .derive.accurate import NotAccurate

        model = Model(sc)
        try:
            modes = [(r.omega_n, r.zeta, r.omega_d) for r in damped_modes(model, None).rows]
        except NotAccurate:  # ζ unsettled in extended precision: the table from the float64 state matrix
            zeta_note = ("damping ratios did not settle in extended precision (as `modes` says): the resonance "
                         "table's ζ and ω_d are from the float64 modal state matrix (H itself is certified)")
    elif sc.chain is not None and system.damped:
        modes = _chain_modes(sc, system)
    response = frequency_response(system, i, o, lo, hi, points, modes)
    notes = []
    if not system.linear:
        notes.append("nonlinear springs: the response of the linearisation about the equilibrium (their stiffness there)")
    if system.chain:
        notes.append("[chain] scene: tridiagonal solve per frequency; the grid is refined at the "
                     f"{min(len(response.resonances), 40)} lowest resonances in range")
    tf = None
    if transfer and sc.chain is None:
        from .derive.model import Model
        from .derive.transfer import MAX_MASSES, transfer_function

        if sc.n <= MAX_MASSES:
            tf = transfer_function(model or Model(sc), i, o)
            if tf is None:
                notes.append("no closed-form transfer function: its determinant is past the symbolic work cap")
    if sc.chain is not None and system.damped and any(math.isnan(r.zeta) for r in response.resonances):
        from .numeric.modes.chain_damping import DENSE_MAX

        notes.append(f"damping ratios not computed (as `modes`): dashpots on a chain of {sc.chain.n} masses (the "
                     f"dense modal state matrix is used up to {DENSE_MAX} masses, or ζ below what it resolves)")
    notes += [zeta_note] if zeta_note else []
    notes += list(response.notes)
    name = lambda k: str(k) if sc.chain is not None else sc.mass_names[k]  # noqa: E731
    return FrequencyResponse(sc, name(i), name(o), response.omega, response.H, response.resonances, tf, notes,
                             response.connected, list(response.extra_peaks), response.angle)


def _chain_modes(sc: Scene, system) -> list | None:
    """``(ω_n, ζ, ω_d)`` of a damped ``[chain]``'s modes by the route ``springchain modes`` takes: with
    dashpots, :func:`numeric.modes.chain_damping.damped_rows` (at most ``DENSE_MAX`` masses; longer: ζ NaN,
    not computed); Rayleigh damping alone, ζ_j = α/(2ω_j) + βω_j/2 at the undamped ω_j (the
    :data:`numeric.frf.response.MAX_REFINED` lowest)."""
    from .numeric.modes.chain_damping import DENSE_MAX, damped_rows
    from .numeric.modes.elements import Elements
    from .numeric.frf.response import MAX_REFINED, undamped_omegas

    if sc.chain_dampers:
        if sc.chain.n > DENSE_MAX:
            return None
        el = Elements.from_system(system)
        return damped_rows(el.masses, el.spring_ends, el.stiffness, el.damper_ends, el.damping)
    alpha, beta = system.rayleigh_coefficients()
    rows = []
    for w in undamped_omegas(system, MAX_REFINED).tolist():
        if w > 0 and len(rows) < MAX_REFINED:
            z = alpha / (2 * w) + beta * w / 2
            rows.append((w, z, w * math.sqrt((1 - z) * (1 + z)) if z < 1 else 0.0))
    return rows


__all__ = ["FrequencyResponse", "frf", "mass_index"]
