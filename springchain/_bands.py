"""``springchain.bands``: the dispersion relation of a periodic chain — symbolic D(q) and closed-form branches
(:mod:`springchain.derive.bands`), and the numbers from the accurate route (:mod:`springchain.numeric.bands`):
branches by continuity, group velocities, band edges and gaps, Im q in the gaps, the density of states, the
finite chain's modes named by band, damped bands. This module checks inputs and packages results.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

from ._defaults import DEFAULT_OUT
from .derive.scene import Scene

#: Most q-points accepted.
MAX_Q = 1_000_000
#: Default q-points on [-π, π] (odd: q = 0 is one of them).
POINTS = 401
#: Frequencies of the density-of-states and Im q grid.
OMEGA_POINTS = 600
#: Largest finite chain whose modes are labelled (its spectrum is dense).
FINITE_MAX = 1200


@dataclass(frozen=True)
class Bands:
    """The bands of a periodic scene.

    Attributes
    ----------
    scene : Scene
    cell : springchain.derive.bands.model.BandCell
        The unit cell, symbolically (:attr:`dispersion` holds D(q), the polynomial and closed forms).
    elements : springchain.numeric.bands.cell.Cell
        The cell at the scene's values.
    q : ndarray, shape (Q,)
        Phase per cell [rad].
    omega2, velocity : ndarray, shape (Q, p)
        ω²_j(q) [rad²/s²] and dω_j/dq [cells/s], branches ordered by continuity.
    vectors : ndarray, shape (Q, p, p), complex
        Unit eigenvectors of D(q) (columns, branch order).
    edges : list of springchain.numeric.bands.edges.Edge
    gaps : list of springchain.numeric.bands.edges.Gap
    omega_grid : ndarray, shape (W,)
        Frequencies [rad/s] of :attr:`dos`, :attr:`imag_q`, :attr:`real_q`.
    dos : ndarray, shape (W, p)
        Density of states of each band [cells⁻¹ (rad/s)⁻¹] (band j = the j-th lowest at each q).
    imag_q, real_q : ndarray, shape (W,)
        Attenuation per cell of the slowest evanescent wave (0 inside a band), and its Re q.
    finite : list of springchain.numeric.bands.finite.FiniteMode or None
        The scene's own finite chain, every mode named.
    damped : springchain.numeric.bands.damped.Damped or None
        Complex ω and ζ per band at :attr:`q` (dashpots or Rayleigh damping).
    sound_speed : float or None
        The long-wave limit of the lowest branch's group velocity [cells/s] (None with a ground spring).
    notes : list of str
    """

    scene: Scene
    cell: object = field(repr=False)
    elements: object = field(repr=False)
    q: object = field(repr=False)
    omega2: object = field(repr=False)
    velocity: object = field(repr=False)
    vectors: object = field(repr=False)
    edges: list = field(default_factory=list, repr=False)
    gaps: list = field(default_factory=list, repr=False)
    omega_grid: object = field(default=None, repr=False)
    dos: object = field(default=None, repr=False)
    imag_q: object = field(default=None, repr=False)
    real_q: object = field(default=None, repr=False)
    finite: list | None = field(default=None, repr=False)
    damped: object = field(default=None, repr=False)
    sound_speed: float | None = None
    notes: list = field(default_factory=list, repr=False)
    #: The scene whose finite chain :attr:`finite` names (this scene, or the one given as ``finite=``).
    finite_scene: Scene | None = field(default=None, repr=False)

    @property
    def p(self) -> int:
        """Masses per cell."""
        return self.elements.p

    @property
    def omega(self):
        """ω_j(q) [rad/s], shape (Q, p)."""
        import numpy as np

        return np.sqrt(self.omega2)

    @cached_property
    def dispersion(self):
        """D(q), the characteristic polynomial and the closed-form branches
        (:class:`springchain.derive.bands.dispersion.Dispersion`)."""
        from .derive.bands.dispersion import dispersion

        return dispersion(self.cell)

    def attenuation(self, omega) -> tuple:
        """``(Im q, Re q)`` of the slowest evanescent wave at each ω [rad/s] (Im q = 0 inside a band), each of
        shape (W,) (:func:`springchain.numeric.bands.decay.attenuation`)."""
        import numpy as np

        from .numeric.bands.decay import attenuation

        return attenuation(self.elements, np.asarray(omega, dtype=float).reshape(-1))

    def at(self, q):
        """ω²_j, group velocities and eigenvectors at other q (ascending at each q): a
        :class:`springchain.numeric.bands.spectrum.Spectrum`."""
        from .numeric.bands.spectrum import spectrum

        return spectrum(self.elements, _q_points(q, POINTS))

    @cached_property
    def _closed_index(self) -> list[int] | None:
        """For each branch (continuity order), the index of its closed form in ``dispersion.branches`` (matched
        by value at a few q: a factorised polynomial lists its branches by factor)."""
        d = self.dispersion
        if d.branches is None:
            return None
        import numpy as np
        import sympy as sp
        from scipy.optimize import linear_sum_assignment

        qs = np.array([0.37, 1.21, 2.53])
        ours = self.at(qs)
        from .numeric.bands.spectrum import align

        ours = align(self._grid, ours, self.elements).omega2
        values = self.cell.values
        theirs = np.array([[complex(sp.N(b.subs(values).subs(d.q, float(x)), 20)).real for x in qs] for b in d.branches])
        cost = np.abs(ours.T[:, None, :] - theirs[None, :, :]).sum(axis=2)
        return list(linear_sum_assignment(cost)[1])

    @cached_property
    def _grid(self):
        from .numeric.bands.edges import edges

        return edges(self.elements)[2]

    # -- reports --------------------------------------------------------------------------------------
    def to_json(self) -> dict:
        """Exactly what ``springchain bands SCENE --json`` prints (without ``files``)."""
        from .derive.bands.report import cell_json, symbolic_json

        d = self.dispersion
        branches = symbolic_json(d)
        out = {"scene": self.scene.name, "parameters": {k: self.scene.parameters[k] for k in sorted(self.scene.parameters)},
               "cell": cell_json(d), "p": self.p, **{k: branches[k] for k in ("dynamical_matrix",
                                                                               "characteristic_polynomial",
                                                                               "coefficients", "determinant",
                                                                               "closed_form", "cos_q")},
               "branches": [{**e.as_json(), **self._expressions(branches, e.branch)} for e in self.edges],
               "gaps": [g.as_json() for g in self.gaps],
               "sound_speed": self.sound_speed,
               "q_points": int(self.q.shape[0]),
               "finite": self._finite_json(),
               "damped": self._damped_json(),
               "notes": list(self.notes)}
        return out

    def _expressions(self, branches: dict, j: int) -> dict:
        """The closed forms of branch j (continuity order), or nulls."""
        k = None if self._closed_index is None else self._closed_index[j]
        return {"omega2_expr": None if k is None else branches["omega2"][k],
                "omega_expr": None if k is None else branches["omega"][k],
                "group_velocity_expr": None if k is None else branches["group_velocity"][k]}

    def _finite_json(self) -> dict | None:
        if self.finite is None:
            return None
        sc = self.finite_scene or self.scene
        ends = ((sc.chain.left, sc.chain.right) if sc.chain is not None else
                (sc.cell.left, sc.cell.right) if sc.cell is not None else (None, None))
        cells = sc.n // self.p if sc.n % self.p == 0 else sc.n / self.p
        return {"scene": sc.name, "n": sc.n, "cells": cells, "left": None if ends[0] is None else str(ends[0]),
                "right": None if ends[1] is None else str(ends[1]), "modes": [m.as_json() for m in self.finite]}

    def _damped_json(self) -> dict | None:
        if self.damped is None:
            return None
        import numpy as np

        z = self.damped.zeta

        def span(j):
            col = z[:, j][np.isfinite(z[:, j])]
            return [float(col.min()), float(col.max())] if col.size else None

        return {"model": "rayleigh" if self.elements.proportional else "dashpots",
                "zeta_range": [span(j) for j in range(self.p)]}

    def to_text(self) -> str:
        """What ``springchain bands SCENE`` prints (without the ``wrote`` lines)."""
        from .derive.bands.report import symbolic_lines

        sc = self.scene
        lines = [f"Bands of {sc.name!r} ({sc.file})" + (f": {sc.description}" if sc.description else ""),
                 "Parameters: " + ", ".join(f"{k} = {sc.parameters[k]:g}" for k in sorted(sc.parameters)), ""]
        lines += symbolic_lines(self.dispersion)
        lines += ["", "Branches at the scene's values (ordered by continuity; accurate numeric route):"]
        for e in self.edges:
            lines.append(f"    branch {e.branch}: omega from {e.omega_low:.12g} (q = {e.q_low:.6g}) to "
                         f"{e.omega_high:.12g} (q = {e.q_high:.6g});  omega**2 in [{e.low:.12g}, {e.high:.12g}]")
        if self.gaps:
            lines.append("Gaps:")
            for g in self.gaps:
                lines.append(f"    between branches {g.below} and {g.above}: omega = {g.omega_lower:.12g} ... "
                             f"{g.omega_upper:.12g}, width {g.width:.12g}, centre {g.centre:.12g}")
        else:
            lines.append("No gap: the branches cover 0 ... the top without a break.")
        if self.sound_speed is not None:
            lines.append(f"Sound speed (q -> 0, the lowest branch's group velocity): {self.sound_speed:.12g} cells/s")
        if self.finite is not None:
            kinds = {k: sum(1 for m in self.finite if m.kind == k) for k in ("band", "edge", "defect")}
            chain = self.finite_scene or self.scene
            lines += ["", f"The finite chain of {chain.name!r} ({chain.n} masses): " +
                      ", ".join(f"{v} {k} mode{'s' if v != 1 else ''}" for k, v in kinds.items() if v) + ":"]
            shown = self.finite if len(self.finite) <= 40 else self.finite[:20] + self.finite[-20:]
            for m in shown:
                what = (f"band {m.band}, q = {m.q:.8g}" if m.kind == "band" else
                        f"{m.kind} mode in a gap, localisation length "
                        + (f"{m.localisation:.6g} cells" if m.localisation else "unknown"))
                lines.append(f"    omega = {m.omega:.12g}:  {what}")
            if len(shown) < len(self.finite):
                lines.append(f"    ... ({len(self.finite) - len(shown)} more in --json)")
        if self.damped is not None:
            dj = self._damped_json()
            lines += ["", f"Damped bands ({dj['model']}): zeta per branch over q:"]
            for j, s in enumerate(dj["zeta_range"]):
                lines.append(f"    branch {j}: zeta in [{s[0]:.6g}, {s[1]:.6g}]" if s else f"    branch {j}: zeta undefined")
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines) + "\n"

    def to_latex(self) -> str:
        """What ``springchain bands SCENE --latex`` prints (amsmath)."""
        from .derive.bands.report import symbolic_latex

        return symbolic_latex(self.dispersion)

    # -- figures and files ----------------------------------------------------------------------------
    def plot(self):
        """The band figure: Im q in the gaps | the band diagram (gaps shaded, the finite chain's modes at ±q) |
        the density of states."""
        from .numeric.bands.plots import band_figure

        return band_figure(self.q, self.omega, [(g.omega_lower, g.omega_upper) for g in self.gaps],
                           f"{self.scene.name}: bands ({self.p} mass{'es' if self.p > 1 else ''} per cell)",
                           finite=self.finite, dos_omega=self.omega_grid, dos=self.dos,
                           decay_omega=self.omega_grid, decay=self.imag_q)

    def arrays(self) -> dict:
        """The NPZ's arrays: ``q`` (Q,), ``omega2``, ``omega``, ``group_velocity`` (Q, p), ``omega_grid`` (W,),
        ``dos`` (W, p), ``imag_q``, ``real_q`` (W,), ``edges`` (p, 2) and ``gaps`` (G, 2) in ω² [rad²/s²],
        ``finite_omega2``, ``finite_band`` (-1 for a gap mode), ``finite_q`` (NaN for a gap mode), and with
        damping ``omega_damped``, ``decay_rate``, ``zeta`` (Q, p)."""
        import numpy as np

        out = {"q": self.q, "omega2": self.omega2, "omega": self.omega, "group_velocity": self.velocity,
               "omega_grid": self.omega_grid, "dos": self.dos, "imag_q": self.imag_q, "real_q": self.real_q,
               "edges": np.array([[e.low, e.high] for e in self.edges]).reshape(-1, 2),
               "gaps": np.array([[g.lower, g.upper] for g in self.gaps]).reshape(-1, 2)}
        if self.finite is not None:
            out["finite_omega2"] = np.array([m.omega2 for m in self.finite])
            out["finite_band"] = np.array([-1 if m.band is None else m.band for m in self.finite])
            out["finite_q"] = np.array([np.nan if m.q is None else m.q for m in self.finite])
        if self.damped is not None:
            out.update(omega_damped=self.damped.omega_d, decay_rate=self.damped.sigma, zeta=self.damped.zeta)
        return {k: v for k, v in out.items() if v is not None}

    def save(self, out: str | Path = DEFAULT_OUT, *, figures: bool = True) -> list[Path]:
        """Write ``OUT/<scene>-bands.npz``, ``-bands.json`` and (``figures``) ``-bands.png``; returns the paths."""
        import io

        import numpy as np

        from .numeric.plots import figures as plots
        from .numeric.io.files import atomic_write_bytes, atomic_write_text
        from .numeric.io.strict_json import dumps

        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        base = out / f"{self.scene.name}-bands"
        buf = io.BytesIO()
        np.savez(buf, **self.arrays())
        paths = [base.with_suffix(".npz"), base.with_suffix(".json")]
        atomic_write_bytes(paths[0], buf.getvalue())
        atomic_write_text(paths[1], dumps(self.to_json(), indent=1) + "\n")
        if figures:
            paths.append(base.with_suffix(".png"))
            plots.save(self.plot(), paths[-1])
        return paths

    def to_xarray(self):
        """An ``xarray.Dataset``: ``omega2``, ``omega``, ``group_velocity`` (and with damping ``zeta``,
        ``omega_damped``, ``decay_rate``) on dims (q, branch); ``dos`` on (frequency, branch); ``imag_q``,
        ``real_q`` on (frequency,) (the ω grid [rad/s]). Needs ``pip install "springchain[data]"``."""
        import numpy as np

        from ._data import require

        xr = require("xarray", "Bands.to_xarray")
        branch = np.arange(self.p)
        data = {"omega2": (("q", "branch"), self.omega2, {"units": "rad^2/s^2"}),
                "omega": (("q", "branch"), self.omega, {"units": "rad/s"}),
                "group_velocity": (("q", "branch"), self.velocity, {"units": "cells/s"}),
                "dos": (("frequency", "branch"), self.dos, {"units": "1/(cell rad/s)"}),
                "imag_q": (("frequency",), self.imag_q, {"units": "1/cell"}),
                "real_q": (("frequency",), self.real_q, {"units": "rad"})}
        if self.damped is not None:
            data["zeta"] = (("q", "branch"), self.damped.zeta, {})
            data["omega_damped"] = (("q", "branch"), self.damped.omega_d, {"units": "rad/s"})
            data["decay_rate"] = (("q", "branch"), self.damped.sigma, {"units": "1/s"})
        return xr.Dataset(data, coords={"q": self.q, "branch": branch, "frequency": self.omega_grid},
                          attrs={"scene": self.scene.name, "cell": self.cell.source, "q_units": "rad per cell"})

    def __repr__(self) -> str:
        return f"Bands(scene={self.scene.name!r}, p={self.p}, q_points={self.q.shape[0]}, gaps={len(self.gaps)})"

    def _repr_png_(self) -> bytes:
        import io

        from .numeric.plots import figures as plots

        buf = io.BytesIO()
        fig = self.plot()
        plots.lay_out(fig, 100)
        fig.savefig(buf, format="png", dpi=100)
        return buf.getvalue()


def _q_points(q, points):
    import numpy as np

    from .numeric.errors import RunRefused

    if q is None:
        if isinstance(points, bool) or not isinstance(points, int) or not 3 <= points <= MAX_Q:
            raise RunRefused(f"points {points!r}: accepted: a whole number 3 ... {MAX_Q}", quantity="points")
        half = (points - 1) / 2
        return np.pi * (np.arange(points) - half) / half  # symmetric: ±π and (odd points) q = 0 exactly
    try:
        arr = np.asarray(q, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise RunRefused(f"q {q!r}: accepted: numbers (phases per cell, rad)", quantity="q") from None
    if arr.size == 0 or arr.size > MAX_Q or not np.all(np.isfinite(arr)):
        raise RunRefused(f"q: {arr.size} values" + ("" if np.all(np.isfinite(arr)) else ", not all finite")
                         + f"; accepted: 1 ... {MAX_Q} finite phases per cell [rad]", quantity="q")
    return arr


def bands(scene: str | Path | Scene, q=None, *, points: int = POINTS, finite=True,
          density: bool = True) -> Bands:
    """The bands of a periodic scene: ω_j(q) of every branch, its edges and gaps, and more.

    Parameters
    ----------
    scene : str, Path or Scene
        A ``[cell]`` scene, or a ``[chain]`` whose expressions repeat in ``i`` (as for :func:`springchain.load`).
    q : array_like, optional
        Phases per cell [rad] at which to give ω_j(q) (default: ``points`` from −π to π).
    points : int
        Default grid size.
    finite : bool, or str, Path or Scene
        Name every mode of the scene's own finite chain by band and q (chains of at most :data:`FINITE_MAX`
        masses); or of another scene's chain laid out cell by cell like this one (a chain with a defect: its
        gap modes are named defect modes).
    density : bool
        Compute the density of states and Im q on a frequency grid (the figure's side panels).

    Returns
    -------
    Bands
        ``.omega2``, ``.velocity`` (q × branch), ``.edges``, ``.gaps``, ``.to_json()``, ``.plot()``,
        ``.save(dir)``, ``.to_xarray()``.

    Raises
    ------
    SceneError
        One line: a scene with no unit cell (``[masses]``), no period found, a cell with a free mass, ...
    """
    import numpy as np

    from ._modules import system_of
    from ._scenes import load
    from .derive.bands.model import band_cell
    from .numeric.bands.edges import edges as band_edges
    from .numeric.bands.spectrum import align, spectrum
    from .numeric.progress import phase

    sc = load(scene)
    qs = _q_points(q, points)
    with phase(f"bands of {sc.name!r}: the unit cell"):
        cell = band_cell(sc)
        system, _ = system_of(sc)
    elements = system.band_cell()
    with phase(f"bands of {sc.name!r}: {qs.shape[0]} q-points"):
        ranges, gaps, grid = band_edges(elements)  # the branches followed on a fine grid of [0, π]
        spec = align(grid, spectrum(elements, qs), elements)
    notes = list(cell.notes)
    top = max(e.omega_high for e in ranges)
    omega_grid = top * 1.05 * (np.arange(OMEGA_POINTS) + 0.5) / OMEGA_POINTS
    dos = imag = real = None
    if density:
        from .numeric.bands.decay import attenuation
        from .numeric.bands.dos import density as density_of

        with phase(f"bands of {sc.name!r}: density of states and Im q"):
            dos = density_of(elements, omega_grid)
            imag, real = attenuation(elements, omega_grid)
    modes = None
    chain = sc if finite is True else (load(finite) if finite is not False and finite is not None else None)
    if chain is not None and chain.n <= FINITE_MAX:
        from .numeric.bands.finite import label

        ends = (chain.chain.left if chain.chain is not None else chain.cell.left if chain.cell is not None else None)
        with phase(f"bands of {sc.name!r}: the finite chain's {chain.n} modes"):
            s = (system if chain is sc else system_of(chain)[0]).spectrum
            modes = label(elements, s.omega2, s.vectors, str(ends) == "ring")
        if chain.n % elements.p:
            notes.append(f"the finite chain of {chain.n} masses ends with a partial cell ({chain.n % elements.p} "
                         f"of {elements.p} masses)")
        if chain is not sc:
            notes.append(f"finite chain: {chain.name!r} ({chain.n} masses, read cell by cell against the bands of "
                         f"{sc.name!r})")
    elif chain is not None:
        notes.append(f"the finite chain's modes are not named: {chain.n} masses (at most {FINITE_MAX})")
    damped = None
    if elements.damped:
        from .numeric.bands.damped import damped as damped_bands

        damped = damped_bands(elements, spec)
        if not elements.proportional:
            notes.append("dashpots: complex omega per band from the quadratic eigenproblem in float64 (not the "
                         "accurate route of the undamped bands)")
    sound = None
    if not elements.grounded:
        sound = float(spectrum(elements, np.array([0.0])).velocity[0, 0])
    return Bands(sc, cell, elements, qs, spec.omega2, spec.velocity, spec.vectors, ranges, gaps, omega_grid, dos,
                 imag, real, modes, damped, sound, notes, chain if modes is not None else None)


__all__ = ["FINITE_MAX", "MAX_Q", "POINTS", "Bands", "bands"]
