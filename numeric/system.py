"""A generated module bound to parameter values: the numbers every numeric method consumes."""

from __future__ import annotations

from dataclasses import dataclass, field
from types import ModuleType
from typing import Callable

import numpy as np


#: Loaded (forced, tabulated, ground) ``[chain]`` scenes have an exact solution (the dense augmented
#: matrix exponential) up to this many masses.
LOADED_CHAIN_EXACT_MAX = 400


@dataclass(frozen=True)
class System:
    """A scene's generated equations at fixed parameter values.

    Attributes
    ----------
    module : module
        The generated module.
    params : dict of str to float
        Parameter values (keyword arguments of the module's functions).
    masses : ndarray, shape (N,)
    spring_ends : ndarray of int, shape (S, 2)
        Mass indices of the spring ends, -1 for a wall.
    stiffness : ndarray, shape (S,)
    tables : tuple of (ndarray, ndarray)
        ``(times, values)`` of each tabulated force, in the module's ``TABLE_FORCE_ON`` order.
    ground_table : (ndarray, ndarray) or None
        ``(times, a_g)`` of a ``[ground]`` table.
    """

    module: ModuleType
    params: dict[str, float]
    masses: np.ndarray = field(repr=False)
    spring_ends: np.ndarray = field(repr=False)
    stiffness: np.ndarray = field(repr=False)
    tables: tuple = field(default=(), repr=False)
    ground_table: tuple | None = field(default=None, repr=False)

    @classmethod
    def from_module(cls, module: ModuleType, params: dict[str, float] | None = None, *,
                    tables: tuple = (), ground_table: tuple | None = None) -> "System":
        values = dict(module.DEFAULTS)
        values.update(params or {})
        if getattr(module, "CHAIN", False):
            ends = np.asarray(module.spring_ends(), dtype=np.intp).reshape(-1, 2)
        else:
            ends = np.asarray(module.SPRING_ENDS, dtype=np.intp).reshape(-1, 2)
        wanted = len(getattr(module, "TABLE_FORCE_ON", ()))
        if len(tables) != wanted or (getattr(module, "GROUND", None) == "table") != (ground_table is not None):
            raise ValueError(f"System.from_module: the module takes {wanted} force tables"
                             + (" and a ground table" if getattr(module, "GROUND", None) == "table" else "")
                             + f"; got {len(tables)}" + (" and a ground table" if ground_table is not None else ""))
        return cls(module, values, np.asarray(module.masses(**values), dtype=float),
                   ends, np.asarray(module.spring_constants(**values), dtype=float),
                   tuple((np.asarray(a, dtype=float), np.asarray(b, dtype=float)) for a, b in tables),
                   None if ground_table is None else tuple(np.asarray(a, dtype=float) for a in ground_table))

    @property
    def chain(self) -> bool:
        """A [chain] scene: stencil acceleration, no dense matrices for large n."""
        return bool(getattr(self.module, "CHAIN", False))

    @property
    def n(self) -> int:
        return int(self.masses.shape[0])

    @property
    def effects(self) -> frozenset[str]:
        return frozenset(self.module.EFFECTS)

    @property
    def linear(self) -> bool:
        return bool(self.module.LINEAR)

    def acceleration(self, x: np.ndarray) -> np.ndarray:
        """Conservative acceleration a(x); x shape (N, ...)."""
        return self.module.acceleration(x, **self.params)

    @property
    def acceleration_fn(self) -> Callable[[np.ndarray], np.ndarray]:
        """a(x) with everything that does not depend on x computed once."""
        mod, p = self.module, self.params
        if self.chain and hasattr(mod, "spring_force"):  # a long potential chain: the law compiled by numba
            from .potential_law import compiled_acceleration

            fast = compiled_acceleration(mod, p, self.n)
            if fast is not None:
                return fast
        if hasattr(mod, "make_acceleration"):
            return mod.make_acceleration(**p, n=self.n) if self.chain else mod.make_acceleration(**p)
        return lambda x: mod.acceleration(x, **p)

    @property
    def damped(self) -> bool:
        return hasattr(self.module, "damping_matrix")

    @property
    def forced(self) -> bool:
        """External forces of any kind: expressions, tables or ground motion."""
        return hasattr(self.module, "external_acceleration") or self.tabulated or self.ground is not None

    @property
    def tabulated(self) -> bool:
        """Tabulated forces ([[forces]] with table)."""
        return bool(getattr(self.module, "TABLE_FORCE_ON", ()))

    @property
    def ground(self) -> str | None:
        """``"expression"`` or ``"table"`` for a scene with [ground], else None."""
        return getattr(self.module, "GROUND", None)

    def ground_acceleration(self, t) -> np.ndarray:
        """Ground acceleration a_g(t), shape of t (zeros without [ground])."""
        if self.ground == "expression":
            return self.module.ground_acceleration(t, **self.params)
        if self.ground == "table":
            return self.module.ground_table_acceleration(t, self.ground_table)
        return np.zeros(np.shape(t))

    def applied_acceleration(self, t) -> np.ndarray:
        """``M⁻¹F(t)`` of the expression and tabulated forces (not the ground), shape (N, *t.shape)."""
        t = np.asarray(t, dtype=float)
        mod, p = self.module, self.params
        out = np.zeros((self.n,) + t.shape)
        if hasattr(mod, "external_acceleration"):
            out += mod.external_acceleration(t, **p)
        if self.tabulated:
            out += mod.table_acceleration(t, self.tables, **p)
        return out

    @property
    def conservative(self) -> bool:
        """Springs only (linear or cubic): no dampers, no external forces, no gravity.

        The one definition: bench, plan, the fused chain kernel and the modal
        solution without augmentation all ask this.
        """
        return not (self.damped or self.forced or "gravity" in self.effects)

    def damping_rate_matrix(self):
        """``-M⁻¹C``, shape (N, N); None without dampers.

        Dense, except for ``[chain]`` scenes of more than ``LOADED_CHAIN_EXACT_MAX`` masses: a
        ``scipy.sparse`` CSR matrix assembled from the module's dashpot list (never N × N dense).
        """
        if not self.damped:
            return None
        if self.chain and self.n > LOADED_CHAIN_EXACT_MAX:
            import scipy.sparse

            mod, n = self.module, self.n
            ends = np.asarray(mod.damper_ends(n), dtype=np.intp).reshape(-1, 2)
            c = np.asarray(mod.damper_constants(**self.params, n=n), dtype=float)
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
        return -np.asarray(self.module.damping_matrix(**self.params), dtype=float) / self.masses[:, None]

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

    @property
    def exact_available(self) -> bool:
        """Whether an exact solution exists: linear; expression forces and ground acceleration (if
        any) constant + harmonic (tables are exact by first-order hold); a loaded ``[chain]`` only
        up to ``LOADED_CHAIN_EXACT_MAX`` masses (its exact solution is dense)."""
        mod = self.module
        if not self.linear:
            return False
        if hasattr(mod, "external_acceleration") and not getattr(mod, "FORCING_HARMONIC", False):
            return False
        if self.ground == "expression" and not getattr(mod, "GROUND_HARMONIC", False):
            return False
        return not (self.chain and not self.conservative and self.n > LOADED_CHAIN_EXACT_MAX)

    def energy(self, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Total energy; x, v shape (N, ...) -> (...)."""
        return self.module.energy(x, v, **self.params)

    def momentum(self, v: np.ndarray) -> np.ndarray:
        """Total momentum Σ m_i v_i; v shape (N, ...) -> (...)."""
        return np.tensordot(self.masses, v, axes=(0, 0))
