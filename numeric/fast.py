"""Fused velocity-Verlet steps for ``[chain]`` modules: one pass over memory per step.

A generated chain module (:mod:`derive.chain`) evaluates its acceleration
with NumPy slices, one ufunc (one pass over memory) at a time; a Verlet step
built on it makes about ten passes. Here the whole step is one sweep over
the chain in cache-sized blocks of rows: a block is drifted
(``x ← x + h v + h²/2 a``) and then the rows whose three neighbours are all
drifted are kicked (``a' = a(x)``, ``v ← v + h/2 (a + a')``), so each row
of ``x``, ``v`` and ``a`` leaves main memory once and comes back once.

Two sweeps are provided:

* :meth:`FusedVerlet.step` — one velocity-Verlet step on ``(x, v, a)``
  (the :class:`~numeric.integrators.base.Integrator` kernel contract; reads
  and writes 24 bytes per mass, 48 in all, one stencil per mass).
* :meth:`FusedVerlet.advance` — many steps in the equivalent "half-step
  velocity" form ``w = v + h/2 a``: ``x ← x + h w;  w ← w + h a(x)``. The
  state in memory is ``(x, w)``: 16 bytes read and 16 written per mass and
  sweep — the 32-byte-per-mass floor — and one stencil per mass and step.
  Open chains (free or wall ends) make two steps per sweep (a two-stage
  wavefront over each cached block), so memory traffic per step halves and
  the step is bound by arithmetic, not memory. ``v`` and ``a`` are restored
  at the end (three extra passes per call), so the result is velocity
  Verlet to rounding.

The compiled path needs numba (the optional ``fast`` extra); it is imported
lazily, and without it the same API runs plain NumPy on the module's own
stencil (:data:`Backend.NUMPY`), which is also what the tests compare with.

Chain ends follow the generated modules: ``free``, ``wall`` (a spring
``k(-1)`` to a wall on the left, ``k(n-1)`` on the right) or ``ring`` (the
spring ``k(n-1)`` closes n-1 to 0); masses and springs may depend on the
index (then read from arrays) and springs may be cubic (``k d + k3 d³``).
"""

from __future__ import annotations

import enum
import functools
import math
from dataclasses import dataclass, field
from types import ModuleType
from typing import Callable

import numpy as np

from .errors import RunRefused

#: Elements (rows × batch) per cache block of a sweep: 8192 doubles = 64 KiB per array (L2-resident).
BLOCK_ELEMENTS = 8192


class Backend(enum.Enum):
    """How a step is computed."""

    NUMBA = "numba"  #: fused compiled sweep (needs numba)
    NUMPY = "numpy"  #: the module's NumPy stencil, one ufunc pass at a time


class End(enum.IntEnum):
    """A chain end (the integer value is what the compiled kernels see)."""

    FREE = 0
    WALL = 1
    RING = 2


class _Mode(enum.IntEnum):
    """What a sweep's kick does with the new acceleration A (a run-time argument of the kernels)."""

    VERLET = 0  #: v ← v + h/2 (a + A); a ← A
    LEAPFROG = 1  #: w ← w + h A
    FORCE = 2  #: a ← A


@functools.lru_cache(maxsize=1)
def available() -> bool:
    """Whether numba can be imported (the fused :data:`Backend.NUMBA` path)."""
    try:
        import numba  # noqa: F401
    except Exception:  # ImportError, or a numba/llvmlite that fails to load
        return False
    return True


def default_backend() -> Backend:
    """:data:`Backend.NUMBA` when numba is available, else :data:`Backend.NUMPY`."""
    return Backend.NUMBA if available() else Backend.NUMPY


# -- coefficients ------------------------------------------------------------------------
def _cubic_constants(module: ModuleType, values: dict[str, float], n: int) -> np.ndarray:
    """Cubic coefficients k3 of a chain module's springs in ``spring_constants()`` order, shape (S,).

    Uses a public ``spring_cubic_constants(**params, n)`` if the module has
    one; otherwise the generator's per-spring helper ``_spring_k3(i, **params)``
    (spring i joins i and i+1; -1 the left wall, n-1 the right wall or the ring closure).
    """
    public = getattr(module, "spring_cubic_constants", None)
    if public is not None:
        return np.asarray(public(**values, n=n), dtype=float)
    helper = getattr(module, "_spring_k3", None) or getattr(module, "_k3", None)
    if helper is None:
        raise RunRefused(f"chain module {getattr(module, 'SCENE', '?')!r} declares cubic springs but exposes "
                         "no cubic coefficients; regenerate it with `springchain derive`")
    left, right = str(module.LEFT), str(module.RIGHT)
    idx = np.arange(-1 if left == "wall" else 0, n if right in ("wall", "ring") else n - 1, dtype=float)
    return np.array(np.broadcast_to(np.asarray(helper(idx, **values), dtype=float), idx.shape))


@dataclass(frozen=True)
class ChainCoefficients:
    """The numbers of a chain's stencil at fixed parameter values.

    Attributes
    ----------
    n : int
        Number of masses.
    left, right : End
        The ends (``RING`` on both or neither).
    inv_mass : ndarray, shape (n,), or (1,) for a uniform chain
        ``1/m_i``.
    k : ndarray, shape (max(n-1, 1),), or (1,) for a uniform chain
        Spring ``i`` joins masses ``i`` and ``i+1``.
    k3 : ndarray, same shape as ``k``, or None
        Cubic coefficients (None for a linear chain).
    k_left, k_right : float
        The left wall spring; the right wall spring or the ring's closing spring (0 if absent).
    k3_left, k3_right : float
        Their cubic coefficients (0 if absent or linear).
    uniform : bool
        Coefficients independent of the index (arrays of length 1).
    """

    n: int
    left: End
    right: End
    inv_mass: np.ndarray = field(repr=False)
    k: np.ndarray = field(repr=False)
    k3: np.ndarray | None = field(repr=False)
    k_left: float
    k_right: float
    k3_left: float
    k3_right: float
    uniform: bool

    @classmethod
    def from_module(cls, module: ModuleType, params: dict[str, float] | None = None,
                    n: int | None = None) -> "ChainCoefficients":
        """Read the coefficients from a generated ``[chain]`` module.

        Parameters
        ----------
        module : module
            A generated chain module (``CHAIN = True``).
        params : dict, optional
            Parameter values overriding ``module.DEFAULTS``.
        n : int, optional
            Number of masses (default ``module.N``).
        """
        if not getattr(module, "CHAIN", False):
            raise RunRefused("the fused chain step needs a [chain] scene's generated module")
        values = dict(module.DEFAULTS)
        values.update(params or {})
        n = int(module.N if n is None else n)
        if n < 1:
            raise ValueError(f"a chain needs n >= 1 masses, got {n}")
        left, right = End[str(module.LEFT).upper()], End[str(module.RIGHT).upper()]
        uniform = bool(module.UNIFORM)
        m = np.asarray(module.masses(**values, n=n), dtype=float)
        ks = np.asarray(module.spring_constants(**values, n=n), dtype=float)
        off = 1 if left is End.WALL else 0
        inner = ks[off:off + n - 1]
        k_left = float(ks[0]) if left is End.WALL else 0.0
        k_right = float(ks[-1]) if right in (End.WALL, End.RING) else 0.0
        k3 = None
        k3_left = k3_right = 0.0
        if not bool(module.LINEAR):
            k3s = _cubic_constants(module, values, n)  # spring_constants() order
            k3 = np.array(k3s[off:off + n - 1])
            if left is End.WALL:
                k3_left = float(k3s[0])
            if right in (End.WALL, End.RING):
                k3_right = float(k3s[-1])
        if uniform:
            inv = np.array([1.0 / m[0]])
            kk = np.array([inner[0] if n > 1 else (k_right or k_left or 0.0)])
            k3a = None if k3 is None else np.array([k3[0] if n > 1 else (k3_right or k3_left)])
        else:
            inv = 1.0 / m
            kk = inner.copy() if n > 1 else np.zeros(1)
            k3a = None if k3 is None else (k3.copy() if n > 1 else np.zeros(1))
        return cls(n, left, right, inv, kk, k3a, k_left, k_right, k3_left, k3_right, uniform)

    @property
    def cubic(self) -> bool:
        return self.k3 is not None

    @property
    def omega_max_bound(self) -> float:
        """Gershgorin bound on ω_max (:func:`numeric.bounds.chain_omega2_bound`; ≥ the true ω_max)."""
        from .bounds import chain_omega2_bound

        inner = self.k if self.n > 1 else np.zeros(0)
        ring = self.right is End.RING
        return math.sqrt(chain_omega2_bound(self.n, self.inv_mass, inner, self.k_left, self.k_right, ring))

    def kernel_args(self) -> tuple:
        """The positional coefficient arguments of the compiled sweeps.

        Floats for a uniform chain and arrays otherwise (the kernels are
        specialised on these types); None for the cubic ones of a linear chain.
        """
        if self.uniform:
            im, k = float(self.inv_mass[0]), float(self.k[0])
            k3 = None if self.k3 is None else float(self.k3[0])
        else:
            im, k, k3 = self.inv_mass, self.k, self.k3
        k3l = None if self.k3 is None else self.k3_left
        k3r = None if self.k3 is None else self.k3_right
        return (self.n, im, k, k3, self.k_left, self.k_right, k3l, k3r, int(self.left), int(self.right))


# -- compiled sweeps -----------------------------------------------------------------------
# -- compiled sweeps ------------------------------------------------------------------------------
# The kernels are plain module-level functions compiled lazily by :func:`_compiled` with
# ``numba.njit(cache=True)`` (so a second process loads machine code instead of compiling).
# They are specialised by the *types* of the coefficients: a uniform chain passes floats, an
# index-dependent one arrays; a linear chain passes None for the cubic coefficients. The helpers
# below are overloaded for numba on those types, so the branches vanish at compile time and the
# inner loops vectorise. What a kick does (:class:`_Mode`) is a run-time argument tested outside
# the inner loops. States are flat C-contiguous float64 views of (n, nb) arrays: row i is
# elements i*nb … i*nb + nb - 1. Chain ends are the integers of :class:`End`.

_FREE, _WALL, _RING = int(End.FREE), int(End.WALL), int(End.RING)
_VERLET, _LEAPFROG, _FORCE = int(_Mode.VERLET), int(_Mode.LEAPFROG), int(_Mode.FORCE)


def _at(c, i):
    """Coefficient of row i: ``c[i]`` for an array, ``c`` for a float (numba overload)."""
    return c if np.ndim(c) == 0 else c[i]


def _rows(c, a, b):
    """Coefficients of rows a … b-1: ``c[a:b]`` for an array, ``c`` for a float (numba overload)."""
    return c if np.ndim(c) == 0 else c[a:b]


def _cubic(s, c, i, d):
    """``s + c_i d³``, or ``s`` when c is None (a linear chain) (numba overload)."""
    return s if c is None else s + _at(c, i) * d * d * d


def _scalar(c):
    """Whether coefficients are one float for the whole chain (a constant under numba)."""
    return np.ndim(c) == 0


def _spring_impl(x, j, b, nb, n, k, k3, kl, kr, k3l, k3r, left, right):
    """Force ``k d + k3 d³`` of spring j (-1 … n-1, ends included), d its extension."""
    if j < 0:
        if left == _FREE:
            return 0.0
        if left == _WALL:
            d = x[b]
            return _cubic(kl * d, k3l, 0, d)
        j = n - 1  # a ring: spring -1 is the closing spring n-1
    if j >= n - 1:
        if right == _FREE:
            return 0.0
        last = (n - 1) * nb + b
        if right == _WALL:
            d = -x[last]
        else:
            d = x[b] - x[last]
        return _cubic(kr * d, k3r, 0, d)
    e = j * nb + b
    d = x[e + nb] - x[e]
    return _cubic(_at(k, j) * d, k3, j, d)


def _kick_end_impl(x, v, a, i, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, c, mode):
    """Kick one row (any row, ends included) through the scalar spring function."""
    mi = _at(im, i)
    for b in range(nb):
        A = mi * (_spring(x, i, b, nb, n, k, k3, kl, kr, k3l, k3r, left, right)
                  - _spring(x, i - 1, b, nb, n, k, k3, kl, kr, k3l, k3r, left, right))
        e = i * nb + b
        if mode == _VERLET:
            v[e] = v[e] + c * (a[e] + A)
            a[e] = A
        elif mode == _LEAPFROG:
            v[e] = v[e] + c * A
        else:
            a[e] = A


def _kick_flat_impl(xm, xc, xp, vv, aa, ku, kd, cu, cd, mm, c, mode):
    """Interior rows as one flat loop: coefficients are floats (uniform) or per element (one state)."""
    if mode == _VERLET:
        for e in range(xc.shape[0]):
            d1 = xp[e] - xc[e]
            d0 = xc[e] - xm[e]
            A = _at(mm, e) * (_cubic(_at(ku, e) * d1, cu, e, d1) - _cubic(_at(kd, e) * d0, cd, e, d0))
            vv[e] = vv[e] + c * (aa[e] + A)
            aa[e] = A
    elif mode == _LEAPFROG:
        if _scalar(ku) and cu is None:
            # w ← w + (h k/m)·(Δ⁺x − Δ⁻x): coefficients folded (this sweep equals Verlet to rounding only)
            q = c * _at(mm, 0) * _at(ku, 0)
            for e in range(xc.shape[0]):
                vv[e] = vv[e] + q * ((xp[e] - xc[e]) - (xc[e] - xm[e]))
        else:
            for e in range(xc.shape[0]):
                d1 = xp[e] - xc[e]
                d0 = xc[e] - xm[e]
                A = _at(mm, e) * (_cubic(_at(ku, e) * d1, cu, e, d1) - _cubic(_at(kd, e) * d0, cd, e, d0))
                vv[e] = vv[e] + c * A
    else:
        for e in range(xc.shape[0]):
            d1 = xp[e] - xc[e]
            d0 = xc[e] - xm[e]
            aa[e] = _at(mm, e) * (_cubic(_at(ku, e) * d1, cu, e, d1) - _cubic(_at(kd, e) * d0, cd, e, d0))


def _kick_row_batch_impl(x, v, a, i, nb, mi, ku, kd, cu, cd, c, mode):
    """One interior row of an index-dependent chain across the batch (coefficients of that row)."""
    base = i * nb
    for b in range(nb):
        e = base + b
        d1 = x[e + nb] - x[e]
        d0 = x[e] - x[e - nb]
        A = mi * (_cubic(ku * d1, cu, 0, d1) - _cubic(kd * d0, cd, 0, d0))
        if mode == _VERLET:
            v[e] = v[e] + c * (a[e] + A)
            a[e] = A
        elif mode == _LEAPFROG:
            v[e] = v[e] + c * A
        else:
            a[e] = A


def _kick_rows_impl(x, v, a, r0, r1, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, c, mode):
    """Kick rows r0 … r1-1 (0 <= r0 <= r1 <= n): end rows scalar, interior rows vectorised."""
    if r1 <= r0:
        return
    if r0 == 0:
        _kick_end(x, v, a, 0, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, c, mode)
        r0 = 1
    last = r1 == n and r0 <= n - 1
    if last:
        r1 = n - 1
    if r1 > r0:
        if _scalar(k) or nb == 1:  # one flat loop; neighbours nb elements apart
            lo = r0 * nb
            hi = r1 * nb
            _kick_flat(x[lo - nb:hi - nb], x[lo:hi], x[lo + nb:hi + nb], v[lo:hi], a[lo:hi],
                       _rows(k, r0, r1), _rows(k, r0 - 1, r1 - 1), _rows(k3, r0, r1), _rows(k3, r0 - 1, r1 - 1),
                       _rows(im, r0, r1), c, mode)
        else:  # index-dependent and a batch: one coefficient per row, the batch vectorised
            for i in range(r0, r1):
                _kick_row_batch(x, v, a, i, nb, _at(im, i), _at(k, i), _at(k, i - 1), _row(k3, i),
                                _row(k3, i - 1), c, mode)
    if last:
        _kick_end(x, v, a, n - 1, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, c, mode)


def _row(c, i):
    """The row's cubic coefficient: None for a linear chain, else ``_at(c, i)`` (numba overload)."""
    return None if c is None else _at(c, i)


def _force_impl(x, a, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right):
    """a ← a(x) for all rows."""
    _kick_rows(x, a, a, 0, n, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, 0.0, _FORCE)


def _drift_rows_impl(x, w, r0, r1, nb, h):
    """x ← x + h w on rows r0 … r1-1 (the half-step form's drift)."""
    if r1 > r0:
        xs = x[r0 * nb:r1 * nb]
        ws = w[r0 * nb:r1 * nb]
        for e in range(xs.shape[0]):
            xs[e] = xs[e] + h * ws[e]


def _sweep_impl(xi, vi, ai, xo, vo, ao, inplace, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, h, mode, steps,
                pairs):
    """``steps`` sweeps of velocity Verlet (mode VERLET, on x v a) or of the half-step form (LEAPFROG, on x w).

    Each sweep drifts a block of rows, then kicks the rows whose neighbours
    are all drifted (lo-1 … hi-2); row n-1 (and a ring's row 0, which needs
    the new x[n-1]) are kicked after the last block. VERLET may write to
    other arrays than it reads (``inplace`` False); LEAPFROG works in place,
    and with ``pairs`` makes two steps per sweep on open chains (:func:`_leapfrog_pair_impl`).
    """
    hh = 0.5 * h * h
    c = 0.5 * h if mode == _VERLET else h
    rows = max(1, BLOCK_ELEMENTS // nb)
    first = 1 if left == _RING else 0
    single = steps
    if pairs and mode == _LEAPFROG and left != _RING:
        for _ in range(steps // 2):
            _leapfrog_pair(xo, vo, rows, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, h)
        single = steps % 2
    for step in range(single):
        lo = 0
        while lo < n:
            hi = min(lo + rows, n)
            s, t = lo * nb, hi * nb
            xs = xo[s:t]
            vs = vo[s:t]
            if mode == _LEAPFROG:
                for e in range(t - s):
                    xs[e] = xs[e] + h * vs[e]
            elif inplace or step > 0:
                as_ = ao[s:t]
                for e in range(t - s):
                    xs[e] = xs[e] + h * vs[e] + hh * as_[e]
            else:
                as_ = ao[s:t]
                xin, vin, ain = xi[s:t], vi[s:t], ai[s:t]
                for e in range(t - s):
                    xs[e] = xin[e] + h * vin[e] + hh * ain[e]
                    vs[e] = vin[e]
                    as_[e] = ain[e]
            _kick_rows(xo, vo, ao, max(lo - 1, first), min(hi - 1, n - 1), nb, n, im, k, k3,
                       kl, kr, k3l, k3r, left, right, c, mode)
            lo = hi
        _kick_rows(xo, vo, ao, n - 1, n, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, c, mode)
        if first == 1 and n > 1:
            _kick_rows(xo, vo, ao, 0, 1, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, c, mode)


def _leapfrog_pair_impl(x, w, rows, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, h):
    """Two half-step-form steps in one sweep (temporal blocking; open chains, not rings).

    Per block [lo, hi): drift 1 on rows lo … hi-1, kick 1 on lo-1 … hi-2,
    drift 2 on lo-2 … hi-3, kick 2 on lo-3 … hi-4 — each stage needs only
    rows the earlier stages have finished, and the block (with its 3-row
    halo) is still in cache, so the pair moves each row through memory once:
    16 bytes per mass and step. The last rows finish after the loop.
    """
    lo = 0
    while lo < n:
        hi = min(lo + rows, n)
        _drift_rows(x, w, lo, hi, nb, h)
        _kick_rows(x, w, w, max(lo - 1, 0), min(hi - 1, n - 1), nb, n, im, k, k3, kl, kr, k3l, k3r, left, right,
                   h, _LEAPFROG)
        _drift_rows(x, w, max(lo - 2, 0), max(hi - 2, 0), nb, h)
        _kick_rows(x, w, w, max(lo - 3, 0), max(hi - 3, 0), nb, n, im, k, k3, kl, kr, k3l, k3r, left, right,
                   h, _LEAPFROG)
        lo = hi
    _kick_rows(x, w, w, n - 1, n, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, h, _LEAPFROG)
    _drift_rows(x, w, max(n - 2, 0), n, nb, h)
    _kick_rows(x, w, w, max(n - 3, 0), n, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, h, _LEAPFROG)


def _half_kick_impl(v, a, c):
    """v ← v + c a (entry to / exit from the half-step velocity form)."""
    for e in range(v.shape[0]):
        v[e] = v[e] + c * a[e]


def _stream_impl(x, v, c):
    """The floor's sweep: x ← x + c v; v ← v − c x, one pass."""
    for e in range(x.shape[0]):
        x[e] = x[e] + c * v[e]
        v[e] = v[e] - c * x[e]


# jitted versions (set by _compiled(); the implementations call these names)
_spring = _kick_end = _kick_flat = _kick_row_batch = _kick_rows = _drift_rows = _leapfrog_pair = None


def _numba_cache_present() -> bool:
    """Whether numba's on-disk cache already holds this module's kernels (index files)."""
    import os
    from pathlib import Path

    here = Path(__file__).resolve()
    base = os.environ.get("NUMBA_CACHE_DIR")
    folder = Path(base) if base else here.parent / "__pycache__"
    try:
        return any(folder.rglob(f"{here.stem}.*.nbi"))
    except OSError:
        return False


#: Said once, before numba compiles the kernels (the first run on a machine; several seconds).
COMPILE_NOTE = ("compiling numba kernels (first run only, several seconds; later runs load them "
                "from numba's cache)")


@functools.lru_cache(maxsize=1)
def _compiled():
    """Register the numba overloads and compile (or load from numba's cache) the kernels.

    Says so on stderr (one line) when nothing is cached yet: compiling takes seconds.
    Returns a namespace with ``force``, ``sweep``, ``half_kick`` and ``stream``.
    """
    import types as pytypes

    if not _numba_cache_present():
        from .progress import note

        note(COMPILE_NOTE)

    import numba
    from numba import types
    from numba.extending import overload

    def is_array(c):
        return isinstance(c, types.Array)

    @overload(_at)
    def _at_ol(c, i):
        return (lambda c, i: c[i]) if is_array(c) else (lambda c, i: c)

    @overload(_rows)
    def _rows_ol(c, a, b):
        return (lambda c, a, b: c[a:b]) if is_array(c) else (lambda c, a, b: c)

    @overload(_cubic)
    def _cubic_ol(s, c, i, d):
        if isinstance(c, (types.NoneType, types.Omitted)):
            return lambda s, c, i, d: s
        if is_array(c):
            return lambda s, c, i, d: s + c[i] * d * d * d
        return lambda s, c, i, d: s + c * d * d * d

    @overload(_row)
    def _row_ol(c, i):
        if isinstance(c, types.NoneType):
            return lambda c, i: None
        return (lambda c, i: c[i]) if is_array(c) else (lambda c, i: c)

    @overload(_scalar)
    def _scalar_ol(c):
        flag = not is_array(c)
        return lambda c: flag

    def jit(fn):
        return numba.njit(cache=True)(fn)

    g = globals()
    for name in ("_spring", "_kick_end", "_kick_flat", "_kick_row_batch", "_kick_rows", "_drift_rows",
                 "_leapfrog_pair"):
        g[name] = jit(g[name + "_impl"])
    return pytypes.SimpleNamespace(force=jit(_force_impl), sweep=jit(_sweep_impl), half_kick=jit(_half_kick_impl),
                                   stream=jit(_stream_impl))


def stream_update(x: np.ndarray, v: np.ndarray, c: float = 1e-12) -> None:
    """The memory floor's reference sweep: ``x ← x + c v;  v ← v - c x`` in place, one pass.

    Reads 16 and writes 16 bytes per element pair, the traffic a Verlet step
    needs at the least (x and v in, x and v out). Compiled with numba when
    available, else NumPy (three passes; then not a floor).

    Parameters
    ----------
    x, v : ndarray, shape (N,), float64, C-contiguous
    """
    if available():
        _compiled().stream(x, v, float(c))
    else:
        x += c * v
        v -= c * x


# -- the public object ----------------------------------------------------------------------
def _flat(arr: np.ndarray, n: int, name: str) -> tuple[np.ndarray, int]:
    """A flat float64 C-contiguous view of a (n,) or (n, B) array, and B."""
    if not (isinstance(arr, np.ndarray) and arr.dtype == np.float64 and arr.flags.c_contiguous):
        raise ValueError(f"{name}: need a C-contiguous float64 ndarray, got "
                         f"{type(arr).__name__} {getattr(arr, 'dtype', '')}")
    if arr.ndim not in (1, 2) or arr.shape[0] != n:
        raise ValueError(f"{name}: need shape ({n},) or ({n}, B), got {arr.shape}")
    nb = 1 if arr.ndim == 1 else arr.shape[1]
    if nb < 1:
        raise ValueError(f"{name}: empty batch, shape {arr.shape}")
    return arr.reshape(-1), nb


@dataclass(frozen=True)
class FusedVerlet:
    """Velocity Verlet with step ``h`` on one chain, fused (numba) or on NumPy.

    Build with :meth:`from_module`. States are float64 C-contiguous arrays of
    shape (n,) or (n, B).
    """

    coefficients: ChainCoefficients
    acceleration: Callable[[np.ndarray], np.ndarray] = field(repr=False)
    h: float
    backend: Backend

    @classmethod
    def from_module(cls, module: ModuleType, params: dict[str, float] | None = None, n: int | None = None,
                    h: float = 1.0, backend: Backend | None = None) -> "FusedVerlet":
        """Bind a generated ``[chain]`` module, parameters, size and step.

        Parameters
        ----------
        backend : Backend, optional
            Default: :func:`default_backend` (numba if it loads).
        """
        h = float(h)
        if not (math.isfinite(h) and h > 0):
            raise ValueError(f"step size h must be finite and > 0, got {h!r}")
        coeffs = ChainCoefficients.from_module(module, params, n)
        values = dict(module.DEFAULTS)
        values.update(params or {})
        backend = default_backend() if backend is None else backend
        if backend is Backend.NUMBA and not available():
            raise RunRefused("the fused chain step needs numba: install the `fast` extra "
                             "(pip install 'springchain[fast]') or use the NumPy backend")
        return cls(coeffs, module.make_acceleration(**values, n=coeffs.n), h, backend)

    @property
    def n(self) -> int:
        return self.coefficients.n

    def _numpy_force(self, x: np.ndarray) -> np.ndarray:
        """The module's stencil; a 1-D state goes through as (n, 1), the generated modules' state shape."""
        if x.ndim == 1:
            return self.acceleration(x[:, None])[:, 0]
        return self.acceleration(x)

    def _kernels(self):
        k = _compiled()
        return k.force, k.sweep, k.half_kick

    # -- building blocks ------------------------------------------------------------------
    def force(self, x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """The acceleration a(x); x shape (n,) or (n, B) -> same shape (written into ``out`` if given)."""
        if self.backend is Backend.NUMPY:
            a = self._numpy_force(x)
            if out is None:
                return a
            out[...] = a
            return out
        xf, nb = _flat(x, self.n, "x")
        out = np.empty_like(x) if out is None else out
        af, _ = _flat(out, self.n, "out")
        self._kernels()[0](xf, af, nb, *self.coefficients.kernel_args())
        return out

    def step(self, x: np.ndarray, v: np.ndarray, a: np.ndarray, *,
             inplace: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One velocity-Verlet step from the state (x, v) with a = a(x).

        Parameters
        ----------
        x, v, a : ndarray, shape (n,) or (n, B)
        inplace : bool
            Update the given arrays and return them (no allocation). Otherwise
            the inputs are left untouched and new arrays are returned.

        Returns
        -------
        x, v, a : ndarray
            The state one step later and the acceleration there.
        """
        h = self.h
        if self.backend is Backend.NUMPY:
            xn = x + h * v + (0.5 * h * h) * a
            an = self._numpy_force(xn)
            vn = v + (0.5 * h) * (a + an)
            if not inplace:
                return xn, vn, an
            x[...], v[...], a[...] = xn, vn, an
            return x, v, a
        xf, nb = _flat(x, self.n, "x")
        vf, _ = _flat(v, self.n, "v")
        af, _ = _flat(a, self.n, "a")
        if inplace:
            xo, vo, ao = x, v, a
            xof, vof, aof = xf, vf, af
        else:
            xo, vo, ao = np.empty_like(x), np.empty_like(v), np.empty_like(a)
            xof, vof, aof = xo.reshape(-1), vo.reshape(-1), ao.reshape(-1)
        self._kernels()[1](xf, vf, af, xof, vof, aof, inplace, nb, *self.coefficients.kernel_args(), h,
                           int(_Mode.VERLET), 1, False)
        return xo, vo, ao

    def advance(self, x: np.ndarray, v: np.ndarray, a: np.ndarray, steps: int, *,
                two_step_sweeps: bool = True) -> tuple[np.ndarray, ...]:
        """``steps`` velocity-Verlet steps in place, through the half-step velocity ``w = v + h/2 a``.

        Equal to ``steps`` calls of :meth:`step` up to rounding. Each sweep
        moves 32 bytes per mass (x and w in and out) and makes one step, or
        two on an open chain (free or wall ends) unless ``two_step_sweeps`` is
        False. Updates and returns x, v, a.
        """
        steps = int(steps)
        if steps < 0:
            raise ValueError(f"steps must be >= 0, got {steps}")
        if steps == 0:
            return x, v, a
        h = self.h
        if self.backend is Backend.NUMPY:
            v += (0.5 * h) * a
            for _ in range(steps):
                x += h * v
                v += h * self._numpy_force(x)
            a[...] = self._numpy_force(x)
            v -= (0.5 * h) * a
            return x, v, a
        xf, nb = _flat(x, self.n, "x")
        vf, _ = _flat(v, self.n, "v")
        af, _ = _flat(a, self.n, "a")
        force, sweep, half_kick = self._kernels()
        args = self.coefficients.kernel_args()
        half_kick(vf, af, 0.5 * h)
        sweep(xf, vf, af, xf, vf, af, True, nb, *args, h, int(_Mode.LEAPFROG), steps, bool(two_step_sweeps))
        force(xf, af, nb, *args)
        half_kick(vf, af, -0.5 * h)
        return x, v, a

    # -- the integrator contract -------------------------------------------------------------
    def kernel(self, *, inplace: bool = False) -> Callable:
        """A step function ``(x, v, a, i) -> (x, v, a)`` (:data:`numeric.integrators.base.StepKernel`).

        With ``inplace=False`` (the contract's default) inputs are never
        modified; with ``inplace=True`` they are updated and returned, which
        is safe for a driver that copies the frames it records (the attribute
        ``inplace`` on the returned function says which). An in-place kernel
        also carries ``advance(x, v, a, steps)`` (:meth:`advance`), which a
        driver may call between recorded frames instead of ``steps`` kernel calls.
        """
        def step(x, v, a, i):
            return self.step(x, v, a, inplace=inplace)

        step.inplace = inplace
        step.backend = self.backend
        if inplace:  # many steps at once, for a driver that records only every k-th step
            step.advance = self.advance
        return step


def chain_verlet_kernel(module: ModuleType, params: dict[str, float] | None, n: int | None, h: float, *,
                        inplace: bool = False, backend: Backend | None = None) -> Callable:
    """Velocity-Verlet step kernel ``(x, v, a, i) -> (x, v, a)`` for a ``[chain]`` module.

    Compatible with :meth:`numeric.integrators.base.Integrator.kernel` for a
    conservative chain (no dampers, no external forces). x, v, a have shape
    (n, B) or (n,), float64, C-contiguous.
    """
    return FusedVerlet.from_module(module, params, n, h, backend).kernel(inplace=inplace)


def chain_verlet_advance(module: ModuleType, params: dict[str, float] | None, n: int | None, h: float, *,
                         backend: Backend | None = None) -> Callable:
    """``advance(x, v, a, steps) -> (x, v, a)``: many Verlet steps in place at the 32-byte floor."""
    return FusedVerlet.from_module(module, params, n, h, backend).advance


__all__ = ["Backend", "End", "ChainCoefficients", "FusedVerlet", "available", "default_backend",
           "chain_verlet_kernel", "chain_verlet_advance", "stream_update", "BLOCK_ELEMENTS"]
