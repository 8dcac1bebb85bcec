"""Figures: each function takes arrays and returns a matplotlib Figure; the caller saves it."""

from __future__ import annotations

import matplotlib
import numpy as np
from matplotlib.figure import Figure


def new_figure(nrows: int = 1, ncols: int = 1, **kw):
    """A Figure and its axes, made without pyplot: no global backend, no figure manager.

    Figures are written with ``Figure.savefig`` (an explicit Agg canvas), so the
    user's backend (a notebook's inline one, say) is never switched.
    """
    kw.setdefault("layout", "constrained")
    fig = Figure(figsize=kw.pop("figsize", (9, 5)), layout=kw.pop("layout"))
    return fig, fig.subplots(nrows, ncols, **kw)

STYLES = {"modal": dict(ls="-", lw=1.6, alpha=0.8), "verlet": dict(ls="--", lw=1.1)}


def _offset(series: dict[str, np.ndarray]) -> np.ndarray:
    """Vertical offset per mass so the curves do not overlap, shape (N,)."""
    first = next(iter(series.values()))
    span = float(np.ptp(first)) if first.size else 1.0
    n = first.shape[1]
    return np.arange(n)[::-1] * (span if span > 0 else 1.0)


def trajectories(t: np.ndarray, series: dict[str, np.ndarray], names, quantity: str, unit: str,
                 title: str):
    """Each mass's curve (offset for readability), every method overlaid.

    series : dict of method name -> ndarray, shape (S, N)
    """
    fig, ax = new_figure(figsize=(9, 5.5))
    off = _offset(series)
    colors = matplotlib.rcParams["axes.prop_cycle"].by_key()["color"]
    for method, y in series.items():
        style = STYLES.get(method, dict(ls=":", lw=1.0))
        for j, name in enumerate(names):
            ax.plot(t, y[:, j] + off[j], color=colors[j % len(colors)],
                    label=f"{name} ({method})", **style)
    ax.set_xlabel("time t [s]")
    ax.set_ylabel(f"{quantity} + offset per mass [{unit}]")
    ax.set_title(title)
    ax.legend(ncol=max(1, len(series)), fontsize=8, loc="upper right")
    ax.grid(alpha=0.3)
    return fig


def differences(t: np.ndarray, dx: np.ndarray, dv: np.ndarray, names, label: str):
    """Position and velocity differences of a method from the exact solution.

    dx, dv : ndarray, shape (S, N)
    """
    fig, axes = new_figure(2, 1, figsize=(9, 6), sharex=True)
    for j, name in enumerate(names):
        axes[0].plot(t, dx[:, j], lw=1, label=name)
        axes[1].plot(t, dv[:, j], lw=1, label=name)
    axes[0].set_ylabel("x − x_exact [m]")
    axes[1].set_ylabel("v − v_exact [m/s]")
    axes[1].set_xlabel("time t [s]")
    axes[0].set_title(f"{label} − exact modal solution")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=min(len(names), 6))
    return fig


def energy(t: np.ndarray, energies: dict[str, np.ndarray], e0: float | None = None, *, conserved: bool = True,
           work: np.ndarray | None = None):
    """Energy of every method, labelled with what is plotted.

    conserved : bool
        No dampers, forces or ground motion: the error E(t) − E(0) is plotted, relative to |E(0)|
        when E(0) ≠ 0, in joules otherwise. Else E(t) itself [J] (it changes by the work of forces
        and damping), and ``work`` (shape (S,), if given) as the curve E(0) + W(t).
    e0 : float, optional
        E(0) (default: the first method's first value).
    """
    fig, ax = new_figure(figsize=(9, 4.5))
    e0 = float(next(iter(energies.values()))[0]) if e0 is None else e0
    if conserved:
        scale = abs(e0) if e0 != 0 else 1.0
        for method, e in energies.items():
            ax.plot(t, (e - e0) / scale, label=method, **STYLES.get(method, {}))
        ax.set_ylabel("(E(t) − E(0)) / |E(0)|" if e0 != 0 else "E(t) − E(0) [J]")
        ax.set_title("Energy error (no dampers or forces: E is conserved)")
    else:
        for method, e in energies.items():
            ax.plot(t, e, label=f"E(t), {method}", **STYLES.get(method, {}))
        if work is not None:
            ax.plot(t, e0 + work, color="k", ls=":", lw=1.2,
                    label="E(0) + W(t): work of forces and damping (trapezoid on the recorded times)")
        ax.set_ylabel("energy E(t) = T + V [J]")
        ax.set_title("Energy E(t): not conserved, it changes by the work of forces and damping")
    ax.set_xlabel("time t [s]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def modal_energies(t: np.ndarray, energies: np.ndarray, omega: np.ndarray, title: str, lowest: int = 5,
                   unit: str = "J"):
    """Energy of the lowest elastic modes over time (E_j(t), j = 1 … ``lowest``), and their sum.

    Parameters
    ----------
    t : ndarray, shape (S,)
    energies : ndarray, shape (S, N)
        ``modal_energy_<method>``: columns in ascending ω.
    omega : ndarray, shape (N,)
        The modes' angular frequencies (ascending); rigid modes (ω = 0) are left out.
    """
    fig, ax = new_figure(figsize=(10, 4.5))
    elastic = np.flatnonzero(omega > 0)[:lowest]
    for r, j in enumerate(elastic):
        ax.plot(t, energies[:, j], label=f"mode {r + 1} (ω = {omega[j]:.4g} rad/s)", lw=1.2)
    ax.plot(t, energies.sum(axis=1), color="0.35", lw=0.8, ls="--", label="sum over all modes")
    ax.set_xlabel("time t [s]")
    ax.set_ylabel(f"modal energy E_j = (p_j² + ω_j² q_j²)/2 [{unit}]")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return fig


#: Resolution of the figures springchain writes.
DPI = 110


def lay_out(fig, dpi: float) -> None:
    """Lay a figure out once, at ``dpi``, for its one final drawing, and drop its layout engine.

    ``savefig`` on a figure that keeps its engine draws it twice (once to lay it out, once to render),
    and a figure's ticks, labels and legends are measured on every pass; laid out here, it is drawn
    once, and the picture is the same (pixel for pixel). For a figure about to be written and closed.
    """
    engine = fig.get_layout_engine()
    if engine is not None:
        fig.set_dpi(dpi)
        engine.execute(fig)
        fig.set_layout_engine(None)  # matplotlib's default: no engine, the axes stay where they are


def save(fig, path) -> None:
    """Save a figure atomically (temporary file, then rename) and close it (laid out once: :func:`lay_out`)."""
    from ..io.files import atomic_path

    lay_out(fig, DPI)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=DPI, format=str(path).rsplit(".", 1)[-1])


#: Profiles of more masses than this are drawn as a min–max envelope per bin of masses.
PROFILE_POINTS = 2000
#: A feature narrower than this fraction of the chain gets a zoomed panel at full resolution.
NARROW = 0.05


def envelope(y: np.ndarray, bins: int = PROFILE_POINTS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Smallest and largest value of ``y`` in each of ``bins`` runs of consecutive masses.

    A plain decimation (every k-th mass) misses or shrinks a feature narrower than k masses; the
    envelope keeps every extreme, so a narrow pulse is drawn at its true height.

    Returns
    -------
    centre, low, high : ndarray, shape (B,)
        Bin centres (mass index) and the extremes of ``y`` in each bin; ``B = min(bins, N)``.
    """
    y = np.asarray(y, dtype=float)
    n = y.shape[0]
    starts = np.unique(np.linspace(0, n, min(bins, n) + 1).astype(np.intp)[:-1])
    ends = np.append(starts[1:], n)
    return 0.5 * (starts + ends - 1), np.minimum.reduceat(y, starts), np.maximum.reduceat(y, starts)


def narrow_window(rows: list[np.ndarray], fraction: float = NARROW) -> tuple[int, int] | None:
    """``(first, last)`` mass index around where the profiles exceed 5 % of their peak, when that
    stretch is narrower than ``fraction`` of the chain (None otherwise, or for an all-zero profile)."""
    top = max((float(np.max(np.abs(r))) for r in rows), default=0.0)
    if top == 0.0:
        return None
    hit = np.flatnonzero(np.any([np.abs(r) > 0.05 * top for r in rows], axis=0))
    n = rows[0].shape[0]
    lo, hi = int(hit[0]), int(hit[-1])
    if hi - lo + 1 > fraction * n:
        return None
    pad = max(10, (hi - lo + 1) // 2)
    return max(0, lo - pad), min(n - 1, hi + pad)


def profiles(snapshots: dict[float, np.ndarray], quantity: str = "displacement x", unit: str = "m"):
    """Chain profiles x(i) at a few times. snapshots: time -> ndarray, shape (N,).

    Up to :data:`PROFILE_POINTS` masses every mass is drawn; longer chains as a min–max envelope
    per bin of masses (a narrow feature keeps its height), and a feature narrower than
    :data:`NARROW` of the chain gets a second panel at full resolution.
    """
    rows = list(snapshots.values())
    n = rows[0].shape[0] if rows else 0
    window = narrow_window(rows) if n > PROFILE_POINTS else None
    fig, axes = new_figure(2 if window else 1, 1, figsize=(9, 7 if window else 4.5), squeeze=False)
    ax = axes[0, 0]
    for j, (t, y) in enumerate(snapshots.items()):
        if n > PROFILE_POINTS:
            c, lo, hi = envelope(y)
            ax.fill_between(c, lo, hi, color=f"C{j % 10}", alpha=0.6, lw=0.6, label=f"t = {t:g} s (min–max per "
                            f"{n / c.shape[0]:.3g} masses)")
        else:
            ax.plot(np.arange(n), y, lw=1, label=f"t = {t:g} s")
    ax.set_xlabel("mass index i")
    ax.set_ylabel(f"{quantity} [{unit}]")
    ax.set_title(f"Chain profile ({n} masses)")
    ax.grid(alpha=0.3)
    # matplotlib's "best" legend place scans every point: seconds for 10^6-mass profiles
    ax.legend(fontsize=8, **({"loc": "upper right"} if n > 100_000 else {}))
    if window:
        lo, hi = window
        zoom = axes[1, 0]
        idx = np.arange(lo, hi + 1)
        for j, (t, y) in enumerate(snapshots.items()):
            zoom.plot(idx, y[lo:hi + 1], color=f"C{j % 10}", lw=1, marker="." if idx.shape[0] <= 200 else None,
                      label=f"t = {t:g} s")
        zoom.set_xlabel("mass index i (every mass)")
        zoom.set_ylabel(f"{quantity} [{unit}]")
        zoom.set_title(f"Zoom: masses {lo} … {hi}, where the profile exceeds 5 % of its peak")
        zoom.grid(alpha=0.3)
        zoom.legend(fontsize=8)
        ax.axvspan(lo, hi, color="0.85", zorder=0, label=None)
    return fig


def frequency_response(drive: np.ndarray, amplitude: np.ndarray, names, natural: np.ndarray,
                       driven: np.ndarray | None = None):
    """Steady-state amplitude |X_j(Ω)| per mass against drive frequency Ω (log amplitude).

    amplitude : ndarray, shape (W, N); natural : undamped ω_j (vertical lines).
    """
    fig, ax = new_figure(figsize=(9, 4.8))
    for j, name in enumerate(names):
        ax.semilogy(drive, amplitude[:, j], lw=1.2, label=name)
    for k, w in enumerate(natural):
        ax.axvline(w, color="0.6", ls=":", lw=1, label="undamped ω_j" if k == 0 else None)
    if driven is not None:
        for k, w in enumerate(driven):
            ax.axvline(w, color="k", ls="--", lw=1, label="scene's drive Ω" if k == 0 else None)
    finish(ax, "drive frequency Ω [rad/s]", "steady-state amplitude |X(Ω)| [m]", "Frequency response (K − Ω²M + iΩC)⁻¹ F")
    return fig


def finish(ax, xlabel: str, ylabel: str, title: str) -> None:
    """Labelled axes (with units), a title, a light grid and the legend: how a figure is finished."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)


def bode(omega: np.ndarray, magnitude: np.ndarray, phase: np.ndarray, title: str, *,
         peaks: tuple = (), infinite: tuple = (), hidden: tuple = (), empty: str | None = None):
    """Bode plot of a receptance: |H| log-log and phase in degrees against ω [rad/s].

    omega, magnitude, phase : ndarray, shape (W,)
    peaks : (ω, |H|) pairs of local maxima of |H| (marked)
    infinite : ω_j of undamped resonances (|H| = ∞ there; vertical lines)
    hidden : ω_j of modes with a node at the input or output (no resonance in this H; thin lines)
    empty : a note drawn instead of the curves (H ≡ 0: no logarithmic axis has anything to show)
    """
    fig, (ax, axp) = new_figure(2, 1, figsize=(9, 6.5), sharex=True)
    positive = magnitude > 0
    if empty is not None or not np.any(positive):
        notes = (empty or "H ≡ 0 on this range", "phase undefined (H ≡ 0)")
        for a, text in zip((ax, axp), notes):
            a.set_xscale("log")
            a.set_xlim(float(omega[0]), float(omega[-1]) if omega[-1] > omega[0] else float(omega[0]) * 10)
            a.set_yticks([])
            a.text(0.5, 0.5, text, transform=a.transAxes, ha="center", va="center", fontsize=11, color="0.3")
        ax.set_ylabel("|H| = |X_out / F_in| [m/N]")
        axp.set_ylabel("phase ∠H [deg] (undefined)")
        axp.set_xlabel("angular frequency ω [rad/s]")
        ax.set_title(title)
        for a in (ax, axp):
            a.grid(alpha=0.3, which="both", axis="x")
        return fig
    ax.loglog(omega[positive], magnitude[positive], lw=1.3, color="C0", label="|H(iω)|")
    axp.semilogx(omega, phase, lw=1.3, color="C0", label="∠H(iω)")
    if peaks:
        w, h = np.asarray(peaks, dtype=float).T
        ax.plot(w, h, "v", color="C3", ms=7, label="local maximum of |H| (exact)")
        for wk, hk in zip(w, h):
            ax.annotate(f"{wk:.4g} rad/s", (wk, hk), textcoords="offset points", xytext=(4, 6), fontsize=8)
    for k, w in enumerate(infinite):
        for a in (ax, axp):
            a.axvline(w, color="C3", ls=":", lw=1, label="undamped ω_j (|H| = ∞)" if k == 0 and a is ax else None)
    for k, w in enumerate(hidden):
        ax.axvline(w, color="0.7", ls="--", lw=0.8, label="ω_j with a node at input/output" if k == 0 else None)
    ax.set_ylabel("|H| = |X_out / F_in| [m/N]")
    axp.set_ylabel("phase ∠H [deg]")
    axp.set_xlabel("angular frequency ω [rad/s]")
    ax.set_title(title)
    for a in (ax, axp):
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=8, loc="best" if omega.shape[0] < 20_000 else "upper right")
    return fig
