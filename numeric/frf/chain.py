"""The receptance of an open chain by dynamic stiffness: O(n) per frequency, relatively accurate.

Every element of an open chain is a two-terminal impedance: the masses and everything tied to
the ground, ``a_i = g_i − ω² m_i + iω c_i`` (wall springs g, ground dashpots c: Rayleigh's α·m
among them), and the element between i−1 and i, ``z_p = k_p + iω c_p`` (spring and dashpots
beside it: Rayleigh's β·k among them). The dynamic stiffness of the part left of a mass, seen
at that mass, is a continued fraction of series and parallel combinations,

    e_0 = a_0,   u_p = z_p + e_{p−1},   e_p = a_p + z_p e_{p−1} / u_p,

and likewise ``f`` from the right end. Then ``X_i = 1 / (e_i + z_{i+1} f_{i+1} / (z_{i+1} + f_{i+1}))``
for the unit force on mass i, and each step away from i multiplies by a transmissibility,
``X_p = X_{p−1} · z_p / (z_p + f_p)`` (to the right) — never a sum of terms of both signs
except ``u`` and ``a`` themselves, whose cancellation is the physics (a resonance of the part
beyond). Each rounding is a relative perturbation of an element (a dynamic stiffness scaled by
1 + δ is that of the same part with every element scaled by 1 + δ), so H is as accurate as
relative changes of the masses, springs and dashpots by O(n ε) allow, whatever their contrast;
the tridiagonal LU of K − ω²M + iωC it replaces loses κ·ε (forming k_{i−1} + k_i rounds a small
spring away next to a large one).

The sweep is compiled with numba (one pass per frequency, O(n) memory, no n × n); a ring (its
closing spring makes a loop) goes through the tridiagonal solve of :mod:`numeric.frf.response`.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from ..io.array_record import array_record
from ..errors import RunRefused
from .scaled import mp_split, unscale


@array_record
class ChainElements:
    """An open chain as impedances: per mass (n,) and per link between p−1 and p (index p, shape (n,); p = 0 unused).

    Attributes
    ----------
    mass, ground_k, ground_c : ndarray, shape (n,)
        Masses, wall springs and ground dashpots at each mass.
    link_k, link_c : ndarray, shape (n,)
        Spring and dashpot constants between masses p−1 and p (entry 0 is 0).
    """

    mass: np.ndarray
    ground_k: np.ndarray
    ground_c: np.ndarray
    link_k: np.ndarray
    link_c: np.ndarray

    @property
    def n(self) -> int:
        return int(self.mass.shape[0])


def _scatter(n: int, ends: np.ndarray, values: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray]:
    """Split elements into ground terms per mass and link terms per position (sums of positive numbers)."""
    ends = np.asarray(ends, dtype=np.intp).reshape(-1, 2)
    values = np.asarray(values, dtype=float).reshape(-1)
    lo, hi = np.minimum(ends[:, 0], ends[:, 1]), np.maximum(ends[:, 0], ends[:, 1])
    ground = lo < 0
    link = ~ground & (hi - lo == 1)
    if np.any(~ground & ~link & (lo != hi)):
        raise RunRefused(f"frequency response of a chain: its {what} couple masses further apart than "
                         "neighbours (accepted: neighbours, the ground)", quantity="frf")
    g = np.zeros(n)
    np.add.at(g, hi[ground], values[ground])
    z = np.zeros(n)
    np.add.at(z, hi[link], values[link])
    return g, z


def chain_elements(masses: np.ndarray, spring_ends: np.ndarray, stiffness: np.ndarray,
                   damper_ends: np.ndarray | None = None, damping: np.ndarray | None = None) -> ChainElements:
    """The impedances of an open chain from its element lists (walls are -1)."""
    m = np.asarray(masses, dtype=float)
    n = int(m.shape[0])
    gk, zk = _scatter(n, spring_ends, stiffness, "springs")
    if damper_ends is None:
        gc, zc = np.zeros(n), np.zeros(n)
    else:
        gc, zc = _scatter(n, damper_ends, damping, "dashpots")
    return ChainElements(m, gk, gc, zk, zc)


#: A sum that rounds to exactly 0 (the dynamic stiffness of a part exactly at its float64 resonance) is
#: taken as this fraction of its largest term: the same sum after a relative change of one element by
#: ε/2, inside the sweep's own rounding (module docstring) — never a division by zero.
NUDGE = 2.0 ** -53


def _nonzero(s, a, b):
    """``s = a + b``, or (``s`` exactly 0) the sum after a relative change of ε/2 of the larger term."""
    if s == 0:
        scale = max(abs(a), abs(b))
        return complex(scale * NUDGE, 0.0) if scale > 0 else complex(1.0, 0.0)
    return s


def _renorm(x):
    """``(m, k)`` with ``x = m · 2**k`` exactly and ``max(|Re m|, |Im m|)`` in [1/2, 1) (``x`` 0 or not
    finite: ``(x, 0)``): a power of two carried apart, so products of transmissibilities never
    underflow (a far transfer above the band: |H| below 1e-308, its phase still known)."""
    a = max(abs(x.real), abs(x.imag))
    if not (0.0 < a < np.inf):
        return x, 0
    k = math.frexp(a)[1]
    return complex(math.ldexp(x.real, -k), math.ldexp(x.imag, -k)), k


def _pow2(k):
    """``2.0**k`` as a float, 0 below the float64 range and inf above it (never an OverflowError)."""
    if k > 1023:
        return np.inf
    if k < -1074:
        return 0.0
    return math.ldexp(1.0, k)


def _receptance_impl(m, gk, gc, zk, zc, omega, i, o, out, expo):
    """H(ω_w) = out_w · 2**expo_w = X_o / F_i for each ω_w (the sweep of the module docstring): the complex
    mantissa ``out`` (W,) and the binary exponent ``expo`` (W,) int64, carried apart (:func:`_renorm`)."""
    n = m.shape[0]
    for w in range(omega.shape[0]):
        om = omega[w]
        om2 = om * om
        # left of i (and the transmissibilities towards o < i)
        e = complex(gk[0] - om2 * m[0], om * gc[0])
        prod_left = complex(1.0, 0.0)
        k_left = 0
        for p in range(1, i + 1):
            z = complex(zk[p], om * zc[p])
            u = _nonzero(z + e, z, e)  # z = 0 (no link): u = 1, nothing passes
            if p > o:
                prod_left, d = _renorm(prod_left * (z / u))
                k_left += d
            e = complex(gk[p] - om2 * m[p], om * gc[p]) + z * e / u
        # right of i (and towards o > i)
        t = complex(0.0, 0.0)
        prod_right = complex(1.0, 0.0)
        k_right = 0
        if i < n - 1:
            f = complex(gk[n - 1] - om2 * m[n - 1], om * gc[n - 1])
            for p in range(n - 1, i, -1):
                z = complex(zk[p], om * zc[p])
                u = _nonzero(z + f, z, f)
                if p <= o:
                    prod_right, d = _renorm(prod_right * (z / u))
                    k_right += d
                if p - 1 > i:
                    f = complex(gk[p - 1] - om2 * m[p - 1], om * gc[p - 1]) + z * f / u
                else:
                    t = z * f / u
        x0, k0 = _renorm(1.0 / _nonzero(e + t, e, t))
        h, d = _renorm(x0 * prod_left * prod_right)
        out[w] = h
        expo[w] = k0 + k_left + k_right + d


@functools.lru_cache(maxsize=1)
def _kernel():
    from ..compiled.fast_kernels import available

    if available():
        import numba
        from numba.extending import register_jitable

        for helper in (_nonzero, _renorm, _pow2):  # callable from the compiled sweep
            register_jitable(helper)
        return numba.njit(cache=True)(_receptance_impl)
    return _receptance_impl


def _certified_impl(m, gk, gc, zk, zc, omega, i, o, out, expo, bound, bexpo):
    """H(ω_w) = out_w · 2**expo_w and a bound on its error per frequency, bound_w · 2**bexpo_w: every
    rounding of the sweep is a relative change of an element by at most γ, so
    ``|ΔH| ≤ γ Σ_e |p_e ∂H/∂p_e|`` with ``∂H/∂k = −(bᵀx)(bᵀy)`` for a link (x, y: the responses to unit
    forces on the input and the output), ``ω² m x_p y_p`` for a mass, ``g x_p y_p`` for the ground;
    ``bound`` gets that sum (times γ: the caller's). The responses come from the left and right
    dynamic stiffnesses ``e``, ``f`` by transmissibilities, the link stretches ``x_p − x_{p−1}``
    likewise (no difference of two displacements is formed); x and y are carried as mantissas with
    binary exponents (:func:`_renorm`: far from the force they fall below 1e-308), and the sum is
    taken relative to ``2**bexpo``, the scale of |y_i| = |H|."""
    n = m.shape[0]
    a = np.empty(n, dtype=np.complex128)
    z = np.empty(n, dtype=np.complex128)
    e = np.empty(n, dtype=np.complex128)
    f = np.empty(n, dtype=np.complex128)
    ue = np.empty(n, dtype=np.complex128)  # 1 / (z_p + e_{p−1}) and 1 / (z_p + f_p): one division each,
    uf = np.empty(n, dtype=np.complex128)  # shared by the sweeps and both responses
    ay = np.empty(n)  # |y_p| and |y_p − y_{p−1}| of the response to the unit force on the output,
    sy = np.zeros(n)  # as mantissas with binary exponents
    ay_k = np.zeros(n, dtype=np.int64)
    sy_k = np.zeros(n, dtype=np.int64)
    for w in range(omega.shape[0]):
        om = omega[w]
        om2 = om * om
        for p in range(n):
            a[p] = complex(gk[p] - om2 * m[p], om * gc[p])
            z[p] = complex(zk[p], om * zc[p])
        e[0] = a[0]
        for p in range(1, n):
            ue[p] = 1.0 / _nonzero(z[p] + e[p - 1], z[p], e[p - 1])
            e[p] = a[p] + z[p] * e[p - 1] * ue[p]
        f[n - 1] = a[n - 1]
        for p in range(n - 2, -1, -1):
            uf[p + 1] = 1.0 / _nonzero(z[p + 1] + f[p + 1], z[p + 1], f[p + 1])
            f[p] = a[p] + z[p + 1] * f[p + 1] * uf[p + 1]
        # y (force on o): magnitudes kept; then x (force on i) summed against them on the fly
        t = complex(0.0, 0.0)
        if o < n - 1:
            t = z[o + 1] * f[o + 1] * uf[o + 1]
        y0, y0_k = _renorm(1.0 / _nonzero(e[o] + t, e[o], t))
        y, yk = y0, y0_k
        ay[o] = abs(y)
        ay_k[o] = yk
        for p in range(o + 1, n):
            s, d = _renorm(y * f[p] * uf[p])
            sy[p] = abs(s)
            sy_k[p] = yk + d
            y, d = _renorm(y * z[p] * uf[p])
            yk += d
            ay[p] = abs(y)
            ay_k[p] = yk
        y, yk = y0, y0_k
        for p in range(o, 0, -1):
            s, d = _renorm(y * e[p - 1] * ue[p])
            sy[p] = abs(s)
            sy_k[p] = yk + d
            y, d = _renorm(y * z[p] * ue[p])
            yk += d
            ay[p - 1] = abs(y)
            ay_k[p - 1] = yk
        ref = ay_k[i]  # |y_i| = |H| (Z symmetric): the scale of every term of the sum
        t = complex(0.0, 0.0)
        if i < n - 1:
            t = z[i + 1] * f[i + 1] * uf[i + 1]
        x0, x0_k = _renorm(1.0 / _nonzero(e[i] + t, e[i], t))
        total = (om2 * m[i] + gk[i] + om * gc[i]) * abs(x0) * ay[i] * _pow2(x0_k + ay_k[i] - ref)
        x, xk = x0, x0_k
        for p in range(i + 1, n):
            s, d = _renorm(x * f[p] * uf[p])
            total += (zk[p] + om * zc[p]) * abs(s) * sy[p] * _pow2(xk + d + sy_k[p] - ref)
            x, d = _renorm(x * z[p] * uf[p])
            xk += d
            total += (om2 * m[p] + gk[p] + om * gc[p]) * abs(x) * ay[p] * _pow2(xk + ay_k[p] - ref)
            if p == o:
                out[w] = x
                expo[w] = xk
        x, xk = x0, x0_k
        for p in range(i, 0, -1):
            s, d = _renorm(x * e[p - 1] * ue[p])
            total += (zk[p] + om * zc[p]) * abs(s) * sy[p] * _pow2(xk + d + sy_k[p] - ref)
            x, d = _renorm(x * z[p] * ue[p])
            xk += d
            total += (om2 * m[p - 1] + gk[p - 1] + om * gc[p - 1]) * abs(x) * ay[p - 1] * _pow2(xk + ay_k[p - 1] - ref)
            if p - 1 == o:
                out[w] = x
                expo[w] = xk
        if o == i:
            out[w] = x0
            expo[w] = x0_k
        bound[w] = total
        bexpo[w] = ref


@functools.lru_cache(maxsize=1)
def _certified_kernel():
    from ..compiled.fast_kernels import available

    if available():
        import numba
        from numba.extending import register_jitable

        for helper in (_nonzero, _renorm, _pow2):  # callable from the compiled sweep
            register_jitable(helper)
        return numba.njit(cache=True)(_certified_impl)
    return _certified_impl


#: Relative change of an element that one sweep's roundings amount to (a few operations per element).
GAMMA = 16 * float(np.finfo(float).eps)
#: Largest certified error of |H| (relative) accepted from float64; beyond it the mpmath sweep.
CERTIFIED = 1e-11
#: Most mass-frequencies (n × uncertified frequencies) swept in mpmath per response (~3 s); past it the
#: float64 value stands, with its certified bound said in a note.
MP_BUDGET = 20_000
#: Two mpmath precisions agreeing to this settle a value.
MP_AGREE = 1e-15


def chain_receptance(el: ChainElements, omega: np.ndarray, input: int, output: int,
                     certify: bool = False, notes: list | None = None, budget: dict | None = None,
                     scaled: bool = False):
    """``H(iω) = X_output / F_input`` of an open chain, shape (W,), complex (module docstring).

    Parameters
    ----------
    el : ChainElements
    omega : ndarray, shape (W,)
        Angular frequencies [rad/s].
    input, output : int
        Mass indices.
    certify : bool
        Bound each value's error (:func:`_certified_impl`, O(n) more per frequency); a value not
        certified to :data:`CERTIFIED` (near a light resonance the sweep's error is ε/ζ) is swept again
        in mpmath (:func:`mp_chain_receptance`) within :data:`MP_BUDGET`, past which the float64 value
        stands and ``notes`` gets one line with its bound.
    budget : dict, optional
        ``{"left": mass-frequencies}`` shared by the calls of one response (default: a fresh
        :data:`MP_BUDGET`); decremented here.
    scaled : bool
        Return ``(mantissa, expo)`` with ``H = mantissa · 2**expo`` (complex (W,), int64 (W,)): H
        below the float64 range (a far transfer above the band) keeps its phase in the mantissa.
    """
    omega = np.ascontiguousarray(np.asarray(omega, dtype=float).reshape(-1))
    out = np.empty(omega.shape[0], dtype=complex)
    expo = np.zeros(omega.shape[0], dtype=np.int64)
    if not certify:
        _kernel()(el.mass, el.ground_k, el.ground_c, el.link_k, el.link_c, omega, int(input), int(output), out,
                  expo)
        return (out, expo) if scaled else unscale(out, expo)
    bound = np.empty(omega.shape[0])
    bexpo = np.zeros(omega.shape[0], dtype=np.int64)
    _certified_kernel()(el.mass, el.ground_k, el.ground_c, el.link_k, el.link_c, omega, int(input), int(output),
                        out, expo, bound, bexpo)
    with np.errstate(all="ignore"):  # both relative to their own powers of two
        rel = GAMMA * np.ldexp(bound, bexpo - expo) / np.abs(out)
    bad = np.flatnonzero(~(rel <= CERTIFIED))
    budget = {} if budget is None else budget
    left = budget.setdefault("left", MP_BUDGET)
    allowed = max(0, left // max(el.n, 1))
    for j in bad[:allowed].tolist():
        out[j], expo[j] = mp_chain_receptance(el, float(omega[j]), int(input), int(output), scaled=True)
    budget["left"] = left - el.n * min(allowed, bad.size)
    rest = bad[allowed:]
    if rest.size and notes is not None:
        worst = budget["worst"] = max(budget.get("worst", 0.0), float(np.nanmax(np.where(np.isfinite(rel[rest]),
                                                                                         rel[rest], np.inf))))
        note = (f"H near resonances is certified to {worst:.2g} relative only at some frequencies: the float64 "
                f"limit of the dynamic-stiffness sweep of {el.n} masses (ε/ζ near a light resonance, ε/gap near "
                f"an undamped one; extended precision takes at most {MP_BUDGET:,} mass-frequencies)")
        notes[:] = [n for n in notes if not n.startswith("H near resonances is certified to")] + [note]
    return (out, expo) if scaled else unscale(out, expo)


def mp_chain_receptance(el: ChainElements, omega: float, input: int, output: int, scaled: bool = False):
    """The sweep of :func:`_receptance_impl` in mpmath (element values read exactly), doubling the digits
    from 30 beyond the decades the element terms span until two agree to :data:`MP_AGREE`; with
    ``scaled``, ``(mantissa, expo)`` as :func:`chain_receptance` (H below 1e-308 keeps its phase)."""
    import mpmath

    from .dense import MP_MAX_DPS

    with np.errstate(all="ignore"):
        terms = np.concatenate([el.ground_k, omega * el.ground_c, omega * omega * el.mass, el.link_k,
                                omega * el.link_c])
    terms = terms[np.isfinite(terms) & (terms > 0)]
    dps = int(min(MP_MAX_DPS, 30 + math.ceil(math.log10(terms.max()) - math.log10(terms.min())))) if terms.size else 30
    prev = None
    while True:
        with mpmath.workdps(dps):
            cur = _mp_sweep(el, mpmath.mpf(omega), input, output, mpmath)
            if prev is not None and abs(cur - prev) <= MP_AGREE * abs(cur):
                return mp_split(cur, mpmath) if scaled else complex(cur)
            if prev is not None and complex(cur) == 0 and complex(prev) == 0:  # shrinking with the digits below
                return (0j, 0) if scaled else 0j  # float64's range: an exact 0 (a part's exact resonance, NUDGE)
        if dps >= MP_MAX_DPS:
            raise RunRefused(f"frequency response of a chain at ω = {omega:.6g} rad/s: H did not settle within "
                             f"{MP_MAX_DPS} digits", quantity="frf")
        prev, dps = cur, min(2 * dps, MP_MAX_DPS)


def _mp_sweep(el: ChainElements, om, i: int, o: int, mpmath):
    """One sweep at the current precision (the module docstring's recursion)."""
    mp = lambda v: mpmath.mpf(float(v))  # noqa: E731  (exact: 53 bits)
    n = el.n
    a = [mpmath.mpc(mp(el.ground_k[p]) - om * om * mp(el.mass[p]), om * mp(el.ground_c[p])) for p in range(n)]
    z = [mpmath.mpc(mp(el.link_k[p]), om * mp(el.link_c[p])) for p in range(n)]
    e = a[0]
    left = mpmath.mpc(1)
    tiny = mpmath.mpf(2) ** -mpmath.mp.prec  # an exact 0 sum: the relative change of one ulp (as NUDGE)

    def nonzero(s, a, b):
        return s if s != 0 else (max(abs(a), abs(b)) * tiny or mpmath.mpf(1))
    for p in range(1, i + 1):
        u = nonzero(z[p] + e, z[p], e)
        if p > o:
            left *= z[p] / u
        e = a[p] + z[p] * e / u
    t, right = mpmath.mpc(0), mpmath.mpc(1)
    if i < n - 1:
        f = a[n - 1]
        for p in range(n - 1, i, -1):
            u = nonzero(z[p] + f, z[p], f)
            if p <= o:
                right *= z[p] / u
            if p - 1 > i:
                f = a[p - 1] + z[p] * f / u
            else:
                t = z[p] * f / u
    return left * right / nonzero(e + t, e, t)


__all__ = ["ChainElements", "chain_elements", "chain_receptance", "mp_chain_receptance"]
