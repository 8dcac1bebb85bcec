"""Numbers people read, correctly rounded to float64 at any parameter values.

Two routes, both independent of float64 cancellation:

* **Closed forms** are evaluated in mpmath with the parameter values as
  *exact* binary fractions (a float is one) at increasing working precision
  (30, 60, 120, … digits) until two successive results agree to 1e-18
  relative (:func:`value`). A casus-irreducibilis cubic or a quadratic root
  that cancels in float64 is then correct to the last bit. (SymPy's own
  ``evalf`` is not used: on a Viète root with acos near -1 it converged,
  at every precision, to a value 1.9e-11 off -- found by hypothesis.)
* **No closed form**: the mass-weighted dynamical matrix ``D = M^-1/2 K M^-1/2``
  is assembled *exactly* from the element list (rational spring constants and
  masses, square roots at working precision) and diagonalised by
  ``mpmath.eigsy`` at 40, 80, 160, … digits until every elastic eigenvalue
  stands 22 decades above eigsy's rounding bound ~n² 10^-dps ‖D‖ (:func:`certified`;
  two precisions agreeing is not proof: both can deflate the same small
  coupling). Rigid-body modes are
  removed by structure (their count), never by a threshold on a value.
  Past :data:`MAX_MPMATH_MODES` masses (mpmath's dense eigensolver costs
  O(N³) multiprecision operations: minutes at N = 200) the fallback is the
  spring-factor route instead (:func:`spring_factor_modes`): the same code the
  generated modules run (``_accurate_modes``), relatively accurate to a few
  float64 ulps at any positive parameter values.

SymPy, mpmath, NumPy and SciPy only (this is the derive side; it never imports ``numeric``).
"""

from __future__ import annotations

import functools
from fractions import Fraction

import mpmath
import sympy as sp

from .caps import CAPS
from .mp_eval import mp_function, mp_function_bounded

#: Relative agreement of two successive precisions accepted as converged.
AGREE = 1e-18
#: Largest working precision (decimal digits) tried before giving up.
MAX_DPS = 1280
#: Most masses whose numeric fallback modes come from mpmath (beyond: the spring-factor route).
MAX_MPMATH_MODES = CAPS.mpmath_modes


class NotAccurate(ArithmeticError):
    """A value could not be evaluated to float64 accuracy within :data:`MAX_DPS` digits."""


def exact_values(params: dict, values: dict) -> dict:
    """``{Symbol: Rational}`` with each float parameter value converted exactly.

    Parameters
    ----------
    params : dict
        Parameter name -> SymPy symbol.
    values : dict
        Parameter name -> float value.
    """
    return {params[k]: sp.Rational(Fraction(float(v))) for k, v in values.items()}


@functools.lru_cache(maxsize=512)
def _mp_function(expr: sp.Expr, symbols: tuple):
    """``expr`` as an mpmath function of ``symbols`` (built once per expression, :mod:`derive.mp_eval`)."""
    return mp_function(expr, symbols)


def _mp_exact(r: sp.Rational):
    """A rational at the current mpmath precision (exact for the binary fractions of float inputs)."""
    return mpmath.mpf(r.p) / r.q


#: Smallest positive normal float64 and the largest finite one: a value people read outside this
#: range would print as 0, a subnormal with fewer digits, or inf (:class:`Float64Limit`).
FLOAT64_TINY, FLOAT64_HUGE = 2.2250738585072014e-308, 1.7976931348623157e308


class Float64Limit(ArithmeticError):
    """A value that must be printed with float64's relative accuracy lies outside its normal range."""


def _known_zero(expr: sp.Expr, subs: tuple):
    """Whether SymPy sees ``expr`` at the exact values as 0 (True, False or None: undecided).

    SymPy evaluates powers of the substituted numbers at once, and its square roots of large
    integers go through ``factorint(limit=2**15)``, which raises on some inputs (SymPy 1.14:
    "... is not a prime factor of ...", sympy/sympy#28621; with gmpy2 on Python < 3.13,
    ``math.log`` of an ``mpz`` past 1e308 overflows). Such a failure only means "undecided":
    the numeric evaluation decides instead.
    """
    try:
        return (expr.xreplace(dict(subs)) if subs else expr).is_zero  # symbols -> exact rationals
    except (ValueError, OverflowError, ArithmeticError):
        return None


@functools.lru_cache(maxsize=512)
def _mp_bounded(expr: sp.Expr, symbols: tuple):
    """``expr`` as ``f(*values) -> (value, error bound)`` (:func:`derive.mp_eval.mp_function_bounded`), or None."""
    return mp_function_bounded(expr, symbols)


@functools.lru_cache(maxsize=4096)
def _value(expr: sp.Expr, subs: tuple, nonzero: bool = False, floor: float | None = None) -> float:
    if not nonzero and _known_zero(expr, subs):
        return 0.0
    symbols = tuple(s for s, _ in subs if expr.has(s))
    values = [v for s, v in subs if expr.has(s)]
    bounded = _mp_bounded(expr, symbols)
    f = _mp_function(expr, symbols) if bounded is None else None
    prev = prev_mp = None
    prev_dps = None
    dps = 30
    while dps <= MAX_DPS:
        with mpmath.workdps(dps):
            try:
                if bounded is not None:
                    z, err = bounded(*[_mp_exact(v) for v in values])
                else:
                    z, err = mpmath.re(f(*[_mp_exact(v) for v in values])), None
                cur = float(z)
            except (ZeroDivisionError, ValueError, OverflowError):
                z, err, cur = None, None, float("nan")
        if err is not None and cur == cur:
            # a first-order bound on the rounding of this evaluation: the value is settled when the
            # bound is far below it (even a term lost at two precisions shows in it)
            if z != 0 and err <= AGREE * abs(z):
                _in_range(expr, z, nonzero)
                return cur
            if floor is not None and not nonzero and abs(z) + err <= floor:
                return 0.0
        if prev is not None and cur == cur and prev == prev:
            if err is None and z != 0 and prev_mp != 0 and abs(z - prev_mp) <= AGREE * max(abs(z), abs(prev_mp)):
                _in_range(expr, z, nonzero)
                return cur
            if floor is not None and not nonzero:
                # without a bound: the value and the lower precision's noise both under the floor. Two
                # exact zeros prove nothing (a term lost at both precisions) before 640 digits.
                if err is None and abs(z) <= floor and abs(z - prev_mp) <= floor and (
                        z != 0 or prev_mp != 0 or prev_dps >= 640):
                    return 0.0
            # a quantity that is exactly zero but not recognised as such: its rounding noise shrinks
            # as fast as the precision grows (never taken for a quantity known to be nonzero, e.g.
            # the ω² of an elastic mode, which may be 1e-300 of the terms it is computed from). A
            # heuristic: an O(1) value under noise of 1e209 shrinks the same way (a shape component
            # of 0.618 from terms of 1e269 was taken for 0), so a caller that knows the scale gives
            # ``floor`` instead.
            elif not nonzero and prev_dps >= 60 and (
                    z == 0 == prev_mp or abs(z) <= abs(prev_mp) * mpmath.mpf(10) ** (-prev_dps // 2)):
                return 0.0
        prev, prev_mp, prev_dps = cur, z, dps
        dps *= 2
    raise NotAccurate(f"{sp.sstr(expr)} does not converge to float64 accuracy within {MAX_DPS} digits")


def _in_range(expr: sp.Expr | None, z, nonzero: bool) -> None:
    """Raise :class:`Float64Limit` for a value float64 cannot hold (inf; below the normal range when
    ``nonzero`` asks for its relative accuracy)."""
    if abs(z) > FLOAT64_HUGE or (nonzero and abs(z) < FLOAT64_TINY):
        raise Float64Limit(f"{mpmath.nstr(z, 3)} is outside float64's normal range "
                           f"({FLOAT64_TINY:.3g} to {FLOAT64_HUGE:.3g} in size)")


def value(expr, subs: dict, *, nonzero: bool = False, floor: float | None = None) -> float:
    """The real part of ``expr`` at ``subs`` (exact rationals), correctly rounded to float64.

    Parameters
    ----------
    expr : sympy.Expr or int
    subs : dict
        ``{Symbol: Rational}`` from :func:`exact_values`.
    nonzero : bool
        The quantity is known not to be 0 (the ω² of an elastic mode): its relative accuracy is
        what counts, so the precision is raised until it settles however small it is next to the
        terms it is computed from, instead of being taken for an exact zero lost in rounding noise.
    floor : float, optional
        A size below which the value does not matter (e.g. 1e-20 of the shape it is a component
        of): the value is 0.0 once it and the rounding noise are both below it. Without it, an
        exact zero SymPy does not recognise is told by its noise shrinking with the precision, a
        heuristic that a value far below the terms it comes from can fool.

    Returns
    -------
    float

    Raises
    ------
    NotAccurate
        If successive precisions up to :data:`MAX_DPS` digits never agree.
    Float64Limit
        If the value is beyond float64's range (or, with ``nonzero``, below its normal range).
    """
    if isinstance(expr, float):  # a float64 already (numeric fallback shapes): its own value
        return expr
    if isinstance(expr, int):
        expr = sp.Integer(expr)
    if expr.is_Float and expr._prec >= 53:  # a float64 (or wider) number already: it is its own value
        return float(expr)
    # keyed by name (a Symbol's str, without printing it: 168 000 str calls were 2 s of a 40-mass report)
    return _value(expr, tuple(sorted(subs.items(), key=lambda kv: getattr(kv[0], "name", None) or str(kv[0]))),
                  nonzero, floor)


def omega2_value(mode, subs: dict) -> float:
    """ω² of ``mode`` (a :class:`derive.modes.Mode`) at the exact parameter values ``subs``, correctly
    rounded to float64.

    0 for a rigid-body mode (by structure); a numeric fallback's own value; a closed form evaluated
    with :func:`accurate.value` as a quantity known to be nonzero (every elastic ω² is > 0), so that
    an ω² of 1e-90 next to terms of size 1 is settled to its own relative accuracy, never taken for a
    zero lost in rounding noise.
    """
    if mode.rigid:
        return 0.0
    if not mode.exact:
        return float(mode.omega2)
    return value(mode.omega2, subs, nonzero=True)



def mp_value(e: sp.Expr, dps: int):
    """An exact SymPy number as an mpmath value at the current working precision."""
    if isinstance(e, sp.Rational):
        return mpmath.mpf(e.p) / e.q
    return mpmath.mpf(sp.N(e, dps + 10)._mpf_)


def eig_dynamical(masses: list, springs: list, n: int, dps: int):
    with mpmath.workdps(dps):
        r = [1 / mpmath.sqrt(mp_value(m, dps)) for m in masses]
        D = mpmath.zeros(n, n)
        for a, b, k in springs:
            kv = mp_value(k, dps)
            for i, si in ((a, 1), (b, -1)):
                for j, sj in ((a, 1), (b, -1)):
                    if i >= 0 and j >= 0:
                        D[i, j] += si * sj * kv * r[i] * r[j]
        w, E = mpmath.eigsy(D)
        order = sorted(range(n), key=lambda j: w[j])
        return [w[j] for j in order], [[E[i, j] * r[i] for i in range(n)] for j in order]


#: Decimal digits below an eigenvalue that the rounding of eigsy (its backward error, ~n² 10^-dps ‖D‖
#: absolute by Weyl's theorem) must stay for the value to count as settled (see :func:`certified`).
CERTIFIED_DIGITS = 22


def dynamical_bound(masses: list, springs: list):
    """An upper bound on ‖D‖₂ for ``D = M^-1/2 K M^-1/2``: Σ over springs of k (1/m_a + 1/m_b).

    Each spring adds the rank-one ``k v vᵀ`` with ``‖v‖² = 1/m_a + 1/m_b`` (a wall end adds nothing).
    """
    with mpmath.workdps(30):
        inv = [1 / mp_value(m, 30) for m in masses]
        return mpmath.fsum(mp_value(k, 30) * ((inv[a] if a >= 0 else 0) + (inv[b] if b >= 0 else 0))
                           for a, b, k in springs)


#: Eigenvalues closer than this many times eigsy's rounding bound are one repeated eigenvalue.
_REPEATED = 10**6


def _rounding(n: int, bound, dps: int):
    """eigsy's absolute rounding bound on each eigenvalue at ``dps`` digits: n² 10^-dps ‖D‖."""
    return mpmath.mpf(10) ** (-dps) * n * n * bound


def certified(w: list, n_rigid: int, bound, dps: int) -> bool:
    """Whether the elastic eigenvalues and eigenvectors computed at ``dps`` digits are settled.

    ``mpmath.eigsy`` is backward stable: its eigenvalues are those of ``D + E`` with ‖E‖ a modest
    multiple (taken as n²) of 10^-dps ‖D‖, so each is within that of the true one (Weyl), and an
    eigenvector's error is that over its gap to the other eigenvalues. Settled: every elastic
    eigenvalue ``CERTIFIED_DIGITS`` decades above that bound (relative accuracy), and every gap
    between neighbours either as far above it (the vectors are determined) or within
    ``_REPEATED`` times it (a repeated eigenvalue: any basis of its eigenspace; :func:`clusters`).
    Two successive precisions agreeing is *not* enough: at 40 and at 80 digits eigsy deflated the
    same 4e-72 off-diagonal entry of a 1e24-norm matrix and returned the same ω² = 7.2820666e-155,
    1.1e-6 above the true 7.2820585e-155 (a 7.5e143 kg mass on a 5.5e-11 N/m spring).
    """
    with mpmath.workdps(dps):
        err = _rounding(len(w), bound, dps)
        far = mpmath.mpf(10) ** CERTIFIED_DIGITS * err
        elastic = w[n_rigid:]
        return all(x > far for x in elastic) and all(
            b - a <= _REPEATED * err or b - a > far for a, b in zip(elastic, elastic[1:]))


def clusters(w: list, n_rigid: int, bound, dps: int) -> list[list[int]]:
    """Index groups of one eigenvalue each: the rigid modes (exact zeros) one group, then elastic
    neighbours within ``_REPEATED`` times eigsy's rounding bound (see :func:`certified`)."""
    groups = [list(range(n_rigid))] if n_rigid else []
    with mpmath.workdps(dps):
        tol = _REPEATED * _rounding(len(w), bound, dps)
        for j in range(n_rigid, len(w)):
            if groups and groups[-1][0] >= n_rigid and w[j] - w[groups[-1][-1]] <= tol:
                groups[-1].append(j)
            else:
                groups.append([j])
    return groups


def numeric_modes(masses: list, springs: list, n_rigid: int) -> list[tuple[float, list[float]]]:
    """Elastic modes ``(ω², physical shape)`` of ``K φ = ω² M φ`` to float64 accuracy.

    Parameters
    ----------
    masses : list of sympy.Expr
        Exact mass values (numbers, usually Rational), length N.
    springs : list of (int, int, sympy.Expr)
        Spring ends (mass indices, -1 = wall) and exact stiffness.
    n_rigid : int
        Number of rigid-body modes (free pieces); the lowest ``n_rigid``
        eigenvalues are theirs and are dropped.

    Returns
    -------
    list of (float, list of float)
        Ascending ω² of the elastic modes and their physical shapes, scaled
        so that the largest component is 1.
    """
    n = len(masses)
    bound = dynamical_bound(masses, springs)
    dps = 40
    while dps <= MAX_DPS:
        w, shapes = eig_dynamical(masses, springs, n, dps)
        if certified(w, n_rigid, bound, dps):
            cur = w[n_rigid:]
            for x in cur:
                _in_range(None, x, True)
            out = []
            for lam, s in zip(cur, shapes[n_rigid:]):
                piv = max(s, key=abs)
                out.append((float(lam), [float(c / piv) for c in s]))
            return out
        dps *= 2
    raise NotAccurate(f"numeric modes did not converge to float64 accuracy within {MAX_DPS} digits")


def spring_factor_modes(masses: list, springs: list, rigid_pieces: list) -> list[tuple[float, list[float]]]:
    """Elastic modes ``(ω², physical shape)`` by the spring-factor route, in float64.

    The subtraction-free LDLᵀ of ``K = Bᵀ diag(k) B`` and the one-sided Jacobi
    SVD of its factor: the very code of the generated modules' ``_accurate_modes``
    (:func:`spring_factor._accurate_modes`, run here on the scene's values), relatively accurate
    to a few ulps at any positive parameter values, O(N³) float64 work.

    Parameters
    ----------
    masses : list of sympy.Expr
        Exact mass values, length N.
    springs : list of (int, int, sympy.Expr)
        Spring ends (mass indices, -1 = wall) and exact stiffness.
    rigid_pieces : list of list of int
        Mass indices of each free piece (one rigid-body mode each).

    Returns
    -------
    list of (float, list of float)
        As :func:`numeric_modes`: ascending elastic ω², shapes scaled so that the
        largest component is 1.
    """
    import numpy as np

    from .spring_factor import accurate_modes_function

    ends = tuple((a, b) for a, b, _ in springs)
    run = accurate_modes_function(len(masses), ends, tuple(tuple(sorted(p)) for p in rigid_pieces))
    w2, shapes = run([float(m) for m in masses], [float(k) for _, _, k in springs])
    r = len(rigid_pieces)
    w2, shapes = w2[r:], shapes[:, r:]
    bad = ~((w2 >= FLOAT64_TINY) & (w2 <= FLOAT64_HUGE))
    if bad.any():
        raise Float64Limit(f"{float(w2[np.argmax(bad)]):.3g} (spring-factor route) is outside float64's normal "
                           f"range ({FLOAT64_TINY:.3g} to {FLOAT64_HUGE:.3g} in size)")
    piv = shapes[np.argmax(np.abs(shapes), axis=0), np.arange(shapes.shape[1])]
    shapes = shapes / piv[None, :]
    return [(float(w), shapes[:, j].tolist()) for j, w in enumerate(w2)]


def float64_closed_form(exprs: list, params: dict):
    """The *naive* route, for benchmarks only: ``exprs`` lambdified to NumPy float64.

    This is how ω² were evaluated before issue 9 (cancelling in float64 on hard
    scenes); ``benchmarks/modes.py`` times it beside the generated
    ``omega2()`` and reports its error.

    Parameters
    ----------
    exprs : list of sympy.Expr
        Closed forms (one per mode).
    params : dict
        Parameter name -> SymPy symbol.

    Returns
    -------
    callable
        ``f(**values) -> ndarray`` of shape (len(exprs),).
    """
    names = sorted(params)
    f = sp.lambdify([params[k] for k in names], list(exprs), modules="numpy")

    def naive(**values):
        import numpy as np

        return np.array(f(*[values[k] for k in names]), dtype=float)

    return naive
