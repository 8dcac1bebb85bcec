"""Closed-form normal modes of ``K φ = ω² M φ`` (equivalently of ``D = M^-1/2 K M^-1/2``).

Structure first, algebra second:

1. **Rigid-body modes by structure.** Each free connected piece of the
   spring graph contributes one exact ``ω² = 0`` with the uniform translation
   of that piece as its shape. They are projected out before any algebra.
2. **Mirror symmetry.** If reversing the mass order maps M and K to
   themselves, the problem splits into symmetric and antisymmetric blocks of
   half the size.
3. **Factor the characteristic polynomial** ``det(K_b - λ M_b)`` of each
   block (rigid-body factors λ divided out exactly), solve the factors of
   degree ≤ 3 by radicals, and build each shape from cofactors (polynomials
   in λ reduced modulo its factor); no ``simplify`` on large expressions.
4. **Work caps, never a clock.** Blocks larger than ``MAX_SYMBOLIC_BLOCK``,
   characteristic polynomials over ``work.MAX_DET_TERMS`` terms (bounded before
   expanding them), factors of degree > 3 and roots over ``MAX_ROOT_OPS``
   operations fall back to numeric values at the scene's parameters, with a
   note. Every cap is a size, so the same scene gives the same module on any
   machine under any load (``derive --check`` is stable).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from .caps import CAPS
from .accurate import MAX_MPMATH_MODES, Float64Limit, exact_values, numeric_modes, omega2_value, spring_factor_modes
from .errors import SceneError
from .model import Model
from .pieces import pieces
from .work import (MAX_DET_TERMS, MAX_NUMBER_DIGITS, NumbersTooLong, SymbolicNumbersFailed, WorkCapExceeded, check,
                   det_terms_bound, number_digits, sympy_numbers)

#: Largest block (after rigid modes and mirror symmetry) whose determinant is expanded symbolically.
MAX_SYMBOLIC_BLOCK = CAPS.symbolic_block
#: Largest closed-form root (SymPy operation count) worth printing and generating.
MAX_ROOT_OPS = CAPS.root_ops


#: The symbolic eigen-problem is past a work cap (kept name: it was once a time budget).
BudgetExceeded = WorkCapExceeded


@dataclass(frozen=True)
class Mode:
    """One eigenvalue ω² with its independent physical shapes.

    ``shapes`` are physical displacement patterns (columns of ``M^-1/2 e``), any
    scale; ``weighted`` the corresponding mass-weighted eigenvectors ``e = M^1/2 φ``.
    ``exact`` is False for numeric fallbacks (whose shape components are Python floats
    past ``MAX_MPMATH_MODES`` masses).
    """

    omega2: sp.Expr
    multiplicity: int
    shapes: tuple[tuple[sp.Expr, ...], ...]
    rigid: bool = False
    exact: bool = True


@dataclass(frozen=True)
class ModeSet:
    modes: tuple[Mode, ...]
    closed_form: bool
    notes: tuple[str, ...] = field(default=())

    def weighted(self, model: Model) -> list[list[tuple[sp.Expr, ...]]]:
        """Mass-weighted eigenvectors ``M^1/2 φ`` for each mode's shapes."""
        r = [sp.sqrt(m) for m in model.masses]
        return [[tuple(ri * c for ri, c in zip(r, s)) for s in mode.shapes] for mode in self.modes]


def _rigid_shapes(model: Model) -> list[tuple[sp.Expr, ...]]:
    n = model.scene.n
    return [tuple(sp.Integer(1) if i in comp else sp.Integer(0) for i in range(n))
            for comp in model.free_components]


def _pieces(model: Model) -> list[list[int]]:
    """Index sets of the decoupled pieces of ``K`` and ``M`` (joined by non-zero off-diagonal entries)."""
    n = model.scene.n
    return pieces(n, ((i, j) for i in range(n) for j in range(i + 1, n)
                      if model.K[i, j] != 0 or model.M[i, j] != 0))


def _mirror(model: Model, piece: list[int]) -> list[int] | None:
    """The reversal of ``piece`` (as positions in it) if it leaves its M and K unchanged, else None."""
    n = len(piece)
    if n < 2:
        return None
    p = list(range(n - 1, -1, -1))
    M, K = model.M, model.K
    for a in range(n):
        i, pi = piece[a], piece[p[a]]
        if sp.expand(M[i, i] - M[pi, pi]) != 0:
            return None
        for b in range(n):
            if sp.expand(K[i, piece[b]] - K[pi, piece[p[b]]]) != 0:
                return None
    return p


def _blocks(model: Model) -> list[sp.Matrix]:
    """Bases (columns) of the invariant subspaces used to split the problem: one set per
    decoupled piece (pieces share no spring, so their problems are independent), each split
    again into mirror-symmetric and antisymmetric halves when the piece reads the same reversed."""
    n = model.scene.n
    blocks = []
    for piece in _pieces(model):
        p = _mirror(model, piece)
        if p is None:
            p = list(range(len(piece)))
        sym, anti = [], []
        for a, b in enumerate(p):
            if a <= b:
                e = [0] * n
                e[piece[a]] = e[piece[b]] = 1
                sym.append(e)
            if a < b:
                f = [0] * n
                f[piece[a]], f[piece[b]] = 1, -1
                anti.append(f)
        blocks.extend(sp.Matrix(half).T for half in (sym, anti) if half)
    return blocks


def _cofactor_vector(A: sp.Matrix, fac: sp.Expr, lam: sp.Symbol) -> list[sp.Expr] | None:
    """A kernel vector of ``A(λ)`` at the roots of ``fac`` from signed minors of one row deletion.

    Deleting row r gives ``adj(A)`` column r, which is the kernel vector times its r-th
    component: it vanishes at the root when the mode does not move mass r (e.g. a mode
    of another free piece), although it is not zero as a polynomial in λ. So the row is
    accepted only if the vector is non-zero modulo ``fac`` (at the root itself).
    """
    n = A.shape[0]
    if n == 1:
        return [sp.Integer(1)]
    for r in range(n):
        sub = A.copy()
        sub.row_del(r)
        vec = []
        for j in range(n):
            minor = sub.copy()
            minor.col_del(j)
            vec.append((-1) ** j * minor.det(method="berkowitz"))
        if any(sp.rem(sp.expand(c), fac, lam) != 0 for c in vec):
            return vec
    return None


def _normalise_mod(vec: list[sp.Expr], fac: sp.Expr, lam: sp.Symbol) -> list[sp.Expr]:
    """Divide by the first non-zero component modulo the factor: components become
    polynomials of degree < deg(fac) in λ with rational coefficients (short and readable)."""
    vec = [sp.rem(sp.expand(c), fac, lam) for c in vec]
    pivot = next(c for c in vec if c != 0)
    inv = sp.invert(pivot, fac, lam)
    out = []
    for c in vec:
        r = sp.Poly(sp.rem(sp.expand(c * inv), fac, lam), lam)
        out.append(sp.Add(*(sp.factor(co) * lam**k for (k,), co in r.terms())))
    return out


def _normalise(vec: list[sp.Expr]) -> tuple[sp.Expr, ...]:
    """Scale so that the first non-zero component is 1, keeping expressions small."""
    vec = [sp.radsimp(sp.cancel(c)) if c.has(sp.Pow) else sp.cancel(c) for c in vec]
    pivot = next((c for c in vec if c != 0), None)
    if pivot is None:
        return tuple(vec)
    return tuple(sp.radsimp(sp.cancel(c / pivot)) for c in vec)


def _solve_block(model: Model, B: sp.Matrix, lam: sp.Symbol, n_rigid_in_block: int,
                 max_radical_degree: int) -> list[Mode]:
    if B.shape[1] - n_rigid_in_block > MAX_SYMBOLIC_BLOCK:
        raise BudgetExceeded  # characteristic polynomial of degree > 6: no closed form worth printing
    Kb = (B.T * model.K * B).applyfunc(sp.expand)
    Mb = (B.T * model.M * B).applyfunc(sp.expand)
    if number_digits([*Kb, *Mb]) > MAX_NUMBER_DIGITS:  # a size, like every cap: no seconds of factoring
        raise NumbersTooLong
    A = Kb - lam * Mb
    check(det_terms_bound(A), MAX_DET_TERMS)  # before expanding: the size of the work, not its time
    poly = sp.Poly(A.det(method="berkowitz"), lam)
    if n_rigid_in_block:
        poly = sp.Poly(sp.quo(poly.as_expr(), lam**n_rigid_in_block, lam), lam)
    _, factors = sp.factor_list(poly.as_expr(), lam)
    modes = []
    for fac, mult in factors:
        fpoly = sp.Poly(fac, lam)
        if fpoly.degree() == 0:
            continue
        if fpoly.degree() > max_radical_degree:
            raise BudgetExceeded  # no readable closed form: numeric fallback
        roots = _cubic_real_roots(fpoly) if fpoly.degree() == 3 else sp.roots(fpoly, lam, multiple=True)
        if len(roots) != fpoly.degree():
            raise BudgetExceeded
        if any(sp.count_ops(r) > MAX_ROOT_OPS for r in roots):
            raise BudgetExceeded  # a closed form nobody can read: numeric values instead
        for root in roots:
            root = sp.factor(sp.radsimp(root)) if fpoly.degree() == 1 else root
            if mult == 1:
                vec = _cofactor_vector(A, fac, lam)
                if vec is None:
                    raise BudgetExceeded
                if fpoly.degree() > 1:
                    vec = _normalise_mod(vec, fac, lam)
                    phys = [tuple(sp.collect(sp.expand(c.subs(lam, root)), root) if c.has(lam) else c
                                  for c in B * sp.Matrix(vec))]
                    modes.append(Mode(root, mult, tuple(phys)))
                    continue
                vec = [c.subs(lam, root) for c in vec]
                shapes = [vec]
            else:
                ns = (Kb - root * Mb).applyfunc(sp.cancel).nullspace(simplify=True)
                if len(ns) != mult:
                    raise BudgetExceeded
                shapes = [list(v) for v in ns]
            phys = [_normalise(list(B * sp.Matrix(s))) for s in shapes]
            modes.append(Mode(root, mult, tuple(phys)))
    return modes


def _cubic_real_roots(poly: sp.Poly) -> list[sp.Expr]:
    """The three real roots of a cubic in Viète's trigonometric form (no complex radicals).

    For ``a λ³ + b λ² + c λ + d`` with depressed form ``t³ + p t + q`` (p < 0 when all
    three roots are real, as for a symmetric positive pencil)::

        λ_k = -b/(3a) + 2 sqrt(-p/3) cos(acos(3q/(2p) sqrt(-3/p))/3 - 2πk/3),  k = 0, 1, 2
    """
    a, b, c, d = poly.all_coeffs()
    p = sp.cancel((3 * a * c - b**2) / (3 * a**2))
    q = sp.cancel((2 * b**3 - 9 * a * b * c + 27 * a**2 * d) / (27 * a**3))
    shift = sp.cancel(-b / (3 * a))
    r = 2 * sp.sqrt(-p / 3)
    phi = sp.acos(3 * q / (2 * p) * sp.sqrt(-3 / p)) / 3
    return [shift + r * sp.cos(phi - 2 * sp.pi * k / 3) for k in range(3)]


def closed_form_modes(model: Model, max_radical_degree: int = 3) -> ModeSet:
    """Eigenvalues ω² and shapes of ``K φ = ω² M φ`` for a (small) scene.

    Parameters
    ----------
    model : Model
    max_radical_degree : int
        Irreducible factors of higher degree are not solved by radicals.

    Returns
    -------
    ModeSet
        Sorted by the numeric value of ω² at the scene's parameters.

    Raises
    ------
    SceneError
        If an ω² lies outside float64's normal range (it could not be printed with its relative accuracy).
    """
    try:
        return _closed_form_modes(model, max_radical_degree)
    except Float64Limit as exc:
        raise _outside_float64(model, exc) from None


def _closed_form_modes(model: Model, max_radical_degree: int) -> ModeSet:
    lam = sp.Symbol("lambda")
    rigid = _rigid_shapes(model)
    modes: list[Mode] = []
    if rigid:
        modes.append(Mode(sp.Integer(0), len(rigid), tuple(rigid), rigid=True))
    notes: list[str] = []
    # a mirror split at best halves the problem: beyond twice the largest block nothing is solvable
    hopeless = model.scene.n - len(rigid) > 2 * MAX_SYMBOLIC_BLOCK + 1
    # K about an equilibrium found by Newton holds numbers, not closed forms
    numeric_k = getattr(model, "equilibrium", None) is not None and not model.equilibrium.closed_form
    try:
        if hopeless or numeric_k:
            raise BudgetExceeded
        with sympy_numbers():
            for B in _blocks(model):
                # rigid translations lie in the symmetric block (uniform vectors are mirror-symmetric)
                # the rigid space is mirror-invariant: its share of this block has dimension rank(Bᵀ R)
                n_rigid = (B.T * sp.Matrix.hstack(*[sp.Matrix(s) for s in rigid])).rank() if rigid else 0
                modes.extend(_solve_block(model, B, lam, n_rigid, max_radical_degree))
            subs = exact_values(model.params, model.scene.parameters)
            modes = _merge_equal(modes, subs)
        closed = True
    except BudgetExceeded as exc:
        why = ("K is the Hessian at a numerically found equilibrium" if numeric_k else
               f"{model.scene.n} masses: symmetry blocks larger than {MAX_SYMBOLIC_BLOCK}" if hopeless else
               "SymPy's arithmetic failed on the scene's exact numbers" if isinstance(exc, SymbolicNumbersFailed) else
               f"exact numbers of more than {MAX_NUMBER_DIGITS} digits" if isinstance(exc, NumbersTooLong)
               else f"a factor of degree > 3, an unreadably long root, or a characteristic polynomial of more "
               f"than {MAX_DET_TERMS} terms")
        how = ("mpmath eigensolver at increasing precision, correct to float64" if model.scene.n <= MAX_MPMATH_MODES
               else "spring-factor SVD, as the generated module's omega2(), relatively accurate to a few float64 ulps")
        notes.append(f"no closed form ({why}); eigenvalues below are numeric ({how}) at the scene's parameter values")
        modes = [m for m in modes if m.rigid] + _numeric_modes(model, lam, len(rigid))
        closed = False
    subs = exact_values(model.params, model.scene.parameters)
    if not closed:
        modes = _merge_equal(modes, subs)
    # rigid modes first (exact zeros by structure), then by the correctly rounded value
    modes.sort(key=lambda m: (not m.rigid, omega2_value(m, subs), str(m.omega2)))
    return ModeSet(tuple(modes), closed, tuple(notes))


def _outside_float64(model: Model, exc: Float64Limit) -> SceneError:
    """The one-line refusal of a scene whose ω² float64 cannot print with its relative accuracy."""
    return SceneError(model.scene.file, "masses", f"an ω² of this scene is {exc}; accepted: masses and "
                      "stiffnesses whose squared frequencies lie in float64's normal range")


def _merge_equal(modes: list[Mode], subs: dict) -> list[Mode]:
    """Merge exact modes whose ω² are equal (e.g. one from each mirror block) into one repeated mode.

    Numeric fallback modes are kept one per shape; each value is evaluated once.
    """
    out: list[Mode] = []
    values: list[float] = []
    for mode in modes:
        v = omega2_value(mode, subs)
        for j, other in enumerate(out):
            ov = values[j]
            if (mode.exact and other.exact and mode.rigid == other.rigid
                    and abs(v - ov) <= 1e-12 * max(abs(v), abs(ov), 1e-300)
                    and sp.cancel(mode.omega2 - other.omega2) == 0):
                out[j] = Mode(other.omega2, other.multiplicity + mode.multiplicity,
                              other.shapes + mode.shapes, other.rigid, True)
                break
        else:
            out.append(mode)
            values.append(v)
    return out


def _numeric_modes(model: Model, lam: sp.Symbol, n_rigid: int) -> list[Mode]:
    """Numeric fallback at the scene's parameter values (rigid modes stay exact).

    ``D = M^-1/2 K M^-1/2`` is assembled from the element list with the
    parameter values as exact rationals and diagonalised by ``mpmath.eigsy``
    at increasing precision until the spectrum is correct to float64
    (:func:`accurate.numeric_modes`); the rigid-body modes were already taken
    out by structure, so the lowest ``n_rigid`` eigenvalues are dropped. Past
    ``MAX_MPMATH_MODES`` masses (where mpmath's O(N³) multiprecision work takes
    minutes) the spring-factor route of the generated modules is used instead
    (:func:`accurate.spring_factor_modes`).
    """
    subs = exact_values(model.params, model.scene.parameters)
    masses = [m.xreplace(subs) for m in model.masses]
    springs = [(a, b, k.xreplace(subs)) for a, b, k, _, _ in model.springs]
    if model.scene.n > MAX_MPMATH_MODES:
        found = spring_factor_modes(masses, springs, model.free_components)
    else:
        found = numeric_modes(masses, springs, n_rigid)
    out = []
    for w, shape in found:
        # the float64 shapes of the spring-factor route stay Python floats: 40 000 SymPy Floats
        # cost a second at N = 200 and carry no more information
        vec = tuple(shape) if model.scene.n > MAX_MPMATH_MODES else tuple(sp.Float(c, 17) for c in shape)
        out.append(Mode(sp.Float(w, 17), 1, (vec,), exact=False))
    return out
