"""Modal participation in the ground direction: Γⱼ, effective modal mass Mⱼ*, mass-normalised shapes.

For support motion every mass feels −mᵢ a_g(t) (coordinates relative to the ground), so the
influence vector is r = 1 for every mass. With the mass-normalised shapes φⱼ (φⱼᵀMφⱼ = 1)

    Γⱼ = φⱼᵀ M r,      Mⱼ* = Γⱼ² = (φᵀMr)² / φᵀMφ  (any scale of φ),

and Σⱼ Mⱼ* = rᵀMr = the total mass (Φ Φᵀ M = I). Γⱼ is the participation factor *of the
mass-normalised shape* (``shape_mass_normalised``, whose sign follows the printed shape):
r = Σⱼ Γⱼ φⱼ.

Values come from the accurate route, never from float64 sums of printed shape components
(φᵀMr of a high mode is a sum of terms of both signs): the dynamical matrix assembled exactly
from the element list and diagonalised by ``mpmath.eigsy`` at 40, 80, … digits until every
value is settled to float64 (up to :data:`~derive.accurate.MAX_MPMATH_MODES` masses), beyond
that the spring-factor SVD of the generated modules with compensated sums. Closed forms (from
the closed-form shapes, modes of multiplicity one) are given where they agree with the values
to 1e-12 and stay readable. Inside a repeated ω the basis is rotated so that one shape carries
the whole participation of the eigenspace and the others none.

Structural zeros are exact (0.0, never rounding noise such as 1e-74): each piece of the spring
graph is diagonalised on its own, and an elastic mode of a free piece (no spring to a wall) has
Γ = 0 exactly — its momentum, 1ᵀM_pφ_p = 1ᵀK_pφ_p/ω² = 0, also inside a repeated ω whose basis
mixes pieces; a free piece's rigid mode is 1_p/√M_p; the shapes of a rotated repeated ω other than
the first have Γ = 0 exactly (see :func:`_values_mp`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import mpmath
import sympy as sp

from .caps import CAPS
from .printing import closed, latex

from .accurate import (MAX_DPS, MAX_MPMATH_MODES, NotAccurate, eig_dynamical, certified, clusters, dynamical_bound,
                       exact_values, omega2_value, value)
from .model import Model
from .model_cache import cached_on
from .modes import ModeSet
from .work import MAX_NUMBER_DIGITS, WorkCapExceeded, number_digits, ops, sympy_numbers
from .scene import WALL

#: Two successive precisions agreeing to this relative difference (of the total mass) settle a value.
_SETTLED = 1e-17
#: Largest size (SymPy operation count of Σ mᵢφᵢ plus Σ mᵢφᵢ², measured before simplifying) of a
#: mode whose Γ and M* are put in closed form: a work cap, never a clock (:mod:`.work`).
MAX_INPUT_OPS = CAPS.participation_input_ops
#: Longest closed form (SymPy operation count) printed.
MAX_OPS = CAPS.participation_ops


@dataclass(frozen=True)
class Participation:
    """Participation of every independent mode (ascending ω, the order of ``modes`` records).

    Attributes
    ----------
    omega2 : tuple of float
        ω² of each mode.
    gamma : tuple of float
        Γⱼ = φⱼᵀ M r for the mass-normalised shape φⱼ.
    effective_mass : tuple of float
        Mⱼ* = Γⱼ².
    total_mass : float
        rᵀ M r.
    shapes : tuple of tuple of float
        Mass-normalised shapes (φᵀMφ = 1), one per mode.
    gamma_expr, effective_mass_expr : tuple of (sympy.Expr or None)
        Closed forms in the scene's parameters (None where none is given).
    shape_expr : tuple of (tuple of sympy.Expr or None)
        Closed-form mass-normalised shapes.
    route : str
        How the values were computed.
    """

    omega2: tuple
    gamma: tuple
    effective_mass: tuple
    total_mass: float
    shapes: tuple
    gamma_expr: tuple
    effective_mass_expr: tuple
    shape_expr: tuple
    route: str

    @property
    def fraction(self) -> tuple:
        """Mⱼ* / total mass."""
        return tuple(m / self.total_mass for m in self.effective_mass)

    @property
    def cumulative(self) -> tuple:
        """Σ_{i ≤ j} Mᵢ* / total mass (compensated sums)."""
        return tuple(math.fsum(self.effective_mass[: j + 1]) / self.total_mass for j in range(len(self.gamma)))

    @property
    def effective_mass_sum(self) -> float:
        return math.fsum(self.effective_mass)


def applies(model) -> bool:
    """Participation is reported for scenes whose supports move: ``[ground]`` or any wall end."""
    sc = model.scene
    if sc.chain is not None:
        return False
    return sc.ground is not None or any(WALL in (s.a, s.b) for s in sc.springs) or any(
        WALL in (d.a, d.b) for d in sc.dampers)


def chain_applies(model) -> bool:
    """A ``[chain]`` scene whose supports move: a wall end or ``[ground]``."""
    sc = model.scene
    return sc.chain is not None and (sc.ground is not None or "wall" in (sc.chain.left, sc.chain.right))


def from_values(omega2, gamma, shapes, total_mass: float, route: str) -> Participation:
    """A :class:`Participation` of values only (no closed forms): a ``[chain]``'s, computed on the
    numeric side (``springchain._api``) from the accurate spectrum and handed to the report."""
    n = len(gamma)
    return Participation(tuple(float(w) for w in omega2), tuple(float(g) for g in gamma),
                         tuple(float(g) ** 2 for g in gamma), float(total_mass),
                         tuple(tuple(float(c) for c in s) for s in shapes), (None,) * n, (None,) * n, (None,) * n,
                         route)


def chain_note(model) -> list[str]:
    """For a ``[chain]`` scene whose supports move (a wall end or ``[ground]``) and whose participation is
    not reported (rings, chains whose modes are not all listed): one line saying where it is (``rsa``)."""
    if not chain_applies(model):
        return []
    return ["Modal participation: reported by modes for open chains of at most 40 masses; `springchain rsa SCENE --spectrum "
            "FILE` prints Gamma and the effective mass of every mode (spring-factor SVD; chains up to 2000 masses)"]


def signed_as_printed(p: Participation, records: list[dict]) -> Participation:
    """``p`` with each mass-normalised shape (and Γ, its closed forms) signed as the record's ``shape_value``
    (modes of multiplicity one; the README: "its sign that of the printed shape"). The numeric side signs a
    chain's shapes by their first component, while a free–wall chain's closed-form shape is positive at the
    wall end: without this, Γ and ``shape_mass_normalised`` could be the negatives of the printed shape's."""
    shapes, gamma = list(p.shapes), list(p.gamma)
    g_expr, s_expr = list(p.gamma_expr), list(p.shape_expr)
    for j, rec in enumerate(records[: len(gamma)]):
        printed = rec.get("shape_value")
        if rec.get("multiplicity", 1) != 1 or not printed or len(printed) != len(shapes[j]):
            continue
        if math.fsum(a * b for a, b in zip(printed, shapes[j])) < 0:
            shapes[j] = tuple(-c + 0.0 for c in shapes[j])
            gamma[j] = -gamma[j] + 0.0  # a structural 0 stays 0, never -0
            g_expr[j] = None if g_expr[j] is None else -g_expr[j]
            s_expr[j] = None if s_expr[j] is None else tuple(-c for c in s_expr[j])
    return replace(p, shapes=tuple(shapes), gamma=tuple(gamma), gamma_expr=tuple(g_expr),
                   shape_expr=tuple(s_expr))


def chain_section(model, p: Participation | None, records: list[dict]) -> tuple[list[str], list[str], dict]:
    """A chain report's participation: ``(text lines, notes, top-level JSON)``; the table (and the
    per-mode JSON fields, added to ``records`` in place) when ``p`` covers every record, else the note.
    Each shape and Γ is signed as the record's printed shape (:func:`signed_as_printed`)."""
    if p is not None and len(records) == len(p.gamma):
        p = signed_as_printed(p, records)
        return [""] + text_lines(p), [], json_fields(p, records)
    notes = chain_note(model)
    return [line for note in notes for line in ("", note)], notes, {}


# -- values -------------------------------------------------------------------------------------
def _pieces(model: Model) -> list[tuple[list[int], bool]]:
    """Every connected piece of the spring graph as ``(mass indices, free)``; ``free``: no spring to a wall."""
    free = {tuple(sorted(c)) for c in model.free_components}
    return [(list(c), tuple(sorted(c)) in free) for c in model.components]


def _piece_springs(model: Model, piece: list[int], subs) -> list:
    """The springs of ``piece`` with local mass indices (a wall stays -1), exact values."""
    local = {g: i for i, g in enumerate(piece)}
    out = []
    for a, b, k, _, _ in model.springs:
        if a in local or b in local:
            out.append((local.get(a, -1), local.get(b, -1), k.xreplace(subs)))
    return out


def _values_mp(model: Model, dps: int, n_rigid: int, bound):
    """(ω², Γ, shapes) at working precision ``dps`` (mpmath), repeated ω rotated (see module docstring);
    ``bound`` bounds ‖D‖ (:func:`accurate.dynamical_bound`), for telling a repeated ω from a close pair.

    Structural zeros (README: a quantity that is exactly 0 prints 0). K and M are block diagonal over the
    pieces of the spring graph, so each piece is diagonalised on its own (its modes are exactly 0 on every
    other mass) and Γⱼ = Σ over pieces of φⱼᵀ M_p 1_p:

    - a free piece (no spring to a wall) has K_p 1_p = 0, so for any ω² > 0 eigenvector restricted to it,
      ω² 1ᵀM_pφ_p = 1ᵀK_pφ_p = 0: its contribution to Γ is exactly 0 for every elastic mode. This holds for
      any basis of a repeated ω, one mixing pieces included, because (K − ω²M)φ = 0 holds piece by piece;
    - its rigid mode is exactly 1_p/√M_p (ω² = 0, not eigsy's), with Γ = √M_p (M_p the piece's mass);
    - a walled piece's Γ is Σ mᵢφᵢ over the piece at ``dps`` digits.

    Inside a repeated ω (the rigid modes of several free pieces, or equal ω on several pieces) the first
    vector is the projection of r onto the eigenspace, normalised: its Γ is the norm of that projection,
    √Σ Γ², and every other vector is M-orthogonal to it, so its Γ is exactly 0. With the rigid modes this
    gives the first rigid shape 1_F/√M_F (F: all free masses), Γ = √M_F, and Γ = 0 for the others.
    """
    subs = exact_values(model.params, model.scene.parameters)
    n = model.scene.n
    masses = [m.xreplace(subs) for m in model.masses]
    with mpmath.workdps(dps):
        m = [mpmath.mpf(x.p) / x.q if isinstance(x, sp.Rational) else mpmath.mpf(str(sp.N(x, dps + 10)))
             for x in masses]
        rigid, elastic = [], []  # (ω², shape on all masses, Γ)
        for piece, free in _pieces(model):
            w2p, shp = eig_dynamical([masses[i] for i in piece], _piece_springs(model, piece, subs), len(piece), dps)
            modes = list(zip(w2p, shp))
            if free:
                # the rigid mode by structure; eigsy's lowest value (its rounding of 0) is dropped
                mp_ = mpmath.fsum(m[i] for i in piece)
                phi = [mpmath.mpf(0)] * n
                for i in piece:
                    phi[i] = 1 / mpmath.sqrt(mp_)
                rigid.append((mpmath.mpf(0), phi, mpmath.sqrt(mp_)))
                modes = modes[1:]
            for w, s in modes:
                phi = [mpmath.mpf(0)] * n
                for i, c in zip(piece, s):
                    phi[i] = c
                g = mpmath.mpf(0) if free else mpmath.fsum(m[i] * phi[i] for i in piece)
                elastic.append((w, phi, g))
        elastic.sort(key=lambda t: t[0])
        w2 = [t[0] for t in rigid + elastic]
        phis = [t[1] for t in rigid + elastic]
        gamma = [t[2] for t in rigid + elastic]
        for cl in clusters(w2, n_rigid, bound, dps):
            if len(cl) < 2:
                continue
            # rotate: first vector along the projection of r onto the eigenspace, the rest M-orthogonal to it
            g = [gamma[j] for j in cl]
            norm = mpmath.sqrt(mpmath.fsum(x * x for x in g))
            if norm == 0:
                continue
            first = [mpmath.fsum(g[a] * phis[j][i] for a, j in enumerate(cl)) / norm for i in range(n)]
            basis = [first]
            for j in cl:
                v = list(phis[j])
                for b in basis:
                    c = mpmath.fsum(m[i] * b[i] * v[i] for i in range(n))
                    v = [v[i] - c * b[i] for i in range(n)]
                nv = mpmath.sqrt(mpmath.fsum(m[i] * v[i] ** 2 for i in range(n)))
                if nv > mpmath.mpf(10) ** (-(dps // 3)) and len(basis) < len(cl):
                    basis.append([x / nv for x in v])
            for a, j in enumerate(cl):
                phis[j] = basis[a]
                gamma[j] = norm if a == 0 else mpmath.mpf(0)
        return w2, gamma, phis, m


def _accurate_values(model: Model):
    """(ω², Γ, shapes, total mass) as floats, settled to float64, plus the route's name."""
    n_rigid = len(model.free_components)
    n = model.scene.n
    if n > MAX_MPMATH_MODES:
        return _spring_factor_values(model) + ("spring-factor SVD (float64, compensated sums)",)
    subs = exact_values(model.params, model.scene.parameters)
    bound = dynamical_bound([x.xreplace(subs) for x in model.masses],
                            [(a, b, k.xreplace(subs)) for a, b, k, _, _ in model.springs])
    prev = None
    dps = 40
    while dps <= MAX_DPS:
        w2, gamma, phis, m = _values_mp(model, dps, n_rigid, bound)
        with mpmath.workdps(dps):
            total = mpmath.fsum(m)
            cur = ([float(x) for x in w2], [float(g) for g in gamma], [[float(c) for c in p] for p in phis],
                   float(total))
            # Γ settled relative to √(total mass); every elastic ω² certified relative to itself (an ω² of
            # 1e-90 next to ω² = 1 is lost in the absolute rounding of eigsy below ~100 digits)
            # (|Γ|: eigsy's sign of a vector may flip between precisions; the sign is fixed afterwards)
            if prev is not None and all(abs(abs(a) - abs(b)) <= _SETTLED * math.sqrt(cur[3]) + 1e-300
                                        for a, b in zip(prev[1], cur[1])) and certified(w2, n_rigid, bound, dps):
                return cur + (f"mpmath eigsy at {dps} digits (settled to float64)",)
        prev = cur
        dps *= 2
    raise NotAccurate(f"participation factors did not settle to float64 accuracy within {MAX_DPS} digits")


def _spring_factor_values(model: Model):
    """(ω², Γ, shapes, total mass) from the spring-factor SVD, piece by piece (structural zeros as in
    :func:`_values_mp`: Γ = 0 exactly for the elastic modes of a free piece, √M_p for its rigid mode;
    each mode exactly 0 off its piece). Rigid modes first (one per free piece), then ascending ω²."""
    import numpy as np

    from .spring_factor import accurate_modes_function

    subs = exact_values(model.params, model.scene.parameters)
    masses = [float(m.xreplace(subs)) for m in model.masses]
    n = len(masses)
    rigid, elastic = [], []
    for piece, free in _pieces(model):
        springs = _piece_springs(model, piece, subs)
        run = accurate_modes_function(len(piece), tuple((a, b) for a, b, _ in springs),
                                      (tuple(range(len(piece))),) if free else ())
        w2p, shp = run([masses[i] for i in piece], [float(k) for _, _, k in springs])
        shp = np.asarray(shp, dtype=float)
        for j in range(shp.shape[1]):
            phi = [0.0] * n
            for i, c in zip(piece, shp[:, j]):
                phi[i] = float(c)
            if free and j == 0:  # RIGID_PIECES first: ω² exactly 0
                rigid.append((0.0, phi, math.sqrt(math.fsum(masses[i] for i in piece))))
            else:
                g = 0.0 if free else math.fsum(masses[i] * phi[i] for i in piece)
                elastic.append((float(w2p[j]), phi, g))
    elastic.sort(key=lambda t: t[0])
    modes = _rotated_rigid(rigid, masses) + elastic
    return [t[0] for t in modes], [t[2] for t in modes], [t[1] for t in modes], math.fsum(masses)


def _rotated_rigid(rigid: list, masses: list) -> list:
    """The rigid modes of several free pieces rotated as a repeated ω (module docstring): the first
    1_F/√M_F with Γ = √M_F, then a weighted Helmert basis (amplitude √(M_k/(S_{k-1}S_k)) on pieces 1…k−1
    and −S_{k-1} times that over M_k on piece k, S_k the mass of pieces 1…k): M-orthonormal, no
    subtraction, and each M-orthogonal to 1_F, so Γ = 0 exactly."""
    if len(rigid) < 2:
        return rigid
    n = len(masses)
    piece = [[i for i in range(n) if phi[i] != 0.0] for _, phi, _ in rigid]
    mass = [math.fsum(masses[i] for i in p) for p in piece]
    total = math.fsum(mass)
    first = [0.0] * n
    for p in piece:
        for i in p:
            first[i] = 1.0 / math.sqrt(total)
    out = [(0.0, first, math.sqrt(total))]
    for k in range(1, len(piece)):
        below, upto = math.fsum(mass[:k]), math.fsum(mass[: k + 1])
        c = math.sqrt(mass[k] / below / upto)
        phi = [0.0] * n
        for p in piece[:k]:
            for i in p:
                phi[i] = c
        for i in piece[k]:
            phi[i] = -c * (below / mass[k])
        out.append((0.0, phi, 0.0))
    return out


# -- closed forms -------------------------------------------------------------------------------
def _closed_forms(model: Model, modes: ModeSet, records: list) -> tuple[list, list, list]:
    """Γ, M* and mass-normalised shapes in closed form per record (None where not available)."""
    n_rec = len(records)
    none = ([None] * n_rec, [None] * n_rec, [None] * n_rec)
    if modes is None or not modes.closed_form:
        return none
    g_out, m_out, s_out = list(none[0]), list(none[1]), list(none[2])
    for j, (mode, shape) in enumerate(records):
        if mode.multiplicity != 1 or not mode.exact:
            continue
        a = sp.Add(*(mi * c for mi, c in zip(model.masses, shape)))
        b = sp.Add(*(mi * c**2 for mi, c in zip(model.masses, shape)))
        # past a work cap (operations, or exact numbers longer than MAX_NUMBER_DIGITS: cancelling them
        # ran for minutes): values only for this mode
        if ops(a) + ops(b) > MAX_INPUT_OPS or number_digits([a, b]) > MAX_NUMBER_DIGITS:
            continue
        try:
            with sympy_numbers():  # SymPy's own failures on large exact numbers: values only
                a, b = sp.radsimp(sp.cancel(sp.expand(a))), sp.radsimp(sp.cancel(sp.expand(b)))
                root = sp.sqrt(b)
                gamma = sp.factor(sp.cancel(a / root)) if not a.has(sp.cos, sp.sin) else a / root
                meff = sp.factor(sp.cancel(a**2 / b)) if not a.has(sp.cos, sp.sin) else sp.cancel(a**2 / b)
        except WorkCapExceeded:
            continue
        if ops(gamma) <= MAX_OPS and ops(meff) <= MAX_OPS:
            g_out[j], m_out[j] = gamma, meff
            s_out[j] = tuple(c / root for c in shape)
    return g_out, m_out, s_out


def participation(model: Model, modes: ModeSet | None) -> Participation:
    """Γⱼ, Mⱼ*, fractions and mass-normalised shapes of every independent mode (see module docstring).

    Parameters
    ----------
    model : Model
    modes : ModeSet or None
        The closed-form modes (for closed forms and the sign of each shape); None for values only.

    Cached on the model (one computation per report).
    """
    return cached_on(model, "_participation", modes is not None, lambda: _participation(model, modes))


def _participation(model: Model, modes: ModeSet | None) -> Participation:
    w2, gamma, phis, total, route = _accurate_values(model)
    n = len(gamma)
    subs = exact_values(model.params, model.scene.parameters)
    records = []
    if modes is not None:
        records = [(mode, shape) for mode in modes.modes for shape in mode.shapes]
        records.sort(key=lambda r: omega2_value(r[0], subs))
    # the sign of each mass-normalised shape follows the printed shape (modes of multiplicity one)
    if len(records) == n:
        mass_values = [value(x, subs) for x in model.masses]  # once, not once per mode
        for j, (mode, shape) in enumerate(records):
            if mode.multiplicity != 1:
                continue
            printed = [value(c, subs) if not isinstance(c, float) else c for c in shape]
            dot = math.fsum(float(mi) * p * q for mi, p, q in zip(mass_values, printed, phis[j]))
            if dot < 0:
                phis[j] = [-c + 0.0 for c in phis[j]]
                gamma[j] = -gamma[j] + 0.0  # + 0.0: a structural 0 stays 0, never -0
    g_expr, m_expr, s_expr = _closed_forms(model, modes, records) if len(records) == n else ([None] * n,) * 3
    # keep a closed form only where it agrees with the accurate value
    for j in range(n):
        if g_expr[j] is None:
            continue
        try:
            gv, mv = value(g_expr[j], subs), value(m_expr[j], subs)
        except NotAccurate:
            gv = mv = float("nan")
        scale = math.sqrt(total)
        if not (abs(gv - gamma[j]) <= 1e-12 * scale and abs(mv - gamma[j] ** 2) <= 1e-12 * total):
            g_expr[j] = m_expr[j] = s_expr[j] = None
    return Participation(tuple(w2), tuple(gamma), tuple(g * g for g in gamma), total,
                         tuple(tuple(p) for p in phis), tuple(g_expr), tuple(m_expr), tuple(s_expr), route)


# -- rendering ----------------------------------------------------------------------------------
def json_fields(p: Participation, records: list[dict]) -> dict:
    """Add ``participation_factor``, ``effective_mass``, ``effective_mass_fraction``,
    ``effective_mass_cumulative``, ``shape_mass_normalised`` (and the ``*_expr`` closed forms) to each
    mode record, in place; return the top-level ``participation`` field."""
    frac, cum = p.fraction, p.cumulative
    for j, rec in enumerate(records[: len(p.gamma)]):
        rec["participation_factor"] = p.gamma[j]
        rec["effective_mass"] = p.effective_mass[j]
        rec["effective_mass_fraction"] = frac[j]
        rec["effective_mass_cumulative"] = cum[j]
        rec["shape_mass_normalised"] = list(p.shapes[j])
        rec["participation_factor_expr"] = None if p.gamma_expr[j] is None else sp.sstr(p.gamma_expr[j])
        rec["effective_mass_expr"] = None if p.effective_mass_expr[j] is None else sp.sstr(p.effective_mass_expr[j])
    return {"participation": {"influence": "ground: r = 1 for every mass", "total_mass": p.total_mass,
                              "effective_mass_sum": p.effective_mass_sum, "route": p.route}}


def text_lines(p: Participation) -> list[str]:
    """The text report's participation section."""
    out = ["Modal participation (ground direction, r = 1 for every mass; shapes mass-normalised, "
           "phi^T M phi = 1; Gamma = phi^T M r, M* = Gamma^2):",
           f"    {'mode':>4}  {'omega':>14}  {'Gamma':>14}  {'M*':>14}  {'M*/M':>10}  {'cumulative':>10}"]
    frac, cum = p.fraction, p.cumulative
    for j, g in enumerate(p.gamma):
        w = math.sqrt(max(p.omega2[j], 0.0))
        out.append(f"    {j + 1:>4}  {w:>14.10g}  {g:>14.10g}  {p.effective_mass[j]:>14.10g}  "
                   f"{frac[j]:>10.6f}  {cum[j]:>10.6f}")
    out.append(f"    total mass = {p.total_mass:.10g}; sum of M* = {p.effective_mass_sum:.17g} "
               f"(relative difference {abs(p.effective_mass_sum - p.total_mass) / p.total_mass:.1e}); {p.route}")
    long = []
    for j, g in enumerate(p.gamma_expr):
        if g is not None:
            gt, mt = sp.sstr(g), sp.sstr(p.effective_mass_expr[j])
            if closed(gt) == gt and closed(mt) == mt:
                out.append(f"    mode {j + 1}: Gamma = {gt}   M* = {mt}")
            else:
                long.append((j + 1, max(len(gt), len(mt)), closed(gt if len(gt) > len(mt) else mt)))
    if long:
        out.append(f"    modes {', '.join(str(j) for j, _, _ in long)}: Gamma and M* "
                   + max(long, key=lambda r: r[1])[2].replace("closed form omitted:", "closed forms omitted: up to").replace("carries it", "carries them"))
    for j, s in enumerate(p.shapes):
        out.append(f"    mode {j + 1}: mass-normalised shape ({', '.join(f'{c:.10g}' for c in s)})")
    return out


def latex_lines(p: Participation) -> list[str]:
    """``\\Gamma_j``, ``M^*_j`` lines for the LaTeX report (closed forms where known)."""
    out = []
    for j, g in enumerate(p.gamma):
        ge, me = p.gamma_expr[j], p.effective_mass_expr[j]
        gt = (latex(ge) + rf" \approx {g:.10g}") if ge is not None else f"{g:.10g}"
        mt = (latex(me) + rf" \approx {p.effective_mass[j]:.10g}") if me is not None else \
            f"{p.effective_mass[j]:.10g}"
        out.append(rf"\\ \Gamma_{{{j + 1}}} &= {gt}, & M^*_{{{j + 1}}} &= {mt}")
    return out


__all__ = ["Participation", "participation", "applies", "chain_applies", "from_values", "chain_note", "chain_section", "json_fields", "text_lines", "latex_lines"]
