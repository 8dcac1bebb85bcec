"""Generated code of the loads: tabulated forces and ground motion (lines of a module).

Section writers shared by the ``[masses]`` renderer (:mod:`derive.codegen`) and the ``[chain]``
renderer (:mod:`derive.chain_codegen`). Tables never reach the source: the functions take them as arguments
(``_tables``: one ``(times, values)`` pair per tabulated force, in scene order). Bodies use
no Python builtin and bind only private names, so any parameter name is safe. Each
function is emitted only for a scene that declares the load.
"""

from __future__ import annotations

import sympy as sp

from .codeprint import array, p
from .forcing import decompose, harmonics_by_mass
from .module_text import function
from .printing import sstr


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
    body = ["    t = numpy.asarray(t, dtype=float)", f"    _out = numpy.zeros(({size},) + t.shape)"]
    body += [f"    _out[{on}] += numpy.interp(t, _tables[{j}][0], _tables[{j}][1], left=0.0, right=0.0) / ({p(m)})"
             for j, (on, m) in enumerate(zip(ons, masses))]
    return ["", "#: Mass index of each tabulated force ([[forces]] with table), in scene order.",
            f"TABLE_FORCE_ON = {tuple(ons)!r}",
            *function(f"table_acceleration(t, _tables{', ' + sig if sig else ''}{extra})",
                      "Acceleration M^-1 F(t) from the tabulated forces; result shape (N, *t.shape).\n\n"
                      "_tables holds one (times, values) pair of 1-D arrays per TABLE_FORCE_ON entry:\n"
                      "linearly interpolated, zero outside the table's time range.",
                      body + ["    return _out"])]


def _of_t(expr: sp.Expr) -> str:
    """An expression of t and the parameters as an array of t's shape."""
    return f"numpy.broadcast_to(numpy.asarray({p(expr)}, dtype=float), t.shape).copy()"


def ground_lines(acceleration: sp.Expr | None, motion, t: sp.Symbol, sig: str) -> list[str]:
    """``GROUND`` and, for an expression, ``ground_acceleration``, ``ground_harmonics`` and
    (when its double integral is known) ``ground_motion``; for a table, ``ground_table_acceleration``."""
    kw = (", " + sig) if sig else ""
    if acceleration is None:
        return ["", "#: Ground motion ([ground]) given as a table of t, a_g (data passed at run time).",
                'GROUND = "table"', *function(
                    "ground_table_acceleration(t, _table)",
                    "Ground acceleration a_g(t) from (times, values): linear, zero outside the table.",
                    ["    return numpy.interp(numpy.asarray(t, dtype=float), _table[0], _table[1], left=0.0, right=0.0)"])]
    out = ["", "#: Ground motion ([ground]) given as an expression of t: every mass feels -m_i a_g(t).",
           'GROUND = "expression"']
    out += function(f"ground_acceleration(t{kw})", "Ground acceleration a_g(t); t scalar or array, result shape t.shape.",
                    ["    t = numpy.asarray(t, dtype=float)", f"    return {_of_t(acceleration)}"])
    parts = decompose(acceleration, t)
    out += ["", f"GROUND_HARMONIC = {parts is not None!r}"]
    if parts is not None:
        const, harmonics = parts
        out += function(f"ground_harmonics({sig})",
                        "a_g(t) = const + sum_h cos_amp[h] cos(omega[h] t) + sin_amp[h] sin(omega[h] t);\n"
                        "returns omega, cos_amp, sin_amp of shape (H,) and const (a float).",
                        [f"    return ({array([p(h.omega) for h in harmonics])}, "
                         f"{array([p(h.cos_amp) for h in harmonics])}, {array([p(h.sin_amp) for h in harmonics])}, "
                         f"_float({p(const)}))"])
    out += ["", f"GROUND_DISPLACEMENT = {motion is not None!r}"]
    if motion is not None:
        vg, xg = motion
        out += function(f"ground_motion(t{kw})",
                        "Ground velocity and displacement (v_g, x_g) at t, from v_g(0) = x_g(0) = 0; shapes t.shape.",
                        ["    t = numpy.asarray(t, dtype=float)",
                         f"    return ({_of_t(vg)},", f"            {_of_t(xg)})"])
    return out


def chain_load_lines(model) -> list[str]:
    """The loads' terms, each traced to its scene entry (forces name masses by index)."""
    lines = [f"    + {sstr(f)} on mass {on}  [{key}]" for on, f, key in model.forces]
    lines += [f"    + f_table{key[7:-1]}(t) on mass {on}  [{key}] (table, linear between rows, zero outside)"
              for on, key in model.table_forces]
    if model.g is not None:
        lines.append(f"    + {sstr(model.mass * model.g)} on every mass i  [gravity]")
    if model.scene.ground is not None:
        lines.append(f"    - {sstr(model.mass)}*a_g(t) on every mass i  [ground]"
                     + (f", a_g(t) = {sstr(model.ground)}" if model.ground is not None else " (table)")
                     + "; coordinates relative to the ground")
    return (["Loads:"] + lines) if lines else []


def chain_load_code(model, sig: str, kw: str) -> list[str]:
    """Gravity, external forces (expressions), tabulated forces and ground motion of a chain
    module: nothing for a chain without loads. Forces act on single masses, so no loop over masses."""
    sep = ", " if sig else ""
    out: list[str] = []
    if model.g is not None:
        out += function(f"gravity_forces({sig}{sep}n=N)",
                        "Constant gravity force m_i*g on each mass (+x direction), shape (n,).",
                        [f"    return masses({kw}{sep}n=n) * ({p(model.g)})"])
    if model.forces:
        out += _chain_forces(model, sig, sep)
    out += table_force_lines([on for on, _ in model.table_forces],
                             [model.mass_at(on) for on, _ in model.table_forces], sig, chain=True)
    if model.scene.ground is not None:
        out += ground_lines(model.ground, model.ground_motion, model.t, sig)
    return out


def _chain_forces(model, sig: str, sep: str) -> list[str]:
    """external_acceleration(), FORCING_HARMONIC and (when harmonic) forcing_harmonics() of a chain."""
    body = ["    t = numpy.asarray(t, dtype=float)", "    _out = numpy.zeros((n,) + t.shape)"]
    body += [f"    _out[{on}] += {p(f / model.mass_at(on))}" for on, f, _ in model.forces]
    out = function(f"external_acceleration(t{sep}{sig}, n=N)",
                   "Acceleration M^-1 F(t) from the external forces; result shape (n, *t.shape).",
                   body + ["    return _out"])
    harmonic = harmonics_by_mass([(on, f) for on, f, _ in model.forces], model.t)
    out += ["", f"FORCING_HARMONIC = {harmonic is not None!r}"]
    if harmonic is None:
        return out
    const, freqs, rows = harmonic
    body = [f"    _omega = {array([p(w) for w in freqs])}",
            "    _cos = numpy.zeros((_omega.shape[0], n))",
            "    _sin = numpy.zeros((_omega.shape[0], n))",
            "    _const = numpy.zeros(n)"]
    body += [f"    _const[{on}] += {p(c)}" for on, c in const.items()]
    for h, (cos_amp, sin_amp) in enumerate(rows):
        body += [f"    _cos[{h}, {on}] += {p(c)}" for on, c in cos_amp.items()]
        body += [f"    _sin[{h}, {on}] += {p(c)}" for on, c in sin_amp.items()]
    return out + function(f"forcing_harmonics({sig}{sep}n=N)",
                          "F(t) = const + sum_h cos_amp[h] cos(omega[h] t) + sin_amp[h] sin(omega[h] t);\n"
                          "omega (H,), cos_amp and sin_amp (H, n), const (n,).",
                          body + ["    return _omega, _cos, _sin, _const"])


__all__ = ["table_force_lines", "ground_lines", "chain_load_lines", "chain_load_code"]
