"""Physical dimensions as exponents of base dimensions, and the dimension each scene key means.

A :class:`Dimension` is an immutable map ``base -> Fraction`` over pint's base dimensions
(``[mass]``, ``[length]``, ``[time]``, ...); products add exponents, powers scale them. Nothing
here imports pint: the dimension check of an expression (:mod:`.check`) is plain Python.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from fractions import Fraction

#: Base dimensions in the order they are printed.
_ORDER = ("[mass]", "[length]", "[time]", "[current]", "[temperature]", "[substance]", "[luminosity]")


@dataclass(frozen=True)
class Dimension:
    """Exponents of base dimensions (only nonzero ones kept), e.g. stiffness ``{[mass]: 1, [time]: -2}``."""

    exponents: tuple[tuple[str, Fraction], ...] = ()

    @classmethod
    def of(cls, mapping) -> "Dimension":
        """From ``{base: exponent}`` (pint's dimensionality, floats or Fractions)."""
        items = {}
        for base, exp in dict(mapping).items():
            e = Fraction(exp).limit_denominator(64) if isinstance(exp, float) else Fraction(exp)
            if e:
                items[str(base)] = e
        key = lambda b: (_ORDER.index(b) if b in _ORDER else len(_ORDER), b)  # noqa: E731
        return cls(tuple((b, items[b]) for b in sorted(items, key=key)))

    @property
    def map(self) -> dict[str, Fraction]:
        return dict(self.exponents)

    @property
    def dimensionless(self) -> bool:
        return not self.exponents

    def __mul__(self, other: "Dimension") -> "Dimension":
        out = self.map
        for b, e in other.exponents:
            out[b] = out.get(b, Fraction(0)) + e
        return Dimension.of(out)

    def __truediv__(self, other: "Dimension") -> "Dimension":
        return self * other ** -1

    def __pow__(self, p) -> "Dimension":
        return Dimension.of({b: e * Fraction(p) for b, e in self.exponents})

    def __str__(self) -> str:
        if not self.exponents:
            return "dimensionless"

        def power(b, e):
            return b if e == 1 else f"{b}^{e}" if e.denominator == 1 else f"{b}^({e})"

        num = "*".join(power(b, e) for b, e in self.exponents if e > 0) or "1"
        return num + "".join(f"/{power(b, -e)}" for b, e in self.exponents if e < 0)


def _dim(**exp) -> Dimension:
    return Dimension.of({f"[{k}]": v for k, v in exp.items()})


NONE = Dimension()
MASS = _dim(mass=1)
LENGTH = _dim(length=1)
TIME = _dim(time=1)
VELOCITY = _dim(length=1, time=-1)
ACCELERATION = _dim(length=1, time=-2)
FORCE = _dim(mass=1, length=1, time=-2)
STIFFNESS = _dim(mass=1, time=-2)
CUBIC_STIFFNESS = _dim(mass=1, length=-2, time=-2)
DAMPING = _dim(mass=1, time=-1)
ENERGY = _dim(mass=1, length=2, time=-2)
RATE = _dim(time=-1)


@dataclass(frozen=True)
class Meaning:
    """What a scene key means: its dimension, its name and an SI example for messages."""

    dimension: Dimension
    name: str
    example: str

    def __str__(self) -> str:
        return f"{self.name}, {self.dimension} (e.g. {self.example})"


#: (pattern on the key, meaning). The first match wins; a key that matches none takes any dimension.
_KEYS = (
    (r"masses\.[^.]+|chain\.mass", Meaning(MASS, "a mass", "'10 t' or kg")),
    (r"(springs\[\d+\]|chain)\.k", Meaning(STIFFNESS, "a stiffness", "'4 MN/m' or N/m")),
    (r"(springs\[\d+\]|chain)\.k3", Meaning(CUBIC_STIFFNESS, "a cubic stiffness", "N/m^3")),
    (r"(springs\[\d+\]|chain)\.potential", Meaning(ENERGY, "a potential energy", "J, with d in m")),
    (r"dampers\[\d+\]\.c", Meaning(DAMPING, "a damping coefficient", "'2 kN*s/m' or N*s/m")),
    (r"forces\[\d+\]\.(f|table\.f)", Meaning(FORCE, "a force", "'2 kN' or N")),
    (r"ground\.(acceleration|table\.a)|gravity\.g", Meaning(ACCELERATION, "an acceleration", "'9.81 m/s^2' or g")),
    (r"(forces\[\d+\]|ground)\.table\.t", Meaning(TIME, "a time", "s")),
    (r"damping\.rayleigh\[0\]", Meaning(RATE, "a rate (alpha of C = alpha M + beta K)", "1/s")),
    (r"damping\.rayleigh\[1\]", Meaning(TIME, "a time (beta of C = alpha M + beta K)", "s")),
    (r"damping\.(modal.*|rayleigh_targets.*)", Meaning(NONE, "a damping ratio", "0.05")),
    (r"initial\.x(\[\d+\])?", Meaning(LENGTH, "a displacement", "'5 mm' or m")),
    (r"initial\.v(\[\d+\])?", Meaning(VELOCITY, "a velocity", "m/s")),
    (r"simulation\.dt", Meaning(TIME, "a time step", "'1 ms' or s")),
)
_COMPILED = tuple((re.compile(p + r"\Z"), m) for p, m in _KEYS)


def meaning(key: str | None) -> Meaning | None:
    """What the scene key ``key`` means (None: any dimension, e.g. a parameter)."""
    if key is None:
        return None
    return next((m for p, m in _COMPILED if p.match(key)), None)


__all__ = ["Dimension", "Meaning", "meaning", "NONE", "MASS", "LENGTH", "TIME", "VELOCITY", "ACCELERATION",
           "FORCE", "STIFFNESS", "CUBIC_STIFFNESS", "DAMPING", "ENERGY", "RATE"]
