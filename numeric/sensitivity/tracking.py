"""Mode branches along a one-parameter grid, followed by shape (MAC) instead of by the order of ω².

Sorting ω² at each grid value labels the modes by rank: where two frequencies cross, rank j jumps
from one physical mode to the other. Here mode j at grid value g+1 continues the branch whose shape
at g it resembles most: the pairing of the two mode sets that maximises the summed MAC
(:func:`.mac.pair`). Two outcomes near a close approach of two ω²:

* a **crossing** — the branches exchange their rank (the pairing is not the identity) while each keeps
  its shape (MAC of the pairs near 1);
* a **veering** — the ranks are kept but the shapes change fast: the MAC between neighbouring grid
  values of one branch drops below :data:`VEERING_MAC` (the two modes exchange their shapes while
  their frequencies repel).
"""

from __future__ import annotations

import numpy as np

from .mac import mac_matrix, pair

#: A branch whose shape correlates less than this with itself at the neighbouring grid value is veering.
VEERING_MAC = 0.9


def track(omega2: np.ndarray, shapes: list[np.ndarray]) -> dict:
    """Follow the modes along a grid.

    Parameters
    ----------
    omega2 : ndarray, shape (G, N)
        ω² ascending at each of G grid values.
    shapes : list of ndarray, each shape (N, N)
        Shapes (columns, ascending ω²) at each grid value (any normalisation: the MAC ignores scale).

    Returns
    -------
    dict
        ``branch`` (G, N): the branch of each ascending mode (branches numbered by rank at the first
        grid value); ``omega2`` (G, N): ω² of each branch; ``mac`` (G − 1, N): MAC of each branch with
        itself at the next grid value; ``crossings`` and ``veerings``: lists of
        ``{"between": [g, g + 1], "branches": [a, b]}`` (veerings also ``"mac"``).
    """
    omega2 = np.asarray(omega2, dtype=float)
    G, N = omega2.shape
    branch = np.zeros((G, N), dtype=np.intp)
    branch[0] = np.arange(N)
    mac_next = np.ones((max(G - 1, 0), N))
    crossings, veerings = [], []
    for g in range(G - 1):
        m = mac_matrix(shapes[g], shapes[g + 1])
        links = pair(m)  # (rank at g, rank at g + 1, MAC)
        nxt = np.empty(N, dtype=np.intp)
        for i, j, v in links:
            nxt[j] = branch[g, i]
            mac_next[g, branch[g, i]] = v
        branch[g + 1] = nxt
        moved = [(i, j) for i, j, _ in links if i != j]
        seen = set()
        for i, j in moved:  # ranks exchanged: a crossing of the branches at those ranks
            key = tuple(sorted((int(branch[g, i]), int(branch[g, j]))))
            if key[0] != key[1] and key not in seen:
                seen.add(key)
                crossings.append({"between": [g, g + 1], "branches": list(key)})
        low = [b for b in range(N) if mac_next[g, b] < VEERING_MAC]
        for a in low:  # the branch it exchanges its shape with: the neighbour in ω² that is veering too
            rank = int(np.flatnonzero(branch[g] == a)[0])
            partner = [int(branch[g, r]) for r in (rank - 1, rank + 1) if 0 <= r < N and branch[g, r] in low]
            for b in partner:
                key = sorted((a, b))
                rec = {"between": [g, g + 1], "branches": key, "mac": float(min(mac_next[g, a], mac_next[g, b]))}
                if rec not in veerings:
                    veerings.append(rec)
    w = np.zeros((G, N))
    for g in range(G):
        w[g, branch[g]] = omega2[g]
    return {"branch": branch, "omega2": w, "mac": mac_next, "crossings": crossings, "veerings": veerings}


def grid_branches(spec, realisations, max_masses: int = 400) -> dict | None:
    """Branches along a sweep's one grid parameter (one realisation per grid value), or None when the sweep
    is not a deterministic one-parameter grid (exactly one ``grid(...)`` and nothing random) or has more
    than ``max_masses`` masses.

    Parameters
    ----------
    spec : numeric.sweep.realisations.SweepSpec
    realisations : module
        :mod:`numeric.sweep.realisations` (``realise``), passed in by the caller.
    """
    from ..modes.spectrum import spectrum

    grids = spec.grids
    if len(grids) != 1 or len(spec.vary) != 1 or spec.disorder:
        return None
    name, dist = grids[0]
    values = dist.grid_values()
    shapes, w2 = [], []
    for g in range(len(values)):
        _, masses, ends, k = realisations.realise(spec, g * spec.samples)
        if masses.shape[0] > max_masses:
            return None
        sp = spectrum(masses, ends, k)
        w2.append(sp.omega2)
        shapes.append(sp.shapes)
    out = track(np.array(w2), shapes)
    return {"parameter": name, "values": [float(v) for v in values], "omega2": out["omega2"].tolist(),
            "branch_of_rank": out["branch"].tolist(), "mac_next": out["mac"].tolist(),
            "crossings": [dict(c, at=[float(values[c["between"][0]]), float(values[c["between"][1]])])
                          for c in out["crossings"]],
            "veerings": [dict(v, at=[float(values[v["between"][0]]), float(values[v["between"][1]])])
                         for v in out["veerings"]],
            "method": "each mode follows the shape it resembles most at the previous grid value (pairing that "
                      "maximises the summed MAC); a crossing exchanges ranks with MAC near 1, a veering keeps "
                      f"ranks while the MAC of a branch with itself drops below {VEERING_MAC}"}


def branches_figure(branches: dict, scene: str):
    """ω² of each branch against the grid parameter, crossings and veerings marked."""
    from ..plots import figures as plots

    x = np.array(branches["values"])
    w = np.array(branches["omega2"])
    fig, ax = plots.new_figure(figsize=(8, 5))
    for b in range(w.shape[1]):
        ax.plot(x, w[:, b], "-", lw=1.2, label=f"branch {b}" if w.shape[1] <= 10 else None)
    for c in branches["crossings"]:
        ax.axvspan(*c["at"], color="C2", alpha=0.15, lw=0)
    for v in branches["veerings"]:
        ax.axvspan(*v["at"], color="C3", alpha=0.15, lw=0)
    ax.set_xlabel(branches["parameter"])
    ax.set_ylabel("ω² [rad²/s²]")
    ax.set_title(f"{scene}: mode branches followed by MAC (green: crossing, red: veering)")
    ax.grid(alpha=0.3)
    if w.shape[1] <= 10:
        ax.legend(fontsize=8)
    return fig


__all__ = ["track", "grid_branches", "branches_figure", "VEERING_MAC"]
