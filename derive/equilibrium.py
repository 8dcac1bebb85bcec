"""The static equilibrium of a scene with spring laws, and the checks that it is a stable one.

The total potential ``U(x) = Σ_s V_s(d_s(x)) − Σ_i F_i x_i`` (springs, and the constant loads:
gravity ``m_i g`` and forces that do not depend on t) has the gradient
``G_i = Σ_s V_s'(d_s) ∂d_s/∂x_i − F_i`` and the Hessian ``K = Σ_s V_s''(d_s) b_s b_sᵀ``, both
assembled spring by spring from the exact symbolic derivatives. The equilibrium solves G(x) = 0:

1. **Exactly at x = 0** when every G_i(0) simplifies to 0 (V'(0) = 0 and no constant loads, or
   tensions that balance): then x_eq = 0 and K = Σ V_s''(0) b bᵀ are closed forms.
2. **Otherwise the equilibrium reached by applying the loads gradually from rest**: the
   out-of-balance force at rest ``G(0)`` (the loads and the springs' pre-stress) is applied as
   ``λ G(0)``, λ from 0 to 1, following ``G(x) = (1 − λ) G(0)`` from x = 0, K positive definite
   along the way (a stable branch), each extension inside the open interval around d = 0 where its
   potential is defined (Lennard-Jones ``d > −r0``, ``log(1 + d/c)``: ``d > −c``, ...), so no step
   crosses a singularity onto another branch:

   * where the springs form a tree with the ground (a chain or a tree hung from one wall, free
     pieces) the path splits into one scalar path per spring, its tension fixed by the loads beyond
     it, followed in mpmath (:mod:`derive.equilibrium_tree`); the positions are sums of extensions;
   * otherwise by continuation in x (:mod:`derive.equilibrium_path`): float64, or the residual and K
     in mpmath where K is too ill-conditioned for float64, then refined in mpmath until two
     precisions agree to 1e-18 per coordinate (correct to float64 even where float64 alone could not
     settle it). Where x = 0 itself is not stable the path cannot start; a descent of U from x = 0
     (Newton with a Levenberg–Marquardt safeguard) looks for a minimum instead.

   Each free piece (no spring to a wall) keeps its centre of mass at the rest position (its rigid
   translation is otherwise undetermined). The report says how the equilibrium was found and that it
   is stable (every V''(d) > 0 there, so K is positive definite).

Refused in one line (a :class:`SceneError` naming the spring's key): V, V' or V'' not finite at
the equilibrium (a singularity or a kink), V'' ≤ 0 there (not a stable spring; the stiffness and the
extension are named), a free piece under a net constant load (it accelerates: no equilibrium), or
no stable equilibrium on the loading path (it ends where K becomes singular — a spring past its
largest tension — or runs off to infinity; the fraction of the loads reached is named).
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath
import sympy as sp

from .accurate import exact_values
from .caps import CAPS
from .equilibrium_path import FIRST_STEP, MAX_DPS, mp_vector, PathEnd, PathProblem, descent, path, refine
from .equilibrium_tree import Ended, solve_tree, tree
from .errors import SceneError
from .scene_loader import MAX_MAGNITUDE, MIN_MAGNITUDE
from .work import ops
from .mp_eval import mp_function
from .potential import SpringLaw
from .expr import as_sympy


@dataclass(frozen=True)
class Equilibrium:
    """The static equilibrium x_eq and the springs' extensions and stiffnesses there.

    Attributes
    ----------
    x : tuple of sympy.Expr
        x_eq per coordinate: closed forms (``closed_form``) or correctly rounded numbers (Float).
    extensions : tuple of sympy.Expr
        d_s at x_eq per spring (same kind).
    stiffness : tuple of sympy.Expr
        V_s''(d_s) per spring: the entries of K about x_eq.
    closed_form : bool
        Whether the values are closed forms in the parameters (x_eq = 0).
    how : str
        How it was found, for the report.
    """

    x: tuple
    extensions: tuple
    stiffness: tuple
    closed_form: bool
    how: str

    @property
    def at_rest(self) -> bool:
        """Whether x_eq = 0 exactly (the springs' rest configuration)."""
        return self.closed_form and all(v == 0 for v in self.x)

def _finite(v) -> bool:
    try:
        return bool(mpmath.isfinite(v)) and not isinstance(v, mpmath.mpc)
    except TypeError:
        return False


def _refuse_value(file: str, law: SpringLaw, what: str, d_value, why: str, accepted: str) -> SceneError:
    return SceneError(file, law.where, f"{what} at the equilibrium extension d = {float(d_value):.6g}: "
                                       f"{why}; accepted: {accepted}")


def _at_rest_finite(file: str, law: SpringLaw, subs: dict) -> None:
    """V, V', V'' finite at d = 0, where Newton starts (e.g. not r0/d: write the potential in the
    extension from the rest length, r = r0 + d)."""
    if any(e.has(sp.DiracDelta, sp.Heaviside, sp.sign, sp.Abs) for e in (law.force, law.stiffness)):
        raise SceneError(file, law.where, f"{sp.sstr(law.energy)}: has a kink or a jump (V' or V'' holds Abs or "
                         "sign): not twice differentiable; accepted: a potential with two continuous derivatives, "
                         "e.g. d**2 instead of sqrt(d**2)")
    with mpmath.workdps(30):
        for name, expr in (("V", law.energy), ("V'", law.force), ("V''", law.stiffness)):
            f = mp_function(expr, (law.d, *subs))
            try:
                v = f(mpmath.mpf(0), *[mp_vector(r, 30) for r in subs.values()])
            except (ZeroDivisionError, ValueError, OverflowError, TypeError, NameError):
                v = mpmath.nan
            if isinstance(v, mpmath.mpc) and v.imag == 0:
                v = v.real
            if not _finite(v):
                raise SceneError(file, law.where, f"{sp.sstr(law.energy)}: {name}(0) = {mpmath.nstr(v, 6)} is not "
                                 "finite at the rest configuration d = 0; accepted: a potential finite and twice "
                                 "differentiable at d = 0, written in the extension from the rest length "
                                 "(e.g. r = r0 + d for a pair at distance r)")


def _simplifies_to_zero(expr: sp.Expr) -> bool:
    """Whether SymPy's ``simplify`` shows ``expr`` is 0; False (unproven) past :attr:`Caps.simplify_ops`
    operations, without trying (the loading path then finds x = 0 numerically)."""
    if expr == 0:
        return True
    return ops(expr) <= CAPS.simplify_ops and sp.simplify(expr) == 0


def check_law(file: str, law: SpringLaw, d_value, subs: dict, *, closed_form: sp.Expr | None = None,
              dps: int = 40) -> sp.Expr:
    """V, V', V'' finite at ``d_value`` and V'' > 0 there; returns V''(d_value) (closed form or Float).

    Parameters
    ----------
    d_value : sympy number or mpf
        The spring's extension at the equilibrium.
    subs : dict
        Parameter symbols (and ``i`` in a chain) to exact values.
    closed_form : sympy.Expr, optional
        V''(d_eq) as a closed form (x_eq = 0), returned after the checks.
    dps : int
        Working digits (at least 40; those ``d_value`` was settled at).
    """
    dps = max(40, dps)
    with mpmath.workdps(dps):
        dv = mp_vector(d_value, dps)
        if any(e.has(sp.DiracDelta, sp.Heaviside, sp.sign) for e in (law.force, law.stiffness)):
            raise _refuse_value(file, law, "V'' has a kink or a jump (Abs, sign)", dv,
                                "not twice differentiable there",
                                "a potential with two continuous derivatives at the equilibrium, e.g. d**2 instead of abs(d)")
        vals = []
        for name, expr in (("V", law.energy), ("V'", law.force), ("V''", law.stiffness)):
            f = mp_function(expr, (law.d, *subs))
            try:
                v = f(dv, *[mp_vector(r, dps) for r in subs.values()])
            except (ZeroDivisionError, ValueError, OverflowError, TypeError, NameError):
                v = mpmath.nan
            if isinstance(v, mpmath.mpc) and abs(v.imag) <= mpmath.mpf(10) ** (-dps + 5) * max(abs(v.real), 1):
                v = v.real
            if not _finite(v):
                raise _refuse_value(file, law, f"{name} is not finite", dv, f"{name}(d) = {mpmath.nstr(v, 6)}",
                                    "a potential finite and twice differentiable at the equilibrium "
                                    "(e.g. a Lennard-Jones pair written about its minimum, d > -r0)")
            vals.append(v)
        if not vals[2] > 0:
            raise _refuse_value(file, law, f"stiffness V''(d) = {mpmath.nstr(vals[2], 6)}", dv,
                                "not positive (this spring is not stable there)",
                                "a potential with V''(d) > 0 at the equilibrium")
        stiff = vals[2]
        if not MIN_MAGNITUDE <= stiff <= MAX_MAGNITUDE:  # the range a spring's k is held to
            raise _refuse_value(file, law, f"stiffness V''(d) = {mpmath.nstr(mpmath.mpf(stiff), 6)}", dv,
                                f"outside {MIN_MAGNITUDE:g} to {MAX_MAGNITUDE:g}",
                                f"a potential whose stiffness at the equilibrium lies in {MIN_MAGNITUDE:g} to "
                                f"{MAX_MAGNITUDE:g}, as a spring's k")
    if closed_form is not None:
        return closed_form
    return sp.Float(mpmath.nstr(stiff, 25), 17)

def _stable(pieces) -> str:
    """What the accepted equilibrium's checks (:func:`check_law` on every spring) establish."""
    return ("stable: every V''(d) > 0 there, so K is positive definite"
            + (" apart from the free pieces' rigid translations" if pieces else ""))


def solve(file: str, n: int, springs, loads, params: dict, values: dict, pieces, *,
          load_keys: str = "the loads") -> Equilibrium:
    """The static equilibrium of ``n`` coordinates, refusing what is not a stable one.

    Parameters
    ----------
    file : str
        The scene file (for messages).
    n : int
        Number of coordinates.
    springs : list of (int, int, SpringLaw)
        Ends (−1 = wall) and law of every spring.
    loads : list of sympy.Expr
        Constant force on each coordinate (gravity m g, forces free of t).
    params : dict
        Parameter name -> symbol; ``values`` parameter name -> float.
    pieces : list of (list of int, list of sympy.Expr)
        Free pieces (mass indices) with their masses.
    """
    subs = exact_values(params, values)
    for _, _, law in springs:
        if law.given:
            _at_rest_finite(file, law, subs)
    grad = [-(load) for load in loads]
    for a, b, law in springs:
        t0 = law.force.subs(law.d, 0)
        if a >= 0:
            grad[a] -= t0
        if b >= 0:
            grad[b] += t0
    for piece, _ in pieces:  # a free piece under a net constant load accelerates: no equilibrium
        net = sp.Add(*(loads[i] for i in piece))
        if not _simplifies_to_zero(net) and abs(float(net.subs(subs))) > 0:
            raise SceneError(file, load_keys, f"net constant force {sp.sstr(sp.simplify(net))} on the free piece of masses "
                             f"{', '.join(str(i) for i in piece)}: it accelerates, so there is no static equilibrium; "
                             "accepted: a spring from that piece to a wall, or no constant load on it")
    if all(_simplifies_to_zero(gi) for gi in grad):
        ext = tuple(sp.Integer(0) for _ in springs)
        stiff = tuple(check_law(file, law, sp.Integer(0), subs, closed_form=sp.factor(law.stiffness.subs(law.d, 0)))
                      for _, _, law in springs)
        return Equilibrium(tuple(sp.Integer(0) for _ in range(n)), ext, stiff, True,
                           "x = 0: every spring at rest balances (V'(0) = 0 or balanced tensions); "
                           + _stable(pieces))
    problem = PathProblem(n, springs, [ld.subs(subs) for ld in loads], subs,
                       [(piece, [float(m.subs(subs)) for m in masses]) for piece, masses in pieces])
    where = springs[0][2].where if springs else None
    shape = tree(n, [(a, b) for a, b, _ in springs])
    if shape is not None and all(float(S(0.0, *problem.fvals)) > 0 for _, _, _, _, S in problem.f64):
        return _on_tree(file, problem, shape, springs, loads, subs, pieces, where)
    x, how = _followed(file, problem, where)
    refined = refine(problem, x)
    if refined is None:
        raise SceneError(file, where, "no static equilibrium found: applying the constant loads and pre-stress "
                         f"gradually from rest reaches them only to float64's rounding (at |x| = "
                         f"{max(abs(float(v)) for v in x):.3g}), and no equilibrium refines there in "
                         f"extended precision (up to {MAX_DPS} digits): the springs hold the loads at most in the "
                         "limit; accepted: springs and loads with a stable equilibrium (V''(d) > 0 there)")
    xs, dps = refined
    how += f", refined in mpmath to {dps} digits; " + _stable(pieces)
    with mpmath.workdps(dps):
        ext = [(xs[b] if b >= 0 else 0) - (xs[a] if a >= 0 else 0) for a, b, _ in springs]
    return _result(file, springs, subs, xs, ext, how, dps)


def _followed(file: str, problem: "PathProblem", where) -> tuple:
    """``(x, how)``: the equilibrium followed from rest by :func:`path` (or found by :func:`descent` where x = 0
    is not stable), in float64, with the words saying how; refusals where neither reaches the loads."""
    found = path(problem)
    if isinstance(found, PathEnd) and problem.float64_limited:
        raise SceneError(file, where, f"no static equilibrium found in float64: applying the constant loads and "
                         f"pre-stress gradually from rest was followed up to {found.fraction} of them; beyond, float64 "
                         "cannot follow it (the path turns within float64's resolution of the loads, or an extension, "
                         "e.g. the distance to a potential's pole, falls below its resolution of x); accepted: springs "
                         "and loads whose equilibrium float64 can hold, or springs forming a tree with the ground "
                         "(solved spring by spring in extended precision)")
    if isinstance(found, PathEnd):
        reach = (f"a stable equilibrium exists only up to {found.fraction} of them" if found.reached > 0 else
                 f"no stable equilibrium exists even at {FIRST_STEP:.0e} of them")
        raise SceneError(file, where, f"no static equilibrium found: applying the constant loads and pre-stress "
                         f"gradually from rest, {reach} ({found.why}); accepted: springs and loads with a "
                         "stable equilibrium (V''(d) > 0 there)")
    if found is None:
        x = descent(problem)
        if x is None:
            raise SceneError(file, where, "no static equilibrium found: the rest configuration x = 0 is not stable "
                             "(K = the Hessian of U is not positive definite there) and a descent of U from it (Newton "
                             "with a Levenberg-Marquardt safeguard) found no minimum; accepted: springs and loads "
                             "with a stable equilibrium (V''(d) > 0 there)")
        how = "descent of U from x = 0 (x = 0 is not stable; Newton with a Levenberg-Marquardt safeguard, float64)"
    else:
        x, steps = found
        how = (f"the loads applied gradually from rest ({steps} load step{'s' if steps != 1 else ''}, Newton "
               + ("correctors with the residual in mpmath where K is ill-conditioned for float64)"
                  if problem.mp_corrections else "correctors in float64)"))
    return x, how


def _result(file: str, springs, subs: dict, xs: list, ext: list, how: str, dps: int) -> Equilibrium:
    """The :class:`Equilibrium` of mpmath positions and extensions, each spring checked (:func:`check_law`) at
    ``dps`` digits (those the extensions were settled at: V'' near a pole rests on the distance to it)."""
    stiff = tuple(check_law(file, law, dv, subs, dps=dps) for (_, _, law), dv in zip(springs, ext))
    return Equilibrium(tuple(sp.Float(mpmath.nstr(v, 25), 17) for v in xs),
                       tuple(sp.Float(mpmath.nstr(dv, 25), 17) for dv in ext), stiff, False, how)


def _on_tree(file: str, problem: PathProblem, shape, springs, loads, subs: dict, pieces, where) -> Equilibrium:
    """The equilibrium of springs that form a tree with the ground, spring by spring (:mod:`derive.equilibrium_tree`)."""
    masses = [sp.Integer(0)] * problem.n  # only the free pieces' are needed (their centres of mass)
    for piece, ms in pieces:
        for i, m in zip(piece, ms):
            masses[i] = as_sympy(m).subs(subs)
    exact_loads = [as_sympy(ld).subs(subs) for ld in loads]
    found = solve_tree(shape, problem.n, [(F, S) for (_, _, F), (_, _, S) in zip(problem.fmp, problem.smp)],
                       lambda dps: [mp_vector(r, dps) for r in problem.values],
                       lambda dps: [mp_vector(v, dps) for v in exact_loads],
                       lambda dps: [mp_vector(m, dps) for m in masses],
                       list(zip(problem.lo, problem.hi)))
    if isinstance(found, Ended) and found.spring == -2:
        raise SceneError(file, where, "no static equilibrium found: the springs' extensions do not settle in extended "
                         "precision (two precisions disagree up to 1600 digits); accepted: springs and loads with a "
                         "stable equilibrium (V''(d) > 0 there)")
    if isinstance(found, Ended):
        law = springs[found.spring][2]
        reach = (f"a stable equilibrium exists only up to {PathEnd(found.reached, '').fraction} of them"
                 if found.reached > 0 else f"no stable equilibrium exists even at {FIRST_STEP:.0e} of them")
        raise SceneError(file, law.where, f"no static equilibrium found: applying the constant loads and pre-stress "
                         f"gradually from rest, {reach} (the springs form a tree with the ground, so each one's "
                         f"tension is fixed by the loads beyond it: this spring's tension V'(d) stops growing "
                         f"towards its share at d = {mpmath.nstr(found.d, 6)}); accepted: springs and loads with a "
                         "stable equilibrium (V''(d) > 0 there)")
    xs, ext, steps, dps = found
    how = (f"statically determinate (the springs form a tree with the ground): each spring's tension from the "
           f"loads beyond it, its extension from V'(d) = that tension followed from rest ({steps} load "
           f"step{'s' if steps != 1 else ''} at most, mpmath, {dps} digits); " + _stable(pieces))
    return _result(file, springs, subs, xs, ext, how, dps)


__all__ = ["Equilibrium", "solve", "check_law", "SpringLaw"]
