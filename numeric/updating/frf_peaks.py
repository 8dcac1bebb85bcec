"""Measured modes from a measured frequency response: peak picking and quadrature picking.

A measured receptance ``H_d(iω) = X_d / F`` (one input, outputs at D sensor masses; CSV columns
``omega`` or ``frequency``, then ``<mass>.re`` and ``<mass>.im`` for each sensor) is reduced to the
modes :mod:`.fit` updates against:

* **natural frequencies**: the local maxima of ``Σ_d |H_d|`` whose prominence (SciPy's ``find_peaks``) is
  at least a factor :data:`PROMINENCE`; around each, the samples down to half the peak are fitted
  with one mode plus a constant for the others (:func:`_local_fit`, a linear least-squares problem), whose
  ω_r is the undamped natural frequency — not the peak, which sits at ``ω_r √(1 − 2ζ²)`` and is pulled by
  the neighbouring modes;
* **shapes**: the fitted residues ``A_d ∝ φ_d φ_input`` (turned real by the phase of the largest); where the
  fit fails, the imaginary part of each ``H_d`` at the peak (quadrature picking: near a lightly damped
  resonance ``H_d ≈ φ_d φ_in / (2iζω_r²)``).

This is what a modal test reads off a lightly damped structure with separated modes (no standard
deviations: the frequencies are weighed as relative errors and the noise level is estimated by the fit).
"""

from __future__ import annotations

import numpy as np

from ..errors import RunRefused
from .measured import Measured, number, read_text, rows_of

#: A peak must exceed the larger of its two neighbouring minima by this factor (in Σ|H|).
PROMINENCE = 2.0


def is_frf(header: list[str]) -> bool:
    """Whether a CSV header is a measured FRF (``<mass>.re`` / ``<mass>.im`` columns)."""
    return any(h.endswith((".re", ".im")) for h in header)


def read_frf(path) -> tuple[str, np.ndarray, tuple[str, ...], np.ndarray]:
    """``(file, ω (W,), sensors, H (W, D) complex)`` of a measured-FRF CSV (refused in one line)."""
    from pathlib import Path

    file = str(path)
    accepted = ("a CSV file with omega (rad/s) or frequency (Hz), then <mass>.re and <mass>.im of the receptance "
                "at each sensor mass, one row per frequency, ascending")
    header, rows = rows_of(read_text(Path(path), file), file)
    hz = "frequency" in header
    col = "frequency" if hz else "omega"
    if col not in header or ("omega" in header and hz):
        raise RunRefused(f"{file}: header: needs exactly one of 'omega' or 'frequency'; accepted: {accepted}",
                         "measured")
    sensors = []
    for h in header:
        if h == col:
            continue
        base, dot, part = h.rpartition(".")
        if not dot or part not in ("re", "im") or not base:
            raise RunRefused(f"{file}: header: column {h!r}; accepted: {accepted}", "measured")
        if base not in sensors:
            sensors.append(base)
    for s in sensors:
        if f"{s}.re" not in header or f"{s}.im" not in header:
            raise RunRefused(f"{file}: header: {s!r} needs both {s}.re and {s}.im; accepted: {accepted}",
                             "measured")
    if len(rows) < 5:
        raise RunRefused(f"{file}: {len(rows)} frequencies; accepted: at least 5 rows ({accepted})", "measured")
    omega = np.empty(len(rows))
    H = np.empty((len(rows), len(sensors)), dtype=complex)
    for r, (line, row) in enumerate(rows):
        if len(row) != len(header):
            raise RunRefused(f"{file}: line {line}: {len(row)} cells for {len(header)} columns; accepted: "
                             f"{accepted}", "measured")
        cells = dict(zip(header, row))
        omega[r] = (2 * np.pi if hz else 1.0) * number(cells[col], file, line, col, positive=True)
        for d, s in enumerate(sensors):
            H[r, d] = complex(number(cells[f"{s}.re"], file, line, f"{s}.re"),
                              number(cells[f"{s}.im"], file, line, f"{s}.im"))
    if np.any(np.diff(omega) <= 0):
        raise RunRefused(f"{file}: {col}: not strictly ascending; accepted: {accepted}", "measured")
    return file, omega, tuple(sensors), H


def _local_fit(w: np.ndarray, H: np.ndarray) -> tuple[float, np.ndarray] | None:
    """ω_r and the shape of one resonance from the samples around its peak: the single-mode model with a
    constant for the other modes, ``H_d = A_d / (a₀ + i a₁ ω − ω²) + B_d``, multiplied out and solved as a
    linear least-squares problem in ``a₀, a₁`` (shared), ``K_d = A_d + B_d a₀, B_d a₁, B_d`` (Levy's
    linearisation): ``ω_r = √a₀``; then, the pole known, the residues ``A_d`` (∝ φ_d φ_input, turned real)
    of ``H_d = A_d / (a₀ + i a₁ ω − ω²) + B_d + E_d (ω − ω_r)`` by linear least squares."""
    W, D = H.shape
    cols = 2 + 6 * D
    rows_re, rows_im, rhs_re, rhs_im = [], [], [], []
    for d in range(D):
        h = H[:, d]
        # H a0 + i H a1 ω − K − i C ω + B ω² = H ω², with K = A + B a0 and C = B a1 (K, C, B complex)
        block = np.zeros((W, cols), dtype=complex)
        block[:, 0] = h
        block[:, 1] = 1j * h * w
        base = 2 + 6 * d
        for k, coef in enumerate((-np.ones(W), -1j * w, w * w)):  # K, C, B: real and imaginary parts
            block[:, base + 2 * k] = coef
            block[:, base + 2 * k + 1] = 1j * coef
        rows_re.append(block.real)
        rows_im.append(block.imag)
        rhs_re.append((h * w * w).real)
        rhs_im.append((h * w * w).imag)
    M = np.vstack(rows_re + rows_im)
    y = np.concatenate(rhs_re + rhs_im)
    scale = np.max(np.abs(M), axis=0)
    scale[scale == 0] = 1.0
    try:
        x = np.linalg.lstsq(M / scale, y, rcond=None)[0] / scale
    except np.linalg.LinAlgError:
        return None
    if not x[0] > 0:
        return None
    # the residues, with the pole now known: H_d = A_d / den + B_d + E_d (ω − ω_r), linear in A, B, E
    den = x[0] + 1j * x[1] * w - w * w
    basis = np.stack([1 / den, np.ones(W), w - np.sqrt(x[0])], axis=1)
    coef = np.linalg.lstsq(basis, H, rcond=None)[0]  # (3, D), complex
    A = coef[0]
    big = A[np.argmax(np.abs(A))]
    shape = (A * np.conj(big) / abs(big)).real if abs(big) > 0 else A.real
    return float(np.sqrt(x[0])), shape


def modes_from_frf(file: str, omega: np.ndarray, sensors: tuple[str, ...], H: np.ndarray) -> Measured:
    """Peak and quadrature picking (module docstring): a :class:`Measured` with frequencies and shapes."""
    from scipy.signal import find_peaks

    a = np.sum(np.abs(H), axis=1)
    with np.errstate(divide="ignore"):
        peaks, _ = find_peaks(np.log(np.maximum(a, np.finfo(float).tiny)), prominence=np.log(PROMINENCE))
    peaks = [int(i) for i in peaks if 0 < i < a.shape[0] - 1]
    if not peaks:
        raise RunRefused(f"{file}: no resonance peak stands out (a factor {PROMINENCE:g} over its surroundings); "
                         "accepted: a measured receptance sampled through its resonances", "measured")
    w, shapes = [], []
    for i in peaks:
        lo, hi = i, i
        while lo > 0 and a[lo - 1] >= a[i] / 2 and a[lo - 1] < a[lo] * 1.0001:
            lo -= 1
        while hi < a.shape[0] - 1 and a[hi + 1] >= a[i] / 2 and a[hi + 1] < a[hi] * 1.0001:
            hi += 1
        lo, hi = max(0, min(lo, i - 8)), min(a.shape[0] - 1, max(hi, i + 8))
        fit = _local_fit(omega[lo:hi + 1], H[lo:hi + 1])
        if fit is not None and omega[lo] < fit[0] < omega[hi]:
            wr, shape = fit
        else:  # the peak itself and quadrature picking (Im H ∝ φ near a lightly damped resonance)
            wr, shape = float(omega[i]), H[i].imag
        w.append(wr)
        shapes.append(shape / np.max(np.abs(shape)) if np.any(shape) else shape)
    return Measured(file, np.array(w), None, sensors, np.array(shapes).T if sensors else None)


__all__ = ["read_frf", "modes_from_frf", "is_frf", "PROMINENCE"]
