"""Response spectra of an accelerogram: SD, PSV, PSA of the damped single-degree-of-freedom oscillator.

For each natural period T (ω = 2π/T) and damping ratio ζ the oscillator

    ü + 2ζω u̇ + ω² u = −a_g(t)

(u relative to the ground) is driven by the record ``a_g``, linear between its rows and zero
outside them (the convention of ``[ground]`` tables). The spectral displacement is
SD = max over t ≥ t₀ of |u(t)|, the pseudo-velocity PSV = ω·SD and the pseudo-acceleration
PSA = ω²·SD.

Exact for piecewise-linear input (Nigam & Jennings, BSSA 59, 1969): over a step of length h
with input linear from a_l to a_r the state maps exactly as

    [u, u̇](h) = Φ [u, u̇](0) + γ_l a_l + γ_r a_r,

so the samples carry no time-stepping error. The coefficients are *not* taken from the
textbook formulas (they divide by ω², ω³h and subtract nearly equal terms when ωh is small):
they are read off the exponential of the 4 × 4 augmented matrix in time units of h,
``expm([[0, 1, 0, 0], [−Ω², −2ζΩ, −1, 0], [0, 0, 0, 1], [0, 0, 0, 0]])`` with Ω = ωh, whose
entries are all of order one; one batched ``scipy.linalg.expm`` per (period, ζ, step length).

The peak between samples is not missed: every period is sampled at least
:data:`SAMPLES_PER_PERIOD` times per period (the record's linear pieces are split into k equal
sub-steps, exact again), and each sampled local maximum of |u| within
:data:`CANDIDATE_BAND` of the largest is refined to the exact stationary point u̇ = 0 by a
safeguarded Newton iteration on exact evaluations inside its sub-step. After the record ends
the oscillator vibrates freely (zero input) for 0.55 damped periods, long enough for the first
free extremum, the largest of the free decay.

The sweep over steps is one compiled loop (numba; the plain Python loop if numba cannot be
loaded), vectorised over (period, ζ) pairs only by the outer loop of that kernel.
"""

from __future__ import annotations

import functools
import math
from dataclasses import field

import numpy as np

from .array_record import array_record
from .errors import RunRefused

#: Least samples per natural period (record steps are split into equal sub-steps to reach it).
SAMPLES_PER_PERIOD = 32
#: Sampled local maxima of |u| within this fraction of the largest are refined to the exact peak
#: (a sinusoid sampled 32 times per period is within 1 - cos(pi/32) = 0.5 % of its peak).
CANDIDATE_BAND = 0.03
#: Most refined candidates per (period, ζ).
MAX_CANDIDATES = 8
#: Newton iterations of the refinement (safeguarded by bisection; converges in a few).
REFINE_ITERATIONS = 40
#: Default periods (s): log-spaced.
DEFAULT_PERIODS = (0.02, 10.0, 100)
#: Default damping ratio.
DEFAULT_ZETA = 0.05


@array_record
class Record:
    """An accelerogram: ``a_g`` linear between rows, zero outside.

    Attributes
    ----------
    t : ndarray, shape (R,)
        Strictly increasing times [s].
    a : ndarray, shape (R,)
        Ground acceleration [m/s²].
    name : str
    """

    t: np.ndarray
    a: np.ndarray
    name: str = "record"

    def __post_init__(self):
        t = np.asarray(self.t, dtype=float)
        a = np.asarray(self.a, dtype=float)
        if t.ndim != 1 or t.shape != a.shape or t.shape[0] < 2:
            raise ValueError(f"Record: t and a must have the same shape (R,), R >= 2; got {t.shape}, {a.shape}")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(a)) and np.all(np.diff(t) > 0)):
            raise ValueError("Record: times must be finite and strictly increasing, accelerations finite")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "a", a)

    @property
    def pga(self) -> float:
        """Peak ground acceleration max |a_g| [m/s²]."""
        return float(np.max(np.abs(self.a)))

    def uniform_step(self) -> float | None:
        """The step h when rows are ``t₀ + i·h`` to 1e-9 relative (decimal CSV times), else None."""
        h = (self.t[-1] - self.t[0]) / (self.t.shape[0] - 1)
        return h if np.max(np.abs(np.diff(self.t) - h)) <= 1e-9 * h else None


@array_record
class ResponseSpectrum:
    """Spectral ordinates of one record.

    Attributes
    ----------
    periods : ndarray, shape (P,)
        Natural periods T [s].
    zeta : ndarray, shape (Z,)
        Damping ratios.
    sd : ndarray, shape (Z, P)
        Spectral displacement max |u| [m].
    record : Record
    """

    periods: np.ndarray
    zeta: np.ndarray
    sd: np.ndarray
    record: Record = field(repr=False)

    @property
    def omega(self) -> np.ndarray:
        """ω = 2π/T, shape (P,)."""
        return 2.0 * np.pi / self.periods

    @property
    def psv(self) -> np.ndarray:
        """Pseudo-velocity ω·SD [m/s], shape (Z, P)."""
        return self.sd * self.omega[None, :]

    @property
    def psa(self) -> np.ndarray:
        """Pseudo-acceleration ω²·SD [m/s²], shape (Z, P)."""
        return self.sd * self.omega[None, :] ** 2

    def at(self, period: np.ndarray, zeta: np.ndarray) -> np.ndarray:
        """SD at given (period, ζ) pairs computed afresh (exact, not interpolated), shape of ``period``."""
        return spectral_displacement(self.record, period, zeta)

    def to_json(self) -> dict:
        return {"record": self.record.name, "pga": self.record.pga, "periods": self.periods.tolist(),
                "zeta": self.zeta.tolist(), "sd": self.sd.tolist(), "psv": self.psv.tolist(),
                "psa": self.psa.tolist(), "units": {"periods": "s", "sd": "m", "psv": "m/s", "psa": "m/s^2"}}

    def __repr__(self) -> str:
        return (f"ResponseSpectrum(record={self.record.name!r}, periods={self.periods.shape[0]} "
                f"({self.periods[0]:g} ... {self.periods[-1]:g} s), zeta={self.zeta.tolist()})")


# -- exact one-step maps -----------------------------------------------------------------------
def _augmented(omega_h: np.ndarray, zeta: np.ndarray, theta: np.ndarray | float = 1.0) -> np.ndarray:
    """``expm(θ·A)`` of the scaled augmented matrix (time unit h), shape (..., 4, 4).

    State ``(u, h·u̇, h²·a, h³·ȧ)``; every entry of A is O(1) for Ω = ωh up to a few.
    """
    om, z = np.broadcast_arrays(np.asarray(omega_h, dtype=float), np.asarray(zeta, dtype=float))
    theta = np.broadcast_to(np.asarray(theta, dtype=float), om.shape)
    A = np.zeros(om.shape + (4, 4))
    A[..., 0, 1] = 1.0
    A[..., 1, 0] = -om**2
    A[..., 1, 1] = -2.0 * z * om
    A[..., 1, 2] = -1.0
    A[..., 2, 3] = 1.0
    A = A * theta[..., None, None]
    return expm_small(A.reshape(-1, 4, 4)).reshape(A.shape)


#: Taylor degree of :func:`expm_small` (after scaling to norm <= 1/2 the remainder is below 1e-25).
_TAYLOR_DEGREE = 20


def expm_small(A: np.ndarray) -> np.ndarray:
    """``expm`` of a stack of small matrices by scaled Taylor series and squaring, shape (B, n, n).

    SciPy's ``expm`` handles one matrix per Padé call (milliseconds per 4 × 4 matrix in a
    stack); here the whole stack is one NumPy Horner loop. Each matrix is scaled by 2^-s
    (s from the largest ∞-norm of the stack) to norm <= 1/2, where the degree-20 Taylor
    polynomial is exact to below 1e-25 relative, and squared back s times.
    """
    A = np.asarray(A, dtype=float)
    norm = float(np.max(np.abs(A).sum(axis=-1))) if A.size else 0.0
    s = max(0, int(math.ceil(math.log2(norm / 0.5)))) if norm > 0.5 else 0
    X = A / 2.0**s
    eye = np.broadcast_to(np.eye(A.shape[-1]), A.shape)
    E = eye + X / _TAYLOR_DEGREE
    for k in range(_TAYLOR_DEGREE - 1, 0, -1):
        E = eye + np.matmul(X, E) / k
    for _ in range(s):
        E = np.matmul(E, E)
    return E


def step_map(omega: np.ndarray, zeta: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Exact one-step map of the oscillator for input linear over the step.

    ``[u, u̇](h) = Φ [u, u̇](0) + γ_l a_l + γ_r a_r``.

    Parameters
    ----------
    omega, zeta, h : array_like, broadcast to shape (...)

    Returns
    -------
    ndarray, shape (..., 2, 4)
        Columns Φ[:, 0], Φ[:, 1], γ_l, γ_r.
    """
    omega, zeta, h = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (omega, zeta, h)))
    E = _augmented(omega * h, zeta)
    out = np.empty(omega.shape + (2, 4))
    # u(h) = E00 u + E01 h u' + E02 h² a_l + E03 h² (a_r − a_l)
    out[..., 0, 0] = E[..., 0, 0]
    out[..., 0, 1] = E[..., 0, 1] * h
    out[..., 0, 2] = (E[..., 0, 2] - E[..., 0, 3]) * h**2
    out[..., 0, 3] = E[..., 0, 3] * h**2
    # h u'(h) = E10 u + E11 h u' + E12 h² a_l + E13 h² (a_r − a_l)
    out[..., 1, 0] = E[..., 1, 0] / h
    out[..., 1, 1] = E[..., 1, 1]
    out[..., 1, 2] = (E[..., 1, 2] - E[..., 1, 3]) * h
    out[..., 1, 3] = E[..., 1, 3] * h
    return out


# -- the sweep --------------------------------------------------------------------------------
def _sweep_impl(a, k, maps, tail, band, maxc, peak, cand_state, cand_input, cand_count):
    """For each oscillator p: march the record split into k[p] sub-steps per row interval with the
    exact map ``maps[p]`` (then ``tail[p]`` free sub-steps), find the largest sampled |u| (first
    pass), then collect the sub-steps bracketing each sampled local maximum of |u| within ``band``
    of it (second pass): the state at the bracket's left end and its input at both ends."""
    rows = a.shape[0]
    for p in range(k.shape[0]):
        kp = k[p]
        f00 = maps[p, 0, 0]
        f01 = maps[p, 0, 1]
        gl0 = maps[p, 0, 2]
        gr0 = maps[p, 0, 3]
        f10 = maps[p, 1, 0]
        f11 = maps[p, 1, 1]
        gl1 = maps[p, 1, 2]
        gr1 = maps[p, 1, 3]
        total = (rows - 1) * kp + tail[p]
        best = 0.0
        for sweep in range(2):
            u = 0.0
            v = 0.0
            pu = 0.0  # previous sample (for local maxima)
            pv = 0.0
            pal = 0.0
            par = 0.0
            ppu = 0.0  # the sample before that
            ppv = 0.0
            ppal = 0.0
            ppar = 0.0
            found = 0
            lo_thr = (1.0 - band) * best
            for s in range(total + 1):
                if s < total:
                    i = s // kp
                    if i < rows - 1:
                        m = s - i * kp
                        da = (a[i + 1] - a[i]) / kp
                        al = a[i] + m * da
                        ar = a[i] + (m + 1) * da if m + 1 < kp else a[i + 1]
                    else:
                        al = 0.0
                        ar = 0.0
                else:
                    al = 0.0
                    ar = 0.0
                # (u, v) is the sample at s; (al, ar) the input of the sub-step that starts there
                if sweep == 0:
                    if abs(u) > best:
                        best = abs(u)
                elif s >= 1 and abs(pu) >= lo_thr and abs(pu) >= abs(ppu) and abs(pu) >= abs(u) and abs(pu) > 0.0:
                    # sample s-1 is a local maximum of |u|: the peak is in the sub-step after it
                    # when |u| still grows there (u·u' > 0), else in the one before it
                    if pu * pv > 0.0:
                        su, sv, sl, sr = pu, pv, pal, par
                    else:
                        su, sv, sl, sr = ppu, ppv, ppal, ppar
                    slot = found
                    if found >= maxc:  # keep the largest: replace the smallest stored
                        slot = 0
                        for c in range(1, maxc):
                            if abs(cand_state[p, c, 2]) < abs(cand_state[p, slot, 2]):
                                slot = c
                        if abs(cand_state[p, slot, 2]) >= abs(pu):
                            slot = -1
                    if slot >= 0:
                        cand_state[p, slot, 0] = su
                        cand_state[p, slot, 1] = sv
                        cand_state[p, slot, 2] = pu
                        cand_input[p, slot, 0] = sl
                        cand_input[p, slot, 1] = sr
                        if found < maxc:
                            found += 1
                if s == total:
                    break
                ppu, ppv, ppal, ppar = pu, pv, pal, par
                pu, pv, pal, par = u, v, al, ar
                nu = f00 * u + f01 * v + gl0 * al + gr0 * ar
                v = f10 * u + f11 * v + gl1 * al + gr1 * ar
                u = nu
            if sweep == 1:
                cand_count[p] = found
        peak[p] = best


@functools.lru_cache(maxsize=1)
def _kernel():
    """The sweep compiled by numba (cached on disk), or the plain function without numba."""
    from .fast_kernels import available

    if not available():
        return _sweep_impl
    import numba

    return numba.njit(cache=True)(_sweep_impl)


def _refine(state: np.ndarray, inputs: np.ndarray, omega: np.ndarray, zeta: np.ndarray, h: np.ndarray) -> np.ndarray:
    """|u| at the exact stationary point u̇ = 0 inside each bracketing sub-step (or the larger end).

    Parameters
    ----------
    state : ndarray, shape (C, 2)
        (u, u̇) at the sub-step's start.
    inputs : ndarray, shape (C, 2)
        Input at the sub-step's two ends.
    omega, zeta, h : ndarray, shape (C,)

    Returns
    -------
    ndarray, shape (C,)
    """
    q0 = np.stack([state[:, 0], h * state[:, 1], h**2 * inputs[:, 0], h**2 * (inputs[:, 1] - inputs[:, 0])], axis=1)
    oh = omega * h

    def at(theta):
        q = np.einsum("cij,cj->ci", _augmented(oh, zeta, theta), q0)
        u, hv = q[:, 0], q[:, 1]
        a = inputs[:, 0] + (inputs[:, 1] - inputs[:, 0]) * theta
        # d(h u')/dθ = h² u'' = −2ζΩ (h u') − Ω² u − h² a
        return u, hv, -2.0 * zeta * oh * hv - oh**2 * u - h**2 * a

    u0, g0, _ = at(np.zeros_like(h))
    u1, g1, _ = at(np.ones_like(h))
    bracket = g0 * g1 < 0
    lo, hi = np.zeros_like(h), np.ones_like(h)
    glo = g0.copy()
    theta = np.full_like(h, 0.5)
    for _ in range(REFINE_ITERATIONS):
        u, g, dg = at(theta)
        same = np.sign(g) == np.sign(glo)
        lo = np.where(same, theta, lo)
        glo = np.where(same, g, glo)
        hi = np.where(same, hi, theta)
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = theta - g / dg
        ok = np.isfinite(newton) & (newton > lo) & (newton < hi)
        nxt = np.where(ok, newton, 0.5 * (lo + hi))
        if np.all(np.abs(nxt - theta) <= 1e-15):
            theta = nxt
            break
        theta = nxt
    u, _, _ = at(theta)
    ends = np.maximum(np.abs(u0), np.abs(u1))
    return np.where(bracket, np.maximum(np.abs(u), ends), ends)


def _validate(periods, zeta) -> tuple[np.ndarray, np.ndarray]:
    periods = np.atleast_1d(np.asarray(periods, dtype=float))
    zeta = np.atleast_1d(np.asarray(zeta, dtype=float))
    if periods.ndim != 1 or periods.size == 0 or not np.all(np.isfinite(periods) & (periods > 0)):
        raise RunRefused(f"periods {periods.tolist()[:5]!r}: accepted: finite periods > 0 s", quantity="periods")
    if zeta.ndim != 1 or zeta.size == 0 or not np.all(np.isfinite(zeta) & (zeta >= 0) & (zeta < 1)):
        raise RunRefused(f"zeta {zeta.tolist()[:5]!r}: accepted: damping ratios 0 <= zeta < 1", quantity="zeta")
    return periods, zeta


def spectral_displacement(record: Record, periods: np.ndarray, zeta: np.ndarray) -> np.ndarray:
    """SD = max_t |u(t)| for paired (period, ζ) arrays (broadcast), exact for piecewise-linear input.

    Parameters
    ----------
    record : Record
    periods, zeta : array_like, broadcast to shape (...)

    Returns
    -------
    ndarray, shape (...)
    """
    periods, zeta = np.broadcast_arrays(np.asarray(periods, dtype=float), np.asarray(zeta, dtype=float))
    shape = periods.shape
    T, z = _validate(periods.ravel(), zeta.ravel())
    h_rec = record.uniform_step()
    if h_rec is not None:
        return _sd_uniform(record.a, h_rec, T, z).reshape(shape)
    # non-uniform rows: march piece by piece (one exact map per distinct step length)
    return np.array([_sd_uniform_pieces(record, Ti, zi) for Ti, zi in zip(T, z)]).reshape(shape)


def _tail_steps(T: np.ndarray, z: np.ndarray, h_sub: np.ndarray) -> np.ndarray:
    """Free sub-steps after the record: 0.55 damped periods (the first free extremum)."""
    damped = T / np.sqrt(1.0 - z**2)
    return np.ceil(0.55 * damped / h_sub).astype(np.int64) + 2


def _sd_uniform(a: np.ndarray, h: float, T: np.ndarray, z: np.ndarray) -> np.ndarray:
    omega = 2.0 * np.pi / T
    k = np.maximum(1, np.ceil(SAMPLES_PER_PERIOD * h / T)).astype(np.int64)
    h_sub = h / k
    maps = np.ascontiguousarray(step_map(omega, z, h_sub))
    tail = _tail_steps(T, z, h_sub)
    P = T.shape[0]
    peak = np.zeros(P)
    cand_state = np.zeros((P, MAX_CANDIDATES, 3))
    cand_input = np.zeros((P, MAX_CANDIDATES, 2))
    count = np.zeros(P, dtype=np.int64)
    _kernel()(np.ascontiguousarray(a, dtype=float), k, maps, tail, CANDIDATE_BAND, MAX_CANDIDATES,
              peak, cand_state, cand_input, count)
    pid = np.repeat(np.arange(P), count)
    slot = np.concatenate([np.arange(c) for c in count]) if P else np.zeros(0, dtype=int)
    if pid.size:
        refined = _refine(cand_state[pid, slot, :2], cand_input[pid, slot], omega[pid], z[pid], h_sub[pid])
        np.maximum.at(peak, pid, refined)
    return peak


def _sd_uniform_pieces(record: Record, T: float, z: float) -> float:
    """SD of one oscillator on a record with unequal row spacing (one map per distinct step)."""
    t, a = record.t, record.a
    omega = 2.0 * np.pi / T
    k = np.maximum(1, np.ceil(SAMPLES_PER_PERIOD * np.diff(t) / T)).astype(np.int64)
    # resample every row interval into k equal sub-steps: exact (the input is linear on each)
    pieces_t = [np.linspace(t[i], t[i + 1], k[i] + 1)[:-1] for i in range(t.shape[0] - 1)] + [t[-1:]]
    tt = np.concatenate(pieces_t)
    aa = np.interp(tt, t, a)
    hs = np.diff(tt)
    uniq, inv = np.unique(hs, return_inverse=True)
    maps = step_map(omega, z, uniq)
    y = np.zeros(2)
    best, arg, states = 0.0, 0, np.zeros((tt.shape[0], 2))
    for s in range(hs.shape[0]):  # rare (hand-made records); the uniform route is the compiled one
        y = maps[inv[s]] @ np.array([y[0], y[1], aa[s], aa[s + 1]])
        states[s + 1] = y
    u = np.abs(states[:, 0])
    arg = int(np.argmax(u))
    best = float(u[arg])
    # the free decay and the refinement: reuse the uniform route on the last state's tail
    h_tail = T / SAMPLES_PER_PERIOD
    tail = int(_tail_steps(np.array([T]), np.array([z]), np.array([h_tail]))[0])
    m = step_map(omega, z, h_tail)
    yt = states[-1].copy()
    for _ in range(tail):
        yt = m @ np.array([yt[0], yt[1], 0.0, 0.0])
        best = max(best, abs(float(yt[0])))
    # refine around the sampled maximum inside the record
    cands = []
    for j in (arg - 1, arg):
        if 0 <= j < hs.shape[0]:
            cands.append((states[j], (aa[j], aa[j + 1]), hs[j]))
    if cands:
        st = np.array([c[0] for c in cands])
        inp = np.array([c[1] for c in cands])
        hh = np.array([c[2] for c in cands])
        best = max(best, float(np.max(_refine(st, inp, np.full(len(cands), omega), np.full(len(cands), z), hh))))
    return best


def response_spectrum(record: Record, zeta=DEFAULT_ZETA, periods=None) -> ResponseSpectrum:
    """SD, PSV and PSA of ``record`` at every (ζ, period) pair.

    Parameters
    ----------
    record : Record
    zeta : float or sequence of float
        Damping ratios, 0 <= ζ < 1 (default 0.05).
    periods : sequence of float, optional
        Natural periods [s] (default: 100 log-spaced from 0.02 to 10 s).

    Returns
    -------
    ResponseSpectrum
    """
    if periods is None:
        lo, hi, n = DEFAULT_PERIODS
        periods = np.geomspace(lo, hi, n)
    periods, zeta = _validate(periods, zeta)
    Tg, zg = np.meshgrid(periods, zeta)
    sd = spectral_displacement(record, Tg, zg)
    return ResponseSpectrum(periods, zeta, sd, record)


def design_spectrum_sa(periods_table: np.ndarray, sa_table: np.ndarray, periods: np.ndarray) -> np.ndarray:
    """Sa of a design spectrum (``T,Sa`` rows, linear between them) at ``periods``; NaN outside its range."""
    periods = np.asarray(periods, dtype=float)
    out = np.interp(periods, periods_table, sa_table)
    return np.where((periods < periods_table[0]) | (periods > periods_table[-1]), np.nan, out)


__all__ = ["Record", "ResponseSpectrum", "response_spectrum", "spectral_displacement", "step_map",
           "design_spectrum_sa", "SAMPLES_PER_PERIOD", "DEFAULT_ZETA", "DEFAULT_PERIODS"]
