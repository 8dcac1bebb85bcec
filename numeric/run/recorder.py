"""Where a run's frames go: :class:`MemoryRecorder` keeps them in arrays, :class:`StreamRecorder`
writes them into a chunked NPZ (bounded memory for long ``[chain]`` runs).

Methods hand over blocks of consecutive frames (``frames(start, x, v)``, x and v of shape (k, N)),
so an exact solution evaluated on many times at once, or a step driver that kept its frames, pays
one call, while a streamed step run passes one frame at a time.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np


class Recorder(Protocol):
    """Receives a run's recorded frames in order."""

    def frames(self, start: int, x: np.ndarray, v: np.ndarray) -> None:
        """Frames ``start … start + k − 1``; x, v : ndarray, shape (k, N) (copied or written out
        before returning)."""


class MemoryRecorder:
    """Keeps every frame: ``x``, ``v`` of shape (S, N)."""

    #: A method may hand over all its frames at the end (they are kept anyway).
    bulk = True

    def __init__(self, frames: int, n: int):
        self.x = np.empty((frames, n))
        self.v = np.empty((frames, n))

    def frames(self, start: int, x: np.ndarray, v: np.ndarray) -> None:
        stop = start + x.shape[0]
        self.x[start:stop] = x
        self.v[start:stop] = v


class StreamRecorder:
    """Writes one method's frames into a :class:`~numeric.io.chunked.ChunkedNPZ` (with the absolute
    motion of a scene with ``[ground]``); keeps per frame only the energy, the kinetic energy and,
    at the rows in ``keep``, a profile snapshot.

    Attributes
    ----------
    energy, kinetic : ndarray, shape (S,)
    snapshots : dict of float to ndarray, shape (N,)
    """

    #: Frames are written out as they come (a method must not keep them all).
    bulk = False

    def __init__(self, writer, system, name: str, t: np.ndarray, keep: set[int]):
        self.writer, self.system, self.name, self.t, self.keep = writer, system, name, t, keep
        self.energy = np.empty(t.shape[0])
        self.kinetic = np.empty(t.shape[0])
        self.snapshots: dict[float, np.ndarray] = {}

    def frames(self, start: int, x: np.ndarray, v: np.ndarray) -> None:
        from ..exact.absolute import absolute_motion

        for r in range(x.shape[0]):
            row = start + r
            x1, v1 = x[r][:, None], v[r][:, None]
            self.writer.frame(self.name, row, x1, v1)
            for key, arr in absolute_motion(self.system, self.t[row:row + 1], x1.T, v1.T).items():
                self.writer.store(f"{key}_{self.name}", row, arr[0])
            self.energy[row] = float(self.system.energy(x1, v1)[0])
            self.kinetic[row] = float(self.system.kinetic_energy(v[r]))  # one dot product
            if row in self.keep:
                self.snapshots[float(self.t[row])] = np.array(x1[:, 0])


__all__ = ["Recorder", "MemoryRecorder", "StreamRecorder"]
