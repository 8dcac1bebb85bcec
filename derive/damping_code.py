"""Generated-module code for damping: the damping matrix C (dashpots, Rayleigh, modal) and M⁻¹C v.

Called by :func:`derive.codegen.render_module` only for scenes that declare damping, so a scene
without it has none of this code. Every damping model ends up in the one accessor
``damping_matrix(**parameters)`` (what the exact solution, the damping splitting of the step
methods and the frequency response read).
"""

from __future__ import annotations

from .codeprint import array, p
from .model import Model

_MODAL_HELPER = '''

def _modal_damping_matrix(m, k, zeta):
    """C = M Φ diag(2 ζ_j ω_j) Φᵀ M with the M-orthonormal modes Φ of _accurate_modes(), shape (N, N).

    Rigid-body modes (ω = 0) get no damping whatever their ratio; the result is symmetrised.
    """
    _w2, _Phi = _accurate_modes(m, k)
    _MPhi = numpy.asarray(m, dtype=float)[:, None] * _Phi
    _C = (_MPhi * (2.0 * numpy.asarray(zeta, dtype=float) * numpy.sqrt(_w2))) @ _MPhi.T
    return 0.5 * (_C + _C.T)
'''


def rayleigh_coefficients_lines(model, sig: str) -> list[str]:
    """Lines of ``rayleigh_coefficients()`` (empty without ``[damping] rayleigh``); dense and chain modules."""
    if model.rayleigh is None:
        return []
    if getattr(model, "rayleigh_targets", None) is not None:
        from .rayleigh_targets import coefficients_lines, values

        values(model)  # refuses targets that give α or β < 0 or a repeated ω, before anything is written
        return coefficients_lines(model, sig)
    return ["", "", f"def rayleigh_coefficients({sig}):",
            '    """(alpha, beta) of Rayleigh damping C = alpha*M + beta*K ([damping] rayleigh), shape (2,)."""',
            f"    return {array([p(e) for e in model.rayleigh])}"]


def damping_matrix_lines(model: Model, sig: str, kwcall: str, matrix=None) -> list[str]:
    """Lines of ``rayleigh_coefficients``/``modal_damping_ratios`` (when declared) and ``damping_matrix``.

    Parameters
    ----------
    model : Model
    sig, kwcall : str
        The parameters as a signature (``c, k, m``) and as keyword arguments (``c=c, k=k, m=m``).
    matrix : callable or None
        Prints a SymPy matrix as a NumPy literal (dense scenes); None assembles from element lists.
    """
    out: list[str] = []
    w = out.append
    out.extend(rayleigh_coefficients_lines(model, sig))
    if model.modal_zeta is not None:
        w("")
        w("")
        w(f"def modal_damping_ratios({sig}):")
        w('    """Damping ratio of each mode in ascending omega order ([damping] modal), shape (N,)."""')
        w(f"    return {array([p(e) for e in model.modal_zeta])}")
        out.extend(_MODAL_HELPER.rstrip("\n").split("\n")[1:])
    parts, what = [], []
    from .rayleigh_targets import binding_lines, private

    if model.C is not None:
        if matrix is not None:
            parts.append(matrix(private(model.C)))
        else:
            if model.dampers:
                parts.append(f"_assemble(_DAMPER_ENDS, damper_constants({kwcall}))")
            if model.rayleigh is not None:
                parts.append(f"rayleigh_coefficients({kwcall})[0] * numpy.diag(masses({kwcall})) "
                             f"+ rayleigh_coefficients({kwcall})[1] * stiffness_matrix({kwcall})")
        what += (["dashpots (d²R/dv²)"] if model.dampers else []) + (
            ["Rayleigh damping alpha*M + beta*K"] if model.rayleigh is not None else [])
    if model.modal_zeta is not None:
        parts.append(f"_modal_damping_matrix(masses({kwcall}), spring_constants({kwcall}), "
                     f"modal_damping_ratios({kwcall}))")
        what.append("modal damping M Φ diag(2 ζ_j ω_j) Φᵀ M, computed at call time from the "
                    "accurate modes (_accurate_modes)")
    w("")
    w("")
    w(f"def damping_matrix({sig}):")
    if what == ["dashpots (d²R/dv²)"]:
        w('    """C = d²R/dv² (Rayleigh dissipation), shape (N, N)."""')
    else:
        w(f'    """C of {" + ".join(what)}, shape (N, N)."""')
    if matrix is not None:
        out.extend(binding_lines(model, kwcall))
    body = "\n        + ".join(parts)
    w(f"    return ({body})" if len(parts) > 1 else f"    return {body}")
    return out


def matrix_damping_acceleration_lines(kw: str, kwcall: str) -> list[str]:
    """``damping_acceleration`` through the damping matrix (modal damping has no element form)."""
    return [
        "",
        "",
        f"def damping_acceleration(_v{kw}):",
        '    """Acceleration -M^-1 C v with C = damping_matrix(); v and result have shape (N, ...)."""',
        "    _v = numpy.asarray(_v, dtype=float)",
        f"    _f = numpy.tensordot(damping_matrix({kwcall}), _v, axes=1)",
        f"    return -_f / masses({kwcall}).reshape((-1,) + (1,) * (_v.ndim - 1))",
    ]


__all__ = ["damping_matrix_lines", "matrix_damping_acceleration_lines"]
