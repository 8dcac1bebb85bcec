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
  limit at q = 0), vectorised, even and odd in q.
"""

from __future__ import annotations

import sympy as sp

from ..codeprint import p as printed
from ..errors import SceneError
from ..module_text import function
from .dispersion import Dispersion, dispersion
from .model import band_cell


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
    lines += function(f"cell_masses({sig})", "Masses of one cell, shape (p,).", [f"    return {_vector(cell.masses)}"])
    lines += function(f"cell_stiffness({sig})",
                      "Stiffness of each CELL_SPRINGS spring (V''(0) of a potential), shape (S,).",
                      [f"    return {_vector([s.k for s in cell.springs])}"])
    lines += function(f"cell_damping({sig})", "Constant of each CELL_DAMPERS dashpot, shape (D,).",
                      [f"    return {_vector([s.k for s in cell.dampers])}"])
    alpha, beta = cell.rayleigh if cell.rayleigh is not None else (0, 0)
    lines += function(f"cell_rayleigh({sig})", "Rayleigh coefficients (alpha, beta) of C = alpha M + beta K (zeros "
                      "without).", [(f"    return numpy.float64({printed(sp.sympify(alpha))}), "
                                     f"numpy.float64({printed(sp.sympify(beta))})")])
    lines += _omega2(d, sig)
    if d.branches is not None:
        lines += _stacked(d, sig, "band_omega", d.frequencies,
                          "Closed-form ω_j(q) of each branch [rad/s], shape q.shape + (p,) (even in q).", odd=False)
        lines += _stacked(d, sig, "group_velocity", d.velocities,
                          "Closed-form group velocity dω_j/dq [cells/s], shape q.shape + (p,) (odd in q; the\n"
                          "right-hand limit at q = 0).", odd=True)
    return lines


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


def _stacked(d: Dispersion, sig: str, name: str, exprs, doc: str, *, odd: bool) -> list[str]:
    """A function of q returning the closed forms stacked on a last axis, evaluated at |q| folded into [0, π]."""
    q = d.q
    folded = sp.Symbol("_qf", nonnegative=True)
    exprs = [sp.sympify(e).subs(q, folded) for e in exprs]
    subs, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("_x"), optimizations="basic")
    body = ["    _q = numpy.asarray(q, dtype=float)",
            "    _qa = numpy.arctan2(numpy.sin(_q), numpy.cos(_q))  # q folded into (-pi, pi]",
            "    _qf = numpy.abs(_qa)"]
    body += [f"    {s} = {printed(e)}" for s, e in subs]
    parts = ", ".join(f"numpy.broadcast_to({printed(e)}, _q.shape)" for e in reduced)
    stack = f"numpy.stack([{parts}], axis=-1)"
    if odd:
        body.append(f"    return numpy.where((_qa < 0)[..., None], -1.0, 1.0) * {stack}")
    else:
        body.append(f"    return {stack}")
    return function(f"{name}(q, {sig})", doc, body)


__all__ = ["band_section", "cell_dispersion"]
