"""Sensitivities ∂ω²/∂p and ∂φ/∂p (issue 36) against extended-precision differences written here.

References (:mod:`sensitivity_reference`) are built from each scene's TOML text with tomllib, SymPy
and mpmath at 100 digits: central differences with h = 1e-30·p for simple modes, one-sided
differences along the branches for repeated ω². Accuracy asked: 1e-12 relative to
max(|∂ω²/∂p|, ω²/p) for eigenvalue derivatives, and 1e-12 relative to max(‖∂φ/∂p‖_M, 1/p) for
shape derivatives (largest mass-weighted component error) — at element contrasts up to 1e12.
"""

from __future__ import annotations

import json

import mpmath
import numpy as np
import pytest
from helpers import chain_toml, one_line_error, run_cli, scene_toml
from sensitivity_reference import Reference

import springchain as sc

TOL = 1e-12


def _random_scene(seed: int, n: int, decades: float = 12.0) -> str:
    """A scene of n masses: a path, sometimes walls, a ring closure and extra springs; masses and springs
    are c·p over 4 + 4 parameters log-uniform over ``decades``, one spring nonlinear in them (k0·k1/k2)."""
    rng = np.random.default_rng(seed)
    params = {}
    for j in range(4):
        params[f"k{j}"] = float(10 ** rng.uniform(-decades / 2, decades / 2))
        params[f"m{j}"] = float(10 ** rng.uniform(-decades / 2, decades / 2))
    coef = ["1", "2", "0.5", "3"]
    masses = {f"x{i}": f"{coef[rng.integers(4)]}*m{rng.integers(4)}" for i in range(n)}
    springs = [{"between": [f"x{i}", f"x{i + 1}"], "k": f"{coef[rng.integers(4)]}*k{rng.integers(4)}"}
               for i in range(n - 1)]
    if seed % 2:
        springs.append({"between": ["wall", "x0"], "k": "k0*k1/k2"})
    if seed % 3 == 0 and n > 2:
        springs.append({"between": [f"x{n - 1}", "x0"], "k": "k3"})
    return scene_toml(f"rs{seed}", params, masses=masses, springs=springs)


def _check(result, text: str, one_sided: bool = False, shapes: bool = True, skip: tuple = ()):
    """Compare every (parameter, elastic mode) with the reference; returns the worst errors."""
    ref = Reference(text)
    r = result.result
    worst_w = worst_s = 0.0
    for ip, p in enumerate(r.parameters):
        if p in skip:
            continue
        w0, dw, s0, ds, m = ref.one_sided(p) if one_sided else ref.central(p)
        m = np.array(m)
        pv = abs(ref.params[p])
        for slot, j in enumerate(r.index.tolist()):
            if r.rigid[slot]:
                assert r.d_omega2[ip, slot] == 0.0
                continue
            scale = max(abs(dw[j]), w0[j] / pv)
            err = abs(result.d_omega2[ip, slot] - dw[j]) / scale
            assert err <= TOL, (p, j, result.d_omega2[ip, slot], dw[j])
            worst_w = max(worst_w, err)
            if shapes:
                ref_shape, ref_d = np.array(s0[j]), np.array(ds[j])
                sign = np.sign(np.sum(m * r.adapted[ip, :, slot] * ref_shape))
                assert np.max(np.sqrt(m) * np.abs(sign * r.adapted[ip, :, slot] - ref_shape)) < 1e-13
                s_scale = max(np.sqrt(np.sum(m * ref_d**2)), 1.0 / pv)
                es = np.max(np.sqrt(m) * np.abs(sign * r.d_shapes[ip, :, slot] - ref_d)) / s_scale
                assert es <= TOL, (p, j, es)
                worst_s = max(worst_s, es)
    return worst_w, worst_s


@pytest.mark.parametrize("seed,n", [(1, 5), (2, 4), (3, 6), (6, 3)])
def test_random_scenes_at_contrast_1e12_match_100_digit_central_differences(tmp_path, seed, n):
    text = _random_scene(seed, n)
    path = tmp_path / f"rs{seed}.toml"
    path.write_text(text)
    names = [f"{c}{j}" for c in "km" for j in range(4)]  # some enter no element: derivatives exactly 0
    result = sc.sensitivities(path, parameters=names)
    assert result.d_omega2.shape == (8, n) and result.d_shapes.shape == (8, n, n)
    w, s = _check(result, text)
    assert w <= TOL and s <= TOL


@pytest.mark.parametrize("left,right", [("wall", "free"), ("free", "free"), ("wall", "wall"), ("free", "wall")])
def test_index_dependent_chain_route_matches_references(tmp_path, left, right):
    """Open [chain] scenes take the O(n) route (bisection, Nelson's tridiagonal system): masses over 6
    decades and springs over 12, every end type, against the 100-digit references."""
    text = chain_toml(9, left, right, parameters={"m": 2.0e3, "k": 3.0e-4, "a": 7.0},
                      mass="m*(1 + a*(i % 2))*exp(6.9*(i % 3))", k="k*exp(6.9*((2*i) % 5)) + a*k", initial=None)
    path = tmp_path / "ch.toml"
    path.write_text(text)
    result = sc.sensitivities(path)
    assert "open chain" in result.result.route
    assert result.result.rigid.sum() == (1 if (left, right) == ("free", "free") else 0)
    _check(result, text)


RING = scene_toml("ringk", {"m": 1.5, "k1": 2.0, "k2": 2.0, "k3": 2.0, "k4": 2.0, "q": 1.0},
                  masses={f"m{i}": "m" for i in range(1, 5)},
                  springs=[{"between": ["m1", "m2"], "k": "k1*q"}, {"between": ["m2", "m3"], "k": "k2*q**2"},
                           {"between": ["m3", "m4"], "k": "k3"}, {"between": ["m4", "m1"], "k": "k4"}])


def test_repeated_eigenvalue_gives_directional_derivatives_of_the_branches(tmp_path):
    """A ring of four equal masses and springs has ω² = 2k/m twice. k1 (one spring) splits the pair: the
    derivatives are the one-sided derivatives of the two branches (eigenvalues of the projected matrix),
    the shapes the branches' limits and their derivatives the branches' (one-sided, second order, 100
    digits; q enters two springs, one of them as q², so K'' is used). m keeps the symmetry: both branches
    have the same derivative, and no NaN anywhere."""
    path = tmp_path / "ringk.toml"
    path.write_text(RING)
    result = sc.sensitivities(path)
    r = result.result
    assert np.all(np.isfinite(r.d_omega2)) and np.all(np.isfinite(r.d_shapes))
    assert list(r.repeated) == [1, 2, 2, 1]
    _check(result, RING, one_sided=True, skip=("m",))
    _check(result, RING, one_sided=True, shapes=False)  # m: eigenvalue derivatives only (the pair stays repeated)
    k1 = r.parameters.index("k1")
    assert r.d_omega2[k1, 1] == 0.0 and r.d_omega2[k1, 2] == pytest.approx(2 / 3, rel=1e-15)


def test_bundled_ring4_is_finite_and_equals_the_closed_form(capsys):
    status, out, err = run_cli(["modes", "ring4", "--sensitivity", "--json"], capsys)
    assert status == 0, err
    data = json.loads(out)
    assert "NaN" not in out
    by_mode = {rec["mode"]: rec for rec in data["modes"]}
    assert by_mode[1]["repeated"] == by_mode[2]["repeated"] == 2
    for j in (1, 2):  # ω² = 2k/m twice: ∂/∂k = 2/m, ∂/∂m = −2k/m² (k = m = 1)
        assert by_mode[j]["d_omega2"] == {"k": 2.0, "m": -2.0}
        assert by_mode[j]["d_omega2_expr"] == {"k": "2/m", "m": "-2*k/m**2"}
        assert by_mode[j]["normalised"] == {"k": 1.0, "m": -1.0}
    assert by_mode[0]["rigid"] and by_mode[0]["d_omega2"] == {"k": 0.0, "m": 0.0}
    # the rigid mode's shape derivative: φ = 1/√(4m) on every mass, ∂φ/∂m = −φ/(2m)
    assert np.allclose(by_mode[0]["d_shape"]["m"], [-0.25] * 4, rtol=1e-15, atol=0)


def test_closed_forms_and_ranking_of_the_reference_scene():
    s = sc.sensitivities("seed")
    data = s.to_json()
    m1, m2 = data["modes"][1], data["modes"][2]
    assert m1["d_omega2_expr"] == {"k": "1/m", "m": "-k/m**2"}
    assert m2["d_omega2_expr"] == {"k": "5/(3*m)", "m": "-5*k/(3*m**2)"}
    assert m2["d_omega2"]["k"] == 5 / 3
    # mode 1: s = (1, 0, -1), sᵀMs = 2m, φ = s/√(2m): ∂φ/∂m = −s/(2√2 m^(3/2)), by hand; ∂φ/∂k = 0
    assert m1["d_shape_expr"]["m"] == ["-sqrt(2)/(4*m**(3/2))", "0", "sqrt(2)/(4*m**(3/2))"]
    assert m1["d_shape_expr"]["k"] == ["0", "0", "0"] and m1["d_shape"]["k"] == [0.0, 0.0, 0.0]
    h = 1 / (2 * 2**0.5)
    assert np.allclose(m1["d_shape"]["m"], [-h, 0.0, h], rtol=1e-15, atol=0)
    assert [row["parameter"] for row in data["ranking"]] == ["k", "m"]
    assert data["ranking"][0]["max_abs_normalised"] == 1.0
    text = s.to_text()
    assert "Ranking" in text and "5/(3*m)" in text


def test_uniform_chain_family_and_long_chain_listing(tmp_path):
    path = tmp_path / "u.toml"
    path.write_text(chain_toml(60, "wall", "free", parameters={"m": 2.0, "k": 3.0}, initial=None))
    s = sc.sensitivities(path)
    data = s.to_json()
    assert data["family"]["k"] is not None and "sin" in data["family"]["k"]
    assert len(data["modes"]) == 20 and "shape" not in data["modes"][0]
    assert any("10 lowest" in note for note in data["notes"])
    # a uniform chain's ω² is proportional to k/m: normalised sensitivities are exactly ±1
    assert np.allclose(s.normalised[0], 1.0, rtol=0, atol=1e-14)
    assert np.allclose(s.normalised[1], -1.0, rtol=0, atol=1e-14)


def test_refusals_are_one_line(capsys, tmp_path):
    status, out, err = run_cli(["modes", "seed", "--sensitivity", "--parameters", "q"], capsys)
    one_line_error(status, out, err, "'q'", "accepted: k, m")
    status, out, err = run_cli(["modes", "seed", "--sensitivity", "--latex"], capsys)
    one_line_error(status, out, err, "--latex")
    path = tmp_path / "pot.toml"
    path.write_text(scene_toml("pot", {"m": 1.0, "k": 2.0}, masses={"a": "m"},
                               springs=[{"between": ["wall", "a"], "potential": "k*d**2/2 + d**4"}]))
    status, out, err = run_cli(["modes", path, "--sensitivity"], capsys)
    one_line_error(status, out, err, "potentials")


def test_mac_pairs_modes_optimally_at_shared_masses(tmp_path):
    from springchain.numeric.sensitivity.mac import mac_matrix

    a = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    b = np.array([[0.0, -2.0, 1.0], [3.0, 0.0, 1.0], [3.0, -2.0, 0.0]])
    m = mac_matrix(a, b)  # by hand: (a·b)²/(|a|²|b|²)
    expect = np.array([[9 / (2 * 18), 16 / (2 * 8), 1 / (2 * 2)], [36 / (2 * 18), 4 / (2 * 8), 1 / (2 * 2)]])
    assert np.allclose(m, expect, rtol=1e-15, atol=0)
    r = sc.mac(a, b)
    assert [(i, j) for i, j, _ in r.pairs] == [(0, 1), (1, 0)]  # 1.0 + 1.0 beats any other assignment
    # a measured file at a subset of masses, paired with the scene's modes by MAC
    shapes = sc.sensitivities("building").result.shapes
    rows = ["omega,floor1,floor3"] + [f"{w!r},{float(shapes[0, j])!r},{float(shapes[2, j])!r}"
                                      for j, w in ((2, 36.0), (0, 8.9))]
    path = tmp_path / "meas.csv"
    path.write_text("\n".join(rows) + "\n")
    r = sc.mac("building", path)
    assert r.a.dofs == ("floor1", "floor3")
    assert [(i, j) for i, j, _ in r.pairs] == [(0, 1), (2, 0)]
    assert all(v > 1 - 1e-14 for _, _, v in r.pairs)
    # an array of shapes takes the scene's masses by height (or masses=...); mismatched heights are refused
    assert [(i, j) for i, j, _ in sc.mac(shapes[[0, 2]], "building", masses="floor1,floor3").pairs] == \
        [(0, 0), (1, 1), (2, 2)]
    with pytest.raises(sc.SceneError, match="as many rows"):
        sc.mac(shapes[:2], shapes)


def test_sweep_follows_branches_by_mac_crossing_and_veering(tmp_path):
    """A one-parameter grid sweep reports mode branches followed by shape: two uncoupled oscillators cross
    (the ranks exchange, each branch keeps its shape), weakly coupled ones veer (the ranks stay, the shapes
    exchange: the MAC of a branch with itself drops)."""
    def scene(name, coupled):
        springs = [{"between": ["wall", "a"], "k": "k1"}, {"between": ["b", "wall"], "k": "k2"}]
        if coupled:
            springs.append({"between": ["a", "b"], "k": "c"})
        path = tmp_path / f"{name}.toml"
        path.write_text(scene_toml(name, {"m": 1.0, "k1": 1.0, "k2": 1.0, "c": 0.02}, masses={"a": "m", "b": "m"},
                                   springs=springs))
        return path

    kw = dict(vary=["k2=grid(0.5, 1.5, 20)"], samples=1, workers=1, progress=False)
    cross = sc.sweep(scene("cross", False), out=tmp_path / "c", **kw).summary["branches"]
    assert [c["branches"] for c in cross["crossings"]] == [[0, 1]] and cross["veerings"] == []
    assert cross["crossings"][0]["at"][0] < 1.0 < cross["crossings"][0]["at"][1]
    w = np.array(cross["omega2"])  # branch 0 is mass b (ω² = k2) all along, though it becomes the higher mode
    assert np.allclose(w[:, 0], np.linspace(0.5, 1.5, 20), rtol=1e-14, atol=0)
    veer = sc.sweep(scene("veer", True), out=tmp_path / "v", **kw)
    b = veer.summary["branches"]
    assert b["crossings"] == [] and [v["branches"] for v in b["veerings"]] == [[0, 1]]
    assert min(min(row) for row in b["mac_next"]) < 0.9
    assert (tmp_path / "v" / "branches.png").stat().st_size > 0 and veer.figures[-1].name == "branches.png"


def test_messages_name_the_flag_of_each_interface_and_modes_chooses_the_listed_modes(tmp_path, capsys):
    """The mac refusal names --masses (and masses= for Python); past 40 masses the sensitivity note names
    --modes; ``modes --sensitivity --modes 0,2`` lists exactly those modes. On the bundled building (equal
    floors m, storeys k) ω² = (k/m)·λ exactly, so p/ω² ∂ω²/∂p is 1 for k and −1 for m, and ω²₀, ω²₂ against
    the 50-digit eigenvalues of the fixed–free chain's (tridiagonal 2, 2, 1) matrix written here."""
    one_line_error(*run_cli(["mac", "building", "seed"], capsys), "--masses on the command line", "masses= in Python")
    with pytest.raises(sc.SceneError, match="masses= in Python"):
        sc.mac("building", "seed")
    status, out, err = run_cli(["modes", "building", "--sensitivity", "--modes", "0,2", "--json"], capsys)
    assert status == 0, err
    data = json.loads(out)
    assert [rec["mode"] for rec in data["modes"]] == [0, 2]
    with mpmath.workdps(50):
        lam = sorted(mpmath.eigsy(mpmath.matrix([[2, -1, 0], [-1, 2, -1], [0, -1, 1]]), eigvals_only=True))
        ref = [float(lam[j] * mpmath.mpf(4000000) / 10000) for j in (0, 2)]
    for rec, w2 in zip(data["modes"], ref):
        assert rec["omega2"] == pytest.approx(w2, rel=1e-13)
        assert rec["normalised"]["k"] == pytest.approx(1.0, rel=1e-12)
        assert rec["normalised"]["m"] == pytest.approx(-1.0, rel=1e-12)
    one_line_error(*run_cli(["modes", "building", "--sensitivity", "--modes", "0,x"], capsys), "--modes", "0,1,2")
    one_line_error(*run_cli(["modes", "building", "--modes", "1"], capsys), "--modes", "--sensitivity")
    path = tmp_path / "long.toml"
    path.write_text('name = "long"\n[parameters]\nm = 1.0\nk = 1.0\n[chain]\nn = 45\nmass = "m"\nk = "k"\n')
    status, out, err = run_cli(["modes", path, "--sensitivity"], capsys)
    assert status == 0, err
    assert "others: --modes J,K,... on the command line, modes=[...] in Python" in out
    status, out, err = run_cli(["modes", path, "--sensitivity", "--modes", "20", "--json"], capsys)
    assert status == 0, err
    assert [rec["mode"] for rec in json.loads(out)["modes"]] == [20]


def test_small_derivatives_are_resolved_relative_to_themselves(tmp_path):
    """A new user's scene: the highest mode (ω² ≈ 8.6e14) barely stretches the soft springs kb, kc, whose
    ∂ω²/∂k = (φ_a − φ_b)² are 4.3e-40 and 8.7e-12 — far below double-double's resolution of ω²/p (2.9e17)
    — and were printed as 0. The reference: mpmath's eigenpairs of M^-1/2 K M^-1/2 at 120 digits from the
    TOML values, (φ_a − φ_b)² with mass-normalised φ."""
    import mpmath

    text = scene_toml("s01", {"ka": 1e12, "kb": 1.0, "kc": 3e-3, "ma": 2e4, "mb": 5e-4},
                      masses={"p": "ma", "q": "mb", "r": "ma", "s": "mb*7"},
                      springs=[{"between": ["wall", "p"], "k": "ka"}, {"between": ["p", "q"], "k": "kb"},
                               {"between": ["q", "r"], "k": "kc"}, {"between": ["r", "s"], "k": "ka*3"}])
    path = tmp_path / "s01.toml"
    path.write_text(text)
    got = {m["mode"]: m["d_omega2"] for m in sc.sensitivities(path).to_json()["modes"]}
    with mpmath.workdps(120):
        F = lambda v: mpmath.mpf(v)  # noqa: E731
        m = [F(2e4), F(5e-4), F(2e4), 7 * F(5e-4)]
        springs = [(-1, 0, F(1e12)), (0, 1, F(1)), (1, 2, F(3e-3)), (2, 3, 3 * F(1e12))]
        K = mpmath.zeros(4, 4)
        for a, b, k in springs:
            for i, si in ((a, 1), (b, -1)):
                for j, sj in ((a, 1), (b, -1)):
                    if i >= 0 and j >= 0:
                        K[i, j] += si * sj * k
        D = mpmath.matrix(4, 4)
        for i in range(4):
            for j in range(4):
                D[i, j] = K[i, j] / mpmath.sqrt(m[i] * m[j])
        lam, E = mpmath.eigsy(D)
        order = sorted(range(4), key=lambda j: lam[j])
        for pos, j in enumerate(order):
            phi = [E[i, j] / mpmath.sqrt(m[i]) for i in range(4)]
            wants = {"ka": phi[0] ** 2 + 3 * (phi[2] - phi[3]) ** 2,  # ka stands in two springs
                     "kb": (phi[0] - phi[1]) ** 2, "kc": (phi[1] - phi[2]) ** 2}
            for name, want in wants.items():
                want = float(want)
                assert abs(got[pos][name] - want) <= 1e-12 * abs(want), (pos, name, got[pos][name], want)
