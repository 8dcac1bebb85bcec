"""The orthonormal sine transform (DST-I) of any length at FFT speed.

A DST-I of length ``n`` is a real FFT of length ``2(n + 1)``. When that length has a large prime
factor (``n = 10⁶``: ``2·101·9901``) pocketfft's transform is 8–12× slower than at a neighbouring
length (2.2 s against 0.18 s at ``n = 10⁶ − 1``), and the modal solution of a long uniform
``[chain]`` evaluates one transform per recorded frame. Such lengths go through a chirp-z
(Bluestein) convolution instead: with ``N = n + 1`` and ``jk = (j² + k² − (k − j)²)/2``::

    Σ_j x_j e^{-iπjk/N} = c_k Σ_j (x_j c_j) conj(c_{k−j}),   c_j = e^{-iπj²/(2N)},

a convolution of a fast length ``L ≥ 2n + 1`` whose chirp spectrum is cached per ``n``
(0.9 s at ``n = 10⁶``). ``j²`` is reduced modulo ``4N`` in integers, so the chirp's phases are
exact to rounding at any ``n``; the error is norm-wise ~1e-17, as the FFT's.

    y = dst1(x, axis=0)     # y_k = √(2/(n+1)) Σ_j x_j sin(π (j+1)(k+1)/(n+1)); dst1(dst1(x)) = x
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import scipy.fft

#: Shorter transforms always go to pocketfft (its slow lengths cost milliseconds there).
MIN_CHIRP_LENGTH = 4096
#: A transform length whose prime factors are all at most this is fast in pocketfft.
SMOOTH = 97
#: Bytes of complex work arrays per chunk of columns on the chirp route.
CHUNK_BYTES = 256 * 2**20


def largest_prime_factor(m: int) -> int:
    """The largest prime factor of ``m ≥ 1`` (1 for ``m = 1``), by trial division."""
    p, largest = 2, 1
    while p * p <= m:
        while m % p == 0:
            m //= p
            largest = p
        p += 1 if p == 2 else 2
    return max(largest, m) if m > 1 else largest


def uses_chirp(n: int) -> bool:
    """Whether a DST-I of length ``n`` goes through the chirp-z route (a slow pocketfft length)."""
    return n >= MIN_CHIRP_LENGTH and largest_prime_factor(2 * (n + 1)) > SMOOTH


@lru_cache(maxsize=4)
def _chirp(n: int) -> tuple[np.ndarray, np.ndarray, int]:
    """The chirp ``c_j`` (j = 0..n), the spectrum of ``conj(c_|m|)`` (m = −n..n) at length ``L``, and L."""
    big_n = n + 1
    j = np.arange(n + 1, dtype=np.int64)
    c = np.exp(-1j * np.pi * ((j * j) % (4 * big_n)) / (2 * big_n))
    length = scipy.fft.next_fast_len(2 * n + 1)
    b = np.zeros(length, dtype=complex)
    b[:n + 1] = np.conj(c)
    b[length - n:] = np.conj(c[1:][::-1])
    return c, scipy.fft.fft(b), length


def _dst1_chirp(x: np.ndarray) -> np.ndarray:
    """Orthonormal DST-I along axis 0 of ``x`` (n,) or (n, m) by the chirp-z convolution."""
    n = x.shape[0]
    c, spectrum, length = _chirp(n)
    cols = x.reshape(n, -1)
    out = np.empty(cols.shape)
    step = max(1, CHUNK_BYTES // (16 * length))
    for s in range(0, cols.shape[1], step):
        block = cols[:, s:s + step]
        a = np.zeros((length, block.shape[1]), dtype=complex)
        a[1:n + 1] = block * c[1:, None]
        conv = scipy.fft.ifft(scipy.fft.fft(a, axis=0) * spectrum[:, None], axis=0)[1:n + 1]
        out[:, s:s + step] = -(c[1:, None] * conv).imag
    return (out * np.sqrt(2.0 / (n + 1))).reshape(x.shape)


def dst1(x: np.ndarray, axis: int = 0) -> np.ndarray:
    """The orthonormal DST-I of ``x`` along ``axis`` (its own inverse).

    Parameters
    ----------
    x : ndarray, shape (..., n, ...)
        Real values; the transform runs along ``axis`` (length n).
    axis : int

    Returns
    -------
    ndarray, the shape of ``x``
        ``y_k = √(2/(n+1)) Σ_j x_j sin(π (j+1)(k+1)/(n+1))``, as ``scipy.fft.dst(x, type=1,
        norm="ortho")``, through pocketfft or (slow lengths) the chirp-z convolution.
    """
    x = np.asarray(x, dtype=float)
    if not uses_chirp(x.shape[axis]):
        return scipy.fft.dst(x, type=1, norm="ortho", axis=axis)
    return np.moveaxis(_dst1_chirp(np.moveaxis(x, axis, 0)), 0, axis)


__all__ = ["dst1", "uses_chirp", "largest_prime_factor"]
