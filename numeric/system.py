"""A generated module bound to parameter values: the numbers every numeric method consumes.

This is the only reader of a generated module's description: :func:`interface` checks a module
against :mod:`springchain.generated.contract` and every other numeric module asks a
:class:`System` (or :func:`interface`) what the module provides, never ``getattr``/``hasattr``
on the module. The facts numeric code decides by are written here once: what makes a system
``springs_only`` (free oscillation: the modal solution without augmentation) or
``energy_conserved``, the stability bound ``ω_max``, and why no exact solution applies.
"""

from __future__ import annotations

import inspect
import math
import weakref
from dataclasses import dataclass, field, replace
from functools import cached_property, lru_cache
from pathlib import Path
from types import ModuleType
from typing import Callable

import numpy as np

from ..generated import contract
from ..generated.contract import MAX_DENSE, End, Ground, Provided

#: Loaded (forced, tabulated, ground) ``[chain]`` scenes have an exact solution (the dense augmented
#: matrix exponential) up to this many masses.
LOADED_CHAIN_EXACT_MAX = 400


#: Values computed once per generated module object (not per parameter values): see :meth:`System.per_module`.
_PER_MODULE: "weakref.WeakKeyDictionary[ModuleType, dict]" = weakref.WeakKeyDictionary()


def interface(module: ModuleType) -> Provided:
    """What a generated module provides (:func:`springchain.generated.contract.read`)."""
    return contract.read(module)


@lru_cache(maxsize=4096)
def _takes_n(function: Callable) -> bool:
    """Whether a generated function takes the chain length ``n=`` (``[chain]`` functions of per-mass arrays)."""
    return "n" in inspect.signature(function).parameters


def _provided(name: str, doc: str) -> property:
    """A property that answers from the module's :class:`Provided` facts."""
    return property(lambda self: getattr(self.provided, name), doc=doc)


@dataclass(frozen=True)
class System:
    """A scene's generated equations at fixed parameter values (build with :meth:`from_module`)."""

    #: The generated module.
    module: ModuleType
    #: Parameter values (keyword arguments of the module's functions).
    params: dict[str, float]
    #: Masses, shape (N,).
    masses: np.ndarray = field(repr=False)
    #: Mass indices of the spring ends, -1 for a wall; int, shape (S, 2).
    spring_ends: np.ndarray = field(repr=False)
    #: Linear spring constants, shape (S,).
    stiffness: np.ndarray = field(repr=False)
    #: ``(times, values)`` of each tabulated force, in the module's ``TABLE_FORCE_ON`` order.
    tables: tuple = field(default=(), repr=False)
    #: ``(times, a_g)`` of a ``[ground]`` table, or None.
    ground_table: tuple | None = field(default=None, repr=False)
    #: What the module provides (read once through the contract).
    provided: Provided | None = field(default=None, repr=False)

    @classmethod
    def from_module(cls, module: ModuleType, params: dict[str, float] | None = None, *,
                    tables: tuple = (), ground_table: tuple | None = None, n: int | None = None) -> "System":
        """Bind a generated module to parameter values (the module's ``DEFAULTS`` where not given).

        Parameters
        ----------
        module : module
            A generated module (checked against :mod:`springchain.generated.contract`).
        params : dict of str to float, optional
        tables, ground_table : tuple, optional
            The scene's force tables and ground table (data, see :class:`System`).
        n : int, optional
            ``[chain]`` scenes only: the number of masses (default the module's ``N``).
        """
        facts = interface(module)
        values = dict(facts.defaults)
        values.update(params or {})
        size = {}
        if n is not None:
            if not facts.chain:
                raise ValueError("System.from_module: n is a [chain] scene's length; a [masses] scene has fixed N")
            if int(n) < 1:
                raise ValueError(f"a chain needs n >= 1 masses, got {n}")
            size = {"n": int(n)}
        if facts.chain:
            ends = np.asarray(module.spring_ends(**size), dtype=np.intp).reshape(-1, 2)
        else:
            ends = np.asarray(module.SPRING_ENDS, dtype=np.intp).reshape(-1, 2)
        wanted, table_ground = len(facts.table_force_on), facts.ground is Ground.TABLE
        if len(tables) != wanted or table_ground != (ground_table is not None):
            raise ValueError(f"System.from_module: the module takes {wanted} force tables"
                             + (" and a ground table" if table_ground else "")
                             + f"; got {len(tables)}" + (" and a ground table" if ground_table is not None else ""))
        return cls(module, values, np.asarray(module.masses(**values, **size), dtype=float),
                   ends, np.asarray(module.spring_constants(**values, **size), dtype=float),
                   tuple((np.asarray(a, dtype=float), np.asarray(b, dtype=float)) for a, b in tables),
                   None if ground_table is None else tuple(np.asarray(a, dtype=float) for a in ground_table),
                   facts)

    def __post_init__(self):
        if self.provided is None:
            object.__setattr__(self, "provided", interface(self.module))

    def fresh(self) -> "System":
        """The same system without the results it has cached (spectrum, ω_max): for timing a run
        with its own set-up."""
        return replace(self)

    def with_params(self, params: dict[str, float]) -> "System":
        """The same module, tables and size at other parameter values (``params`` override the current ones)."""
        return System.from_module(self.module, {**self.params, **params}, tables=self.tables,
                                  ground_table=self.ground_table, n=self.n if self.chain else None)

    def with_n(self, n: int) -> "System":
        """The same ``[chain]`` at ``n`` masses (itself when ``n`` is its size)."""
        if int(n) == self.n:
            return self
        return System.from_module(self.module, self.params, tables=self.tables, ground_table=self.ground_table,
                                  n=int(n))

    # -- the generated module, asked through the System only ----------------------------------------
    def _call(self, name: str, *args):
        """The module's function ``name`` at ``args``, the parameter values and, for chains, ``n``."""
        function = getattr(self.module, name)
        if self.chain and _takes_n(function):
            return function(*args, **self.params, n=self.n)
        return function(*args, **self.params)

    @property
    def scene_name(self) -> str:
        """The scene's name (the module's ``SCENE``)."""
        return self.provided.scene

    @property
    def source_text(self) -> str:
        """The generated module's source text (the file it was imported from)."""
        return Path(self.module.__file__).read_text(encoding="utf-8")

    def source(self, name: str) -> str:
        """The source of the module's function or constant ``name`` (compiled kernels are built from it).

        Functions give their definition (:func:`inspect.getsource`); other bindings their ``repr``.
        """
        value = getattr(self.module, name)
        return inspect.getsource(value) if callable(value) else repr(value)

    def binds(self, name: str) -> bool:
        """Whether the module binds ``name`` (also its private helpers, e.g. a potential's scalar law helpers)."""
        return hasattr(self.module, name)

    def per_module(self, key: str, make: Callable[[], object] | None = None):
        """A value computed once per generated module object, whatever the parameter values (compiled
        kernels built from its sources): ``make()`` on the first call with ``key``, the same value after;
        with ``make=None`` the value if made already, else None. Held as long as the module lives."""
        memo = _PER_MODULE.setdefault(self.module, {})
        if key not in memo and make is not None:
            memo[key] = make()
        return memo.get(key)

    def value(self, name: str):
        """The module's binding ``name`` (a private helper constant of a compiled section, e.g. a
        coefficient table); compiled code reads these through the System only."""
        return getattr(self.module, name)

    def parameter_vector(self) -> np.ndarray:
        """The parameter values in the module's ``PARAMETERS`` order, float64, shape (P,) (the compiled
        kernels' argument)."""
        return np.array([float(self.params[q]) for q in self.provided.parameters], dtype=np.float64)

    def stiffness_matrix(self) -> np.ndarray:
        """K, shape (N, N) (chains: N ≤ ``MAX_DENSE``)."""
        return np.asarray(self._call("stiffness_matrix"), dtype=float)

    def damping_matrix(self) -> np.ndarray:
        """C, shape (N, N) (damped scenes; chains: N ≤ ``MAX_DENSE``)."""
        return np.asarray(self._call("damping_matrix"), dtype=float)

    def stiffness_bands(self) -> tuple[np.ndarray, np.ndarray]:
        """``(diag (n,), off (n-1,))`` of a ``[chain]``'s K."""
        diag, off = self._call("stiffness_bands")
        return np.asarray(diag, dtype=float), np.asarray(off, dtype=float)

    def mode_omega(self) -> np.ndarray:
        """Closed-form ω of mode j = 0 … n-1 of a uniform ``[chain]`` (index order, not sorted), shape (n,)."""
        return np.asarray(self._call("mode_omega"), dtype=float)

    def omega2(self) -> np.ndarray:
        """The module's ω², shape (N,) (closed forms where it has them)."""
        return np.asarray(self._call("omega2"), dtype=float)

    def mode_shapes(self) -> np.ndarray:
        """The module's mode shapes as columns in :meth:`omega2` order, shape (N, N) (``[masses]``)."""
        return np.asarray(self._call("mode_shapes"), dtype=float)

    def gravity_forces(self) -> np.ndarray:
        """m_i g, shape (N,) (``[gravity]``)."""
        return np.asarray(self._call("gravity_forces"), dtype=float)

    def forcing_harmonics(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(omega (H,), cos_amp (H, N), sin_amp (H, N), const (N,))`` of the expression forces F(t)."""
        return tuple(np.asarray(a, dtype=float) for a in self._call("forcing_harmonics"))

    def ground_harmonics(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """``(omega (H,), cos_amp (H,), sin_amp (H,), const)`` of the ground acceleration a_g(t)."""
        wg, gc, gs, g0 = self._call("ground_harmonics")
        return (np.asarray(wg, dtype=float), np.asarray(gc, dtype=float), np.asarray(gs, dtype=float),
                float(g0))

    def dampers(self) -> tuple[np.ndarray, np.ndarray]:
        """``(ends, c)``: the dashpots' mass indices (-1 a wall), int shape (D, 2), and constants, shape (D,);
        empty without ``[[dampers]]``."""
        if not self.has("damper_constants"):
            return np.zeros((0, 2), dtype=np.intp), np.zeros(0)
        if self.chain:
            ends = self.module.damper_ends(n=self.n)
        else:
            ends = self.module.DAMPER_ENDS
        return (np.asarray(ends, dtype=np.intp).reshape(-1, 2),
                np.asarray(self._call("damper_constants"), dtype=float))

    def rayleigh_coefficients(self) -> tuple[float, float] | None:
        """``(alpha, beta)`` of ``[damping] rayleigh`` (C = alpha M + beta K); None without it."""
        if not self.has("rayleigh_coefficients"):
            return None
        a, b = self._call("rayleigh_coefficients")
        return float(a), float(b)

    def modal_damping_ratios(self) -> np.ndarray | None:
        """ζ per mode (ascending ω) of ``[damping] modal``, shape (N,); None without it."""
        if not self.has("modal_damping_ratios"):
            return None
        return np.asarray(self._call("modal_damping_ratios"), dtype=float)

    def make_acceleration(self) -> Callable[[np.ndarray], np.ndarray]:
        """a(x) with everything that does not depend on x computed once (the module's ``make_acceleration``)."""
        return self._call("make_acceleration")

    # -- what the module provides ---------------------------------------------------------------
    @property
    def chain(self) -> bool:
        """A [chain] scene: stencil acceleration, no dense matrices for large n."""
        return self.provided.chain

    @property
    def n(self) -> int:
        return int(self.masses.shape[0])

    effects = _provided("effects", "The Lagrangian's effects (``spring``, ``damper``, ``gravity``, ...).")
    linear = _provided("linear", "No cubic springs, no spring potentials other than quadratic ones.")
    potential = _provided("potential", "Spring potentials (``potential = \"EXPR\"``): ``equilibrium()`` exists.")
    law_indexed = _provided("law_indexed", "A ``[chain]`` potential whose law depends on the spring index.")
    uniform = _provided("uniform", "A uniform ``[chain]`` (coefficients independent of the index).")
    rigid_modes = _provided("rigid_modes", "The number of rigid-body modes (free pieces).")
    ground = _provided("ground", "How ``[ground]`` is given (a :class:`Ground`, equal to its word), else None.")
    ground_displacement = _provided("ground_displacement",
                                    "Whether the ground displacement x_g(t) is known (``ground_motion``).")

    @property
    def ends(self) -> tuple[End, End] | None:
        """``(left, right)`` of a ``[chain]``; None otherwise."""
        return (self.provided.left, self.provided.right) if self.chain else None

    def potential_equilibrium(self) -> np.ndarray | None:
        """The static equilibrium x_eq of a scene with spring potentials (the module's ``equilibrium()``),
        shape (N,); None without potentials."""
        if not self.potential:
            return None
        return np.asarray(self._call("equilibrium"), dtype=float)

    def spring_tensions(self, x: np.ndarray) -> np.ndarray:
        """Tension V'(d) of every spring (scenes with spring potentials; the generated cancellation-free
        forms) at the frames x, shape (F, N) -> (F, S), in ``spring_ends`` order."""
        return self._law_values(x, "spring_tensions", "spring_force")

    def spring_stiffnesses(self, x: np.ndarray) -> np.ndarray:
        """Stiffness V''(d) of every spring (scenes with spring potentials) at the frames x, (F, N) -> (F, S)."""
        return self._law_values(x, "spring_stiffnesses", "spring_stiffness")

    def _law_values(self, x: np.ndarray, dense: str, chain: str) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        mod, p = self.module, self.params
        if not self.chain:
            return np.asarray(getattr(mod, dense)(x.T, **p), dtype=float).T
        ends = self.spring_ends
        xe = np.concatenate([x, np.zeros((x.shape[0], 1))], axis=1)  # column -1 = wall
        d = xe[:, ends[:, 1]] - xe[:, ends[:, 0]]
        law = getattr(mod, chain)
        if self.law_indexed:  # spring i spans (i, i + 1): the left wall spring is i = -1
            i = np.where(ends[:, 0] >= 0, ends[:, 0], -1)[None, :]
            return np.asarray(law(d, i, **p), dtype=float) * np.ones_like(d)
        return np.asarray(law(d, **p), dtype=float) * np.ones_like(d)

    def has(self, name: str) -> bool:
        """Whether the module defines the contract function ``name``."""
        return self.provided.has(name)

    def acceleration(self, x: np.ndarray) -> np.ndarray:
        """Conservative acceleration a(x); x shape (N, ...)."""
        return self.module.acceleration(x, **self.params)

    @property
    def acceleration_fn(self) -> Callable[[np.ndarray], np.ndarray]:
        """a(x) with everything that does not depend on x computed once."""
        return self.make_acceleration()

    @property
    def damped(self) -> bool:
        return self.has("damping_matrix")

    @property
    def forced(self) -> bool:
        """External forces of any kind: expressions, tables or ground motion."""
        return self.has("external_acceleration") or self.tabulated or self.ground is not None

    @property
    def tabulated(self) -> bool:
        """Tabulated forces ([[forces]] with table)."""
        return bool(self.provided.table_force_on)

    @property
    def harmonic_forcing(self) -> bool:
        """Expression forces that are constant + harmonic (``forcing_harmonics``)."""
        return self.has("forcing_harmonics")

    def ground_acceleration(self, t) -> np.ndarray:
        """Ground acceleration a_g(t), shape of t (zeros without [ground])."""
        if self.ground is Ground.EXPRESSION:
            return self.module.ground_acceleration(t, **self.params)
        if self.ground is Ground.TABLE:
            return self.module.ground_table_acceleration(t, self.ground_table)
        return np.zeros(np.shape(t))

    def ground_motion(self, t) -> np.ndarray:
        """Ground displacement x_g(t), shape of t (only when :attr:`ground_displacement`)."""
        return self.module.ground_motion(t, **self.params)[1]

    def applied_acceleration(self, t) -> np.ndarray:
        """``M⁻¹F(t)`` of the expression and tabulated forces (not the ground), shape (N, *t.shape)."""
        t = np.asarray(t, dtype=float)
        mod, p = self.module, self.params
        out = np.zeros((self.n,) + t.shape)
        if self.has("external_acceleration"):
            out += mod.external_acceleration(t, **p)
        if self.tabulated:
            out += mod.table_acceleration(t, self.tables, **p)
        return out

    # -- the facts numeric code decides by ------------------------------------------------------
    @property
    def springs_only(self) -> bool:
        """Springs only (linear or cubic): no dampers, no external forces or ground, no gravity.

        The one definition of free oscillation: the modal solution without augmentation, the fused
        chain kernel, and plan/bench's closed-form error models all ask this.
        """
        return not (self.damped or self.forced or "gravity" in self.effects)

    @property
    def energy_conserved(self) -> bool:
        """Whether :meth:`energy` is conserved: no dampers, no external forces or ground (gravity
        conserves it: its potential is part of the energy)."""
        return not (self.damped or self.forced)

    @cached_property
    def no_exact_solution(self) -> str | None:
        """Why no exact solution applies (None when one does): the one wording of the reason.

        Exact solutions: linear springs; expression forces and ground acceleration (if any)
        constant + harmonic (tables are exact by first-order hold); a loaded ``[chain]`` only up to
        ``LOADED_CHAIN_EXACT_MAX`` masses and an index-dependent one up to ``MAX_DENSE`` (both dense).
        """
        if not self.linear:
            return "this scene has spring potentials" if self.potential else "this scene has cubic springs"
        if self.has("external_acceleration") and not self.provided.forcing_harmonic:
            return "its external forces are not constant + harmonic"
        if self.ground is Ground.EXPRESSION and not self.provided.ground_harmonic:
            return "its ground acceleration is not constant + harmonic"
        if self.chain and not self.springs_only and self.n > LOADED_CHAIN_EXACT_MAX:
            return f"a loaded [chain] of more than {LOADED_CHAIN_EXACT_MAX} masses (the exact solution is dense)"
        if self.chain and not self.uniform and self.n > MAX_DENSE:
            return (f"an index-dependent [chain] of more than {MAX_DENSE} masses (no closed-form modes, and "
                    f"the eigenvector solution is dense)")
        return None

    @property
    def exact_available(self) -> bool:
        """Whether an exact solution exists (see :attr:`no_exact_solution`)."""
        return self.no_exact_solution is None

    @cached_property
    def spectrum(self):
        """The accurate modes (:func:`numeric.modes.spectrum.spectrum`: the spring-factor SVD), computed once."""
        from .modes.spectrum import spectrum

        return spectrum(self.masses, self.spring_ends, self.stiffness)

    def omega_max_bound(self) -> float:
        """A proven upper bound on ω_max (Gershgorin, :func:`numeric.modes.bounds.omega2_bound`): no eigen-solve."""
        from .modes.bounds import omega2_bound

        return math.sqrt(omega2_bound(self.masses, self.spring_ends, self.stiffness))

    @cached_property
    def omega_max(self) -> float:
        """ω_max of the linear springs: the one rule for stability checks and step plans.

        Exact from the accurate spectrum for ``[masses]`` scenes, from the closed form
        ``mode_omega()`` for uniform chains, and the proven Gershgorin bound for index-dependent
        chains (no eigen-solve of a long chain).
        """
        if not self.chain:
            return float(self.spectrum.omega_max)
        if self.has("mode_omega"):
            return float(np.max(self.mode_omega(), initial=0.0))
        return self.omega_max_bound()

    def stable(self, h: float, limit: float = 2.0) -> bool:
        """Whether a step ``h`` is inside the stability limit, ``ω_max·h < limit`` (the cheap bound
        clears the usual case without computing ω_max)."""
        return self.omega_max_bound() * h < limit or self.omega_max * h < limit

    # -- periodic scenes: the unit cell and its bands ---------------------------------------------
    @property
    def periodic(self) -> bool:
        """A periodic scene ([cell], or a [chain] repeating in i): the module has the band section."""
        return self.has("cell_masses")

    def band_cell(self):
        """The unit cell's elements at the parameter values (:class:`numeric.bands.cell.Cell`)."""
        from .bands.cell import Cell

        if not self.periodic:
            raise ValueError("System.band_cell: the module has no band section (not a periodic scene)")
        mod, p = self.module, self.params
        return Cell.from_lists(tuple(mod.CELL_NAMES), mod.cell_masses(**p), tuple(mod.CELL_SPRINGS),
                               mod.cell_stiffness(**p), tuple(mod.CELL_DAMPERS), mod.cell_damping(**p),
                               mod.cell_rayleigh(**p))

    @property
    def band_closed_form(self) -> bool:
        """Whether the module's ``band_omega2`` is a closed form (``band_omega``, ``group_velocity`` exist)."""
        return self.has("group_velocity")

    def band_omega2(self, q) -> np.ndarray:
        """The module's ω²_j(q), shape q.shape + (p,) (closed forms, or float64 eigvalsh without them)."""
        return np.asarray(self.module.band_omega2(q, **self.params), dtype=float)

    def band_omega(self, q) -> np.ndarray:
        """The module's closed-form ω_j(q), shape q.shape + (p,)."""
        return np.asarray(self.module.band_omega(q, **self.params), dtype=float)

    def group_velocity(self, q) -> np.ndarray:
        """The module's closed-form dω_j/dq [cells/s], shape q.shape + (p,)."""
        return np.asarray(self.module.group_velocity(q, **self.params), dtype=float)

    # -- operators --------------------------------------------------------------------------------
    @cached_property
    def cubic_stiffness(self) -> np.ndarray | None:
        """Cubic coefficient k₃ of each spring in ``spring_ends`` order (0 where linear), shape (S,);
        None for linear springs."""
        if self.linear:
            return None
        k3 = self._call("spring_cubic_constants" if self.chain else "cubic_constants")
        return np.asarray(k3, dtype=float) * np.ones(self.spring_ends.shape[0])

    def damping_rate_matrix(self):
        """``-M⁻¹C``, shape (N, N); None without dampers.

        Dense, except for ``[chain]`` scenes of more than ``LOADED_CHAIN_EXACT_MAX`` masses: a
        ``scipy.sparse`` CSR matrix assembled from the module's dashpot list (never N × N dense).
        """
        if not self.damped:
            return None
        if self.chain and self.n > LOADED_CHAIN_EXACT_MAX:
            import scipy.sparse

            n = self.n
            ends, c = self.dampers()
            rows, cols, vals = [], [], []
            for ci, si in ((0, 1.0), (1, -1.0)):
                for cj, sj in ((0, 1.0), (1, -1.0)):
                    ok = (ends[:, ci] >= 0) & (ends[:, cj] >= 0)
                    rows.append(ends[ok, ci])
                    cols.append(ends[ok, cj])
                    vals.append(si * sj * c[ok])
            C = scipy.sparse.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                                        shape=(n, n)).tocsr()
            return -(scipy.sparse.diags(1.0 / self.masses) @ C).tocsr()
        return -self.damping_matrix() / self.masses[:, None]

    @property
    def external_fn(self) -> Callable[[float], np.ndarray] | None:
        """``a_ext(t)`` shape (N,); None without external forces."""
        if not self.forced:
            return None
        mod, p = self.module, self.params
        if not (self.tabulated or self.ground):
            return lambda t: mod.external_acceleration(t, **p)

        def external(t):  # relative coordinates: every mass feels -a_g(t) (force -m_i a_g)
            return self.applied_acceleration(t) - self.ground_acceleration(t)

        return external

    def energy(self, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Total energy; x, v shape (N, ...) -> (...)."""
        return self.module.energy(x, v, **self.params)

    def kinetic_energy(self, v: np.ndarray) -> np.ndarray:
        """``Σ m_i v_i² / 2``; v shape (N, ...) -> (...)."""
        return 0.5 * np.tensordot(self.masses, np.asarray(v) ** 2, axes=(0, 0))

    def momentum(self, v: np.ndarray) -> np.ndarray:
        """Total momentum Σ m_i v_i; v shape (N, ...) -> (...)."""
        return np.tensordot(self.masses, v, axes=(0, 0))


__all__ = ["System", "interface", "LOADED_CHAIN_EXACT_MAX", "MAX_DENSE"]
