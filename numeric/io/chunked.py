"""NPZ output written frame by frame, so a long run never holds its whole trajectory in memory.

Each array is a ``.npy`` memory map in a temporary folder beside the target;
frames are written into it as they come, and at the end the files are
stored (uncompressed, ZIP64) into ``<name>.npz`` under a temporary name and
renamed into place. Memory use is one frame plus the OS page cache.
"""

from __future__ import annotations

import shutil
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from .files import atomic_path


class ChunkedNPZ:
    """Write ``t`` (S,) and per-method ``x_<m>``, ``v_<m>`` (S, N) without holding them.

    Use as a context manager; :meth:`frame` writes one recorded state.
    """

    def __init__(self, path: str | Path, t: np.ndarray, n: int, methods: list[str],
                 progress: bool | None = None, extra: list[str] = ()):
        self.path = Path(path)
        self.progress = progress
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.t = np.asarray(t, dtype=float)
        self.tmpdir = Path(tempfile.mkdtemp(prefix=f".{self.path.name}.", dir=self.path.parent))
        self.index = {int(round(i)): k for k, i in enumerate(range(len(self.t)))}
        self.arrays: dict[str, np.memmap] = {}
        for m in methods:
            for q in ("x", "v"):
                self.arrays[f"{q}_{m}"] = np.lib.format.open_memmap(
                    self.tmpdir / f"{q}_{m}.npy", mode="w+", dtype=float, shape=(len(self.t), n))
        for key in extra:  # further (S, N) arrays, e.g. aabs_<method>
            self.arrays[key] = np.lib.format.open_memmap(self.tmpdir / f"{key}.npy", mode="w+", dtype=float,
                                                         shape=(len(self.t), n))

    def frame(self, method: str, row: int, x: np.ndarray, v: np.ndarray) -> None:
        """Store frame number ``row`` (0-based) of ``method``; x, v shape (N,) or (N, 1)."""
        self.arrays[f"x_{method}"][row] = np.reshape(x, -1)
        self.arrays[f"v_{method}"][row] = np.reshape(v, -1)

    def store(self, key: str, row: int, values: np.ndarray) -> None:
        """Store frame ``row`` of a further array ``key`` (declared in ``extra``); values shape (N,)."""
        self.arrays[key][row] = np.reshape(values, -1)

    def close(self) -> None:
        from ..progress import phase

        with phase(f"writing {self.path.name}", enabled=self.progress):
            self._close()

    def _close(self) -> None:
        np.save(self.tmpdir / "t.npy", self.t)
        for arr in self.arrays.values():
            arr.flush()
        names = ["t", *self.arrays]
        self.arrays.clear()
        with atomic_path(self.path, suffix=".npz") as tmp:
            with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_STORED, allowZip64=True) as zf:
                for name in names:
                    zf.write(self.tmpdir / f"{name}.npy", arcname=f"{name}.npy")
        shutil.rmtree(self.tmpdir, ignore_errors=True)

    def abort(self) -> None:
        self.arrays.clear()
        shutil.rmtree(self.tmpdir, ignore_errors=True)

    def __enter__(self) -> "ChunkedNPZ":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()
