"""The dimension of a scene expression, checked node by node (plain Python, no pint).

In an expression that involves a quantity with a unit (a parameter given as ``"10 t"``), every
name has a dimension: parameters with units theirs, ``t`` a time, ``d`` (a potential's extension)
a length, ``i``, ``n``, ``pi``, literal numbers and parameters given as plain numbers none.
Sums and differences must agree, a power's exponent is a plain constant, and cos, sin, exp, log,
tanh, cosh, sinh take a dimensionless argument; sqrt halves the exponents.
"""

from __future__ import annotations

from fractions import Fraction

from ..expr_tree import BinOp, Call, Expr, Name, Neg, Num
from .dimension import LENGTH, NONE, TIME, Dimension

#: The dimension of the scene language's own variables once units are in play.
VARIABLES = {"t": TIME, "d": LENGTH, "i": NONE, "n": NONE, "pi": NONE}


class DimensionProblem(ValueError):
    """A sub-expression whose dimensions do not fit (``why``: one clause for the message)."""

    def __init__(self, why: str):
        super().__init__(why)
        self.why = why


def _constant(node: Expr) -> Fraction | None:
    if isinstance(node, Num):
        return node.value
    if isinstance(node, Neg):
        v = _constant(node.operand)
        return None if v is None else -v
    if isinstance(node, BinOp) and node.op in "+-*/":
        a, b = _constant(node.left), _constant(node.right)
        if a is None or b is None or (node.op == "/" and b == 0):
            return None
        return {"+": a + b, "-": a - b, "*": a * b, "/": a / b if b else None}[node.op]
    return None


def text_of(node: Expr) -> str:
    """A compact rendering of a node for messages."""
    if isinstance(node, Num):
        v = node.value
        return str(v.numerator) if v.denominator == 1 else f"{float(v):g}"
    if isinstance(node, Name):
        return node.name
    if isinstance(node, Neg):
        return f"-{text_of(node.operand)}"
    if isinstance(node, Call):
        return f"{node.func}({text_of(node.arg)})"
    if isinstance(node, BinOp):
        return f"({text_of(node.left)}{node.op}{text_of(node.right)})"
    return "?"  # pragma: no cover


def dimension_of(node: Expr, names: dict[str, Dimension]) -> Dimension:
    """The dimension of ``node`` with ``names`` the dimensions of parameters (missing: none).

    Raises
    ------
    DimensionProblem
        Naming the sub-expression and what does not fit.
    """
    if isinstance(node, Num):
        return NONE
    if isinstance(node, Name):
        return names.get(node.name, VARIABLES.get(node.name, NONE))
    if isinstance(node, Neg):
        return dimension_of(node.operand, names)
    if isinstance(node, Call):
        inner = dimension_of(node.arg, names)
        if node.func == "sqrt":
            return inner ** Fraction(1, 2)
        if not inner.dimensionless:
            raise DimensionProblem(f"the argument of {node.func}() in {text_of(node)} has dimension {inner} "
                                   "(accepted there: a plain number)")
        return NONE
    if isinstance(node, BinOp):
        left = dimension_of(node.left, names)
        if node.op == "**":
            p = _constant(node.right)
            if p is None:  # the parser allows constant exponents only
                raise DimensionProblem(f"the exponent of {text_of(node)} is not a plain constant")
            return left ** p
        right = dimension_of(node.right, names)
        if node.op in "+-":
            if left != right:
                word = lambda d: "a plain number" if d.dimensionless else str(d)  # noqa: E731
                raise DimensionProblem(f"{text_of(node)} {'adds' if node.op == '+' else 'subtracts'} "
                                       f"{word(right)} {'to' if node.op == '+' else 'from'} {word(left)}")
            return left
        if node.op == "*":
            return left * right
        if node.op == "/":
            return left / right
        if node.op == "%":
            if not right.dimensionless and right != left:
                raise DimensionProblem(f"{text_of(node)} takes the remainder of {left} by {right}")
            return left
    raise DimensionProblem(f"cannot tell the dimension of {text_of(node)}")  # pragma: no cover


__all__ = ["dimension_of", "DimensionProblem", "VARIABLES", "text_of"]
