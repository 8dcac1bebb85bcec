"""GIF animations of a scene: masses as dots on a line joined by springs, or a chain's profile.

Each function takes arrays (displacements per frame) and writes one GIF through matplotlib's
``PillowWriter`` on a Figure made without pyplot (:func:`numeric.plots.figures.new_figure`): the user's
backend is never touched. Every frame carries its own time or phase label, so no two frames are
pixel-identical (GIF encoders merge identical neighbours) and the file has exactly the frames drawn.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...generated.contract import MAX_DENSE, End
from ..io.files import atomic_path
from .figures import new_figure
from ..modes.spectrum import pieces

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
    """Draw ``frames`` frames with ``update(f)`` and write them as a GIF, atomically.

    The first frame lays the figure out (constrained layout); the others keep that layout: a frame
    moves artists inside fixed axis limits and changes a label's text, nothing the layout depends
    on, and laying out each frame again cost more than drawing it.
    """
    from matplotlib.animation import PillowWriter

    writer = PillowWriter(fps=fps)
    with atomic_path(path, suffix=".gif") as tmp:
        with writer.saving(fig, str(tmp), DPI):
            for f in range(frames):
                update(f)
                writer.grab_frame()
                if f == 0:  # keep the axes where the first frame put them; with no layout engine
                    fig.set_layout_engine(None)  # (matplotlib's default), savefig draws a frame once, not twice
    return path


#: Space between the drawings of two pieces that no spring joins (rest spacing 1).
PIECE_GAP = 1.5
#: Height of the ground under a mass whose wall spring is drawn downwards.
GROUND_Y = -0.45


def layout(n: int, spring_ends) -> tuple[np.ndarray, list[tuple[int, int, str, float]]]:
    """Where to draw masses and walls so that every piece is drawn as it is connected.

    Each piece (masses joined by springs) gets its own stretch of the line, masses in scene order at
    spacing 1, :data:`PIECE_GAP` between pieces; a wall spring of a piece's first (last) mass goes
    to a wall just left (right) of it, any other wall spring straight down to the ground. No spring
    is drawn across a mass of another piece.

    Returns
    -------
    rest : ndarray, shape (N,)
        Rest position of each mass on the drawing.
    walls : list of (spring index, mass, side, x)
        Every wall spring: side ``"left"``, ``"right"`` (wall at x) or ``"below"`` (ground under the mass).
    """
    ends = np.asarray(spring_ends, dtype=np.intp).reshape(-1, 2)
    wall_springs: dict[int, list[int]] = {}
    for j, (a, b) in enumerate(ends):
        if (a < 0) != (b < 0):
            wall_springs.setdefault(int(b if a < 0 else a), []).append(j)
    rest = np.zeros(n)
    walls: list[tuple[int, int, str, float]] = []
    cursor = 0.0
    for piece in (idx.tolist() for idx in pieces(n, ends)):  # in mass order, pieces by first mass
        first, last = piece[0], piece[-1]
        todo = {m: list(wall_springs.get(m, ())) for m in piece}
        left = todo[first].pop(0) if todo[first] else None
        right = todo[last].pop(0) if todo[last] else None
        cursor += 1.0 if left is not None else 0.0
        rest[piece] = cursor + np.arange(len(piece))
        if left is not None:
            walls.append((left, first, "left", rest[first] - 1.0))
        if right is not None:
            walls.append((right, last, "right", rest[last] + 1.0))
        walls += [(j, m, "below", rest[m]) for m in piece for j in todo[m]]
        cursor = rest[last] + (1.0 if right is not None else 0.0) + PIECE_GAP + 1.0
    return rest, walls


def _zigzag_down(x: float, top: float, turns: int = 4, width: float = 0.06) -> tuple[np.ndarray, np.ndarray]:
    """A spring drawn from the ground (y = GROUND_Y) up to a mass at (x, top)."""
    ys, xs = _zigzag(GROUND_Y, top, turns, width)
    return x + xs, ys


def line_animation(path: Path, displacement: np.ndarray, labels: list[str], spring_ends: np.ndarray,
                   masses: np.ndarray, title: str, fps: float) -> Path:
    """Masses as dots displaced along the line, springs between them, each piece on its own stretch.

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
    ends = np.asarray(spring_ends, dtype=np.intp).reshape(-1, 2)
    rest, walls = layout(n, ends)
    at_wall = {j: (side, x) for j, _, side, x in walls}
    fig, ax = new_figure(figsize=(6.4, 2.6))
    size = 60 + 140 * (masses / masses.max()) if masses.size else masses
    for k, (_, m, side, x) in enumerate(walls):
        if side == "below":
            ax.plot([x - 0.25, x + 0.25], [GROUND_Y, GROUND_Y], color="0.3", lw=3,
                    label="wall / ground" if k == 0 else None)
        else:
            ax.plot([x, x], [-0.35, 0.35], color="0.3", lw=3, label="wall / ground" if k == 0 else None)
    lines = [ax.plot([], [], color="0.45", lw=1, label="spring" if j == 0 else None)[0] for j in range(len(ends))]
    dots = ax.scatter(rest, np.zeros(n), s=size, color="C0", zorder=3, label="mass (area ∝ m)")
    stamp = ax.text(0.01, 0.95, "", transform=ax.transAxes, va="top", fontsize=9)
    xs_all = [*rest, *(x for *_, x in walls)]
    ax.set_xlim(min(xs_all) - 1.0, max(xs_all) + 1.0)
    ax.set_ylim(-0.6, 0.8)
    ax.set_yticks([])
    ax.set_xlabel("rest position (spacing 1; pieces apart) + scaled displacement [-]")
    ax.set_ylabel("(springs, masses)")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=7, loc="upper right", ncol=3)

    def update(f: int) -> None:
        pos = rest + displacement[f]
        dots.set_offsets(np.column_stack([pos, np.zeros(n)]))
        for j, (line, (a, b)) in enumerate(zip(lines, ends)):
            if j in at_wall:
                side, x = at_wall[j]
                m = b if a < 0 else a
                xs, ys = _zigzag_down(pos[m], 0.0) if side == "below" else _zigzag(x, pos[m])
            elif abs(rest[a] - rest[b]) == 1.0:
                xs, ys = _zigzag(pos[a], pos[b])
            else:
                xs, ys = _arc(pos[a], pos[b])
            line.set_data(xs, ys)
        stamp.set_text(labels[f])

    return _write(fig, update, frames, fps, path)


def profile_envelopes(rows, limit: int = MAX_PROFILE_POINTS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per frame, the min–max envelope of a chain's profile over ``limit`` bins of masses.

    rows : iterable of ndarray, shape (N,) each (read one at a time: memory stays O(limit) per frame)

    Returns
    -------
    centre : ndarray, shape (P,); low, high : ndarray, shape (F, P)
        Every mass when N <= limit (low == high); otherwise each bin's extremes, so a feature
        narrower than a bin keeps its true height (a decimated line would miss it).
    """
    from .figures import envelope

    lows, highs, centre = [], [], None
    for y in rows:
        centre, lo, hi = envelope(np.asarray(y, dtype=float), limit)
        lows.append(lo)
        highs.append(hi)
    return centre, np.array(lows), np.array(highs)


def profile_animation(path: Path, centre: np.ndarray, low: np.ndarray, high: np.ndarray, labels: list[str],
                      title: str, ylabel: str, fps: float, n: int) -> Path:
    """A chain's displacement profile x(i) per frame, as drawn by :func:`profile_envelopes`.

    Parameters
    ----------
    centre : ndarray, shape (P,)
        Mass index of each point (a bin's centre when the chain is longer than P).
    low, high : ndarray, shape (F, P)
        Per frame, the smallest and largest displacement in each bin (equal for unbinned chains).
    labels : list of str, length F
    n : int
        Masses in the chain.
    """
    frames = low.shape[0]
    binned = centre.shape[0] < n
    fig, ax = new_figure(figsize=(6.4, 3.0))
    label = (f"x(i): min–max over bins of {n / centre.shape[0]:.3g} masses" if binned else "x(i)")
    (line_hi,) = ax.plot(centre, high[0], color="C0", lw=1.0, marker="." if centre.shape[0] <= 60 else None,
                         label=label)
    (line_lo,) = ax.plot(centre, low[0], color="C0", lw=1.0, visible=binned)
    stamp = ax.text(0.01, 0.95, "", transform=ax.transAxes, va="top", fontsize=9)
    top = float(max(np.max(np.abs(low)), np.max(np.abs(high)))) or 1.0
    ax.set_ylim(-1.15 * top, 1.15 * top)
    ax.set_xlim(0.0, float(n - 1) if n > 1 else 1.0)
    ax.set_xlabel("mass index i")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")

    def update(f: int) -> None:
        line_hi.set_ydata(high[f])
        line_lo.set_ydata(low[f])
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

    ``[masses]`` scenes: the accurate spectrum (:mod:`numeric.modes.spectrum`). Chains: a uniform ring
    by its Fourier closed form, another ring up to ``MAX_DENSE`` masses by the spectrum, an open
    chain by one eigenpair of the scaled tridiagonal matrix (bisection + inverse iteration, O(n));
    the frequency of a uniform chain from its closed form.
    """
    import scipy.linalg

    from ..errors import RunRefused
    from ..modes.spectrum import spectrum

    n = system.n
    if not (0 <= j < n):
        raise RunRefused(f"mode {j!r}: accepted: a mode number 0 ... {n - 1} (ascending frequency, "
                         "rigid-body modes included)", quantity="mode")
    ring = system.chain and system.ends[0] is End.RING
    uniform = system.chain and system.has("mode_omega")
    if not system.chain or (ring and not uniform and n <= MAX_DENSE):
        spec = spectrum(system.masses, system.spring_ends, system.stiffness)
        omega, shape, rigid = float(spec.omega[j]), spec.shapes[:, j], j < spec.rigid
    elif ring and uniform:
        i = np.arange(n)
        q = (j + 1) // 2
        shape = np.cos(2 * np.pi * q * i / n) if j % 2 == 1 or j == 0 else np.sin(2 * np.pi * q * i / n)
        omega = float(np.sort(system.mode_omega())[j])
        rigid = j == 0
    elif ring:
        raise RunRefused(f"mode shapes of an index-dependent ring of {n} masses need a dense solve; "
                         f"accepted: rings of at most {MAX_DENSE} masses", quantity="mode")
    else:
        diag, off = system.stiffness_bands()
        r = 1 / np.sqrt(system.masses)
        w2, e = scipy.linalg.eigh_tridiagonal(diag * r * r, off * r[:-1] * r[1:], select="i", select_range=(j, j))
        rigid = j < system.rigid_modes
        shape = np.ones(n) if rigid else e[:, 0] * r
        omega = 0.0 if rigid else float(np.sqrt(max(w2[0], 0.0)))
        if uniform and not rigid:
            omega = float(np.sort(system.mode_omega())[j])
    shape = np.asarray(shape, dtype=float)
    big = int(np.argmax(np.abs(shape)))
    return omega, shape / shape[big], bool(rigid)
