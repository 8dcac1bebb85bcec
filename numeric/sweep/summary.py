"""A finished sweep's summary (per-mode statistics) and figures.

The Matsuda–Ishii low-frequency law for a chain of springs k and independent random
masses (mean m̄, variance σ²): inverse localisation length ``γ(ω) ≈ σ² ω² / (8 k m̄)``
(H. Matsuda and K. Ishii, Prog. Theor. Phys. Suppl. 45, 56 (1970)). Its constant is
checked against a transfer-matrix computation in tests/sweep/test_sweep.py.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..plots import figures as plots
from ..io.files import atomic_write_text
from ..io.strict_json import dumps
from .driver import read

QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)
#: What ``participation_ratio`` means (the sweep chapter of the guide, summary.json and the figure say the same).
PR_CONVENTION = ("normalised: 1 / (N * sum_i psi_i^4) of each mass-weighted mode psi (sum_i psi_i^2 = 1), i.e. "
                 "the participation number 1 / sum_i psi_i^4 divided by N: 1 for a mode spread evenly over all N "
                 "masses, 1/N for a mode on one mass")
GAMMA_MISSING = "γ is not computed for rings (no open-chain transfer matrix): null in summary.json"


def matsuda_ishii(omega2, k: float, mbar: float, sigma2: float) -> np.ndarray:
    """γ(ω) ≈ σ² ω² / (8 k m̄): inverse localisation length per site at low ω."""
    return sigma2 * np.asarray(omega2, dtype=float) / (8.0 * k * mbar)


def _column(table, name: str) -> np.ndarray:
    col = table.column(name).combine_chunks()
    width = len(col[0]) if len(col) else 0
    return np.asarray(col.flatten().to_numpy(zero_copy_only=False), dtype=float).reshape(len(col), width)


def binned(omega: np.ndarray, values: np.ndarray, bins: int = 40):
    """Mean of ``values`` in ω bins: (centres, means, counts), empty bins dropped."""
    omega, values = omega.ravel(), values.ravel()
    ok = np.isfinite(values) & (omega > 0)
    if not ok.any():
        return np.zeros(0), np.zeros(0), np.zeros(0, int)
    edges = np.linspace(0.0, omega[ok].max() * (1 + 1e-12), bins + 1)
    idx = np.clip(np.searchsorted(edges, omega[ok], side="right") - 1, 0, bins - 1)
    counts = np.bincount(idx, minlength=bins)
    sums = np.bincount(idx, weights=values[ok], minlength=bins)
    keep = counts > 0
    centres = 0.5 * (edges[:-1] + edges[1:])
    return centres[keep], sums[keep] / counts[keep], counts[keep]


def _stats(a: np.ndarray) -> dict:
    q = np.quantile(a, QUANTILES, axis=0)
    out = {"mean": a.mean(axis=0).tolist(), "std": a.std(axis=0, ddof=1).tolist() if a.shape[0] > 1 else
           [0.0] * a.shape[1]}
    out["quantiles"] = {f"{p:g}": q[i].tolist() for i, p in enumerate(QUANTILES)}
    return out


def figure_paths(out: Path, chain: bool) -> list[Path]:
    """The figures :func:`summarise` writes: the ω distribution, and for a chain the localisation panels."""
    out = Path(out)
    return [out / "omega-distribution.png"] + ([out / "localisation.png"] if chain else [])


def written(out: Path, chain: bool, figures: bool = True) -> tuple[dict, list[Path]] | None:
    """The summary (and, with ``figures``, the figures) already in ``out``, None when any is missing: a
    resumed sweep that computed nothing has nothing new to summarise (``summary.json`` is written last,
    after the figures)."""
    paths = figure_paths(out, chain) if figures else []
    summary = Path(out) / "summary.json"
    if not summary.is_file() or not all(p.is_file() for p in paths):
        return None
    return json.loads(summary.read_text(encoding="utf-8")), paths


def summarise(out: Path, scene: str, law: dict | None = None, figures: bool = True,
              extra: dict | None = None) -> tuple[dict, list[Path]]:
    """Write DIR/summary.json and (``figures``) the figures; return (summary, figure paths).

    Reads the ω² column (and, for chains, the participation ratio and γ) of the finished
    parts: S × N numbers each. ``extra`` entries (e.g. ``branches``) are added to the summary.
    """
    out = Path(out)
    import pyarrow.parquet as pq

    names = pq.read_schema(next((out / "sweep.parquet").glob("part-*.parquet"))).names
    chain = "participation_ratio" in names
    cols = ["sample", "omega2"] + (["participation_ratio", "inverse_localisation_length"] if chain else [])
    table = read(out, cols)
    w2 = _column(table, "omega2")
    summary = {"scene": scene, "samples": int(w2.shape[0]), "modes": int(w2.shape[1]),
               "quantiles": list(QUANTILES), "omega2": _stats(w2)}
    omega = np.sqrt(np.maximum(w2, 0.0))
    pr = None
    centres = g_mean = np.zeros(0)
    if chain:
        pr = _column(table, "participation_ratio")
        gamma = _column(table, "inverse_localisation_length")
        summary["participation_ratio"] = {"mean": pr.mean(axis=0).tolist(), "convention": PR_CONVENTION}
        summary["inverse_localisation_length"] = {"mean": gamma.mean(axis=0).tolist()}
        centres, g_mean, counts = binned(omega, gamma)
        summary["inverse_localisation_length"]["binned"] = {"omega": centres.tolist(), "mean": g_mean.tolist(),
                                                            "count": counts.tolist()}
        if not centres.size:
            summary["inverse_localisation_length"]["note"] = GAMMA_MISSING
        if law:
            summary["matsuda_ishii"] = dict(law, formula="gamma = sigma2 * omega^2 / (8 * k * mbar)")
    summary.update(extra or {})
    paths = _figures(out, scene, omega, pr, (centres, g_mean), law) if figures else []
    atomic_write_text(out / "summary.json", dumps(summary, indent=1) + "\n")  # strict: NaN (e.g. γ of a ring) as null
    return summary, paths


def _figures(out: Path, scene: str, omega: np.ndarray, pr: np.ndarray | None, gamma_binned: tuple,
             law: dict | None) -> list[Path]:
    """Draw the ω distribution and, for a chain (``pr`` of shape (S, N); ``gamma_binned`` the summary's
    (ω bin centres, mean γ), empty for rings), the localisation panels into ``out``; return their paths
    (:func:`figure_paths`)."""
    paths = figure_paths(out, pr is not None)
    fig, ax = plots.new_figure(figsize=(8, 4.5))
    ax.hist(omega.ravel(), bins=min(120, max(20, int(np.sqrt(omega.size)))), density=True, color="C0", alpha=0.8,
            histtype="stepfilled")  # one polygon, not a patch per bin: the same picture, drawn in half the time
    ax.set_xlabel("ω [rad/s]")
    ax.set_ylabel("density of ω (all modes, all samples)")
    ax.set_title(f"{scene}: distribution of ω over {omega.shape[0]} samples")
    ax.grid(alpha=0.3)
    plots.save(fig, paths[0])
    if pr is None:
        return paths
    centres, g_mean = gamma_binned
    # no γ (rings): one panel, not an empty one with a legend entry
    fig, axes = plots.new_figure(1, 2 if centres.size else 1, figsize=(11 if centres.size else 6.5, 4.5),
                                 squeeze=False)
    a1 = axes[0, 0]
    pc, pm, _ = binned(omega, pr)
    step = max(1, omega.size // 20000)
    a1.plot(omega.ravel()[::step], pr.ravel()[::step], ".", ms=1, alpha=0.3, color="0.5", label="modes")
    a1.plot(pc, pm, "-o", ms=3, color="C0", label="mean per ω bin")
    a1.set_xlabel("ω [rad/s]")
    a1.set_ylabel("participation ratio 1/(N Σψ⁴)")
    a1.set_title("Participation ratio (1 = spread over all masses, 1/N = one mass)"
                 + ("" if centres.size else f"\n{GAMMA_MISSING}"), fontsize=10)
    a1.grid(alpha=0.3)
    a1.legend(fontsize=8)
    if centres.size:
        a2 = axes[0, 1]
        a2.loglog(centres, g_mean, "o", ms=4, color="C1", label="γ: transfer matrix, mean per ω bin")
        if law:
            w = np.geomspace(max(centres[0], 1e-3), centres[-1], 100)
            a2.loglog(w, matsuda_ishii(w**2, **law), "k--",
                      label=f"Matsuda–Ishii σ²ω²/(8km̄), σ² = {law['sigma2']:.3g}")
        a2.set_xlabel("ω [rad/s]")
        a2.set_ylabel("inverse localisation length γ [1/site]")
        a2.set_title("Inverse localisation length")
        a2.grid(alpha=0.3, which="both")
        a2.legend(fontsize=8)
    plots.save(fig, paths[1])
    return paths


__all__ = ["summarise", "matsuda_ishii", "binned", "QUANTILES"]
