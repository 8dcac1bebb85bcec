"""Past the printed-matrix size, generated damping code of explicit scenes: dashpots in incidence
form, Rayleigh damping per mass; both equal -M⁻¹ C v with C built here from the scene's numbers."""

from __future__ import annotations

import numpy as np
import pytest

from helpers import scene_toml
from springchain import load
from springchain._modules import load_module

N = 15


def large_damped_text(rayleigh: bool) -> str:
    springs = [{"between": [f"p{i}", f"p{i + 1}"], "k": f"k*{1 + i % 3}"} for i in range(N - 1)]
    springs.append({"between": ["wall", "p0"], "k": "k"})
    dampers = [{"between": [f"p{N - 1}", "wall"], "c": "c"}, {"between": ["p3", "p4"], "c": "2*c"}]
    return scene_toml("big_damped", {"m": 2.0, "k": 3.0, "c": 0.25, "al": 0.1, "be": 0.01},
                      masses={f"p{i}": f"m*{i + 1}" for i in range(N)}, springs=springs, dampers=dampers,
                      tables={"damping": {"rayleigh": ["al", "be"]}} if rayleigh else None)


@pytest.mark.parametrize("rayleigh", [False, True])
def test_damping_acceleration_matches_C(tmp_path, monkeypatch, rayleigh):
    monkeypatch.setenv("SPRINGCHAIN_CACHE", str(tmp_path / "cache"))
    path = tmp_path / "big_damped.toml"
    path.write_text(large_damped_text(rayleigh))
    mod, _ = load_module(load(path))
    m = 2.0 * np.arange(1, N + 1)
    K = np.zeros((N, N))
    for i in range(N - 1):
        k = 3.0 * (1 + i % 3)
        K[np.ix_([i, i + 1], [i, i + 1])] += k * np.array([[1, -1], [-1, 1]])
    K[0, 0] += 3.0
    C = np.zeros((N, N))
    C[N - 1, N - 1] += 0.25
    C[np.ix_([3, 4], [3, 4])] += 0.5 * np.array([[1, -1], [-1, 1]])
    if rayleigh:
        C += 0.1 * np.diag(m) + 0.01 * K
    v = np.random.default_rng(5).standard_normal((N, 4))
    params = dict(m=2.0, k=3.0, c=0.25, al=0.1, be=0.01)
    got = mod.damping_acceleration(v, **params)
    want = -(C @ v) / m[:, None]
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-15 * np.abs(want).max())
    np.testing.assert_allclose(mod.damping_matrix(**params), C, rtol=1e-13, atol=1e-15)
