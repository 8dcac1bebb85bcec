"""The band section of a generated module: the unit cell's numbers and the closed-form branches.

Written into the module of every periodic scene (a ``[cell]`` scene, or a ``[chain]`` whose expressions repeat
in ``i``; uniform chains are periodic with one mass per cell), by :func:`band_section` placed in the
``SECTIONS`` of :mod:`derive.codegen` and :mod:`derive.chain_codegen`; nothing for other scenes:

* ``CELL_NAMES``, ``CELL_SPRINGS`` (``(a, b, reach)`` per spring, -1 the ground), ``CELL_DAMPERS``,
  ``cell_masses()``, ``cell_stiffness()``, ``cell_damping()``, ``cell_rayleigh()`` (alpha, beta; zeros
  without Rayleigh damping): the elements
  :mod:`springchain.numeric.bands` starts from (through :class:`~springchain.numeric.system.System`);
* ``band_omega2(q)``: ω²_j(q) of every branch, shape ``q.shape + (p,)`` — the closed forms where they exist
  (``BAND_CLOSED_FORM``), else the eigenvalues of D(q) from ``numpy.linalg.eigvalsh`` (plain float64: the
  accurate route is ``springchain.bands``);
* with closed forms, ``band_omega(q)`` and ``group_velocity(q)`` (dω/dq, cells per second; the right-hand
  limit at q = 0), vectorised, even and odd in q. Two branches from one quadratic (they share the square root
  of its discriminant) may touch where the discriminant vanishes — a folded monatomic chain at q = π — and their
  closed-form velocity divides by that root: within :data:`BAND_TOUCH` of each other (relative), or where the
  closed form is not finite, ``group_velocity`` takes Hellmann–Feynman on D(q) instead (``_band_touching``):
  the diagonal of dD/dq in D's eigenvectors, or at a degeneracy within rounding the eigenvalues of dD/dq on the
  pair's eigenspace, each branch its limit from inside (0, π) (at q = π the left-hand one).
"""

from __future__ import annotations

import sympy as sp

from ..codeprint import p as printed
from ..errors import SceneError
from ..module_text import function
from .dispersion import Dispersion, dispersion
from .model import band_cell
from ..expr import as_sympy

#: Two branches of one quadratic closer than this (relative) take the Hellmann–Feynman group velocity: the closed
#: form divides by the root of their discriminant, whose rounding error grows as 1/gap² (1e-12 relative at 1e-2).
BAND_TOUCH = 1e-2


def cell_dispersion(scene) -> Dispersion | None:
    """The scene's dispersion, or None when it has no unit cell (not periodic: the module has no band section)."""
    if scene.cell is None and scene.chain is None:
        return None
    try:
        return dispersion(band_cell(scene))
    except SceneError:
        return None


def band_section(c) -> list[str]:
    """The band constants and functions of the module of ``c.model.scene`` (nothing when not periodic)."""
    d = cell_dispersion(c.model.scene)
    if d is None:
        return []
    cell = d.cell
    sig = ", ".join(sorted(cell.params))
    ends = tuple((s.a, s.b, s.reach) for s in cell.springs)
    dampers = tuple((s.a, s.b, s.reach) for s in cell.dampers)
    lines = ["", "", f"#: The unit cell ({cell.source}): mass names, and springs as (a, b, reach) from mass a of",
             "#: cell c to mass b of cell c + reach (-1: the ground); dashpots likewise (Rayleigh damping apart).",
             f"CELL_NAMES = {tuple(cell.names)!r}",
             f"CELL_SPRINGS = {ends!r}",
             f"CELL_DAMPERS = {dampers!r}",
             "_CELL_SPRINGS = CELL_SPRINGS  # what bodies read (a parameter cannot shadow a private name)",
             f"BAND_CLOSED_FORM = {d.branches is not None!r}"]
    pairs = _pairs(d) if d.branches is not None else ()
    if pairs:
        lines += ["#: Pairs of branches closer than this (relative) take the Hellmann-Feynman group velocity.",
                  f"_BAND_TOUCH = {BAND_TOUCH!r}"]
    lines += function(f"cell_masses({sig})", "Masses of one cell, shape (p,).", [f"    return {_vector(cell.masses)}"])
    lines += function(f"cell_stiffness({sig})",
                      "Stiffness of each CELL_SPRINGS spring (V''(0) of a potential), shape (S,).",
                      [f"    return {_vector([s.k for s in cell.springs])}"])
    lines += function(f"cell_damping({sig})", "Constant of each CELL_DAMPERS dashpot, shape (D,).",
                      [f"    return {_vector([s.k for s in cell.dampers])}"])
    alpha, beta = cell.rayleigh if cell.rayleigh is not None else (0, 0)
    lines += function(f"cell_rayleigh({sig})", "Rayleigh coefficients (alpha, beta) of C = alpha M + beta K (zeros "
                      "without).", [(f"    return numpy.float64({printed(as_sympy(alpha))}), "
                                     f"numpy.float64({printed(as_sympy(beta))})")])
    lines += _omega2(d, sig)
    if d.branches is not None:
        lines += _stacked(d, sig, "band_omega", d.frequencies,
                          "Closed-form ω_j(q) of each branch [rad/s], shape q.shape + (p,) (even in q).", odd=False)
        lines += _stacked(d, sig, "group_velocity", d.velocities,
                          "Closed-form group velocity dω_j/dq [cells/s], shape q.shape + (p,) (odd in q; the\n"
                          "right-hand limit at q = 0)" + (
                              "; where two branches of one quadratic touch (the closed form divides by\n"
                              "the root of their discriminant), Hellmann-Feynman on D(q), each branch its limit from\n"
                              "inside (0, pi)." if pairs else "."), odd=True, touching=pairs)
        if pairs:
            lines += _TOUCHING
    return lines


def _pairs(d: Dispersion) -> tuple[tuple[int, int], ...]:
    """Branches (i, j) from one quadratic: their ω² share the square root of a q-dependent discriminant."""
    roots = [{a.base for a in as_sympy(b).atoms(sp.Pow) if a.exp == sp.Rational(1, 2) and a.base.has(d.q)}
             for b in d.branches]
    return tuple((i, j) for i in range(len(roots)) for j in range(i + 1, len(roots)) if roots[i] & roots[j])


def _vector(exprs) -> str:
    if not exprs:
        return "numpy.zeros(0)"
    return "numpy.array([" + ", ".join(f"numpy.float64({printed(e)})" for e in exprs) + "])"


def _omega2(d: Dispersion, sig: str) -> list[str]:
    if d.branches is not None:
        return _stacked(d, sig, "band_omega2", d.branches,
                        "Closed-form ω²_j(q) of each branch [rad²/s²], shape q.shape + (p,).", odd=False)
    p = d.p
    helper = ["", "", "def _band_eigvalsh(_q, _m, _k):",
              '    """eigvalsh of D(q) = M^-1/2 K(q) M^-1/2 assembled from CELL_SPRINGS, shape _q.shape + (p,)."""',
              f"    _K = numpy.zeros(_q.shape + ({p}, {p}), dtype=numpy.complex128)",
              "    for (_a, _b, _r), _w in zip(_CELL_SPRINGS, _k):",
              "        if _a < 0 or _b < 0:",
              "            _c = _b if _a < 0 else _a",
              "            _K[..., _c, _c] += _w",
              "        elif _a == _b:",
              "            _K[..., _a, _a] += 4 * _w * numpy.sin(_r * _q / 2) ** 2",
              "        else:",
              "            _e = numpy.exp(1j * _r * _q)",
              "            _K[..., _a, _a] += _w",
              "            _K[..., _b, _b] += _w",
              "            _K[..., _a, _b] -= _w * _e",
              "            _K[..., _b, _a] -= _w * numpy.conj(_e)",
              "    _s = 1 / numpy.sqrt(_m)",
              "    return numpy.linalg.eigvalsh(_K * _s[:, None] * _s[None, :])"]
    return function(f"band_omega2(q, {sig})",
                    "ω²_j(q) of each branch, ascending [rad²/s²], shape q.shape + (p,): eigvalsh of D(q) in float64\n"
                    "(no closed form; springchain.bands gives them to a few ulps at any contrast).",
                    [f"    return _band_eigvalsh(numpy.asarray(q, dtype=float), cell_masses({sig}), cell_stiffness({sig}))"]
                    ) + helper


#: The Hellmann–Feynman group velocity of a pair of branches that touch (module docstring), pasted into modules
#: whose closed forms have such pairs.
_TOUCHING = """

def _band_touching(_qf, _v, _w2, _m, _k, _pairs):
    \"\"\"_v (shape _qf.shape + (p,), closed-form dω/dq at _qf in [0, π]) where the branches of a pair are within
    _BAND_TOUCH of each other or _v is not finite: Hellmann-Feynman on D(q) = M^-1/2 K(q) M^-1/2.\"\"\"
    _v = numpy.array(_v, dtype=float)
    _p = _v.shape[-1]
    _fq, _fv, _fw = _qf.reshape(-1), _v.reshape(-1, _p), numpy.broadcast_to(_w2, _v.shape).reshape(-1, _p)
    for _i, _j in _pairs:
        _lo, _hi = numpy.minimum(_fw[:, _i], _fw[:, _j]), numpy.maximum(_fw[:, _i], _fw[:, _j])
        _near = (_lo > 0) & ((_hi - _lo <= _BAND_TOUCH * _hi) | ~numpy.isfinite(_fv[:, _i]) | ~numpy.isfinite(_fv[:, _j]))
        _at = numpy.flatnonzero(_near)
        if _at.size == 0:
            continue
        _d = _band_pair_slopes(_fq[_at], _m, _k, _lo[_at], _hi[_at])  # dω²/dq of (lower, upper)
        _low_i = _fw[_at, _i] <= _fw[_at, _j]
        _fv[_at, _i] = numpy.where(_low_i, _d[:, 0], _d[:, 1]) / (2 * numpy.sqrt(_fw[_at, _i]))
        _fv[_at, _j] = numpy.where(_low_i, _d[:, 1], _d[:, 0]) / (2 * numpy.sqrt(_fw[_at, _j]))
    return _v


def _band_pair_slopes(_q, _m, _k, _lo, _hi):
    \"\"\"dω²/dq (shape (Q, 2): lower, upper) of the two adjacent eigenvalues of D(q) nearest _lo, _hi: the diagonal of
    dD/dq in D's eigenvectors; where they are equal within rounding, the eigenvalues of dD/dq on their eigenspace,
    the larger to the lower branch (its limit from inside (0, π); the smaller at q = 0).\"\"\"
    _p = _m.shape[0]
    _K = numpy.zeros(_q.shape + (_p, _p), dtype=numpy.complex128)
    _dK = numpy.zeros_like(_K)
    for (_a, _b, _r), _w in zip(_CELL_SPRINGS, _k):
        if _a < 0 or _b < 0:
            _c = _b if _a < 0 else _a
            _K[..., _c, _c] += _w
        elif _a == _b:
            _K[..., _a, _a] += 4 * _w * numpy.sin(_r * _q / 2) ** 2
            _dK[..., _a, _a] += 2 * _r * _w * numpy.sin(_r * _q)
        else:
            _e = numpy.exp(1j * _r * _q)
            _K[..., _a, _a] += _w
            _K[..., _b, _b] += _w
            _K[..., _a, _b] -= _w * _e
            _K[..., _b, _a] -= _w * numpy.conj(_e)
            _dK[..., _a, _b] -= 1j * _r * _w * _e
            _dK[..., _b, _a] += 1j * _r * _w * numpy.conj(_e)
    _s = 1 / numpy.sqrt(_m)
    _lam, _U = numpy.linalg.eigh(_K * _s[:, None] * _s[None, :])
    _G = numpy.einsum("qki,qkl,qlj->qij", _U.conj(), _dK * _s[:, None] * _s[None, :], _U)
    _t = numpy.argmin(numpy.abs(_lam[:, :-1] - _lo[:, None]) + numpy.abs(_lam[:, 1:] - _hi[:, None]), axis=1)
    _rows = numpy.arange(_q.shape[0])
    _B = numpy.stack([numpy.stack([_G[_rows, _t, _t], _G[_rows, _t, _t + 1]], -1),
                      numpy.stack([_G[_rows, _t + 1, _t], _G[_rows, _t + 1, _t + 1]], -1)], -2)
    _diag = numpy.stack([_B[:, 0, 0].real, _B[:, 1, 1].real], -1)
    _eig = numpy.linalg.eigvalsh(_B)  # ascending
    _eig = numpy.where((_q > 0)[:, None], _eig[:, ::-1], _eig)
    _same = _lam[_rows, _t + 1] - _lam[_rows, _t] <= 1e-13 * numpy.abs(_lam).max(axis=1)
    return numpy.where(_same[:, None], _eig, _diag)\
""".split("\n")


def _stacked(d: Dispersion, sig: str, name: str, exprs, doc: str, *, odd: bool, touching=()) -> list[str]:
    """A function of q returning the closed forms stacked on a last axis, evaluated at |q| folded into [0, π]
    (``touching``: the pairs of branches whose values ``_band_touching`` replaces where they touch)."""
    q = d.q
    folded = sp.Symbol("_qf", nonnegative=True)
    exprs = [as_sympy(e).subs(q, folded) for e in exprs]
    subs, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("_x"), optimizations="basic")
    body = ["    _q = numpy.asarray(q, dtype=float)",
            "    _qa = numpy.arctan2(numpy.sin(_q), numpy.cos(_q))  # q folded into (-pi, pi]",
            "    _qf = numpy.abs(_qa)"]
    pad = "        " if touching else "    "
    if touching:
        body.append('    with numpy.errstate(divide="ignore", invalid="ignore"):  # where branches touch: replaced below')
    body += [f"{pad}{s} = {printed(e)}" for s, e in subs]
    parts = ", ".join(f"numpy.broadcast_to({printed(e)}, _q.shape)" for e in reduced)
    stack = f"numpy.stack([{parts}], axis=-1)"
    if touching:
        body += [f"{pad}_v = {stack}",
                 f"    _v = _band_touching(_qf, _v, band_omega2(_qf, {sig}), cell_masses({sig}), cell_stiffness({sig}), "
                 f"{tuple(touching)!r})"]
        stack = "_v"
    if odd:
        body.append(f"    return numpy.where((_qa < 0)[..., None], -1.0, 1.0) * {stack}")
    else:
        body.append(f"    return {stack}")
    return function(f"{name}(q, {sig})", doc, body)


__all__ = ["band_section", "cell_dispersion"]
