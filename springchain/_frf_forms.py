"""``springchain.frf_form``: receptance, mobility, accelerance, dynamic stiffness and (for a moving
base) absolute and relative transmissibility, in Hz or rad/s, optionally in dB, labelled with units.

Every number comes from the receptances of the accurate route (:func:`springchain.frf`, and
:func:`springchain.numeric.frf.response.receptance` on the same grid for the other masses a base drives);
:mod:`springchain.numeric.interop.frf_forms` turns them into each form without a subtraction that
cancels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ._defaults import DEFAULT_OUT

#: Most masses whose receptances a base input sums (one certified solve per mass and frequency).
MAX_BASE_MASSES = 400
#: Spellings accepted for each form.
ALIASES = {"dynamic_stiffness": "dynamic-stiffness", "dynamic stiffness": "dynamic-stiffness",
           "relative_transmissibility": "relative-transmissibility", "absolute-transmissibility": "transmissibility",
           "inertance": "accelerance", "compliance": "receptance", "admittance": "mobility"}


@dataclass(frozen=True)
class FrfForm:
    """One form of a frequency response on the refined grid of :func:`springchain.frf`.

    Attributes
    ----------
    scene : Scene
    form : str
        One of :data:`springchain.numeric.interop.frf_forms.FORMS`.
    input, output : str
        Mass names (``"ground"`` for the base).
    omega : ndarray, shape (W,)
        Angular frequencies [rad/s].
    values : ndarray, shape (W,), complex
        The form in SI units (:attr:`unit`).
    hz, db : bool
        Show frequencies in Hz; magnitudes in dB (re 1 of the unit).
    resonances : list
        The receptance's resonances (:class:`springchain.numeric.frf.response.Resonance`).
    notes : list of str
    """

    scene: object
    form: str
    input: str
    output: str
    omega: np.ndarray = field(repr=False)
    values: np.ndarray = field(repr=False)
    hz: bool = False
    db: bool = False
    resonances: list = field(default_factory=list, repr=False)
    notes: list = field(default_factory=list, repr=False)

    @property
    def frequency(self) -> np.ndarray:
        """Frequencies in Hz (``hz``) or rad/s, shape (W,)."""
        return self.omega / (2 * math.pi) if self.hz else self.omega

    @property
    def frequency_unit(self) -> str:
        return "Hz" if self.hz else "rad/s"

    @property
    def unit(self) -> str:
        """The SI unit of :attr:`values`."""
        from .numeric.interop.frf_forms import FORMS

        return FORMS[self.form][0]

    def display_unit(self, units=None) -> tuple[str, float]:
        """(unit, SI value of one unit) the magnitude is shown in.

        Parameters
        ----------
        units : None, str, sequence of str or OutputUnits
            Results in these units: ``"mm,kN"`` as ``--units`` takes it (one unit per dimension, ``g``
            standard gravity; ratios follow their numerator and denominator), None for SI.

        Raises
        ------
        SceneError
            A bad units text (one line; pint missing included).
        """
        from .derive.units.output import output_units
        from .numeric.interop.frf_forms import RATIO

        units = output_units(units)
        if units is None:
            return self.unit, 1.0
        return units.ratio(*RATIO[self.form])

    def magnitude(self, units=None) -> np.ndarray:
        """|value| in the display unit, or in dB re 1 display unit (``db``), shape (W,).

        ``units``: as :meth:`display_unit` (e.g. ``"mm,kN"``).
        """
        from .numeric.interop.frf_forms import decibels

        _, fac = self.display_unit(units)
        mag = np.abs(self.values) / fac
        return decibels(mag) if self.db else mag

    @property
    def phase(self) -> np.ndarray:
        """Phase [deg], unwrapped along ω, shape (W,)."""
        return np.degrees(np.unwrap(np.angle(self.values)))

    def magnitude_label(self, units=None) -> str:
        """The magnitude axis label with its unit (``units``: as :meth:`display_unit`)."""
        from .numeric.interop.frf_forms import FORMS

        u, _ = self.display_unit(units)
        what = f"{self.form.replace('-', ' ')} {FORMS[self.form][1].replace('_{', '_').replace('}', '')}"
        if self.db:
            return f"{what} [dB re 1 {u}]" if u != "1" else f"{what} [dB]"
        return f"|{what}| [{u}]" if u != "1" else f"|{what}| [-]"

    def to_json(self, units=None) -> dict:
        """What ``springchain frf ... --form F --json`` prints (``units``: as :meth:`display_unit`)."""
        from .derive.units.output import output_units

        units = output_units(units)
        u, _ = self.display_unit(units)
        return {"scene": self.scene.name, "form": self.form, "input": self.input, "output": self.output,
                "frequency": self.frequency.tolist(), "magnitude": self.magnitude(units).tolist(),
                "phase": self.phase.tolist(),
                "units": {"frequency": self.frequency_unit, "magnitude": f"dB re 1 {u}" if self.db else u,
                          "phase": "deg"},
                "resonances": [{"frequency": (r.omega_d / (2 * math.pi) if self.hz else r.omega_d), "zeta":
                                None if np.isnan(r.zeta) else r.zeta} for r in self.resonances if r.participates],
                "notes": list(self.notes)}

    def to_text(self, units=None) -> str:
        """What ``springchain frf ... --form F`` prints (``units``: as :meth:`display_unit`)."""
        from .derive.units.output import output_units

        units = output_units(units)
        f, u = self.frequency, self.frequency_unit
        mag = self.magnitude(units)
        lines = [f"{self.magnitude_label(units)} of {self.scene.name!r}, input {self.input}, output {self.output}: "
                 f"{f.shape[0]} frequencies from {f[0]:.6g} to {f[-1]:.6g} {u}"]
        seen = [r for r in self.resonances if r.participates]
        if seen:
            lines.append(f"resonances (damped frequency [{u}], damping ratio):")
        for r in seen:
            fd = r.omega_d / (2 * math.pi) if self.hz else r.omega_d
            lines.append(f"  {fd:.8g} {u}   zeta = {r.zeta:.4g}")
        k = int(np.argmax(np.abs(self.values)))
        lines.append(f"largest magnitude on the grid (not an exact peak: {f.shape[0]} frequencies, refined at "
                     f"each resonance): {mag[k]:.6g} at {f[k]:.8g} {u}")
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines) + "\n"

    def plot(self, units=None):
        """Magnitude (log or dB) and phase against frequency, axes labelled with units (``units``: as
        :meth:`display_unit`, e.g. ``"mm,kN"``)."""
        from .derive.units.output import output_units
        from .numeric.plots.figures import new_figure

        units = output_units(units)
        fig, (ax, axp) = new_figure(2, 1, figsize=(9, 6.5), sharex=True)
        f, mag = self.frequency, self.magnitude(units)
        (ax.semilogx if self.db else ax.loglog)(f, mag, lw=1.3, color="C0")
        axp.semilogx(f, self.phase, lw=1.3, color="C0")
        ax.set_ylabel(self.magnitude_label(units))
        axp.set_ylabel("phase [deg]")
        axp.set_xlabel(f"frequency {'f' if self.hz else 'ω'} [{self.frequency_unit}]")
        ax.set_title(f"{self.scene.name}: {self.form.replace('-', ' ')}, input {self.input}, output {self.output}")
        for a in (ax, axp):
            a.grid(alpha=0.3, which="both")
        return fig

    def save(self, out: str | Path = DEFAULT_OUT, units=None) -> Path:
        """Write the figure as ``OUT/<scene>-frf-<form>-<input>-<output>.png``; returns its path (``units``: as
        :meth:`display_unit`)."""
        from .numeric.plots import figures as plots

        path = Path(out) / f"{self.scene.name}-frf-{self.form}-{self.input}-{self.output}.png"
        plots.save(self.plot(units), path)
        return path


def _form_name(form) -> str:
    from .numeric.errors import RunRefused
    from .numeric.interop.frf_forms import FORMS

    name = ALIASES.get(str(form).strip().lower(), str(form).strip().lower())
    if name not in FORMS:
        raise RunRefused(f"form {form!r}; accepted: {', '.join(FORMS)}", quantity="form")
    return name


def frf_form(source, form: str = "receptance", *, input=None, output=None, hz: bool = False, db: bool = False,
             omega_min: float | None = None, omega_max: float | None = None, points: int = 400) -> FrfForm:
    """A form of the frequency response, on the accurate route.

    Parameters
    ----------
    source : FrequencyResponse, or str, Path or Scene
        A receptance already computed by :func:`springchain.frf` (force-input forms reuse its grid and
        values), or a scene.
    form : str
        ``receptance``, ``mobility``, ``accelerance``, ``dynamic-stiffness`` (force on ``input``), or
        ``transmissibility`` (absolute), ``relative-transmissibility`` (the base moves: ``input`` is
        ``"ground"`` or None).
    input, output : str or int
        Mass names (indices for ``[chain]`` scenes); for a FrequencyResponse, its own.
    hz, db : bool
        Frequencies in Hz; magnitudes in dB re 1 of the unit.
    omega_min, omega_max, points
        As for :func:`springchain.frf` (rad/s).

    Returns
    -------
    FrfForm
    """
    from ._frf import FrequencyResponse, frf, mass_index
    from ._modules import system_of
    from ._scenes import load
    from .numeric.modes.elements import Elements
    from .numeric.errors import RunRefused
    from .numeric.frf.response import operator, receptance
    from .numeric.interop import frf_forms as ff

    name = _form_name(form)
    base = ff.FORMS[name][2]
    if isinstance(source, FrequencyResponse):
        if base:
            raise RunRefused(f"form {name!r} needs the base as input: call frf_form(scene, {name!r}, output=...)",
                             quantity="form")
        h = source
        return FrfForm(h.scene, name, h.input, h.output, h.omega, ff.from_receptance(name, h.omega, h.H), hz, db,
                       list(h.resonances), list(h.notes))
    sc = load(source)
    if output is None:
        raise RunRefused("output: missing; accepted: a mass name (an index for [chain] scenes)", quantity="output")
    if not base:
        if input is None or str(input) == "ground":
            raise RunRefused(f"input {input!r}: form {name!r} is driven by a force on a mass; accepted: a mass name "
                             "(transmissibility forms take the base, input 'ground')", quantity="input")
        h = frf(sc, input, output, omega_min, omega_max, points, transfer=False)
        return FrfForm(sc, name, h.input, h.output, h.omega, ff.from_receptance(name, h.omega, h.H), hz, db,
                       list(h.resonances), list(h.notes))
    if input is not None and str(input) != "ground":
        raise RunRefused(f"input {input!r}: form {name!r} is driven by the base; accepted: 'ground' (or no input)",
                         quantity="input")
    o = mass_index(sc, output, "output")
    system, _ = system_of(sc)
    el = Elements.from_system(system)
    k1, c1 = ff.ground_couplings(el)
    tied = [a for a in range(sc.n) if k1[a] != 0 or c1[a] != 0]
    if not tied:
        raise RunRefused(f"scene {sc.name!r} has no spring or dashpot to the wall: the base drives nothing",
                         quantity="form")
    need = tied if name == "transmissibility" else list(range(sc.n))
    if len(need) > MAX_BASE_MASSES:
        raise RunRefused(f"{name} of {sc.n} masses: at most {MAX_BASE_MASSES} receptances summed", quantity="form")
    names = tuple(sc.mass_names) if sc.chain is None else tuple(str(j) for j in range(sc.n))
    h = frf(sc, names[tied[0]] if sc.chain is None else tied[0], output, omega_min, omega_max, points, transfer=False)
    op = operator(system)
    cols = {a: (h.H if a == tied[0] else receptance(op, h.omega, a, o)) for a in need}
    values = (ff.transmissibility(h.omega, cols, k1, c1) if name == "transmissibility"
              else ff.relative_transmissibility(h.omega, cols, el.masses))
    return FrfForm(sc, name, "ground", names[o], h.omega, values, hz, db, list(h.resonances), list(h.notes))


__all__ = ["FrfForm", "frf_form", "ALIASES"]
