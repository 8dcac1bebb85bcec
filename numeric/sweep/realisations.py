"""One batch of realisations of a parameter study: draw, build, solve. Runs in any process.

A :class:`SweepSpec` is everything a worker needs (plain data: the generated
module's *source text*, numbers and distributions), so a batch is computed the
same way in the client, in a local worker or on another machine.

Sample ``s`` of a sweep:

* grid point ``g = s // samples`` (``samples`` realisations per point of the
  product of the ``grid(...)`` distributions, first grid slowest);
* its random numbers come from ``SeedSequence(seed, spawn_key=(s,))`` - the
  ``s``-th child of ``SeedSequence(seed)`` - drawn in a fixed order: each
  random ``--vary`` parameter (in the order given), then one factor per mass
  (mass disorder), then one per spring (spring disorder). Nothing depends on
  the batch a sample falls in, so rows are identical whatever the batch size,
  worker count or scheduler.

Results per sample: ``omega2`` ascending; for ``[chain]`` scenes the
participation ratio ``1 / (n Σ ψ_i⁴)`` of each mass-weighted mode ``ψ``
(``Σ ψ² = 1``) and the inverse localisation length ``γ`` of each mode: the
transfer-matrix Lyapunov exponent of the sample's own chain (growth rate per
site of the interior equations' solution) at ω² midway to the next mode.
"""

from __future__ import annotations

import hashlib
import os
import types
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from .distributions import Dist
from ..errors import RunRefused
from ..system import System, interface
from ...generated.contract import Ground

_MODULES: dict[str, types.ModuleType] = {}


@dataclass(frozen=True)
class SweepSpec:
    """A sweep's settings (picklable, plain data)."""

    scene: str
    source: str  # generated module source
    params: tuple[tuple[str, float], ...]  # the scene's parameter values
    vary: tuple[tuple[str, Dist], ...]
    disorder: tuple[tuple[str, Dist], ...]  # ("mass" | "k", Dist)
    samples: int  # realisations per grid point
    seed: int

    @property
    def grids(self) -> tuple[tuple[str, Dist], ...]:
        return tuple((n, d) for n, d in self.vary if d.is_grid)

    @property
    def grid_points(self) -> int:
        return int(np.prod([int(d.args[2]) for _, d in self.grids], dtype=np.int64)) if self.grids else 1

    @property
    def total(self) -> int:
        return self.samples * self.grid_points


def module_of(source: str) -> types.ModuleType:
    """The generated module from its source text (cached per process)."""
    key = hashlib.sha256(source.encode()).hexdigest()
    mod = _MODULES.get(key)
    if mod is None:
        mod = _import_generated(source, key)
        _MODULES[key] = mod
    return mod


def _import_generated(source: str, key: str) -> types.ModuleType:
    """Import generated source through a content-addressed file (written atomically once per machine),
    so a worker on another host loads the very module the client derived, by the import system."""
    import tempfile
    from pathlib import Path

    from ..io.files import atomic_write_text
    from ..io.imports import import_file

    path = Path(tempfile.gettempdir()) / f"springchain-sweep-{os.getuid() if hasattr(os, 'getuid') else 0}" / f"m_{key[:32]}.py"
    if not path.exists() or hashlib.sha256(path.read_bytes()).hexdigest() != key:
        path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        atomic_write_text(path, source)
    return import_file(path, f"springchain_sweep_{key[:12]}")


def system_of(source: str, params: dict[str, float]) -> System:
    """The generated module of ``source`` (:func:`module_of`) bound to ``params``.

    A sweep draws masses and springs only: a scene's force or ground tables never enter a realisation,
    so they are bound as empty stand-ins (one sample at t = 0) to satisfy :meth:`System.from_module`.
    """
    mod = module_of(source)
    facts = interface(mod)
    blank = (np.zeros(1), np.zeros(1))
    return System.from_module(mod, params, tables=tuple(blank for _ in facts.table_force_on),
                              ground_table=blank if facts.ground is Ground.TABLE else None)


def _describe(dist_owner: str, dist: Dist) -> str:
    return f"{dist_owner}={dist.text}"


def realise(spec: SweepSpec, s: int):
    """Sample ``s``: (varied values dict, masses, spring_ends, stiffness)."""
    rng = np.random.default_rng(np.random.SeedSequence(spec.seed, spawn_key=(int(s),)))
    params = dict(spec.params)
    varied = {}
    g = s // spec.samples
    sizes = [int(d.args[2]) for _, d in spec.grids]
    idx = list(np.unravel_index(g, sizes)) if sizes else []
    for name, dist in spec.vary:
        value = float(dist.grid_values()[idx.pop(0)]) if dist.is_grid else float(dist.draw(rng))
        params[name] = value
        varied[name] = value
    system = system_of(spec.source, params)
    masses, ends, k = system.masses.copy(), system.spring_ends, system.stiffness.copy()
    for what, dist in spec.disorder:
        target = masses if what == "mass" else k
        factors = dist.draw(rng, target.shape[0])
        bad = np.flatnonzero(~(factors > 0))
        if bad.size:
            i = int(bad[0])
            raise RunRefused(f"sample {s}: --disorder {_describe(what, dist)} drew the factor {factors[i]:.6g} "
                             f"for {'mass' if what == 'mass' else 'spring'} {i}, which makes it non-positive; "
                             "accepted: distributions whose draws are > 0 (e.g. uniform(a, b) with a > 0, "
                             "lognormal, or a smaller sigma)")
        target *= factors
    for label, arr in (("mass", masses), ("spring", k)):
        bad = np.flatnonzero(~(arr > 0) | ~np.isfinite(arr))
        if bad.size:
            i = int(bad[0])
            shown = ", ".join(f"{n} = {v:.6g}" for n, v in varied.items())
            raise RunRefused(f"sample {s}: {label} {i} = {arr[i]:.6g} is not positive"
                             f"{' (drawn ' + shown + ')' if shown else ''}; accepted: --vary distributions "
                             "whose draws keep every mass and spring > 0")
    return varied, masses, ends, k


def chain_bands(n: int, ends: np.ndarray, k: np.ndarray):
    """Diagonal and off-diagonal of K for a chain without a ring closure; None for a ring."""
    a, b = ends[:, 0], ends[:, 1]
    inner = (a >= 0) & (b >= 0)
    if np.any(inner & (np.abs(a - b) != 1)):
        return None
    diag = np.zeros(n)
    np.add.at(diag, a[a >= 0], k[a >= 0])
    np.add.at(diag, b[b >= 0], k[b >= 0])
    off = np.zeros(n - 1)
    off[np.minimum(a[inner], b[inner])] = -k[inner]
    return diag, off


def lyapunov(masses: np.ndarray, ends: np.ndarray, k: np.ndarray, omega2: np.ndarray) -> np.ndarray:
    """Transfer-matrix Lyapunov exponent (per site) of the chain's interior at each ω².

    Iterates ``k_i (u_{i+1} − u_i) = k_{i−1} (u_i − u_{i−1}) − m_i ω² u_i`` along the
    chain's nearest-neighbour springs, vectorised over ω², renormalising every step.
    """
    n = masses.shape[0]
    a, b = ends[:, 0], ends[:, 1]
    inner = (a >= 0) & (b >= 0) & (np.abs(a - b) == 1)
    ks = np.empty(n - 1)
    ks[np.minimum(a[inner], b[inner])] = k[inner]
    w2 = np.asarray(omega2, dtype=float)
    # start from (u_0, u_1) = (0, 1), not from the free-end condition: at an eigenfrequency of the
    # finite chain the free-end solution is the (localised) mode itself, whose net growth is ~0;
    # a generic start grows at the Lyapunov rate.
    u0 = np.zeros_like(w2)
    u1 = np.ones_like(w2)
    # Growth is measured in the invariant of the mean chain, Q = u_i² + u_{i-1}² − 2 cos q u_i u_{i-1}
    # (cos q = 1 − m̄ω²/(2k̄)), which the ordered chain conserves exactly: without it a finite chain
    # shows a spurious growth ~ log(1/sin q)/n at low ω (the transfer matrix is far from normal).
    cos_q = 1.0 - masses.mean() * w2 / (2.0 * ks.mean())
    inside = np.abs(cos_q) < 1 - 1e-12

    def invariant(a, b):
        q = a * a + b * b - 2.0 * cos_q * a * b
        return np.where(inside, q, a * a + b * b)

    q_start = invariant(u0, u1)
    log_sum = np.zeros_like(w2)
    for i in range(1, n - 1):
        u2 = u1 + (ks[i - 1] * (u1 - u0) - masses[i] * w2 * u1) / ks[i]
        norm = np.hypot(u2, u1)
        log_sum += np.log(norm)
        u0, u1 = u1 / norm, u2 / norm
    log_sum += 0.5 * np.log(invariant(u0, u1) / q_start)
    steps = max(n - 2, 1)
    return log_sum / steps


def solve_chain(masses: np.ndarray, ends: np.ndarray, k: np.ndarray, rigid: int):
    """(ω² ascending, participation ratio per mode, γ per mode) of one chain realisation."""
    n = masses.shape[0]
    bands = chain_bands(n, ends, k)
    rs = 1.0 / np.sqrt(masses)
    if bands is not None:
        diag, off = bands
        # shapes (for the participation ratio) from D; ω² from the bidiagonal spring factor by LAPACK's
        # dqds, relatively accurate (eigh_tridiagonal's small ω² lose κ(D)·ε at high contrast)
        _, psi = scipy.linalg.eigh_tridiagonal(diag * rs * rs, off * rs[:-1] * rs[1:])
        from ..modes.chain import bidiagonal_factor
        from ..modes.lapack_bidiagonal import bidiagonal_svd

        f = bidiagonal_factor(masses, ends, k)
        sigma = np.sort(bidiagonal_svd(f.d, f.e, f.upper, vectors=False)[0])[f.size - n:]
        w2 = sigma * sigma
    else:  # a ring: the accurate dense route (spring-factor SVD; rigid modes exact by structure)
        from ..modes.spectrum import spectrum

        spec = spectrum(masses, ends, k)
        w2, psi = spec.omega2, spec.vectors
    if rigid:
        w2[:rigid] = 0.0  # rigid-body modes are exact zeros (structure, not rounding)
    w2 = np.maximum(w2, 0.0)
    pr = 1.0 / (n * np.sum(psi**4, axis=0))
    if bands is not None:
        # γ of mode j at ω² midway to the next mode: *at* an eigenfrequency of this very chain the
        # growth of the transfer-matrix solution is biased low (the solution nearly satisfies both
        # ends' conditions); between eigenfrequencies it is the chain's generic Lyapunov exponent.
        gap = np.diff(w2)
        probe = w2 + 0.5 * np.append(gap, gap[-1] if gap.size else 0.0)
        gamma = lyapunov(masses, ends, k, probe)
    else:
        gamma = np.full(n, np.nan)
    gamma[:rigid] = 0.0
    return w2, pr, gamma


def compute_batch(spec: SweepSpec, start: int, stop: int) -> dict:
    """Samples ``start ... stop-1``: a dict of columns (NumPy arrays; list columns as 2-D arrays)."""
    from threadpoolctl import threadpool_limits

    facts = interface(module_of(spec.source))
    chain = facts.chain
    rigid = facts.rigid_modes if chain else 0
    names = [n for n, _ in spec.vary]
    cols: dict[str, list] = {"sample": [], **{n: [] for n in names}, "omega2": []}
    if chain:
        cols["participation_ratio"], cols["inverse_localisation_length"] = [], []
    with threadpool_limits(limits=1):
        for s in range(start, stop):
            varied, masses, ends, k = realise(spec, s)
            cols["sample"].append(s)
            for n in names:
                cols[n].append(varied[n])
            if chain:
                w2, pr, gamma = solve_chain(masses, ends, k, rigid)
                cols["participation_ratio"].append(pr)
                cols["inverse_localisation_length"].append(gamma)
            else:
                from ..modes.spectrum import spectrum

                w2 = np.asarray(spectrum(masses, ends, k).omega2, dtype=float)
            cols["omega2"].append(w2)
    out = {"sample": np.asarray(cols.pop("sample"), dtype=np.int64)}
    for key, values in cols.items():
        out[key] = np.asarray(values, dtype=float)
    return out


__all__ = ["SweepSpec", "realise", "compute_batch", "solve_chain", "lyapunov", "module_of", "system_of", "chain_bands"]
