"""The transform solution of uniform chains (numeric.exact.chain) against the dense modal solution.

* for free–free, wall–wall, wall–free, free–wall and ring ends and n in
  {1, 2, 3, 10, 64, 257}: positions and velocities at several times equal
  :class:`numeric.exact.modal.ModalSolution` on :func:`numeric.modes.spectrum.spectrum`
  (dense SVD, built here from the module's masses and springs) to 1e-12
  relative, for one state and a batch;
* the closed-form frequencies equal ``scipy.linalg.eigh_tridiagonal`` of the
  mass-weighted stiffness (dense ``eigvalsh`` for rings);
* the rigid-body drift of a free chain is exact at long times;
* index-dependent chains (eigenvector fallback) agree with the dense solution too;
* bad requests are refused.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from helpers import chain_toml
from springchain.numeric.exact.chain import Basis, ChainModal
from springchain.numeric.errors import RunRefused
from springchain.numeric.exact.modal import ModalSolution
from springchain.numeric.modes.spectrum import spectrum

ENDS = [("free", "free"), ("wall", "wall"), ("wall", "free"), ("free", "wall"), ("ring", "ring")]
SIZES = [1, 2, 3, 10, 64, 257]
TIMES = np.array([0.0, 0.3, 1.7, 12.5, 61.0])


def chain_modal_text(left, right, uniform=True, cubic=False):
    return chain_toml(10, left, right, name=f"cm_{left}_{right}_{int(uniform)}", parameters={"m": 1.7, "k": 2.3, "c": 0.1},
                      mass="m" if uniform else "m*(1 + 0.5*sin(i))", k="k" if uniform else "k*(1 + 0.25*(i % 3))",
                      k3="c" if cubic else None)


@pytest.fixture(scope="module")
def chain_module(chain_module_of):
    def get(left, right, uniform=True, cubic=False):
        return chain_module_of(chain_modal_text(left, right, uniform, cubic), "chainmodal")
    return get


def dense_spectrum(module, n):
    p = dict(module.DEFAULTS)
    return spectrum(module.masses(**p, n=n), module.spring_ends(n=n), module.spring_constants(**p, n=n))


def dense_solution(module, n, x0, v0, spec=None):
    return ModalSolution.from_initial(spec if spec is not None else dense_spectrum(module, n), x0, v0)


def initial(n, batch, seed=1):
    rng = np.random.default_rng(seed + n)
    shape = (n,) if batch is None else (n, batch)
    return rng.standard_normal(shape), rng.standard_normal(shape)


def rel(got, want):
    return float(np.max(np.abs(got - want)) / max(np.max(np.abs(want)), 1e-300))


@pytest.mark.parametrize("ends", ENDS, ids=lambda e: "-".join(e))
def test_transform_solution_equals_dense_modal(chain_module, ends):
    module = chain_module(*ends)
    for n in SIZES:
        spec = dense_spectrum(module, n)
        for batch in (None, 3):
            x0, v0 = initial(n, batch)
            sol = ChainModal.from_module(module, None, x0, v0)
            assert sol.basis.fast
            ref = dense_solution(module, n, x0, v0, spec)
            x, v = sol.at(TIMES)
            xr, vr = ref.at(TIMES)
            assert x.shape == xr.shape == (len(TIMES),) + x0.shape
            assert rel(x, xr) <= 1e-12 and rel(v, vr) <= 1e-12, (n, batch)
            xs, vs = sol.at(1.7)  # a scalar time gives one state
            assert xs.shape == x0.shape
            assert rel(xs, xr[2]) <= 1e-12 and rel(vs, vr[2]) <= 1e-12
        np.testing.assert_allclose(sol.at(0.0)[0], x0, rtol=0, atol=1e-14 * np.max(np.abs(x0)))


@pytest.mark.parametrize("ends", ENDS, ids=lambda e: "-".join(e))
def test_closed_form_frequencies_equal_tridiagonal_eigenvalues(chain_module, ends):
    module = chain_module(*ends)
    p = dict(module.DEFAULTS)
    for n in (1, 2, 5, 64, 300):
        x0 = np.zeros(n)
        w = ChainModal.from_module(module, None, x0, x0).omega_sorted
        m = module.masses(**p, n=n)
        r = np.sqrt(m)
        if ends[0] == "ring":
            K = module.stiffness_matrix(**p, n=n)
            w2 = np.linalg.eigvalsh(K / np.outer(r, r))
        else:
            diag, off = module.stiffness_bands(**p, n=n)
            w2 = scipy.linalg.eigh_tridiagonal(diag / m, off / (r[:-1] * r[1:]), eigvals_only=True)
        scale = max(float(np.max(np.abs(w2))), 1.0)
        assert np.max(np.abs(np.sort(w) ** 2 - np.sort(w2))) <= 1e-12 * scale, n
    # and the module's own closed form (derive.chain), in ascending order
    w_mod = np.sqrt(np.maximum(module.omega2(**p, n=64), 0.0))
    np.testing.assert_allclose(ChainModal.from_module(module, None, np.zeros(64), np.zeros(64)).omega_sorted,
                               w_mod, rtol=1e-13, atol=1e-13)


def test_mode_omega_rigid_mode_is_exactly_zero(chain_module):
    """The generated closed forms (derive.chain) give ω = 0 exactly for the rigid mode, > 0 otherwise."""
    p = {"m": 1.0, "k": 1.0, "c": 0.1}
    assert chain_module("free", "free").mode_omega(**p, n=7)[0] == 0.0
    assert chain_module("ring", "ring").mode_omega(**p, n=7)[0] == 0.0
    assert np.all(chain_module("wall", "free").mode_omega(**p, n=7) > 0)


def test_rigid_drift_is_exact_at_long_times(chain_module):
    n = 1000
    x0 = np.zeros(n)
    v0 = np.full(n, 0.25)
    for ends in (("free", "free"), ("ring", "ring")):
        module = chain_module(*ends)
        x, v = ChainModal.from_module(module, {"m": 2.0, "k": 3.0}, x0, v0).at(1e6)
        np.testing.assert_allclose(x, 0.25e6, rtol=1e-12)
        np.testing.assert_allclose(v, 0.25, rtol=1e-12)


@pytest.mark.parametrize("ends", [("free", "free"), ("wall", "free"), ("ring", "ring")], ids=lambda e: "-".join(e))
def test_index_dependent_chain_falls_back_to_eigenvectors(chain_module, ends):
    module = chain_module(*ends, uniform=False)
    for n in (1, 3, 40):
        x0, v0 = initial(n, 2, seed=7)
        sol = ChainModal.from_module(module, None, x0, v0)
        assert sol.basis is Basis.EIGENVECTORS
        x, v = sol.at(TIMES)
        xr, vr = dense_solution(module, n, x0, v0).at(TIMES)
        assert rel(x, xr) <= 1e-11 and rel(v, vr) <= 1e-11


def test_refusals(chain_module, seed_module):
    with pytest.raises(RunRefused, match="cubic"):
        ChainModal.from_module(chain_module("free", "free", cubic=True), None, np.zeros(3), np.zeros(3))
    with pytest.raises(RunRefused, match=r"\[chain\]"):
        ChainModal.from_module(seed_module, None, np.zeros(3), np.zeros(3))
    with pytest.raises(RunRefused, match="n <= "):
        ChainModal.from_module(chain_module("free", "free", uniform=False), None, np.zeros(5000), np.zeros(5000))
    with pytest.raises(ValueError, match="same shape"):
        ChainModal.transform(np.zeros(3), "free", "free", np.zeros(3), np.zeros(4))
    with pytest.raises(ValueError, match="ring on both"):
        ChainModal.transform(np.zeros(3), "ring", "free", np.zeros(3), np.zeros(3))
    with pytest.raises(ValueError, match="ring on both"):
        ChainModal.transform(np.zeros(3), "sideways", "free", np.zeros(3), np.zeros(3))


def test_large_uniform_chain_needs_no_matrix(chain_module):
    """n = 2·10⁵ wall–free: only transforms (memory O(n)); energy is conserved exactly."""
    n = 200_000
    i = np.arange(n)
    x0 = 0.01 * np.sin(np.pi * (i + 1) / (n + 1))
    v0 = np.zeros(n)
    sol = ChainModal.from_module(chain_module("wall", "free"), {"m": 1.0, "k": 1.0}, x0, v0)
    x, v = sol.at(123.0)

    def energy(x, v):
        d = np.diff(x)
        return 0.5 * np.sum(v * v) + 0.5 * np.sum(d * d) + 0.5 * x[0] ** 2

    assert abs(energy(x, v) - energy(x0, v0)) <= 1e-12 * energy(x0, v0)
