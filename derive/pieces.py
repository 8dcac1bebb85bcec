"""Connected pieces of a scene's graph: masses joined by links (springs, dashpots), walls joining nothing.

The one union-find of the derive side: the rigid-body count of a scene (:mod:`.scene`), the
spring components of a model (:mod:`.model`) and the pieces damped modes are found in
(:mod:`.damping_report`) all read it.
"""

from __future__ import annotations

from typing import Iterable


def pieces(n: int, links: Iterable[tuple[int, int]]) -> list[list[int]]:
    """The connected pieces of masses ``0 … n-1`` joined by ``links``.

    Parameters
    ----------
    n : int
        Number of masses.
    links : iterable of (int, int)
        Mass index pairs; a negative index (a wall) joins nothing.

    Returns
    -------
    list of list of int
        Each piece in mass order, the pieces ordered by their first mass.
    """
    parent = list(range(n))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b in links:  # one pass over the links, not over the masses
        if a >= 0 and b >= 0:
            parent[root(a)] = root(b)
    groups: dict[int, list[int]] = {}
    for i in range(n):
        groups.setdefault(root(i), []).append(i)
    return list(groups.values())
