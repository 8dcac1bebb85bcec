"""The units of one scene while it loads (:class:`SceneUnits`, held by the scene loader).

* A value ``"NUMBER UNIT"`` (``m = "10 t"``, ``k = "4 MN/m"``) is converted to SI once, here, and
  checked against what its key means (:func:`.dimension.meaning`); a parameter keeps its dimension.
* An expression that involves a parameter with a unit is checked for dimensional consistency
  (:mod:`.check`) and its dimension against the key's.

A scene with no unit anywhere never reaches pint and is checked exactly as before. Every refusal is
a :class:`~springchain.derive.errors.SceneError`: one line naming the file, the key, the given
value or unit and the expected dimension.
"""

from __future__ import annotations

from ..errors import SceneError, show
from .check import VARIABLES, DimensionProblem, dimension_of
from .dimension import Dimension, meaning
from .registry import UnitProblem, gram_hint, parse_unit, si_unit_text, split_quantity

#: What common dimensions are called in messages.
_NAMES = {}


def called(dim: Dimension) -> str:
    """``[mass]*[length]/[time]^2 (a force)``: the dimension and, when it has one, its name."""
    if not _NAMES:
        from . import dimension as d

        _NAMES.update({d.MASS: "a mass", d.LENGTH: "a length", d.TIME: "a time", d.VELOCITY: "a velocity",
                       d.ACCELERATION: "an acceleration", d.FORCE: "a force", d.STIFFNESS: "a stiffness",
                       d.CUBIC_STIFFNESS: "a cubic stiffness", d.DAMPING: "a damping coefficient",
                       d.ENERGY: "an energy", d.RATE: "a rate", d.NONE: "a plain number"})
    name = _NAMES.get(dim)
    return f"{dim} ({name})" if name and not dim.dimensionless else str(dim)


def _weight(given: Dimension, m) -> str:
    """A hint when a weight (a force) stands where a mass goes: the silent factor-g error of
    "consistent units"."""
    from .dimension import FORCE, MASS

    return (": a weight, not a mass (mass = weight / g, e.g. '10 kip' weighs what '4.536 t' is)"
            if m is not None and m.dimension == MASS and given == FORCE else "")


class SceneUnits:
    """Dimensions of the parameters given with units, and the checks of one scene file."""

    def __init__(self, file: str | None):
        self.file = file
        #: parameter name -> its dimension (only parameters given with a unit)
        self.dims: dict[str, Dimension] = {}
        #: parameter name -> the text it was given as
        self.given: dict[str, str] = {}

    def _fail(self, key: str, value, why: str, accepted: str) -> SceneError:
        return SceneError(self.file, key, f"{show(value)}: {why}; accepted: {accepted}")

    def number(self, key: str, value) -> float | None:
        """The SI value of ``value`` if it is ``"NUMBER UNIT"`` (None otherwise), checked against ``key``."""
        m = meaning(key)
        if not (m is not None or key.startswith("parameters.")):
            return None
        split = split_quantity(value)
        if split is None:
            return None
        number, unit_text = split
        try:
            unit = parse_unit(unit_text, m.dimension if m else None)
        except UnitProblem as p:
            raise self._fail(key, value, p.why, p.accepted) from None
        if m is not None and unit.dimension != m.dimension:
            raise self._fail(key, value, f"unit {unit.text} is {called(unit.dimension)}{_weight(unit.dimension, m)}"
                                         f"{gram_hint(value, unit.dimension)}", f"{m}")
        if key.startswith("parameters."):
            name = key.split(".", 1)[1]
            self.dims[name], self.given[name] = unit.dimension, value
        try:
            return float(number * unit.factor)  # exact product, rounded once
        except OverflowError:
            return float("inf") if number > 0 else float("-inf")  # refused as not finite by the caller

    def value(self, key: str, text):
        """``text`` for the expression parser: a ``"NUMBER UNIT"`` becomes its SI float."""
        si = self.number(key, text)
        return text if si is None else si

    def check(self, key: str, text, expr, extra: dict[str, Dimension] | None = None) -> None:
        """Refuse ``expr`` (the parsed ``text`` of ``key``) if it involves units inconsistently."""
        if not self.dims or not (expr.symbols() & self.dims.keys()):
            return
        m = meaning(key)
        names = {**self.dims, **(extra or {})}
        plain = sorted(s for s in expr.symbols() if s not in names and s not in VARIABLES)
        hint = (f" (in an expression with units, the plain-number parameter{'s' if len(plain) > 1 else ''} "
                f"{', '.join(plain)} count{'' if len(plain) > 1 else 's'} as dimensionless: give "
                f"{'them units' if len(plain) > 1 else 'it a unit'})") if plain else ""
        involved = sorted(expr.symbols() & self.dims.keys())
        with_units = ", ".join(f"{p} = {self.given[p]!r}" for p in involved)
        # a parameter in grams where the expression does not want a mass: likely meant standard gravity
        grams = "".join(gram_hint(self.given[p], self.dims[p]).replace("; g is", f"; {p}: g is", 1)
                        for p in involved)
        try:
            dim = dimension_of(expr, names)
        except DimensionProblem as p:
            raise self._fail(key, text, f"{p.why} (with {with_units}){hint}{grams}",
                             "a dimensionally consistent expression" + (f" giving {m}" if m else "")) from None
        if m is not None and dim != m.dimension:
            raise self._fail(key, text, f"has dimension {called(dim)}{_weight(dim, m)} (with {with_units}){hint}{grams}",
                             f"{m}")

    def keep_unit(self, name: str, value: float):
        """A new SI value for parameter ``name`` written with its SI unit when it was given with a unit
        (so the scene's other expressions keep their dimensions), else the plain number."""
        dim = self.dims.get(name)
        return value if dim is None else f"{float(value)!r} {si_unit_text(dim)}"


__all__ = ["SceneUnits", "called"]
