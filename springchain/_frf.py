"""``springchain.frf``: the receptance H(iω) = X_out / F_in of a scene, its Bode figure and, for small
scenes, its transfer function in closed form. The numbers come from :mod:`springchain.numeric.frf`,
the algebra from :mod:`springchain.derive.transfer`; this module checks inputs and packages results.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

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
    resonances : list of springchain.numeric.frf.Resonance
    transfer : springchain.derive.transfer.TransferFunction or None
        ``H(s)`` as a ratio of polynomials (``[masses]`` scenes of at most 6 masses).
    notes : list of str
    """

    scene: Scene
    input: str
    output: str
    omega: object = field(repr=False)
    H: object = field(repr=False)
    resonances: list = field(default_factory=list, repr=False)
    transfer: object = field(default=None, repr=False)
    notes: list = field(default_factory=list, repr=False)

    @property
    def magnitude(self):
        """|H| [m/N], ndarray, shape (W,)."""
        import numpy as np

        return np.abs(self.H)

    @property
    def phase(self):
        """Phase of H [degrees], unwrapped along ω, ndarray, shape (W,)."""
        import numpy as np

        return np.degrees(np.unwrap(np.angle(self.H)))

    def to_json(self) -> dict:
        """Exactly what ``springchain frf ... --json`` prints."""
        return {"scene": self.scene.name, "input": self.input, "output": self.output,
                "omega": self.omega.tolist(), "magnitude": self.magnitude.tolist(), "phase": self.phase.tolist(),
                "units": {"omega": "rad/s", "magnitude": "m/N", "phase": "deg"},
                "resonances": [r.as_json() for r in self.resonances if r.participates],
                "transfer_function": None if self.transfer is None else self.transfer.as_json(),
                "notes": list(self.notes)}

    def to_text(self) -> str:
        """What ``springchain frf`` prints (without the ``wrote`` lines)."""
        w = self.omega
        lines = [f"frequency response of {self.scene.name!r}: H = X_{self.output} / F_{self.input} "
                 f"(receptance, m/N), {w.shape[0]} frequencies from {w[0]:.6g} to {w[-1]:.6g} rad/s"]
        seen = [r for r in self.resonances if r.participates]
        if seen:
            lines.append("resonances in range (undamped ω_n, damping ratio ζ, damped ω_d; exact peak of |H|):")
        for r in seen:
            line = f"  ω_n = {r.omega_n:.8g} rad/s   ζ = {r.zeta:.4g}   ω_d = {r.omega_d:.8g} rad/s"
            if math.isnan(r.zeta):
                line = f"  ω_n = {r.omega_n:.8g} rad/s (undamped; damped [chain]: ζ not computed, grid refined here)"
            elif r.undamped:
                line += "   |H| = ∞ at ω_n (undamped; the grid stops 1e-4 short on each side)"
            elif r.peak_omega is not None:
                line += f"   peak |H| = {r.peak_magnitude:.6e} m/N at ω = {r.peak_omega:.8g} rad/s"
            lines.append(line)
        for r in self.resonances:
            if not r.participates:
                lines.append(f"  ω = {r.omega_n:.8g} rad/s: a mode with a node at the input or output "
                             "(no resonance in this H)")
        if self.transfer is not None:
            lines += ["transfer function (adj(M s² + C s + K)[out, in] / det(M s² + C s + K), cancelled):",
                      self.transfer.text().rstrip("\n"), "LaTeX:", self.transfer.latex().rstrip("\n")]
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines) + "\n"

    def plot(self):
        """The Bode figure (a matplotlib Figure: |H| log-log, phase in degrees, resonances marked)."""
        from .numeric import plots

        peaks = tuple((r.peak_omega, r.peak_magnitude) for r in self.resonances
                      if r.participates and r.peak_omega is not None)
        infinite = tuple(r.omega_n for r in self.resonances if r.participates and r.undamped)
        hidden = tuple(r.omega_n for r in self.resonances if not r.participates)
        return plots.bode(self.omega, self.magnitude, self.phase,
                          f"{self.scene.name}: receptance X_{self.output} / F_{self.input}",
                          peaks=peaks, infinite=infinite[:200], hidden=hidden[:200])

    def save(self, out: str | Path = DEFAULT_OUT) -> Path:
        """Write the Bode figure as ``OUT/<scene>-frf-<input>-<output>.png``; returns its path."""
        from .numeric import plots

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
    from .numeric.frf import frequency_response

    sc = load(scene)
    i, o = mass_index(sc, input, "input"), mass_index(sc, output, "output")
    lo, hi = _check_omega(omega_min, "omega_min"), _check_omega(omega_max, "omega_max")
    if isinstance(points, bool) or not isinstance(points, int) or not 2 <= points <= MAX_POINTS:
        raise RunRefused(f"points {points!r}: accepted: a whole number 2 ... {MAX_POINTS}", quantity="points")
    system, _ = _system(sc)
    model, modes = None, None
    if sc.chain is None and system.damped:  # the resonance table from the damped modes `modes` prints
        from .derive.damping_report import damped_modes
        from .derive.model import Model

        model = Model(sc)
        modes = [(r.omega_n, r.zeta, r.omega_d) for r in damped_modes(model, None).rows]
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
    name = lambda k: str(k) if sc.chain is not None else sc.mass_names[k]  # noqa: E731
    return FrequencyResponse(sc, name(i), name(o), response.omega, response.H, response.resonances, tf, notes)


__all__ = ["FrequencyResponse", "frf", "mass_index"]
