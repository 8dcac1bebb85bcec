"""``[[dampers]]`` in ``[chain]`` scenes: families of dashpots indexed by ``i``, or single ones.

Three forms of ``between`` (``c`` may use ``i`` in the families, like the chain's ``mass``/``k``):

* ``["i", "i+1"]`` — a dashpot beside every interior spring, between masses i and i+1
  (i = 0 … n−2); force on i is ``-c(i) (v_i − v_{i+1})``;
* ``["i", "wall"]`` — a dashpot from every mass to the ground (i = 0 … n−1): ``-c(i) v_i``;
* ``[I, J]`` or ``[I, "wall"]`` with 0-based indices — one dashpot (``c`` without ``i``).

SymPy is not imported here.
"""

from __future__ import annotations

from dataclasses import dataclass

from .expr import Expr
from .scene_loader import Loader

DAMPER_KEYS = ("between", "c")
ALONG, GROUND, SINGLE = "along", "ground", "single"
_ACCEPTED = ('["i", "i+1"] (beside every spring), ["i", "wall"] (every mass to the ground), '
             'or two 0-based mass indices / "wall", e.g. [0, "wall"]')


@dataclass(frozen=True)
class ChainDamper:
    """A family (``kind`` ALONG or GROUND, ``c`` of i) or a SINGLE dashpot between ``a`` and ``b``
    (mass indices, -1 = wall)."""

    kind: str
    a: int
    b: int
    c: Expr
    key: str


def parse_chain_dampers(ld: Loader, entries: list[dict], n: int, pnames: frozenset[str],
                        env: dict) -> tuple[ChainDamper, ...]:
    """Validate the ``[[dampers]]`` entries of a chain of ``n`` masses."""
    out = []
    for j, d in enumerate(entries):
        key = f"dampers[{j}]"
        ld.keys(d, DAMPER_KEYS, key, required=("between", "c"), what="a [[dampers]] entry")
        between = d["between"]
        if between == ["i", "i+1"] or between == ["i+1", "i"]:
            if n < 2:
                raise ld.bad(f"{key}.between", between, "a chain of one mass has no springs", '["i", "wall"]')
            c = ld.expression(f"{key}.c", d["c"], pnames | {"i"}, positive=True, bounded=True, env=env,
                              index_range=range(n - 1))
            out.append(ChainDamper(ALONG, 0, 1, c, key))
            continue
        if between in (["i", "wall"], ["wall", "i"]):
            c = ld.expression(f"{key}.c", d["c"], pnames | {"i"}, positive=True, bounded=True, env=env,
                              index_range=range(n))
            out.append(ChainDamper(GROUND, 0, -1, c, key))
            continue
        if not isinstance(between, list) or len(between) != 2:
            raise ld.bad(f"{key}.between", between, "not a pair of ends", _ACCEPTED)
        ends = []
        for e in between:
            if e == "wall":
                ends.append(-1)
            elif isinstance(e, int) and not isinstance(e, bool) and 0 <= e < n:
                ends.append(e)
            else:
                raise ld.bad(f"{key}.between", e, f"not a mass index 0 ... {n - 1} or 'wall'", _ACCEPTED)
        if ends[0] == ends[1]:
            raise ld.bad(f"{key}.between", between, "both ends are the same", "two different ends")
        c = ld.expression(f"{key}.c", d["c"], pnames, positive=True, bounded=True, env=env)
        out.append(ChainDamper(SINGLE, ends[0], ends[1], c, key))
    return tuple(out)


__all__ = ["ChainDamper", "parse_chain_dampers", "ALONG", "GROUND", "SINGLE"]
