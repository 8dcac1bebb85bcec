"""``springchain.random_response`` and ``springchain psd``: stationary response to a random input.

A one-sided input PSD (a CSV of frequency [Hz] and PSD [unit²/Hz], the field's convention; units in
the header, ``f [Hz], psd [g^2/Hz]``, need the units extra) drives either a force on one mass or the
base (a base-acceleration PSD). The RMS of every mass's displacement, velocity and acceleration and of
every spring force comes from the exact modal integral (:mod:`springchain.numeric.random`); the
response PSDs, for figures, from the same pole–residue form on a grid refined at every resonance.
"""

from __future__ import annotations

import math
import os
import re
import stat
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ._defaults import DEFAULT_OUT
from .derive.scene import Scene

#: Largest PSD file read.
MAX_PSD_BYTES = 16 * 2**20


@dataclass(frozen=True)
class RandomVibration:
    """The random response of a scene (``sc.random_response``).

    Attributes
    ----------
    scene : Scene
    on : str or None
        The mass the random force drives; None for a base-acceleration PSD.
    response : springchain.numeric.random.response.RandomResponse
        ``names``, ``kinds``, ``units``, ``rms`` (Y,), ``f`` (W,) [Hz], ``psd`` (Y, W), ``input_psd`` (W,).
    input_unit : str
        The unit the input is shown in: U when the file's header gave ``psd [U^2/Hz]`` (``g``, ``kN``,
        ``mm/s^2``), else SI. Outputs of the input's dimension (accelerations under a base acceleration,
        spring forces under a force) are shown in it too, unless ``units`` says otherwise.
    input_factor : float
        SI value of one ``input_unit``.
    notes : list of str
    """

    scene: Scene
    on: str | None
    response: object = field(repr=False)
    input_unit: str = "N"
    input_factor: float = 1.0
    notes: list = field(default_factory=list, repr=False)

    def rms(self, name: str, kind: str = "displacement") -> float:
        """RMS [SI] of output ``name`` (a mass or ``"spring 0 (...)"``) of ``kind``."""
        r = self.response
        for nm, kd, v in zip(r.names, r.kinds, r.rms):
            if kd == kind and (nm == name or (kd == "spring force" and nm.split(" (")[0] == name)):
                return float(v)
        raise KeyError(f"no output {name!r} of kind {kind!r}")

    def _display(self, kind: str, units=None) -> tuple[str, float]:
        """(unit, SI value of one unit) an output kind is shown in (``units``: parsed by
        :func:`springchain.derive.units.output.output_units`)."""
        from .derive.units.output import output_units

        units = output_units(units)
        si = {"displacement": "m", "velocity": "m/s", "acceleration": "m/s^2", "spring force": "N"}[kind]
        if units is None and kind == ("spring force" if self.on else "acceleration") and \
                (self.input_unit, self.input_factor) != (si, 1.0):
            return self.input_unit, self.input_factor  # the input's own unit (g, kN, ...) for its dimension
        return (si, 1.0) if units is None else units.of(si)

    def _input_display(self, units=None) -> tuple[str, float]:
        """(unit, SI value of one unit) the input is shown in."""
        from .derive.units.output import output_units

        units = output_units(units)
        if units is None:
            return self.input_unit, self.input_factor
        return units.of("N" if self.on else "m/s^2")

    def to_json(self, units=None) -> dict:
        """Exactly what ``springchain psd ... --json`` prints.

        Parameters
        ----------
        units : None, str, sequence of str or OutputUnits
            Results in these units: ``"mm,kN,g"`` as ``--units`` takes it (one unit per dimension, ``g``
            standard gravity; PSDs follow as unit²/Hz), None for SI (accelerations in g when the input was).

        Raises
        ------
        SceneError
            A bad units text (one line; pint missing included).
        """
        from .derive.units.output import output_units

        units = output_units(units)
        r = self.response
        rows = []
        for nm, kd, v in zip(r.names, r.kinds, r.rms):
            u, fac = self._display(kd, units)
            rows.append({"output": nm, "kind": kd, "rms": float(v) / fac, "unit": u})
        iu, ifac = self._input_display(units)
        return {"scene": self.scene.name, "input": "force on " + self.on if self.on else "base acceleration",
                "psd_convention": "one-sided, per Hz", "input_rms": r.input_rms / ifac,
                "input_unit": iu, "rms": rows,
                "method": "exact modal integral (closed form per PSD segment; no frequency sampling)",
                "notes": list(self.notes)}

    def to_text(self, units=None) -> str:
        """What ``springchain psd`` prints.

        Parameters
        ----------
        units : None, str, sequence of str or OutputUnits
            Results in these units: ``"mm,kN,g"`` as ``--units`` takes it (one unit per dimension, ``g``
            standard gravity; PSDs follow as unit²/Hz), None for SI (accelerations in g when the input was).

        Raises
        ------
        SceneError
            A bad units text (one line; pint missing included).
        """
        from .derive.units.output import output_units

        units = output_units(units)
        r = self.response
        what = f"a random force on {self.on}" if self.on else "a random base acceleration"
        iu, ifac = self._input_display(units)
        lines = [f"random response of {self.scene.name!r} to {what}: input RMS {r.input_rms / ifac:.6g} "
                 f"{iu} (one-sided PSD per Hz, {r.f[0]:.6g} ... {r.f[-1]:.6g} Hz); RMS by the exact "
                 "modal integral (no frequency sampling)"]
        for kind in ("displacement", "velocity", "acceleration", "spring force"):
            u, fac = self._display(kind, units)
            label = kind + (" (absolute)" if kind == "acceleration" and self.on is None else
                            " (relative to the base)" if kind in ("displacement", "velocity") and self.on is None else "")
            lines.append(f"  RMS {label} [{u}]:")
            for nm, kd, v in zip(r.names, r.kinds, r.rms):
                if kd == kind:
                    lines.append(f"    {nm:<28} {float(v) / fac:.6e}")
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines) + "\n"

    def plot(self, kind: str = "acceleration", units=None):
        """Log–log figure: input PSD and the response PSD of every mass's ``kind`` (or spring forces);
        ``units`` as :meth:`to_text` (e.g. ``"mm,kN,g"``)."""
        from .derive.units.output import output_units
        from .numeric.random.figures import psd_figure

        units = output_units(units)
        r = self.response
        u, fac = self._display(kind, units)
        curves = [(nm, r.psd[j] / fac**2, float(r.rms[j]) / fac) for j, (nm, kd) in enumerate(zip(r.names, r.kinds))
                  if kd == kind][:12]
        iu, ifac = self._input_display(units)
        label = f"input PSD [{iu}²/Hz]" if "/" not in iu else f"input PSD [({iu})²/Hz]"
        what = f"force on {self.on}" if self.on else "base acceleration"
        return psd_figure(r.f, r.input_psd / ifac**2, label, curves, u,
                          f"{self.scene.name}: {kind} PSD under a random {what}")

    def save(self, out: str | Path = DEFAULT_OUT, kind: str = "acceleration", units=None) -> Path:
        """Write the figure as ``OUT/<scene>-psd-<kind>.png``; returns its path (``units`` as :meth:`to_text`)."""
        from .numeric.plots import figures as plots

        path = Path(out) / f"{self.scene.name}-psd-{kind.replace(' ', '-')}.png"
        plots.save(self.plot(kind, units), path)
        return path


def read_psd(path: str | Path, ground: bool):
    """``(f [Hz], G [SI²/Hz], display unit, its SI factor)`` from a CSV ``f,psd`` (header units optional).

    Raises
    ------
    SceneError
        One line naming the file, the bad value and what is accepted.
    """
    from .derive.errors import SceneError
    from .derive.units import HeaderProblem, header_factors
    from .derive.units.dimension import ACCELERATION, FORCE, RATE, TIME

    file = str(path)
    unit = "m/s^2" if ground else "N"
    form = (f"a CSV file with a header line 'f,psd' (units optional: 'f [Hz], psd [{'g' if ground else 'N'}^2/Hz]') "
            "and rows of frequency [Hz] and one-sided PSD [unit^2/Hz]")

    def bad(why: str) -> SceneError:
        return SceneError(file, "--input", f"{why}; accepted: {form}")

    try:
        mode = os.stat(path).st_mode
        if not stat.S_ISREG(mode):
            raise bad("not a regular file")
        with open(path, "rb") as fh:
            raw = fh.read(MAX_PSD_BYTES + 1)
    except OSError as exc:
        raise bad(f"cannot read the file ({exc.strerror or exc})") from None
    if len(raw) > MAX_PSD_BYTES:
        raise bad(f"larger than {MAX_PSD_BYTES // 2**20} MiB")
    try:
        text = raw.decode("utf-8").lstrip("\ufeff")
    except UnicodeDecodeError as exc:
        raise bad(f"byte {exc.start} is not UTF-8") from None
    lines = [ln.strip() for ln in text.splitlines() if ln.strip() and not ln.strip().startswith("#")]
    if not lines:
        raise bad("empty")
    base = ACCELERATION if ground else FORCE
    psd_dim = base * base * TIME
    if "rad" in lines[0].split(",")[0]:
        raise bad(f"header {lines[0][:60]!r}: the frequency column is in Hz (cycles per second), not rad/s")
    try:
        ff, fg = header_factors(lines[0], ("f", "psd"), {"f": (RATE, "a frequency [Hz]"),
                                                         "psd": (psd_dim, f"a PSD of {'an acceleration' if ground else 'a force'}, "
                                                                          f"{unit}^2/Hz")})
    except HeaderProblem as exc:
        raise bad(str(exc)) from None
    rows = []
    for r, line in enumerate(lines[1:], start=1):
        cells = line.split(",")
        try:
            if len(cells) != 2:
                raise ValueError
            a, b = float(cells[0]), float(cells[1])
        except ValueError:
            raise bad(f"row {r} {line[:40]!r} is not two numbers") from None
        if not (math.isfinite(a) and math.isfinite(b)):
            raise bad(f"row {r} {line[:40]!r} is not two finite numbers")
        rows.append((a * ff, b * fg))
    data = np.array(rows, dtype=float).reshape(-1, 2)
    display, factor = input_unit(lines[0].split(",")[1], base, fg) or (unit, 1.0)
    return data[:, 0], data[:, 1], display, factor


#: A PSD unit ``U^2/Hz`` (or ``(U)^2/Hz``, ``U**2/Hz``): U, the unit the input itself is shown in.
_PSD_UNIT = re.compile(r"\s*\[\s*(?:\((?P<paren>[^\[\]]+)\)|(?P<bare>[^\s()\[\]^*/]+))\s*(?:\^|\*\*)\s*2\s*/\s*Hz\s*\]\s*\Z")


def input_unit(psd_header: str, dimension, psd_factor: float) -> tuple[str, float] | None:
    """``(U, SI value of one U)`` for a PSD column headed ``psd [U^2/Hz]`` (``g^2/Hz``, ``kN^2/Hz``,
    ``(mm/s^2)^2/Hz``), so that the input and the outputs of its dimension are shown in U as given;
    None when the header has no such unit (SI is shown).

    Parameters
    ----------
    psd_header : str
        The header cell, ``"psd [kN^2/Hz]"``.
    dimension : Dimension
        The input's (a force or an acceleration).
    psd_factor : float
        The SI value of one unit of the PSD column (already checked), to cross-check U.
    """
    from .derive.units import UnitProblem, parse_unit

    m = _PSD_UNIT.match(psd_header[psd_header.find("["):] if "[" in psd_header else "")
    if m is None:
        return None
    text = (m.group("paren") or m.group("bare")).strip()
    try:
        u = parse_unit(text, dimension)  # a bare g in an acceleration: standard gravity
    except UnitProblem:
        return None
    if u.dimension != dimension or not math.isclose(float(u.factor) ** 2, psd_factor, rel_tol=1e-12):
        return None
    return text, float(u.factor)


def random_response(scene: str | Path | Scene, input, on=None, *, interpolation: str = "loglog") -> RandomVibration:
    """Stationary response of ``scene`` to a random input given by its one-sided PSD.

    Parameters
    ----------
    scene : str, Path or Scene
    input : str, Path, ndarray of shape (K, 2), or dict ``{"f": ..., "psd": ...}``
        The PSD: a CSV file (``f,psd``: frequency [Hz], one-sided PSD [unit²/Hz]; header units such
        as ``f [Hz], psd [g^2/Hz]`` with the units extra) or arrays in SI (N²/Hz for a force,
        (m/s²)²/Hz for a base acceleration).
    on : str or int, optional
        The mass a random force drives (a name; an index for ``[chain]`` scenes); None: the PSD is a
        base acceleration (every mass feels ``−m a_g``; displacements and velocities relative to the
        base, accelerations absolute).
    interpolation : {"loglog", "linear"}
        Between breakpoints: straight on log–log axes (test specifications) or on linear axes.

    Returns
    -------
    RandomVibration
        ``.rms(name, kind)``, ``.to_json()``, ``.to_text()``, ``.plot(kind)``, ``.save(dir)``;
        ``.response`` holds the arrays.

    Notes
    -----
    The RMS is the exact integral of ``G(f)|H(i2πf)|²`` over the band (closed form per segment,
    Gauss's 2F1 for non-integer log–log slopes, at 40 digits); only the PSD curves use a grid.
    Springs enter by their linear stiffness; forces, gravity and the scene's own ground record do not
    change the response. Refused: rigid-body modes, undamped modes, more than 400 masses.
    """
    from ._frf import mass_index
    from ._modules import system_of
    from ._scenes import load
    from .numeric.modes.elements import Elements
    from .numeric.errors import RunRefused
    from .numeric.random.modal_form import pole_residue
    from .numeric.random.psd_input import InputPSD
    from .numeric.random.response import random_response as _response

    sc = load(scene)
    ground = on is None
    k = None if ground else mass_index(sc, on, "on")
    display, factor = ("m/s^2" if ground else "N"), 1.0
    if isinstance(input, str | Path):
        f, G, display, factor = read_psd(input, ground)
    elif isinstance(input, dict):
        if sorted(map(str, input)) != ["f", "psd"]:
            raise RunRefused(f"input: keys {sorted(map(str, input))}; accepted: {{'f': [...], 'psd': [...]}}",
                             quantity="input")
        f, G = input["f"], input["psd"]
    else:
        arr = np.asarray(input, dtype=float) if not isinstance(input, bool) else None
        if arr is None or arr.ndim != 2 or arr.shape[1] != 2:
            raise RunRefused("input: accepted: a CSV file name, an array of shape (K, 2) (f [Hz], PSD) or a dict "
                             "{'f': ..., 'psd': ...}", quantity="input")
        f, G = arr[:, 0], arr[:, 1]
    psd = InputPSD.checked(f, G, interpolation)
    system, _ = system_of(sc)
    el = Elements.from_system(system)
    names = tuple(sc.mass_names) if sc.chain is None else tuple(str(j) for j in range(sc.n))
    b = -el.masses if ground else np.eye(sc.n)[k]
    model = pole_residue(el, b, ground=ground, names=names)
    notes = []
    if not system.linear:
        notes.append("nonlinear springs: the response of the linearisation (their linear stiffness)")
    if not el.proportional:
        notes.append("dashpots: poles and residues from the eigen-decomposition of the balanced first-order modal "
                     "matrix (accurate to about eps x its condition)")
    return RandomVibration(sc, None if ground else names[k], _response(model, psd), display, factor, notes)


__all__ = ["RandomVibration", "random_response", "read_psd"]
