"""``springchain.animate``: a GIF of a mode shape oscillating, or of a simulated trajectory.

The drawing is :mod:`springchain.numeric.plots.animation`; trajectories come from :func:`springchain.simulate`
with only the frames drawn recorded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from ._defaults import DEFAULT_OUT
from .derive.scene import Scene

#: Most frames accepted (a GIF of more is rarely what anyone wants, and memory grows with it).
MAX_FRAMES = 2000


@dataclass(frozen=True)
class Animation:
    """A written GIF.

    Attributes
    ----------
    path : Path
    frames : int
    kind : str
        ``"mode"`` or ``"method"``.
    what : str
        The mode (``"mode 2"``) or the method's name.
    omega : float or None
        The mode's angular frequency [rad/s].
    """

    path: Path
    frames: int
    kind: str
    what: str
    omega: float | None = None
    scale: float = 1.0

    def describe(self) -> str:
        """One line: what the GIF shows."""
        extra = f", ω = {self.omega:.8g} rad/s" if self.omega is not None else ""
        return f"animated {self.what}{extra}: {self.frames} frames"

    def _repr_html_(self) -> str:  # the GIF inline
        from ._display import animation_html

        return animation_html(self)


def _check(frames, fps):
    from .numeric.errors import RunRefused

    if isinstance(frames, bool) or not isinstance(frames, int) or not 2 <= frames <= MAX_FRAMES:
        raise RunRefused(f"frames {frames!r}: accepted: a whole number 2 ... {MAX_FRAMES}", quantity="frames")
    if isinstance(fps, bool) or not isinstance(fps, float | int) or not math.isfinite(fps) or not 0 < fps <= 100:
        raise RunRefused(f"fps {fps!r}: accepted: a number > 0 and <= 100", quantity="fps")


def animate(scene: str | Path | Scene, mode: int | None = None, method: str | None = None, *,
            out: str | Path = DEFAULT_OUT, frames: int = 48, fps: float = 16.0) -> Animation:
    """Write a GIF: mode ``mode`` oscillating through one period, or the trajectory of ``method``.

    Parameters
    ----------
    scene : str, Path or Scene
        As for :func:`springchain.load`.
    mode : int, optional
        Mode number, 0 = lowest frequency, rigid-body modes included. Default (neither ``mode``
        nor ``method``): the lowest elastic mode.
    method : str, optional
        A name from :func:`springchain.method_names`: the scene is simulated from its initial state
        over (about) its horizon, ``frames`` frames recorded.
    out : str or Path
        Folder for ``<scene>-mode<J>.gif`` or ``<scene>-<method>.gif``.
    frames : int
    fps : float
        Frames per second of the GIF.

    Returns
    -------
    Animation
    """
    import numpy as np

    from ._api import load, simulate
    from ._modules import system_of
    from .numeric.plots import animation as anim
    from .numeric.errors import RunRefused

    sc = load(scene)
    _check(frames, fps)
    if mode is not None and method is not None:
        raise RunRefused("give a mode or a method, not both", quantity="mode")
    if method is not None:
        from .numeric.run import registry

        registry.entry(method)  # an unknown name: one line naming the accepted ones
    if mode is not None and (isinstance(mode, bool) or not isinstance(mode, int | np.integer)):
        raise RunRefused(f"mode {mode!r}: accepted: a whole number >= 0", quantity="mode")
    out = Path(out)
    system, _ = system_of(sc)
    chain = system.chain
    if method is None:
        if mode is None:
            from .numeric.modes.spectrum import free_pieces

            rigid = system.rigid_modes if chain else \
                len(free_pieces(system.n, system.spring_ends))
            mode = min(rigid, system.n - 1)  # the lowest elastic mode
        omega, shape, rigid = anim.mode_shape(system, int(mode))
        if chain:  # the envelope of the shape once; each frame scales it by cos(phase): never F × N
            centre, lo, hi = anim.profile_envelopes([shape])
            c = np.cos(2 * np.pi * np.arange(frames) / frames)[:, None]
            envelopes = (centre, np.minimum(c * lo, c * hi), np.maximum(c * lo, c * hi))
            disp, labels = envelopes[2], anim.mode_frames(shape[:1], frames)[1]
        else:
            disp, labels = anim.mode_frames(shape, frames)
        kind, what = "mode", f"mode {mode}"
        label = ("rigid-body mode (ω = 0): a uniform translation, shown back and forth" if rigid
                 else f"ω = {omega:.6g} rad/s, period {2 * math.pi / omega:.4g} s")
        title = f"{sc.name}: mode {mode}, {label}"
        path = out / f"{sc.name}-mode{mode}.gif"
    else:
        steps = max(sc.steps, frames - 1)
        every = max(1, steps // (frames - 1))
        steps = every * (frames - 1)
        if chain:
            import tempfile

            out.mkdir(parents=True, exist_ok=True)
            with tempfile.TemporaryDirectory(dir=out, prefix=".animate-") as tmp:
                run = simulate(sc, [method], steps=steps, record_every=every, out=tmp, progress=False)
                xs = run.x[method]
                envelopes = anim.profile_envelopes(xs[r] for r in range(min(frames, xs.shape[0])))
                disp = envelopes[1]
        else:
            run = simulate(sc, [method], steps=steps, record_every=every, progress=False)
            disp = np.asarray(run.x[method])
        t = np.asarray(run.t)
        omega, kind, what = None, "method", method
        labels = [f"t = {tt:.4g} s" for tt in t[:frames]]
        disp = disp[:frames]
        title = f"{sc.name}: {method}, t = 0 ... {t[min(frames, t.shape[0]) - 1]:.4g} s"
        path = out / f"{sc.name}-{method}.gif"
    if chain:
        ylabel = "mode shape (largest component 1) [-]" if kind == "mode" else "displacement x [m]"
        anim.profile_animation(path, *envelopes, labels[:envelopes[1].shape[0]], title, ylabel, fps, system.n)
        scale = 1.0
    else:
        scale = anim.display_scale(disp)
        title += f"; displacements x{scale:.3g}" if kind == "method" else ""
        anim.line_animation(path, disp * scale, labels, system.spring_ends, system.masses, title, fps)
    return Animation(path, int(disp.shape[0]), kind, what, omega, scale)


__all__ = ["Animation", "animate"]
