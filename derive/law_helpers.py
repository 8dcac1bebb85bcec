"""Helpers that generated modules of potential scenes copy (``inspect.getsource``): NumPy only.

Real code, so it is tested as code; the generator copies its source into a module that uses it
(:func:`helper_source`), and the derive side calls the same function for its checks.
"""

from __future__ import annotations

import inspect

import numpy as _np

from ..generated.contract import SCALAR_HELPERS

#: 1/k! for k = 2 … 18: the series of expm1(z) − z, to below 2⁻⁵³ relative for |z| ≤ 1/2.
_EXPM1MX_COEFFICIENTS = (
    1 / 2, 1 / 6, 1 / 24, 1 / 120, 1 / 720, 1 / 5040, 1 / 40320, 1 / 362880, 1 / 3628800,
    1 / 39916800, 1 / 479001600, 1 / 6227020800, 1 / 87178291200, 1 / 1307674368000,
    1 / 20922789888000, 1 / 355687428096000, 1 / 6402373705728000)


def _expm1mx(_z):
    """exp(z) − 1 − z without cancellation: the Taylor series for |z| ≤ 1/2, expm1(z) − z beyond
    (where the subtraction loses at most a factor 5); any shape."""
    _z = _np.asarray(_z, dtype=_np.float64)
    _s = _np.zeros_like(_z)
    for _c in _EXPM1MX_COEFFICIENTS[::-1]:
        _s = _s * _z + _c
    return _np.where(_np.abs(_z) <= 0.5, _s * _z * _z, _np.expm1(_z) - _z)


def _log1pmx(_z):
    """log(1 + z) − z without cancellation: with s = z/(2 + z), log1p(z) = 2 atanh(s), so
    log1p(z) − z = −z²/(2 + z) + 2 (s³/3 + s⁵/5 + …) (18 terms: |s| ≤ 1/3 for |z| ≤ 1/2),
    and log1p(z) − z beyond; any shape."""
    _z = _np.asarray(_z, dtype=_np.float64)
    with _np.errstate(all="ignore"):
        _s = _z / (2.0 + _z)
        _q = _s * _s
        _t = _np.zeros_like(_z)
        for _j in range(18, -1, -1):
            _t = _t * _q + 1.0 / (2 * _j + 3)
        _series = -_z * _z / (2.0 + _z) + 2.0 * _s * _q * _t
        return _np.where(_np.abs(_z) <= 0.5, _series, _np.log1p(_z) - _z)


def _expm1mx_s(_z):
    """_expm1mx of one float, in straight scalar code (``scalar_force``: numba compiles it)."""
    if abs(_z) <= 0.5:
        _s = 0.0
        for _j in range(len(_EXPM1MX_COEFFICIENTS) - 1, -1, -1):
            _s = _s * _z + _EXPM1MX_COEFFICIENTS[_j]
        return _s * _z * _z
    return _np.expm1(_z) - _z


def _log1pmx_s(_z):
    """_log1pmx of one float, in straight scalar code (``scalar_force``: numba compiles it)."""
    if abs(_z) <= 0.5:
        _s = _z / (2.0 + _z)
        _q = _s * _s
        _t = 0.0
        for _j in range(18, -1, -1):
            _t = _t * _q + 1.0 / (2 * _j + 3)
        return -_z * _z / (2.0 + _z) + 2.0 * _s * _q * _t
    return _np.log1p(_z) - _z


#: The helpers a generated module may need, by the name its code calls (``_s``: the scalar forms of
#: ``scalar_force``, which call them where the array forms are called).
HELPERS = {"_expm1mx": _expm1mx, "_log1pmx": _log1pmx, "_expm1mx_s": _expm1mx_s, "_log1pmx_s": _log1pmx_s}
#: The scalar form of each array helper (the shared fact, :data:`generated.contract.SCALAR_HELPERS`).
SCALAR = SCALAR_HELPERS


def helper_source(names) -> str:
    """The source of the named helpers (and the series table if ``_expm1mx`` is one of them)."""
    parts = []
    if "_expm1mx" in names:  # the scalar form reads the same table (emitted with the array form)
        text = inspect.getsource(__import__(__name__, fromlist=["x"])).split("_EXPM1MX_COEFFICIENTS = ", 1)[1]
        parts.append("_EXPM1MX_COEFFICIENTS = " + text.split("\n\n\n", 1)[0])
    parts += [inspect.getsource(HELPERS[n]).rstrip("\n") for n in sorted(names)]
    return "\n\n\n".join(parts) + "\n"
