"""Distributions of a parameter study, parsed from text such as ``uniform(0.5, 1.5)``.

Accepted forms (numbers in Python/TOML float syntax, no expressions)::

    uniform(a, b)        a < b, a draw is uniform on [a, b)
    normal(mu, sigma)    sigma > 0
    lognormal(mu, sigma) exp of normal(mu, sigma), sigma > 0
    grid(a, b, n)        n >= 1 evenly spaced values a ... b (deterministic, not drawn)

The parser is a small tokenizer of its own: nothing is ever evaluated.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from ..errors import RunRefused

KINDS = {"uniform": 2, "normal": 2, "lognormal": 2, "grid": 3}
ACCEPTED = "uniform(a, b), normal(mu, sigma), lognormal(mu, sigma) or grid(a, b, n)"

_NUMBER = r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?"
_FORM = re.compile(r"^\s*([A-Za-z_]\w*)\s*\((.*)\)\s*$", re.S)
_ARG = re.compile(rf"^\s*({_NUMBER})\s*$")


@dataclass(frozen=True)
class Dist:
    """One distribution. ``args`` are floats (``grid``'s n is a whole number)."""

    kind: str
    args: tuple[float, ...]

    @property
    def is_grid(self) -> bool:
        return self.kind == "grid"

    @property
    def text(self) -> str:
        """Canonical text (``repr`` of each number): the same settings give the same text."""
        parts = [str(int(a)) if (self.kind == "grid" and i == 2) else repr(float(a)) for i, a in enumerate(self.args)]
        return f"{self.kind}({', '.join(parts)})"

    def grid_values(self) -> np.ndarray:
        a, b, n = self.args
        return np.linspace(a, b, int(n))

    def draw(self, rng: np.random.Generator, size=None):
        """Draws from ``rng`` (not for grids)."""
        a, b = self.args[:2]
        if self.kind == "uniform":
            return rng.uniform(a, b, size)
        if self.kind == "normal":
            return rng.normal(a, b, size)
        if self.kind == "lognormal":
            return rng.lognormal(a, b, size)
        raise ValueError(f"{self.kind} is not drawn")

    def mean(self) -> float:
        a, b = self.args[:2]
        return {"uniform": (a + b) / 2, "normal": a, "lognormal": math.exp(a + b * b / 2),
                "grid": (a + b) / 2}[self.kind]

    def variance(self) -> float:
        a, b = self.args[:2]
        if self.kind == "uniform":
            return (b - a) ** 2 / 12
        if self.kind == "normal":
            return b * b
        if self.kind == "lognormal":
            return math.expm1(b * b) * math.exp(2 * a + b * b)
        return float(np.var(self.grid_values()))


def parse(text: str, flag: str = "DIST") -> Dist:
    """Parse one distribution; errors name ``flag`` and the accepted forms."""
    if not isinstance(text, str):
        raise RunRefused(f"{flag} {text!r}: not a distribution; accepted: {ACCEPTED}")
    m = _FORM.match(text)
    if not m:
        raise RunRefused(f"{flag} {text!r}: not a distribution; accepted: {ACCEPTED}")
    kind, body = m.group(1), m.group(2)
    if kind not in KINDS:
        raise RunRefused(f"{flag} {text!r}: unknown distribution {kind!r}; accepted: {ACCEPTED}")
    raw = body.split(",") if body.strip() else []
    if len(raw) != KINDS[kind]:
        raise RunRefused(f"{flag} {text!r}: {kind} takes {KINDS[kind]} numbers, got {len(raw)}; accepted: {ACCEPTED}")
    args = []
    for piece in raw:
        am = _ARG.match(piece)
        if not am:
            raise RunRefused(f"{flag} {text!r}: {piece.strip()!r} is not a number; accepted: {ACCEPTED} "
                             "with plain numbers")
        value = float(am.group(1))
        if not math.isfinite(value):
            raise RunRefused(f"{flag} {text!r}: {piece.strip()!r} is not finite; accepted: finite numbers")
        args.append(value)
    if kind == "uniform" and not args[0] < args[1]:
        raise RunRefused(f"{flag} {text!r}: uniform(a, b) needs a < b")
    if kind in ("normal", "lognormal") and not args[1] > 0:
        raise RunRefused(f"{flag} {text!r}: {kind}(mu, sigma) needs sigma > 0")
    if kind == "grid":
        n = args[2]
        if n != int(n) or n < 1:
            raise RunRefused(f"{flag} {text!r}: grid(a, b, n) needs a whole number n >= 1")
        if n > 1 and not args[0] < args[1]:
            raise RunRefused(f"{flag} {text!r}: grid(a, b, n) needs a < b")
    return Dist(kind, tuple(args))


def parse_assignment(text: str, flag: str, names=None) -> tuple[str, Dist]:
    """``NAME=DIST`` -> (NAME, Dist); ``names`` (optional) are the accepted NAMEs."""
    if not isinstance(text, str) or "=" not in text:
        raise RunRefused(f"{flag} {text!r}: accepted: NAME=DIST with DIST one of {ACCEPTED}")
    name, dist = (s.strip() for s in text.split("=", 1))
    if names is not None and name not in names:
        raise RunRefused(f"{flag} {text!r}: {name!r} is not accepted here; accepted: {', '.join(sorted(names))}")
    if not re.fullmatch(r"[A-Za-z_]\w*", name):
        raise RunRefused(f"{flag} {text!r}: {name!r} is not a name; accepted: NAME=DIST")
    return name, parse(dist, f"{flag} {name}")


__all__ = ["Dist", "parse", "parse_assignment", "ACCEPTED", "KINDS"]
