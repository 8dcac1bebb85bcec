"""Damped modes for the report: ζ per mode (closed form where one exists) or complex modes.

Everything is computed in the **modal coordinates** of the undamped problem, at the scene's
values and at high precision (mpmath, successive precisions until float64 is settled; past
:data:`accurate.MAX_MPMATH_MODES` masses, where mpmath's eigensolvers take minutes, in float64 by
the spring-factor route, :func:`_rows_float`):

* Φ, ω² — M-orthonormal modes from the exactly assembled dynamical matrix
  (:func:`accurate.eig_dynamical`; rigid-body modes are the lowest ``RIGID_MODES``, set to 0
  by structure);
* G = ΦᵀCΦ for the dashpots and Rayleigh damping, plus diag(2ζⱼωⱼ) for modal damping
  (which *is* diagonal in these coordinates by definition).

**Proportional** damping (G diagonal, up to rotations inside a repeated ω) keeps real modes:
ζⱼ = Gⱼⱼ/(2ωⱼ), ω_d = √(ω² − Gⱼⱼ²/4). Closed forms: Rayleigh ζⱼ = α/(2ωⱼ) + βωⱼ/2, modal
the given ratio, dashpots φⱼᵀCφⱼ/(2ωⱼ φⱼᵀMφⱼ) from the closed-form shapes; their sum when
several are declared. Otherwise the **complex modes** are the eigenvalues
λ = −σ ± iω_d of the state-space matrix [[0, I], [−diag(ω²), −G]] (ω_n = |λ|, ζ = σ/ω_n); an overdamped
mode has two real eigenvalues r₁, r₂ (ω_n = √(r₁r₂), ζ = −(r₁ + r₂)/(2ω_n), ω_d = 0), grouped by the undamped
mode that carries most of their eigenvectors, two per mode (:func:`_real_pairs`; a rigid mode's λ = 0 and −g
make a rigid row).
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath
import sympy as sp

from .caps import CAPS
from .printing import closed, latex, sstr
from .accurate import (MAX_DPS, MAX_MPMATH_MODES, NotAccurate, eig_dynamical, mp_value, certified, dynamical_bound,
                       exact_values, omega2_value, value)
from .model import Model
from .model_cache import cached_on
from .modes import ModeSet
from .pieces import pieces
from .qep_roots import qep_roots
from .work import MAX_NUMBER_DIGITS, WorkCapExceeded, check, number_digits, ops, sympy_numbers

#: Two successive precisions agreeing to this relative difference settle a float64 value.
_SETTLED = 4e-16
#: Largest dashpot damping ratio ``φᵀCφ / φᵀMφ`` (SymPy operations, before simplifying it) whose
#: closed form is sought (a size, never a time: the same scene gives the same report under any load).
MAX_ZETA_OPS = CAPS.zeta_ops
#: First working precision of the damped modes (digits); each retry doubles it.
FIRST_DIGITS = 40
#: The absolute floor near ζ = 0: a ratio that is noise at FIRST_DIGITS and below this at twice
#: that (10^(−1.8·40)) is printed as exactly 0 (see :func:`_zero_noise`). A true ζ under it — a
#: mode all but confined to a 1e-12 kg mass far from the only dashpot, ζ = 5e-91 — reads as 0.
ZETA_FLOOR = 10.0 ** (-1.8 * FIRST_DIGITS)


@dataclass(frozen=True)
class DampedMode:
    """One mode of a damped scene at the scene's values.

    ``zeta`` is None for a rigid-body mode (no restoring force); ``zeta_expr`` is the
    closed form (SymPy, in the scene's parameters) or None; ``eigenvalue`` is λ = −σ + iω_d
    (the upper one of a pair), given for complex modes.
    """

    omega_n: float
    zeta: float | None
    omega_d: float
    zeta_expr: sp.Expr | None = None
    eigenvalue: complex | None = None


@dataclass(frozen=True)
class DampedModes:
    rows: tuple[DampedMode, ...]
    proportional: bool
    model: str  # "dashpots", "rayleigh", "modal" or a combination joined by " + "


def _values(model: Model) -> dict:
    """Exact parameter values, and α_R, β_R of ``rayleigh_targets`` (:func:`rayleigh_targets.values`)."""
    from .rayleigh_targets import values

    return {**exact_values(model.params, model.scene.parameters), **values(model)}


def _pieces(model: Model) -> list[list[int]]:
    """Mass indices of the pieces joined by springs or dashpots (walls join nothing)."""
    return pieces(model.scene.n, ((a, b) for a, b, *_ in [*model.springs, *model.dampers]))


def _eig_by_piece(masses: list, springs: list, pieces: list[list[int]], dps: int):
    """``eig_dynamical`` piece by piece: ω² ascending and shapes that are exactly zero outside
    their piece, so a piece without damping has exactly zero rows in G = ΦᵀCΦ (its modes are
    undamped by structure, not by a value that shrinks with the precision)."""
    n = len(masses)
    where = {i: (p, j) for p, piece in enumerate(pieces) for j, i in enumerate(piece)}
    found = []
    for p, piece in enumerate(pieces):
        local = [(where[a][1] if a >= 0 else -1, where[b][1] if b >= 0 else -1, k)
                 for a, b, k in springs if (a >= 0 and where[a][0] == p) or (b >= 0 and where[b][0] == p)]
        w, shapes = eig_dynamical([masses[i] for i in piece], local, len(piece), dps)
        with mpmath.workdps(dps):
            for wj, sj in zip(w, shapes):
                full = [mpmath.mpf(0)] * n
                for j, i in enumerate(piece):
                    full[i] = sj[j]
                found.append((wj, full))
    found.sort(key=lambda r: r[0])
    return [w for w, _ in found], [s for _, s in found]


def _modal_damping(model: Model, dps: int):
    """(ω² list, G matrix) in modal coordinates at working precision ``dps``."""
    subs = _values(model)
    n = model.scene.n
    masses = [m.xreplace(subs) for m in model.masses]
    springs = [(a, b, k.xreplace(subs)) for a, b, k, _, _ in model.springs]
    w2, shapes = _eig_by_piece(masses, springs, _pieces(model), dps)
    with mpmath.workdps(dps):
        n_rigid = len(model.free_components)
        w2 = [mpmath.mpf(0) if j < n_rigid else w for j, w in enumerate(w2)]
        Phi = mpmath.matrix(n, n)
        for j, s in enumerate(shapes):
            for i in range(n):
                Phi[i, j] = s[i]
        G = mpmath.zeros(n, n)
        if model.dampers:  # the dashpots' C from their elements, at this precision
            C = mpmath.zeros(n, n)
            for a, b, c, _ in model.dampers:
                cv = mp_value(c.xreplace(subs), dps)
                for i, si in ((a, 1), (b, -1)):
                    for j, sj in ((a, 1), (b, -1)):
                        if i >= 0 and j >= 0:
                            C[i, j] += si * sj * cv
            G = Phi.T * C * Phi
        if model.rayleigh is not None:
            # Φᵀ(αM + βK)Φ = α + βω² on the diagonal by definition (M-orthonormal Φ of this K): the K of
            # model.C holds an equilibrium stiffness rounded to 17 digits, and β times it (SymPy Floats)
            # is not βK at this precision, an off-diagonal of ~1e-20 that read as non-proportional
            alpha, beta = (mp_value(e.xreplace(subs), dps) for e in model.rayleigh)
            for j in range(n):
                G[j, j] += alpha + beta * w2[j]
        if model.modal_zeta is not None:
            for j in range(n):
                G[j, j] += 2 * mp_value(model.modal_zeta[j].xreplace(subs), dps) * mpmath.sqrt(max(w2[j], 0))  # ω² noise < 0
        return w2, G


def _is_proportional(w2, G, dps: int) -> bool:
    """G diagonal between distinct ω² (within a repeated ω any block is fine after rotation)."""
    n = len(w2)
    tiny = mpmath.mpf(10) ** (-(dps // 2))
    scale = max([abs(G[i, i]) for i in range(n)] + [mpmath.mpf(10) ** -300])
    wscale = max([abs(w) for w in w2] + [mpmath.mpf(1)])
    for i in range(n):
        for j in range(i + 1, n):
            same = abs(w2[i] - w2[j]) <= tiny * wscale
            if not same and abs(G[i, j]) > tiny * scale:
                return False
    return True


def _cluster_diagonal(w2, G, dps: int) -> list:
    """Diagonal of G after rotating inside each repeated ω (where any basis is a basis of modes):
    the eigenvalues of each cluster's block, ascending; G's own diagonal elsewhere."""
    n = len(w2)
    tiny = mpmath.mpf(10) ** (-(dps // 2))
    wscale = max([abs(w) for w in w2] + [mpmath.mpf(1)])
    out = [G[j, j] for j in range(n)]
    j = 0
    while j < n:
        k = j + 1
        while k < n and abs(w2[k] - w2[j]) <= tiny * wscale:
            k += 1
        if k - j > 1:
            block = mpmath.matrix([[G[a, b] for b in range(j, k)] for a in range(j, k)])
            vals = sorted(mpmath.eigsy(block, eigvals_only=True))
            out[j:k] = vals
        j = k
    return out


def _rows_at(model: Model, dps: int, w2G=None) -> tuple[list[tuple], bool]:
    w2, G = _modal_damping(model, dps) if w2G is None else w2G
    n = len(w2)
    with mpmath.workdps(dps):
        if _is_proportional(w2, G, dps):
            diag = _cluster_diagonal(w2, G, dps)
            rows = []
            for j in range(n):
                # an ω² that is noise below zero at this precision (stiffness contrast beyond the
                # digits) reads as rigid here; the next precision settles it
                if w2[j] <= 0:
                    rows.append((0.0, None, 0.0, None))
                    continue
                w = mpmath.sqrt(w2[j])
                g = diag[j]
                wd2 = w2[j] - g * g / 4
                rows.append((float(w), float(g / (2 * w)), float(mpmath.sqrt(wd2)) if wd2 > 0 else 0.0, None))
            return rows, True
        # modes with an exactly zero row of G (a piece without damping) are undamped by structure:
        # λ = ±iω, left out of the eigenvalue problem (whose QR would give them a real part of noise)
        free = [j for j in range(n) if all(G[j, i] == 0 for i in range(n))]
        kept = [j for j in range(n) if j not in free]
        m = len(kept)
        A = mpmath.zeros(2 * m, 2 * m)
        for a, i in enumerate(kept):
            A[a, m + a] = 1
            A[m + a, a] = -w2[i]
            for b, j in enumerate(kept):
                A[m + a, m + b] = -G[i, j]
        lam = qep_roots([w2[i] for i in kept], mpmath.matrix([[G[i, j] for j in kept] for i in kept]), dps) \
            if m else []
        if lam is None:  # a repeated or nearly repeated eigenvalue: Newton is not trusted there
            lam = list(mpmath.eig(A, left=False, right=False))
        lam += [mpmath.mpc(0, mpmath.sqrt(w2[j])) for j in free if w2[j] > 0]
        lam += [mpmath.mpc(0, 0)] * (2 * sum(1 for j in free if w2[j] == 0))
        scale = max(abs(l) for l in lam) or mpmath.mpf(1)
        tiny = mpmath.mpf(10) ** (-(dps // 2)) * scale
        cplx = sorted((l for l in lam if mpmath.im(l) > tiny), key=abs)
        undamped = {id(l) for l in lam if mpmath.re(l) == 0}
        rows = [(float(abs(l)), 0.0 if id(l) in undamped else float(-mpmath.re(l) / abs(l)), float(mpmath.im(l)),
                 complex(float(mpmath.re(l)), float(mpmath.im(l)))) for l in cplx]
        # the real eigenvalues of the damped modes (kept) grouped by mode (:func:`_real_pairs`); the
        # undamped rigid modes' λ = 0 (two each) are one rigid row each
        real = [mpmath.re(l) for l in lam[:2 * m] if abs(mpmath.im(l)) <= tiny]
        rows += [(0.0, None, 0.0, None)] * sum(1 for j in free if w2[j] == 0)
        weights = _mp_weights(real, [w2[i] for i in kept], [[G[i, j] for j in kept] for i in kept], dps) \
            if real else None
        pairs = _real_pairs(weights, m) if real else []
        if pairs is not None:
            rows += [_overdamped_row(real[a], real[b], w2[kept[j]] > 0, tiny) for j, (a, b) in pairs]
        else:
            rows += _value_pairs(real, tiny)
        rows.sort(key=lambda r: r[0])
        return rows[:n], False


def _overdamped_row(r1, r2, elastic: bool, tiny) -> tuple:
    """``(ω_n, ζ, 0, None)`` of two real eigenvalues of one mode: ω_n = √(r₁r₂), ζ = −(r₁ + r₂)/(2ω_n); a rigid
    row (ζ None) for a rigid mode's pair (λ = 0 and −g) or a pair with a zero."""
    if not elastic or abs(r1) <= tiny or abs(r2) <= tiny or r1 * r2 <= 0:
        return (0.0, None, 0.0, None)
    wn = mpmath.sqrt(r1 * r2) if isinstance(r1, mpmath.mpf) else (r1 * r2) ** 0.5
    return (float(wn), float(-(r1 + r2) / (2 * wn)), 0.0, None)


def _value_pairs(real: list, tiny) -> list[tuple]:
    """The fallback when the eigenvectors do not tell the modes apart (:func:`_real_pairs` None): zeros make
    rigid rows (two per row), the rest are paired by value, the slowest with the fastest."""
    real = sorted(real, key=lambda r: -r)
    zeros = [r for r in real if abs(r) <= tiny]
    rest = [r for r in real if abs(r) > tiny]
    rows = [(0.0, None, 0.0, None)] * (len(zeros) // 2 or (1 if zeros else 0))
    while len(rest) >= 2:
        r1, r2 = rest.pop(0), rest.pop(-1)
        rows.append(_overdamped_row(r1, r2, True, tiny))
    return rows


def _mp_weights(real: list, w2: list, G: list, dps: int):
    """The modal weights of the eigenvectors of the real eigenvalues r (rows of an (R, m) float array): the
    null vector of Q(r) = r² I + r G + diag(ω²) (symmetric, in the M-orthonormal modal coordinates, so
    q = ΦᵀMx) and each mode's share q_j² of it. By two steps of inverse iteration at ``dps`` digits
    (``mpmath.lu_solve`` at r shifted by 10^(−dps/4), one factorisation); where that elimination finds Q
    singular, ``mpmath.eigsy``: the eigenvectors of the eigenvalues within 10^(−dps/2) of the scale
    r² + |r|‖G‖ + max ω² (at least the smallest one), a null space of two dimensions sharing 2."""
    import numpy as np

    m = len(w2)
    out = np.zeros((len(real), m))
    with mpmath.workdps(dps):
        gnorm = max([sum(abs(G[i][j]) for j in range(m)) for i in range(m)] + [mpmath.mpf(0)])
        wmax = max([abs(w) for w in w2] + [mpmath.mpf(0)])
        big = max([abs(r) for r in real] + [mpmath.mpf(1)])

        def Q(r):
            return mpmath.matrix([[r * G[i][j] + ((r * r + w2[i]) if i == j else 0) for j in range(m)]
                                  for i in range(m)])

        for k, r in enumerate(real):
            try:
                A = Q(r + mpmath.mpf(10) ** (-(dps // 4)) * (abs(r) or big))
                x = mpmath.matrix([1 + mpmath.mpf(i) / (m + 1) for i in range(m)])  # (fixed, not special)
                for _ in range(2):
                    x = mpmath.lu_solve(A, x)
                    x /= mpmath.norm(x)
                out[k] = [float(x[j] ** 2) for j in range(m)]
                continue
            except ZeroDivisionError:  # Q singular at this precision: the null space from eigsy
                pass
            E, U = mpmath.eigsy(Q(r))
            cut = mpmath.mpf(10) ** (-(dps // 2)) * (r * r + abs(r) * gnorm + wmax)
            low = min(range(m), key=lambda i: abs(E[i]))
            for i in range(m):
                if i == low or abs(E[i]) <= cut:
                    out[k] += [float(U[j, i] ** 2) for j in range(m)]
    return out


def _float_weights(real: list, w2, G):
    """:func:`_mp_weights` in float64 (``numpy.linalg.eigh``; a null space within 1e-9 of the scale)."""
    import numpy as np

    m = w2.shape[0]
    out = np.zeros((len(real), m))
    gnorm = float(np.max(np.sum(np.abs(G), axis=1), initial=0.0))
    wmax = float(np.max(np.abs(w2), initial=0.0))
    for k, r in enumerate(real):
        E, U = np.linalg.eigh(r * r * np.eye(m) + r * G + np.diag(w2))
        near = np.abs(E) <= 1e-9 * (r * r + abs(r) * gnorm + wmax)
        near[np.argmin(np.abs(E))] = True
        out[k] = np.sum(U[:, near] ** 2, axis=1)
    return out


def _real_pairs(weights, m: int) -> list[tuple] | None:
    """The real eigenvalues of the damped modal problem grouped two by two by mode (the convention for the
    ζ of overdamped modes): ``[(j, (a, b)), …]``, j the mode (0 … m−1 of the modes passed) and a, b the
    indices of its two real eigenvalues, or None when some mode would get only one (then the caller pairs
    by value, :func:`_value_pairs`).

    Each real eigenvalue r goes to the mode with the largest share of its eigenvector in the undamped
    modes, |φ_jᵀMv|² / Σ_i |φ_iᵀMv|² (``weights``, rows of shares), two per mode: an optimal assignment
    (``scipy.optimize.linear_sum_assignment`` with each mode taken twice, most total share). With
    proportional damping each eigenvector lies in one mode and the pair is that mode's roots of
    λ² + g_j λ + ω_j² = 0 exactly; nearly proportional damping keeps that grouping. Pairing by value (the
    slowest with the fastest) mixed modes: three masses with C ≈ 3M paired the ω² = 1 mode's −0.38 with
    the rigid mode's −3 (ζ 1.586 for ≈ 1.5). The same convention as ``numeric.modes.chain_damping`` for
    ``[chain]`` scenes (which weighs the balanced coordinates (ω_j q_j, q̇_j) instead).
    """
    import numpy as np
    from scipy.optimize import linear_sum_assignment

    weights = np.asarray(weights, dtype=float)
    if weights.shape[0] == 0:
        return []
    if weights.shape[0] > 2 * m:
        return None
    weights = weights / np.maximum(np.sum(weights, axis=1, keepdims=True), np.finfo(float).tiny)
    rows, cols = linear_sum_assignment(-np.repeat(weights, 2, axis=1))  # (R, 2m): two slots per mode
    groups: dict[int, list[int]] = {}
    for r, c in zip(rows, cols):
        groups.setdefault(int(c) // 2, []).append(int(r))
    if any(len(g) != 2 for g in groups.values()):
        return None
    return [(j, tuple(sorted(g))) for j, g in sorted(groups.items())]


def _rows_float(model: Model) -> tuple[list[tuple], bool]:
    """The rows of :func:`_rows_at` in float64, for scenes past :data:`accurate.MAX_MPMATH_MODES`
    masses (mpmath's eigensolvers take minutes there): the modes of each piece by the spring-factor
    route (relatively accurate, the generated modules' own code), G = ΦᵀCΦ from the elements
    (Rayleigh and modal damping diagonal by definition), and LAPACK's eigenvalues of the state
    matrix in the balanced form ``[[0, Ω], [−Ω, −G]]``; modes of a piece without damping undamped by
    structure, as at high precision."""
    subs = _values(model)
    w2, Phi = _float_modes(model, subs)
    G = _float_damping(model, subs, w2, Phi)
    return _float_proportional_rows(w2, G) or _float_complex_rows(w2, G)


def _float_modes(model: Model, subs: dict):
    """ω² ascending and physical M-orthonormal shapes (columns), piece by piece (exact zeros outside)."""
    import numpy as np

    from .spring_factor import accurate_modes_function

    n = model.scene.n
    masses = np.array([float(m.xreplace(subs)) for m in model.masses])
    springs = [(a, b, float(k.xreplace(subs))) for a, b, k, _, _ in model.springs]
    found = []
    for piece in _pieces(model):  # a loop over pieces, not masses
        where = {i: j for j, i in enumerate(piece)}
        local = [(where.get(a, -1), where.get(b, -1), k) for a, b, k in springs if a in where or b in where]
        rigid = [] if any(a < 0 or b < 0 for a, b, _ in local) else [tuple(range(len(piece)))]
        run = accurate_modes_function(len(piece), tuple((a, b) for a, b, _ in local), tuple(rigid))
        pw2, pshapes = run(masses[piece], [k for *_, k in local])
        found += [(float(pw2[j]), piece, pshapes[:, j]) for j in range(len(piece))]
    found.sort(key=lambda r: r[0])
    w2, Phi = np.zeros(n), np.zeros((n, n))
    for j, (wj, piece, shape) in enumerate(found):
        w2[j] = wj
        Phi[piece, j] = shape
    return w2, Phi


def _float_damping(model: Model, subs: dict, w2, Phi):
    """G = ΦᵀCΦ: dashpots from their elements, Rayleigh α + βω², modal 2ζω (diagonal by definition)."""
    import numpy as np

    n = w2.shape[0]
    G = np.zeros((n, n))
    if model.dampers:
        B = np.zeros((len(model.dampers), n))
        c = np.array([float(cc.xreplace(subs)) for _, _, cc, _ in model.dampers])
        for r, (a, b, _, _) in enumerate(model.dampers):  # a loop over dashpots
            B[r, a] += 1.0 if a >= 0 else 0.0
            B[r, b] -= 1.0 if b >= 0 else 0.0
        P = B @ Phi
        G = P.T @ (c[:, None] * P)
        G = 0.5 * (G + G.T)
    if model.rayleigh is not None:
        alpha, beta = (float(e.xreplace(subs)) for e in model.rayleigh)
        G[np.arange(n), np.arange(n)] += alpha + beta * w2
    if model.modal_zeta is not None:
        zeta = np.array([float(z.xreplace(subs)) for z in model.modal_zeta])
        G[np.arange(n), np.arange(n)] += 2 * zeta * np.sqrt(np.maximum(w2, 0.0))
    return G


def _float_proportional_rows(w2, G) -> tuple[list[tuple], bool] | None:
    """Rows of real modes if G is diagonal between distinct ω² (else None)."""
    import numpy as np

    n = w2.shape[0]
    d = np.sqrt(np.abs(np.diag(G)))
    off = np.abs(G - np.diag(np.diag(G))) > 1e-12 * np.outer(d, d) + 1e-300
    same = np.abs(w2[:, None] - w2[None, :]) <= 1e-12 * max(float(np.max(w2, initial=0.0)), 1e-300)
    if np.any(off & ~same):
        return None
    diag = np.diag(G).copy()
    j = 0
    while j < n:  # within a repeated ω, the eigenvalues of G's block (any basis is one of modes)
        k = j + 1
        while k < n and same[j, k]:
            k += 1
        if k - j > 1:
            diag[j:k] = np.linalg.eigvalsh(G[j:k, j:k])
        j = k
    w = np.sqrt(np.maximum(w2, 0.0))
    rows = []
    for j in range(n):
        if w2[j] == 0:
            rows.append((0.0, None, 0.0, None))
            continue
        wd2 = w2[j] - diag[j] ** 2 / 4
        rows.append((float(w[j]), float(diag[j] / (2 * w[j])), float(np.sqrt(wd2)) if wd2 > 0 else 0.0, None))
    return rows, True


def _float_complex_rows(w2, G) -> tuple[list[tuple], bool]:
    """Rows of complex modes from the balanced state matrix (a piece without damping left out: λ = ±iω)."""
    import numpy as np
    import scipy.linalg

    n = w2.shape[0]
    w = np.sqrt(np.maximum(w2, 0.0))
    free = [j for j in range(n) if not np.any(G[j])]
    kept = [j for j in range(n) if np.any(G[j])]
    m = len(kept)
    A = np.zeros((2 * m, 2 * m))
    A[np.arange(m), m + np.arange(m)] = np.where(w[kept] > 0, w[kept], 1.0)
    A[m + np.arange(m), np.arange(m)] = -w[kept]
    A[m:, m:] = -G[np.ix_(kept, kept)]
    lam = list(scipy.linalg.eigvals(A)) if m else []
    undamped = [complex(0.0, float(w[j])) for j in free if w2[j] > 0]
    tiny = 1e-12 * max([abs(v) for v in lam + undamped] + [1.0])
    rows = [(float(abs(v)), float(-v.real / abs(v)), float(v.imag), complex(v))
            for v in sorted([v for v in lam if v.imag > tiny], key=abs)]
    rows += [(float(v.imag), 0.0, float(v.imag), v) for v in undamped]
    real = [float(v.real) for v in lam if abs(v.imag) <= tiny]
    rows += [(0.0, None, 0.0, None)] * sum(1 for j in free if w2[j] == 0)
    pairs = _real_pairs(_float_weights(real, w2[kept], G[np.ix_(kept, kept)]), m) if real else []
    if pairs is not None:  # each mode's own two real eigenvalues (:func:`_real_pairs`)
        rows += [_overdamped_row(real[a], real[b], w2[kept[j]] > 0, tiny) for j, (a, b) in pairs]
    else:
        rows += _value_pairs(real, tiny)
    rows.sort(key=lambda r: r[0])
    return rows[:n], False


def _zero_noise(x: float, y: float, dps: int) -> bool:
    """``x`` (at ``dps`` digits) is below 10^(−dps/2) and ``y`` (at 2·dps) below 10^(−1.8·dps): noise
    that shrinks with the precision, i.e. a quantity that is exactly zero (a node of a mode at every
    dashpot) — the absolute floor near ζ = 0. A true ζ of 1e-61 is noise at 40 digits but stays
    1e-61 at 80 (above 1e-72), so it is not taken for zero: the precision keeps doubling until it
    settles."""
    return abs(x) < 10.0 ** (-dps / 2) and abs(y) <= 10.0 ** (-1.8 * dps)


def _settled(a: list[tuple], b: list[tuple], dps: int = 40) -> bool:
    """Rows at ``dps`` and at 2·dps digits agree: relative 4e-16, or both noise around an exact zero."""
    def close(x, y):
        if x is None or y is None:
            return x is y
        if isinstance(x, complex):
            return abs(x - y) <= _SETTLED * max(abs(x), abs(y))
        return abs(x - y) <= _SETTLED * max(abs(x), abs(y)) or _zero_noise(x, y, dps)
    return len(a) == len(b) and all(close(x, y) for ra, rb in zip(a, b) for x, y in zip(ra, rb))


def _clean(rows: list[tuple], prev: list[tuple], dps: int) -> list[tuple]:
    """Rows with a damping ratio that settled to an exact zero (see :func:`_zero_noise`) made
    undamped: ζ = 0, ω_d = ω_n, λ = iω_n."""
    out = []
    for (wn, zeta, wd, lam), old in zip(rows, prev):
        if zeta is not None and zeta != 0.0 and old[1] is not None and _zero_noise(old[1], zeta, dps):
            zeta, wd, lam = 0.0, wn, (None if lam is None else complex(0.0, wn))
        out.append((wn, zeta, wd, lam))
    return out


def _closed_forms(model: Model, modes: ModeSet) -> list[sp.Expr | None]:
    """Closed-form ζⱼ per independent mode in ascending order (None where none is available)."""
    out: list[sp.Expr | None] = []
    j = 0
    subs = _values(model)
    records = [(mode, shape) for mode in modes.modes for shape in mode.shapes]
    records.sort(key=lambda r: omega2_value(r[0], subs))
    C_d = None
    if model.dampers:
        C_d = model._assemble([(a, b, c) for a, b, c, _ in model.dampers], model.v)
    try:
        for mode, shape in records:
            if mode.rigid:
                out.append(None)
                j += 1
                continue
            w = sp.sqrt(mode.omega2)
            zeta = sp.Integer(0)
            if model.rayleigh is not None:
                alpha, beta = model.rayleigh
                zeta += alpha / (2 * w) + beta * w / 2
            if model.modal_zeta is not None:
                zeta += model.modal_zeta[j]
            if C_d is not None:
                if not (mode.exact and modes.closed_form):
                    raise WorkCapExceeded("no closed-form mode shape")
                phi = sp.Matrix(shape)
                ratio = (phi.T * C_d * phi)[0, 0] / (phi.T * model.M * phi)[0, 0]
                check(ops(ratio), MAX_ZETA_OPS)
                check(number_digits([ratio]), MAX_NUMBER_DIGITS)  # cancelling huge exact numbers: minutes
                with sympy_numbers():  # SymPy's own failures on large exact numbers: no closed form
                    ratio = sp.factor(sp.radsimp(sp.cancel(sp.expand(ratio))))
                zeta += ratio / (2 * w)
            out.append(zeta)
            j += 1
    except WorkCapExceeded:
        return [None] * len(records)
    return out


def damped_modes(model: Model, modes: ModeSet | None) -> DampedModes:
    """The damped modes of a scene with dashpots or a ``[damping]`` model (see module docstring).

    ``modes`` (the closed-form modes) gives the closed forms of ζ; None for the numbers only.
    Cached on the model (one computation per report).
    """
    return cached_on(model, "_damped_modes", modes is not None, lambda: _damped_modes(model, modes))


def _settled_rows(model: Model) -> tuple[list[tuple], bool]:
    """:func:`_rows_at` at 40, 80, … digits until two successive precisions agree (float64 settled)."""
    subs = _values(model)
    bound = dynamical_bound([m.xreplace(subs) for m in model.masses],
                            [(a, b, k.xreplace(subs)) for a, b, k, _, _ in model.springs])
    n_rigid = len(model.free_components)
    prev = None
    dps = FIRST_DIGITS
    while dps <= MAX_DPS:
        w2G = _modal_damping(model, dps)
        rows, prop = _rows_at(model, dps, w2G)
        # the undamped ω² certified too: two precisions can agree on the same wrong value (both
        # deflating one tiny coupling, :func:`accurate.certified`)
        if prev is not None and prev[1] == prop and _settled(prev[0], rows, dps // 2) \
                and certified(w2G[0], n_rigid, bound, dps):
            return _clean(rows, prev[0], dps // 2), prop
        prev = (rows, prop)
        dps *= 2
    raise NotAccurate(f"damped modes did not settle to float64 accuracy within {MAX_DPS} digits")


def _rows(model: Model) -> tuple[list[tuple], bool]:
    """The damped rows at the scene's values and whether the damping is proportional, computed once per
    model (the notes ask for ``proportional`` alone, the report for the rows with closed forms: one
    mpmath eigen-solve, not two)."""
    def compute():
        if model.scene.n > MAX_MPMATH_MODES:  # float64 spring-factor route (mpmath takes minutes here)
            return _rows_float(model)
        return _settled_rows(model)

    return cached_on(model, "_damped_rows", None, compute)


def _damped_modes(model: Model, modes: ModeSet | None) -> DampedModes:
    parts = (["dashpots"] if model.dampers else []) + (
        [model.scene.damping.kind] if model.scene.damping is not None else [])
    rows, prop = _rows(model)
    exprs = _closed_forms(model, modes) if prop and modes is not None else [None] * len(rows)
    subs = _values(model)
    out = []
    for (wn, zeta, wd, lam), expr in zip(rows, exprs + [None] * (len(rows) - len(exprs))):
        if expr is not None:  # the closed form, evaluated accurately; the numeric row checks it
            closed = value(expr, subs)
            if zeta is not None and abs(closed - zeta) <= 1e-12 * max(abs(zeta), 1e-300):
                zeta = closed
            else:
                expr = None
        out.append(DampedMode(wn, zeta, wd, expr, lam))
    return DampedModes(tuple(out), prop, " + ".join(parts))


def json_fields(dm: DampedModes, records: list[dict]) -> dict:
    """Add ``damping_ratio``, ``omega_damped`` and ``damping_ratio_expr`` to each mode record (in
    place) and return the top-level fields: ``damping`` (model, proportional) and, for
    non-proportional damping, ``complex_modes`` (one per conjugate pair or real pair)."""
    for rec, row in zip(records, dm.rows):
        rec["damping_ratio"] = row.zeta
        rec["omega_damped"] = row.omega_d
        rec["damping_ratio_expr"] = None if row.zeta_expr is None else sp.sstr(row.zeta_expr)
    out: dict = {"damping": {"model": dm.model, "proportional": dm.proportional}}
    if not dm.proportional:
        out["complex_modes"] = [
            {"eigenvalue": None if r.eigenvalue is None else [r.eigenvalue.real, r.eigenvalue.imag],
             "sigma": (-r.eigenvalue.real if r.eigenvalue is not None
                       else None if r.zeta is None else r.zeta * r.omega_n),
             "omega_damped": r.omega_d, "omega_n": r.omega_n, "damping_ratio": r.zeta}
            for r in dm.rows]
    return out


def damped_mode_lines(model: Model, dm: DampedModes) -> list[str]:
    """The text report's damped-mode section."""
    kind = "proportional: real modes" if dm.proportional else \
        "not proportional: complex modes, eigenvalues lambda = -sigma +/- i omega_d"
    out = [f"Damped modes at the scene's values ({dm.model}; {kind}):"]
    for r in dm.rows:
        if r.zeta is None:
            out.append(f"    omega_n = {r.omega_n:.10g}   rigid (no restoring force)")
            continue
        line = f"    omega_n = {r.omega_n:.10g}   zeta = {r.zeta:.10g}   omega_d = {r.omega_d:.10g}"
        if r.eigenvalue is not None:
            line += f"   lambda = {r.eigenvalue.real:.10g} +/- {r.eigenvalue.imag:.10g}i"
        elif not dm.proportional:
            line += f"   (overdamped: real eigenvalues, sigma = {r.zeta * r.omega_n:.10g})"
        if r.zeta_expr is not None:
            line += f"   zeta = {closed(sstr(r.zeta_expr))}"
        out.append(line)
    return out


def latex_lines(dm: DampedModes) -> list[str]:
    """``\\zeta_j = ...`` lines (closed forms where known, values otherwise) for the LaTeX report."""
    out = []
    for j, r in enumerate(dm.rows, start=1):
        if r.zeta is None:
            continue
        from .rayleigh_targets import LATEX_NAMES

        rhs = (latex(r.zeta_expr, symbol_names=LATEX_NAMES) + rf" \approx {r.zeta:.10g}"
               if r.zeta_expr is not None else f"{r.zeta:.10g}")
        extra = (rf", & \lambda_{{{j}}} &= {r.eigenvalue.real:.10g} \pm {r.eigenvalue.imag:.10g}\,i"
                 if r.eigenvalue is not None else "")
        out.append(rf"\\ \zeta_{{{j}}} &= {rhs}{extra}")
    return out


__all__ = ["DampedMode", "DampedModes", "damped_modes", "json_fields", "damped_mode_lines", "latex_lines"]
