"""The Dask driver of a sweep: batches as tasks, parquet parts written as results arrive, resume.

Layout of an output folder ``DIR``::

    DIR/manifest.json                       the sweep's settings (refused if they differ on a re-run)
    DIR/sweep.parquet/part-000000.parquet   one file per finished batch (written atomically)
    DIR/summary.json, DIR/*.png             written after the last batch (numeric.sweep.summary)

Tasks are batches of realisations (``numeric.sweep.realisations.compute_batch``). The client
submits every unfinished batch, takes results with ``as_completed`` and writes each
batch's part file the moment it arrives, then releases it: nothing is collected whole
in the client. A worker that dies mid-run loses no sample - its batches are recomputed
by Dask, and a part file exists only once it is complete (temp file + rename), so a
re-run skips exactly the finished batches.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Callable

import numpy as np

from ..errors import RunRefused
from ..io.files import atomic_path, atomic_write_text
from ..progress import Reporter
from .realisations import SweepSpec, compute_batch

PARTS = "sweep.parquet"
MANIFEST = "manifest.json"
PROGRESS_EVERY = 5.0  # seconds between progress lines


def part_path(out: Path, b: int) -> Path:
    return Path(out) / PARTS / f"part-{b:06d}.parquet"


def batches(total: int, batch: int) -> list[tuple[int, int, int]]:
    """(batch index, first sample, end) of every batch."""
    return [(b, s, min(s + batch, total)) for b, s in enumerate(range(0, total, batch))]


def to_table(cols: dict):
    """A pyarrow Table of one batch: scalars as columns, 2-D arrays as list<double> columns."""
    import pyarrow as pa

    arrays, names = [], []
    for name, values in cols.items():
        values = np.asarray(values)
        if values.ndim == 2:
            rows, width = values.shape
            offsets = pa.array(np.arange(rows + 1, dtype=np.int32) * width)
            arrays.append(pa.ListArray.from_arrays(offsets, pa.array(values.reshape(-1))))
        else:
            arrays.append(pa.array(values))
        names.append(name)
    return pa.Table.from_arrays(arrays, names=names)


def write_part(out: Path, b: int, cols: dict) -> Path:
    import pyarrow.parquet as pq

    path = part_path(out, b)
    with atomic_path(path) as tmp:
        pq.write_table(to_table(cols), tmp)
    return path


def finished(out: Path, n_batches: int) -> set[int]:
    """Indices of batches whose part file exists (complete by construction: atomic rename)."""
    folder = Path(out) / PARTS
    if not folder.is_dir():
        return set()
    done = set()
    for p in folder.glob("part-*.parquet"):
        try:
            b = int(p.stem.split("-")[1])
        except (IndexError, ValueError):
            continue
        if 0 <= b < n_batches:
            done.add(b)
    return done


def check_manifest(out: Path, manifest: dict) -> bool:
    """Write the manifest, or check an existing one. Returns True when resuming."""
    path = Path(out) / MANIFEST
    if path.exists():
        try:
            old = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            raise RunRefused(f"--out {out}: {path} is unreadable; accepted: a sweep folder or a new --out") from None
        diff = [k for k in sorted(set(old) | set(manifest)) if old.get(k) != manifest.get(k)]
        if diff and not any((Path(out) / PARTS).glob("part-*.parquet")):
            diff = []  # nothing finished yet (e.g. a refused first run): start afresh
            atomic_write_text(path, json.dumps(manifest, indent=1, sort_keys=True) + "\n")
        if diff:
            k = diff[0]
            raise RunRefused(f"--out {out}: holds a sweep made with different settings ({k}: {old.get(k)!r} "
                             f"there, {manifest.get(k)!r} now); accepted: the same settings (to resume) or "
                             "another --out")
        return True
    if (Path(out) / PARTS).exists():
        raise RunRefused(f"--out {out}: has {PARTS} but no {MANIFEST}; accepted: a sweep folder or a new --out")
    atomic_write_text(path, json.dumps(manifest, indent=1, sort_keys=True) + "\n")
    return False


class Progress(Reporter):
    """Samples done of a sweep, on the one reporter (:class:`numeric.progress.Reporter`): a line
    ``sweep: done/total samples, rate, ETA`` every ``every`` seconds (only for sweeps that take that long)."""

    def __init__(self, total: int, every: float = PROGRESS_EVERY, stream=None, enabled: bool = True):
        super().__init__("sweep", total, enabled=enabled, stream=stream, quiet_seconds=every, prefix="sweep",
                         interval=every)
        self.skipped = 0

    def _text(self, done: int | None) -> str:
        elapsed = max(time.monotonic() - self.t0, 1e-9)
        rate = self.done / elapsed
        eta = (self.total - self.done) / rate if rate > 0 else float("inf")
        return (f"{self.done + self.skipped}/{self.total + self.skipped} samples, {rate:.3g} samples/s, "
                f"ETA {eta:.0f} s")

    def add(self, n: int, force: bool = False) -> None:
        """``n`` more samples done (``force``: the last call; the total is reached)."""
        self.update(self.total if force else self.done + n)


def local_cluster(workers: int):
    """An embedded LocalCluster: processes, one thread each, BLAS pinned to one thread."""
    import logging

    from dask.distributed import LocalCluster

    env = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0",
                        env=env, silence_logs=logging.CRITICAL)


def run(spec: SweepSpec, out: Path, batch: int, client=None, progress: bool = True,
        on_batch: Callable[[int], None] | None = None) -> dict:
    """Compute every unfinished batch on ``client`` (a dask Client) and write its part file.

    Returns ``{"batches", "computed", "skipped", "seconds"}``.
    """
    from dask.distributed import as_completed

    t0 = time.perf_counter()
    plan = batches(spec.total, batch)
    done = finished(out, len(plan))
    todo = [bt for bt in plan if bt[0] not in done]
    prog = Progress(sum(e - s for _, s, e in todo), enabled=progress)
    prog.skipped = spec.total - prog.total
    if todo:
        if client is None:
            raise RunRefused("sweep: batches left to compute but no Dask client")
        # the spec (a few kB: numbers and the module's source) travels inside each task rather than
        # scattered: scattered data dies with the worker that holds it, a task's argument does not
        futures = {client.submit(compute_batch, spec, s, e, pure=False): b for b, s, e in todo}
        try:
            for fut in as_completed(futures):
                b = futures.pop(fut)
                cols = fut.result()  # a refusal (e.g. a non-positive draw) re-raises here
                write_part(out, b, cols)
                prog.add(len(cols["sample"]))
                fut.release()
                if on_batch is not None:
                    on_batch(b)
        except BaseException:
            client.cancel(list(futures))  # a shared client must not keep computing a failed sweep
            raise
        prog.add(0, force=True)
    return {"batches": len(plan), "computed": len(todo), "skipped": len(plan) - len(todo),
            "seconds": time.perf_counter() - t0}


def seconds_per_sample(spec: SweepSpec) -> float:
    """Seconds one sample takes in this process: sample 0 computed twice (the first pays the imports and
    the module's compilation), the second timed; nothing is written."""
    compute_batch(spec, 0, 1)
    t0 = time.perf_counter()
    compute_batch(spec, 0, 1)
    return time.perf_counter() - t0


def run_in_process(spec: SweepSpec, out: Path, batch: int, progress: bool = True,
                   max_batches: int | None = None) -> dict:
    """Compute unfinished batches here, on Dask's synchronous scheduler (no worker process, no thread),
    writing each part file as it is done; at most ``max_batches`` of them (None: all).

    Returns ``{"batches", "computed", "skipped", "seconds"}`` (``skipped``: finished before this call).
    """
    import dask

    t0 = time.perf_counter()
    plan = batches(spec.total, batch)
    done = finished(out, len(plan))
    todo = [bt for bt in plan if bt[0] not in done][:max_batches]
    prog = Progress(sum(e - s for _, s, e in todo), enabled=progress)
    prog.skipped = spec.total - prog.total
    for b, s, e in todo:
        (cols,) = dask.compute(dask.delayed(compute_batch, pure=False)(spec, s, e), scheduler="synchronous")
        write_part(out, b, cols)
        prog.add(len(cols["sample"]))
    if todo:
        prog.add(0, force=True)
    return {"batches": len(plan), "computed": len(todo), "skipped": len(done), "seconds": time.perf_counter() - t0}


def read(out: Path, columns: list[str] | None = None):
    """The finished rows as a pyarrow Table, in sample order (reads only ``columns``)."""
    import pyarrow.parquet as pq

    parts = sorted((Path(out) / PARTS).glob("part-*.parquet"))
    if not parts:
        raise RunRefused(f"--out {out}: no finished batches in {PARTS}")
    import pyarrow as pa

    return pa.concat_tables([pq.read_table(p, columns=columns) for p in parts])


__all__ = ["run", "run_in_process", "seconds_per_sample", "read", "batches", "finished", "check_manifest", "write_part", "local_cluster", "part_path",
           "Progress", "PARTS", "MANIFEST"]
