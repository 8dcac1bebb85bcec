"""A fixed–free chain rebuilt from two spectra: the Jacobi-matrix inverse eigenvalue problem.

The chain: a wall, spring k₁, mass m₁, spring k₂, mass m₂, …, spring k_n, mass m_n (free). Its
mass-weighted stiffness ``J = M^-1/2 K M^-1/2`` is a Jacobi matrix (tridiagonal, negative
off-diagonal). Given

* λ₁ < … < λ_n — the ω² of the chain, and
* μ₁ < … < μ_{n−1} — the ω² with mass n clamped too (J without its last row and column),

which must interlace strictly, ``λ₁ < μ₁ < λ₂ < … < μ_{n−1} < λ_n``, the last components of J's
orthonormal eigenvectors follow from the residues of ``[(J − z)⁻¹]_nn = Π(μ_j − z)/Π(λ_i − z)``:

    w_i = u_{n,i}² = Π_j (μ_j − λ_i) / Π_{k≠i} (λ_k − λ_i)      (all > 0 by interlacing, Σ w_i = 1),

and Lanczos on ``diag(λ)`` from the vector ``(√w_i)`` rebuilds J (in reversed order) — here in mpmath
with full reorthogonalisation. (Alternatively the w_i come from the end components of the
mass-normalised shapes: ``w_i = m_n φ_{n,i}²`` with ``m_n = 1/Σ_i φ_{n,i}²``.)

J fixes the chain up to one scale (k and m multiplied together leave every ω² unchanged): with
``z = J⁻¹ e₁`` (positive), ``√m_i = c z_i`` (``M^½ 1`` is the static shape under a load on mass 1)
and ``k₁ = c² z₁``, ``k_{i+1} = |J_{i,i+1}| √(m_i m_{i+1})``; the total mass (or m_n) gives c.

**Conditioning.** The map from the spectra to the parameters can amplify relative input errors a
lot. The condition estimate is ``κ = max_i Σ_j |∂ log p_i / ∂ log s_j|`` (s the 2n − 1 input values,
with the scale fixed), from the inverse of the forward Jacobian — the sensitivities ``∂ω²/∂k``,
``∂ω²/∂m`` of the rebuilt chain and of its clamped form, in mpmath — and the error bound it implies
is ``κ·u`` for inputs known to relative accuracy u (½ ulp = 1.1e-16 for float64, ½·10^(1−d) for d digits).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import mpmath

from ..errors import RunRefused

#: Digits of a float64's shortest representation: inputs with no more digits than this are float64 data.
FLOAT64_DIGITS = 17
#: Most significant digits of an input value, and most masses (the work is O(n³) operations at that precision).
MAX_DIGITS = 200
MAX_MASSES = 200


@dataclass(frozen=True)
class Chain:
    """A rebuilt fixed–free chain.

    Attributes
    ----------
    masses, springs : list of mpmath.mpf
        ``m_1 … m_n``; ``k_1`` (to the wall) … ``k_n`` (between masses n − 1 and n).
    condition : float
        κ (module docstring).
    input_accuracy : float
        u, the relative accuracy the input digits carry.
    bound : float
        κ·u: the relative error the inputs' own rounding can cause in any mass or spring.
    dps : int
        Working precision (decimal digits).
    """

    masses: list = field(repr=False)
    springs: list = field(repr=False)
    condition: float = 0.0
    input_accuracy: float = 0.0
    bound: float = 0.0
    dps: int = 0


def significant_digits(text: str) -> int:
    """Significant digits of a decimal number's text (``"1.2500e3"`` has 5)."""
    mant = re.split("[eE]", text.strip().lstrip("+-"))[0].replace(".", "").lstrip("0")
    return max(len(mant), 1)


def weights_from_spectra(lam: list, mu: list) -> list:
    """``w_i = Π_j(μ_j − λ_i) / Π_{k≠i}(λ_k − λ_i)`` (current mpmath precision; interlacing checked by the caller)."""
    out = []
    for i, li in enumerate(lam):
        num = mpmath.fprod(m - li for m in mu)
        den = mpmath.fprod(lk - li for k, lk in enumerate(lam) if k != i)
        out.append(num / den)
    return out


def lanczos(lam: list, w: list) -> tuple[list, list]:
    """Diagonal α (n) and off-diagonal β (n − 1, > 0) of the Jacobi matrix with eigenvalues ``lam`` whose
    eigenvectors' last components are ``√w``, in J's order (mass 1 first)."""
    n = len(lam)
    q = [mpmath.sqrt(x) for x in w]
    norm = mpmath.sqrt(mpmath.fsum(x * x for x in q))
    q = [x / norm for x in q]
    Q = [q]
    alpha, beta = [], []
    prev, b = [mpmath.mpf(0)] * n, mpmath.mpf(0)
    for k in range(n):
        v = [lam[i] * q[i] for i in range(n)]
        a = mpmath.fsum(q[i] * v[i] for i in range(n))
        alpha.append(a)
        if k == n - 1:
            break
        v = [v[i] - a * q[i] - b * prev[i] for i in range(n)]
        for _ in range(2):  # full reorthogonalisation, twice
            for u in Q:
                c = mpmath.fsum(u[i] * v[i] for i in range(n))
                v = [v[i] - c * u[i] for i in range(n)]
        b = mpmath.sqrt(mpmath.fsum(x * x for x in v))
        beta.append(b)
        prev, q = q, [x / b for x in v]
        Q.append(q)
    return alpha[::-1], beta[::-1]


def chain_from_jacobi(alpha: list, beta: list, scale_mass, last_mass: bool = False) -> tuple[list, list]:
    """Masses and springs from the Jacobi matrix (diagonal α, off-diagonal magnitudes β), with the total
    mass (or, ``last_mass``, m_n) equal to ``scale_mass``."""
    n = len(alpha)
    # z = J⁻¹ e₁ (J has off-diagonal −β): Thomas algorithm, no pivoting needed (J is positive definite)
    c_ = [mpmath.mpf(0)] * n
    d_ = [mpmath.mpf(0)] * n
    rhs = [mpmath.mpf(1)] + [mpmath.mpf(0)] * (n - 1)
    diag = alpha[0]
    c_[0] = (-beta[0] / diag) if n > 1 else 0
    d_[0] = rhs[0] / diag
    for i in range(1, n):
        diag = alpha[i] - (-beta[i - 1]) * c_[i - 1]
        if i < n - 1:
            c_[i] = -beta[i] / diag
        d_[i] = (rhs[i] - (-beta[i - 1]) * d_[i - 1]) / diag
    z = [mpmath.mpf(0)] * n
    z[-1] = d_[-1]
    for i in range(n - 2, -1, -1):
        z[i] = d_[i] - c_[i] * z[i + 1]
    if any(x <= 0 for x in z):
        raise RunRefused("reconstruct: the rebuilt matrix is not that of a chain (a non-positive static shape)")
    c2 = scale_mass / (z[-1] ** 2 if last_mass else mpmath.fsum(x * x for x in z))
    m = [c2 * x * x for x in z]
    k = [c2 * z[0]] + [beta[i] * mpmath.sqrt(m[i] * m[i + 1]) for i in range(n - 1)]
    return m, k


def chain_spectra(m: list, k: list) -> tuple[list, list, list, list]:
    """ω² and M-normalised shapes of the fixed–free chain and of its clamped form (mpmath eigsy)."""
    n = len(m)

    def solve(size):
        r = [1 / mpmath.sqrt(x) for x in m[:size]]
        D = mpmath.zeros(size, size)
        for i in range(size):
            D[i, i] = (k[i] + (k[i + 1] if i + 1 < n else 0)) * r[i] * r[i]
            if i + 1 < size:
                D[i, i + 1] = D[i + 1, i] = -k[i + 1] * r[i] * r[i + 1]
        w, E = mpmath.eigsy(D)
        order = sorted(range(size), key=lambda j: w[j])
        return [w[j] for j in order], [[E[i, j] * r[i] for i in range(size)] for j in order]

    lam, phi = solve(n)
    mu, psi = solve(n - 1) if n > 1 else ([], [])
    return lam, phi, mu, psi


def _fractions(m, k, clamped: bool):
    """Rows ``∂ log ω²_j / ∂ log p`` (p = m_1 … m_n, k_1 … k_n) of the fixed–free chain (or of its clamped
    form), from the modes refined to double-double (:mod:`numeric.sensitivity.refine`): ``−m_i φ_i²``
    and ``k_s (φ_a − φ_b)² / ω²`` — energy fractions, accurate at any contrast."""
    import numpy as np

    from ..sensitivity import double_double as ddm
    from ..sensitivity.refine import dense_modes
    from ..modes.spectrum import spectrum

    n = len(m)
    size = n - 1 if clamped else n
    masses = np.array(m[:size], dtype=float)
    ends = np.array([(-1, 0)] + [(i - 1, i) for i in range(1, size)] + ([(size - 1, -1)] if clamped else []),
                    dtype=np.intp)
    kk = np.array(k[:size + (1 if clamped else 0)], dtype=float)
    st = ddm.Stencil(masses, ends)
    modes, _ = dense_modes(st, kk, spectrum(masses, ends, kk))
    hi, lo = np.zeros((size, 2 * n)), np.zeros((size, 2 * n))
    for j in range(size):
        x = modes.column(j)
        w = (np.float64(modes.omega2[0][j]), np.float64(modes.omega2[1][j]))
        a = ddm.neg(ddm.mul_f(ddm.mul(x, x), masses))
        d = st.stretches(x)
        b = ddm.div(ddm.mul_f(ddm.mul(d, d), kk), (np.full(kk.shape, w[0]), np.full(kk.shape, w[1])))
        hi[j, :size], lo[j, :size] = a
        hi[j, n:n + kk.shape[0]], lo[j, n:n + kk.shape[0]] = b
    return hi, lo


def condition(m: list, k: list) -> float:
    """κ = max_i Σ_j |∂ log p_i / ∂ log s_j| of the rebuilt chain (module docstring): the inverse of the forward
    Jacobian (both spectra, and the log of the total mass for the scale)."""
    import numpy as np

    n = len(m)
    mf = np.array([float(x) for x in m])
    kf = np.array([float(x) for x in k])
    (h1, l1), (h2, l2) = _fractions(mf, kf, False), _fractions(mf, kf, True)
    scale = np.concatenate([mf / mf.sum(), np.zeros(n)])[None, :]
    hi, lo = np.vstack([h1, h2, scale]), np.vstack([l1, l2, np.zeros_like(scale)])
    A = hi + lo
    if not np.linalg.cond(A) < 1e12:  # float64 cannot settle it (the caller measures it instead)
        return float("inf")
    return float(np.max(np.sum(np.abs(np.linalg.inv(A)[:, :2 * n - 1]), axis=1)))


def distinct_texts(values: list, least: int = 12) -> list[str]:
    """The values printed with the fewest significant digits (at least ``least``, at most the working
    precision) whose rounding stays below a tenth of the smallest difference between unequal values, so
    that the texts show how they differ."""
    gaps = [abs(a - b) for i, a in enumerate(values) for b in values[:i] if a != b]
    gap = min(gaps) if gaps else mpmath.mpf(0)
    for digits in range(least, mpmath.mp.dps + 1):
        texts = [mpmath.nstr(v, digits) for v in values]
        if all(10 * abs(mpmath.mpf(t) - v) <= gap for t, v in zip(texts, values)):
            return texts
    return [mpmath.nstr(v, mpmath.mp.dps) for v in values]


def _rebuild(lam: list, mu: list | None, phi_end: list | None, total_mass, file: str) -> tuple[list, list]:
    """(m, k) at the current precision from mpmath inputs (checked here: positivity, order, interlacing)."""
    n = len(lam)
    if any(x <= 0 for x in lam) or any(b <= a for a, b in zip(lam, lam[1:])):
        raise RunRefused(f"{file}: omega2_free: the values must be > 0 and strictly increasing (sorted, no "
                         "repeats); accepted: the n squared natural frequencies of the fixed-free chain", "spectra")
    last = None
    if phi_end is not None:
        if len(phi_end) != n:
            raise RunRefused(f"{file}: end_component: {len(phi_end)} values for {n} in omega2_free; accepted: as "
                             "many", "spectra")
        if any(x == 0 for x in phi_end):
            raise RunRefused(f"{file}: end_component: a zero end component (a mode with a node at the free end "
                             "cannot be one of this chain's); accepted: nonzero values", "spectra")
        s = mpmath.fsum(x * x for x in phi_end)
        last = 1 / s
        w = [x * x / s for x in phi_end]
    else:
        if len(mu) != n - 1:
            raise RunRefused(f"{file}: omega2_clamped: {len(mu)} values for {n} in omega2_free; accepted: one fewer",
                             "spectra")
        bad = next((i for i in range(n - 1) if not lam[i] < mu[i] < lam[i + 1]), None)
        if bad is not None:
            a, b, c = lam[bad], mu[bad], lam[bad + 1]
            low, high, gap = (f"omega2_free[{bad}]", f"omega2_clamped[{bad}]", b - a) if not a < b else \
                (f"omega2_clamped[{bad}]", f"omega2_free[{bad + 1}]", c - b)
            raise RunRefused(f"{file}: the spectra do not interlace: need omega2_free[{bad}] < omega2_clamped[{bad}] "
                             f"< omega2_free[{bad + 1}], got {', '.join(distinct_texts([a, b, c]))} ({high} - {low} "
                             f"= {mpmath.nstr(gap, 3)}); accepted: strictly interlacing spectra (every clamped value "
                             "between two free ones, distinct in the digits given)", "spectra")
        w = weights_from_spectra(lam, mu)
    alpha, beta = lanczos(lam, w)
    if last is not None and total_mass is None:
        return chain_from_jacobi(alpha, beta, last, last_mass=True)
    return chain_from_jacobi(alpha, beta, mpmath.mpf(total_mass))


def reconstruct(lam_text: list[str], mu_text: list[str] | None, total_mass: float | None, file: str,
                end_text: list[str] | None = None) -> Chain:
    """Masses and springs of the fixed–free chain with spectra ``lam_text`` (n) and ``mu_text`` (n − 1),
    or ``lam_text`` and the end components ``end_text`` (n) of the mass-normalised shapes.

    Parameters
    ----------
    lam_text, mu_text, end_text : list of str
        Decimal texts (checked by the caller), any number of digits.
    total_mass : float or None
        The scale (required with two spectra; with end components, m_n is known).
    file : str
        For messages.

    Notes
    -----
    Working precision: 20 digits beyond the input's (so the arithmetic adds less than the input's own
    rounding, whatever κ). κ from the forward Jacobian in float64 where that matrix is well enough
    conditioned to invert (cond < 1e12), else measured: the rebuild repeated 40 digits deeper from inputs
    moved by ±10^-dps (random signs, two draws), the largest relative change of any mass or spring over
    the relative move.

    Raises
    ------
    RunRefused
        Spectra that do not interlace, non-positive values, a wrong count (one line).
    """
    import numpy as np

    texts = lam_text + (mu_text or []) + (end_text or [])
    if len(lam_text) > MAX_MASSES:
        raise RunRefused(f"{file}: {len(lam_text)} values in omega2_free; accepted: at most {MAX_MASSES} masses",
                         "spectra")
    longest = max(significant_digits(t) for t in texts)
    if longest > MAX_DIGITS:
        raise RunRefused(f"{file}: a value of {longest} significant digits; accepted: at most {MAX_DIGITS}",
                         "spectra")
    digits = min(significant_digits(t) for t in texts)
    dps = max(40, digits + 20)
    u = 0.5 * 2.0 ** -52 if digits <= FLOAT64_DIGITS else 0.5 * 10.0 ** (1 - digits)
    n = len(lam_text)

    def read(texts_):
        return None if texts_ is None else [mpmath.mpf(t) for t in texts_]

    with mpmath.workdps(dps):
        m, k = _rebuild(read(lam_text), read(mu_text), read(end_text), total_mass, file)
    kappa = condition(m, k) if n > 1 else 1.0
    if not np.isfinite(kappa):  # float64 could not settle it: measure it
        rng = np.random.default_rng(0)
        with mpmath.workdps(dps + 40):
            delta = mpmath.mpf(10) ** (-dps)
            worst = mpmath.mpf(0)
            for _ in range(2):
                move = lambda xs: None if xs is None else [x * (1 + delta * int(rng.choice([-1, 1])))  # noqa: E731
                                                           for x in read(xs)]
                m2, k2 = _rebuild(move(lam_text), move(mu_text), move(end_text), total_mass, file)
                worst = max([worst] + [abs(a / b - 1) for a, b in zip(m2 + k2, m + k)])
            kappa = float(worst / delta)
    return Chain(m, k, kappa, u, kappa * u, dps)


__all__ = ["Chain", "reconstruct", "weights_from_spectra", "lanczos", "chain_from_jacobi", "chain_spectra",
           "condition", "significant_digits"]
