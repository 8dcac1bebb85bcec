"""Generated code of spring potentials (lines of a module): the laws, the forces, the energy.

Shared by the ``[masses]`` renderer (:mod:`derive.codegen`) and the ``[chain]`` renderer
(:mod:`derive.chain`); emitted only for scenes with ``potential = "EXPR"`` springs. Forces and
energies are printed in the cancellation-free forms of :mod:`derive.stable_laws` (``expm1``,
``log1p``, the private helpers ``_expm1mx``/``_log1pmx`` copied from :mod:`derive.law_helpers`);
the extension prints as the private name ``_d``, so no parameter can shadow it. Energies are
``V(d) − V(0)`` per spring (the energy at rest is 0; a constant changes no motion).

What the modules gain (the contract numeric reads):

``[masses]``: ``spring_tensions(x)`` (S, ...) — V'(d) of every spring (k d + k3 d³ for k springs),
``spring_stiffnesses(x)`` (S, ...) — V''(d), ``equilibrium()`` (N,) — x_eq, and ``EQUILIBRIUM_CLOSED_FORM``;
``acceleration`` and ``energy`` go through the tensions and the stable energies.

``[chain]``: ``spring_force(d, [i,] ...)``, ``spring_energy(d, [i,] ...)``, ``spring_stiffness(d, [i,] ...)``
(elementwise in d; ``i`` the spring index for an index-dependent law), ``equilibrium(n)`` (zeros: x_eq = 0
for every chain springchain accepts), ``POTENTIAL_LAW_INDEXED``. ``spring_force`` uses NumPy ufuncs and
arithmetic only, so numba compiles it into the fused chain kernels (:mod:`numeric.potential_kernels`).
"""

from __future__ import annotations

import sympy as sp

from .codeprint import array as _array
from .codeprint import p as _p
from .potential import D
from .stable_laws import HELPER_NAMES

#: The extension as generated code names it.
_D = sp.Symbol("_d", real=True)


def helpers_needed(exprs) -> set[str]:
    """The private helpers (``_expm1mx``, ``_log1pmx``) the printed expressions call."""
    names = set()
    for e in exprs:
        for f in e.atoms(sp.Function):
            if type(f).__name__ in HELPER_NAMES:
                names.add(HELPER_NAMES[type(f).__name__])
    return names


def helper_lines(exprs) -> list[str]:
    """The source of the helpers ``exprs`` call, ready to append to a module (or nothing)."""
    from .law_helpers import helper_source

    names = helpers_needed(exprs)
    return ["", "", *helper_source(names).rstrip("\n").split("\n")] if names else []


def _law(expr: sp.Expr, at: sp.Symbol = _D) -> sp.Expr:
    return expr.xreplace({D: at})


# -- [masses] scenes ------------------------------------------------------------------------------
def dense_law_exprs(model) -> tuple[list[sp.Expr], list[sp.Expr], list[sp.Expr]]:
    """Per spring: the tension, the stiffness and the energy V − V(0), in ``d`` (stable forms)."""
    tensions, stiffs, energies = [], [], []
    for (_, _, k, k3, _), law in zip(model.springs, model.laws):
        if law.given:
            tensions.append(law.stable_force)
            stiffs.append(law.stiffness)
            energies.append(law.stable_energy)
        else:
            tensions.append(k * D + (k3 * D**3 if k3 is not None else 0))
            stiffs.append(k + (3 * k3 * D**2 if k3 is not None else 0))
            energies.append(k * D**2 / 2 + (k3 * D**4 / 4 if k3 is not None else 0))
    return tensions, stiffs, energies


def _grouped(exprs: list[sp.Expr], out: str, d: str) -> list[str]:
    """``out[idx] = expr(d[idx])`` once per distinct expression (a chain of equal springs is one line)."""
    groups: dict = {}
    for j, e in enumerate(exprs):
        groups.setdefault(e, []).append(j)
    lines = []
    for e, idx in groups.items():
        if len(idx) == len(exprs):  # one law for every spring
            lines.append(f"    {out}[...] = {_p(_law(e, sp.Symbol(d)))}")
            continue
        sel = f"[{idx[0]}]" if len(idx) == 1 else f"[{list(idx)!r}]"
        lines.append(f"    {out}{sel} = {_p(_law(e, sp.Symbol(f'{d}{sel}')))}")
    return lines


def dense_law_lines(model, sig: str, kwcall: str) -> list[str]:
    """``spring_tensions``, ``spring_stiffnesses``, ``equilibrium`` and the helpers they need."""
    tensions, stiffs, energies = dense_law_exprs(model)
    eq = model.equilibrium
    ext = ["    _x = numpy.asarray(_x, dtype=float)",
           "    _ends = numpy.asarray(_SPRING_ENDS, dtype=numpy.intp).reshape(-1, 2)",
           "    _xe = numpy.concatenate([_x, numpy.zeros((1,) + _x.shape[1:])])  # row -1 = wall",
           "    _d = _xe[_ends[:, 1]] - _xe[_ends[:, 0]]  # extension x_b - x_a, shape (S, ...)",
           "    _out = numpy.empty(_d.shape)"]
    lines = ["", "", f"def spring_tensions(_x{', ' + sig if sig else ''}):",
             "    \"\"\"Tension V'(d) of each spring (positive when stretched) at x, shape (S, ...); d = x_b - x_a.",
             "", "    Potentials in cancellation-free form (expm1, log1p, ...): accurate to a few ulps near d = 0.",
             '    """', *ext, *_grouped(tensions, "_out", "_d"), "    return _out",
             "", "", f"def spring_stiffnesses(_x{', ' + sig if sig else ''}):",
             "    \"\"\"Stiffness V''(d) of each spring at x, shape (S, ...).\"\"\"",
             *ext, *_grouped(stiffs, "_out", "_d"), "    return _out",
             "", "", f"def _spring_energies(_x{', ' + sig if sig else ''}):",
             '    """Energy V(d) - V(0) of each spring at x, shape (S, ...) (0 at rest)."""',
             *ext, *_grouped(energies, "_out", "_d"), "    return _out"]
    lines += ["", "", f"EQUILIBRIUM_CLOSED_FORM = {eq.closed_form!r}"]
    if eq.closed_form:
        lines += ["", "", f"def equilibrium({sig}):",
                  '    """Static equilibrium x_eq, shape (N,): closed form (every spring at rest)."""',
                  f"    return {_array([_p(v) for v in eq.x])}"]
    else:
        lines += ["#: x_eq at DEFAULTS: Newton refined in mpmath at derive time, correctly rounded.",
                  f"_EQUILIBRIUM_AT_DEFAULTS = {tuple(float(v) for v in eq.x)!r}",
                  "EQUILIBRIUM_AT_DEFAULTS = _EQUILIBRIUM_AT_DEFAULTS", "", "",
                  f"def equilibrium({sig}):",
                  '    """Static equilibrium x_eq, shape (N,), solved at derive time for DEFAULTS only.',
                  "",
                  "    The equilibrium has no closed form; springchain solved it at the scene's parameter values.",
                  '    Other values are refused: change [parameters] and regenerate."""',
                  f"    _given = ({', '.join(f'{p}' for p in model.params)}{',' if len(model.params) == 1 else ''})",
                  f"    if _given != {tuple(float(model.scene.parameters[p]) for p in model.params)!r}:",
                  "        raise ValueError('equilibrium: solved for DEFAULTS only (no closed form); "
                  "regenerate the module with the new [parameters]')",
                  "    return numpy.array(_EQUILIBRIUM_AT_DEFAULTS, dtype=float)"]
    lines += helper_lines(energies + tensions)
    return lines


def dense_spring_constant_lines(model, sig: str, kwcall: str) -> list[str] | None:
    """The body of ``spring_constants()`` when K comes from a numeric equilibrium (else None):
    the stiffnesses there, at DEFAULTS only (``equilibrium`` refuses other values)."""
    eq = model.equilibrium
    if eq is None or eq.closed_form:
        return None
    return [f"    return spring_stiffnesses(equilibrium({kwcall}){', ' + kwcall if kwcall else ''})"]


def dense_acceleration_lines(model, kwcall: str) -> list[str]:
    """The body of ``acceleration(_x)``: the tensions summed on the masses, plus gravity and
    constant terms, divided by the masses (no N x N matrix)."""
    out = [f"    _t = spring_tensions(_x{', ' + kwcall if kwcall else ''})",
           "    _col = (-1,) + (1,) * (numpy.ndim(_x) - 1)",
           "    _ends = numpy.asarray(_SPRING_ENDS, dtype=numpy.intp).reshape(-1, 2)",
           "    _a, _b = _ends[:, 0], _ends[:, 1]",
           "    _f = numpy.zeros(numpy.shape(_x))",
           "    _ia, _ib = numpy.flatnonzero(_a >= 0), numpy.flatnonzero(_b >= 0)",
           "    numpy.add.at(_f, _a[_ia], _t[_ia])",
           "    numpy.add.at(_f, _b[_ib], -_t[_ib])"]
    if model.g is not None:
        out.append(f"    _f += gravity_forces({kwcall}).reshape(_col)")
    out.append(f"    return _f / masses({kwcall}).reshape(_col)")
    return out


def dense_energy_lines(model, kwcall: str) -> list[str]:
    """The body of ``energy(_x, _v)``: T + Σ (V_s(d) − V_s(0)) [− Σ m g x]."""
    out = ["    _x = numpy.asarray(_x, dtype=float)",
           "    _v = numpy.asarray(_v, dtype=float)",
           "    _col = (-1,) + (1,) * (_x.ndim - 1)",
           f"    _e = 0.5 * numpy.sum(masses({kwcall}).reshape(_col) * _v**2, axis=0)",
           f"    _e = _e + numpy.sum(_spring_energies(_x{', ' + kwcall if kwcall else ''}), axis=0)"]
    if model.g is not None:
        out.append(f"    _e = _e - numpy.sum(gravity_forces({kwcall}).reshape(_col) * _x, axis=0)")
    out.append("    return _e")
    return out


# -- [chain] scenes -------------------------------------------------------------------------------
def chain_law_lines(model, sig: str) -> list[str]:
    """``spring_force``, ``spring_energy``, ``spring_stiffness`` (elementwise in d) and ``equilibrium``."""
    law = model.law
    indexed = law.energy.has(model.i)
    args = "_d, i" if indexed else "_d"
    tail = (", " + sig) if sig else ""
    at = {model.i: sp.Symbol("i")}
    force = _law(law.stable_force).xreplace(at)
    energy = _law(law.stable_energy).xreplace(at)
    stiff = _law(law.stiffness).xreplace(at)
    lines = ["", "", f"POTENTIAL_LAW_INDEXED = {indexed!r}", "", "",
             f"def spring_force({args}{tail}):",
             "    \"\"\"Tension V'(d) of a spring at extension d (elementwise; positive when stretched)"
             + (", spring index i" if indexed else "") + ".",
             "",
             "    Cancellation-free form (expm1, log1p, ...), plain NumPy ufuncs and arithmetic: numba compiles it.",
             '    """',
             f"    return {_p(force)}",
             "", "", f"def spring_energy({args}{tail}):",
             '    """Energy V(d) - V(0) of a spring at extension d (elementwise; 0 at rest)."""',
             f"    return {_p(energy)}",
             "", "", f"def spring_stiffness({args}{tail}):",
             "    \"\"\"Stiffness V''(d) of a spring at extension d (elementwise).\"\"\"",
             f"    return {_p(stiff)}",
             "", "", f"def equilibrium({sig}{', ' if sig else ''}n=N):",
             '    """Static equilibrium x_eq, shape (n,): 0 (every chain springchain accepts is at rest there)."""',
             "    return numpy.zeros(n)"]
    lines += helper_lines([energy, force])
    scalar = scalar_helper_names([force])
    if scalar:  # the fused kernels call the tension on one float (numeric.compiled.potential_law)
        from .law_helpers import helper_source

        lines += ["", "", *helper_source(scalar).rstrip("\n").split("\n")]
    return lines


def scalar_helper_names(exprs) -> list[str]:
    """The scalar forms (``_expm1mx_s``, ...) of the helpers ``exprs`` call."""
    from .law_helpers import SCALAR

    return sorted(SCALAR[h] for h in helpers_needed(exprs))


def chain_tension_code(model, kw: str, d: str, index: str) -> str:
    """Code for the tension of springs at extension ``d`` with spring index ``index``."""
    indexed = model.law.energy.has(model.i)
    return f"spring_force({d}{', ' + index if indexed else ''}{', ' + kw if kw else ''})"


__all__ = ["dense_law_lines", "dense_acceleration_lines", "dense_energy_lines", "dense_spring_constant_lines",
           "chain_law_lines", "chain_tension_code", "helper_lines", "scalar_helper_names"]
