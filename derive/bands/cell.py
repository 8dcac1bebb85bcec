"""The ``[cell]`` table: a periodic chain given by its unit cell, and the finite chain of ``cells`` copies.

A unit cell lists its masses and the springs (and dashpots) that start in it; the second end of each may lie in
the same cell (``"b"``), the next one (``"a+1"``), the one after (``"a+2"``, next-nearest neighbours) or on the
ground (``"wall"``)::

    [cell]
    cells = 40                  # copies in the finite chain (modes, simulate, frf); bands: the infinite chain
    left = "free"               # "free", "wall" (the missing neighbours are clamped) or "ring"
    right = "free"
    [cell.masses]               # name = mass expression, in order
    a = "m1"
    b = "m2"
    [[cell.springs]]
    between = ["a", "b"]        # a and b of the same cell
    k = "k1"
    [[cell.springs]]
    between = ["b", "a+1"]      # b to a of the next cell
    k = "k2"
    [[cell.dampers]]            # optional, the same ends
    between = ["a", "wall"]
    c = "c"

The scene loader checks the table here (one line per problem, naming ``cell.springs[1].between`` and so on) and
expands it into the masses ``a_0, b_0, a_1, b_1, ...`` (name_cell) and the springs and dashpots between them, so
that every command sees an ordinary ``[masses]`` scene; :attr:`Scene.cell` keeps the cell for ``bands``. With
``left = "wall"`` a spring reaching into a cell before the first ends on the wall (likewise on the right); with
``"free"`` it is left out; a ring joins the last cell to the first. SymPy is not imported here.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ...generated.contract import END_WORDS, End
from ..expr import Expr
from ..scene_loader import Loader, did_you_mean

#: Keys of the [cell] table, of a cell spring and of a cell dashpot.
CELL_KEYS = ("cells", "left", "right", "masses", "springs", "dampers")
CELL_SPRING_KEYS = ("between", "k", "k3", "potential")
CELL_DAMPER_KEYS = ("between", "c")
#: Farthest cell a spring may reach (``"a+8"``).
MAX_REACH = 8
#: Most masses in one cell.
MAX_CELL_MASSES = 64
#: Most masses of the finite chain (cells x masses per cell): it is a ``[masses]`` scene (dense matrices).
MAX_EXPANDED = 4000
#: The ground end of a cell spring.
GROUND = -1
_END = re.compile(r"^\s*([A-Za-z][A-Za-z0-9_]*)\s*(?:\+\s*(\d+)\s*)?$")


@dataclass(frozen=True)
class CellLink:
    """A spring or dashpot of the unit cell: from mass ``a`` of cell c to mass ``b`` of cell c + ``reach``
    (either end :data:`GROUND`, the ground, with reach 0), in the order written. Springs carry ``k`` (and
    ``k3``) or their energy ``potential`` V(d), d = x_b − x_a (the ground counts 0); dashpots carry ``c`` in
    ``k``."""

    a: int
    b: int
    reach: int
    k: Expr | None
    key: str
    k3: Expr | None = None
    potential: Expr | None = None

    @property
    def ground(self) -> bool:
        return GROUND in (self.a, self.b)

    @property
    def mass(self) -> int:
        """The mass end of a ground link."""
        return self.b if self.a == GROUND else self.a


@dataclass(frozen=True)
class Cell:
    """A scene's unit cell (``[cell]``), as the loader checked it.

    Attributes
    ----------
    names : tuple of str
        The cell's mass names, shape (p,).
    masses : tuple of Expr
        Their expressions, shape (p,).
    springs, dampers : tuple of CellLink
    cells : int
        Copies in the finite chain.
    left, right : End
    """

    names: tuple[str, ...]
    masses: tuple[Expr, ...]
    springs: tuple[CellLink, ...]
    dampers: tuple[CellLink, ...]
    cells: int
    left: End
    right: End

    @property
    def size(self) -> int:
        """Masses per cell, p."""
        return len(self.names)

    def mass_name(self, a: int, c: int) -> str:
        """The finite chain's name of mass ``a`` in cell ``c``: ``name_c``."""
        return f"{self.names[a]}_{c}"


def _end(ld: Loader, key: str, text, index: dict[str, int]) -> tuple[int, int]:
    """``(mass, cell offset)`` of one end: ``"a"``, ``"a+1"``; ``(GROUND, 0)`` for ``"wall"``."""
    accepted = (", ".join(repr(n) for n in index) + ", the same with +1 ... +"
                f"{MAX_REACH} (a later cell) or 'wall'")
    if text == "wall":
        return GROUND, 0
    match = _END.match(text) if isinstance(text, str) else None
    if match is None or match.group(1) not in index:
        name = match.group(1) if match else text
        raise ld.bad(key, text, f"not a mass of the cell{did_you_mean(name, index)}", accepted)
    reach = int(match.group(2) or 0)
    if reach > MAX_REACH:
        raise ld.bad(key, text, f"reaches {reach} cells on", accepted)
    return index[match.group(1)], reach


def _link_ends(ld: Loader, key: str, between, index: dict[str, int]) -> tuple[int, int, int]:
    """``(a, b, reach)`` of ``between = [END, END]`` in the order written (a spring's extension is
    x_b − x_a): b lies ``reach`` cells after a (negative: before); a wall end is :data:`GROUND` (reach 0)."""
    if not isinstance(between, list) or len(between) != 2:
        raise ld.bad(key, between, "not a list of two ends", '["a", "b"], ["b", "a+1"] or ["a", "wall"]')
    (a, ra), (b, rb) = (_end(ld, key, e, index) for e in between)
    if a == GROUND and b == GROUND:
        raise ld.bad(key, between, "both ends are walls", "two different ends")
    if GROUND in (a, b):
        if ra or rb:
            raise ld.bad(key, between, "the ground end has no cell, so the mass end takes no +",
                         '["a", "wall"]: every cell\'s mass a tied to the ground')
        return a, b, 0
    if a == b and ra == rb:
        raise ld.bad(key, between, "joins a mass to itself", 'two different masses, or a mass to its copy in '
                     'another cell ("a", "a+1")')
    return a, b, rb - ra


def parse_cell(ld: Loader, pnames: frozenset[str], env: dict, potential) -> Cell:
    """The checked ``[cell]`` table (``potential(ld, key, text, names)`` parses a spring's energy)."""
    raw = ld.table("cell")
    ld.keys(raw, CELL_KEYS, "cell", required=("cells", "masses", "springs"), what="[cell]")
    masses = raw["masses"]
    if not isinstance(masses, dict) or not masses:
        raise ld.bad("cell.masses", masses, "not a table of masses", 'a table [cell.masses] such as a = "m"')
    if len(masses) > MAX_CELL_MASSES:
        raise ld.bad("cell.masses", f"{len(masses)} masses", f"more than {MAX_CELL_MASSES} in one cell",
                     f"at most {MAX_CELL_MASSES}")
    names, exprs = [], []
    for name, text in masses.items():
        key = f"cell.masses.{name}"
        ld.identifier(key, name, "mass name")
        if name == "wall":
            raise ld.bad(key, name, "reserved (the ground end of springs)", f"another mass name, e.g. {name}1")
        names.append(name)
        exprs.append(ld.expression(key, text, pnames, positive=True, bounded=True, env=env))
    index = {n: j for j, n in enumerate(names)}
    cells = int(ld.number("cell.cells", raw["cells"], positive=True, integer=True,
                          maximum=max(1, MAX_EXPANDED // len(names))))
    left, right = raw.get("left", "free"), raw.get("right", "free")
    for key, v in (("cell.left", left), ("cell.right", right)):
        if not isinstance(v, str) or v not in END_WORDS:
            raise ld.bad(key, v, f"not a chain end{did_you_mean(v, END_WORDS)}", ", ".join(END_WORDS))
    left, right = End(left), End(right)
    if (left is End.RING) != (right is End.RING):
        raise ld.bad("cell.right" if left is End.RING else "cell.left", (right if left is End.RING else left).value,
                     "a ring closes both ends", 'left = right = "ring"')
    springs = _links(ld, raw, "springs", index, pnames, env, potential)
    dampers = _links(ld, raw, "dampers", index, pnames, env, None)
    joined = {e for s in springs for e in (s.a, s.b)}
    free = [n for j, n in enumerate(names) if j not in joined]
    if free:
        raise ld.bad(f"cell.masses.{free[0]}", free[0], "no spring holds this mass (it would float free in every "
                     "cell: a flat band at 0)", "every cell mass joined by [[cell.springs]] to another mass or "
                     '"wall"')
    if not any(s.reach for s in springs):
        raise ld.bad("cell.springs", f"{len(springs)} springs inside the cell", "no spring joins a cell to the "
                     "next, so the chain falls apart into separate cells", 'a spring such as between = ["b", "a+1"]')
    reach = max(abs(s.reach) for s in (*springs, *dampers))
    if left is End.RING and cells <= reach:
        raise ld.bad("cell.cells", cells, f"a ring of {cells} cells with springs reaching {reach} cells on (a "
                     "spring would join a mass to itself)", f"cells > {reach}")
    return Cell(tuple(names), tuple(exprs), springs, dampers, cells, left, right)


def _links(ld: Loader, raw: dict, table: str, index: dict[str, int], pnames, env, potential) -> tuple[CellLink, ...]:
    entries = raw.get(table, [])
    if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
        raise ld.bad(f"cell.{table}", entries, "not an array of tables", f"entries written [[cell.{table}]]")
    if table == "springs" and not entries:
        raise ld.bad("cell.springs", entries, "no springs", '[[cell.springs]] entries such as between = ["a", "a+1"]')
    out = []
    for j, entry in enumerate(entries):
        key = f"cell.{table}[{j}]"
        if table == "dampers":
            ld.keys(entry, CELL_DAMPER_KEYS, key, required=("between", "c"), what="a [[cell.dampers]] entry")
            a, b, reach = _link_ends(ld, f"{key}.between", entry["between"], index)
            c = ld.expression(f"{key}.c", entry["c"], pnames, positive=True, bounded=True, env=env)
            out.append(CellLink(a, b, reach, c, key))
            continue
        if "potential" in entry:
            ld.keys(entry, ("between", "potential"), key, required=("between", "potential"),
                    what="a [[cell.springs]] entry with a potential (instead of k, k3)")
            a, b, reach = _link_ends(ld, f"{key}.between", entry["between"], index)
            out.append(CellLink(a, b, reach, None, key, None,
                                potential(ld, f"{key}.potential", entry["potential"], pnames)))
            continue
        ld.keys(entry, CELL_SPRING_KEYS, key, required=("between", "k"), what="a [[cell.springs]] entry")
        a, b, reach = _link_ends(ld, f"{key}.between", entry["between"], index)
        k = ld.expression(f"{key}.k", entry["k"], pnames, positive=True, bounded=True, env=env)
        k3 = (ld.expression(f"{key}.k3", entry["k3"], pnames, nonzero=True, bounded=True, env=env)
              if "k3" in entry else None)
        out.append(CellLink(a, b, reach, k, key, k3))
    return tuple(out)


def expand(cell: Cell):
    """The finite chain: ``(mass names, mass expressions, springs, dampers)`` with each link as
    ``(link, first mass, second mass)`` (indices into the names, -1 a wall), in the order of the links."""
    p, n = cell.size, cell.cells
    names = tuple(cell.mass_name(a, c) for c in range(n) for a in range(p))
    masses = tuple(cell.masses[a] for _ in range(n) for a in range(p))

    def end(mass: int, c: int) -> int | None:
        """The index of ``mass`` in cell ``c``; -1 past a wall end, None past a free end."""
        if mass == GROUND:
            return -1
        if 0 <= c < n:
            return c * p + mass
        if cell.left is End.RING:
            return (c % n) * p + mass
        side = cell.left if c < 0 else cell.right
        return -1 if side is End.WALL else None

    def copies(links):
        out = []
        for link in links:
            lo, hi = (0, n) if cell.left is End.RING else (min(0, -link.reach), max(n, n - link.reach))
            for c in range(lo, hi):
                i, j = end(link.a, c), end(link.b, c + link.reach)
                if i is None or j is None or i == j == -1:
                    continue
                out.append((link, i, j))
        return tuple(out)

    return names, masses, copies(cell.springs), copies(cell.dampers)


__all__ = ["CELL_KEYS", "GROUND", "MAX_EXPANDED", "MAX_REACH", "Cell", "CellLink", "expand", "parse_cell"]
