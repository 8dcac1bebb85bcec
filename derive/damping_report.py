"""Damped modes for the report: ζ per mode (closed form where one exists) or complex modes.

Everything is computed in the **modal coordinates** of the undamped problem, at the scene's
values and at high precision (mpmath, successive precisions until float64 is settled):

* Φ, ω² — M-orthonormal modes from the exactly assembled dynamical matrix
  (:func:`accurate._eig_dynamical`; rigid-body modes are the lowest ``RIGID_MODES``, set to 0
  by structure);
* G = ΦᵀCΦ for the dashpots and Rayleigh damping, plus diag(2ζⱼωⱼ) for modal damping
  (which *is* diagonal in these coordinates by definition).

**Proportional** damping (G diagonal, up to rotations inside a repeated ω) keeps real modes:
ζⱼ = Gⱼⱼ/(2ωⱼ), ω_d = √(ω² − Gⱼⱼ²/4). Closed forms: Rayleigh ζⱼ = α/(2ωⱼ) + βωⱼ/2, modal
the given ratio, dashpots φⱼᵀCφⱼ/(2ωⱼ φⱼᵀMφⱼ) from the closed-form shapes; their sum when
several are declared. Otherwise the **complex modes** are the eigenvalues
λ = −σ ± iω_d of the state-space matrix [[0, I], [−diag(ω²), −G]] (ω_n = |λ|, ζ = σ/ω_n).
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath
import sympy as sp

from .printing import latex, sstr
from .accurate import NotAccurate, _eig_dynamical, _mp, exact_values, value
from .model import Model
from .modes import BudgetExceeded, ModeSet, time_budget

#: Two successive precisions agreeing to this relative difference settle a float64 value.
_SETTLED = 4e-16
#: Seconds allowed to simplify closed-form damping ratios of dashpots.
ZETA_BUDGET = 5.0


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


def _modal_damping(model: Model, dps: int):
    """(ω² list, G matrix) in modal coordinates at working precision ``dps``."""
    subs = _values(model)
    n = model.scene.n
    masses = [m.subs(subs) for m in model.masses]
    springs = [(a, b, k.subs(subs)) for a, b, k, _, _ in model.springs]
    w2, shapes = _eig_dynamical(masses, springs, n, dps)
    with mpmath.workdps(dps):
        n_rigid = len(model.free_components)
        w2 = [mpmath.mpf(0) if j < n_rigid else w for j, w in enumerate(w2)]
        Phi = mpmath.matrix(n, n)
        for j, s in enumerate(shapes):
            for i in range(n):
                Phi[i, j] = s[i]
        G = mpmath.zeros(n, n)
        if model.C is not None:
            C = mpmath.matrix([[_mp(model.C[i, j].subs(subs), dps) for j in range(n)] for i in range(n)])
            G = Phi.T * C * Phi
        if model.modal_zeta is not None:
            for j in range(n):
                G[j, j] += 2 * _mp(model.modal_zeta[j].subs(subs), dps) * mpmath.sqrt(w2[j])
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


def _rows_at(model: Model, dps: int) -> tuple[list[tuple], bool]:
    w2, G = _modal_damping(model, dps)
    n = len(w2)
    with mpmath.workdps(dps):
        if _is_proportional(w2, G, dps):
            diag = _cluster_diagonal(w2, G, dps)
            rows = []
            for j in range(n):
                w = mpmath.sqrt(w2[j])
                if w2[j] == 0:
                    rows.append((0.0, None, 0.0, None))
                    continue
                g = diag[j]
                wd2 = w2[j] - g * g / 4
                rows.append((float(w), float(g / (2 * w)), float(mpmath.sqrt(wd2)) if wd2 > 0 else 0.0, None))
            return rows, True
        A = mpmath.zeros(2 * n, 2 * n)
        for i in range(n):
            A[i, n + i] = 1
            A[n + i, i] = -w2[i]
            for j in range(n):
                A[n + i, n + j] = -G[i, j]
        lam = mpmath.eig(A, left=False, right=False)
        scale = max(abs(l) for l in lam) or mpmath.mpf(1)
        tiny = mpmath.mpf(10) ** (-(dps // 2)) * scale
        cplx = sorted((l for l in lam if mpmath.im(l) > tiny), key=abs)
        real = sorted((mpmath.re(l) for l in lam if abs(mpmath.im(l)) <= tiny), key=lambda r: -r)
        rows = [(float(abs(l)), float(-mpmath.re(l) / abs(l)), float(mpmath.im(l)),
                 complex(float(mpmath.re(l)), float(mpmath.im(l)))) for l in cplx]
        zeros = [r for r in real if abs(r) <= tiny]
        rest = [r for r in real if abs(r) > tiny]
        rows += [(0.0, None, 0.0, None)] * (len(zeros) // 2 or (1 if zeros else 0))
        while len(rest) >= 2:  # overdamped: real pairs, slowest with fastest
            r1, r2 = rest.pop(0), rest.pop(-1)
            wn = mpmath.sqrt(r1 * r2)
            rows.append((float(wn), float(-(r1 + r2) / (2 * wn)), 0.0, None))
        rows.sort(key=lambda r: r[0])
        return rows[:n], False


def _settled(a: list[tuple], b: list[tuple]) -> bool:
    def close(x, y):
        if x is None or y is None:
            return x is y
        if isinstance(x, complex):
            return abs(x - y) <= _SETTLED * max(abs(x), abs(y))
        return abs(x - y) <= _SETTLED * max(abs(x), abs(y))
    return len(a) == len(b) and all(close(x, y) for ra, rb in zip(a, b) for x, y in zip(ra, rb))


def _closed_forms(model: Model, modes: ModeSet) -> list[sp.Expr | None]:
    """Closed-form ζⱼ per independent mode in ascending order (None where none is available)."""
    out: list[sp.Expr | None] = []
    j = 0
    subs = _values(model)
    records = [(mode, shape) for mode in modes.modes for shape in mode.shapes]
    records.sort(key=lambda r: max(value(r[0].omega2, subs), 0.0) if r[0].exact else float(r[0].omega2))
    C_d = None
    if model.dampers:
        C_d = model._assemble([(a, b, c) for a, b, c, _ in model.dampers], model.v)
    try:
        with time_budget(ZETA_BUDGET):
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
                        raise BudgetExceeded
                    phi = sp.Matrix(shape)
                    ratio = (phi.T * C_d * phi)[0, 0] / (phi.T * model.M * phi)[0, 0]
                    ratio = sp.factor(sp.radsimp(sp.cancel(sp.expand(ratio))))
                    zeta += ratio / (2 * w)
                out.append(zeta)
                j += 1
    except BudgetExceeded:
        return [None] * len(records)
    return out


def damped_modes(model: Model, modes: ModeSet | None) -> DampedModes:
    """The damped modes of a scene with dashpots or a ``[damping]`` model (see module docstring).

    ``modes`` (the closed-form modes) gives the closed forms of ζ; None for the numbers only.
    Cached on the model (one computation per report).
    """
    cache = model.__dict__.setdefault("_damped_modes", {})
    key = modes is not None
    if key not in cache:
        cache[key] = _damped_modes(model, modes)
    return cache[key]


def _damped_modes(model: Model, modes: ModeSet | None) -> DampedModes:
    parts = (["dashpots"] if model.dampers else []) + (
        [model.scene.damping.kind] if model.scene.damping is not None else [])
    prev = None
    dps = 40
    while dps <= 640:
        rows, prop = _rows_at(model, dps)
        if prev is not None and prev[1] == prop and _settled(prev[0], rows):
            break
        prev = (rows, prop)
        dps *= 2
    else:
        raise NotAccurate("damped modes did not settle to float64 accuracy within 640 digits")
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
            line += f"   zeta = {sstr(r.zeta_expr)}"
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
