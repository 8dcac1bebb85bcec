"""The NPZ a simulation writes: ``t`` (S,) and per method ``x_<method>``, ``v_<method>`` (S, N)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .files import atomic_path


def save_npz(path: Path, t: np.ndarray, x: dict[str, np.ndarray], v: dict[str, np.ndarray],
             extra: dict[str, np.ndarray] | None = None) -> None:
    """NPZ with ``t`` (S,) and ``x_<method>``, ``v_<method>`` (S, N) (and ``extra`` arrays such as
    ``aabs_<method>``), written atomically."""
    arrays = {"t": t}
    for name in x:
        arrays[f"x_{name}"] = x[name]
        arrays[f"v_{name}"] = v[name]
    arrays.update(extra or {})
    with atomic_path(path, suffix=".npz") as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays)


def write_npz(path: Path, runs: dict) -> None:
    """:func:`save_npz` of runs (``numeric.run.simulate.Run`` by method name)."""
    first = next(iter(runs.values()))
    save_npz(path, first.t, {m: r.x for m, r in runs.items()}, {m: r.v for m, r in runs.items()})


__all__ = ["save_npz", "write_npz"]
