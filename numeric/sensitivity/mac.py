"""The modal assurance criterion and the optimal pairing of two mode sets.

``MAC(a, b) = (aᵀb)² / ((aᵀa)(bᵀb))`` of two shapes sampled at the same degrees of freedom: 1 for
proportional shapes (any scale or sign), 0 for orthogonal ones. Two sets of different sizes are
paired by the assignment that maximises the summed MAC (Hungarian method, SciPy's
``linear_sum_assignment``): every mode of the smaller set gets a distinct partner.
"""

from __future__ import annotations

import numpy as np


def mac_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """MAC of every pair of columns.

    Parameters
    ----------
    a : ndarray, shape (D, Ja)
    b : ndarray, shape (D, Jb)
        Shapes as columns, sampled at the same D degrees of freedom.

    Returns
    -------
    ndarray, shape (Ja, Jb)
        In [0, 1]; 0 where a shape is zero at every degree of freedom.
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if a.ndim == 1:
        a = a[:, None]
    if b.ndim == 1:
        b = b[:, None]
    # scale each column to unit max-norm first: no overflow or underflow in the squares
    sa = np.max(np.abs(a), axis=0)
    sb = np.max(np.abs(b), axis=0)
    a = a / np.where(sa > 0, sa, 1.0)[None, :]
    b = b / np.where(sb > 0, sb, 1.0)[None, :]
    num = (a.T @ b) ** 2
    den = np.sum(a * a, axis=0)[:, None] * np.sum(b * b, axis=0)[None, :]
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)
    return np.clip(out, 0.0, 1.0)


def pair(mac: np.ndarray) -> list[tuple[int, int, float]]:
    """The pairing that maximises the summed MAC: ``(row, column, MAC)`` sorted by row.

    Parameters
    ----------
    mac : ndarray, shape (Ja, Jb)
    """
    from scipy.optimize import linear_sum_assignment

    mac = np.asarray(mac, dtype=float)
    rows, cols = linear_sum_assignment(mac, maximize=True)
    return sorted((int(i), int(j), float(mac[i, j])) for i, j in zip(rows, cols))


__all__ = ["mac_matrix", "pair"]
