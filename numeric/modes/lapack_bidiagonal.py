"""LAPACK's bidiagonal SVD ``dbdsqr``, which ``scipy.linalg.lapack`` does not wrap.

SciPy exports every LAPACK routine it links as a C function pointer for Cython
(``scipy.linalg.cython_lapack.__pyx_capi__``, the route numba's SciPy support takes too); this
module calls ``dbdsqr`` through that pointer with :mod:`ctypes`, so it runs the very LAPACK SciPy
uses, whatever the build. ``dbdsqr`` computes the singular values of a bidiagonal matrix to high
*relative* accuracy (implicit zero-shift QR where needed; Demmel & Kahan, "Accurate singular
values of bidiagonal matrices", SIAM J. Sci. Stat. Comput. 11, 1990) and singular vectors whose
error is bounded by ε over the *relative* gap — what the modes of a graded chain need, where any
method working on ``BᵀB`` has only absolute accuracy.
"""

from __future__ import annotations

import ctypes
from functools import lru_cache

import numpy as np

_P = ctypes.c_void_p


@lru_cache(maxsize=None)
def _dbdsqr():
    """The ``dbdsqr`` function pointer of SciPy's LAPACK, as a ctypes function."""
    import scipy.linalg.cython_lapack as cython_lapack

    capsule = cython_lapack.__pyx_capi__["dbdsqr"]
    api = ctypes.pythonapi
    api.PyCapsule_GetName.restype = ctypes.c_char_p
    api.PyCapsule_GetName.argtypes = [ctypes.py_object]
    api.PyCapsule_GetPointer.restype = ctypes.c_void_p
    api.PyCapsule_GetPointer.argtypes = [ctypes.py_object, ctypes.c_char_p]
    address = api.PyCapsule_GetPointer(capsule, api.PyCapsule_GetName(capsule))
    # void dbdsqr(char *uplo, int *n, int *ncvt, int *nru, int *ncc, double *d, double *e, double *vt,
    #             int *ldvt, double *u, int *ldu, double *c, int *ldc, double *work, int *info)
    return ctypes.CFUNCTYPE(None, ctypes.c_char_p, *([_P] * 14))(address)


def bidiagonal_svd(d: np.ndarray, e: np.ndarray, upper: bool, vectors: bool = True, *,
                   qr: bool = False) -> tuple[np.ndarray, np.ndarray | None]:
    """Singular values and right singular vectors of a square bidiagonal matrix B.

    Parameters
    ----------
    d : ndarray, shape (s,)
        Diagonal.
    e : ndarray, shape (s - 1,)
        Off-diagonal: ``B[i, i+1]`` if ``upper`` else ``B[i+1, i]``.
    upper : bool
    vectors : bool
        Also return the right singular vectors (columns of V, ``B = U Σ Vᵀ``).
    qr : bool
        Values only, but by dbdsqr's implicit (zero-shift) QR instead of dqds, which dbdsqr takes
        when no vectors are asked for: one dummy row of U is rotated along (O(s²) still). dqds lost
        4e-4 on the small singular values of a bidiagonal whose entries span 1e160 (a 14-mass chain
        of 1 / 1.3e28 kg and 3.2e149 / 3.2e-144 N/m); the QR iteration kept them to a few ulps.

    Returns
    -------
    sigma : ndarray, shape (s,)
        Singular values, descending, to high relative accuracy.
    V : ndarray, shape (s, s) or None
        Right singular vectors as columns, in ``sigma`` order (the eigenvectors of ``BᵀB``).

    Notes
    -----
    V is computed as the *left* singular vectors of Bᵀ: LAPACK then rotates contiguous columns
    (about 3× faster than rotating the rows of Vᵀ). Cost O(s²) for values, O(s³) with vectors.
    """
    s = int(d.shape[0])
    if s == 0:
        return np.zeros(0), (np.zeros((0, 0)) if vectors else None)
    dd = np.array(d, dtype=float, order="F")
    ee = np.zeros(max(s, 1))
    ee[: s - 1] = e
    nru = s if vectors else (1 if qr else 0)
    u = np.asfortranarray(np.eye(s)) if vectors else np.zeros((1, s if qr else 1), order="F")
    dummy = np.zeros((1, 1), order="F")
    work = np.zeros(max(4 * s, 1))
    info = ctypes.c_int(0)

    def ref(v: int):
        return ctypes.byref(ctypes.c_int(v))

    def ptr(a: np.ndarray):
        return a.ctypes.data_as(_P)

    uplo = b"L" if upper else b"U"  # Bᵀ: an upper B has a lower transpose
    _dbdsqr()(uplo, ref(s), ref(0), ref(nru), ref(0), ptr(dd), ptr(ee), ptr(dummy), ref(1), ptr(u),
              ref(max(1, u.shape[0])), ptr(dummy), ref(1), ptr(work), ctypes.byref(info))
    if info.value != 0:
        raise np.linalg.LinAlgError(f"dbdsqr: {info.value} superdiagonals did not converge"
                                    if info.value > 0 else f"dbdsqr: bad argument {-info.value}")
    return dd, (u if vectors else None)


__all__ = ["bidiagonal_svd"]
