"""Generated code of the loads: tabulated forces and ground motion (lines of a module).

Shared by the ``[masses]`` renderer (:mod:`derive.codegen`) and the ``[chain]`` renderer
(:mod:`derive.chain`). Tables never reach the source: the functions take them as arguments
(``_tables``: one ``(times, values)`` pair per tabulated force, in scene order). Bodies use
no Python builtin and bind only private names, so any parameter name is safe. Each
function is emitted only for a scene that declares the load.
"""

from __future__ import annotations

import sympy as sp

from .codegen import _array, _p
from .forcing import decompose


def table_force_lines(ons: list[int], masses: list[sp.Expr], sig: str, chain: bool) -> list[str]:
    """``TABLE_FORCE_ON`` and ``table_acceleration(t, _tables, **parameters)``.

    Parameters
    ----------
    ons : list of int
        Mass index of each tabulated force, in scene order.
    masses : list of Expr
        The mass (an expression of the parameters) at each of those indices.
    """
    if not ons:
        return []
    size = "n" if chain else "_N"
    extra = ", n=N" if chain else ""
    out = ["", "#: Mass index of each tabulated force ([[forces]] with table), in scene order.",
           f"TABLE_FORCE_ON = {tuple(ons)!r}", "", "",
           f"def table_acceleration(t, _tables{', ' + sig if sig else ''}{extra}):",
           '    """Acceleration M^-1 F(t) from the tabulated forces; result shape (N, *t.shape).',
           "",
           "    _tables holds one (times, values) pair of 1-D arrays per TABLE_FORCE_ON entry:",
           '    linearly interpolated, zero outside the table\'s time range."""',
           "    t = numpy.asarray(t, dtype=float)",
           f"    _out = numpy.zeros(({size},) + t.shape)"]
    for j, (on, m) in enumerate(zip(ons, masses)):
        out.append(f"    _out[{on}] += numpy.interp(t, _tables[{j}][0], _tables[{j}][1], left=0.0, right=0.0)"
                   f" / ({_p(m)})")
    out.append("    return _out")
    return out


def ground_lines(acceleration: sp.Expr | None, motion, t: sp.Symbol, sig: str) -> list[str]:
    """``GROUND`` and, for an expression, ``ground_acceleration``, ``ground_harmonics`` and
    (when its double integral is known) ``ground_motion``; for a table, ``ground_table_acceleration``."""
    kw = (", " + sig) if sig else ""
    if acceleration is None:
        return ["", "#: Ground motion ([ground]) given as a table of t, a_g (data passed at run time).",
                'GROUND = "table"', "", "",
                "def ground_table_acceleration(t, _table):",
                '    """Ground acceleration a_g(t) from (times, values): linear, zero outside the table."""',
                "    return numpy.interp(numpy.asarray(t, dtype=float), _table[0], _table[1], left=0.0, right=0.0)"]
    out = ["", "#: Ground motion ([ground]) given as an expression of t: every mass feels -m_i a_g(t).",
           'GROUND = "expression"', "", "",
           f"def ground_acceleration(t{kw}):",
           '    """Ground acceleration a_g(t); t scalar or array, result shape t.shape."""',
           "    t = numpy.asarray(t, dtype=float)",
           f"    return numpy.broadcast_to(numpy.asarray({_p(acceleration)}, dtype=float), t.shape).copy()"]
    parts = decompose(acceleration, t)
    out += ["", f"GROUND_HARMONIC = {parts is not None!r}"]
    if parts is not None:
        const, harmonics = parts
        out += ["", "", f"def ground_harmonics({sig}):",
                '    """a_g(t) = const + sum_h cos_amp[h] cos(omega[h] t) + sin_amp[h] sin(omega[h] t);',
                '    returns omega, cos_amp, sin_amp of shape (H,) and const (a float)."""',
                f"    return ({_array([_p(h.omega) for h in harmonics])}, "
                f"{_array([_p(h.cos_amp) for h in harmonics])}, {_array([_p(h.sin_amp) for h in harmonics])}, "
                f"_float({_p(const)}))"]
    out += ["", f"GROUND_DISPLACEMENT = {motion is not None!r}"]
    if motion is not None:
        vg, xg = motion
        out += ["", "", f"def ground_motion(t{kw}):",
                '    """Ground velocity and displacement (v_g, x_g) at t, from v_g(0) = x_g(0) = 0; shapes t.shape."""',
                "    t = numpy.asarray(t, dtype=float)",
                f"    return (numpy.broadcast_to(numpy.asarray({_p(vg)}, dtype=float), t.shape).copy(),",
                f"            numpy.broadcast_to(numpy.asarray({_p(xg)}, dtype=float), t.shape).copy())"]
    return out


__all__ = ["table_force_lines", "ground_lines"]
