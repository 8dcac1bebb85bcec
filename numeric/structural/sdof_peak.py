"""The exact peak max |u(t)| of a damped single-degree-of-freedom oscillator driven by a
piecewise-linear record, over the record and the free vibration after it.

The oscillator ü + 2ζωu̇ + ω²u = −a(t) starts at rest at the first row; ``a`` is linear between
rows and zero after the last (the ``[ground]`` table convention). Its peak is found from three
exact pieces, each of bounded cost whatever the record's length over the period:

* **Short row intervals** (at most :data:`LONG_CYCLES` natural periods) are split into
  k = ⌈:data:`SAMPLES_PER_PERIOD` · h/T⌉ equal sub-steps and advanced by the exact one-step map of
  linear input (Nigam & Jennings). The map is read off the exponential of the scaled 4 × 4
  augmented matrix ``[[0, 1, 0, 0], [−Ω², −2ζΩ, −1, 0], [0, 0, 0, 1], [0, 0, 0, 0]]`` (Ω = ωg ≤ 2π/32
  for a sub-step g; its Taylor series to degree :data:`TAYLOR_DEGREE` is exact to ~1e-22), never
  from the textbook coefficients, which divide by ω²·ωg and cancel when ωg is small. Every sampled
  local maximum of |u| whose curvature bound could reach the running peak is refined to the exact
  stationary point u̇ = 0 inside its sub-step (Newton with bisection on the same series in the
  sub-step's time).
* **Long row intervals** (more than :data:`LONG_CYCLES` periods: a tiny period, or a gap in the
  rows) are not sub-stepped. On such an interval u = p + w, with p(t) = c₀ + c₁t the particular
  solution of the linear input and w the damped free vibration, of envelope E(t) = r·e^{−ζωt}. At a
  local maximum of u, u̇ = 0 gives u = F(t) = p(t) + ζκ + cos δ·√(E(t)² − κ²) (κ = c₁/ω,
  sin δ = ζ): F is monotone between the two times where E(t) = |κ|·√z±, with
  (1 − ζ²)ζ²z² − z + 1 = 0, so the largest local maximum is the first one, the last one before
  the interval's end, or one next to the time where E = |κ|·√z₋. Each of these lies within a damped
  period of its time; a window of ±:data:`WINDOW_PERIODS` damped periods around each is sampled
  and refined as above from the closed-form state at its start. Extrema after the time where the
  envelope falls below 2⁻⁵⁵ of the running peak cannot change it (u = p there to rounding: the
  value at that time and at the interval's end bound them). The state at the interval's end is
  the closed form. The closed forms divide by ω, which is harmless here: times are scaled by a
  power of two near the period, so ω ∈ [4.4, 8.9], and the interval is many periods long (no
  cancellation between p and w).
* **After the record** the oscillator vibrates freely from its end state (u, v). For ζ > 0 the
  first extremum after the end is the largest of the free decay (|u| at successive extrema falls
  by e^{−πζ/√(1−ζ²)}), at ω_d t₁ = x ∈ (0, π] with x = atan2(√(1−ζ²)·v, ωu + ζv) (mod π); there
  |u| = √(1−ζ²)·√(u² + S²)·e^{−ζx/√(1−ζ²)}, S = (v/ω + ζu)/√(1−ζ²). For ζ = 0 this is the
  amplitude √(u² + (v/ω)²). The tail's peak is the larger of that and |u| at the end.

Cost per oscillator and row interval: at most :data:`SAMPLES_PER_PERIOD` · :data:`LONG_CYCLES` = 512
sub-steps for a short one; for a long one three windows of 2 × :data:`WINDOW_PERIODS` damped periods
or up to the envelope's decay, whichever is shorter (~160–600 sub-steps, a few thousand at most as
ζ → 1; measured 4–13 µs per long interval), plus the refinements; memory O(1) beyond the record.
Rounding: the phase carries float64's relative error of ω and of the row times, so an undamped
oscillator's SD is good to ~(record length / T)·ε (measured 1.9e-13 at 600 periods; rounding level
for the damped ones and short records). Compiled by numba (the plain Python loops when numba
cannot be loaded).

Units: the caller scales the record so that the accelerations are at most 1 in magnitude and time
is measured in units of a power of two near the period (both exact); see
:func:`springchain.numeric.structural.response_spectrum.spectral_displacement`.
"""

from __future__ import annotations

import functools
import math

import numpy as np

#: Least samples per natural period inside a sub-stepped row interval (and in the windows of a long one).
SAMPLES_PER_PERIOD = 32
#: Row intervals longer than this many natural periods are analysed in closed form (windows), not sub-stepped.
LONG_CYCLES = 16
#: Half-width of a long interval's windows, in damped periods (the local maxima are at most 1.25 apart).
WINDOW_PERIODS = 2.5
#: Degree of the Taylor series of the sub-step exponential (remainder ≤ 1.44²⁵/25! ≈ 6e-22 for Ω ≤ 2π/32).
TAYLOR_DEGREE = 24
#: Newton (with bisection) iterations of the refinement to u̇ = 0; it converges in a few.
REFINE_ITERATIONS = 60
#: Extrema of a long interval whose free-vibration envelope is below this fraction of the running
#: peak are not searched (u equals the linear particular solution there to rounding).
NEGLIGIBLE = 2.0**-55
#: Slots of the stream state (the previous sample and the sub-step that ends at the current one).
_BEST, _HAVE, _UPP, _VPP, _A0, _A1, _G, _NSTATE = 0, 1, 2, 3, 4, 5, 6, 7
_TWO_PI = 2.0 * math.pi


# -- one sub-step: the exact map and the series of the refinement ---------------------------------
def _substep_map_impl(om, z, g, M):
    """Exact map of one sub-step of length g (input linear from a₀ to a₁) into ``M`` (2, 4):
    ``u₁ = M[0]·(u, v, a₀, a₁)``, ``v₁ = M[1]·(u, v, a₀, a₁)``.

    E = exp(A) of the scaled augmented matrix A (state u, g·u̇, g²·a₀, g²·(a₁ − a₀); Ω = ωg), by
    Horner's rule on its Taylor series (A·E has rows E₁, −Ω²E₀ − 2ζΩE₁ − E₂, E₃, 0).
    """
    Om = om * g
    b = 2.0 * z * Om
    c = Om * Om
    e = np.zeros((3, 4))  # rows 0, 1, 2 of the Horner iterate (row 3 is the unit row e₃ throughout)
    e[0, 0] = 1.0
    e[1, 1] = 1.0
    e[2, 2] = 1.0
    for n in range(TAYLOR_DEGREE, 0, -1):  # E ← I + A·E/n, column by column
        inv = 1.0 / n
        for j in range(4):
            new1 = (1.0 if j == 1 else 0.0) - (c * e[0, j] + b * e[1, j] + e[2, j]) * inv
            e[0, j] = (1.0 if j == 0 else 0.0) + e[1, j] * inv
            e[1, j] = new1
            e[2, j] = (1.0 if j == 2 else 0.0) + (inv if j == 3 else 0.0)
    e0 = e[0]
    e1 = e[1]
    g2 = g * g
    M[0, 0] = e0[0]
    M[0, 1] = e0[1] * g
    M[0, 2] = (e0[2] - e0[3]) * g2
    M[0, 3] = e0[3] * g2
    M[1, 0] = e1[0] / g
    M[1, 1] = e1[1]
    M[1, 2] = (e1[2] - e1[3]) * g
    M[1, 3] = e1[3] * g


def _refine_impl(u, v, a0, a1, g, om, z):
    """|u| at the stationary point u̇ = 0 inside the sub-step of length g that starts at (u, v) with
    input linear from a0 to a1; 0 when u̇ does not change sign there (the ends are samples).

    u(θg) = Σ cₙθⁿ with cₙ = (Aⁿq)₀/n! (the exponential's series, exact to ~1e-22 relative to the
    state for Ω ≤ 2π/32); Newton with bisection on du/dθ in [0, 1].
    """
    Om = om * g
    b = 2.0 * z * Om
    c = Om * Om
    q0, q1, q2, q3 = u, g * v, g * g * a0, g * g * (a1 - a0)
    cu = np.empty(TAYLOR_DEGREE + 1)
    cu[0] = q0
    for n in range(1, TAYLOR_DEGREE + 1):
        r0 = q1
        r1 = -c * q0 - b * q1 - q2
        r2 = q3
        inv = 1.0 / n
        q0, q1, q2, q3 = r0 * inv, r1 * inv, r2 * inv, 0.0
        cu[n] = q0
    f0 = cu[1]
    f1 = 0.0
    for n in range(TAYLOR_DEGREE, 0, -1):
        f1 += n * cu[n]
    if f0 == 0.0 or f1 == 0.0 or (f0 > 0.0) == (f1 > 0.0):
        return 0.0
    lo, hi, flo = 0.0, 1.0, f0
    th = 0.5
    for _ in range(REFINE_ITERATIONS):
        d1 = 0.0
        d2 = 0.0
        for n in range(TAYLOR_DEGREE, 1, -1):
            d1 = d1 * th + n * cu[n]
            d2 = d2 * th + n * (n - 1) * cu[n]
        d1 = d1 * th + cu[1]
        if d1 == 0.0:
            break
        if (d1 > 0.0) == (flo > 0.0):
            lo, flo = th, d1
        else:
            hi = th
        nxt = th - d1 / d2 if d2 != 0.0 else -1.0
        if not (lo < nxt < hi):
            nxt = 0.5 * (lo + hi)
        if abs(nxt - th) <= 4e-16:
            th = nxt
            break
        th = nxt
    val = 0.0
    for n in range(TAYLOR_DEGREE, -1, -1):
        val = val * th + cu[n]
    return abs(val)


# -- a stream of samples: local maxima of |u| and their refinement --------------------------------
def _march_impl(st, M, u, v, a_start, a_end, n, g, om, z):
    """Advance (u, v) by n equal sub-steps of length g (map ``M``), the input linear from a_start
    to a_end over them, keeping the running peak in ``st`` and refining each sampled local maximum
    of |u| that could exceed it. Returns the state after the n sub-steps."""
    da = (a_end - a_start) / n
    m00, m01, m02, m03 = M[0, 0], M[0, 1], M[0, 2], M[0, 3]
    m10, m11, m12, m13 = M[1, 0], M[1, 1], M[1, 2], M[1, 3]
    w2 = om * om
    zw2 = 2.0 * z * om
    g2 = g * g
    for m in range(n):
        a0 = a_start + m * da
        a1 = a_end if m + 1 == n else a_start + (m + 1) * da
        u1 = m00 * u + m01 * v + m02 * a0 + m03 * a1
        v1 = m10 * u + m11 * v + m12 * a0 + m13 * a1
        au = abs(u)
        if st[_HAVE] == 0.0:  # a stream's first sub-step: no earlier sample shows its peak
            val = _refine(u, v, a0, a1, g, om, z)
            if val > st[_BEST]:
                st[_BEST] = val
        elif au > 0.0 and au >= abs(st[_UPP]) and au >= abs(u1):
            # sample (u, v) is a local maximum of |u|: the true one is within a sub-step of it, and
            # exceeds it by at most max|ü|·g²/2 (bounded here with a factor 2 to spare)
            bound = au + (zw2 * max(abs(v), abs(st[_VPP]), abs(v1)) + 1.5 * w2 * au
                          + max(abs(a0), abs(a1), abs(st[_A0]))) * g2
            if bound >= st[_BEST]:
                if u * v > 0.0:  # |u| still grows at the sample: the peak is in the next sub-step
                    val = _refine(u, v, a0, a1, g, om, z)
                else:
                    val = _refine(st[_UPP], st[_VPP], st[_A0], st[_A1], st[_G], om, z)
                if val > st[_BEST]:
                    st[_BEST] = val
        if abs(u1) > st[_BEST]:
            st[_BEST] = abs(u1)
        st[_UPP] = u
        st[_VPP] = v
        st[_A0] = a0
        st[_A1] = a1
        st[_G] = g
        st[_HAVE] = 1.0
        u = u1
        v = v1
    return u, v


def _close_stream_impl(st, om, z):
    """End of a stream of samples (the record's end, or a window's): refine its last sub-step,
    whose peak no later sample can reveal."""
    if st[_HAVE] > 0.0:
        val = _refine(st[_UPP], st[_VPP], st[_A0], st[_A1], st[_G], om, z)
        if val > st[_BEST]:
            st[_BEST] = val
    st[_HAVE] = 0.0


# -- a long row interval: closed form and windows ---------------------------------------------------
def _state_at_impl(c0, c1, W0, W1, S, D, alpha, beta, anchor, off):
    """(u, u̇) at time ``anchor + off`` of a long interval in closed form, p + w.

    The phase β·anchor is taken once and ``off`` added by angle addition, so that a window near a
    late anchor (even where float64 cannot resolve ``anchor + off``) is sampled consistently with
    the state at the anchor itself.
    """
    e = math.exp(-(alpha * anchor + alpha * off))
    ca = math.cos(beta * anchor)
    sa = math.sin(beta * anchor)
    co = math.cos(beta * off)
    so = math.sin(beta * off)
    c = ca * co - sa * so
    s = sa * co + ca * so
    return (c0 + c1 * anchor) + c1 * off + e * (W0 * c + S * s), c1 + e * (W1 * c - D * s)


def _long_interval_impl(st, M, u0, v0, al, ar, h, om, z):
    """Peak of |u| over a row interval of many periods (see the module docstring); returns the
    state at its end (closed form).

    Windows are (anchor, lo, hi): times anchor + [lo, hi] with anchor 0, the stationary time of
    the local-maximum curve, or h."""
    cd = math.sqrt((1.0 - z) * (1.0 + z))
    alpha = z * om
    beta = om * cd
    s = (ar - al) / h
    c1 = -s / (om * om)
    c0 = -(al + 2.0 * z * om * c1) / (om * om)
    W0 = u0 - c0
    W1 = v0 - c1
    S = (W1 + alpha * W0) / beta
    D = (om * om * W0 + alpha * W1) / beta
    uh, vh = _state_at(c0, c1, W0, W1, S, D, alpha, beta, h, 0.0)
    r = math.hypot(W0, S)
    L = max(st[_BEST], abs(u0), abs(uh))
    if z > 0.0:
        tol = L * NEGLIGIBLE if L > 0.0 else r * 2.0**-1000
        t_neg = math.log(r / tol) / alpha if r > tol else 0.0
    else:
        t_neg = h
    tmax = min(h, t_neg)
    half = WINDOW_PERIODS * _TWO_PI / beta
    anc = np.zeros(3)
    lo = np.zeros(3)
    hi = np.zeros(3)
    hi[0] = min(half, tmax)
    nw = 1
    if z > 0.0 and c1 != 0.0:
        x = 4.0 * z * z * (1.0 - z) * (1.0 + z)
        zm = 2.0 / (1.0 + math.sqrt(max(0.0, 1.0 - x)))
        em = abs(c1) / om * math.sqrt(zm)
        if r > em:
            tm = math.log(r / em) / alpha
            if tm < tmax:
                anc[nw] = tm
                lo[nw] = -min(half, tm)
                hi[nw] = min(half, tmax - tm)
                nw += 1
    if tmax >= h:
        anc[nw] = h
        lo[nw] = -min(half, h)
        hi[nw] = 0.0
        nw += 1
    j = 0
    while j < nw:  # march the windows, merging overlaps into the earlier one (anchors ascending)
        anchor = anc[j]
        a = lo[j]
        b = hi[j]
        at_end = anchor == h
        while j + 1 < nw and (anc[j + 1] - anchor) + lo[j + 1] <= b:
            j += 1
            b = max(b, (anc[j] - anchor) + hi[j])
            at_end = at_end or anc[j] == h
        j += 1
        if not b > a:
            continue
        if anchor == 0.0 and a == 0.0:  # continues the stream from the interval's start
            uw = u0
            vw = v0
        else:  # a fresh stream from the closed-form state at the window's start
            _close_stream(st, om, z)
            uw, vw = _state_at(c0, c1, W0, W1, S, D, alpha, beta, anchor, a)
            if abs(uw) > st[_BEST]:
                st[_BEST] = abs(uw)
        n = max(1, int(math.ceil((b - a) * om * SAMPLES_PER_PERIOD / _TWO_PI)))
        g = (b - a) / n
        _substep_map(om, z, g, M)
        a_start = (al + s * anchor) + s * a
        a_end = ar if at_end else (al + s * anchor) + s * b
        _march(st, M, uw, vw, a_start, a_end, n, g, om, z)
        if not at_end:
            _close_stream(st, om, z)
    if t_neg < h:  # the bound of the extrema past t_neg: |u| there and at the end
        un, _ = _state_at(c0, c1, W0, W1, S, D, alpha, beta, 0.0, t_neg)
        if abs(un) > st[_BEST]:
            st[_BEST] = abs(un)
        st[_HAVE] = 0.0
    if abs(uh) > st[_BEST]:
        st[_BEST] = abs(uh)
    return uh, vh


# -- the free vibration after the record --------------------------------------------------------------
def _free_peak_impl(u, v, om, z):
    """max |u(t)| of the free vibration from (u, v) for t ≥ 0 (closed form; module docstring).

    Parameters
    ----------
    u, v : float
        Displacement and velocity at the record's end.
    om, z : float
        ω > 0 and 0 ≤ ζ < 1.

    Returns
    -------
    float
    """
    cd = math.sqrt((1.0 - z) * (1.0 + z))
    y = cd * v
    X = om * u + z * v
    if y < 0.0 or (y == 0.0 and X > 0.0):  # the root in (0, π]: the opposite direction (no x + π rounding)
        y = -y if y != 0.0 else 0.0
        X = -X
    x = math.atan2(y, X)
    S = (v / om + z * u) / cd
    first = cd * math.hypot(u, S) * math.exp(-z * x / cd)
    return max(abs(u), first)


# -- the sweep over oscillators ----------------------------------------------------------------------
def _peaks_impl(hs, a, omega, zeta, tscale, peak, peak_record):
    """Peaks of every oscillator p (ω = omega[p], ζ = zeta[p]) on the record with row intervals
    ``hs * tscale[p]`` and accelerations ``a``: over the record and the free vibration after it
    (``peak``), over the record alone (``peak_record``)."""
    st = np.zeros(_NSTATE)
    M = np.empty((2, 4))
    for p in range(omega.shape[0]):
        om = omega[p]
        z = zeta[p]
        sc = tscale[p]
        period = _TWO_PI / om
        for q in range(_NSTATE):
            st[q] = 0.0
        u = 0.0
        v = 0.0
        g_map = -1.0
        for i in range(hs.shape[0]):
            h = hs[i] * sc
            if not h > 0.0:  # below float64's range in these units: no effect
                continue
            cycles = h / period
            if cycles <= LONG_CYCLES:
                k = max(1, int(math.ceil(SAMPLES_PER_PERIOD * cycles)))
                g = h / k
                if g != g_map:
                    _substep_map(om, z, g, M)
                    g_map = g
                u, v = _march(st, M, u, v, a[i], a[i + 1], k, g, om, z)
            else:
                u, v = _long_interval(st, M, u, v, a[i], a[i + 1], h, om, z)
                g_map = -1.0
        _close_stream(st, om, z)
        peak_record[p] = st[_BEST]
        peak[p] = max(st[_BEST], _free_peak(u, v, om, z))


# jitted versions (set by _kernel(); the implementations call these names)
_substep_map = _substep_map_impl
_refine = _refine_impl
_march = _march_impl
_close_stream = _close_stream_impl
_state_at = _state_at_impl
_long_interval = _long_interval_impl
_free_peak = _free_peak_impl
_INNER = ("_substep_map", "_refine", "_march", "_close_stream", "_state_at", "_long_interval", "_free_peak")
#: The tail's closed form, callable from Python.
free_peak = _free_peak_impl


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


@functools.lru_cache(maxsize=1)
def _kernel():
    """The sweep compiled by numba (cached on disk), or the plain functions without numba."""
    from ..compiled.fast_kernels import COMPILE_NOTE, available

    if not available():
        return _peaks_impl
    if not _numba_cache_present():
        from ..progress import note

        note(COMPILE_NOTE)
    import numba

    g = globals()
    for name in _INNER:
        g[name] = numba.njit(cache=True)(g[name + "_impl"])
    return numba.njit(cache=True)(_peaks_impl)


def peaks(hs: np.ndarray, a: np.ndarray, omega: np.ndarray, zeta: np.ndarray,
          tscale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Peaks of |u| of oscillators on one scaled record (module docstring).

    Parameters
    ----------
    hs : ndarray, shape (R - 1,)
        Row intervals (≥ 0).
    a : ndarray, shape (R,)
        Accelerations at the rows, |a| ≤ 1 (zero after the last row).
    omega, zeta, tscale : ndarray, shape (P,)
        ω (in the scaled time of each oscillator), ζ in [0, 1), and the factor (a power of two)
        turning ``hs`` into that time.

    Returns
    -------
    peak, peak_record : ndarray, shape (P,)
        max |u| over the record and the free vibration after it; over the record alone.
    """
    P = omega.shape[0]
    peak = np.zeros(P)
    peak_record = np.zeros(P)
    _kernel()(np.ascontiguousarray(hs, dtype=float), np.ascontiguousarray(a, dtype=float),
              np.ascontiguousarray(omega, dtype=float), np.ascontiguousarray(zeta, dtype=float),
              np.ascontiguousarray(tscale, dtype=float), peak, peak_record)
    return peak, peak_record


#: Work units (sub-steps) charged per row interval of a long interval's windows (an estimate for
#: the budget, three windows of 2·WINDOW_PERIODS damped periods at ζ ≤ 0.6).
LONG_INTERVAL_WORK = int(3 * 2 * WINDOW_PERIODS * SAMPLES_PER_PERIOD * 1.25)

__all__ = ["peaks", "free_peak", "SAMPLES_PER_PERIOD", "LONG_CYCLES", "WINDOW_PERIODS", "LONG_INTERVAL_WORK"]
