"""The model-updating figure: frequency errors before and after, and the MAC of the pairs."""

from __future__ import annotations

import numpy as np

from ..plots import figures as plots


def update_figure(title: str, labels: list[str], before: np.ndarray, after: np.ndarray,
                  mac_before: np.ndarray | None, mac_after: np.ndarray | None):
    """Relative frequency errors (ω_model/ω̃ − 1, %) before and after, and the paired MAC.

    Parameters
    ----------
    title : str
    labels : list of str
        One per measured mode.
    before, after : ndarray, shape (R,)
        Relative frequency errors.
    mac_before, mac_after : ndarray, shape (R,) or None
        MAC of each pair (NaN where no shape was measured).
    """
    panels = 2 if mac_after is not None and np.any(np.isfinite(mac_after)) else 1
    fig, axes = plots.new_figure(1, panels, figsize=(6 + 4 * (panels - 1), 4.5), squeeze=False)
    x = np.arange(len(labels))
    ax = axes[0, 0]
    ax.bar(x - 0.2, 100 * before, 0.4, label="before", color="C1")
    ax.bar(x + 0.2, 100 * after, 0.4, label="after", color="C0")
    ax.axhline(0.0, color="0.3", lw=0.8)
    ax.set_xticks(x, labels)
    ax.set_ylabel("ω model / ω measured − 1 [%]")
    ax.set_xlabel("paired model mode")
    ax.set_title("Frequency errors")
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=8)
    if panels == 2:
        ax = axes[0, 1]
        ax.plot(x, mac_before, "o--", color="C1", label="before")
        ax.plot(x, mac_after, "s-", color="C0", label="after")
        ax.set_xticks(x, labels)
        ax.set_ylim(min(0.9, float(np.nanmin(np.concatenate([mac_before, mac_after]))) - 0.02), 1.005)
        ax.set_ylabel("MAC of the pair")
        ax.set_xlabel("paired model mode")
        ax.set_title("Mode shape correlation")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(title)
    return fig


__all__ = ["update_figure"]
