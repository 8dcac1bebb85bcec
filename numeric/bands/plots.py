"""The band figure: Im q in the gaps | the band diagram | the density of states, on one ω axis.

The centre panel draws each branch ω_j(q) over q ∈ [−π, π], shades the gaps, and puts the finite chain's modes
at ±q of their band (gap modes on the axis q = 0 with their own marker); the left panel the attenuation per
cell Im q(ω) (zero inside the bands); the right the density of states of each band (van Hove peaks at the band
edges, clipped to the panel). Made without pyplot (:func:`springchain.numeric.plots.figures.new_figure`).
"""

from __future__ import annotations

import numpy as np

from ..plots.figures import new_figure


def band_figure(q: np.ndarray, omega: np.ndarray, gaps: list[tuple[float, float]], title: str, *,
                finite: list | None = None, dos_omega: np.ndarray | None = None, dos: np.ndarray | None = None,
                decay_omega: np.ndarray | None = None, decay: np.ndarray | None = None):
    """The figure.

    Parameters
    ----------
    q : ndarray, shape (Q,)
    omega : ndarray, shape (Q, p)
        Branches (continuity order).
    gaps : list of (ω_low, ω_up)
    finite : list of FiniteMode, optional
    dos_omega, dos : ndarray, shapes (W,) and (W, p), optional
    decay_omega, decay : ndarray, shapes (V,) and (V,), optional
        ω and Im q (attenuation per cell).
    """
    fig, axes = new_figure(1, 3, figsize=(12, 5.5), sharey=True, gridspec_kw={"width_ratios": [1, 3, 1.2]})
    left, mid, right = axes
    order = np.argsort(q)
    for j in range(omega.shape[1]):
        mid.plot(q[order], omega[order, j], lw=1.6, label=f"branch {j}")
    for lo, hi in gaps:
        for ax in axes:
            ax.axhspan(lo, hi, color="0.85", zorder=0, lw=0)
    if finite:
        band = [(m.q, m.omega) for m in finite if m.kind == "band"]
        if band:
            bq, bw = np.array(band).T
            mid.plot(np.concatenate([bq, -bq]), np.concatenate([bw, bw]), "o", ms=3.2, mfc="none", mec="k", mew=0.7,
                     label="finite chain modes (±q)")
        lone = [m.omega for m in finite if m.kind != "band"]
        if lone:
            mid.plot(np.zeros(len(lone)), lone, "D", ms=4.5, color="C3", label="gap modes (edge/defect)")
    mid.set_xlim(-np.pi, np.pi)
    mid.set_xticks([-np.pi, -np.pi / 2, 0, np.pi / 2, np.pi], ["−π", "−π/2", "0", "π/2", "π"])
    mid.set_xlabel("q (phase per cell) [rad]")
    mid.set_title(title)
    mid.grid(alpha=0.3)
    mid.legend(fontsize=8, loc="lower right")
    left.set_ylabel("ω [rad/s]")
    if decay is not None and decay_omega is not None:
        left.plot(decay, decay_omega, color="C3", lw=1.4)
        left.set_xlim(left=0)
    left.invert_xaxis()
    left.set_xlabel("Im q per cell (in the gaps)")
    left.grid(alpha=0.3)
    if dos is not None and dos_omega is not None:
        finite_dos = np.where(np.isfinite(dos), dos, np.nan)
        cap = np.nanpercentile(finite_dos[finite_dos > 0], 97) * 1.6 if np.any(finite_dos > 0) else 1.0
        for j in range(dos.shape[1]):
            right.plot(np.minimum(finite_dos[:, j], cap), dos_omega, lw=1.2)
        right.set_xlim(0, cap)
    right.set_xlabel("density of states g(ω)")
    right.grid(alpha=0.3)
    top = float(np.nanmax(omega)) if omega.size else 1.0
    mid.set_ylim(0, top * 1.05 if top > 0 else 1.0)
    return fig


__all__ = ["band_figure"]
