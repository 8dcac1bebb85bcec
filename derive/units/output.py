"""Results in the user's units (``--units mm,kN,g``): SI values and unit texts converted for display.

Each entry of the list is a unit; a result of that entry's dimension is shown in it. Ratios
(receptance m/N, mobility (m/s)/N, …) convert their numerator and denominator apart, and a PSD
(unit²/Hz) its unit; velocity and acceleration follow length and time when not listed. Frequencies
are not converted here (pint counts rad/s and Hz alike; ``--hz`` says which): a frequency unit is
refused. In this list ``g`` is standard gravity.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .dimension import ACCELERATION, LENGTH, NONE, RATE, TIME, VELOCITY, Dimension
from .registry import UnitProblem, parse_unit

#: SI texts of the quantities results carry, and their dimensions.
SI = {"m": LENGTH, "m/s": VELOCITY, "m/s^2": ACCELERATION, "N": Dimension.of({"[mass]": 1, "[length]": 1, "[time]": -2}),
      "s": TIME, "N/m": Dimension.of({"[mass]": 1, "[time]": -2}), "1": NONE, "J": Dimension.of(
          {"[mass]": 1, "[length]": 2, "[time]": -2})}


@dataclass(frozen=True)
class OutputUnits:
    """The ``--units`` list: dimension -> (unit text, SI factor)."""

    chosen: dict = field(default_factory=dict)

    @classmethod
    def parse(cls, spec: str | None) -> "OutputUnits":
        """From ``"mm, kN, g"``; raises :class:`UnitProblem` for a bad entry (one clause)."""
        chosen = {}
        for text in (spec or "").split(","):
            text = text.strip()
            if not text:
                continue
            unit = parse_unit(text, ACCELERATION)  # a bare g: standard gravity
            if unit.dimension == RATE:
                raise UnitProblem(f"{text!r} is a frequency", "frequencies in rad/s, or Hz with --hz")
            if unit.dimension in chosen:
                raise UnitProblem(f"two units of dimension {unit.dimension}", "one unit per dimension")
            chosen[unit.dimension] = (text, float(unit.factor))
        if LENGTH in chosen and VELOCITY not in chosen:
            t_text, t_f = chosen.get(TIME, ("s", 1.0))
            chosen[VELOCITY] = (f"{chosen[LENGTH][0]}/{t_text}", chosen[LENGTH][1] / t_f)
        if LENGTH in chosen and ACCELERATION not in chosen:
            t_text, t_f = chosen.get(TIME, ("s", 1.0))
            chosen[ACCELERATION] = (f"{chosen[LENGTH][0]}/{t_text}^2", chosen[LENGTH][1] / t_f ** 2)
        return cls(chosen)

    def of(self, si_text: str) -> tuple[str, float]:
        """``(unit text, factor)``: a value in SI unit ``si_text`` divided by ``factor`` is in ``unit text``."""
        dim = SI.get(si_text)
        if dim is None or dim not in self.chosen:
            return si_text, 1.0
        return self.chosen[dim]

    def ratio(self, num: str, den: str) -> tuple[str, float]:
        """The unit of ``num/den`` (both SI texts of :data:`SI`) and its factor."""
        (a, fa), (b, fb) = self.of(num), self.of(den)
        if b == "1":
            return a, fa
        if a == "1":
            return f"1/{b}", 1.0 / fb
        wrap = lambda u: f"({u})" if "/" in u or "*" in u else u  # noqa: E731
        return f"{wrap(a)}/{wrap(b)}", fa / fb


def output_units(units, key: str = "units") -> OutputUnits | None:
    """The results' units from anything the command line's ``--units`` or the API's ``units=`` takes.

    Parameters
    ----------
    units : None, str, sequence of str, or OutputUnits
        ``"mm,kN,g"`` (the ``--units`` text: one unit per dimension, ``g`` standard gravity), the same as
        a list ``["mm", "kN", "g"]``, or an :class:`OutputUnits` (returned as is). None or ``""``: SI.
    key : str
        What the error names (``--units`` on the command line).

    Returns
    -------
    OutputUnits or None
        None for SI.

    Raises
    ------
    SceneError
        A bad entry, a frequency unit, two units of one dimension, another type, or pint missing (one line).
    """
    from ..errors import SceneError

    if units is None or isinstance(units, OutputUnits):
        return units
    if isinstance(units, (list, tuple)) and all(isinstance(u, str) for u in units):
        units = ",".join(units)
    if not isinstance(units, str):
        raise SceneError(None, key, f"{type(units).__name__} {str(units)[:40]!r}; accepted: a text such as "
                                    "'mm,kN,g' (as --units), a list of unit texts, or None for SI")
    if not units.strip():
        return None
    try:
        return OutputUnits.parse(units)
    except UnitProblem as exc:
        raise SceneError(None, key, f"{units[:80]!r}: {exc}") from None


__all__ = ["OutputUnits", "SI", "output_units"]
