"""The DST-I of any length (numeric/sine_transform.py) against references built here.

Slow pocketfft lengths (2(n+1) with a large prime factor, e.g. n = 10⁶) go through a chirp-z
convolution; it must agree with the dense sine matrix (small n, the route forced) and with
pocketfft's own transform (an independent implementation) to ~1e-15 of the norm.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.fft
from hypothesis import given, settings
from hypothesis import strategies as st

from springchain.numeric.exact import sine_transform as stf


def dense_dst1(x: np.ndarray) -> np.ndarray:
    n = x.shape[0]
    j = np.arange(1, n + 1)
    S = np.sqrt(2.0 / (n + 1)) * np.sin(np.pi * np.outer(j, j) / (n + 1))
    return S @ x


@settings(deadline=None)
@given(st.integers(1, 300), st.integers(0, 2**32 - 1), st.integers(1, 3))
def test_chirp_route_matches_the_dense_sine_matrix(n, seed, cols):
    x = np.random.default_rng(seed).standard_normal((n, cols))
    got = stf._dst1_chirp(x)
    ref = dense_dst1(x)
    assert np.max(np.abs(got - ref)) <= 1e-14 * max(np.linalg.norm(x), 1e-300)


@pytest.mark.parametrize("n", [9900, 20_000, 100_000])
def test_slow_lengths_take_the_chirp_route_and_match_pocketfft(n):
    assert stf.uses_chirp(n)  # 2(n+1) = 2·9901, 2·20001 = 2·3·59·113, 2·100001 = 2·11·9091
    x = np.random.default_rng(n).standard_normal((n, 2))
    got = stf.dst1(x, axis=0)
    ref = scipy.fft.dst(x, type=1, norm="ortho", axis=0)
    assert np.max(np.abs(got - ref)) <= 1e-14 * np.linalg.norm(x)
    np.testing.assert_allclose(stf.dst1(got.T, axis=1).T, x, atol=1e-13 * np.linalg.norm(x))  # self-inverse


def test_route_choice():
    assert stf.uses_chirp(1_000_000) and not stf.uses_chirp(999_999)  # 2·101·9901 against 2·10⁶
    assert not stf.uses_chirp(4000)  # short: pocketfft always
    assert stf.largest_prime_factor(2_000_002) == 9901 and stf.largest_prime_factor(1) == 1
    assert stf.largest_prime_factor(97 * 89) == 97 and stf.largest_prime_factor(2**20) == 2


def test_chunks_of_columns_agree(monkeypatch):
    monkeypatch.setattr(stf, "CHUNK_BYTES", 1)  # one column per chunk
    x = np.random.default_rng(0).standard_normal((9900, 3))
    np.testing.assert_allclose(stf.dst1(x), scipy.fft.dst(x, type=1, norm="ortho", axis=0),
                               atol=1e-14 * np.linalg.norm(x))


def test_benchmark_script_measures_both_routes():
    from benchmark_scripts import load

    r = load("sine_transform").measure(9900, rounds=1)
    assert r["chirp_route"] and set(r["median_seconds"]) == {"pocketfft", "chirp", "fast neighbour"}
    assert r["max_difference_over_norm"] < 1e-14
