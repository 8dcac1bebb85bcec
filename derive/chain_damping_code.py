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

from .chain_dampers import ALONG, GROUND, SINGLE
from .codeprint import p
from .damping_code import rayleigh_coefficients_lines
from .module_text import function
from .printing import sstr


def chain_damping_code(model, sig: str, kw: str) -> list[str]:
    """Lines of the damping functions of a chain module (empty without damping)."""
    if not model.dampers and model.rayleigh is None:
        return []
    head = f"{sig}, " if sig else ""
    kwn = _with_n(kw)
    ends, consts = _dashpot_list(model, kw)
    out = rayleigh_coefficients_lines(model, sig)
    out += function("damper_ends(n=N)",
                    "Ends (mass indices, -1 = ground) of every dashpot in damper_constants() order, shape (D, 2).",
                    ["    _parts = [", *(f"        {e},  # {why}" for e, why in ends), "    ]",
                     "    return numpy.concatenate(_parts).astype(numpy.intp)"])
    out += function(f"damper_constants({head}n=N)", "Damping coefficient of each dashpot in damper_ends() order, shape (D,).",
                    ["    return numpy.concatenate([", *(f"        {c}," for c in consts), "    ]).astype(float)"])
    out += function(f"damping_acceleration(_v, {sig})",
                    "Acceleration -M^-1 C v of the dashpots, by the dashpot list (O(n), no n x n);\n"
                    "v and result have shape (n, ...).",
                    ["    _v = numpy.asarray(_v, dtype=float)",
                     "    n = _v.shape[0]",
                     "    _ends = damper_ends(n)",
                     "    _a, _b = _ends[:, 0], _ends[:, 1]",
                     "    _shape = (-1,) + (1,) * (_v.ndim - 1)",
                     f"    _c = damper_constants({kwn}).reshape(_shape)",
                     "    _ve = numpy.concatenate([_v, numpy.zeros((1,) + _v.shape[1:])])  # row -1 = ground",
                     "    _s = _c * (_ve[_a] - _ve[_b])",
                     "    _f = numpy.zeros_like(_v)",
                     "    _ia, _ib = numpy.flatnonzero(_a >= 0), numpy.flatnonzero(_b >= 0)",
                     "    numpy.add.at(_f, _a[_ia], -_s[_ia])",
                     "    numpy.add.at(_f, _b[_ib], _s[_ib])",
                     f"    return _f / masses({kwn}).reshape(_shape)"])
    return out + function(f"damping_matrix({head}n=N)",
                          "Dense C of every dashpot (and Rayleigh damping), shape (n, n); only for n <= MAX_DENSE.",
                          ["    if n > _MAX_DENSE:",
                           "        raise _ValueError(f'damping_matrix: n = {n} > MAX_DENSE = {_MAX_DENSE}; use damper_ends()')",
                           "    _ends = damper_ends(n)",
                           f"    _c = damper_constants({kwn})",
                           "    _C = numpy.zeros((n, n))",
                           "    for _ci, _si in ((0, 1.0), (1, -1.0)):",
                           "        for _cj, _sj in ((0, 1.0), (1, -1.0)):",
                           "            _ok = (_ends[:, _ci] >= 0) & (_ends[:, _cj] >= 0)",
                           "            numpy.add.at(_C, (_ends[_ok, _ci], _ends[_ok, _cj]), _si * _sj * _c[_ok])",
                           "    return _C"])


def _with_n(kw: str) -> str:
    """The parameters passed on, then ``n=n`` (only ``n=n`` for a scene without parameters)."""
    return f"{kw}, n=n" if kw else "n=n"


def _dashpot_list(model, kw: str) -> tuple[list[tuple[str, str]], list[str]]:
    """The dashpots as generated expressions: ``[(ends (D_e, 2), scene key)]`` and their constants (D_e,).

    ``[[dampers]]`` families and single dashpots in scene order, then Rayleigh damping as α·m(i)
    from every mass to the ground and β·k beside every spring (zero coefficients left out).
    """
    i = sp.Symbol("i")
    kwn = _with_n(kw)
    ends, consts = [], []
    for kind, a, b, c, key in model.dampers:
        expr = p(c.subs(model.i, i))
        if kind == ALONG:
            ends.append(("numpy.stack([numpy.arange(n - 1), numpy.arange(1, n)], axis=1)", key))
            consts.append(f"(lambda i: numpy.broadcast_to(numpy.asarray({expr}, dtype=float), (n - 1,)))"
                          "(numpy.arange(n - 1, dtype=float))")
        elif kind == GROUND:
            ends.append(("numpy.stack([numpy.arange(n), numpy.full(n, -1)], axis=1)", key))
            consts.append(f"(lambda i: numpy.broadcast_to(numpy.asarray({expr}, dtype=float), (n,)))"
                          "(numpy.arange(n, dtype=float))")
        else:
            assert kind == SINGLE
            ends.append((f"numpy.array([[{a}, {b}]])", key))
            consts.append(f"numpy.array([{expr}], dtype=float)")
    if model.rayleigh is not None:
        alpha, beta = model.rayleigh
        if alpha != 0:
            ends.append(("numpy.stack([numpy.arange(n), numpy.full(n, -1)], axis=1)", "damping: alpha*M"))
            consts.append(f"rayleigh_coefficients({kw})[0] * masses({kwn})")
        if beta != 0:
            ends.append(("spring_ends(n)", "damping: beta*K"))
            consts.append(f"rayleigh_coefficients({kw})[1] * spring_constants({kwn})")
    return ends, consts


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
