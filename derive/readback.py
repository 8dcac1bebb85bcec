"""Read the ``omega2`` and ``shape`` strings of ``modes --json`` back into SymPy, with the scene's symbols.

The strings are ``sympy.sstr`` of the closed forms. Handing them to ``sympify`` or
``parse_expr`` would read a parameter named ``E``, ``I``, ``S``, ``Q``, ``N``, ``O``,
``beta``, ``gamma`` or ``zeta`` as SymPy's constant or function of that name, and would
evaluate arbitrary text. Here the text goes through the scene-expression whitelist
(:func:`derive.expr.parse_expression`: names limited to the scene's parameters, calls to
the few functions closed forms use, constant exponents) and is built with the very
symbols the derivation used (:func:`derive.model.parameter_symbols`, same assumptions),
so ``parse_printed(sstr(e), scene) == e`` for every closed form ``e``.

Decimal numbers (the numeric values printed where there is no closed form) read back as
the exact rationals of their decimal text.
"""

from __future__ import annotations

import sympy as sp

from .expr import parse_expression
from .model import parameter_symbols
from .scene import Scene

#: Functions that printed closed forms call (Viète's cubic roots use acos and cos).
READBACK_FUNCTIONS = ("acos", "cos", "exp", "sin", "sqrt")
#: Printed closed forms are at most a few hundred operations (derive.modes.MAX_ROOT_OPS).
READBACK_MAX_LENGTH = 20_000
READBACK_MAX_NODES = 4_000


def parse_printed(text: str, scene: Scene, *, key: str = "omega2") -> sp.Expr:
    """A printed ``omega2`` or ``shape`` string as a SymPy expression in the scene's symbols.

    Parameters
    ----------
    text : str
        One ``omega2`` string, or one entry of a ``shape`` list, from ``modes --json``.
    scene : Scene
        The scene the modes were derived from (its parameter names and signs).
    key : str
        Named in error messages.

    Returns
    -------
    sympy.Expr

    Raises
    ------
    SceneError
        If the text is not an expression in the scene's parameters (naming the text and
        what is accepted); nothing is evaluated.
    """
    tree = parse_expression(text, frozenset(scene.parameters), file=scene.file, key=key,
                            functions=READBACK_FUNCTIONS, max_length=READBACK_MAX_LENGTH,
                            max_nodes=READBACK_MAX_NODES)
    return tree.to_sympy(parameter_symbols(scene))
