"""The fused chain step (numeric.compiled.fast) against the generated NumPy stencil.

* one fused velocity-Verlet step equals the reference step built here from the
  module's own ``acceleration`` (x + h v + h²/2 a; a' = a(x'); v + h/2 (a + a'))
  to 1e-14 relative, for free/wall/ring ends, uniform and index-dependent
  masses and springs, cubic springs, with and without a batch, and for sizes
  that span several cache blocks;
* the NumPy fallback (what runs without numba) gives the same numbers;
* ``advance`` (half-step velocity form) equals repeated steps to rounding;
* in-place and out-of-place kernels keep their promises about their inputs;
* bad input is refused with a message.
"""

from __future__ import annotations

import importlib

import numpy as np
import pytest

from helpers import chain_toml
from springchain.numeric.compiled import fast
from springchain.numeric.errors import RunRefused

ENDS = [("free", "free"), ("wall", "wall"), ("wall", "free"), ("free", "wall"), ("ring", "ring")]
BACKENDS = [fast.Backend.NUMPY] + ([fast.Backend.NUMBA] if fast.available() else [])


def chain_scene_text(left: str, right: str, uniform: bool, cubic: bool = False, n: int = 50) -> str:
    k3 = None if not cubic else ("c" if uniform else "c*(1 + cos(i))")
    return chain_toml(n, left, right, name=f"fast_{left}_{right}_{int(uniform)}_{int(cubic)}",
                      parameters={"m": 1.3, "k": 0.7, "c": 0.2}, mass="m" if uniform else "m*(1 + 0.5*sin(i))",
                      k="k" if uniform else "k*(1 + 0.25*(i % 3))", k3=k3)


@pytest.fixture(scope="module")
def chain_module(chain_module_of):
    """``chain_module(left, right, uniform, cubic)``: a freshly rendered [chain] module."""
    def get(left, right, uniform, cubic=False):
        return chain_module_of(chain_scene_text(left, right, uniform, cubic), "fastchain")
    return get


def module_acceleration(module, x, params=None):
    """The generated stencil's a(x); 1-D states go through as (n, 1) (the modules' state shape)."""
    p = dict(module.DEFAULTS)
    p.update(params or {})
    if x.ndim == 1:
        return module.acceleration(x[:, None], **p)[:, 0]
    return module.acceleration(x, **p)


def reference_step(module, x, v, a, h, params=None):
    """Velocity Verlet written out on the module's own acceleration (independent of numeric.compiled.fast)."""
    xn = x + h * v + 0.5 * h * h * a
    an = module_acceleration(module, xn, params)
    return xn, v + 0.5 * h * (a + an), an


def rel(got, want):
    return float(np.max(np.abs(got - want)) / max(np.max(np.abs(want)), 1e-300))


def state(n, batch, seed=0):
    rng = np.random.default_rng(seed)
    shape = (n,) if batch is None else (n, batch)
    return rng.standard_normal(shape), rng.standard_normal(shape)


@pytest.mark.parametrize("backend", BACKENDS, ids=lambda b: b.value)
@pytest.mark.parametrize("uniform", [True, False], ids=["uniform", "indexed"])
@pytest.mark.parametrize("ends", ENDS, ids=lambda e: "-".join(e))
def test_step_equals_numpy_stencil_step(chain_module, ends, uniform, backend):
    module = chain_module(*ends, uniform)
    for n in (1, 2, 3, 7, 20001):
        for batch in (None, 3):
            x, v = state(n, batch, seed=n)
            a = module_acceleration(module, x)
            want = reference_step(module, x, v, a, 0.37)
            fv = fast.FusedVerlet.from_module(module, None, n, 0.37, backend)
            np.testing.assert_allclose(fv.force(x), a, rtol=0, atol=1e-14 * np.max(np.abs(a)) + 1e-300)
            got = fv.step(x, v, a)
            for g, w in zip(got, want):
                assert g.shape == w.shape
                assert rel(g, w) <= 1e-14, (n, batch)


@pytest.mark.parametrize("backend", BACKENDS, ids=lambda b: b.value)
@pytest.mark.parametrize("ends,uniform", [(("free", "free"), True), (("wall", "free"), False),
                                          (("ring", "ring"), False), (("wall", "wall"), True)])
def test_cubic_chain_step_equals_numpy(chain_module, ends, uniform, backend):
    module = chain_module(*ends, uniform, cubic=True)
    assert not module.LINEAR
    for n, batch in ((1, None), (4, 2), (9000, None)):
        x, v = state(n, batch, seed=3)
        a = module_acceleration(module, x)
        want = reference_step(module, x, v, a, 0.05)
        got = fast.FusedVerlet.from_module(module, None, n, 0.05, backend).step(x, v, a)
        for g, w in zip(got, want):
            assert rel(g, w) <= 1e-14


@pytest.mark.parametrize("backend", BACKENDS, ids=lambda b: b.value)
@pytest.mark.parametrize("ends,uniform", [(("free", "free"), True), (("wall", "free"), False),
                                          (("ring", "ring"), True), (("free", "wall"), False)])
def test_advance_equals_repeated_steps(chain_module, ends, uniform, backend):
    module = chain_module(*ends, uniform)
    h, steps = 0.2, 41  # pairs of steps in one sweep (open chains) and one single sweep
    for n, batch in ((1, None), (2, None), (3, 2), (4, None), (300, 4), (12000, None)):
        x0, v0 = state(n, batch, seed=5)
        a0 = module_acceleration(module, x0)
        x, v, a = x0, v0, a0
        for _ in range(steps):
            x, v, a = reference_step(module, x, v, a, h)
        fv = fast.FusedVerlet.from_module(module, None, n, h, backend)
        for pairs in (True, False):
            xa, va, aa = x0.copy(), v0.copy(), a0.copy()
            out = fv.advance(xa, va, aa, steps, two_step_sweeps=pairs)
            assert out[0] is xa and out[1] is va and out[2] is aa
            # the same scheme, different rounding: errors stay at roundoff × steps
            assert rel(xa, x) <= 1e-12 and rel(va, v) <= 1e-12 and rel(aa, a) <= 1e-12


@pytest.mark.parametrize("backend", BACKENDS, ids=lambda b: b.value)
def test_kernel_contract_inplace_and_not(chain_module, backend):
    module = chain_module("wall", "free", False)
    x0, v0 = state(40, 2, seed=9)
    a0 = module_acceleration(module, x0)
    keep = [arr.copy() for arr in (x0, v0, a0)]
    safe = fast.chain_verlet_kernel(module, None, 40, 0.1, backend=backend)
    assert safe.inplace is False
    x, v, a = safe(x0, v0, a0, 0)
    for arr, orig in zip((x0, v0, a0), keep):
        np.testing.assert_array_equal(arr, orig)  # inputs untouched
    assert x is not x0 and v is not v0 and a is not a0
    fused = fast.chain_verlet_kernel(module, None, 40, 0.1, inplace=True, backend=backend)
    assert fused.inplace is True
    xi, vi, ai = (arr.copy() for arr in keep)
    out = fused(xi, vi, ai, 0)
    assert out[0] is xi and out[1] is vi and out[2] is ai
    for g, w in zip(out, (x, v, a)):
        assert rel(g, w) <= 1e-15
    assert not hasattr(safe, "advance")
    xa, va, aa = (arr.copy() for arr in keep)
    fused.advance(xa, va, aa, 3)
    xr, vr, ar = (arr.copy() for arr in keep)
    for i in range(3):
        xr, vr, ar = safe(xr, vr, ar, i)
    assert rel(xa, xr) <= 1e-13 and rel(va, vr) <= 1e-13
    # several steps through the kernel equal several reference steps
    xs, vs, as_ = (arr.copy() for arr in keep)
    xr, vr, ar = (arr.copy() for arr in keep)
    for i in range(25):
        xs, vs, as_ = safe(xs, vs, as_, i)
        xr, vr, ar = reference_step(module, xr, vr, ar, 0.1)
    assert rel(xs, xr) <= 1e-13 and rel(vs, vr) <= 1e-13


def test_uniform_module_has_scalar_coefficients():
    module = importlib.import_module("springchain.generated.chain100k")
    c = fast.ChainCoefficients.from_module(module, None, 10)
    assert c.uniform and c.inv_mass.shape == (1,) and c.k.shape == (1,)
    assert c.left is fast.End.FREE and c.right is fast.End.FREE and not c.cubic
    # Gershgorin bound ≥ the uniform chain's ω_max = 2√(k/m) sin(π(n-1)/(2n))
    assert c.omega_max_bound >= 2.0 * np.sin(np.pi * 9 / 20) - 1e-12


def test_indexed_coefficients_follow_the_module(chain_module):
    module = chain_module("wall", "wall", False)
    p = dict(module.DEFAULTS)
    c = fast.ChainCoefficients.from_module(module, None, 6)
    ks = module.spring_constants(**p, n=6)
    assert c.k_left == ks[0] and c.k_right == ks[-1]
    np.testing.assert_array_equal(c.k, ks[1:-1])
    np.testing.assert_allclose(c.inv_mass, 1.0 / module.masses(**p, n=6), rtol=1e-15)


def test_refuses_bad_input(chain_module, seed_module):
    module = chain_module("free", "free", True)
    with pytest.raises(RunRefused, match=r"\[chain\]"):
        fast.FusedVerlet.from_module(seed_module, None, 3, 0.1)
    with pytest.raises(ValueError, match="step size"):
        fast.FusedVerlet.from_module(module, None, 5, 0.0)
    if fast.available():
        fv = fast.FusedVerlet.from_module(module, None, 5, 0.1, fast.Backend.NUMBA)
        x = np.zeros(5)
        with pytest.raises(ValueError, match="shape"):
            fv.step(np.zeros(4), np.zeros(4), np.zeros(4))
        with pytest.raises(ValueError, match="float64"):
            fv.step(np.zeros(5, dtype=np.float32), x, x)
        with pytest.raises(ValueError, match="C-contiguous"):
            fv.step(np.zeros((5, 2))[:, :1], np.zeros((5, 1)), np.zeros((5, 1)))


def test_stream_update_is_the_stated_sweep():
    x = np.linspace(0.0, 1.0, 1001)
    v = np.cos(x)
    xe = x + 0.5 * v
    ve = v - 0.5 * xe
    fast.stream_update(x, v, 0.5)
    np.testing.assert_allclose(x, xe, rtol=1e-15)
    np.testing.assert_allclose(v, ve, rtol=1e-15, atol=1e-15)


def test_available_is_a_bool_and_backend_follows_it():
    assert isinstance(fast.available(), bool)
    assert fast.default_backend() is (fast.Backend.NUMBA if fast.available() else fast.Backend.NUMPY)


def test_inplace_kernel_runs_in_the_driver(chain_module):
    """The hook the integrator can use: an in-place fused kernel under numeric.run.driver.integrate
    records the same trajectory as the NumPy verlet kernel (the driver copies what it records)."""
    from springchain.numeric.run.driver import integrate
    from springchain.numeric.integrators.base import Problem
    from springchain.numeric.integrators.verlet import VelocityVerlet

    module = chain_module("wall", "free", True)
    n, h, steps = 200, 0.3, 60
    p = dict(module.DEFAULTS)
    problem = Problem(module.make_acceleration(**p, n=n))

    class FusedChainVerlet(VelocityVerlet):
        def kernel(self, problem, h):
            return fast.chain_verlet_kernel(module, None, n, h, inplace=True)

    x0, v0 = state(n, None, seed=11)
    ref = integrate(VelocityVerlet(), problem, x0, v0, h, steps, record_every=7)
    got = integrate(FusedChainVerlet(), problem, x0, v0, h, steps, record_every=7)
    np.testing.assert_array_equal(got.t, ref.t)
    assert rel(got.x, ref.x) <= 1e-13 and rel(got.v, ref.v) <= 1e-13
    assert np.all(x0 == state(n, None, seed=11)[0])  # the caller's arrays are untouched


def test_one_gershgorin_bound_for_stencils_and_spring_lists():
    """numeric.modes.bounds: the stencil form equals the spring-list form and bounds the true ω²_max."""
    from springchain.numeric.modes.bounds import chain_omega2_bound, omega2_bound
    from springchain.numeric.modes.spectrum import spectrum

    rng = np.random.default_rng(5)
    for n in (1, 2, 3, 7, 30):
        m = rng.uniform(0.1, 10.0, n)
        k = rng.uniform(0.1, 10.0, n + 1)
        for left, right, ring in ((True, True, False), (False, False, False), (True, False, False),
                                  (False, True, True)):
            ends = [(i, i + 1) for i in range(n - 1)]
            ks = list(k[1:n])
            if left:
                ends.insert(0, (-1, 0)); ks.insert(0, k[0])
            if right:
                ends.append((n - 1, 0) if ring else (n - 1, -1)); ks.append(k[n])
            if ring and n < 3:
                continue
            ends, ks = np.array(ends, dtype=np.intp).reshape(-1, 2), np.array(ks)
            full = omega2_bound(m, ends, ks)
            stencil = chain_omega2_bound(n, 1.0 / m, k[1:n], k[0] if left else 0.0, k[n] if right else 0.0, ring)
            assert stencil == pytest.approx(full, rel=1e-14)
            if ks.size:
                assert full >= spectrum(m, ends, ks).omega_max ** 2 * (1 - 1e-13)


def test_driver_runs_the_multi_step_sweep_between_frames(chain_module):
    """With an in-place kernel that has ``advance``, the driver makes one sweep call per recorded
    frame (never a per-step call) and records the per-step kernel's trajectory."""
    from springchain.numeric.run.driver import integrate
    from springchain.numeric.integrators.base import Problem
    from springchain.numeric.integrators.verlet import VelocityVerlet

    module = chain_module("free", "free", False)
    n, h, steps = 150, 0.2, 60
    problem = Problem(module.make_acceleration(**dict(module.DEFAULTS), n=n))
    fused = fast.chain_verlet_kernel(module, None, n, h, inplace=True)
    calls = []

    def step(x, v, a, i):
        raise AssertionError("per-step call of a kernel that can sweep")

    def advance(x, v, a, k):
        calls.append(k)
        return fused.advance(x, v, a, k)

    step.inplace, step.advance = True, advance

    class Sweeping(VelocityVerlet):
        def kernel(self, problem, h):
            return step

    x0, v0 = state(n, None, seed=3)
    ref = integrate(VelocityVerlet(), problem, x0, v0, h, steps, record_every=7)
    got = integrate(Sweeping(), problem, x0, v0, h, steps, record_every=7)
    assert calls == [7] * 8 + [4]
    assert rel(got.x, ref.x) <= 1e-12 and rel(got.v, ref.v) <= 1e-12
    assert np.all(x0 == state(n, None, seed=3)[0])
