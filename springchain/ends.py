"""Chain ends: the one vocabulary shared by the scene language (``left``/``right`` of ``[chain]``),
the symbolic side, the generated modules' ``LEFT``/``RIGHT`` constants and the numeric kernels.

Imports nothing of springchain's, so both sides may use it.
"""

from __future__ import annotations

import enum


class End(enum.StrEnum):
    """How a chain ends. The value is the scene's word and the generated ``LEFT``/``RIGHT``
    constant; :attr:`code` is the integer the compiled kernels see.

    ``FREE``: no spring beyond the end mass. ``WALL``: a spring to a fixed wall (``k(-1)`` on the
    left, ``k(n-1)`` on the right). ``RING``: the spring ``k(n-1)`` closes mass n-1 to mass 0
    (both ends, or neither).
    """

    FREE = "free"
    WALL = "wall"
    RING = "ring"

    @property
    def code(self) -> int:
        """0, 1, 2 for free, wall, ring (the compiled kernels' argument)."""
        return _CODES[self]

    @property
    def has_spring(self) -> bool:
        """Whether a spring lies beyond the end mass (to a wall, or closing the ring)."""
        return self is not End.FREE


_CODES = {End.FREE: 0, End.WALL: 1, End.RING: 2}

#: The scene words, in the order the error messages list them.
END_WORDS = tuple(e.value for e in End)
