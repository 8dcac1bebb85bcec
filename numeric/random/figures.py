"""Log–log PSD figures in the conventions of random vibration (one-sided PSD per Hz, RMS in the legend)."""

from __future__ import annotations

import numpy as np

from ..plots.figures import new_figure


def psd_figure(f: np.ndarray, input_psd: np.ndarray, input_label: str, curves: list[tuple[str, np.ndarray, float]],
               unit: str, title: str):
    """Input PSD (top) and response PSDs (bottom), log–log against frequency [Hz].

    Parameters
    ----------
    f : ndarray, shape (W,)
        Frequencies [Hz].
    input_psd : ndarray, shape (W,)
        In the unit of ``input_label``.
    curves : list of (label, psd (W,), rms)
        Response PSDs in ``unit``²/Hz and their RMS in ``unit``.
    """
    fig, (ax, axr) = new_figure(2, 1, figsize=(9, 7), sharex=True)
    on = input_psd > 0
    ax.loglog(f[on], input_psd[on], color="k", lw=1.4, label="input")
    ax.set_ylabel(input_label)
    ax.set_title(title)
    for k, (label, psd, rms) in enumerate(curves):
        ok = psd > 0
        axr.loglog(f[ok], psd[ok], lw=1.2, color=f"C{k % 10}", label=f"{label}: RMS {rms:.4g} {unit}")
    axr.set_ylabel(f"response PSD [{unit}²/Hz]" if "/" not in unit else f"response PSD [({unit})²/Hz]")
    axr.set_xlabel("frequency f [Hz]")
    for a in (ax, axr):
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=8, loc="best")
    return fig


__all__ = ["psd_figure"]
