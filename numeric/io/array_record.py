"""Frozen records of arrays: ``@array_record`` is ``@dataclass(frozen=True)`` with every field
annotated ``np.ndarray`` kept out of the repr (a repr that prints long arrays is noise).

The one place that says so: a record class writes ``omega: np.ndarray`` rather than
``omega: np.ndarray = field(repr=False)`` on every array field.
"""

from __future__ import annotations

import dataclasses

import numpy as np

#: The annotations (as written, under ``from __future__ import annotations``) that mark an array field.
_ARRAY_ANNOTATIONS = frozenset({"np.ndarray", "numpy.ndarray", "ndarray"})


def _is_array(annotation) -> bool:
    return annotation is np.ndarray or (isinstance(annotation, str) and annotation.strip() in _ARRAY_ANNOTATIONS)


def array_record(cls: type) -> type:
    """``@dataclass(frozen=True)`` whose ``np.ndarray`` fields have ``repr=False``.

    A field with an explicit ``field(...)`` keeps its own settings; an array field with a plain
    default keeps that default.
    """
    for name, annotation in cls.__dict__.get("__annotations__", {}).items():
        if not _is_array(annotation):
            continue
        default = cls.__dict__.get(name, dataclasses.MISSING)
        if isinstance(default, dataclasses.Field):
            continue
        setattr(cls, name, dataclasses.field(default=default, repr=False))
    return dataclasses.dataclass(frozen=True)(cls)
