"""Response-spectrum analysis (issue 20, item 5) and the time-history storey outputs (item 6).

Independent references, built in the test from the scene's TOML text: modes from the 60-digit
mpmath solution (tests/modes_reference.py), each modal oscillator integrated by DOP853 on the
record; Der Kiureghian's correlation written out here for equal damping; drifts and forces from
the positions and the spring list; the base shear against Newton's law on the absolute
accelerations.
"""

from __future__ import annotations

import json
import subprocess
import sys

import mpmath
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import springchain as sc
from modes_reference import reference as mp_reference

SCENE = """name = "{name}"
description = "shear building for RSA tests"
[parameters]
m1 = {m1!r}
m2 = {m2!r}
k1 = {k1!r}
k2 = {k2!r}
[masses]
a = "m1"
b = "m2"
[[springs]]
between = ["wall", "a"]
k = "k1"
[[springs]]
between = ["a", "b"]
k = "k2"
[damping]
rayleigh_targets = {{zeta = [0.05, 0.05], modes = [1, 2]}}
[ground]
table = "rec.csv"
[simulation]
dt = 0.005
steps = 400
"""


def _files(tmp_path, m1=2.0e4, m2=1.0e4, k1=6.0e6, k2=3.0e6, name="two"):
    rng = np.random.default_rng(3)
    t = np.arange(101) * 0.02
    a = rng.normal(0, 2.0, t.shape) * np.sin(np.pi * t / t[-1])
    (tmp_path / "rec.csv").write_text("t,a\n" + "".join(f"{float(x)!r},{float(y)!r}\n" for x, y in zip(t, a)))
    p = tmp_path / f"{name}.toml"
    p.write_text(SCENE.format(name=name, m1=m1, m2=m2, k1=k1, k2=k2))
    return p, t, a, (m1, m2, k1, k2)


def _sdof_peak(t, a, w, z):
    y = np.zeros(2)
    best = 0.0
    for i in range(len(t) - 1):
        sl = (a[i + 1] - a[i]) / (t[i + 1] - t[i])
        s = solve_ivp(lambda tt, q: [q[1], -2 * z * w * q[1] - w * w * q[0] - (a[i] + sl * (tt - t[i]))],
                      (t[i], t[i + 1]), y, method="DOP853", rtol=1e-13, atol=1e-16, dense_output=True)
        y = s.y[:, -1]
        best = max(best, np.max(np.abs(s.sol(np.linspace(t[i], t[i + 1], 200))[0])))
    s = solve_ivp(lambda tt, q: [q[1], -2 * z * w * q[1] - w * w * q[0]], (t[-1], t[-1] + 4 * np.pi / w), y,
                  method="DOP853", rtol=1e-13, atol=1e-16, dense_output=True)
    return max(best, np.max(np.abs(s.sol(np.linspace(t[-1], t[-1] + 4 * np.pi / w, 4000))[0])))


def test_modal_peaks_against_independent_oscillators(tmp_path):
    p, t, a, (m1, m2, k1, k2) = _files(tmp_path)
    res = sc.rsa(str(p), spectrum=str(tmp_path / "rec.csv"))
    w2, S = mp_reference([m1, m2], [(-1, 0, k1), (0, 1, k2)])
    with mpmath.workdps(60):
        w = [float(mpmath.sqrt(x)) for x in w2]
        gamma = [float(m1 * S[0, j] + m2 * S[1, j]) for j in range(2)]
        phi = [[float(S[i, j]) for i in range(2)] for j in range(2)]
    r = res.result
    assert np.allclose(r.modes.zeta, 0.05, rtol=1e-12)  # Rayleigh from targets at both modes
    for j in range(2):
        sd = _sdof_peak(t, a, w[j], 0.05)
        assert r.sd[j] == pytest.approx(sd, rel=2e-7)  # the reference samples 200 points per row
        ref_u = np.abs(gamma[j] * sd * np.array(phi[j]))
        assert np.allclose(np.abs(r.displacement[j]), ref_u, rtol=2e-7)
        # base shear of mode j = M*_j PSA_j = sum of the wall spring force
        assert abs(r.base_shear[j]) == pytest.approx(gamma[j] ** 2 * w[j] ** 2 * sd, rel=2e-7)
        assert abs(r.spring_force[j][0]) == pytest.approx(k1 * ref_u[0], rel=2e-7)
        assert abs(r.drift[j][1]) == pytest.approx(abs(gamma[j] * sd * (phi[j][1] - phi[j][0])), rel=2e-7)
    assert r.modes.effective_mass.sum() == pytest.approx(m1 + m2, rel=1e-14)


def _rho_equal_damping(r, z):
    """Der Kiureghian's coefficient for equal damping, written out independently."""
    return 8 * z * z * (1 + r) * r**1.5 / ((1 - r * r) ** 2 + 4 * z * z * r * (1 + r) ** 2)


def test_cqc_correlation_formula():
    from springchain.numeric.structural.rsa import cqc_correlation

    w = np.array([1.0, 1.05, 3.0, 20.0])
    rho = cqc_correlation(w, np.full(4, 0.05))
    for i in range(4):
        for j in range(4):
            ref = 1.0 if i == j else _rho_equal_damping(w[j] / w[i], 0.05)
            assert rho[i, j] == pytest.approx(ref, rel=1e-14)
    assert np.allclose(rho, rho.T, rtol=1e-14)
    assert rho[0, 1] > 0.8 and rho[0, 3] < 1e-3


def test_cqc_reduces_to_srss_for_separated_modes_and_differs_for_close_ones(tmp_path):
    # well separated: a stiff upper storey (omega ratio ~ 4.5), 5 % damping
    sep, *_ = _files(tmp_path, m1=1e4, m2=1e4, k1=1e6, k2=2e7, name="sep")
    r = sc.rsa(str(sep), spectrum=str(tmp_path / "rec.csv")).result
    rho12 = r.rho[0, 1]
    assert rho12 < 0.01
    from springchain.numeric.structural.rsa import Combination

    srss, cqc = r.combined(Combination.SRSS), r.combined(Combination.CQC)
    R = r.base_shear
    assert abs(cqc["base_shear"] - srss["base_shear"]) <= rho12 * abs(R[0] * R[1]) / srss["base_shear"] + 1e-9
    # close modes: a heavy lower floor on a soft spring beside a light upper floor tuned near it
    close, *_ = _files(tmp_path, m1=1e4, m2=1e2, k1=4e6, k2=3.6e4, name="close")
    r = sc.rsa(str(close), spectrum=str(tmp_path / "rec.csv")).result
    assert r.modes.omega[1] / r.modes.omega[0] < 1.3 and r.rho[0, 1] > 0.3
    srss, cqc = r.combined(Combination.SRSS), r.combined(Combination.CQC)
    rho = _rho_equal_damping(r.modes.omega[1] / r.modes.omega[0], 0.05)
    for q in ("displacement", "drift", "spring_force"):
        R = getattr(r, q)
        ref = np.sqrt(R[0] ** 2 + R[1] ** 2 + 2 * rho * R[0] * R[1])
        assert np.allclose(cqc[q], ref, rtol=1e-12)
        assert np.allclose(srss[q], np.sqrt(R[0] ** 2 + R[1] ** 2), rtol=1e-14)
    assert abs(cqc["drift"][1] - srss["drift"][1]) > 0.05 * srss["drift"][1]


def test_design_spectrum_and_cli(tmp_path):
    p, *_ = _files(tmp_path)
    (tmp_path / "design.csv").write_text("T,Sa\n0,3.0\n0.5,7.5\n4,1.0\n")
    out = subprocess.run([sys.executable, "-m", "springchain", "rsa", str(p), "--spectrum", str(tmp_path / "design.csv"),
                          "--combine", "srss", "--json"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    for mode in data["modes"]:
        sa = np.interp(mode["period"], [0, 0.5, 4], [3.0, 7.5, 1.0])
        assert mode["psa"] == pytest.approx(sa, rel=1e-14)
        assert abs(mode["base_shear"]) == pytest.approx(mode["effective_mass"] * sa, rel=1e-12)
    assert data["result"] == data["srss"] and data["combination"] == "srss"
    (tmp_path / "short.csv").write_text("T,Sa\n0.5,7.5\n4,1.0\n")
    bad = subprocess.run([sys.executable, "-m", "springchain", "rsa", str(p), "--spectrum", str(tmp_path / "short.csv")],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "--spectrum: " in bad.stderr
    assert "outside the design spectrum's periods" in bad.stderr
    (tmp_path / "odd.csv").write_text("x,y\n0,1\n1,2\n")
    bad = subprocess.run([sys.executable, "-m", "springchain", "rsa", str(p), "--spectrum", str(tmp_path / "odd.csv")],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "accepted: a record CSV with the header 't,a'" in bad.stderr


def test_free_scene_refused():
    with pytest.raises(sc.RunRefused, match="free piece"):
        sc.rsa("seed", spectrum=([0.0, 10.0], [1.0, 1.0]))


def test_time_history_outputs(tmp_path):
    """drifts, spring forces, base shear of a simulation; the NPZ keys of --springs; and the base shear
    (wall springs + the wall dashpot) equals -sum m_i aabs_i (Newton on the whole building)."""
    import tomllib

    scene_path = tmp_path / "bq.toml"
    text = (sc.load("building_quake").file and open(sc.load("building_quake").file).read())
    scene_path.write_text(text.replace('table = "quake-record.csv"', 'table = "rec.csv"').replace("steps = 5000",
                                                                                                   "steps = 400"))
    _files(tmp_path)  # writes rec.csv
    run = sc.simulate(str(scene_path), methods=["modal"], out=tmp_path / "out", springs=True)
    data = np.load(run.npz)
    for key in ("drift_modal", "spring_force_modal", "base_shear_modal"):
        assert key in data.files
    toml = tomllib.loads(text)
    names = list(toml["masses"])
    k = toml["parameters"]["k"]
    x = run.x["modal"]
    ends = [[-1 if e == "wall" else names.index(e) for e in s["between"]] for s in toml["springs"]]
    col = lambda e: np.zeros(x.shape[0]) if e < 0 else x[:, e]  # noqa: E731
    drift = np.stack([col(b) - col(a) for a, b in ends], axis=1)
    assert np.array_equal(run.drifts("modal"), drift) and np.array_equal(data["drift_modal"], drift)
    assert np.allclose(run.spring_forces("modal"), k * drift, rtol=1e-15)
    assert np.allclose(run.base_shear("modal"), k * x[:, 0], rtol=1e-15)
    c = toml["parameters"]["c"]
    m = toml["parameters"]["m"]
    total = run.base_shear("modal") + c * run.v["modal"][:, 0]
    newton = -m * run.extra["aabs_modal"].sum(axis=1)
    assert np.allclose(total, newton, rtol=1e-9, atol=1e-9 * np.abs(newton).max())


def test_springs_on_a_chain(tmp_path):
    """--springs on a streamed [chain] run (exact and Newmark): drifts from the frames, the NPZ rewritten
    with them, and the base shear (the wall spring) equal to -sum m aabs_i (Newton; no dashpots)."""
    _files(tmp_path)  # writes rec.csv
    m, k, n = 1000.0, 4.0e6, 40
    path = tmp_path / "cq.toml"
    path.write_text(f'name = "cq"\n[parameters]\nm = {m!r}\nk = {k!r}\n[chain]\nn = {n}\nmass = "m"\nk = "k"\n'
                    'left = "wall"\nright = "free"\n[ground]\ntable = "rec.csv"\n[simulation]\ndt = 0.005\nsteps = 300\n')
    run = sc.simulate(str(path), methods=["modal", "newmark"], out=tmp_path / "out", springs=True, progress=False)
    data = np.load(run.npz)
    for method in ("modal", "newmark"):
        x = run.x[method]
        wall_first = np.diff(np.concatenate([np.zeros((x.shape[0], 1)), x], axis=1), axis=1)
        drift = data[f"drift_{method}"]
        assert drift.shape == (x.shape[0], n) and np.array_equal(np.abs(drift), np.abs(wall_first))
        assert np.allclose(data[f"spring_force_{method}"], k * drift, rtol=1e-15, atol=0)
        newton = -m * run.extra[f"aabs_{method}"].sum(axis=1)
        assert np.allclose(data[f"base_shear_{method}"], newton, rtol=1e-9, atol=1e-9 * np.abs(newton).max())
        assert np.array_equal(run.base_shear(method), data[f"base_shear_{method}"])
