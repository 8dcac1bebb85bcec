"""Index-dependent rings: the generated omega2() takes the spring-factor route (it was a generalized
eigh(K, M), which loses small ω² at large contrasts), checked against 60-digit mpmath."""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest

import springchain as sc
from springchain._modules import load_module


def reference(n, mass, k):
    with mp.workdps(60):
        K = mp.zeros(n)
        for i in range(n):
            a, b = i, (i + 1) % n
            K[a, a] += k[i]
            K[b, b] += k[i]
            K[a, b] -= k[i]
            K[b, a] -= k[i]
        R = mp.diag([1 / mp.sqrt(x) for x in mass])
        E, _ = mp.eigsy(R * K * R)
        return sorted(float(e) for e in E)


@pytest.mark.parametrize("n, mass_ratio, k_ratio", [(6, 1e8, 1e6), (7, 1e-9, 1e9), (5, 1e12, 1.0), (2, 1e6, 1e6)])
def test_ring_omega2_relative_accuracy(tmp_path, monkeypatch, n, mass_ratio, k_ratio):
    monkeypatch.setenv("SPRINGCHAIN_CACHE", str(tmp_path / "cache"))
    path = tmp_path / "ringx.toml"
    path.write_text(f'name = "ringx"\n[parameters]\nm = 1.5\nk = 2.0\n[chain]\nn = {n}\n'
                    f'mass = "m*(1 + {mass_ratio!r}*(i % 2))"\nk = "k*(1 + {k_ratio!r}*(i % 3))"\n'
                    'left = "ring"\nright = "ring"\n')
    scene = sc.load(path)
    mod, _ = load_module(scene)
    got = np.asarray(mod.omega2(m=1.5, k=2.0, n=n))
    mass = [mp.mpf(1.5) * (1 + mp.mpf(mass_ratio) * (i % 2)) for i in range(n)]
    k = [mp.mpf(2.0) * (1 + mp.mpf(k_ratio) * (i % 3)) for i in range(n)]
    want = reference(n, mass, k)
    assert got[0] == 0.0  # the rigid mode, by structure
    np.testing.assert_allclose(got[1:], want[1:], rtol=1e-13, atol=0)
    printed = [m["omega2_value"] for m in sc.modes(scene).to_json()["modes"]]
    np.testing.assert_allclose(printed[1:], want[1:], rtol=1e-13, atol=0)
