"""Figures of the structural-dynamics outputs: response spectra.

Each function takes arrays and returns a matplotlib Figure (made without pyplot); the caller saves it.
"""

from __future__ import annotations

import numpy as np

from .figures import new_figure


def response_spectrum(periods: np.ndarray, zeta: np.ndarray, sd: np.ndarray, psv: np.ndarray, psa: np.ndarray,
                      title: str, pga: float | None = None, note: str | None = None):
    """SD, PSV and PSA against the period, one curve per damping ratio, the points joined in
    ascending period (whatever order they come in); ``note`` (the SD convention) under the title.

    periods : ndarray, shape (P,); zeta : ndarray, shape (Z,); sd, psv, psa : ndarray, shape (Z, P)
    """
    order = np.argsort(periods, kind="stable")
    periods = np.asarray(periods)[order]
    sd, psv, psa = (np.asarray(d)[:, order] for d in (sd, psv, psa))
    marker = "o" if periods.shape[0] <= 12 else None  # a few points: show them, not only the lines
    fig, axes = new_figure(1, 3, figsize=(13, 4.4))
    for ax, data, label in zip(axes, (sd, psv, psa), ("SD: spectral displacement [m]",
                                                        "PSV = ω·SD: pseudo-velocity [m/s]",
                                                        "PSA = ω²·SD: pseudo-acceleration [m/s²]")):
        for z, row in zip(zeta, data):
            ax.plot(periods, row, lw=1.4, marker=marker, ms=3, label=f"ζ = {z:g}")
        ax.set_xscale("log")
        ax.set_xlabel("natural period T [s]")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    if pga is not None:
        axes[2].axhline(pga, color="0.4", ls=":", lw=1, label=f"PGA = {pga:.3g} m/s²")
        axes[2].legend(fontsize=8)
    fig.suptitle(title if not note else f"{title}\n{note}", fontsize=11)
    return fig


__all__ = ["response_spectrum"]
