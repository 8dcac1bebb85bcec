"""The receptance of a ``[masses]`` scene: a certified float64 solve, extended precision where needed.

1. **Float64, in the accurate modal basis.** ``x = Φ Z_q⁻¹ Φᵀ e_in`` with the M-orthonormal modes
   Φ and ω of the spring-factor SVD (:mod:`numeric.modes.spectrum`) and
   ``Z_q = diag((ω_j − ω)(ω_j + ω)) + iω G``, ``G = ΦᵀCΦ`` (dashpots from their elements;
   Rayleigh and modal damping diagonal by definition, :func:`numeric.modes.elements.modal_damping`).
   Proportional damping needs no solve at all (O(N²) per frequency), dashpots one N × N solve.
2. **A certificate per frequency.** With the residual ``r = e_in − Z x`` (K, C stamped from the
   elements) and the rounding allowance ``γ (|K| |x| + ω² M |x| + ω |C| |x|)`` (what forming Z and
   the product can hide), the error of ``x_out`` is bounded by ``Σ_j |(Z⁻¹)_{out,j}| (|r_j| + γ …)``,
   the row of Z⁻¹ being the solution for the unit force on the output (Z is symmetric), taken
   with a normwise allowance. Accepted when the bound is below :data:`CERTIFIED` of ``|x_out|``.
3. **Refinement with residuals in extended precision** where it is not: ``r`` from the elements
   in 50-digit arithmetic (x, ω and the parameters are exact binary numbers, so γ drops to
   ~1e-45), ``x_lo ← x_lo + Φ Z_q⁻¹ Φᵀ r`` (the corrections kept apart from x: a double-length
   solution), up to :data:`REFINE_STEPS` times, certified the same way — with the row of Z⁻¹ refined
   alike (a float64 row 1e12 off at a mass contrast of 1e150 certified a wrong H) and only once the
   last correction is below :data:`CONVERGED` of the value.
4. **Extended precision** for the frequencies the certificate still rejects: Gaussian elimination in
   mpmath on Z assembled exactly from the elements (parameters as exact binary fractions; modal
   damping from mpmath's ``eigsy``), at 30, 60, 120, … digits until two agree to 1e-15 —
   scenes of at most :data:`MPMATH_MAX_MASSES` masses, or banded ones of the same cost
   (:func:`mp_solvable`: chains of any practical length). Other larger scenes are refused at such a
   frequency in one line (never a silently wrong number).

A plain float64 LU of ``K − ω²M + iωC`` (the route this replaces) loses κ·ε: 45 % on four masses
on springs 1e-9 … 1e9, 150 % at 1e12 in the issue that asked for this.
"""

from __future__ import annotations

import math
from dataclasses import field

import numpy as np

from ..io.array_record import array_record
from ..modes.elements import Elements, incidence, modal_damping
from ..errors import RunRefused
from .scaled import mp_split, split
from ..modes.spectrum import spectrum, stiffness_matrix

#: Largest certified error of |H| (relative) accepted from the float64 route.
CERTIFIED = 1e-11
#: |H| moving by more than this (relative) when every element value changes in its last bit is said in a
#: note (the README's accuracy of H: its own conditioning at the scene's values can exceed it).
SENSITIVE = 1e-10
#: Normwise error allowed for the float64 row of Z⁻¹ that weights the certificate.
ROW_ALLOWANCE = 1e-6
#: Refinement steps (residuals in extended precision) before the mpmath solve.
REFINE_STEPS = 3
#: A refined value is certified only once its last correction is below this fraction of it.
CONVERGED = 1e-6
#: Largest scene solved in mpmath where float64 cannot be certified.
MPMATH_MAX_MASSES = 24
#: Two mpmath precisions agreeing to this relative difference settle a value.
MP_AGREE = 1e-15
#: Highest mpmath precision tried (decimal digits).
MP_MAX_DPS = 1000
#: Bytes of the (W, N, N) complex stack of frequencies solved at once by a dense solve (~32 MB).
_DENSE_BYTES = 32 * 2**20
_EPS = float(np.finfo(float).eps)


def _stamp(n: int, ends: np.ndarray, values: np.ndarray, absolute: bool) -> np.ndarray:
    """Σ v bbᵀ over elements (b the incidence row); with ``absolute`` every entry positive (|K|)."""
    B = incidence(n, ends)
    if absolute:
        B = np.abs(B)
    return B.T @ (np.asarray(values, dtype=float)[:, None] * B)


def dense_chunk(n: int) -> int:
    """Frequencies solved at once by a dense solve of ``n`` masses (bounds the stack by :data:`_DENSE_BYTES`)."""
    return max(1, _DENSE_BYTES // (16 * n * n))


@array_record
class DenseReceptance:
    """Certified receptances of one ``[masses]`` scene (see the module docstring).

    Build with :meth:`from_elements`; call :meth:`receptance`.
    """

    el: Elements = field(repr=False)
    omega_n: np.ndarray
    shapes: np.ndarray
    G: np.ndarray
    K: np.ndarray
    K_abs: np.ndarray
    C: np.ndarray
    C_abs: np.ndarray

    @classmethod
    def from_elements(cls, el: Elements) -> "DenseReceptance":
        n = el.n
        spec = spectrum(el.masses, el.spring_ends, el.stiffness)
        Phi, w = spec.shapes, spec.omega
        K = stiffness_matrix(n, el.spring_ends, el.stiffness)
        K_abs = _stamp(n, el.spring_ends, el.stiffness, True)
        C = _stamp(n, el.damper_ends, el.damping, False)
        C_abs = _stamp(n, el.damper_ends, el.damping, True)
        if el.rayleigh is not None:
            a, b = el.rayleigh
            C = C + a * np.diag(el.masses) + b * K
            C_abs = C_abs + a * np.diag(el.masses) + b * K_abs
        if el.modal_zeta is not None:
            MPhi = el.masses[:, None] * Phi
            d = 2.0 * el.modal_zeta * w
            C = C + (MPhi * d[None, :]) @ MPhi.T
            C_abs = C_abs + (np.abs(MPhi) * d[None, :]) @ np.abs(MPhi).T
        return cls(el, w, Phi, modal_damping(el, w, Phi), K, K_abs, C, C_abs)

    # -- float64 ----------------------------------------------------------------------------------
    def solve(self, omega: np.ndarray, col: int | np.ndarray) -> np.ndarray:
        """``x`` of ``Z(ω) x = e_col`` (or ``= col[w]`` for an array of right-hand sides, shape (W, N))
        for each ω by the modal route, shape (W, N), complex."""
        omega = np.asarray(omega, dtype=float).reshape(-1)
        wj, Phi, G = self.omega_n, self.shapes, self.G
        n = wj.shape[0]
        b = (np.broadcast_to(Phi[col], (omega.shape[0], n)) if np.ndim(col) == 0
             else np.asarray(col) @ Phi)  # Φᵀ (right-hand side), one row per frequency
        d = (wj[None, :] - omega[:, None]) * (wj[None, :] + omega[:, None])
        if self.el.proportional:
            q = b / (d + 1j * omega[:, None] * np.diag(G)[None, :])
            return q @ Phi.T
        out = np.empty((omega.shape[0], n), dtype=complex)
        chunk = dense_chunk(n)
        for lo in range(0, omega.shape[0], chunk):  # chunks of frequencies, not a loop over masses
            w = omega[lo:lo + chunk]
            Z = 1j * w[:, None, None] * G[None]
            Z[:, np.arange(n), np.arange(n)] += d[lo:lo + chunk]
            try:
                q = np.linalg.solve(Z, b[lo:lo + chunk].astype(complex)[..., None])[..., 0]
            except np.linalg.LinAlgError:  # Z overflowed or is singular in float64: left to the certificate
                q = np.full(b[lo:lo + chunk].shape, np.nan, dtype=complex)
            out[lo:lo + chunk] = q @ Phi.T
        return out

    def residual(self, omega: np.ndarray, x: np.ndarray, col: int) -> tuple[np.ndarray, np.ndarray]:
        """``r = e_col − Z x`` in float64 and what its rounding can hide, ``γ (|K||x| + ω²M|x| + ω|C||x|)``;
        both shape (W, N)."""
        m = self.el.masses
        w = omega[:, None]
        e = np.zeros(x.shape[1])
        e[col] = 1.0
        r = e[None, :] - (x @ self.K - (w * w) * m[None, :] * x + 1j * w * (x @ self.C))
        ax = np.abs(x)
        hidden = ax @ self.K_abs + (w * w) * m[None, :] * ax + w * (ax @ self.C_abs)
        return r, 4.0 * (x.shape[1] + 8) * _EPS * hidden

    def mp_residual(self, omega: np.ndarray, x: np.ndarray, col: int,
                    x_lo: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``r = e_col − Z (x + x_lo)`` with Z's elements in 50-digit arithmetic (x, x_lo, the parameters
        and ω are exact binary numbers), rounded to float64, and what it can hide (modal damping,
        whose C is a float64 product, keeps the float allowance); both shape (W, N)."""
        import mpmath

        el, n = self.el, self.el.n
        x_lo = np.zeros_like(x) if x_lo is None else x_lo
        r = np.empty(x.shape, dtype=complex)
        springs = list(zip(el.spring_ends.tolist(), el.stiffness.tolist()))
        dashpots = list(zip(el.damper_ends.tolist(), el.damping.tolist()))
        alpha, beta = el.rayleigh if el.rayleigh is not None else (0.0, 0.0)
        with mpmath.workdps(50):
            mp = lambda v: to_mp(v, mpmath)  # noqa: E731
            ks = [((a, b), mp(k)) for (a, b), k in springs]
            cs = [((a, b), mp(c)) for (a, b), c in dashpots]
            ms = [mp(v) for v in el.masses.tolist()]
            al, be = mp(alpha), mp(beta)
            for j, w in enumerate(omega.tolist()):  # the frequencies the float64 certificate rejected
                W = mp(w)
                X = [mpmath.mpc(mp(v.real) + mp(u.real), mp(v.imag) + mp(u.imag))
                     for v, u in zip(x[j].tolist(), x_lo[j].tolist())] + [mpmath.mpc(0)]  # X[-1]: the wall
                acc = [-W * W * ms[i] * X[i] + 1j * W * al * ms[i] * X[i] for i in range(n)]
                for (a, b), k in ks:
                    f = (k + 1j * W * be * k) * (X[a] - X[b])
                    if a >= 0:
                        acc[a] += f
                    if b >= 0:
                        acc[b] -= f
                for (a, b), c in cs:
                    f = 1j * W * c * (X[a] - X[b])
                    if a >= 0:
                        acc[a] += f
                    if b >= 0:
                        acc[b] -= f
                acc[col] -= 1
                r[j] = [-complex(v) for v in acc]
        hidden = np.zeros(x.shape)
        if el.modal_zeta is not None:  # its C is not an element sum: the float64 product and its allowance
            MPhi = el.masses[:, None] * self.shapes
            g = 2.0 * el.modal_zeta * self.omega_n
            Cm = (MPhi * g[None, :]) @ MPhi.T
            r -= 1j * omega[:, None] * ((x + x_lo) @ Cm)
            hidden = 4.0 * (n + 8) * _EPS * omega[:, None] * (np.abs(x) @ ((np.abs(MPhi) * g[None, :]) @ np.abs(MPhi).T))
        return r, hidden + 1e-45 * np.abs(r)

    def error_bound(self, x: np.ndarray, row: np.ndarray, r: np.ndarray, hidden: np.ndarray) -> np.ndarray:
        """Bound on ``|x_out − x_out,exact|`` per frequency, shape (W,) (step 2 of the module docstring).

        ``row`` is the float64 solution for the unit force on the output (the row of Z⁻¹); ``r`` and
        ``hidden`` from :meth:`residual` or :meth:`mp_residual`.
        """
        weight = np.abs(row) + ROW_ALLOWANCE * np.max(np.abs(row), axis=1, keepdims=True)
        return np.sum(weight * (np.abs(r) + hidden), axis=1)

    # -- the answer ---------------------------------------------------------------------------------
    def receptance(self, omega: np.ndarray, input: int, output: int, certify: bool = True,
                   notes: list | None = None, scaled: bool = False):
        """``H(iω) = X_output / F_input``, shape (W,), complex: certified float64 or mpmath.

        With ``scaled``, ``(mantissa, expo)``, ``H = mantissa · 2**expo`` (complex (W,), int64 (W,)): a
        certified value whose |H| is below the smallest normal float64 (a subnormal has lost digits,
        0 has lost everything) is solved in mpmath (:func:`mp_solvable` scenes) and split there, so
        its phase and magnitude are kept; other scenes keep the float64 value's.

        With ``notes`` (certified calls), one line is added where H itself is sensitive to the last
        bit of the element values (:meth:`rounding_sensitivity` above :data:`SENSITIVE`): the value
        returned is that of the elements as the generated module rounded them.

        Raises
        ------
        RunRefused
            At a frequency where float64 cannot be certified on a scene of more than
            :data:`MPMATH_MAX_MASSES` masses.
        """
        omega = np.asarray(omega, dtype=float).reshape(-1)
        x = self.solve(omega, input)
        H = x[:, output].copy()
        if not certify or omega.shape[0] == 0:
            return split(H) if scaled else H
        row = x if output == input else self.solve(omega, output)
        bad = np.flatnonzero(~(self.error_bound(x, row, *self.residual(omega, x, input)) <= CERTIFIED * np.abs(H)))
        x_lo = np.zeros_like(x)  # corrections, kept apart from x: x + x_lo is a double-length solution
        row_lo = np.zeros_like(row)
        r = None
        unsettled = np.zeros(omega.shape[0], dtype=bool)  # x + x_lo not converged (for the note below)
        for _ in range(REFINE_STEPS):  # refinement with residuals in extended precision
            if not bad.size:
                break
            w = omega[bad]
            if r is None:
                r, _ = self.mp_residual(w, x[bad], input, x_lo[bad])
            step = self.solve(w, r)
            x_lo[bad] += step
            H[bad] = x[bad, output] + x_lo[bad, output]
            if output != input:  # the certificate's weights (the row of Z⁻¹) refined alike: a float64 row
                rr, _ = self.mp_residual(w, row[bad], output, row_lo[bad])  # off by 1e12 certified a wrong H
                row_lo[bad] += self.solve(w, rr)
                weights = row[bad] + row_lo[bad]
            else:
                weights = x[bad] + x_lo[bad]
            r, hidden = self.mp_residual(w, x[bad], input, x_lo[bad])
            converged = np.abs(step[:, output]) <= CONVERGED * np.abs(H[bad])
            unsettled[bad] = ~converged
            ok = (self.error_bound(x[bad], weights, r, hidden) <= CERTIFIED * np.abs(H[bad])) & converged
            bad, r = bad[~ok], r[~ok]
        if bad.size and not mp_solvable(self.el):
            raise RunRefused(f"frequency response: H at {bad.size} of {omega.shape[0]} frequencies (first "
                             f"ω = {omega[bad[0]]:.6g} rad/s) cannot be certified to 1e-10 in float64 (parameter "
                             f"contrast), and the extended-precision solve takes at most {MPMATH_MAX_MASSES} "
                             f"masses (or N·b² ≤ {MPMATH_MAX_MASSES}³ for a banded Z of half-bandwidth b, "
                             "without modal damping)", quantity="frf")
        if bad.size:
            H[bad] = mp_receptance(self.el, omega[bad], input, output)
        if notes is not None:  # from the responses where they are settled (refined, or certified)
            keep = ~unsettled
            xs = (x + x_lo)[keep]
            ys = xs if output == input else (row + row_lo)[keep]
            with np.errstate(all="ignore"):
                rel = self.rounding_sensitivity(omega[keep], xs, ys) / np.abs(H[keep])
                worst = float(np.max(rel[np.isfinite(rel)], initial=0.0))
            if worst > SENSITIVE:
                note = (f"|H| at some frequencies moves by up to {worst:.2g} relative when each mass, spring and "
                        "dashpot value changes in its last bit (float64 rounding of the scene's expressions): the "
                        "values are exact for the elements as rounded, the scene itself is that sensitive there")
                notes[:] = [n for n in notes if not n.startswith("|H| at some frequencies moves by up to")] + [note]
        if not scaled:
            return H
        mantissa, expo = split(H)
        with np.errstate(all="ignore"):
            under = np.flatnonzero(np.abs(H) < np.finfo(float).tiny)
        if under.size and mp_solvable(self.el):  # below the float64 range: its digits (and, at 0, its phase) in mpmath
            mantissa[under], expo[under] = mp_receptance(self.el, omega[under], input, output, scaled=True)
        return mantissa, expo

    def rounding_sensitivity(self, omega: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """``ε Σ_e |p_e ∂H/∂p_e|`` over the masses, springs and dashpots (and Rayleigh's α, β): the first-order
        change of H when every element value changes by one rounding, shape (W,). ``x``, ``y``: the
        responses to unit forces on the input and the output, shape (W, N); ``∂H/∂k = −(bᵀx)(bᵀy)``,
        ``∂H/∂m_p = ω² x_p y_p``, ``∂H/∂c = −iω (bᵀx)(bᵀy)``."""
        el = self.el
        w = np.asarray(omega, dtype=float).reshape(-1, 1)
        ax, ay = np.abs(x), np.abs(y)
        Bk = incidence(el.n, el.spring_ends)
        kk = np.abs((x @ Bk.T) * (y @ Bk.T)) @ el.stiffness  # Σ k |bᵀx||bᵀy|, (W,)
        mm = (ax * ay) @ el.masses
        total = kk + w[:, 0] ** 2 * mm
        if el.damping.shape[0]:
            Bc = incidence(el.n, el.damper_ends)
            total = total + w[:, 0] * (np.abs((x @ Bc.T) * (y @ Bc.T)) @ el.damping)
        if el.rayleigh is not None:
            total = total + w[:, 0] * (abs(el.rayleigh[0]) * mm + abs(el.rayleigh[1]) * kk)
        return _EPS * total


# -- extended precision ----------------------------------------------------------------------------
def bandwidth(el: Elements) -> int:
    """Half-bandwidth of Z = K − ω²M + iωC in mass order: the largest |a − b| over springs and dashpots
    between two masses (0 for none)."""
    ends = [np.asarray(e).reshape(-1, 2) for e in (el.spring_ends, el.damper_ends)]
    ends = np.concatenate(ends) if ends else np.zeros((0, 2), int)
    ends = ends[(ends[:, 0] >= 0) & (ends[:, 1] >= 0)]
    return int(np.max(np.abs(ends[:, 0] - ends[:, 1]))) if ends.size else 0


def mp_solvable(el: Elements) -> bool:
    """Whether the extended-precision elimination (:func:`sparse_solve`, cost ~ N·b² per frequency and
    precision) is offered: at most :data:`MPMATH_MAX_MASSES` masses, or a banded Z (no modal damping, whose
    C is dense) of the same cost, N·b² ≤ MPMATH_MAX_MASSES³ — a chain of any length up to 13 824 masses
    (a 40-mass chain was refused at 28 near-resonance frequencies its float64 certificate rejected)."""
    if el.n <= MPMATH_MAX_MASSES:
        return True
    return el.modal_zeta is None and el.n * max(bandwidth(el), 1) ** 2 <= MPMATH_MAX_MASSES ** 3


def to_mp(v, mpmath):
    """A float64 as an mpmath number, exactly (its 53 bits fit at every precision used here, >= 30 digits)."""
    return mpmath.mpf(float(v))


def mp_stamp(target, ends: np.ndarray, values: np.ndarray, r: list, mpmath, *, row: int = 0, col: int = 0,
             sign: int = 1) -> None:
    """Add ``sign · Σ k r_i r_j (e_a − e_b)(e_a − e_b)ᵀ`` over the elements (ends ``(a, b)``, -1 a wall; k
    read as exact binary fractions) into ``target`` at block offset ``(row, col)``: the mass-scaled
    M^-1/2 K M^-1/2 (or C) assembled exactly at the current precision."""
    for (a, b), k in zip(ends.tolist(), values.tolist()):
        if a == b:
            continue
        k = to_mp(k, mpmath)
        for i, si in ((a, 1), (b, -1)):
            for j, sj in ((a, 1), (b, -1)):
                if i >= 0 and j >= 0:
                    target[row + i, col + j] += sign * si * sj * k * r[i] * r[j]


def mp_modes(el: Elements, mpmath) -> tuple[list, list[list]]:
    """λ = ω² ascending and the physical M-orthonormal shapes φⱼ = M^-1/2 eⱼ (one list per mode), from
    ``mpmath.eigsy`` of D = M^-1/2 K M^-1/2 assembled exactly from the elements at the current precision.
    Computed once per scene and precision (the resonance table asks once per resonance: 20 eigsy of one
    matrix were 1 s of a 12-mass ``frf``)."""
    key = (mpmath.mp.dps, el.masses.tobytes(), el.spring_ends.tobytes(), el.stiffness.tobytes())
    if key not in _MODES:
        if len(_MODES) > 16:
            _MODES.clear()
        _MODES[key] = _mp_modes_at(el, mpmath)
    lam, shapes = _MODES[key]
    return list(lam), [list(s) for s in shapes]


_MODES: dict = {}


def _mp_modes_at(el: Elements, mpmath) -> tuple[list, list[list]]:
    n = el.n
    r = [1 / mpmath.sqrt(to_mp(m, mpmath)) for m in el.masses.tolist()]
    D = mpmath.zeros(n, n)
    mp_stamp(D, el.spring_ends, el.stiffness, r, mpmath)
    lam, E = mpmath.eigsy(D)
    order = sorted(range(n), key=lambda j: lam[j])
    return [lam[j] for j in order], [[E[i, j] * r[i] for i in range(n)] for j in order]


def _mp_modal_damping(el: Elements, mpmath):
    """C = M Φ diag(2ζⱼωⱼ) Φᵀ M of modal damping at the current precision (:func:`mp_modes`), computed
    once per scene and precision (every frequency the certificate rejects needs it)."""
    key = (mpmath.mp.dps, el.masses.tobytes(), el.spring_ends.tobytes(), el.stiffness.tobytes(),
           np.asarray(el.modal_zeta).tobytes())
    if key not in _MODAL_C:
        if len(_MODAL_C) > 16:
            _MODAL_C.clear()
        _MODAL_C[key] = _mp_modal_damping_at(el, mpmath)
    return _MODAL_C[key].copy()


_MODAL_C: dict = {}


def _mp_modal_damping_at(el: Elements, mpmath):
    n = el.n
    lam, shapes = mp_modes(el, mpmath)
    m = [to_mp(v, mpmath) for v in el.masses.tolist()]
    C = mpmath.zeros(n, n)
    for pos, (lj, phi) in enumerate(zip(lam, shapes)):
        g = 2 * to_mp(el.modal_zeta[pos], mpmath) * mpmath.sqrt(max(lj, 0))
        if g == 0:
            continue
        mphi = [m[i] * phi[i] for i in range(n)]
        for a in range(n):
            for b in range(n):
                C[a, b] += g * mphi[a] * mphi[b]
    return C


def _mp_solve(el: Elements, omega: float, i: int, o: int, dps: int) -> complex:
    import mpmath

    n = el.n
    with mpmath.workdps(dps):
        w = to_mp(omega, mpmath)
        Z = [dict() for _ in range(n)]  # row a: {column: entry}, the nonzeros of Z(ω) only

        def add(p, q, v):
            Z[p][q] = Z[p].get(q, 0) + v

        for a in range(n):
            add(a, a, -w * w * to_mp(el.masses[a], mpmath))
        iw = mpmath.mpc(0, 1) * w
        groups = [(el.spring_ends, el.stiffness, 1), (el.damper_ends, el.damping, iw)]
        if el.rayleigh is not None:
            a_, b_ = (to_mp(v, mpmath) for v in el.rayleigh)
            for a in range(n):
                add(a, a, iw * a_ * to_mp(el.masses[a], mpmath))
            groups.append((el.spring_ends, el.stiffness, iw * b_))
        for ends, vals, fac in groups:
            for (a, b), v in zip(np.asarray(ends).tolist(), np.asarray(vals).tolist()):
                for p, sp in ((a, 1), (b, -1)):
                    for q, sq in ((a, 1), (b, -1)):
                        if p >= 0 and q >= 0 and a != b:
                            add(p, q, sp * sq * fac * to_mp(v, mpmath))
        if el.modal_zeta is not None:
            G = _mp_modal_damping(el, mpmath)
            for a in range(n):
                for b in range(n):
                    if G[a, b]:
                        add(a, b, iw * G[a, b])
        return mpmath.mpc(sparse_solve(Z, i, mpmath)[o])  # exact beyond float64's range (its phase below 1e-308)


def sparse_solve(rows: list[dict], i: int, mpmath) -> list:
    """``Z⁻¹ e_i`` by Gaussian elimination with partial pivoting on the nonzeros of ``Z`` (in place).

    The same elimination as ``mpmath.lu_solve`` (largest pivot in its column; a pivot at most
    ε·max|Z| raises ZeroDivisionError, as mpmath's does), touching only nonzero entries: a chain's
    tridiagonal Z costs O(n) operations instead of O(n³) (a 12-mass chain at contrast 1e12 spent
    3 s of a 200-point ``frf`` in mpmath's dense elimination).

    Parameters
    ----------
    rows : list of dict, length n
        Row ``a`` of Z as ``{column: mpmath number}``.
    i : int
        The unit right-hand side's index.
    mpmath : module

    Returns
    -------
    list, length n
        The solution.
    """
    n = len(rows)
    rhs = [mpmath.mpf(0)] * n
    rhs[i] = mpmath.mpf(1)
    scale = max((abs(v) for r in rows for v in r.values()), default=0)
    tiny = scale * mpmath.eps
    for c in range(n):
        p = max((r for r in range(c, n) if c in rows[r]), key=lambda r: abs(rows[r][c]), default=None)
        if p is None or abs(rows[p][c]) <= tiny:
            raise ZeroDivisionError("matrix is numerically singular")
        rows[c], rows[p] = rows[p], rows[c]
        rhs[c], rhs[p] = rhs[p], rhs[c]
        pivot = rows[c]
        for r in range(c + 1, n):
            f = rows[r].pop(c, None)
            if f is None or not f:
                continue
            f = f / pivot[c]
            row = rows[r]
            for q, v in pivot.items():
                if q != c:
                    row[q] = row.get(q, 0) - f * v
            rhs[r] -= f * rhs[c]
    x = [mpmath.mpf(0)] * n
    for c in reversed(range(n)):
        acc = rhs[c] - mpmath.fsum(v * x[q] for q, v in rows[c].items() if q != c)
        x[c] = acc / rows[c][c]
    return x


def mp_start_digits(el: Elements, omega: float) -> int:
    """Digits the elimination starts at for ``Z(ω)``: 30 beyond the decades between its largest and
    smallest element terms (springs k, dashpots ω c, masses ω² m; Rayleigh and modal damping
    through k, m and ω), so that the smallest term survives being added to the largest — a
    contrast of 1e36 needs more than the 30 digits a well-scaled Z does (mpmath's elimination
    calls a pivot below ε·‖Z‖ singular)."""
    terms = [np.abs(el.stiffness), omega * np.abs(el.damping), omega * omega * np.abs(el.masses)]
    if el.rayleigh is not None:
        a, b = (abs(float(v)) for v in el.rayleigh)
        terms += [omega * a * np.abs(el.masses), omega * b * np.abs(el.stiffness)]
    with np.errstate(all="ignore"):
        v = np.concatenate([np.asarray(t, dtype=float).reshape(-1) for t in terms])
    v = v[np.isfinite(v) & (v > 0)]
    decades = math.log10(float(v.max())) - math.log10(float(v.min())) if v.size else 0.0
    return int(min(MP_MAX_DPS, 30 + math.ceil(decades)))


def _mp_settled(el: Elements, omega: float, input: int, output: int):
    """H at one ω, doubling the digits from :func:`mp_start_digits` until two agree to :data:`MP_AGREE`
    (a pivot mpmath calls singular at some precision is retried at the next)."""
    dps, prev = mp_start_digits(el, omega), None
    while True:
        try:
            cur = _mp_solve(el, omega, input, output, dps)
        except ZeroDivisionError:  # a pivot below ε·‖Z‖ at this precision
            cur = None
        if cur is not None and prev is not None and abs(cur - prev) <= MP_AGREE * abs(cur):
            return cur
        if dps >= MP_MAX_DPS:
            raise RunRefused(f"frequency response at ω = {omega:.6g} rad/s: H did not settle within {MP_MAX_DPS} "
                             "digits (ω on an undamped resonance, or a contrast past 1e900)", quantity="frf")
        prev, dps = cur, min(2 * dps, MP_MAX_DPS)


def mp_receptance(el: Elements, omega: np.ndarray, input: int, output: int, scaled: bool = False):
    """H at each ω by Gaussian elimination in mpmath on Z assembled exactly from the elements,
    doubling the precision from :func:`mp_start_digits` until two results agree to :data:`MP_AGREE`;
    with ``scaled``, ``(mantissa, expo)`` as :meth:`DenseReceptance.receptance`."""
    import mpmath


    out = np.empty(len(omega), dtype=complex)
    expo = np.zeros(len(omega), dtype=np.int64)
    for j, w in enumerate(np.asarray(omega, dtype=float).tolist()):  # frequencies that failed the certificate
        value = _mp_settled(el, w, input, output)
        if scaled:
            out[j], expo[j] = mp_split(value, mpmath)
        else:
            out[j] = complex(value)
    return (out, expo) if scaled else out


__all__ = ["DenseReceptance", "mp_receptance", "mp_solvable", "CERTIFIED", "MPMATH_MAX_MASSES"]
