"""Generated code and report lines for damping in ``[chain]`` scenes: a dashpot list, never N × N.

Every damping a chain declares is a list of dashpots (ends, constants): the ``[[dampers]]``
families and single dashpots, and Rayleigh damping C = αM + βK as α·m(i) from every mass to
the ground plus β·k beside every spring (walls and ring closure included). The generated
module gets ``damper_ends(n)``, ``damper_constants(**parameters, n)``, the O(n) stencil
``damping_acceleration(v, **parameters)`` and ``damping_matrix(**parameters, n)`` (dense,
n <= MAX_DENSE, for the exact solution and the frequency response). Emitted only when
declared.
"""

from __future__ import annotations

import sympy as sp

from .printing import sstr
from .chain_dampers import ALONG, GROUND, SINGLE
from .codegen import _p
from .damping_code import rayleigh_coefficients_lines


def chain_damping_code(model, sig: str, kw: str) -> list[str]:
    """Lines of the damping functions of a chain module (empty without damping)."""
    if not model.dampers and model.rayleigh is None:
        return []
    i = sp.Symbol("i")
    head = f"{sig}, " if sig else ""
    out: list[str] = []
    w = out.append
    out.extend(rayleigh_coefficients_lines(model, sig))
    ends, consts = [], []
    for kind, a, b, c, key in model.dampers:
        expr = _p(c.subs(model.i, i))
        if kind == ALONG:
            ends.append(f"numpy.stack([numpy.arange(n - 1), numpy.arange(1, n)], axis=1)  # {key}")
            consts.append(f"(lambda i: numpy.broadcast_to(numpy.asarray({expr}, dtype=float), (n - 1,)))"
                          "(numpy.arange(n - 1, dtype=float))")
        elif kind == GROUND:
            ends.append(f"numpy.stack([numpy.arange(n), numpy.full(n, -1)], axis=1)  # {key}")
            consts.append(f"(lambda i: numpy.broadcast_to(numpy.asarray({expr}, dtype=float), (n,)))"
                          "(numpy.arange(n, dtype=float))")
        else:
            assert kind == SINGLE
            ends.append(f"numpy.array([[{a}, {b}]])  # {key}")
            consts.append(f"numpy.array([{expr}], dtype=float)")
    if model.rayleigh is not None:
        alpha, beta = model.rayleigh
        if alpha != 0:
            ends.append("numpy.stack([numpy.arange(n), numpy.full(n, -1)], axis=1)  # damping: alpha*M")
            consts.append(f"rayleigh_coefficients({kw})[0] * masses({kw}, n=n)")
        if beta != 0:
            ends.append("spring_ends(n)  # damping: beta*K")
            consts.append(f"rayleigh_coefficients({kw})[1] * spring_constants({kw}, n=n)")
    w("")
    w("")
    w("def damper_ends(n=N):")
    w('    """Ends (mass indices, -1 = ground) of every dashpot in damper_constants() order, shape (D, 2)."""')
    w("    _parts = [")
    out.extend(f"        {e.split('  #')[0]},  #{e.split('  #')[1]}" for e in ends)
    w("    ]")
    w("    return numpy.concatenate(_parts).astype(numpy.intp)")
    w("")
    w("")
    w(f"def damper_constants({head}n=N):")
    w('    """Damping coefficient of each dashpot in damper_ends() order, shape (D,)."""')
    w("    return numpy.concatenate([")
    out.extend(f"        {c}," for c in consts)
    w("    ]).astype(float)")
    w("")
    w("")
    w(f"def damping_acceleration(_v, {sig}):")
    w('    """Acceleration -M^-1 C v of the dashpots, by the dashpot list (O(n), no n x n);')
    w('    v and result have shape (n, ...)."""')
    w("    _v = numpy.asarray(_v, dtype=float)")
    w("    n = _v.shape[0]")
    w("    _ends = damper_ends(n)")
    w("    _a, _b = _ends[:, 0], _ends[:, 1]")
    w("    _shape = (-1,) + (1,) * (_v.ndim - 1)")
    w(f"    _c = damper_constants({kw}, n=n).reshape(_shape)")
    w("    _ve = numpy.concatenate([_v, numpy.zeros((1,) + _v.shape[1:])])  # row -1 = ground")
    w("    _s = _c * (_ve[_a] - _ve[_b])")
    w("    _f = numpy.zeros_like(_v)")
    w("    _ia, _ib = numpy.flatnonzero(_a >= 0), numpy.flatnonzero(_b >= 0)")
    w("    numpy.add.at(_f, _a[_ia], -_s[_ia])")
    w("    numpy.add.at(_f, _b[_ib], _s[_ib])")
    w(f"    return _f / masses({kw}, n=n).reshape(_shape)")
    w("")
    w("")
    w(f"def damping_matrix({head}n=N):")
    w('    """Dense C of every dashpot (and Rayleigh damping), shape (n, n); only for n <= MAX_DENSE."""')
    w("    if n > _MAX_DENSE:")
    w("        raise _ValueError(f'damping_matrix: n = {n} > MAX_DENSE = {_MAX_DENSE}; use damper_ends()')")
    w("    _ends = damper_ends(n)")
    w(f"    _c = damper_constants({kw}, n=n)")
    w("    _C = numpy.zeros((n, n))")
    w("    for _ci, _si in ((0, 1.0), (1, -1.0)):")
    w("        for _cj, _sj in ((0, 1.0), (1, -1.0)):")
    w("            _ok = (_ends[:, _ci] >= 0) & (_ends[:, _cj] >= 0)")
    w("            numpy.add.at(_C, (_ends[_ok, _ci], _ends[_ok, _cj]), _si * _sj * _c[_ok])")
    w("    return _C")
    return out


def chain_damping_report_lines(model, modes) -> tuple[list[str], dict | None]:
    """Text lines and the JSON ``damping`` object of a damped chain (ζ family for uniform Rayleigh)."""
    if not model.dampers and model.rayleigh is None:
        return [], None
    lines = ["", "Damping (dashpots; force on i is -c*(v_i - v_j)):"]
    for kind, a, b, c, key in model.dampers:
        where = {ALONG: "beside every spring, between i and i+1", GROUND: "from every mass i to the ground",
                 SINGLE: f"between {'wall' if a < 0 else a} and {'wall' if b < 0 else b}"}[kind]
        lines.append(f"    {key}: c = {sstr(c)}  {where}")
    parts = (["dashpots"] if model.dampers else []) + (["rayleigh"] if model.rayleigh is not None else [])
    data: dict = {"model": " + ".join(parts), "zeta_family": None}
    if model.rayleigh is not None:
        alpha, beta = model.rayleigh
        lines.append(f"    [damping]: Rayleigh C = alpha*M + beta*K with alpha = {sstr(alpha)}, beta = {sstr(beta)}")
        if not model.dampers and modes.omega2 is not None:
            wj = sp.sqrt(modes.omega2)
            zeta = alpha / (2 * wj) + beta * wj / 2
            lines.append(f"    zeta_j = alpha/(2 omega_j) + beta*omega_j/2 = {sstr(zeta)}")
            data["zeta_family"] = sp.sstr(zeta)
    return lines, data


__all__ = ["chain_damping_code", "chain_damping_report_lines"]
