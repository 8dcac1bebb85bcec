"""Strict JSON for machines: what ``--json`` prints and the ``.json`` files springchain writes.

``json.dumps`` writes ``NaN`` and ``Infinity`` by default, which are not JSON (RFC 8259: most
parsers outside Python refuse them). Here a non-finite float becomes ``null`` and anything else
that is not plain data (NumPy scalars and arrays, enums) its plain value; ``allow_nan=False`` then
guarantees the output is JSON.
"""

from __future__ import annotations

import enum
import json
import math

import numpy as np


def jsonable(obj):
    """``obj`` with NumPy scalars/arrays as Python numbers/lists, enums as their values and
    non-finite floats as None (null)."""
    if isinstance(obj, dict):
        return {(k.value if isinstance(k, enum.Enum) else k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, enum.Enum):
        return jsonable(obj.value)
    if isinstance(obj, (np.floating, np.integer, np.bool_)):
        return jsonable(obj.item())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def dumps(obj, **kwargs) -> str:
    """``json.dumps`` of :func:`jsonable` ``(obj)``, refusing anything that would not be JSON."""
    return json.dumps(jsonable(obj), allow_nan=False, **kwargs)


__all__ = ["jsonable", "dumps"]
