"""The Python API: what every ``springchain`` command does, callable from a notebook or a script.

The command line (:mod:`springchain.cli`) only parses flags, calls these and prints.
Heavy packages (SymPy, SciPy, matplotlib) are imported by the function that needs them.
"""

from __future__ import annotations

import math
import shutil
from dataclasses import dataclass, field
from pathlib import Path

from ._scenes import resolve
from .derive.errors import SceneError
from .derive.scene import Scene
from .numeric.files import human_bytes as _human_bytes

#: The most memory a simulation's recorded trajectories may take (in-memory runs).
MAX_RECORDED_BYTES = 4 * 2**30
#: Default output folder of the commands that write files.
DEFAULT_OUT = "springchain-out"


# -- scenes -----------------------------------------------------------------------------------------
def load(source: str | Path | Scene | dict) -> Scene:
    """Read and validate a scene.

    Parameters
    ----------
    source : str, Path, Scene or dict
        A path to a TOML scene file, or the name of a bundled scene (``"seed"``,
        ``"building"``, ...). A :class:`Scene` is returned as it is; a dict goes through
        :func:`scene_from_dict`.

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        (a ``ValueError``) with the one-line message the command prints.
    """
    if isinstance(source, Scene):
        return source
    if isinstance(source, dict):
        from .derive.scene_edit import scene_from_dict

        return scene_from_dict(source)
    from .derive.scene import load_scene

    from .numeric.progress import phase

    path = resolve(source)
    with phase(f"reading {Path(path).name}"):  # a long chain's expressions are checked at every index
        return load_scene(path)


def _system(scene: Scene):
    """The generated module bound to the scene's parameters (no SymPy for fresh bundled scenes)."""
    from ._modules import load_module
    from .numeric.system import System

    module, origin = load_module(scene)  # keyed by the scene's whole content: a changed scene has its own
    return System.from_module(module, scene.parameters, **load_tables(scene)), origin


def load_tables(scene: Scene) -> dict:
    """The scene's tables as keyword arguments of ``System.from_module`` (data, never source)."""
    ground = scene.ground
    return {"tables": tuple((tf.table.t, tf.table.y) for tf in scene.table_forces),
            "ground_table": None if ground is None or ground.table is None else (ground.table.t, ground.table.y)}


# -- modes ------------------------------------------------------------------------------------------
def _chain_omega2(scene: Scene, chain_modes):
    """ω² of a chain without closed form from its generated module (None when too large)."""
    if chain_modes.omega2 is not None:
        return None
    from ._modules import load_module

    module, _ = load_module(scene)
    try:
        return module.omega2(**scene.parameters)
    except ValueError:  # a non-uniform ring longer than the module's MAX_DENSE
        return None


@dataclass(frozen=True)
class Modes:
    """A scene's equations of motion and normal modes.

    Attributes
    ----------
    scene : Scene
    model : the symbolic model (``springchain.derive.model.Model`` or ``...chain.ChainModel``)
    modes : the mode set (closed forms as SymPy expressions)
    """

    scene: Scene
    model: object = field(repr=False)
    modes: object = field(repr=False)

    @property
    def chain(self) -> bool:
        return self.scene.chain is not None

    def to_json(self) -> dict:
        """Exactly what ``springchain modes SCENE --json`` prints."""
        if self.chain:
            from .derive.chain import chain_report

            return chain_report(self.model, self.modes, _chain_omega2(self.scene, self.modes))[1]
        from .derive.report import modes_json

        return modes_json(self.model, self.modes)

    def to_text(self) -> str:
        """What ``springchain modes SCENE`` prints."""
        if self.chain:
            from .derive.chain import chain_report

            return chain_report(self.model, self.modes, _chain_omega2(self.scene, self.modes))[0]
        from .derive.report import render_text

        return render_text(self.model, self.modes)

    def to_latex(self) -> str:
        """What ``springchain modes SCENE --latex`` prints (amsmath)."""
        if self.chain:
            from .derive.printing import latex

            return "\\begin{align*}\n\\omega_j^2 &= " + latex(self.modes.omega2) + "\n\\end{align*}\n" \
                if self.modes.omega2 is not None else self.to_text()
        from .derive.report import render_latex

        return render_latex(self.model, self.modes)

    @property
    def omega2(self) -> list:
        """ω² of each mode as SymPy expressions (ascending at the scene's values)."""
        return [m.omega2 for m in getattr(self.modes, "modes", ())]

    @property
    def omega2_values(self):
        """ω² at the scene's parameter values, ndarray, shape (number of distinct modes,)."""
        import numpy as np

        return np.array([rec["omega2_value"] for rec in self.to_json().get("modes", [])], dtype=float)

    @property
    def participation(self):
        """Modal participation in the ground direction (Γⱼ, Mⱼ*, fractions, mass-normalised shapes).

        A :class:`springchain.derive.participation.Participation` (values settled to float64 on the
        accurate route, closed forms where they exist); None for ``[chain]`` scenes and for scenes
        whose supports cannot move (no wall, no ``[ground]``).
        """
        from .derive import participation as part

        if self.chain or not part.applies(self.model):
            return None
        return part.participation(self.model, self.modes)

    def parse(self, text: str):
        """An ``omega2`` or ``shape`` string of :meth:`to_json` back as a SymPy expression.

        Built with the scene's own symbols (a parameter named ``E``, ``I``, ``S``, ``Q``,
        ``beta``, ``gamma`` ... stays that parameter), through the scene-expression
        whitelist; ``m.parse(m.to_json()["modes"][j]["omega2"]) == m.omega2[j]``.
        See :func:`parse_expression`.
        """
        return parse_expression(text, self.scene)

    def to_dataframe(self):
        """A ``pandas.DataFrame``, one row per listed mode: ``omega2`` (text), ``omega2_value``, ``omega``,
        ``multiplicity``, ``shape`` and ``shape_<mass>`` columns. Needs ``pip install "springchain[data]"``."""
        from ._data import modes_dataframe

        return modes_dataframe(self)

    def __str__(self) -> str:
        return self.to_text()

    def __repr__(self) -> str:  # short; str() and the notebook show everything
        return f"Modes(scene={self.scene.name!r}, omega2={self.omega2})"

    def _repr_latex_(self) -> str:
        text = self.to_latex()
        return text if text.lstrip().startswith(("$", "\\begin")) else f"$${text}$$"


def parse_expression(text: str, scene: str | Path | Scene):
    """Read an ``omega2`` or ``shape`` string printed by ``springchain modes --json`` back into SymPy.

    Parameters
    ----------
    text : str
        The printed string.
    scene : str, Path or Scene
        As for :func:`load`: its parameters are the only names accepted, as SymPy symbols
        with the derivation's assumptions (``sympify``/``parse_expr`` would read ``E``, ``I``,
        ``S``, ``Q``, ``beta``, ``gamma``, ``zeta`` as SymPy's own objects). The text goes
        through the same whitelist as scene expressions (plus ``acos``); nothing is evaluated.

    Returns
    -------
    sympy.Expr
        Equal to the derivation's expression; printed decimals (numeric modes) read back as
        the exact rationals of their text.

    Raises
    ------
    SceneError
        Naming the text and what is accepted.
    """
    from .derive.readback import parse_printed

    return parse_printed(text, load(scene))


def modes(scene: str | Path | Scene) -> Modes:
    """Derive a scene's equations of motion and normal modes (SymPy).

    Parameters
    ----------
    scene : str, Path or Scene
        As for :func:`load`.
    """
    from ._modules import derive

    from .numeric.progress import phase

    sc = load(scene)
    with phase(f"deriving {sc.name!r}"):
        d = derive(sc)
    return Modes(sc, d.model, d.modes)


# -- simulation -------------------------------------------------------------------------------------
def method_names() -> list[str]:
    """Every method :func:`simulate` takes by name, the exact one first."""
    from .numeric.methods import METHOD_NAMES

    return list(METHOD_NAMES)


@dataclass(frozen=True)
class Simulation:
    """Recorded trajectories of one or more methods on one scene.

    Attributes
    ----------
    scene : Scene
    t : ndarray, shape (S,)
        Recorded times ``t = i·dt``.
    x, v : dict of str to ndarray, shape (S, N)
        Positions and velocities per method (read from the NPZ for streamed ``[chain]`` runs).
    summary : dict
        What ``springchain simulate --json`` prints.
    npz : Path or None
        Where the trajectories were written, if they were.
    figures : tuple of Path
    """

    scene: Scene
    t: object = field(repr=False)
    x: dict = field(repr=False)
    v: dict = field(repr=False)
    summary: dict = field(repr=False)
    npz: Path | None = None
    figures: tuple[Path, ...] = ()
    #: Further arrays of the NPZ: ``aabs_<method>`` (and ``xabs_<method>``) for scenes with [ground].
    extra: dict = field(default_factory=dict, repr=False)

    @property
    def methods(self) -> list[str]:
        return list(self.x)

    def save(self, path: str | Path) -> Path:
        """Write the NPZ ``springchain simulate`` writes (``t``, ``x_<method>``, ``v_<method>``)."""
        from .numeric.simulate import save_npz

        path = Path(path)
        save_npz(path, self.t, self.x, self.v, self.extra)
        return path

    def drifts(self, method: str):
        """Drift ``x_b − x_a`` of every spring ``between = [a, b]`` (a wall is 0), ndarray, shape (S, springs) [m]."""
        from ._structural import spring_series

        return spring_series(self.scene, self.x[method])[0]

    def spring_forces(self, method: str):
        """Tension ``k·d + k3·d³`` (d the drift) of every spring: storey shears, shape (S, springs) [N]."""
        from ._structural import spring_series

        return spring_series(self.scene, self.x[method])[1]

    def base_shear(self, method: str):
        """Force of the wall springs on the ground (positive in +x), ndarray, shape (S,) [N]."""
        from ._structural import spring_series

        return spring_series(self.scene, self.x[method])[2]

    def plot(self, quantity: str = "x"):
        """A matplotlib Figure of every mass's position (``"x"``) or velocity (``"v"``), all methods
        (the first 12 masses; ``[chain]`` scenes: the profile at a few times)."""
        import numpy as np

        from .numeric import plots

        if quantity not in ("x", "v"):
            raise ValueError(f"quantity {quantity!r}: accepted: 'x' or 'v'")
        series = self.x if quantity == "x" else self.v
        label, unit = ("position x", "m") if quantity == "x" else ("velocity v", "m/s")
        if self.scene.chain is not None:  # a chain: its profile at a few recorded times (first method)
            first = next(iter(series.values()))
            rows = sorted({int(r) for r in np.linspace(0, first.shape[0] - 1, min(5, first.shape[0])).round()})
            fig = plots.profiles({float(self.t[r]): np.asarray(first[r]) for r in rows},
                                 "displacement x" if quantity == "x" else "velocity v", unit)
            fig.axes[0].set_title(f"{self.scene.name}: profile ({next(iter(series))}, {self.scene.n} masses)")
            return fig
        names = self.scene.mass_names if len(self.scene.mass_names) <= 12 else self.scene.mass_names[:12]
        cut = {m: s[:, : len(names)] for m, s in series.items()}
        return plots.trajectories(self.t, cut, names, label, unit,
                                  f"{self.scene.name}: {label.split()[0]}s (" + " vs ".join(series) + ")")

    def __repr__(self) -> str:
        return (f"Simulation(scene={self.scene.name!r}, methods={self.methods}, samples={len(self.t)}, "
                f"masses={self.scene.n})")

    # data out and notebook display (springchain._data, springchain._display)
    def to_xarray(self):
        """An ``xarray.Dataset``: dims ``time``, ``mass`` (mass names; indices for ``[chain]``), one variable per
        quantity and method (``x_modal``, ``v_verlet``, ...), attributes ``scene``, ``dt``, ``units``.
        Needs ``pip install "springchain[data]"``."""
        from ._data import simulation_xarray

        return simulation_xarray(self)

    def to_dataframe(self):
        """A long ``pandas.DataFrame``: columns ``method, quantity, time, mass, value, unit``."""
        from ._data import simulation_dataframe

        return simulation_dataframe(self)

    def _repr_html_(self) -> str:
        from ._display import simulation_html

        return simulation_html(self)

    def _repr_png_(self) -> bytes:
        from ._display import simulation_png

        return simulation_png(self)

    def _repr_mimebundle_(self, include=None, exclude=None) -> dict:  # both, from one drawing
        from ._display import simulation_bundle

        return simulation_bundle(self)


def _check_memory(scene: Scene, steps: int, record_every: int, methods: int, key: str) -> None:
    frames = steps // record_every + 1
    need = frames * scene.n * 8 * 2 * methods
    if need > MAX_RECORDED_BYTES:
        raise SceneError(scene.file, key,
                         f"{steps}: {steps} steps x {scene.n} masses (recorded every {record_every}, "
                         f"{methods} methods) would need {_human_bytes(need)} for the trajectories; "
                         f"accepted: at most {_human_bytes(MAX_RECORDED_BYTES)} - raise the recording "
                         f"stride (--record-every) or lower the steps (--steps)")


def _check_disk(scene: Scene, steps: int, record_every: int, methods: int, out: Path, key: str) -> None:
    frames = steps // record_every + 1
    need = frames * scene.n * 8 * 2 * methods
    probe = out
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    free = shutil.disk_usage(probe).free
    if need > 0.95 * free:
        raise SceneError(scene.file, key,
                         f"{steps}: {steps} steps x {scene.n} masses (recorded every {record_every}, "
                         f"{methods} methods) would write {_human_bytes(need)} into {out}, which has "
                         f"{_human_bytes(free)} free; accepted: a run that fits - raise the recording "
                         f"stride (--record-every), lower the steps (--steps) or choose another --out")


def simulate(scene: str | Path | Scene, methods: list[str] | None = None, dt: float | None = None,
             steps: int | None = None, record_every: int | None = None, *, spectrum: str = "svd",
             rtol: float = 1e-10, atol: float = 1e-12, out: str | Path | None = None,
             figures: bool = False, progress: bool | None = None, springs: bool = False) -> Simulation:
    """Simulate a scene from its initial state with exact and numerical methods.

    Parameters
    ----------
    scene : str, Path or Scene
        As for :func:`load`.
    methods : list of str, optional
        Names from :func:`method_names`. Default: the exact ``modal`` solution and ``verlet``
        for linear scenes with an exact solution, ``verlet`` otherwise.
    dt, steps, record_every : optional
        Override the scene's ``[simulation]`` values. Times are ``t = i·dt``.
    spectrum : {"svd", "closed-form"}
        Modes of the exact solution: the spring-factor SVD (accurate) or the generated closed forms.
    rtol, atol : float
        Tolerances of the adaptive methods (``rk45``, ``dop853``, ``lsoda``).
    out : str or Path, optional
        Folder for ``<scene>.npz`` (and figures with ``figures=True``). ``[chain]`` scenes stream
        their frames to disk, into ``out`` or ``springchain-out``.
    figures : bool
        Write PNG figures into ``out``.
    progress : bool, optional
        Progress on stderr of every phase longer than about a second (default: on; a bar on a
        terminal, a plain line every few seconds otherwise). ``False`` silences it.
    springs : bool
        Add ``drift_<method>``, ``spring_force_<method>`` (S × springs) and ``base_shear_<method>``
        (S,) to ``extra`` and the NPZ (``[masses]`` scenes).

    Returns
    -------
    Simulation
    """
    import time

    import numpy as np

    from .numeric.errors import RunRefused
    from .numeric import simulate as sim

    sc = load(scene)
    _check_motion(sc, "simulate")
    dt = dt if dt is not None else sc.dt
    steps = steps if steps is not None else sc.steps
    record_every = record_every if record_every is not None else sc.record_every
    if not (isinstance(dt, float | int) and math.isfinite(dt) and dt > 0):
        raise RunRefused(f"dt {dt!r}: accepted: a finite number > 0", quantity="dt")
    for what, value in (("steps", steps), ("record_every", record_every)):
        if not (isinstance(value, int | np.integer) and value > 0):
            raise RunRefused(f"{what} {value!r}: accepted: a whole number > 0", quantity=what)
    if sc.chain is None:  # refuse before any derivation when even one method would not fit
        _check_memory(sc, steps, record_every, len(methods) if methods else 1, "steps")
    from .numeric.progress import phase

    with phase("loading the generated module (deriving it if not cached)", enabled=progress):
        system, origin = _system(sc)
    names = methods or sim.default_methods(system)
    notes: list[str] = []
    if not methods:  # a default Verlet that would be unstable at this dt gives way to the exact method
        names, notes = sim.unstable_defaults(system, names, dt)
    unknown = [m for m in names if m not in method_names()]
    if unknown:
        raise RunRefused(f"method {unknown[0]!r} is unknown; accepted: {', '.join(method_names())}",
                         quantity="method")
    if spectrum not in ("svd", "closed-form"):
        raise RunRefused(f"spectrum {spectrum!r}: accepted: 'svd' or 'closed-form'", quantity="spectrum")
    t0 = time.perf_counter()
    if springs and system.chain:
        raise RunRefused("springs: the drift and spring-force arrays of a [chain] scene are not written yet "
                         "(streamed runs); accepted: a [masses] scene", quantity="springs")
    if system.chain:
        out = Path(out if out is not None else DEFAULT_OUT)
        _check_disk(sc, steps, record_every, len(names), out, "steps")
        out.mkdir(parents=True, exist_ok=True)
        summary = sim.stream_methods(system, sc.x0, sc.v0, dt, steps, names, record_every, out, sc.name,
                                     figures=figures, progress=progress)
        npz = Path(summary["npz"])
        figs = tuple(Path(p) for p in summary["figures"])
        data = np.load(npz)
        t = data["t"]
        x = {m: data[f"x_{m}"] for m in names}
        v = {m: data[f"v_{m}"] for m in names}
        extra = {k: data[k] for k in data.files if k.startswith(("aabs_", "xabs_"))}
    else:
        _check_memory(sc, steps, record_every, len(names), "steps")
        runs = sim.run_methods(system, sc.x0, sc.v0, dt, steps, names, record_every,
                               spectrum_source=spectrum, rtol=rtol, atol=atol, progress=progress)
        summary = sim.compare(system, runs)
        t = next(iter(runs.values())).t
        x = {m: r.x for m, r in runs.items()}
        v = {m: r.v for m, r in runs.items()}
        npz, figs = None, ()
        extra = sim.absolute_npz_arrays(system, t, x, v)
        if springs:
            from ._structural import spring_series

            for m in names:
                extra[f"drift_{m}"], extra[f"spring_force_{m}"], extra[f"base_shear_{m}"] = spring_series(sc, x[m])
        if out is not None:
            out = Path(out)
            out.mkdir(parents=True, exist_ok=True)
            npz = out / f"{sc.name}.npz"
            with phase(f"writing {npz.name}", enabled=progress):
                sim.save_npz(npz, t, x, v, extra)
            if figures:
                with phase("figures", enabled=progress):
                    figs = tuple(sim.write_figures(out, sc.name, sc.mass_names, system, runs))
    summary.update({"scene": sc.name, "module": origin, "dt": dt, "steps": steps, "t_end": steps * dt,
                    "npz": None if npz is None else str(npz), "figures": [str(p) for p in figs],
                    "methods_that_apply": sim.applicable(system),
                    "energy_conserved": not (system.damped or system.forced),
                    "seconds": time.perf_counter() - t0, "notes": notes})
    return Simulation(sc, t, x, v, summary, npz, figs, extra)


# -- plan and bench ---------------------------------------------------------------------------------
def _check_motion(sc: Scene, what: str) -> None:
    """Refuse a run whose answer is known: no ``[initial]`` and nothing driving the scene."""
    from .numeric.errors import RunRefused

    if not sc.initial_given and not sc.loaded:
        raise RunRefused(f"{sc.file}: initial: missing; {what} of {sc.name!r} would start at rest with nothing "
                         "driving it (its motion is zero); accepted: a table [initial] with x = [...] and/or "
                         "v = [...] (modes and derive do not need one)", quantity="initial")


def _horizon(sc: Scene, t_end: float | None) -> float:
    return t_end if t_end is not None else sc.dt * sc.steps


def plan(scene: str | Path | Scene, tol: float, t_end: float | None = None):
    """The cheapest method and step (or tolerance) to keep the largest position error below ``tol``.

    Parameters
    ----------
    scene : str, Path or Scene
    tol : float
        Largest position error allowed over ``t = 0 ... t_end``.
    t_end : float, optional
        Horizon (default: the scene's ``dt·steps``).

    Returns
    -------
    springchain.numeric.plan.Plan
        ``.recommended``, ``.candidates``, ``.unreachable`` and ``.as_json()``.
    """
    from .numeric.errors import RunRefused
    from .numeric.plan import Planner
    from .numeric.timing import single_threaded_blas

    if not (isinstance(tol, float | int) and math.isfinite(tol) and tol > 0):
        raise RunRefused(f"tol {tol!r}: accepted: a finite number > 0", quantity="tol")
    sc = load(scene)
    _check_motion(sc, "plan")
    system, _ = _system(sc)
    from .numeric.plan_pilot import PilotPlanner, needs_pilot

    with single_threaded_blas():
        # damped, forced, gravity, ground scenes and long uniform chains: calibrated against the exact solution
        planner = (PilotPlanner if needs_pilot(system) else Planner).for_system(
            system, sc.x0, sc.v0, _horizon(sc, t_end), sc.dt * sc.record_every)
        try:
            return planner.plan(tol)
        except ValueError as exc:
            raise RunRefused(f"tol {tol:g}: {exc}", quantity="tol") from None


def bench(scene: str | Path | Scene = "seed", t_end: float | None = None, *, quick: bool = False,
          methods: list[str] | None = None, progress: bool = False):
    """Work-precision benchmark: every method's error against an exact reference, and its cost.

    Returns
    -------
    springchain.numeric.bench.BenchResult
        ``.records``, ``.targets`` and ``.as_json()``; write its files with
        :func:`springchain.numeric.bench.write_outputs`.
    """
    import time

    from ._modules import derive
    from .numeric.bench import BenchConfig, run_bench, with_derive_seconds
    from .numeric.timing import single_threaded_blas

    sc = load(scene)
    _check_motion(sc, "bench")
    system, _ = _system(sc)
    import sympy  # noqa: F401  (imported before timing: the derive time excludes the SymPy import)

    t0 = time.perf_counter()
    derive(sc)
    derive_seconds = time.perf_counter() - t0
    config = BenchConfig.quick_config() if quick else BenchConfig()
    with single_threaded_blas():
        result = run_bench(system, sc.x0, sc.v0, _horizon(sc, t_end), sc.dt * sc.record_every, sc.name,
                           config, progress=progress, methods=tuple(methods or ()) or None)
    return with_derive_seconds(result, derive_seconds)


def sweep(*args, **kwargs):
    """Ensembles and parameter studies on Dask: see :func:`springchain._sweep.sweep`."""
    from ._sweep import sweep as _sweep

    return _sweep(*args, **kwargs)


__all__ = ["load", "modes", "simulate", "plan", "bench", "sweep", "method_names", "Modes", "Simulation",
           "MAX_RECORDED_BYTES"]
