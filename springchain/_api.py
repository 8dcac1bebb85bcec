"""The Python API: what every ``springchain`` command does, callable from a notebook or a script.

The command line (:mod:`springchain.cli`) only parses flags, calls these and prints.
Heavy packages (SymPy, SciPy, matplotlib) are imported by the function that needs them.
"""

from __future__ import annotations

import functools
import math
import shutil
from dataclasses import dataclass, field
from pathlib import Path

from ._modules import system_of
from ._defaults import DEFAULT_OUT
from ._scenes import load
from .derive.errors import SceneError
from .derive.scene import Scene
from .numeric.io.files import human_bytes as _human_bytes
from .numeric.run.protocol import DEFAULT_ATOL, DEFAULT_RTOL

#: The most memory a simulation's recorded trajectories may take (in-memory runs).
MAX_RECORDED_BYTES = 4 * 2**30


# -- modes ------------------------------------------------------------------------------------------
def _chain_omega2(scene: Scene, chain_modes):
    """ω² of a chain without closed form (None when too large): every value from the generated
    module's ``omega2()`` for a chain whose modes are all listed, else ``{position: ω²}`` of the
    listed lowest and highest only (:func:`numeric.modes.chain.extreme_omega2`)."""
    if chain_modes.omega2 is not None:
        return None
    from .derive.chain import MAX_MODES_LISTED, MODES_LISTED_EACH_END
    from .generated.contract import End

    system, _ = system_of(scene)
    n = scene.chain.n
    if n > MAX_MODES_LISTED and system.ends[0] is not End.RING:
        from .numeric.modes.chain import extreme_omega2
        from .numeric.progress import phase

        e = MODES_LISTED_EACH_END
        with phase(f"modes: the {e} lowest and {e} highest of {n} (bisection on the spring factor)"):
            return extreme_omega2(system.masses, system.spring_ends, system.stiffness, e)
    try:
        return system.omega2()
    except ValueError:  # a non-uniform ring longer than the module's MAX_DENSE
        return None


def _chain_damped(scene: Scene, model):
    """``(ω_n, ζ, ω_d)`` of every mode of a chain with dashpots (:func:`numeric.modes.chain_damping.
    chain_damped_rows`), else None (Rayleigh-only damping has a closed form)."""
    if not getattr(model, "dampers", None):
        return None
    from .numeric.modes.chain_damping import chain_damped_rows

    return chain_damped_rows(system_of(scene)[0])


def _chain_shapes(scene: Scene, chain_modes):
    """The mode shapes of a chain without closed-form modes whose modes are all listed (at most
    ``MAX_MODES_LISTED`` masses), one row per mode in ascending ω² (:func:`numeric.structural.
    modal_quantities.chain_mode_shapes`); else None (a closed form gives its own values)."""
    from .derive.chain import MAX_MODES_LISTED

    if chain_modes.omega2 is not None or scene.chain.n > MAX_MODES_LISTED:
        return None
    from .numeric.structural.modal_quantities import chain_mode_shapes

    return chain_mode_shapes(system_of(scene)[0])[1]


def _chain_participation(scene: Scene, model):
    """Γⱼ, Mⱼ* and mass-normalised shapes of an open chain with a wall end or ``[ground]`` whose modes are
    all listed (at most ``MAX_MODES_LISTED`` masses), from
    :func:`numeric.structural.modal_quantities.chain_participation`; else None."""
    from .derive import participation as part
    from .derive.chain import MAX_MODES_LISTED

    if not part.chain_applies(model) or scene.chain.n > MAX_MODES_LISTED or "ring" in (scene.chain.left,
                                                                                        scene.chain.right):
        return None
    from .numeric.structural.modal_quantities import chain_participation

    omega2, gamma, shapes, total = chain_participation(system_of(scene)[0])
    return part.from_values(omega2, gamma, shapes, total, "spring-factor SVD (float64, compensated sums)")


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

    @functools.cached_property
    def _chain_report(self) -> tuple[str, dict]:
        """A ``[chain]`` scene's text and JSON reports, computed once (ζ of a damped chain can take seconds)."""
        from .derive.chain import chain_report

        return chain_report(self.model, self.modes, _chain_omega2(self.scene, self.modes),
                            _chain_damped(self.scene, self.model), self._chain_participation,
                            _chain_shapes(self.scene, self.modes))

    @functools.cached_property
    def _chain_participation(self):
        """A chain's participation as the numeric side computes it (signed as its report prints it by
        :attr:`participation`), computed once."""
        return _chain_participation(self.scene, self.model)

    @functools.cached_property
    def bands(self):
        """The modes of a periodic scene's finite chain named by band and q, or as gap modes
        (:class:`springchain._mode_bands.ModeBands`); None for a scene without a unit cell."""
        from ._mode_bands import mode_bands

        return mode_bands(self.scene, uniform_chain=self.chain and bool(self.model.chain.uniform))

    def to_json(self) -> dict:
        """Exactly what ``springchain modes SCENE --json`` prints.

        A periodic scene's listed modes also carry ``band``, ``q`` (rad per cell), ``kind`` (``band``, ``edge``
        or ``defect``), ``localisation_length`` (cells, gap modes) and ``bloch_weight`` (band modes), as
        ``springchain bands`` names them (up to :data:`springchain._mode_bands.MAX_MASSES` masses).
        """
        if self.chain:
            import copy

            data = copy.deepcopy(self._chain_report[1])  # the caller may edit its dict
        else:
            from .derive.report import modes_json

            data = modes_json(self.model, self.modes)
        b = self.bands
        if b is not None:
            from .derive.chain import MODES_LISTED_EACH_END

            b.records(data["modes"], self.scene.n, MODES_LISTED_EACH_END)
            if b.labels is not None:
                data["gap_modes"] = b.gap_modes()
            data["notes"].append(b.note or f"modes named by band: band and q (rad per cell) of the unit cell of "
                                            f"{b.p} masses (springchain bands), or a gap mode's kind and "
                                            "localisation length (cells)")
        return data

    def to_text(self) -> str:
        """What ``springchain modes SCENE`` prints (a periodic scene's modes named by band at the end)."""
        if self.chain:
            text = self._chain_report[0]
        else:
            from .derive.report import render_text

            text = render_text(self.model, self.modes)
        b = self.bands
        if b is None:
            return text
        from .derive.chain import MODES_LISTED_EACH_END

        return text + "\n".join(b.text_lines(MODES_LISTED_EACH_END)).lstrip("\n").join(["\n", "\n"])

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
        accurate route, closed forms where they exist; values only for open ``[chain]`` scenes of at most
        40 masses); None for scenes whose supports cannot move (no wall, no ``[ground]``), rings and
        longer chains.
        """
        from .derive import participation as part

        if self.chain:
            p = self._chain_participation
            return None if p is None else part.signed_as_printed(p, self._chain_report[1]["modes"])
        if not part.applies(self.model):
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
    if sc.chain is not None:
        from .derive.chain import check_modes_apply

        check_modes_apply(d.model)  # a cubic chain under a constant load: one line
    return Modes(sc, d.model, d.modes)


# -- simulation -------------------------------------------------------------------------------------
def method_names() -> list[str]:
    """Every method :func:`simulate` takes by name, the exact one first."""
    from .numeric.run import registry

    return list(registry.names())


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
        from .numeric.io.npz import save_npz

        path = Path(path)
        save_npz(path, self.t, self.x, self.v, self.extra)
        return path

    def _spring_series(self, method: str):
        """(drift, spring force, base shear) of ``method``'s trajectory (:func:`numeric.structural.storeys.series`: the
        exact method's by the load path where the springs form a tree with the ground)."""
        from .numeric.run import registry
        from .numeric.structural.storeys import series

        exact = (self.scene.x0, self.scene.v0, self.t) if method == registry.EXACT else None
        return series(system_of(self.scene)[0], self.x[method], exact)[:3]

    def drifts(self, method: str):
        """Drift ``x_b − x_a`` of every spring ``between = [a, b]`` (a wall is 0), ndarray, shape (S, springs) [m]."""
        return self._spring_series(method)[0]

    def spring_forces(self, method: str):
        """Tension ``k·d + k3·d³`` (``V'(d)`` for a spring potential; d the drift) of every spring: storey
        shears, shape (S, springs) [N]. The exact method's come from the load path where positions would
        round them (:mod:`numeric.structural.storeys`)."""
        return self._spring_series(method)[1]

    def base_shear(self, method: str):
        """Force of the wall springs on the ground (positive in +x), ndarray, shape (S,) [N]."""
        return self._spring_series(method)[2]

    def plot(self, quantity: str = "x"):
        """A matplotlib Figure of every mass's position (``"x"``) or velocity (``"v"``), all methods
        (the first 12 masses; ``[chain]`` scenes: the profile at a few times)."""
        import numpy as np

        from .numeric.plots import figures as plots

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


def _recorded(scene: Scene, steps: int, record_every: int, methods: int) -> tuple[int, str]:
    """Bytes of the recorded trajectories, and how the run is described in a refusal."""
    need = (steps // record_every + 1) * scene.n * 8 * 2 * methods
    return need, (f"{steps}: {steps} steps x {scene.n} masses (recorded every {record_every}, {methods} methods) "
                  f"would {{}} {_human_bytes(need)}")


def _check_memory(scene: Scene, steps: int, record_every: int, methods: int, key: str) -> None:
    need, what = _recorded(scene, steps, record_every, methods)
    if need > MAX_RECORDED_BYTES:
        raise SceneError(scene.file, key,
                         what.format("need") + f" for the trajectories; accepted: at most "
                         f"{_human_bytes(MAX_RECORDED_BYTES)} - raise the recording stride (--record-every) or "
                         f"lower the steps (--steps)")


def _check_disk(scene: Scene, steps: int, record_every: int, methods: int, out: Path, key: str) -> None:
    need, what = _recorded(scene, steps, record_every, methods)
    probe = out
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    free = shutil.disk_usage(probe).free
    if need > 0.95 * free:
        raise SceneError(scene.file, key,
                         what.format("write") + f" into {out}, which has {_human_bytes(free)} free; accepted: a run "
                         f"that fits - raise the recording stride (--record-every), lower the steps (--steps) or "
                         f"choose another --out")


def _check_settings(chosen, options) -> None:
    """Refuse a setting (``alpha``) that none of the chosen methods takes, naming those that do."""
    from .numeric.errors import RunRefused
    from .numeric.run import registry

    for key, value in options.settings:
        if not any(key in m.takes for m in chosen):
            takers = [m.name for m in registry.methods(options=options) if key in m.takes]
            raise RunRefused(f"{key} {value!r}: a setting of {' and '.join(takers)}, not of "
                             f"{', '.join(m.name for m in chosen)}; accepted: with the method {' or '.join(takers)}",
                             quantity=key)


def _method_settings(alpha: float | None, names=None) -> tuple:
    """The run's method settings (HHT's ``alpha``) as :attr:`Options.settings`, checked once for
    simulate, plan and bench: out of range, or taken by none of ``names`` (default: every method), refused."""
    from .numeric.run import registry
    from .numeric.run.protocol import Options

    options = Options(progress=False, settings={} if alpha is None else {"alpha": alpha})
    if not options.settings:  # nothing to check (and no method to import)
        return options.settings
    chosen = [registry.method(name, options) for name in (names or registry.names())]  # refuses a bad value
    _check_settings(chosen, options)
    return options.settings


def _grid_settings(sc: Scene, dt, steps, record_every) -> tuple[float, int, int]:
    """The run's step, steps and recording stride: the arguments, else the scene's; refused when not
    a finite dt > 0 and whole numbers > 0."""
    import numpy as np

    from .numeric.errors import RunRefused

    dt = dt if dt is not None else sc.dt
    steps = steps if steps is not None else sc.steps
    record_every = record_every if record_every is not None else sc.record_every
    if not (isinstance(dt, float | int) and math.isfinite(dt) and dt > 0):
        raise RunRefused(f"dt {dt!r}: accepted: a finite number > 0", quantity="dt")
    for what, value in (("steps", steps), ("record_every", record_every)):
        if not (isinstance(value, int | np.integer) and value > 0):
            raise RunRefused(f"{what} {value!r}: accepted: a whole number > 0", quantity=what)
    return dt, steps, record_every


def _streamed(sc: Scene, system, names, dt, steps, record_every, out, figures, options):
    """A ``[chain]`` run streamed into ``out`` (bounded memory), read back from its NPZ."""
    import numpy as np

    from .numeric.run.simulate import stream_methods

    out = Path(out if out is not None else DEFAULT_OUT)
    _check_disk(sc, steps, record_every, len(names), out, "steps")
    out.mkdir(parents=True, exist_ok=True)
    summary = stream_methods(system, sc.x0, sc.v0, dt, steps, names, record_every, out, sc.name,
                             figures=figures, progress=options.progress, settings=options.settings)
    npz = Path(summary["npz"])
    data = np.load(npz)
    extra = {k: data[k] for k in data.files if k.startswith(("aabs_", "xabs_"))}
    return (summary, data["t"], {m: data[f"x_{m}"] for m in names}, {m: data[f"v_{m}"] for m in names}, extra,
            npz, tuple(Path(p) for p in summary["figures"]))


def _spring_arrays(system, x: dict, exact: tuple | None = None) -> tuple[dict, list[str]]:
    """NPZ arrays ``drift_<method>``, ``spring_force_<method>`` (S × springs) and ``base_shear_<method>``
    (S,) of every method's frames ``x[method]`` (S, N) (:func:`numeric.structural.storeys.series`; ``exact = (x0, v0,
    t)``: the exact method's by the load path), and the notes of those whose float64 rounding of drifts
    formed from positions exceeds :data:`numeric.structural.storeys.FORCE_ROUNDING` of the largest force."""
    from .numeric.run import registry
    from .numeric.structural.storeys import rounding_note, series

    out, notes = {}, []
    for m, xm in x.items():
        drift, force, base, bound = series(system, xm, exact if m == registry.EXACT else None)
        out[f"drift_{m}"], out[f"spring_force_{m}"], out[f"base_shear_{m}"] = drift, force, base
        note = rounding_note(m, bound)
        if note is not None:
            notes.append(note)
    return out, notes


def _notes_array(notes: list[str]) -> dict:
    """``{"notes": array of str}`` for the NPZ when there are notes (the float64-limit line), else {}."""
    import numpy as np

    return {"notes": np.array(notes, dtype=str)} if notes else {}


def _kept(sc: Scene, system, names, dt, steps, record_every, options, out, figures, springs=False, notes=()):
    """An in-memory run; the NPZ (and figures) written into ``out`` when given; with ``springs`` the
    drift, spring-force and base-shear arrays of every method among its NPZ arrays, with ``notes``
    a ``notes`` array of str (the float64-limit line, also in the summary)."""
    from .numeric.exact.absolute import absolute_npz_arrays
    from .numeric.run.compare import compare
    from .numeric.progress import phase
    from .numeric.run.simulate import non_finite_notes, quiet_floats, run_methods

    _check_memory(sc, steps, record_every, len(names), "steps")
    runs = run_methods(system, sc.x0, sc.v0, dt, steps, names, record_every, spectrum_source=options.spectrum,
                       rtol=options.rtol, atol=options.atol, progress=options.progress, settings=options.settings)
    diverged = non_finite_notes(runs)
    notes = list(notes) + diverged
    t = next(iter(runs.values())).t
    x, v = {m: r.x for m, r in runs.items()}, {m: r.v for m, r in runs.items()}
    spring_notes = []
    with quiet_floats(bool(diverged)):  # a run that left the finite numbers is said once, in its note
        extra = absolute_npz_arrays(system, t, x, v)
        if springs:
            arrays, spring_notes = _spring_arrays(system, x, (sc.x0, sc.v0, t))
            extra.update(arrays)
        extra.update(_notes_array(notes + spring_notes))
        npz, figs = None, ()
        if out is not None:
            from .numeric.io.npz import save_npz

            out = Path(out)
            out.mkdir(parents=True, exist_ok=True)
            npz = out / f"{sc.name}.npz"
            with phase(f"writing {npz.name}", enabled=options.progress):
                save_npz(npz, t, x, v, extra)
            if figures:
                from .numeric.plots.simulation import write_figures

                with phase("figures", enabled=options.progress):
                    figs = tuple(write_figures(out, sc.name, sc.mass_names, system, runs))
        summary = compare(system, runs)
    summary["diverged"] = diverged
    summary["spring_notes"] = spring_notes
    return summary, t, x, v, extra, npz, figs


def _modal_energies(sc: Scene, system, t, x, v, extra, npz, figs, figures, progress):
    """``modal_energy_<method>`` into ``extra`` (and the NPZ, rewritten), the figure with ``figures``;
    returns the summary's ``modal_energy`` entry and the figures."""
    from .numeric.exact.modal_energy import modal_energy_figure, modal_energy_record
    from .numeric.io.npz import save_npz
    from .numeric.progress import phase

    with phase("modal energies", enabled=progress):
        energies, omega = modal_energy_record(system, x, v)
        extra.update(energies)
        if npz is not None:
            save_npz(npz, t, x, v, extra)
        if figures and npz is not None:
            figs = tuple(figs) + (modal_energy_figure(Path(npz).parent, sc.name, t, energies, omega),)
    return ({m[len("modal_energy_"):]: {"initial": e[0].tolist()[:10], "final": e[-1].tolist()[:10]}
             for m, e in energies.items()}, figs)


def simulate(scene: str | Path | Scene, methods: list[str] | None = None, dt: float | None = None,
             steps: int | None = None, record_every: int | None = None, *, spectrum: str = "svd",
             rtol: float = DEFAULT_RTOL, atol: float = DEFAULT_ATOL, out: str | Path | None = None,
             figures: bool = False, progress: bool | None = None, modal_energy: bool = False,
             springs: bool = False, alpha: float | None = None) -> Simulation:
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
        Tolerances of the adaptive methods (``rk45``, ``dop853``, ``lsoda``, ``dprkn6/8/12``).
    out : str or Path, optional
        Folder for ``<scene>.npz`` (and figures with ``figures=True``). ``[chain]`` scenes stream
        their frames to disk, into ``out`` or :data:`DEFAULT_OUT` (``springchain-out``).
    figures : bool
        Write PNG figures into ``out``.
    progress : bool, optional
        Progress on stderr of every phase longer than about a second (default: on; a bar on a
        terminal, a plain line every few seconds otherwise). ``False`` silences it.
    modal_energy : bool
        Also record ``modal_energy_<method>`` (S × N): the harmonic energy ½(q̇ⱼ² + ωⱼ² qⱼ²) of each
        linear normal mode about the equilibrium, ascending ω (:mod:`numeric.exact.modal_energy`), in
        ``extra`` and the NPZ, and with ``figures`` the figure ``<scene>-modal-energy.png``.
    springs : bool
        Add ``drift_<method>``, ``spring_force_<method>`` (S × springs) and ``base_shear_<method>``
        (S,) to ``extra`` and the NPZ.
    alpha : float, optional
        HHT-α's α in [−1/3, 0] (default −0.05) for ``hht``; refused when no chosen method takes it.

    Returns
    -------
    Simulation
    """
    import time

    from .numeric.run import simulate as sim
    from .numeric.progress import phase
    from .numeric.run import registry
    from .numeric.run.protocol import Options

    sc = load(scene)
    _check_motion(sc, "simulate")
    dt, steps, record_every = _grid_settings(sc, dt, steps, record_every)
    if sc.chain is None:  # refuse before any derivation when even one method would not fit
        _check_memory(sc, steps, record_every, len(methods) if methods else 1, "steps")
    for name in methods or ():  # refusals before any work: their one line stands alone
        registry.entry(name)  # unknown names: one line naming the accepted ones
    # refuses an unknown spectrum source, and settings out of range (the methods check them when made)
    options = Options(rtol, atol, spectrum, progress, _method_settings(alpha))
    for name in methods or ():
        registry.method(name, options)  # before any derivation
    with phase("loading the generated module (deriving it if not cached)", enabled=progress):
        system, origin = system_of(sc)
    _check_motion(sc, "simulate", system)
    names, notes = methods, []
    if not methods:  # a default Verlet that would be unstable at this dt gives way to the exact method
        names, notes = sim.unstable_defaults(system, sim.default_methods(system), dt)
    _check_settings([registry.method(name, options) for name in names], options)
    limits = sim.float64_limits(system, names, steps * dt)  # one line where float64 cannot follow
    t0 = time.perf_counter()
    if system.chain:
        summary, t, x, v, extra, npz, figs = _streamed(sc, system, names, dt, steps, record_every, out, figures,
                                                       options)
        if springs:  # from the frames read back
            arrays, summary["spring_notes"] = _spring_arrays(system, x)
            extra.update(arrays)
        if springs or limits or summary["diverged"]:  # the NPZ rewritten with them
            from .numeric.io.npz import save_npz

            extra.update(_notes_array(limits + summary["diverged"] + summary.get("spring_notes", [])))
            save_npz(npz, t, x, v, extra)
    else:
        summary, t, x, v, extra, npz, figs = _kept(sc, system, names, dt, steps, record_every, options, out, figures,
                                                   springs, limits)
    if modal_energy:
        summary["modal_energy"], figs = _modal_energies(sc, system, t, x, v, extra, npz, figs, figures, progress)
    notes = notes + limits + summary.pop("diverged", []) + summary.pop("spring_notes", [])
    summary.update({"scene": sc.name, "module": origin, "dt": dt, "steps": steps, "t_end": steps * dt,
                    "npz": None if npz is None else str(npz), "figures": [str(p) for p in figs],
                    "methods_that_apply": sim.applicable(system),
                    "energy_conserved": system.energy_conserved,
                    "seconds": time.perf_counter() - t0, "notes": notes})
    return Simulation(sc, t, x, v, summary, npz, figs, extra)


# -- plan and bench ---------------------------------------------------------------------------------
def _check_motion(sc: Scene, what: str, system=None) -> None:
    """Refuse a run whose answer is known: no ``[initial]`` (it starts at rest at x = 0), nothing driving
    the scene, and x = 0 its equilibrium. With spring potentials x = 0 need not be the equilibrium (a
    pre-stressed spring, V'(0) ≠ 0, out of balance): such a scene moves, and is decided once its
    equilibrium is known (``system``; called without it before the derivation, with it after)."""
    from .numeric.errors import RunRefused

    if sc.initial_given or sc.loaded:
        return
    if sc.has_potential:
        if system is None:
            return
        x_eq = system.potential_equilibrium()
        if x_eq is not None and bool((x_eq != 0.0).any()):
            return  # released at rest away from its equilibrium: it oscillates about x_eq
    raise RunRefused(f"{sc.file}: initial: missing; {what} of {sc.name!r} would start at rest at its equilibrium "
                     "x = 0 with nothing driving it (its motion is zero); accepted: a table [initial] with "
                     "x = [...] and/or v = [...] (modes and derive do not need one)", quantity="initial")


def _horizon(sc: Scene, t_end: float | None) -> float:
    return t_end if t_end is not None else sc.dt * sc.steps


def plan(scene: str | Path | Scene, tol: float, t_end: float | None = None, *, alpha: float | None = None):
    """The cheapest method and step (or tolerance) to keep the largest position error below ``tol``.

    Parameters
    ----------
    scene : str, Path or Scene
    tol : float
        Largest position error allowed over ``t = 0 ... t_end``.
    t_end : float, optional
        Horizon (default: the scene's ``dt·steps``).
    alpha : float, optional
        HHT-α's α for the method ``hht`` (−1/3 ≤ α ≤ 0; default −0.05), as in :func:`simulate`.

    Returns
    -------
    springchain.numeric.plan.planner.Plan
        ``.recommended``, ``.candidates``, ``.unreachable`` and ``.as_json()``.
    """
    from .numeric.errors import RunRefused
    from .numeric.plan.planner import Planner
    from .numeric.bench.timing import single_threaded_blas

    if not (isinstance(tol, float | int) and math.isfinite(tol) and tol > 0):
        raise RunRefused(f"tol {tol!r}: accepted: a finite number > 0", quantity="tol")
    settings = _method_settings(alpha)
    sc = load(scene)
    _check_motion(sc, "plan")
    system, _ = system_of(sc)
    _check_motion(sc, "plan", system)
    from .numeric.plan.pilot import PilotPlanner, needs_pilot, tight_reference_applies

    with single_threaded_blas():
        # damped, forced, gravity, ground scenes and long uniform chains: calibrated against the exact solution;
        # nonlinear (cubic, potential) scenes: against a tight DOP853 reference
        pilot = needs_pilot(system) or tight_reference_applies(system)
        planner = (PilotPlanner if pilot else Planner).for_system(
            system, sc.x0, sc.v0, _horizon(sc, t_end), sc.dt * sc.record_every, settings=settings)
        try:
            return planner.plan(tol)
        except ValueError as exc:
            raise RunRefused(f"tol {tol:g}: {exc}", quantity="tol") from None


def bench(scene: str | Path | Scene = "seed", t_end: float | None = None, *, quick: bool = False,
          methods: list[str] | None = None, progress: bool = False, alpha: float | None = None):
    """Work-precision benchmark: every method's error against an exact reference, and its cost.

    ``alpha``: HHT-α's α for the method ``hht`` (as in :func:`simulate`).

    Returns
    -------
    springchain.numeric.bench.workprecision.BenchResult
        ``.records``, ``.targets`` and ``.as_json()``; write its files with
        :func:`springchain.numeric.bench.workprecision.write_outputs`.
    """
    import time

    from ._modules import derive
    from .numeric.bench.workprecision import BenchConfig, run_bench, with_derive_seconds
    from .numeric.bench.timing import single_threaded_blas

    settings = _method_settings(alpha, methods)
    sc = load(scene)
    _check_motion(sc, "bench")
    system, _ = system_of(sc)
    _check_motion(sc, "bench", system)
    import sympy  # noqa: F401  (imported before timing: the derive time excludes the SymPy import)

    t0 = time.perf_counter()
    derive(sc)
    derive_seconds = time.perf_counter() - t0
    config = BenchConfig.quick_config() if quick else BenchConfig()
    from .numeric.compiled.run import eager

    with single_threaded_blas(), eager(not quick):  # the full bench compiles its loops once (a warm-up)
        result = run_bench(system, sc.x0, sc.v0, _horizon(sc, t_end), sc.dt * sc.record_every, sc.name,
                           config, progress=progress, methods=tuple(methods or ()) or None, settings=settings)
    return with_derive_seconds(result, derive_seconds)


# -- generated modules -------------------------------------------------------------------------------
@dataclass(frozen=True)
class Generated:
    """One scene's generated module, written or checked (see :func:`generate`)."""

    scene: Scene
    path: Path  #: where the module is
    fresh: bool | None  #: with ``check``, whether it equals a fresh render; None when it was written
    lines: int | None  #: lines written (None with ``check``)
    seconds: float
    message: str = ""  #: ``"<path>: fresh"``, ``"<path>: stale (run ...)"``, ``"<path>: missing (run ...)"``


def generate(scenes=(), out: str | Path | None = None, *, check: bool = False) -> list[Generated]:
    """What ``springchain derive`` does: write the generated module of each scene into ``out``, or
    (``check``) compare it with a fresh render. (``springchain.derive`` is the symbolic subpackage,
    so the function is called ``generate``.)

    Parameters
    ----------
    scenes : iterable of (str, Path or Scene)
        As for :func:`load`; empty: every bundled scene. All are loaded before anything is written.
    out : str or Path, optional
        Folder of the modules, written or checked (default ``./generated``: ``check`` reads where
        writing writes).
    check : bool
        Write nothing; report whether each module on disk is fresh.

    Returns
    -------
    list of Generated
    """
    import time

    from . import _modules
    from ._scenes import bundled_scenes
    from .numeric.progress import phase

    sources = list(scenes) or bundled_scenes()
    if not sources:
        raise SceneError(None, "SCENE", "nothing to derive: no scene given and no bundled scenes found; "
                                        "accepted: scene files, e.g. `springchain derive my_scene.toml`")
    loaded = [load(p) for p in sources]  # validate everything before writing anything
    folder = Path(out) if out is not None else Path.cwd() / "generated"
    done = []
    for sc in loaded:
        t0 = time.perf_counter()
        if check:
            ok, msg = _modules.check(sc, folder)
            done.append(Generated(sc, _modules.module_path(sc, folder), ok, None, time.perf_counter() - t0, msg))
            continue
        with phase(f"deriving {sc.name!r}"):
            d = _modules.derive(sc)
        path = _modules.write(d, folder)
        done.append(Generated(sc, path, None, len(d.source.splitlines()), time.perf_counter() - t0, f"{path}: written"))
    return done


# -- scaling ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Scaling:
    """``springchain scaling``'s measurements: the numeric scaling table and the symbolic cost.

    Attributes
    ----------
    result : springchain.numeric.bench.scaling.ScalingResult
    symbolic : springchain.symbolic_cost.SymbolicResult or None
    files : tuple of Path
    """

    result: object = field(repr=False)
    symbolic: object = field(repr=False)
    files: tuple[Path, ...] = ()

    def to_json(self) -> dict:
        """What ``springchain scaling --json`` prints."""
        from .numeric.bench import scaling_report

        return {"scaling": scaling_report.jsonable(self.result.to_json()),
                "symbolic": None if self.symbolic is None else scaling_report.jsonable(self.symbolic.to_json()),
                "files": [str(p) for p in self.files]}

    def to_markdown(self) -> str:
        """The tables ``springchain scaling`` prints."""
        from . import symbolic_cost
        from .numeric.bench import scaling_report

        text = scaling_report.markdown(self.result) + "\n"
        return text + (symbolic_cost.markdown(self.symbolic) + "\n" if self.symbolic is not None else "")


def scaling(max_n: int = 1_000_000, symbolic_max_n: int = 40, out: str | Path = DEFAULT_OUT, *,
            progress: bool = True) -> Scaling:
    """Exact-solution set-up against one Verlet step for chains of N = 3 … ``max_n`` masses, the memory
    floor, and (up to ``symbolic_max_n`` masses; 0 skips it) derive time against SymPy's ``LagrangesMethod``.

    Writes ``scaling.{json,md,png}`` (and ``symbolic-cost.*``) into ``out``.
    """
    from . import symbolic_cost
    from .numeric.bench import scaling as sc_mod, scaling_report
    from .numeric.errors import RunRefused

    if isinstance(max_n, bool) or not isinstance(max_n, int) or max_n < 3:
        raise RunRefused(f"max_n {max_n!r}: accepted: a whole number >= 3", quantity="max_n")
    if isinstance(symbolic_max_n, bool) or not isinstance(symbolic_max_n, int) or symbolic_max_n < 0:
        raise RunRefused(f"symbolic_max_n {symbolic_max_n!r}: accepted: a whole number >= 0 (0 skips it)",
                         quantity="symbolic_max_n")
    say = sc_mod.print_progress if progress else (lambda line: None)
    out = Path(out)
    sizes = tuple(n for n in sc_mod.DEFAULT_SIZES if n < max_n) + (max_n,)
    uniform, random = symbolic_cost.scaling_cases()
    result = sc_mod.run(uniform, random, sc_mod.ScalingConfig(sizes=sizes), progress=say)
    files = scaling_report.write(result, out)
    sym = None
    if symbolic_max_n:
        small = tuple(n for n in (3, 10, 20, 40, 80, 160, 320) if n <= symbolic_max_n)
        sym = symbolic_cost.run(small, symbolic_cost.DEFAULT_CHAIN_SIZES, progress=lambda line: say("symbolic: " + line))
        files += symbolic_cost.write(sym, out)
    return Scaling(result, sym, tuple(files))


def sweep(*args, **kwargs):
    """Ensembles and parameter studies on Dask: see :func:`springchain._sweep.sweep`."""
    from ._sweep import sweep as _sweep

    return _sweep(*args, **kwargs)


__all__ = ["load", "modes", "simulate", "plan", "bench", "generate", "scaling", "sweep", "method_names", "Modes",
           "Simulation", "Generated", "Scaling", "MAX_RECORDED_BYTES", "DEFAULT_OUT"]
