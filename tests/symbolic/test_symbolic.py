"""Exact symbolic checks of the derivation (derive.model, derive.modes) on small scenes.

Matrices and equations are compared with exact SymPy arithmetic (``expand`` of
a difference, ``simplify`` only on 3x3 or smaller results); spectra of larger
scenes are compared numerically at random positive parameter values.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
import sympy as sp

from springchain.derive.model import Model
from springchain.derive.modes import closed_form_modes


def _is_zero(expr) -> bool:
    return sp.simplify(sp.expand(expr)) == 0


def _matrix_is_zero(mat: sp.Matrix) -> bool:
    return all(_is_zero(e) for e in mat)


def _flat_modes(modes):
    """[(omega2, shape)] once per independent shape, in the ModeSet's order."""
    return [(mode.omega2, sp.Matrix(s)) for mode in modes.modes for s in mode.shapes]


def _proportional(a: sp.Matrix, b: sp.Matrix) -> bool:
    """a ∥ b exactly: every 2x2 minor a_i b_j - a_j b_i simplifies to 0 (and neither is 0)."""
    n = a.shape[0]
    if all(e == 0 for e in a) or all(e == 0 for e in b):
        return False
    return all(_is_zero(a[i] * b[j] - a[j] * b[i]) for i in range(n) for j in range(i + 1, n))


# -- the reference scene -------------------------------------------------------------------
@pytest.fixture(scope="module")
def seed_model(seed_derivation):
    return seed_derivation.model


@pytest.fixture(scope="module")
def mk(seed_model):
    return seed_model.params["m"], seed_model.params["k"]


def test_seed_mass_and_stiffness_matrices(seed_model, mk):
    m, k = mk
    assert seed_model.M == sp.diag(m, 3 * m, m)
    assert seed_model.K == sp.Matrix([[k, -k, 0], [-k, 2 * k, -k], [0, -k, k]])
    assert seed_model.K == seed_model.K.T


def test_seed_dynamical_matrix(seed_model, mk):
    m, k = mk
    c = k / (sp.sqrt(3) * m)
    expected = sp.Matrix([[k / m, -c, 0], [-c, 2 * k / (3 * m), -c], [0, -c, k / m]])
    assert _matrix_is_zero(seed_model.D - expected)
    # D = M^-1/2 K M^-1/2, from the model's own M and K
    s = sp.diag(*[1 / sp.sqrt(e) for e in seed_model.M.diagonal()])
    assert _matrix_is_zero(seed_model.D - s * seed_model.K * s)


def test_seed_lagrangian(seed_model, mk):
    m, k = mk
    x1, x2, x3 = seed_model.x
    v1, v2, v3 = seed_model.v
    T = m * v1**2 / 2 + 3 * m * v2**2 / 2 + m * v3**2 / 2
    V = k * (x1 - x2) ** 2 / 2 + k * (x2 - x3) ** 2 / 2
    assert sp.expand(seed_model.T - T) == 0
    assert sp.expand(seed_model.V - V) == 0
    assert sp.expand(seed_model.L - (T - V)) == 0


def test_seed_euler_lagrange_is_Ma_plus_Kx(seed_model):
    residual = seed_model.euler_lagrange()
    assert len(residual) == 3
    a, x = sp.Matrix(seed_model.a), sp.Matrix(seed_model.x)
    expected = seed_model.M * a + seed_model.K * x
    for got, want in zip(residual, expected):
        assert sp.expand(got - want) == 0


def test_euler_lagrange_matches_generic_derivation(seed_model):
    """The element-wise residual equals d/dt ∂L/∂v - ∂L/∂x computed on the whole Lagrangian."""
    L = seed_model.L
    for i, got in enumerate(seed_model.euler_lagrange()):
        p = sp.diff(L, seed_model.v[i])
        ddt = sum(sp.diff(p, seed_model.v[j]) * seed_model.a[j] + sp.diff(p, seed_model.x[j]) * seed_model.v[j]
                  for j in range(3))
        assert sp.expand(got - (ddt - sp.diff(L, seed_model.x[i]))) == 0


def test_seed_closed_form_modes(seed_derivation, mk):
    m, k = mk
    model, modes = seed_derivation.model, seed_derivation.modes
    assert modes.closed_form
    flat = _flat_modes(modes)
    assert len(flat) == 3
    expected = [(sp.Integer(0), sp.Matrix([1, 1, 1])),
                (k / m, sp.Matrix([1, 0, -1])),
                (5 * k / (3 * m), sp.Matrix([1, sp.Rational(-2, 3), 1]))]
    for (w2, shape), (w2_ref, shape_ref) in zip(flat, expected):
        assert _is_zero(w2 - w2_ref), (w2, w2_ref)
        assert _proportional(shape, shape_ref), (shape, shape_ref)
        assert _matrix_is_zero((model.K - w2 * model.M) * shape)
    assert [mode.rigid for mode in modes.modes] == [True, False, False]
    assert [mode.multiplicity for mode in modes.modes] == [1, 1, 1]


def test_seed_weighted_vectors_are_eigenvectors_of_D(seed_derivation):
    model, modes = seed_derivation.model, seed_derivation.modes
    for mode, weighted in zip(modes.modes, modes.weighted(model)):
        for e in weighted:
            assert _matrix_is_zero((model.D - mode.omega2 * sp.eye(3)) * sp.Matrix(e))


def test_seed_shapes_are_mass_orthogonal(seed_derivation):
    model = seed_derivation.model
    shapes = [s for _, s in _flat_modes(seed_derivation.modes)]
    for i in range(3):
        for j in range(i + 1, 3):
            assert _is_zero((shapes[i].T * model.M * shapes[j])[0])


# -- two masses ---------------------------------------------------------------------------------
def test_two_masses_with_wall_general(derived):
    """wall - ka - p - kb - q: exact eigen-equation, trace and determinant identities."""
    d = derived("wall2")
    model, modes = d.model, d.modes
    ma, mb, ka, kb = (model.params[n] for n in ("ma", "mb", "ka", "kb"))
    assert model.M == sp.diag(ma, mb)
    assert model.K == sp.Matrix([[ka + kb, -kb], [-kb, kb]])
    assert model.free_components == []
    flat = _flat_modes(modes)
    assert len(flat) == 2 and modes.closed_form
    for w2, shape in flat:
        assert _matrix_is_zero((model.K - w2 * model.M) * shape)
    w = [w2 for w2, _ in flat]
    assert _is_zero(w[0] + w[1] - ((ka + kb) / ma + kb / mb))
    assert _is_zero(w[0] * w[1] - ka * kb / (ma * mb))
    values = {model.params[n]: v for n, v in model.scene.parameters.items()}
    num = [float(sp.N(e.subs(values))) for e in w]
    ref = scipy.linalg.eigh(np.array(model.K.subs(values), dtype=float),
                            np.array(model.M.subs(values), dtype=float), eigvals_only=True)
    np.testing.assert_allclose(num, ref, rtol=1e-13)


def test_two_masses_between_walls_symmetric(derived):
    d = derived("sym2")
    model = d.model
    m, k = model.params["m"], model.params["k"]
    assert model.K == sp.Matrix([[2 * k, -k], [-k, 2 * k]])
    flat = _flat_modes(d.modes)
    assert len(flat) == 2
    assert _is_zero(flat[0][0] - k / m) and _is_zero(flat[1][0] - 3 * k / m)
    assert _proportional(flat[0][1], sp.Matrix([1, 1]))
    assert _proportional(flat[1][1], sp.Matrix([1, -1]))


# -- four masses, mirror symmetric --------------------------------------------------------------
def test_four_mass_mirror_chain(derived):
    d = derived("four")
    model, modes = d.model, d.modes
    assert modes.closed_form
    flat = _flat_modes(modes)
    assert len(flat) == 4
    # mirror symmetry: every shape is exactly symmetric or antisymmetric
    for _, s in flat:
        sym = all(_is_zero(s[i] - s[3 - i]) for i in range(2))
        anti = all(_is_zero(s[i] + s[3 - i]) for i in range(2))
        assert sym or anti, s
    m, k = model.params["m"], model.params["k"]
    rng = np.random.default_rng(20240501)
    for _ in range(5):
        mv, kv = rng.uniform(0.1, 10.0, size=2)
        subs = {m: mv, k: kv}
        got = sorted(float(sp.N(w2.subs(subs), 30)) for w2, _ in flat)
        want = [(2 - 2 * math.cos(j * math.pi / 5)) * kv / mv for j in range(1, 5)]
        np.testing.assert_allclose(got, want, rtol=1e-12)
        K = np.array(model.K.subs(subs), dtype=float)
        M = np.array(model.M.subs(subs), dtype=float)
        for w2, shape in flat:
            w = float(sp.N(w2.subs(subs), 30))
            phi = np.array(shape.subs(subs).evalf(30), dtype=float).ravel()
            r = (K - w * M) @ phi
            assert np.linalg.norm(r) <= 1e-12 * np.linalg.norm(K) * np.linalg.norm(phi)


# -- topology: non-neighbours, duplicate springs ----------------------------------------------------
def test_non_neighbour_and_duplicate_springs_add(derived):
    d = derived("nonneigh")
    model = d.model
    m, k = model.params["m"], model.params["k"]
    # p1-p3 (k), p1-p2 (k), p2-p1 (2k): the two p1-p2 springs add to 3k
    assert model.K == sp.Matrix([[4 * k, -3 * k, -k], [-3 * k, 3 * k, 0], [-k, 0, k]])
    assert model.M == sp.diag(m, 2 * m, m)
    assert model.free_components == [[0, 1, 2]]
    flat = _flat_modes(d.modes)
    assert len(flat) == 3
    assert flat[0][0] == 0 and _proportional(flat[0][1], sp.Matrix([1, 1, 1]))
    for w2, shape in flat:
        assert _matrix_is_zero((model.K - w2 * model.M) * shape)
    # sum of the ω² = trace(M^-1 K) = 4k/m + 3k/(2m) + k/m
    assert _is_zero(sum(w2 for w2, _ in flat) - sp.Rational(13, 2) * k / m)


def test_disconnected_pieces_have_one_rigid_mode_each(derived):
    model = derived("pairs").model
    assert model.free_components == [[0, 1], [2, 3]]


def test_two_free_pairs_modes(derived):
    d = derived("pairs")
    model, modes = d.model, d.modes
    m, k = model.params["m"], model.params["k"]
    flat = _flat_modes(modes)
    assert len(flat) == 4
    values = sorted((w2 for w2, _ in flat), key=lambda e: float(e.subs({m: 1, k: 1})))
    assert values[0] == 0 and values[1] == 0
    assert _is_zero(values[2] - 2 * k / m) and _is_zero(values[3] - 2 * k / m)
    # a repeated value is one mode with multiplicity 2 and two shapes
    assert sorted(mode.multiplicity for mode in modes.modes) == [2, 2]
    shapes = sp.Matrix.hstack(*[s for _, s in flat])
    assert shapes.rank() == 4
    for w2, shape in flat:
        assert _matrix_is_zero((model.K - w2 * model.M) * shape)


# -- one mass ----------------------------------------------------------------------------------------
def test_one_mass_on_a_wall_spring(derived):
    d = derived("one_wall")
    model = d.model
    m, k = model.params["m"], model.params["k"]
    assert model.M == sp.Matrix([[m]]) and model.K == sp.Matrix([[k]])
    flat = _flat_modes(d.modes)
    assert len(flat) == 1
    assert _is_zero(flat[0][0] - k / m)
    assert not d.modes.modes[0].rigid


def test_one_free_mass(derived):
    d = derived("one_free")
    model = d.model
    assert model.K == sp.zeros(1, 1)
    flat = _flat_modes(d.modes)
    assert len(flat) == 1
    assert flat[0][0] == 0 and flat[0][1] == sp.Matrix([1])
    assert d.modes.modes[0].rigid
    a = sp.Matrix(model.a)
    assert sp.expand(model.euler_lagrange()[0] - (model.M * a)[0]) == 0


# -- gravity and cubic springs: the model's terms are the gradient of V -------------------------------
@pytest.mark.parametrize("name", ["seed", "wall2", "nonneigh", "hanging", "cubic"])
def test_terms_are_minus_grad_V(derived, name):
    from springchain.derive.model import Effect

    model = derived(name).model
    forces = model.force_expressions(Effect.SPRING, Effect.CUBIC, Effect.GRAVITY)
    for i, f in enumerate(forces):
        assert sp.expand(f + sp.diff(model.V, model.x[i])) == 0


@pytest.mark.parametrize("name", ["seed", "wall2", "four", "nonneigh", "hanging", "cubic"])
def test_K_is_hessian_of_V_at_rest(derived, name):
    model = derived(name).model
    zero = {x: 0 for x in model.x}
    H = sp.hessian(model.V, model.x).subs(zero)
    assert (H - model.K).applyfunc(sp.expand) == sp.zeros(*H.shape)


def test_model_refuses_chain_scene(scene_from_text):
    scene = scene_from_text('name = "c"\n[parameters]\nm = 1.0\nk = 1.0\n'
                            '[chain]\nn = 3\nmass = "m"\nk = "k"\n'
                            '[initial]\nx = "0"\nv = "0"\n', "c.toml")
    with pytest.raises(ValueError):
        Model(scene)


def test_budget_fallback_is_numeric_and_flagged(derived):
    """max_radical_degree=0 forces the numeric fallback; values still match eigh."""
    model = derived("wall2").model
    modes = closed_form_modes(model, max_radical_degree=0)
    assert not modes.closed_form and modes.notes
    values = model.scene.parameters
    subs = {model.params[k]: v for k, v in values.items()}
    got = [float(mode.omega2) for mode in modes.modes for _ in mode.shapes]
    ref = scipy.linalg.eigh(np.array(model.K.subs(subs), dtype=float),
                            np.array(model.M.subs(subs), dtype=float), eigvals_only=True)
    np.testing.assert_allclose(got, ref, rtol=1e-12)
    assert all(not mode.exact for mode in modes.modes)


@pytest.mark.parametrize("name", ["building", "building_quake", "duffing", "hanging", "ring4", "seed"])
def test_stamped_euler_lagrange_equals_differentiating_L_and_R(name):
    """The element-stamped residual (no sp.diff) equals d/dt ∂L/∂v − ∂L/∂x + ∂R/∂v − Q computed by
    differentiating the whole Lagrangian and Rayleigh function (dampers, cubic springs, gravity,
    ground motion and forces included)."""
    from springchain._scenes import bundled_scene_dir
    from springchain.derive.model import Effect
    from springchain.derive.scene import load_scene

    model = Model(load_scene(bundled_scene_dir() / f"{name}.toml"))
    L, R, n = model.L, model.R, model.scene.n
    Q = model.force_expressions(Effect.FORCE, Effect.TABLE, Effect.GROUND)
    for i, got in enumerate(model.euler_lagrange()):
        p = sp.diff(L, model.v[i])
        ddt = sum(sp.diff(p, model.v[j]) * model.a[j] + sp.diff(p, model.x[j]) * model.v[j] for j in range(n))
        want = ddt + sp.diff(p, model.t) - sp.diff(L, model.x[i]) + sp.diff(R, model.v[i]) - Q[i]
        assert sp.expand(got - want) == 0, (name, i)
    assert model.M == sp.diag(*[sp.diff(model.T, v, 2) for v in model.v])


def test_two_walled_pieces_get_closed_forms_piece_by_piece(scene_from_text):
    """Two pieces (wall–x0–x1, wall–x2–x3) with eight distinct parameters: each piece is its own block,
    so every ω² is a closed form, an exact eigenpair, and its shape is confined to its piece (was: the
    whole 4×4 block, whose quartic split into two quadratics, and an inverse modulo one of them that
    ran for > 10 min in SymPy's gcd)."""
    from springchain._modules import derive

    from helpers import scene_toml

    params = {"m0": 1.0, "m1": 1.0, "m2": 1.0, "m3": 2.0, "k0": 1.0, "k1": 1.0, "k2": 3.0, "k3": 1.0}
    springs = [{"between": list(ends), "k": k}
               for ends, k in ((("wall", "x0"), "k0"), (("x0", "x1"), "k1"), (("wall", "x2"), "k2"), (("x2", "x3"), "k3"))]
    text = scene_toml("pieces2", params, masses={f"x{i}": f"m{i}" for i in range(4)}, springs=springs)
    d = derive(scene_from_text(text, "pieces2.toml"))
    model, modes = d.model, d.modes
    assert modes.closed_form
    flat = _flat_modes(modes)
    assert len(flat) == 4
    for w2, shape in flat:
        assert _matrix_is_zero((model.K - w2 * model.M) * shape)
        moved = {i for i in range(4) if shape[i] != 0}
        assert moved <= {0, 1} or moved <= {2, 3}, moved
    p = {name: model.params[name] for name in ("m0", "m1", "k0", "k1")}
    first = [w2 for w2, s in flat if s[0] != 0]
    assert len(first) == 2
    assert _is_zero(first[0] * first[1] - p["k0"] * p["k1"] / (p["m0"] * p["m1"]))
