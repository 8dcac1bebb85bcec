"""Frequency response: ``springchain frf`` / ``springchain.frf``.

References are built in the test from the scene file's TOML text (tomllib, masses, springs and
dampers assembled by hand) and solved with ``np.linalg.solve`` one frequency at a time.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from helpers import TomlScene, chain_toml, one_line_error, run_cli, write_scene
import springchain as sc
from springchain.cli import main

REL = 1e-10


def _matrices(path: Path):
    """M, K, C (dense) from a [masses] scene's TOML, assembled element by element."""
    return TomlScene.read(path).matrices()


def _reference(M, K, C, omega, i, o):
    out = np.empty(omega.shape[0], dtype=complex)
    for j, w in enumerate(omega):
        F = np.zeros(M.shape[0], dtype=complex)
        F[i] = 1.0
        out[j] = np.linalg.solve(K - w * w * M + 1j * w * C, F)[o]
    return out


def _pick(omega, count=200):
    return omega[np.unique(np.linspace(0, omega.shape[0] - 1, count).round().astype(int))]


@pytest.mark.parametrize("scene,inp,out", [("building", "floor3", "floor3"), ("building", "floor1", "floor3"),
                                           ("seed", "m1", "m3"), ("hanging", "m1", "m2"), ("ring4", "m1", "m2")])
def test_frf_matches_independent_solve(repo_root, scene, inp, out):
    names, M, K, C = _matrices(repo_root / "scenes" / f"{scene}.toml")
    r = sc.frf(scene, input=inp, output=out, transfer=False)
    assert r.omega.shape == r.magnitude.shape == r.phase.shape
    assert np.all(np.diff(r.omega) > 0)
    w = _pick(r.omega)  # 200 frequencies of the refined grid, near-resonance points included
    assert w.shape[0] == 200
    ref = _reference(M, K, C, w, names.index(inp), names.index(out))
    idx = np.searchsorted(r.omega, w)
    H = r.magnitude[idx] * np.exp(1j * np.radians(r.phase[idx]))
    assert np.max(np.abs(H - ref) / np.abs(ref)) <= REL
    from springchain.numeric.frf.response import operator, receptance
    from springchain._modules import system_of as _system

    other = np.geomspace(w[0], w[-1], 200) * (1 + 1e-3 * np.sin(np.arange(200)))  # off the grid too
    system, _ = _system(sc.load(scene))
    got = receptance(operator(system), other, names.index(inp), names.index(out))
    ref2 = _reference(M, K, C, other, names.index(inp), names.index(out))
    assert np.max(np.abs(got - ref2) / np.abs(ref2)) <= REL


def test_default_range_and_undamped_gap():
    r = sc.frf("seed", input="m1", output="m3", transfer=False)
    w1, w2 = 1.0, np.sqrt(5 / 3)  # k = m = 1
    assert r.omega[0] == pytest.approx(w1 / 10, rel=1e-12)
    assert r.omega[-1] == pytest.approx(3 * w2, rel=1e-12)
    for wj in (w1, w2):  # undamped: never on ω_j, approached from both sides to within 2e-4
        d = r.omega / wj - 1
        assert np.min(np.abs(d)) >= 1e-4 * (1 - 1e-9)
        assert np.min(d[d > 0]) <= 2e-4 and np.max(d[d < 0]) >= -2e-4
    assert all(res.undamped for res in r.resonances)


def test_damped_peaks_are_exact_local_maxima():
    r = sc.frf("building", input="floor3", output="floor3", transfer=False)
    from springchain._modules import system_of as _system
    from springchain.numeric.frf.response import operator, receptance

    system, _ = _system(sc.load("building"))
    op = operator(system)
    peaks = [res for res in r.resonances if res.peak_omega is not None]
    assert len(peaks) == 3
    for res in peaks:
        wp = res.peak_omega
        assert abs(wp / res.omega_d - 1) <= 3 * res.zeta
        side = np.abs(receptance(op, wp * (1 + np.array([-1e-6, 1e-6])), 2, 2))
        assert np.all(side < res.peak_magnitude)
        assert wp in r.omega  # the peak is a grid point
        assert res.peak_magnitude == pytest.approx(r.magnitude.max() if res is peaks[0] else res.peak_magnitude)
    # the peak magnitude beats every grid point within its half-power band
    for res in peaks:
        band = np.abs(r.omega / res.peak_omega - 1) <= res.zeta
        assert r.magnitude[band].max() <= res.peak_magnitude * (1 + 1e-12)


@pytest.mark.parametrize("inp,out", [("floor1", "floor3"), ("floor3", "floor3"), ("floor2", "floor1")])
def test_transfer_function_matches_numeric(inp, out):
    r = sc.frf("building", input=inp, output=out)
    assert r.transfer is not None
    h = np.array(r.transfer.evaluate(1j * r.omega))
    assert np.max(np.abs(h - r.H) / np.abs(r.H)) <= REL
    assert r.to_json()["transfer_function"]["latex"].startswith("\\begin{align*}")


def test_transfer_function_closed_form_one_mass(tmp_path):
    import sympy as sp

    path = tmp_path / "sdof.toml"
    path.write_text('name = "sdof"\n[parameters]\nm = 2.0\nk = 8.0\nc = 0.5\n[masses]\nx1 = "m"\n'
                    '[[springs]]\nbetween = ["x1", "wall"]\nk = "k"\n[[dampers]]\nbetween = ["x1", "wall"]\nc = "c"\n'
                    '[initial]\nx = [0.0]\nv = [0.0]\n')
    r = sc.frf(path, input="x1", output="x1")
    m, k, c, s = sp.symbols("m k c s")
    expr = r.transfer.expr.subs({sym: sp.Symbol(sym.name) for sym in r.transfer.expr.free_symbols})
    assert sp.simplify(expr - 1 / (m * s**2 + c * s + k)) == 0
    # and the cancellation: seed m1 -> m3 is k^2 / (s^2 M-stuff), no common factor left
    t = sc.frf("seed", input="m1", output="m3").transfer
    assert sp.gcd(sp.Poly(t.numerator, t.s), sp.Poly(t.denominator, t.s)).degree() == 0


def _chain_scene(tmp_path, n, left, right, name):
    text = chain_toml(n, left, right, name=name, parameters={"m": 1.5, "k": 3.0}, mass="m*(1 + i % 3)",
                      k="k*(2 + i % 2)", initial={"x": "0", "v": "0"}, simulation={"dt": 0.01, "steps": 10})
    return write_scene(tmp_path, name, text)


@pytest.mark.parametrize("left,right", [("free", "free"), ("wall", "free"), ("wall", "wall"), ("ring", "ring")])
def test_banded_chain_matches_dense(tmp_path, left, right):
    n = 37
    path = _chain_scene(tmp_path, n, left, right, f"ch_{left}_{right}")
    i = np.arange(n)
    M = np.diag(1.5 * (1 + i % 3))
    K = np.zeros((n, n))
    kk = lambda j: 3.0 * (2 + j % 2)  # noqa: E731  spring between j and j+1 (j = -1: the left wall)
    for j in range(n - 1):
        K[np.ix_([j, j + 1], [j, j + 1])] += kk(j) * np.array([[1, -1], [-1, 1]])
    if left == "wall":
        K[0, 0] += kk(-1)
    if right == "wall":
        K[-1, -1] += kk(n - 1)
    if left == "ring":
        K[np.ix_([n - 1, 0], [n - 1, 0])] += kk(n - 1) * np.array([[1, -1], [-1, 1]])
    r = sc.frf(path, input=3, output="20")
    from springchain._modules import system_of as _system
    from springchain.numeric.frf.response import operator

    op = operator(_system(sc.load(path))[0])
    assert op.banded and isinstance(op.K, tuple)  # bands, never an N x N matrix
    w = _pick(r.omega)
    ref = _reference(M, K, 0 * K, w, 3, 20)
    H = r.H[np.searchsorted(r.omega, w)]
    assert np.max(np.abs(H - ref) / np.abs(ref)) <= REL
    assert r.input == "3" and r.output == "20"


def test_long_chain_runs_banded(tmp_path):
    path = _chain_scene(tmp_path, 50_000, "wall", "free", "longchain")
    r = sc.frf(path, input=0, output=49_999, points=20)
    assert np.all(np.isfinite(r.H)) and r.omega.shape[0] >= 20
    assert len(r.resonances) <= 40


def test_cli_json_and_figure(tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["frf", "building", "--input", "floor1", "--output", "floor3", "--json", "--points", "50",
                 "--out", str(out)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert {"omega", "magnitude", "phase"} <= set(data)
    assert len(data["omega"]) == len(data["magnitude"]) == len(data["phase"]) >= 50
    api = sc.frf("building", input="floor1", output="floor3", points=50).to_json()
    np.testing.assert_allclose(data["magnitude"], api["magnitude"], rtol=1e-13)
    assert (out / "building-frf-floor1-floor3.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["frf", "seed", "--input", "m1", "--output", "m2", "--omega-min", "0.5", "--omega-max", "2",
                 "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "H(s) = X_m2(s)/F_m1(s)" in text and "\\frac" in text and "wrote" in text


@pytest.mark.parametrize("argv,needle", [
    (["frf", "building", "--input", "floor9", "--output", "floor1"], "--input: input 'floor9'"),
    (["frf", "building", "--input", "floor1", "--output", "roof"], "--output: output 'roof'"),
    (["frf", "chain100k", "--input", "100000", "--output", "0"], "index 0 ... 99999"),
    (["frf", "chain100k", "--input", "m1", "--output", "0"], "--input"),
    (["frf", "seed", "--input", "m1", "--output", "m2", "--omega-min", "abc"], "--omega-min"),
    (["frf", "seed", "--input", "m1", "--output", "m2", "--omega-max", "-1"], "--omega-max"),
    (["frf", "seed", "--input", "m1", "--output", "m2", "--omega-min", "3", "--omega-max", "2"], "omega_min 3 >= omega_max 2"),
    (["frf", "seed", "--input", "m1", "--output", "m2", "--points", "1"], "--points"),
    (["frf", "seed", "--output", "m2"], "--input"),
])
def test_cli_errors_one_line(tmp_path, capsys, argv, needle):
    one_line_error(*run_cli(argv + ["--out", tmp_path], capsys), needle)
    assert not any(tmp_path.iterdir())


def test_api_errors():
    with pytest.raises(sc.RunRefused, match="omega_min"):
        sc.frf("seed", input="m1", output="m2", omega_min=float("nan"))
    with pytest.raises(sc.RunRefused, match="not a mass"):
        sc.frf("seed", input=0, output="m2")


def test_plot_is_a_figure_without_pyplot():
    import matplotlib
    from matplotlib.figure import Figure

    before = matplotlib.get_backend()
    fig = sc.frf("building", input="floor3", output="floor3", transfer=False).plot()
    assert isinstance(fig, Figure)
    ax = fig.axes[0]
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    assert "rad/s" in fig.axes[1].get_xlabel() and "deg" in fig.axes[1].get_ylabel()
    assert matplotlib.get_backend() == before


@pytest.mark.parametrize("ring", [False, True])
def test_banded_solver_with_damping_matches_dense(ring):
    """The tridiagonal path with a damping band (and ring corners) against the dense solve."""
    from springchain.numeric.frf.response import Operator, receptance

    rng = np.random.default_rng(3)
    n = 25
    m = rng.uniform(0.5, 2.0, n)
    kd, ko = rng.uniform(2, 4, n), -rng.uniform(0.5, 1.0, n - 1)
    cd, co = rng.uniform(0.01, 0.1, n), -rng.uniform(0.0, 0.02, n - 1)
    kc, cc = (-0.7, -0.03) if ring else (0.0, 0.0)
    dense = lambda d, o, c: np.diag(d) + np.diag(o, 1) + np.diag(o, -1) + c * (np.eye(n, k=n - 1) + np.eye(n, k=1 - n))  # noqa: E731
    K, C = dense(kd, ko, kc), dense(cd, co, cc)
    op = Operator(m, (kd, ko, kc), (cd, co, cc), True)
    w = np.geomspace(0.1, 5.0, 200)
    got = receptance(op, w, 4, 17)
    ref = _reference(np.diag(m), K, C, w, 4, 17)
    assert np.max(np.abs(got - ref) / np.abs(ref)) <= REL


@pytest.mark.parametrize("certify", [False, True])
def test_chain_sweep_through_an_exact_float64_resonance_of_a_part(certify):
    """Two free unit masses on a unit spring at ω = 1: the left mass's dynamic stiffness −ω²m cancels
    the link exactly (u = k + e = 0 in float64). Was ZeroDivisionError in the compiled sweep; the
    true values are Z = [[0, −1], [−1, 0]], Z⁻¹ = [[0, −1], [−1, 0]]: H₁₁ = 0, H₀₁ = −1."""
    from springchain.numeric.frf.chain import chain_elements, chain_receptance

    el = chain_elements(np.ones(2), np.array([[0, 1]]), np.array([1.0]))
    h11 = chain_receptance(el, np.array([1.0]), 1, 1, certify=certify)[0]
    h01 = chain_receptance(el, np.array([1.0]), 0, 1, certify=certify)[0]
    assert abs(h11) <= 1e-15 and abs(h01 + 1) <= 1e-15
