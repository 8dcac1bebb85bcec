"""``springchain.sweep``: ensembles and parameter studies on Dask (the API behind ``springchain sweep``)."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from ._defaults import DEFAULT_SWEEP_OUT
from .derive.scene import Scene
from .numeric.errors import RunRefused

#: A sweep whose remaining samples would take less than this in-process (predicted from two probe
#: samples) runs in-process: starting worker processes costs seconds of its own.
IN_PROCESS_SECONDS = 10.0
RESERVED = ("sample", "omega2", "participation_ratio", "inverse_localisation_length")


@dataclass(frozen=True)
class SweepResult:
    """A finished sweep.

    Attributes
    ----------
    out : Path
        The output folder (``sweep.parquet/``, ``manifest.json``, ``summary.json``, figures).
    rows : int
        Number of samples (rows of ``sweep.parquet``).
    summary : dict
        What ``DIR/summary.json`` holds.
    figures : tuple of Path
        Paths of the figures (empty for ``figures=False``).
    run : dict
        Batches computed and skipped (resumed), seconds, the scheduler; ``summary``: ``"written"``, or
        ``"kept"`` when nothing was computed and the summary and figures on disk were returned.
    """

    out: Path
    rows: int
    summary: dict = field(repr=False)
    figures: tuple[Path, ...]
    run: dict
    manifest: dict = field(repr=False)

    @property
    def parquet(self) -> Path:
        return self.out / "sweep.parquet"

    def table(self, columns: list[str] | None = None):
        """The rows as a pyarrow Table (sample order)."""
        from .numeric.sweep.driver import read

        return read(self.out, columns)

    def to_pandas(self, columns: list[str] | None = None):
        """The rows as a ``pandas.DataFrame`` (sample order; list columns hold one array per sample).
        Needs ``pip install "springchain[data]"``."""
        from ._data import sweep_pandas

        return sweep_pandas(self, columns)

    def _repr_html_(self) -> str:  # the summary table
        from ._display import sweep_html

        return sweep_html(self)

    def to_json(self) -> dict:
        """What ``springchain sweep --json`` prints."""
        return {"out": str(self.out), "parquet": str(self.parquet), "rows": self.rows,
                "summary": str(self.out / "summary.json"), "figures": [str(p) for p in self.figures],
                "batches": self.run["batches"], "computed_batches": self.run["computed"],
                "skipped_batches": self.run["skipped"], "seconds": self.run["seconds"],
                "scheduler": self.run.get("scheduler"),
                "settings": self.manifest}


def _whole(value, flag: str, minimum: int = 1) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise RunRefused(f"{flag} {value!r}: accepted: a whole number >= {minimum}")
    return int(value)


def _pairs(items, flag: str, names) -> list[tuple[str, object]]:
    from .numeric.sweep.distributions import Dist, parse, parse_assignment

    out = []
    if isinstance(items, dict):
        items = list(items.items())
    for item in items or ():
        if isinstance(item, str):
            out.append(parse_assignment(item, flag, names))
        else:
            name, dist = item
            if name not in names:
                raise RunRefused(f"{flag} {name}: {name!r} is not accepted here; accepted: {', '.join(sorted(names))}")
            out.append((name, dist if isinstance(dist, Dist) else parse(dist, f"{flag} {name}")))
    seen = set()
    for name, _ in out:
        if name in seen:
            raise RunRefused(f"{flag} {name}: given twice; accepted: each name once")
        seen.add(name)
    return out


def _refuse_unguarded(workers: int, predicted: float) -> None:
    """Refuse, at once, to start worker processes from a script's top level outside the guard."""
    from ._guard import GUARD, unguarded_call

    where = unguarded_call()
    if where is not None:
        script, line = where
        raise RunRefused(f"sweep: {script}, line {line}: starting {workers} worker processes from the top level of a "
                         f"script without `{GUARD}` would run the whole script again in each of them; accepted: "
                         f"the script's work under `{GUARD}`, or workers=1 (in-process, about {predicted:.0f} s here)",
                         quantity="workers")


def _law(scene: Scene, system, disorder, vary) -> dict | None:
    """Matsuda–Ishii parameters when they apply: uniform chain, mass disorder only, nothing varied."""
    import numpy as np

    if vary or [w for w, _ in disorder] != ["mass"] or not scene.chain.uniform or not scene.linear:
        return None
    d = disorder[0][1]
    m, k = float(system.masses[0]), float(np.median(system.stiffness))
    return {"k": k, "mbar": m * d.mean(), "sigma2": m * m * d.variance()}


def _branches(spec) -> dict | None:
    """Mode branches of a one-parameter grid sweep, followed by MAC (:mod:`numeric.sensitivity.tracking`)."""
    from .numeric.sweep import realisations
    from .numeric.sensitivity.tracking import grid_branches

    return grid_branches(spec, realisations)


def _branches_figure(branches: dict, scene: str, out: Path) -> Path:
    from .numeric.plots import figures as plots
    from .numeric.sensitivity.tracking import branches_figure

    path = Path(out) / "branches.png"
    plots.save(branches_figure(branches, scene), path)
    return path


def sweep(scene: str | Path | Scene, vary=(), disorder=(), samples: int = 100, *, seed: int = 0,
          batch: int | None = None, workers: int | None = None, scheduler: str | None = None,
          out: str | Path | None = None, figures: bool = True, progress: bool = True, client=None) -> SweepResult:
    """A parameter study or disorder ensemble, computed on Dask and written as parquet.

    Parameters
    ----------
    scene : str, Path or Scene
        As for :func:`springchain.load`.
    vary : list of "NAME=DIST" (or (name, DIST) pairs, or a dict)
        One scene parameter per entry, drawn per sample; ``grid(a, b, n)`` entries vary
        deterministically and several grids form their product (``samples`` realisations
        per grid point).
    disorder : list of "mass=DIST" / "k=DIST"
        ``[chain]`` scenes: every mass (spring) multiplied by its own draw, per sample.
    samples : int
        Realisations (per grid point).
    seed : int
        Sample ``s`` draws from ``SeedSequence(seed, spawn_key=(s,))``: the same rows
        whatever the workers, batch size or scheduler.
    batch : int, optional
        Realisations per Dask task (default: about 64 batches in all).
    workers : int, optional
        Processes of the embedded LocalCluster (default: the cores). ``workers=1`` runs in this
        process (Dask's synchronous scheduler), and so does a small study: one predicted (from two
        probe samples) to take less than ``IN_PROCESS_SECONDS`` here. A script that
        starts worker processes needs ``if __name__ == "__main__":`` around its work (the workers
        import the script again); without it the sweep is refused at once, in one line.
    scheduler : str, optional
        Address of a running ``dask scheduler`` (``tcp://HOST:PORT``) instead.
    out : str or Path
        Output folder (default ``springchain-sweep``). Re-running into it resumes; when every batch is
        already there, the summary and figures on disk are returned, not drawn again.
    figures : bool
        Draw the figures (default); False writes the parquet parts and ``summary.json`` only.
    progress : bool
        A line on stderr every few seconds of a long sweep.
    client : dask.distributed.Client, optional
        Use this client (and its cluster) instead of ``workers``/``scheduler``.

    Returns
    -------
    SweepResult
    """
    from ._modules import system_of as _system
    from ._scenes import load
    from .numeric.sweep import driver as sweep_driver, summary as sweep_summary
    from .numeric.sweep.realisations import SweepSpec

    sc = load(scene)
    samples = _whole(samples, "--samples")
    seed = _whole(seed, "--seed", 0)
    if workers is not None and scheduler is not None:
        raise RunRefused(f"--workers {workers} and --scheduler {scheduler}: accepted: one of them")
    if workers is not None:
        workers = _whole(workers, "--workers")
    if scheduler is not None and (not isinstance(scheduler, str) or "://" not in scheduler):
        raise RunRefused(f"--scheduler {scheduler!r}: accepted: an address such as tcp://HOST:PORT "
                         "(printed by `dask scheduler`)")
    vary = _pairs(vary, "--vary", sc.parameter_names)
    disorder = _pairs(disorder, "--disorder", ("mass", "k"))
    for name, _ in vary:
        if name in RESERVED:
            raise RunRefused(f"--vary {name}: the name clashes with a result column; accepted: other parameters")
    if disorder and sc.chain is None:
        raise RunRefused(f"--disorder {disorder[0][0]}: {sc.name!r} is not a [chain] scene; accepted: --disorder "
                         "on [chain] scenes (use --vary for the others)")
    for what, dist in disorder:
        if dist.is_grid:
            raise RunRefused(f"--disorder {what}={dist.text}: accepted: uniform, normal or lognormal (a grid "
                             "is not a disorder)")
    system, _ = _system(sc)
    source = system.source_text
    spec = SweepSpec(sc.name, source, tuple(sorted(sc.parameters.items())), tuple(vary), tuple(disorder),
                     samples, seed)
    total = spec.total
    batch = _whole(batch, "--batch") if batch is not None else max(1, min(1000, math.ceil(total / 64)))
    out = Path(out if out is not None else DEFAULT_SWEEP_OUT)
    manifest = {"format": 1, "scene": sc.name, "scene_sha256": sc.sha256,
                "vary": [f"{n}={d.text}" for n, d in vary], "disorder": [f"{w}={d.text}" for w, d in disorder],
                "samples": samples, "grid_points": spec.grid_points, "total": total, "seed": seed, "batch": batch}
    out.mkdir(parents=True, exist_ok=True)
    sweep_driver.check_manifest(out, manifest)

    own = []
    n_batches = len(sweep_driver.batches(total, batch))
    left = n_batches - len(sweep_driver.finished(out, n_batches))
    runs = []
    try:
        if client is None and scheduler is None and left:
            # here, on Dask's synchronous scheduler: workers=1, or a study that two probe samples (the
            # first pays the imports) predict to be cheaper than starting worker processes
            done = sweep_driver.finished(out, n_batches)
            todo = sum(e - s for b, s, e in sweep_driver.batches(total, batch) if b not in done)
            predicted = 0.0 if workers == 1 else sweep_driver.seconds_per_sample(spec) * todo
            if predicted < IN_PROCESS_SECONDS:
                runs.append(sweep_driver.run_in_process(spec, out, batch, progress))
                left = 0
        if left and client is None:
            from dask.distributed import Client

            if scheduler is not None:
                try:
                    client = Client(scheduler, timeout="10s")
                except (OSError, TimeoutError) as exc:
                    raise RunRefused(f"--scheduler {scheduler}: cannot connect ({exc}); accepted: the address "
                                     "of a running `dask scheduler`, e.g. tcp://127.0.0.1:8786") from None
                own.append(client)
            else:
                _refuse_unguarded(workers or os.cpu_count() or 1, predicted)
                cluster = sweep_driver.local_cluster(workers or os.cpu_count() or 1)
                own.append(cluster)
                client = Client(cluster)
                own.append(client)
        runs.append(sweep_driver.run(spec, out, batch, client, progress=progress))
    finally:
        for obj in reversed(own):
            obj.close()
    run = {"batches": n_batches, "computed": sum(r["computed"] for r in runs), "skipped": runs[0]["skipped"],
           "seconds": sum(r["seconds"] for r in runs),
           "scheduler": ("none: every batch was already done" if not any(r["computed"] for r in runs) else
                         "an existing client" if client is not None and not own else
                         f"Dask scheduler {scheduler}" if scheduler is not None else
                         f"LocalCluster, {workers or os.cpu_count() or 1} worker processes" if own else
                         "in-process (Dask's synchronous scheduler)")}
    done = None if run["computed"] else sweep_summary.written(out, sc.chain is not None, figures)
    branches = None if done else _branches(spec)
    summary, drawn = done or sweep_summary.summarise(out, sc.name,
                                                    _law(sc, system, disorder, vary) if sc.chain else None, figures,
                                                    {"branches": branches} if branches else None)
    if figures and summary.get("branches"):  # a resumed sweep keeps its branches figure (drawn if deleted)
        path = Path(out) / "branches.png"
        drawn = list(drawn) + [path if done and path.is_file() else _branches_figure(summary["branches"], sc.name, out)]
    run["summary"] = "kept" if done else "written"
    return SweepResult(out, summary["samples"], summary, tuple(drawn), run, manifest)


__all__ = ["sweep", "SweepResult", "DEFAULT_SWEEP_OUT"]
