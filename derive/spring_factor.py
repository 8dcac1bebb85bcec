"""The spring-factor route to ω² and mode shapes, as the generated modules run it.

:func:`_accurate_modes` below is real code *and* the text that :mod:`derive.codegen` copies
into every generated module that has no stable closed form (``inspect.getsource``; names then
made private). Its globals ``N``, ``SPRING_ENDS`` and ``RIGID_PIECES`` are the generated
module's constants; :func:`accurate_modes_function` binds them for the derive side's own
large-scene fallback (:func:`derive.accurate.spring_factor_modes`), so both sides run the very
same code — without ``exec``: a function object is made from this code object and a globals
dict of our own.
"""

from __future__ import annotations

import inspect
import types

#: Placeholders for the generated module's globals, bound per call by :func:`accurate_modes_function`
#: (NumPy and SciPy are imported only then: ``springchain modes`` starts without SciPy).
numpy = scipy = None
N = 0
SPRING_ENDS: tuple = ()
RIGID_PIECES: tuple = ()

def _accurate_modes(m, k):
    """ω² (ascending, rigid modes exactly 0 first) and M-orthonormal physical shapes (columns).

    The spring-factor route, accurate to float64 in the relative sense at any
    positive parameter values: a subtraction-free LDLᵀ of K = Bᵀ diag(k) B
    (eliminating in the diagonally dominant parts, pivoting on D = M^-1/2 K M^-1/2),
    then the one-sided Jacobi SVD (LAPACK dgejsv) of F = M^-1/2 L Λ^1/2 (F Fᵀ = D).
    Rigid-body modes come from the structure (RIGID_PIECES), never from a threshold.
    """
    _m = numpy.asarray(m, dtype=float)
    _k = numpy.asarray(k, dtype=float)
    _ends = numpy.asarray(SPRING_ENDS, dtype=numpy.intp).reshape(-1, 2)
    _a, _b = _ends[:, 0], _ends[:, 1]
    _W = numpy.zeros((N, N))
    _in = (_a >= 0) & (_b >= 0) & (_a != _b)
    numpy.add.at(_W, (_a[_in], _b[_in]), _k[_in])
    numpy.add.at(_W, (_b[_in], _a[_in]), _k[_in])
    _wall = numpy.zeros(N)
    _one = (_a >= 0) != (_b >= 0)
    numpy.add.at(_wall, numpy.where(_a[_one] >= 0, _a[_one], _b[_one]), _k[_one])
    _d = _wall + _W.sum(axis=1)
    _alive = numpy.ones(N, dtype=bool)
    _rm = numpy.sqrt(_m)
    _F = numpy.zeros((N, N), order="F")
    _c = 0
    for _ in range(N):
        _score = numpy.where(_alive, _d / _m, -1.0)
        _p = int(numpy.argmax(_score))
        if not _score[_p] > 0.0:
            break
        _dp = _d[_p]
        _alive[_p] = False
        _nb = numpy.flatnonzero(_W[_p])
        _w = _W[_p, _nb]
        _F[_p, _c] = numpy.sqrt(_dp) / _rm[_p]
        _F[_nb, _c] = -(_w / numpy.sqrt(_dp)) / _rm[_nb]
        _c += 1
        _W[_p, :] = 0.0
        _W[:, _p] = 0.0
        if _nb.size:
            _W[numpy.ix_(_nb, _nb)] += numpy.outer(_w, _w / _dp)
            _W[_nb, _nb] = 0.0
            _wall[_nb] += _w * (_wall[_p] / _dp)
            _d[_nb] = _wall[_nb] + _W[_nb].sum(axis=1)
    _R = numpy.zeros((N, len(RIGID_PIECES)))
    for _j, _idx in enumerate(RIGID_PIECES):
        _R[list(_idx), _j] = _rm[list(_idx)] / numpy.linalg.norm(_rm[list(_idx)])
    if _c != N - len(RIGID_PIECES):
        raise FloatingPointError("parameter values outside the float range of the accurate mode route")
    if _c:
        _sva, _u, _, _work, _, _info = scipy.linalg.lapack.dgejsv(numpy.asfortranarray(_F[:, :_c]),
                                                                 joba=2, jobu=0, jobv=3, jobr=0, jobt=0, jobp=0)
        if _info != 0:
            raise numpy.linalg.LinAlgError(f"dgejsv failed to converge (info = {_info})")
        _s = _sva * (_work[0] / _work[1])
        _o = numpy.argsort(_s, kind="stable")
        _s, _V = _s[_o], _u[:, :_c][:, _o]
        if _R.shape[1]:
            _V = _V - _R @ (_R.T @ _V)
        _V = _V - 0.5 * (_V @ (_V.T @ _V - numpy.eye(_c)))
    else:
        _s, _V = numpy.zeros(0), numpy.zeros((N, 0))
    _w2 = numpy.concatenate([numpy.zeros(_R.shape[1]), _s * _s])
    return _w2, numpy.hstack([_R, _V]) / _rm[:, None]


def helper_source() -> str:
    """The text of :func:`_accurate_modes` for a generated module (public names, privatized later)."""
    return inspect.getsource(_accurate_modes)


def accurate_modes_function(n: int, spring_ends: tuple, rigid_pieces: tuple):
    """``_accurate_modes(m, k)`` of a module with these N, SPRING_ENDS and RIGID_PIECES, as a callable."""
    import numpy
    import scipy.linalg.lapack

    env = {"numpy": numpy, "scipy": scipy, "N": n, "SPRING_ENDS": spring_ends, "RIGID_PIECES": rigid_pieces,
           "__builtins__": __builtins__}
    return types.FunctionType(_accurate_modes.__code__, env, "_accurate_modes")
