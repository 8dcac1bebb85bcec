"""The split evaluation of cos(ωt), sin(ωt) on uniform grids (numeric.modal.cos_sin) stays at the
rounding level of the direct one, on any grid, and falls back on grids that are not uniform."""

from __future__ import annotations

import mpmath as mp
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from springchain.numeric.modal import _uniform_split, cos_sin

EPS = np.finfo(float).eps


@settings(max_examples=60, deadline=None)
@given(s=st.integers(1, 3000), log_h=st.floats(-4, 1), t0=st.floats(0, 1e3),
       log_w=st.lists(st.floats(-4, 3), min_size=1, max_size=5))
def test_split_matches_direct(s, log_h, t0, log_w):
    t = t0 + np.arange(s) * 10.0**log_h
    w = 10.0 ** np.array(log_w)
    cs = cos_sin(t, w)
    assert cs.shape == (2 * w.size, s)
    z = np.exp(1j * np.multiply.outer(w, t))
    scale = EPS * max(1.0, float(w.max() * np.abs(t).max()))
    assert np.abs(cs[: w.size] - z.real).max() <= 4 * scale
    assert np.abs(cs[w.size:] - z.imag).max() <= 4 * scale


def test_against_mpmath_on_the_reference_grid():
    t = np.arange(1001) * 0.1
    w = np.array([1.0, np.sqrt(5.0 / 3.0)])
    assert _uniform_split(t) is not None
    cs = cos_sin(t, w)
    worst = 0.0
    for j, wj in enumerate(w):
        for i in range(0, 1001, 37):
            ph = mp.mpf(float(wj)) * mp.mpf(float(t[i]))
            worst = max(worst, abs(cs[j, i] - float(mp.cos(ph))), abs(cs[2 + j, i] - float(mp.sin(ph))))
    assert worst <= 64 * EPS * 130  # phases up to ~130 rad, rounded once, as the direct route


def test_non_uniform_grid_takes_the_direct_route():
    t = np.sort(np.random.default_rng(3).uniform(0, 10, 500))
    assert _uniform_split(t) is None
    w = np.array([0.5, 2.0])
    np.testing.assert_allclose(cos_sin(t, w)[:2], np.cos(np.multiply.outer(w, t)), rtol=0, atol=4 * EPS * 20)
