"""Response spectra (issue 20, item 4): every ordinate against a damped oscillator integrated by
DOP853 at tight tolerance, piece by piece between the record's rows (``np.interp`` of the CSV
written in the test), with the peak of |u| searched on the dense output and refined; the free
vibration after the record is integrated too."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

import springchain as sc


def _record(tmp_path, uniform=True, rows=121, seed=7):
    rng = np.random.default_rng(seed)
    if uniform:
        t = np.round(np.arange(rows) * 0.02, 10)
    else:
        t = np.concatenate([[0.0], np.cumsum(rng.uniform(0.005, 0.03, rows - 1))])
    a = rng.normal(0.0, 2.0, rows) * np.sin(np.pi * t / t[-1])
    a[0] = a[-1] = 0.0
    path = tmp_path / ("rec.csv" if uniform else "recnu.csv")
    path.write_text("t,a\n" + "".join(f"{float(ti)!r},{float(ai)!r}\n" for ti, ai in zip(t, a)))
    data = np.loadtxt(path, delimiter=",", skiprows=1)  # what the file says, read independently
    return path, data[:, 0], data[:, 1]


def _dop853_sd(t, a, T, z):
    """max |u| of ü + 2ζωu̇ + ω²u = −a_g(t) from rest, a_g linear between rows and 0 after."""
    w = 2 * np.pi / T

    def f(tt, y, slope, a0, t0):
        return [y[1], -2 * z * w * y[1] - w * w * y[0] - (a0 + slope * (tt - t0))]

    y = np.zeros(2)
    segments = []
    for i in range(len(t) - 1):
        slope = (a[i + 1] - a[i]) / (t[i + 1] - t[i])
        s = solve_ivp(f, (t[i], t[i + 1]), y, method="DOP853", rtol=1e-13, atol=1e-15 * max(T * T, 1e-3),
                      dense_output=True, args=(slope, a[i], t[i]))
        y = s.y[:, -1]
        segments.append(s.sol)
    s = solve_ivp(f, (t[-1], t[-1] + 1.5 * T), y, method="DOP853", rtol=1e-13, atol=1e-15 * max(T * T, 1e-3),
                  dense_output=True, args=(0.0, 0.0, t[-1]))
    segments.append(s.sol)
    best = []
    for sol in segments:
        tt = np.linspace(sol.t_min, sol.t_max, max(20, int(64 * (sol.t_max - sol.t_min) / T)))
        u = np.abs(sol(tt)[0])
        j = int(np.argmax(u))
        best.append((u[j], sol, tt, j))
    best.sort(key=lambda b: -b[0])
    out = best[0][0]
    for val, sol, tt, j in best[:4]:
        lo, hi = tt[max(j - 1, 0)], tt[min(j + 1, len(tt) - 1)]
        r = minimize_scalar(lambda x: -abs(sol(x)[0]), bounds=(lo, hi), method="bounded",
                            options={"xatol": 1e-13 * max(abs(hi), 1)})
        out = max(out, -r.fun)
    return out


PERIODS = [0.01, 0.04, 0.1, 0.25, 0.6, 1.5, 4.0]
ZETAS = [0.02, 0.05]


def test_every_ordinate_against_dop853(tmp_path):
    path, t, a = _record(tmp_path)
    res = sc.response_spectrum(path, zeta=ZETAS, periods=PERIODS)
    assert res.sd.shape == (2, len(PERIODS))
    worst = 0.0
    for zi, z in enumerate(ZETAS):
        for pj, T in enumerate(PERIODS):
            ref = _dop853_sd(t, a, T, z)
            err = abs(res.sd[zi, pj] - ref) / ref
            worst = max(worst, err)
            assert err <= 1e-9, (T, z, res.sd[zi, pj], ref)
    w = 2 * np.pi / np.array(PERIODS)
    assert np.allclose(res.psv, res.sd * w, rtol=1e-15) and np.allclose(res.psa, res.sd * w**2, rtol=1e-15)
    print(f"worst relative SD error against DOP853: {worst:.1e}")


def test_unequal_rows_against_dop853(tmp_path):
    path, t, a = _record(tmp_path, uniform=False, rows=80)
    res = sc.response_spectrum(path, zeta=[0.05], periods=[0.05, 0.5, 2.0])
    for pj, T in enumerate([0.05, 0.5, 2.0]):
        ref = _dop853_sd(t, a, T, 0.05)
        assert res.sd[0, pj] == pytest.approx(ref, rel=1e-9)


def test_limits_and_linearity(tmp_path):
    path, t, a = _record(tmp_path)
    res = sc.response_spectrum(path, zeta=[0.05], periods=[1e-4, 1.0])
    # a very stiff oscillator follows the ground: PSA -> PGA
    assert res.psa[0, 0] == pytest.approx(np.max(np.abs(a)), rel=1e-3)
    doubled = sc.response_spectrum((t, 3.0 * a), zeta=[0.05], periods=[1e-4, 1.0])
    assert np.allclose(doubled.sd, 3.0 * res.sd, rtol=1e-13)


def test_cli_json_and_files(tmp_path):
    path, _, _ = _record(tmp_path)
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, "-m", "springchain", "spectrum", str(path), "--zeta", "0.05", "--zeta", "0.1",
                        "--periods", "0.1:2:5", "--json", "--out", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    data = json.loads(r.stdout)
    assert set(data) >= {"periods", "zeta", "sd", "psv", "psa", "pga"}
    assert len(data["periods"]) == 5 and np.array(data["sd"]).shape == (2, 5)
    assert (out / "rec-spectrum.png").stat().st_size > 0 and (out / "rec-spectrum.json").exists()


@pytest.mark.parametrize("args, fragment", [
    (["--zeta", "1.5"], "--zeta '1.5': accepted: a damping ratio 0 <= zeta < 1"),
    (["--periods", "1:0.1:5"], "--periods: periods '1:0.1:5': accepted"),
    (["--periods", "a,b"], "--periods: periods 'a,b': accepted"),
])
def test_cli_refusals(tmp_path, args, fragment):
    path, _, _ = _record(tmp_path)
    r = subprocess.run([sys.executable, "-m", "springchain", "spectrum", str(path), *args, "--out", str(tmp_path)],
                       capture_output=True, text=True)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and fragment in r.stderr, r.stderr


def test_bad_record_one_line(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("t,a\n0,1\n0,2\n1,3\n")
    r = subprocess.run([sys.executable, "-m", "springchain", "spectrum", str(bad)], capture_output=True, text=True)
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "times not strictly increasing" in r.stderr and "accepted" in r.stderr
