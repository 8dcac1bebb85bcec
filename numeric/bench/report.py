"""Rendering a benchmark result: the Markdown table (a string), the figures, and writing them."""

from __future__ import annotations

import math

import numpy as np

from .records import BenchResult


# -- outputs -----------------------------------------------------------------------------------------------
def _fmt(v, spec=".3g"):
    return "—" if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, spec)


def markdown_table(result: BenchResult, targets: bool = False) -> str:
    """The records as a Markdown table, then the cheapest run per accuracy.

    ``targets=True`` adds the project's own acceptance targets (the speed-up required of the best
    method and whether it was met), which are for springchain's benchmarks, not for its users.
    """
    lines = [f"# springchain bench: {result.scene}, t = 0 … {result.t_end:g}", "",
             f"Reference: {result.reference}.", ""]
    if result.derive_seconds is not None:
        lines += [f"Derive + codegen (once, not part of any run): {result.derive_seconds:.3f} s.", ""]
    lines += ["| method | setting | error | predicted error | energy error | final error (energy norm) "
              "| seconds | force evals |", "|---|---|---|---|---|---|---|---|"]
    for r in result.records:
        lines.append(f"| {r.method} | {r.setting} | {_fmt(r.error, '.2e')} | {_fmt(r.predicted_error, '.2e')} | "
                     f"{_fmt(r.energy_error, '.2e')} | {_fmt(r.final_energy_norm_error, '.2e')} | "
                     f"{_fmt(r.seconds, '.3e')} | {r.force_evals} |")
    tg = result.targets()
    lines += ["", "## Targets" if targets else "## Cheapest run per accuracy", ""]
    met = lambda row: [f"{'yes' if row['met'] else 'NO'}"] if targets else []  # noqa: E731
    if result.exact:
        lines += ["Fastest run reaching each accuracy against the fastest DOP853 run reaching it"
                  + (f" (required: ≥ {tg['required']:g}×)." if targets else "."), ""]
        head = ["accuracy", "fastest", "seconds", "DOP853", "seconds", "speed-up", "vs compiled DOP853"] \
            + (["met"] if targets else [])
        lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        for row in tg["rows"]:
            cells = [f"{row['accuracy']:.0e}", f"{row['fastest'] or '—'} {row['fastest_setting'] or ''}".strip(),
                     _fmt(row['fastest_seconds'], '.3e'), row['dop853_setting'] or 'not reached',
                     _fmt(row['dop853_seconds'], '.3e'), _fmt(row['speedup'], '.0f'),
                     _fmt(row['compiled_ratio'], '.2f')] + met(row)
            lines.append("| " + " | ".join(cells) + " |")
    else:
        lines += ["Best fixed-step integrator against DOP853 at equal accuracy, in force evaluations and in seconds"
                  + (f" (required: ≥ {tg['required']:g}× in both)." if targets else "."), ""]
        head = ["accuracy", "best (evals)", "evals", "DOP853 evals", "ratio", "best (seconds)", "seconds",
                "DOP853 seconds", "ratio", "compiled DOP853 seconds", "ratio"] + (["met"] if targets else [])
        lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        for row in tg["rows"]:
            cells = [f"{row['accuracy']:.0e}", row['best_evals'] or '—', _fmt(row['best_force_evals']),
                     _fmt(row['dop853_force_evals']), _fmt(row['evals_ratio'], '.2f'), row['best_seconds_run'] or '—',
                     _fmt(row['best_seconds'], '.3e'), _fmt(row['dop853_seconds'], '.3e'),
                     _fmt(row['seconds_ratio'], '.2f'), _fmt(row['dop853_compiled_seconds'], '.3e'),
                     _fmt(row['compiled_ratio'], '.2f')] + met(row)
            lines.append("| " + " | ".join(cells) + " |")
    if result.notes:
        lines += ["", "## Notes", ""] + [f"- {n}" for n in result.notes]
    return "\n".join(lines) + "\n"


def _method_order(records) -> list[str]:
    seen = []
    for r in records:
        if r.method not in seen:
            seen.append(r.method)
    return seen


def work_precision_figure(result: BenchResult):
    """Error against seconds and against force evaluations, log–log, one line per method."""
    import matplotlib

    from ..plots.figures import new_figure

    fig, axes = new_figure(1, 2, figsize=(13, 5.5))
    floor = 1e-17
    markers = "os^vD<>ph*Xd"
    colors = matplotlib.colormaps["tab20"].colors
    for j, name in enumerate(_method_order(result.records)):
        # connected in the order of the setting (coarse to fine), so timing noise shows as noise
        rs = sorted((r for r in result.records if r.method == name), key=lambda r: -r.error)
        err = np.array([max(r.error, floor) for r in rs])
        style = dict(marker=markers[j % len(markers)], ms=5, lw=1.2, label=name, color=colors[(2 * j) % 20])
        axes[0].loglog([r.seconds for r in rs], err, **style)
        ev = [(r.force_evals, e) for r, e in zip(rs, err) if r.force_evals > 0]
        if ev:
            axes[1].loglog([a for a, _ in ev], [b for _, b in ev], **style)
    axes[0].set_xlabel("wall-clock seconds per run (min of repeats, single-threaded BLAS)")
    axes[1].set_xlabel("force evaluations per run")
    for ax in axes:
        ax.set_ylabel("max |x − x_ref| over all recorded times [m]")
        ax.grid(alpha=0.3, which="both")
    axes[0].set_title(f"{result.scene}: error vs time (t = 0 … {result.t_end:g})")
    axes[1].set_title("error vs force evaluations (exact methods have none)")
    axes[0].legend(fontsize=8, ncol=2)
    axes[1].legend(fontsize=8, ncol=2)
    return fig


def horizon_figure(result: BenchResult):
    """Error and energy error against the horizon: measured (markers) and model (dashed)."""
    import matplotlib

    from ..plots.figures import new_figure

    fig, axes = new_figure(1, 2, figsize=(13, 5.5))
    colors = matplotlib.rcParams["axes.prop_cycle"].by_key()["color"]
    for j, c in enumerate(result.horizons):
        col = colors[j % len(colors)]
        axes[0].loglog(c.measured_t, np.maximum(c.measured_error, 1e-17), "o-", color=col,
                       label=f"{c.method} {c.setting} (measured)")
        if c.model_t.size:
            axes[0].loglog(c.model_t, np.maximum(c.model_error, 1e-17), "--", color=col, lw=1,
                           label=f"{c.method} ({c.model_label})")
        axes[1].loglog(c.measured_t, np.maximum(c.measured_energy, 1e-17), "o-", color=col, label=c.method)
    axes[0].set_xlabel("horizon T [s]")
    axes[0].set_ylabel("max |x − x_exact| over t ≤ T [m]")
    axes[0].set_title("Position error vs horizon (step methods: equal force evaluations per unit time)")
    axes[1].set_xlabel("horizon T [s]")
    axes[1].set_ylabel("max |E(t) − E(0)| / |E(0)| over t ≤ T")
    axes[1].set_title("Energy error vs horizon: bounded for symplectic methods")
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7, ncol=1)
    return fig


def write_outputs(result: BenchResult, out) -> list:
    """Write ``bench-<scene>.md``, ``.json`` and the figures into ``out``; returns the paths."""
    from ..io.strict_json import dumps
    from pathlib import Path

    from ..plots import figures as plots
    from ..io.files import atomic_write_text

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    base = f"bench-{result.scene}"
    paths = [out / f"{base}.md", out / f"{base}.json", out / f"{base}-work-precision.png"]
    atomic_write_text(paths[0], markdown_table(result))
    atomic_write_text(paths[1], dumps(result.as_json(), indent=1) + "\n")
    plots.save(work_precision_figure(result), paths[2])
    if result.horizons:
        paths.append(out / f"{base}-horizon.png")
        plots.save(horizon_figure(result), paths[-1])
    return paths

