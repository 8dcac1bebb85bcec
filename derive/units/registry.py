"""Units through pint (the optional extra ``springchain[units]``): parse a unit safely, convert to SI.

Scene text is untrusted, so a unit is checked before pint sees it: ASCII letters, digits, ``_``,
spaces, ``* / . ( )`` and powers ``^N`` / ``**N`` with a small whole exponent (|N| <= 16) only,
at most :data:`MAX_UNIT` characters — no nested exponents, nothing pint would have to compute at
length. Offset units (degC) are refused. Factors are exact rationals (pint with
``non_int_type=Fraction``), so ``"20 kN/cm^3"`` becomes the float nearest 2e10, rounded once. pint is imported on the first unit only; a scene
without units never imports it. In a slot that means an acceleration, a bare ``g`` is standard
gravity (9.80665 m/s²), as test engineers write it (``a [g]``, ``g^2/Hz``); elsewhere pint's
``g`` (the gram) stands.
"""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass
from fractions import Fraction

from .dimension import Dimension

#: How to get pint, said in every message that needs it.
EXTRA = 'pip install "springchain[units]"'
#: Longest unit text accepted.
MAX_UNIT = 80
#: Largest |exponent| of a unit power.
MAX_UNIT_EXPONENT = 16

#: ``NUMBER UNIT``: a number, then a unit that starts with a letter or ``(`` or ``1/``.
QUANTITY = re.compile(r"\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)(?![\d.eE])\s*((?:[A-Za-z_(]|1\s*/).*?)\s*\Z",
                      re.S)
_UNIT_CHARS = re.compile(r"[A-Za-z0-9_ */.()^-]*\Z")
_POWER = re.compile(r"(\^|\*\*)\s*(-?\d{1,2}|\(\s*-?\d{1,2}\s*\))(?![\d^.]|\*\*)")  # "m^2*s" is a product
_BARE_G = re.compile(r"(?<![A-Za-z0-9_])g(?![A-Za-z0-9_])")


class UnitProblem(ValueError):
    """A unit that is refused: ``why`` and ``accepted`` make the message's two halves."""

    def __init__(self, why: str, accepted: str):
        super().__init__(f"{why}; accepted: {accepted}")
        self.why, self.accepted = why, accepted


@dataclass(frozen=True)
class Unit:
    """A parsed unit: its text, its exact SI factor (``value [unit] = value * factor [SI]``) and dimension."""

    text: str
    factor: Fraction
    dimension: Dimension


def split_quantity(text) -> tuple[Fraction, str] | None:
    """``(number, unit text)`` of ``"4 MN/m"`` (the number exact, as written); None for anything else."""
    if not isinstance(text, str) or len(text) > MAX_UNIT + 40:
        return None
    m = QUANTITY.match(text)
    if not m or not re.search(r"[A-Za-z]", m.group(2)):
        return None
    try:
        number = Fraction(m.group(1))
    except (ValueError, ZeroDivisionError):  # pragma: no cover - the pattern is a decimal literal
        return None
    if abs(number) > 10**300:
        return None
    return number, m.group(2)


@functools.cache
def registry():
    """pint's UnitRegistry with exact rational factors (one per process; cached on disk by pint where it can)."""
    try:
        import pint
    except ImportError:
        raise UnitProblem("a value with a unit needs pint, which springchain installs only on request",
                          f"{EXTRA}, or a plain number in SI units") from None
    try:
        return pint.UnitRegistry(non_int_type=Fraction, cache_folder=":auto:")
    except Exception:  # noqa: BLE001 - an unwritable cache folder: build without the cache
        return pint.UnitRegistry(non_int_type=Fraction)


def _screen(text: str) -> str:
    """The unit text if it is of the safe form (see the module docstring); raises UnitProblem."""
    form = ("a unit such as kg, t, N/m, MN/m, kN*s/m, m/s^2, g (accelerations), with whole powers "
            f"^N up to {MAX_UNIT_EXPONENT}")
    if len(text) > MAX_UNIT:
        raise UnitProblem(f"unit longer than {MAX_UNIT} characters", form)
    if not text.isascii() or not _UNIT_CHARS.match(text):
        bad = next((ch for ch in text if not (ch.isascii() and _UNIT_CHARS.match(ch))), "?")
        raise UnitProblem(f"character {bad!r} in the unit {text!r}", form)
    rest = _POWER.sub(" ", text)
    if "^" in rest or "**" in rest:
        raise UnitProblem(f"unit {text!r}: a power that is not a small whole number", form)
    for m in _POWER.finditer(text):
        if abs(int(re.sub(r"[()\s]", "", m.group(2)))) > MAX_UNIT_EXPONENT:
            raise UnitProblem(f"unit {text!r}: exponent beyond {MAX_UNIT_EXPONENT}", form)
    if text.count("(") != text.count(")"):
        raise UnitProblem(f"unit {text!r}: unbalanced parentheses", form)
    return text


def parse_unit(text: str, expected: Dimension | None = None) -> Unit:
    """The unit ``text`` as a :class:`Unit`.

    ``expected``: the dimension of the slot; where it contains [length]/[time]^2 and no [mass]
    (an acceleration, or its PSD), a bare ``g`` means standard gravity.

    Raises
    ------
    UnitProblem
        pint missing, an unsafe or unknown unit, an offset unit.
    """
    text = _screen(text.strip())
    ureg = registry()
    pint_text = text
    if expected is not None and _BARE_G.search(text):
        m = expected.map
        if "[mass]" not in m and m.get("[length]") and m.get("[time]"):
            pint_text = _BARE_G.sub("g_0", text)
    import pint

    try:
        unit = ureg.parse_units(pint_text)
        q = ureg.Quantity(Fraction(1), unit)
        q * 2  # offset units (degC) refuse arithmetic
        base = q.to_base_units()
    except pint.errors.OffsetUnitCalculusError:
        raise UnitProblem(f"{text!r} is an offset unit", "multiplicative units (K, not degC)") from None
    except (pint.errors.UndefinedUnitError, pint.errors.DefinitionSyntaxError, AttributeError, TypeError,
            ValueError, SyntaxError, KeyError, IndexError) as exc:
        name = getattr(exc, "unit_names", None) or text
        name = name[0] if isinstance(name, (list, tuple)) and name else name
        raise UnitProblem(f"unknown unit {str(name)!r}", "a unit pint knows, e.g. kg, t, N, kN, MN/m, kN*s/m, "
                                                         "m/s^2, mm, s, ms") from None
    return Unit(text, Fraction(base.magnitude), Dimension.of(dict(base.dimensionality)))


def gram_hint(text: str, dimension: Dimension) -> str:
    """A clause for a message when ``text`` (a unit or ``"NUMBER UNIT"``) of ``dimension`` uses pint's ``g``
    (the gram) and so has a mass in it where the slot wanted something else: the silent "0.3 g is
    0.3 gram" of a scene that meant standard gravity. ``""`` when ``g`` is not involved.
    """
    if not isinstance(text, str) or "[mass]" not in dimension.map or not _BARE_G.search(text):
        return ""
    return (f"; g is the gram there (a mass); standard gravity (9.80665 m/s^2) is g_0, as in "
            f"{_BARE_G.sub('g_0', text.strip())!r}")


def si_unit_text(dimension: Dimension) -> str:
    """The SI base-unit text of a dimension (``kg/s^2``), for writing a number back with its unit."""
    names = {"[mass]": "kg", "[length]": "m", "[time]": "s", "[current]": "A", "[temperature]": "K",
             "[substance]": "mol", "[luminosity]": "cd"}
    num = [f"{names[b]}" + (f"^{e}" if e != 1 else "") for b, e in dimension.exponents if e > 0]
    den = [f"{names[b]}" + (f"^{-e}" if e != -1 else "") for b, e in dimension.exponents if e < 0]
    text = "*".join(num) or "1"
    return text + "".join(f"/{d}" for d in den) if den else text


__all__ = ["EXTRA", "Unit", "UnitProblem", "parse_unit", "split_quantity", "registry", "si_unit_text", "MAX_UNIT",
           "gram_hint"]
