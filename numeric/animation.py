"""GIF animations of a scene: masses as dots on a line joined by springs, or a chain's profile.

Each function takes arrays (displacements per frame) and writes one GIF through matplotlib's
``PillowWriter`` on a Figure made without pyplot (:func:`numeric.plots.new_figure`): the user's
backend is never touched. Every frame carries its own time or phase label, so no two frames are
pixel-identical (GIF encoders merge identical neighbours) and the file has exactly the frames drawn.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..generated.contract import MAX_DENSE, End
from .files import atomic_path
from .plots import new_figure

#: Largest number of points drawn for a chain profile (the chain is decimated to this).
MAX_PROFILE_POINTS = 1000
#: Largest drawn displacement as a fraction of the rest spacing.
DISPLAY_AMPLITUDE = 0.35
#: Dots per inch of the frames (6.4 x 2.6 in -> 512 x 208 px).
DPI = 80


def decimate(n: int, limit: int = MAX_PROFILE_POINTS) -> np.ndarray:
    """At most ``limit`` mass indices spread evenly over ``0 … n−1`` (both ends kept), shape (P,)."""
    if n <= limit:
        return np.arange(n)
    return np.unique(np.round(np.linspace(0, n - 1, limit)).astype(np.intp))


def _zigzag(a: float, b: float, turns: int = 6, height: float = 0.08) -> tuple[np.ndarray, np.ndarray]:
    """A spring drawn from x = a to x = b on y = 0 (straight leads, zigzag middle)."""
    u = np.concatenate([[0.0, 0.15], np.linspace(0.15, 0.85, 2 * turns + 1)[1:-1], [0.85, 1.0]])
    y = np.zeros_like(u)
    y[2:-2] = height * np.where(np.arange(u.shape[0] - 4) % 2 == 0, 1.0, -1.0)
    return a + (b - a) * u, y


def _arc(a: float, b: float, height: float = 0.45) -> tuple[np.ndarray, np.ndarray]:
    """A spring between masses that are not neighbours on the line, drawn as an arc above it."""
    u = np.linspace(0.0, 1.0, 41)
    return a + (b - a) * u, height * np.sin(np.pi * u)


def _write(fig, update, frames: int, fps: float, path: Path) -> Path:
    """Draw ``frames`` frames with ``update(f)`` and write them as a GIF, atomically."""
    from matplotlib.animation import PillowWriter

    writer = PillowWriter(fps=fps)
    with atomic_path(path, suffix=".gif") as tmp:
        with writer.saving(fig, str(tmp), DPI):
            for f in range(frames):
                update(f)
                writer.grab_frame()
    return path


def line_animation(path: Path, displacement: np.ndarray, labels: list[str], spring_ends: np.ndarray,
                   masses: np.ndarray, title: str, fps: float) -> Path:
    """Masses as dots at rest positions 0, 1, …, N−1 displaced along the line, springs between them.

    Parameters
    ----------
    path : Path
        The GIF to write.
    displacement : ndarray, shape (F, N)
        Displacement per frame, already scaled to the drawing (rest spacing 1).
    labels : list of str, length F
        The time or phase shown on each frame.
    spring_ends : ndarray of int, shape (S, 2)
        Mass indices of the spring ends, -1 for a wall.
    masses : ndarray, shape (N,)
        Dot areas scale with the masses.
    """
    frames, n = displacement.shape
    rest = np.arange(n, dtype=float)
    ends = np.asarray(spring_ends, dtype=np.intp).reshape(-1, 2)
    fig, ax = new_figure(figsize=(6.4, 2.6))
    size = 60 + 140 * (masses / masses.max()) if masses.size else masses

    def anchor(a: int, b: int) -> float:  # a wall beside the end mass nearer to it
        return -1.0 if b <= (n - 1) / 2 else float(n)

    walls = sorted({anchor(a, b) if a < 0 else anchor(b, a) for a, b in ends if (a < 0) != (b < 0)})
    for w in walls:
        ax.axvline(w, color="0.3", lw=3, label="wall" if w == walls[0] else None)
    lines = [ax.plot([], [], color="0.45", lw=1, label="spring" if j == 0 else None)[0] for j in range(len(ends))]
    dots = ax.scatter(rest, np.zeros(n), s=size, color="C0", zorder=3, label="mass (area ∝ m)")
    stamp = ax.text(0.01, 0.95, "", transform=ax.transAxes, va="top", fontsize=9)
    lo = min([-0.5, *walls]) - 0.5
    hi = max([n - 0.5, *walls]) + 0.5
    ax.set_xlim(lo, hi)
    ax.set_ylim(-0.6, 0.8)
    ax.set_yticks([])
    ax.set_xlabel("rest position (spacing 1) + scaled displacement [-]")
    ax.set_ylabel("(springs, masses)")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=7, loc="upper right", ncol=3)

    def update(f: int) -> None:
        pos = rest + displacement[f]
        dots.set_offsets(np.column_stack([pos, np.zeros(n)]))
        for line, (a, b) in zip(lines, ends):
            if a < 0 or b < 0:
                m = b if a < 0 else a
                xs, ys = _zigzag(anchor(m, -1), pos[m])
            elif abs(a - b) == 1:
                xs, ys = _zigzag(pos[a], pos[b])
            else:
                xs, ys = _arc(pos[a], pos[b])
            line.set_data(xs, ys)
        stamp.set_text(labels[f])

    return _write(fig, update, frames, fps, path)


def profile_animation(path: Path, index: np.ndarray, displacement: np.ndarray, labels: list[str], title: str,
                      ylabel: str, fps: float) -> Path:
    """A chain's displacement profile x(i) per frame, at the (decimated) indices ``index``.

    Parameters
    ----------
    index : ndarray of int, shape (P,)
    displacement : ndarray, shape (F, P)
    labels : list of str, length F
    """
    frames = displacement.shape[0]
    fig, ax = new_figure(figsize=(6.4, 3.0))
    (line,) = ax.plot(index, displacement[0], color="C0", lw=1.2, marker="." if index.shape[0] <= 60 else None,
                      label=f"x(i) at {index.shape[0]} of {int(index[-1]) + 1} masses" if index.shape[0] < int(index[-1]) + 1
                      else "x(i)")
    stamp = ax.text(0.01, 0.95, "", transform=ax.transAxes, va="top", fontsize=9)
    top = float(np.max(np.abs(displacement))) or 1.0
    ax.set_ylim(-1.15 * top, 1.15 * top)
    ax.set_xlim(float(index[0]), float(index[-1]) if index[-1] > index[0] else 1.0)
    ax.set_xlabel("mass index i")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")

    def update(f: int) -> None:
        line.set_ydata(displacement[f])
        stamp.set_text(labels[f])

    return _write(fig, update, frames, fps, path)


def mode_frames(shape: np.ndarray, frames: int) -> tuple[np.ndarray, list[str]]:
    """One period of a mode: ``shape · cos(2π f / F)``, shape (F, N), with phase labels."""
    phase = 2 * np.pi * np.arange(frames) / frames
    return np.cos(phase)[:, None] * shape[None, :], [f"phase ωt = {np.degrees(p):.0f}°" for p in phase]


def display_scale(x: np.ndarray) -> float:
    """Factor that makes the largest |x| equal :data:`DISPLAY_AMPLITUDE` (1 for x = 0)."""
    top = float(np.max(np.abs(x))) if x.size else 0.0
    return DISPLAY_AMPLITUDE / top if top > 0 else 1.0


def mode_shape(system, j: int) -> tuple[float, np.ndarray, bool]:
    """Mode ``j`` (ascending ω, rigid-body modes first) of a linear system.

    Returns
    -------
    omega : float
        [rad/s]; 0 for a rigid-body mode.
    shape : ndarray, shape (N,)
        Physical shape, largest component +1.
    rigid : bool

    ``[masses]`` scenes: the accurate spectrum (:mod:`numeric.spectrum`). Chains: a uniform ring
    by its Fourier closed form, another ring up to ``MAX_DENSE`` masses by the spectrum, an open
    chain by one eigenpair of the scaled tridiagonal matrix (bisection + inverse iteration, O(n));
    the frequency of a uniform chain from its closed form.
    """
    import scipy.linalg

    from .errors import RunRefused
    from .spectrum import spectrum

    n = system.n
    if not (0 <= j < n):
        raise RunRefused(f"mode {j!r}: accepted: a mode number 0 ... {n - 1} (ascending frequency, "
                         "rigid-body modes included)", quantity="mode")
    mod, p = system.module, system.params
    ring = system.chain and system.ends[0] is End.RING
    uniform = system.chain and system.has("mode_omega")
    if not system.chain or (ring and not uniform and n <= MAX_DENSE):
        spec = spectrum(system.masses, system.spring_ends, system.stiffness)
        omega, shape, rigid = float(spec.omega[j]), spec.shapes[:, j], j < spec.rigid
    elif ring and uniform:
        i = np.arange(n)
        q = (j + 1) // 2
        shape = np.cos(2 * np.pi * q * i / n) if j % 2 == 1 or j == 0 else np.sin(2 * np.pi * q * i / n)
        omega = float(np.sort(np.asarray(mod.mode_omega(**p, n=n), dtype=float))[j])
        rigid = j == 0
    elif ring:
        raise RunRefused(f"mode shapes of an index-dependent ring of {n} masses need a dense solve; "
                         f"accepted: rings of at most {MAX_DENSE} masses", quantity="mode")
    else:
        diag, off = (np.asarray(b, dtype=float) for b in mod.stiffness_bands(**p, n=n))
        r = 1 / np.sqrt(system.masses)
        w2, e = scipy.linalg.eigh_tridiagonal(diag * r * r, off * r[:-1] * r[1:], select="i", select_range=(j, j))
        rigid = j < system.rigid_modes
        shape = np.ones(n) if rigid else e[:, 0] * r
        omega = 0.0 if rigid else float(np.sqrt(max(w2[0], 0.0)))
        if uniform and not rigid:
            omega = float(np.sort(np.asarray(mod.mode_omega(**p, n=n), dtype=float))[j])
    shape = np.asarray(shape, dtype=float)
    big = int(np.argmax(np.abs(shape)))
    return omega, shape / shape[big], bool(rigid)
