"""Units in CSV headers: ``t [s], a [g]`` or ``t [ms], f [kN]`` (a unit in brackets after the name).

:func:`header_factors` reads a table's header line and returns the SI factor of each column; a
header without brackets means SI, as before (and never imports pint).
"""

from __future__ import annotations

import re

from .dimension import ACCELERATION, FORCE, TIME, Dimension
from .registry import UnitProblem, gram_hint, parse_unit
from .scope import called

#: ``name`` or ``name [unit]``.
_CELL = re.compile(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*(?:\[(.*)\])?\s*\Z")
#: What each table column means.
COLUMNS = {"t": (TIME, "a time"), "f": (FORCE, "a force"), "a": (ACCELERATION, "an acceleration")}


class HeaderProblem(ValueError):
    """A header that is refused (``why``; the caller adds what is accepted)."""


def header_factors(line: str, names: tuple[str, ...],
                   meanings: dict[str, tuple[Dimension, str]] | None = None) -> tuple[float, ...]:
    """SI factors of the columns ``names`` from the header ``line`` (``1.0`` where no unit is given).

    Raises
    ------
    HeaderProblem
        A header whose names differ from ``names``, or whose unit is unknown, unsafe or of the wrong
        dimension (the message names the column, the given unit and the expected dimension).
    """
    meanings = meanings or COLUMNS
    cells = line.split(",")
    parsed = [_CELL.match(c) for c in cells]
    if len(cells) != len(names) or not all(parsed) or [p.group(1).lower() for p in parsed] != list(names):
        raise HeaderProblem(f"header {line[:60]!r} (line 1)")
    factors = []
    for p in parsed:
        name, text = p.group(1).lower(), p.group(2)
        if text is None:
            factors.append(1.0)
            continue
        dim, what = meanings[name]
        try:
            unit = parse_unit(text, dim)
        except UnitProblem as exc:
            raise HeaderProblem(f"header {line[:60]!r}: column {name}: {exc.why} (accepted: {exc.accepted})") from None
        if unit.dimension != dim:
            raise HeaderProblem(f"header {line[:60]!r}: column {name} [{unit.text}] is {called(unit.dimension)}, "
                                f"expected {what}, {dim}{gram_hint(unit.text, unit.dimension)}")
        factors.append(float(unit.factor))
    return tuple(factors)


__all__ = ["header_factors", "HeaderProblem", "COLUMNS"]
