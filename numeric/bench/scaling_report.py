"""Rendering the scaling study: the Markdown summary (a string), the figure, and writing them."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..io.strict_json import jsonable  # the one definition (null for non-finite), kept importable here
from .scaling import PER_MASS_COLUMNS, SECONDS_COLUMNS, ScalingResult


def _fmt(value) -> str:
    if value is None:
        return "–"
    if isinstance(value, str):
        return value
    if isinstance(value, float) and math.isinf(value):
        return "∞"
    if isinstance(value, int):
        return str(value)
    return f"{value:.3g}"


def markdown(result: ScalingResult) -> str:
    """The scaling table (seconds; T* in time units) with the headline and notes."""
    cfg, h = result.config, result.headline
    ns = h["ns_per_mass"]
    lines = ["### Scaling: exact set-up vs Verlet step (single-threaded, minimum of repeats)", "",
             f"At N = {h['n']:,} (ns per mass and step): NumPy stencil step {_fmt(ns['step_numpy'])} "
             f"({h['numpy_source']}); fused step on (x, v, a) {_fmt(ns['step_fused'])} (48 B/mass); fused "
             f"multi-step {_fmt(ns['step_fused_advance'])} (two steps per sweep); fused one-step sweeps "
             f"{_fmt(ns['step_fused_sweep'])} (32 B/mass); memory floor, moving 32 B/mass, "
             f"{_fmt(ns['floor'])} (in-place stream {_fmt(ns['floor_stream'])}, NumPy copy "
             f"{_fmt(ns['floor_copy'])}).", "",
             f"Fused multi-step / floor = {_fmt(h['fused_over_floor'])} (ratio of minima; median of per-round "
             f"ratios {_fmt(h['fused_over_floor_paired'])}; target, on the median: ≤ 1.5: "
             f"{'met' if h['target_met'] else 'not met' if h['target_met'] is not None else 'n/a'}); one-step "
             f"sweeps / floor = {_fmt(h['fused_sweep_over_floor'])} "
             f"(median {_fmt(h['fused_sweep_over_floor_paired'])}); "
             f"single fused step / floor = {_fmt(h['fused_step_over_floor'])} "
             f"(median {_fmt(h['fused_step_over_floor_paired'])}).", "",
             f"Crossover for T = {cfg.t_end:g}, tolerance {cfg.tol:g} (Verlet phase error ω³h²T/24): "
             "T* is the horizon beyond which the exact solution is cheaper than fused Verlet.", ""]
    lines += _table(result.records, SECONDS_COLUMNS, "Seconds (random = index-dependent chain):")
    lines += _table(result.records, PER_MASS_COLUMNS, "Per mass and crossover:")
    lines.append("")
    lines += [f"- {note}" for note in result.notes]
    return "\n".join(lines) + "\n"


def _cell(record: dict, key: str) -> str:
    if key.startswith("ns:"):
        v = record.get(key[3:])
        return _fmt(None if v is None else 1e9 * v / record["n"])
    text = _fmt(record.get(key))
    if key == "crossover_dense" and record.get("exact_dense_extrapolated"):
        text += " (extrap.)"
    return text


def _table(records: list[dict], columns: dict[str, str], title: str) -> list[str]:
    lines = [title, "", "| " + " | ".join(columns.values()) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(_cell(r, key) for key in columns) + " |" for r in records]
    return lines + [""]


def figure(result: ScalingResult):
    """Seconds vs N (log–log): set-up costs, per-step costs and the memory floor."""
    from ..plots.figures import new_figure

    recs = result.records
    n = np.array([r["n"] for r in recs], dtype=float)
    fig, ax = new_figure(figsize=(9, 6))
    series = [
        ("setup_dense_svd", "exact set-up: dense SVD (modal), random chain", "C3", "o-"),
        ("setup_dense_eigh", "exact set-up: dense eigh, random chain", "C1", "s-"),
        ("setup_tridiagonal", "exact set-up: eigh_tridiagonal + vectors, random", "C5", "^-"),
        ("setup_transform", "exact set-up: transform (uniform)", "C2", "D-"),
        ("eval_transform", "exact, one output time: transform (uniform)", "C2", "d:"),
        ("step_numpy", "Verlet step: NumPy stencil (uniform)", "C0", "o-"),
        ("step_numpy_random", "Verlet step: NumPy stencil (random)", "C0", "o--"),
        ("step_fused", "Verlet step: fused (uniform)", "C4", "v-"),
        ("step_fused_random", "Verlet step: fused (random)", "C4", "v--"),
        ("step_fused_advance", "Verlet step: fused multi-step, 2 steps/sweep (uniform)", "C6", "*-"),
        ("step_fused_sweep", "Verlet step: fused multi-step, 1 step/sweep (uniform)", "C6", "*:"),
    ]
    for key, label, color, style in series:
        y = np.array([np.nan if r.get(key) is None else r[key] for r in recs], dtype=float)
        if np.all(np.isnan(y)):
            continue
        ax.plot(n, y, style, color=color, label=label, ms=4, lw=1.2)
    floor = np.array([r["floor"] for r in recs], dtype=float)
    ax.plot(n, floor, "k-", lw=2, alpha=0.5, label="memory floor: move 32 B per mass (measured)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("chain size N (masses)")
    ax.set_ylabel("seconds")
    ax.set_title("Exact-solution set-up vs one Verlet step (single-threaded)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, loc="upper left")
    return fig


def write(result: ScalingResult, out: Path, *, json_name: str = "scaling.json", md_name: str = "scaling.md",
          png_name: str = "scaling.png") -> list[Path]:
    """Write the JSON, Markdown and figure into ``out`` (atomically); returns the paths."""
    import json

    from ..plots import figures as plots
    from ..io.files import atomic_write_text

    out = Path(out)
    paths = [out / json_name, out / md_name, out / png_name]
    atomic_write_text(paths[0], json.dumps(jsonable(result.to_json()), indent=1) + "\n")
    atomic_write_text(paths[1], markdown(result))
    plots.save(figure(result), paths[2])
    return paths
