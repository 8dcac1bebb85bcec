"""Checking the values of an untrusted scene file, one key at a time (:class:`Loader`).

Every check raises :class:`~springchain.derive.errors.SceneError` with one line naming the file,
the key, the bad value and what is accepted (with "did you mean" for near spellings and usual
synonyms, :func:`did_you_mean`). :mod:`springchain.derive.scene` builds the scene with it.
"""

from __future__ import annotations

import difflib
import keyword
import math

import numpy as np

from .errors import SceneError, show
from .expr import Expr, Num, parse_expression
from .units import SceneUnits

#: Longest name (parameter, mass).
MAX_NAME = 64
#: Masses, stiffnesses, damping and |k3|, |g| must lie in this range (no
#: subnormal numbers, no overflow when two of them multiply); so must every number written in an
#: expression (or be 0), and a potential's stiffness at the equilibrium. (Parameter values are not
#: held to it themselves: a phase of 1e-167 is harmless; what they make is checked.)
MIN_MAGNITUDE, MAX_MAGNITUDE = 1e-150, 1e150
#: What the range check says is accepted.
IN_RANGE = f"0 or numbers of size {MIN_MAGNITUDE:g} to {MAX_MAGNITUDE:g}"
#: Index values evaluated at once when checking [chain] expressions.
INDEX_CHUNK = 1 << 16


#: Words people write for each key, tried after spelling mistakes for "did you mean".
_SYNONYMS = {
    "k": "stiffness spring_constant spring_k k1",
    "k3": "kappa cubic k_cubic nonlinear",
    "c": "damping viscosity coefficient c1",
    "between": "ends connects nodes pair link",
    "masses": "mass",
    "springs": "spring",
    "dampers": "damper dashpots",
    "forces": "force forcing loads load",
    "on": "target mass_name at",
    "f": "force_expression value",
    "parameters": "params parameter constants values",
    "initial": "init initial_conditions ic start",
    "x": "x0 position positions displacement displacements",
    "v": "v0 velocity velocities",
    "simulation": "sim settings solver run",
    "dt": "h step timestep time_step step_size",
    "steps": "nsteps n_steps num_steps iterations",
    "record_every": "record stride every save_every",
    "name": "title",
    "description": "desc comment",
    "n": "count length size",
    "mass": "m",
    "left": "left_end",
    "right": "right_end",
    "g": "g0 acceleration",
}
#: Each such word -> the key it means.
ALIASES = {word: key for key, words in _SYNONYMS.items() for word in words.split()}



def did_you_mean(word: object, options) -> str:
    """`` (did you mean 'x'?)`` for a near spelling or a usual synonym of ``word``, else ``""``."""
    if not isinstance(word, str):
        return ""
    options = [o for o in options if isinstance(o, str)]
    norm = word.strip().lower().replace("-", "_").replace(" ", "_")
    if norm in options and norm != word:
        return f" (did you mean {norm!r}?)"
    near = difflib.get_close_matches(word, options, n=1) or difflib.get_close_matches(norm, options, n=1)
    if not near and ALIASES.get(norm) in options:
        near = [ALIASES[norm]]
    return f" (did you mean {near[0]!r}?)" if near else ""


class Loader:
    def __init__(self, file: str, data: dict):
        self.file = file
        self.data = data
        #: Units of this scene (values "NUMBER UNIT" to SI, dimension checks); idle without units.
        self.units = SceneUnits(file)

    def err(self, key: str | None, message: str) -> SceneError:
        return SceneError(self.file, key, message)

    def bad(self, key: str | None, value, why: str, accepted: str) -> SceneError:
        """``<key>: <value>: <why>; accepted: <accepted>``."""
        return SceneError(self.file, key, f"{show(value)}: {why}; accepted: {accepted}")

    def keys(self, table: dict, allowed: tuple[str, ...], where: str | None, required=(),
             what: str | None = None) -> None:
        for k in table:
            if k not in allowed:
                raise self.err(f"{where}.{k}" if where else k,
                               f"unknown key{did_you_mean(k, allowed)}; accepted: {', '.join(allowed)}")
        optional = [k for k in allowed if k not in required]
        form = (f"{what or where or 'the file'} with {', '.join(required)}"
                + (f" (optional: {', '.join(optional)})" if optional else ""))
        for k in required:
            if k not in table:
                raise self.err(f"{where}.{k}" if where else k, f"missing; accepted: {form}")

    def table(self, key: str, required=False, example: str = "") -> dict:
        value = self.data.get(key)
        if value is None:
            if required:
                raise self.err(key, f"missing; accepted: a table [{key}]{example}")
            return {}
        if not isinstance(value, dict):
            raise self.bad(key, value, "not a table", f"a table written [{key}]{example}")
        return value

    def array_of_tables(self, key: str) -> list[dict]:
        value = self.data.get(key, [])
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise self.bad(key, value, "not an array of tables", f"entries written [[{key}]]")
        return value

    def identifier(self, key: str, value, what: str = "name") -> str:
        accepted = f"an ASCII Python identifier of at most {MAX_NAME} characters, such as 'm1'"
        if not isinstance(value, str):
            raise self.bad(key, value, f"a {type(value).__name__}, not a {what}", accepted)
        if not value.isascii():
            bad = next(ch for ch in value if not ch.isascii())
            raise self.bad(key, value, f"non-ASCII character {bad!r} (look-alike letters are refused)",
                           accepted)
        if not value.isidentifier():
            raise self.bad(key, value, f"not an identifier", accepted)
        if len(value) > MAX_NAME:
            raise self.bad(key, value, f"longer than {MAX_NAME} characters", accepted)
        if keyword.iskeyword(value):
            raise self.bad(key, value, "a Python keyword", f"another {what}, e.g. {value}_1")
        if value.startswith("_"):
            raise self.bad(key, value, "starts with '_' (kept for generated code)", accepted)
        return value

    def number(self, key: str, value, *, positive=False, integer=False, maximum=None) -> float | int:
        """A finite TOML number (int or float; never a boolean or a string)."""
        if isinstance(value, str) and (si := self.units.number(key, value)) is not None:
            value = si  # "NUMBER UNIT", in SI
        what = "a whole number" if integer else "a number"
        accepted = what + (" > 0" if positive else "") + (f" up to {maximum:g}" if maximum else "")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            kind = "a boolean" if isinstance(value, bool) else f"a {type(value).__name__}"
            raise self.bad(key, value, f"{kind}, not a number", accepted)
        if integer and not isinstance(value, int):
            raise self.bad(key, value, "not a whole number", accepted)
        try:
            finite = math.isfinite(value) and abs(float(value)) < math.inf
        except OverflowError:
            finite = False
        if not finite:
            raise self.bad(key, value, "not a finite number", accepted)
        if positive and value <= 0:
            raise self.bad(key, value, "not > 0", accepted)
        if maximum is not None and value > maximum:
            raise self.bad(key, value, f"more than {maximum:g}", accepted)
        return value

    def literals(self, key: str, text, expr: Expr) -> Expr:
        """Check every number written in ``expr``: 0 or of size ``MIN_MAGNITUDE`` … ``MAX_MAGNITUDE``.

        A potential's ``1e200*d**2`` has no value to check before its derivatives, and a product
        of in-range values can still be range-checked only as a whole: the literals themselves are
        held to the same range as the values, so no number the derivation starts from is outside it.
        """
        for v in expr.numbers():
            if v != 0 and not MIN_MAGNITUDE <= abs(float(v)) <= MAX_MAGNITUDE:
                raise self.bad(key, text, f"the number {float(v):g} is outside the accepted range",
                               f"numbers written as {IN_RANGE}")
        return expr

    def expression(self, key: str, text, allowed, *, positive=False, nonzero=False, env=None,
                   index_range=None, bounded=False) -> Expr:
        """Parse an expression and check its value at the scene's parameter values.

        ``index_range`` is an iterable of index values i (for [chain]
        expressions), evaluated in chunks so that memory stays bounded.
        ``positive`` and ``nonzero`` hold only if rounding cannot blur them:
        the value must exceed its error bound. ``bounded`` asks for
        ``MIN_MAGNITUDE <= |value| <= MAX_MAGNITUDE``.
        """
        text = self.units.value(key, text)  # "NUMBER UNIT" -> its SI number
        expr = parse_expression(text, allowed, file=self.file, key=key)
        self.units.check(key, text, expr)
        env = dict(env or {})
        chunks = [None] if index_range is None else [index_range[s:s + INDEX_CHUNK]
                                                    for s in range(0, len(index_range), INDEX_CHUNK)]
        for chunk in chunks:
            if chunk is not None:
                env["i"] = np.asarray(chunk, dtype=float)
            self._check_value(key, text, expr, env, positive=positive, nonzero=nonzero, bounded=bounded)
        return self.literals(key, text, expr)

    def _check_value(self, key, text, expr, env, *, positive, nonzero, bounded):
        try:
            value, error = expr.evaluate_error(env)
        except (OverflowError, ZeroDivisionError, ValueError, TypeError, FloatingPointError):
            value, error = math.nan, math.inf
        shape = np.broadcast_shapes(np.shape(value), np.shape(error), np.shape(env.get("i", 0.0)),
                                    np.shape(env.get("t", 0.0)))
        value = np.broadcast_to(np.asarray(value, dtype=float), shape)
        error = np.broadcast_to(np.asarray(error, dtype=float), shape)
        verb = "is" if isinstance(expr, Num) else "evaluates to"

        def where(mask) -> str:
            if "i" in env and np.ndim(env["i"]):
                return f" at i = {int(np.asarray(env['i'])[np.argmax(mask)])}"
            if "t" in env and np.ndim(env["t"]):
                return f" at t = {float(np.asarray(env['t'])[np.argmax(mask)]):g}"
            return ""

        def first(mask):
            return float(value.ravel()[np.argmax(mask.ravel())])

        bad = ~np.isfinite(value)
        if bad.any():
            raise self.bad(key, text, f"{verb} {first(bad):g}{where(bad)}",
                           "an expression finite at the scene's parameter values")
        unbounded = ~np.isfinite(error)
        if unbounded.any():
            raise self.bad(key, text, f"rounding cannot pin its value down{where(unbounded)} (a divisor "
                                      "or root argument that rounding cannot tell from 0, or % at a jump)",
                           "an expression whose divisors are clearly away from 0")
        wanted = "a value > 0" if positive else "a nonzero value"
        if positive and (value <= 0).any():
            mask = value <= 0
            raise self.bad(key, text, f"{verb} {first(mask):g}{where(mask)}", wanted)
        if nonzero and (value == 0).any():
            mask = value == 0
            raise self.bad(key, text, f"{verb} 0{where(mask)}", wanted + " (or leave the key out)")
        if (positive or nonzero) and (np.abs(value) <= error).any():
            mask = np.abs(value) <= error
            raise self.bad(key, text, f"{verb} {first(mask):.3g}{where(mask)}, which rounding cannot "
                                      f"tell from 0 (error bound {float(error.ravel()[np.argmax(mask.ravel())]):.2g})",
                           wanted + " clearly away from 0")
        if bounded:
            mask = (np.abs(value) < MIN_MAGNITUDE) | (np.abs(value) > MAX_MAGNITUDE)
            if mask.any():
                raise self.bad(key, text, f"{verb} {first(mask):g}{where(mask)}",
                               f"values of size {MIN_MAGNITUDE:g} to {MAX_MAGNITUDE:g}")


