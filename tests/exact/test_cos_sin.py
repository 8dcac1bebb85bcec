"""The split evaluation of cos(ωt) and t·sinc(ωt) on uniform grids (numeric.exact.modal.cos_tsinc) stays
at the rounding level of the direct one, on any grid, with rigid modes (ω = 0) exactly t, and
falls back on grids that are not uniform."""

from __future__ import annotations

import mpmath as mp
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from springchain.numeric.exact.modal import _uniform_split, cos_tsinc

EPS = np.finfo(float).eps


def direct(t, w):
    ph = np.multiply.outer(w, t)
    with np.errstate(divide="ignore", invalid="ignore"):
        ts = np.where(w[:, None] > 0, np.sin(ph) / np.where(w > 0, w, 1.0)[:, None], t[None, :])
    return np.cos(ph), ts


@settings(max_examples=60, deadline=None)
@given(s=st.integers(1, 3000), log_h=st.floats(-4, 1), t0=st.floats(0, 1e3),
       log_w=st.lists(st.floats(-4, 3), min_size=1, max_size=5), rigid=st.integers(0, 2))
def test_split_matches_direct(s, log_h, t0, log_w, rigid):
    t = t0 + np.arange(s) * 10.0**log_h
    w = np.concatenate([np.zeros(rigid), np.sort(10.0 ** np.array(log_w))])
    cs = cos_tsinc(t, w)
    n = w.size
    assert cs.shape == (2 * n, s)
    c, ts = direct(t, w)
    tmax = float(np.abs(t).max())
    phase = max(1.0, float(w.max() * tmax))
    assert np.abs(cs[:n] - c).max() <= 6 * EPS * phase
    # |t·sinc(ωt)| ≤ min(t, 1/ω): errors in units of that scale (phase rounding) plus t's own rounding
    scale = np.minimum(tmax, 1.0 / np.where(w > 0, w, np.inf))[:, None]
    assert np.all(np.abs(cs[n:] - ts) <= 6 * EPS * phase * scale + 4 * EPS * tmax)
    # rigid modes: a + b, which is t_i to rounding (the grid is rebuilt as block start + offset)
    np.testing.assert_allclose(cs[n:n + rigid], np.broadcast_to(t, (rigid, s)), rtol=0, atol=4 * EPS * tmax)


def test_against_mpmath_on_the_reference_grid():
    t = np.arange(1001) * 0.1
    w = np.array([0.0, 1.0, np.sqrt(5.0 / 3.0)])
    assert _uniform_split(t) is not None
    cs = cos_tsinc(t, w)
    worst = 0.0
    for j, wj in enumerate(w[1:], start=1):
        for i in range(0, 1001, 37):
            ph = mp.mpf(float(wj)) * mp.mpf(float(t[i]))
            worst = max(worst, abs(cs[j, i] - float(mp.cos(ph))), abs(cs[3 + j, i] - float(mp.sin(ph) / float(wj))))
    assert worst <= 64 * EPS * 130  # phases up to ~130 rad, rounded once, as the direct route
    np.testing.assert_allclose(cs[3], t, rtol=4 * EPS, atol=0)  # the rigid mode: t


def test_non_uniform_grid_takes_the_direct_route():
    t = np.sort(np.random.default_rng(3).uniform(0, 10, 500))
    assert _uniform_split(t) is None
    w = np.array([0.0, 0.5, 2.0])
    c, ts = direct(t, w)
    np.testing.assert_allclose(cos_tsinc(t, w)[:3], c, rtol=0, atol=4 * EPS * 20)
    np.testing.assert_allclose(cos_tsinc(t, w)[3:], ts, rtol=0, atol=4 * EPS * 20)
