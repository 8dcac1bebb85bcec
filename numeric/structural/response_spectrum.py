"""Response spectra of an accelerogram: SD, PSV, PSA of the damped single-degree-of-freedom oscillator.

For each natural period T (ω = 2π/T) and damping ratio ζ the oscillator

    ü + 2ζω u̇ + ω² u = −a_g(t)

(u relative to the ground, at rest at the first row) is driven by the record ``a_g``, linear
between its rows and zero outside them (the convention of ``[ground]`` tables). The spectral
displacement is

    SD = max over t ≥ t₀ of |u(t)|,

the peak over the record **and the free vibration after its last row** (:data:`SD_CONVENTION`);
``sd_record`` is the peak over the record alone. The pseudo-velocity is PSV = ω·SD and the
pseudo-acceleration PSA = ω²·SD.

The peaks are exact for the piecewise-linear input (:mod:`springchain.numeric.structural.sdof_peak`:
exact one-step maps, the peak between samples refined to u̇ = 0, row intervals of many periods in
closed form, the free vibration's first extremum in closed form), at a cost of at most
~:data:`~springchain.numeric.structural.sdof_peak.SAMPLES_PER_PERIOD` · :data:`~springchain.numeric.structural.sdof_peak.LONG_CYCLES`
sub-steps per row interval and oscillator, whatever the record's length over the period. Before
the sweep the accelerations are scaled by a power of two to at most 1, and each oscillator's time
by a power of two near its period (both exact), so no intermediate quantity leaves float64's range
for any accepted period (:data:`PERIOD_RANGE`) or record (times and accelerations within ±1e150).
A request whose work estimate exceeds :data:`MAX_WORK` sub-steps is refused in one line; the
sweep runs in chunks of about :data:`CHUNK_WORK`, with a progress line past a second and Ctrl-C
honoured between chunks.
"""

from __future__ import annotations

import math
from dataclasses import field

import numpy as np

from ..io.array_record import array_record
from ..errors import RunRefused
from .sdof_peak import LONG_CYCLES, LONG_INTERVAL_WORK, SAMPLES_PER_PERIOD

#: Default periods (s): log-spaced.
DEFAULT_PERIODS = (0.02, 10.0, 100)
#: Default damping ratio.
DEFAULT_ZETA = 0.05
#: Accepted natural periods [s]: with times within ±1e150 s, every row interval stays within float64
#: in units of the period (and the period's ω² within its range).
PERIOD_RANGE = (1e-150, 1e150)
#: Largest magnitude of a record's times [s] and accelerations [m/s²] (the ``[ground]`` tables' limit).
RECORD_VALUE_LIMIT = 1e150
#: Most oscillator sub-steps (work units) one call may take (~30 s at ~1.3e8 per second on one core).
MAX_WORK = 4e9
#: Work units per compiled call between progress updates (Ctrl-C is honoured between calls).
CHUNK_WORK = 2e7
#: Work units charged for a row interval whose sub-step map must be computed afresh (unequal rows).
MAP_WORK = 100
#: What SD means, stated in every output.
SD_CONVENTION = ("SD = max |u| over the record and the free vibration after its last row "
                 "(the free decay's first extremum, in closed form)")


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
        lim = RECORD_VALUE_LIMIT
        if not (np.all(np.abs(t) <= lim) and np.all(np.abs(a) <= lim) and np.all(t[1:] > t[:-1])):
            raise ValueError(f"Record: times must be strictly increasing, times and accelerations finite with "
                             f"magnitude <= {lim:g}")
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
        Spectral displacement [m]: max |u| over the record and the free vibration after it
        (:data:`SD_CONVENTION`).
    record : Record
    sd_record : ndarray, shape (Z, P), optional
        max |u| over the record alone [m] (≤ ``sd``).
    notes : tuple of str
        Float64 limits met (ordinates below the smallest normal number).
    """

    periods: np.ndarray
    zeta: np.ndarray
    sd: np.ndarray
    record: Record = field(repr=False)
    sd_record: np.ndarray | None = field(default=None, repr=False)
    notes: tuple = ()

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
        out = {"record": self.record.name, "pga": self.record.pga, "periods": self.periods.tolist(),
               "zeta": self.zeta.tolist(), "sd": self.sd.tolist(), "psv": self.psv.tolist(),
               "psa": self.psa.tolist(), "sd_convention": SD_CONVENTION,
               "units": {"periods": "s", "sd": "m", "psv": "m/s", "psa": "m/s^2", "sd_record": "m"},
               "notes": list(self.notes)}
        if self.sd_record is not None:
            out["sd_record"] = self.sd_record.tolist()
        return out

    def __repr__(self) -> str:
        return (f"ResponseSpectrum(record={self.record.name!r}, periods={self.periods.shape[0]} "
                f"({self.periods[0]:g} ... {self.periods[-1]:g} s), zeta={self.zeta.tolist()})")


# -- exact one-step maps (NumPy; the compiled sweep builds the same maps in sdof_peak) ------------
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


# -- the sweep ------------------------------------------------------------------------------------
def _validate(periods, zeta) -> tuple[np.ndarray, np.ndarray]:
    periods = np.atleast_1d(np.asarray(periods, dtype=float))
    zeta = np.atleast_1d(np.asarray(zeta, dtype=float))
    lo, hi = PERIOD_RANGE
    if periods.ndim != 1 or periods.size == 0 or not np.all((periods >= lo) & (periods <= hi)):
        raise RunRefused(f"periods {periods.tolist()[:5]!r}: accepted: periods {lo:g} <= T <= {hi:g} s",
                         quantity="periods")
    if zeta.ndim != 1 or zeta.size == 0 or not np.all((zeta >= 0) & (zeta < 1)):
        raise RunRefused(f"zeta {zeta.tolist()[:5]!r}: accepted: damping ratios 0 <= zeta < 1", quantity="zeta")
    return periods, zeta


def _intervals(record: Record) -> np.ndarray:
    """Row intervals, shape (R - 1,): equal when the rows are ``t₀ + i·h`` to 1e-9 relative (decimal CSV
    times; one sub-step map per oscillator), else the differences of the times."""
    h = record.uniform_step()
    return np.full(record.t.shape[0] - 1, h) if h is not None else np.diff(record.t)


def work_estimate(hs: np.ndarray, periods: np.ndarray) -> np.ndarray:
    """Sub-steps (work units) of one oscillator per period on row intervals ``hs``, shape of ``periods``.

    ⌈32·h/T⌉ per short interval (bounded above by 32·h/T + 1), :data:`LONG_INTERVAL_WORK` per long
    one, :data:`MAP_WORK` per change of interval length (a sub-step map computed afresh).
    """
    periods = np.asarray(periods, dtype=float)
    hs_sorted = np.sort(hs)
    cums = np.concatenate([[0.0], np.cumsum(hs_sorted)])
    n_short = np.searchsorted(hs_sorted, LONG_CYCLES * periods, side="right")
    short = SAMPLES_PER_PERIOD * cums[n_short] / periods + n_short
    changes = 1 + np.count_nonzero(hs[1:] != hs[:-1])
    return short + (hs.shape[0] - n_short) * float(LONG_INTERVAL_WORK) + MAP_WORK * changes


def _check_work(record: Record, total: float, pairs: int) -> None:
    """Refuse (one line naming the limit) a request of more than :data:`MAX_WORK` sub-steps."""
    if total > MAX_WORK:
        raise RunRefused(
            f"response spectrum of {record.name!r}: {total:.3g} oscillator sub-steps ({pairs} (period, zeta) "
            f"pairs on {record.t.shape[0]} rows; {SAMPLES_PER_PERIOD} per period, at most about "
            f"{LONG_INTERVAL_WORK} per row interval); accepted: at most {MAX_WORK:.0e} (fewer periods or damping "
            "ratios, longer periods, or fewer rows)", quantity="periods")


def _scaled_time(periods: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """k with 2^k nearest the period in log scale, and ω in units of 2^k s, shape (P,)."""
    k = np.round(np.log2(periods)).astype(np.int64)
    return k, 2.0 * np.pi / np.ldexp(periods, -k)


def spectral_displacement(record: Record, periods, zeta, *, progress: bool | None = None,
                          with_record: bool = False):
    """SD (see :data:`SD_CONVENTION`) for paired (period, ζ) arrays (broadcast), exact for
    piecewise-linear input.

    Parameters
    ----------
    record : Record
    periods, zeta : array_like, broadcast to shape (...)
        Periods within :data:`PERIOD_RANGE` [s], damping ratios 0 ≤ ζ < 1.
    progress : bool, optional
        A progress line on stderr past a second (default: on; ``SPRINGCHAIN_PROGRESS=0`` silences it).
    with_record : bool
        Also return the peak over the record alone and the notes.

    Returns
    -------
    ndarray, shape (...)
        SD [m]; with ``with_record``, ``(sd, sd_record, notes)``.

    Raises
    ------
    RunRefused
        Periods or ζ outside the accepted range; work beyond :data:`MAX_WORK`; an ordinate beyond
        float64's largest number.
    """
    from ..progress import Reporter
    from .sdof_peak import peaks

    periods, zeta = np.broadcast_arrays(np.asarray(periods, dtype=float), np.asarray(zeta, dtype=float))
    shape = periods.shape
    T, z = _validate(periods.ravel(), zeta.ravel())
    hs = _intervals(record)
    uniq, inverse = np.unique(T, return_inverse=True)
    per_period = work_estimate(hs, uniq)
    work = per_period[inverse]
    total = float(np.sum(work))
    _check_work(record, total, T.size)
    sd = np.zeros(T.shape)
    sd_rec = np.zeros(T.shape)
    pga = record.pga
    notes: list[str] = []
    if pga > 0.0 and T.size:
        e_a = math.frexp(pga)[1]  # pga < 2^e_a: accelerations scaled into (−1, 1), exactly
        a = np.ldexp(record.a, -e_a)
        k, om = _scaled_time(T)
        tscale = np.ldexp(1.0, -k)
        bar = Reporter("response spectrum", total=int(total), enabled=progress)
        chunk = np.floor((np.cumsum(work) - work) / CHUNK_WORK)  # a new compiled call every CHUNK_WORK units
        edges = [0, *(np.flatnonzero(np.diff(chunk)) + 1).tolist(), T.size]
        pk, pr = np.zeros(T.shape), np.zeros(T.shape)
        done = 0.0
        for start, stop in zip(edges[:-1], edges[1:]):
            pk[start:stop], pr[start:stop] = peaks(hs, a, om[start:stop], z[start:stop], tscale[start:stop])
            done += float(np.sum(work[start:stop]))
            bar.update(int(done))
        bar.close()
        with np.errstate(over="ignore", under="ignore"):  # out of float64's range: refused or noted below
            sd = np.ldexp(pk, 2 * k + e_a)  # back to metres: ×(2^k)²·2^e_a, exact unless out of range
            sd_rec = np.ldexp(pr, 2 * k + e_a)
        if not np.all(np.isfinite(sd)):
            j = int(np.argmin(np.isfinite(sd)))
            raise RunRefused(f"response spectrum of {record.name!r}: SD at T = {T[j]:.6g} s, zeta = {z[j]:g} exceeds "
                             "float64's largest number (1.8e308 m); accepted: records and periods whose response "
                             "is within float64's range", quantity="periods")
        low = np.count_nonzero((pk > 0) & (sd < np.finfo(float).tiny))
        if low:
            notes.append(f"{low} SD ordinate(s) below float64's smallest normal number (2.2e-308 m): shown with "
                         "fewer significant digits, or as 0")
    if with_record:
        return sd.reshape(shape), sd_rec.reshape(shape), tuple(notes)
    return sd.reshape(shape)


def response_spectrum(record: Record, zeta=DEFAULT_ZETA, periods=None, *, progress: bool | None = None) -> ResponseSpectrum:
    """SD, PSV and PSA of ``record`` at every (ζ, period) pair.

    Parameters
    ----------
    record : Record
    zeta : float or sequence of float
        Damping ratios, 0 <= ζ < 1 (default 0.05).
    periods : sequence of float, optional
        Natural periods [s] within :data:`PERIOD_RANGE` (default: 100 log-spaced from 0.02 to
        10 s). The result lists them in ascending order, whatever the order given.
    progress : bool, optional
        A progress line past a second (default: on).

    Returns
    -------
    ResponseSpectrum
        ``sd`` by :data:`SD_CONVENTION`; ``sd_record`` the peak over the record alone.
    """
    if periods is None:
        lo, hi, n = DEFAULT_PERIODS
        periods = np.geomspace(lo, hi, n)
    periods, zeta = _validate(periods, zeta)
    periods = np.sort(periods)
    _check_work(record, float(np.sum(work_estimate(_intervals(record), periods))) * zeta.size,
                periods.size * zeta.size)  # before the (Z, P) grids are made
    Tg, zg = np.meshgrid(periods, zeta)
    sd, sd_record, notes = spectral_displacement(record, Tg, zg, progress=progress, with_record=True)
    return ResponseSpectrum(periods, zeta, sd, record, sd_record, notes)


def design_spectrum_sa(periods_table: np.ndarray, sa_table: np.ndarray, periods: np.ndarray) -> np.ndarray:
    """Sa of a design spectrum (``T,Sa`` rows, linear between them) at ``periods``; NaN outside its range."""
    periods = np.asarray(periods, dtype=float)
    out = np.interp(periods, periods_table, sa_table)
    return np.where((periods < periods_table[0]) | (periods > periods_table[-1]), np.nan, out)


__all__ = ["Record", "ResponseSpectrum", "response_spectrum", "spectral_displacement", "step_map",
           "design_spectrum_sa", "work_estimate", "SAMPLES_PER_PERIOD", "DEFAULT_ZETA", "DEFAULT_PERIODS",
           "PERIOD_RANGE", "MAX_WORK", "SD_CONVENTION"]
