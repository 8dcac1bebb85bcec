"""The compiled sweeps behind :mod:`springchain.numeric.compiled.fast` (numba, compiled on first use).

Module-level plain functions (``*_impl``) compiled lazily by :func:`compiled_kernels` with
``numba.njit(cache=True)``; :func:`stream_update` is the memory floor's reference sweep.
"""

from __future__ import annotations

import enum
import functools

import numpy as np

from ...generated.contract import End

#: Elements (rows × batch) per cache block of a sweep: 8192 doubles = 64 KiB per array (L2-resident).
BLOCK_ELEMENTS = 8192


@functools.lru_cache(maxsize=1)
def available() -> bool:
    """Whether numba can be imported (the fused compiled path)."""
    try:
        import numba  # noqa: F401
    except Exception:  # ImportError, or a numba/llvmlite that fails to load
        return False
    return True


class SweepMode(enum.IntEnum):
    """What a sweep's kick does with the new acceleration A (a run-time argument of the kernels)."""

    VERLET = 0  #: v ← v + h/2 (a + A); a ← A
    LEAPFROG = 1  #: w ← w + h A
    FORCE = 2  #: a ← A


# -- compiled sweeps ------------------------------------------------------------------------------
# The kernels are plain module-level functions compiled lazily by :func:`compiled_kernels` with
# ``numba.njit(cache=True)`` (so a second process loads machine code instead of compiling).
# They are specialised by the *types* of the coefficients: a uniform chain passes floats, an
# index-dependent one arrays; a linear chain passes None for the cubic coefficients. The helpers
# below are overloaded for numba on those types, so the branches vanish at compile time and the
# inner loops vectorise. What a kick does (:class:`SweepMode`) is a run-time argument tested outside
# the inner loops. States are flat C-contiguous float64 views of (n, nb) arrays: row i is
# elements i*nb … i*nb + nb - 1. Chain ends are the integers of :class:`End`.

_FREE, _WALL, _RING = End.FREE.code, End.WALL.code, End.RING.code
_VERLET, _LEAPFROG, _FORCE = int(SweepMode.VERLET), int(SweepMode.LEAPFROG), int(SweepMode.FORCE)
#: Integer constants passed to the inner kernels go through ``_int`` (``np.intp``): numba types a bare
#: ``0`` or a global constant as a literal and compiles the callee once more for each literal value;
#: ``_int(0)`` is a plain int64, so every call site shares one compiled kick (half the compile time).
_int = np.intp


def _at(c, i):
    """Coefficient of row i: ``c[i]`` for an array, ``c`` for a float (numba overload)."""
    return c if np.ndim(c) == 0 else c[i]


def _rows(c, a, b):
    """Coefficients of rows a … b-1: ``c[a:b]`` for an array, ``c`` for a float (numba overload)."""
    return c if np.ndim(c) == 0 else c[a:b]


def _cubic(s, c, i, d):
    """``s + c_i d³``, ``s`` when c is None (a linear chain), ``s + _law(d, *c)`` when c is a tuple: the
    parameter values of a spring potential (numba overload)."""
    return s if c is None else s + _at(c, i) * d * d * d


#: A spring potential's tension V'(d, *parameters), compiled. None here: the copy of this module that
#: :mod:`numeric.compiled.potential_law` writes for a law binds it (its kernels are then called with the
#: parameter values as the cubic coefficients).
_law = None


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
        _apply(v, a, i * nb + b, A, c, mode)


def _apply_impl(v, a, e, A, c, mode):
    """What a kick does with element e's acceleration A: Verlet's v += c(a + A), a = A; leapfrog's
    v += c·A; a force evaluation's a = A."""
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
        _apply(v, a, e, mi * (_cubic(ku * d1, cu, 0, d1) - _cubic(kd * d0, cd, 0, d0)), c, mode)


def _kick_rows_impl(x, v, a, r0, r1, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, c, mode):
    """Kick rows r0 … r1-1 (0 <= r0 <= r1 <= n): end rows scalar, interior rows vectorised."""
    if r1 <= r0:
        return
    if r0 == 0:
        _kick_end(x, v, a, r0, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, c, mode)
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
    _kick_rows(x, a, a, _int(0), n, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, 0.0, _int(_FORCE))


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
        lo = _int(0)
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
            _kick_rows(xo, vo, ao, _int(0), _int(1), nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, c, mode)


def _leapfrog_pair_impl(x, w, rows, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, h):
    """Two half-step-form steps in one sweep (temporal blocking; open chains, not rings).

    Per block [lo, hi): drift 1 on rows lo … hi-1, kick 1 on lo-1 … hi-2,
    drift 2 on lo-2 … hi-3, kick 2 on lo-3 … hi-4 — each stage needs only
    rows the earlier stages have finished, and the block (with its 3-row
    halo) is still in cache, so the pair moves each row through memory once:
    16 bytes per mass and step. The last rows finish after the loop.
    """
    lo = _int(0)
    while lo < n:
        hi = min(lo + rows, n)
        _drift_rows(x, w, lo, hi, nb, h)
        _kick_rows(x, w, w, max(lo - 1, 0), min(hi - 1, n - 1), nb, n, im, k, k3, kl, kr, k3l, k3r, left, right,
                   h, _int(_LEAPFROG))
        _drift_rows(x, w, max(lo - 2, 0), max(hi - 2, 0), nb, h)
        _kick_rows(x, w, w, max(lo - 3, 0), max(hi - 3, 0), nb, n, im, k, k3, kl, kr, k3l, k3r, left, right,
                   h, _int(_LEAPFROG))
        lo = hi
    _kick_rows(x, w, w, n - 1, n, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, h, _int(_LEAPFROG))
    _drift_rows(x, w, max(n - 2, 0), n, nb, h)
    _kick_rows(x, w, w, max(n - 3, 0), n, nb, n, im, k, k3, kl, kr, k3l, k3r, left, right, h, _int(_LEAPFROG))


def _half_kick_impl(v, a, c):
    """v ← v + c a (entry to / exit from the half-step velocity form)."""
    for e in range(v.shape[0]):
        v[e] = v[e] + c * a[e]


def _stream_impl(x, v, c):
    """The floor's sweep: x ← x + c v; v ← v − c x, one pass."""
    for e in range(x.shape[0]):
        x[e] = x[e] + c * v[e]
        v[e] = v[e] - c * x[e]


# jitted versions (set by compiled_kernels(); the implementations call these names)
_spring = _apply = _kick_end = _kick_flat = _kick_row_batch = _kick_rows = _drift_rows = _leapfrog_pair = None


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
def compiled_kernels():
    """Register the numba overloads and compile (or load from numba's cache) the kernels.

    Says so on stderr (one line) when nothing is cached yet: compiling takes seconds.
    Returns a namespace with ``force``, ``sweep``, ``half_kick`` and ``stream``.
    """
    import types as pytypes

    if not _numba_cache_present():
        from ..progress import note

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
        if isinstance(c, types.BaseTuple):  # a spring potential's parameters (s is 0 then)
            return lambda s, c, i, d: s + _law(d, *c)
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
    for name in _INNER:
        g[name] = jit(g[name + "_impl"])
    return pytypes.SimpleNamespace(force=jit(_force_impl), sweep=jit(_sweep_impl), half_kick=jit(_half_kick_impl),
                                   stream=jit(_stream_impl))


_INNER = ("_spring", "_apply", "_kick_end", "_kick_flat", "_kick_row_batch", "_kick_rows", "_drift_rows", "_leapfrog_pair")


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
        compiled_kernels().stream(x, v, float(c))
    else:
        x += c * v
        v -= c * x
