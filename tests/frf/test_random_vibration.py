"""Random vibration (issue 37, item 5): RMS by the exact modal integral against Miles' equation, against
an extended-precision quadrature of |H|²G with H solved in mpmath from the elements, and against a
Monte-Carlo simulation driven by synthesized random loads; the psd command's one-line refusals.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
from helpers import one_line_error, run_cli

import springchain as sc


def sdof(tmp_path, m=2.0, k=800.0, zeta=0.05, damper=True):
    wn = math.sqrt(k / m)
    damp = (f'[[dampers]]\nbetween = ["m1", "wall"]\nc = {2 * zeta * wn * m!r}\n' if damper
            else f"[damping]\nrayleigh = [{2 * zeta * wn!r}, 0.0]\n")
    path = tmp_path / "sdof.toml"
    path.write_text(f'name = "sdof"\n[parameters]\n[masses]\nm1 = {m!r}\n[[springs]]\nbetween = ["wall", "m1"]\n'
                    f"k = {k!r}\n{damp}")
    return path, wn / (2 * math.pi)


@pytest.mark.parametrize("damper", [True, False])
def test_miles_equation_for_a_single_oscillator_under_a_wide_flat_band(tmp_path, damper):
    """Relative displacement under base acceleration G [(m/s²)²/Hz]: Miles, z_rms² = G Q / (32 π³ f_n³),
    exact for white noise; the band 1e-13 f_n ... 1e10 f_n leaves out less than 1e-12 of it."""
    zeta, G = 0.05, 0.1
    path, fn = sdof(tmp_path, zeta=zeta, damper=damper)
    r = sc.random_response(path, {"f": [1e-13 * fn, 1e10 * fn], "psd": [G, G]})
    Q = 1 / (2 * zeta)
    miles_z = math.sqrt(G * Q / (32 * math.pi**3 * fn**3))
    assert abs(r.rms("m1", "displacement") / miles_z - 1) < 1e-9
    # absolute acceleration: Miles' (π/2) f_n Q G with the 4ζ² its derivation drops (exact for white noise)
    miles_a = math.sqrt(math.pi / 2 * fn * Q * G * (1 + 4 * zeta**2))
    assert abs(r.rms("m1", "acceleration") / miles_a - 1) < 1e-9
    assert abs(r.rms("spring 0", "spring force") / (800.0 * miles_z) - 1) < 1e-9


def test_force_on_a_single_oscillator_under_a_wide_flat_band(tmp_path):
    m, k, zeta, G = 2.0, 800.0, 0.02, 3.0
    path, fn = sdof(tmp_path, m, k, zeta)
    wn = 2 * math.pi * fn
    r = sc.random_response(path, {"f": [1e-14 * fn, 1e10 * fn], "psd": [G, G]}, on="m1")
    exact = math.sqrt(G / (8 * zeta * wn**3 * m**2))  # σ_x² = π S0 / (2 ζ ω³ m²), S0 = G / (4π)
    assert abs(r.rms("m1", "displacement") / exact - 1) < 1e-9


def _mp_reference(masses, springs, dampers, f_pts, g_pts, pts, inp, out, kind, ground=False):
    """∫ G(f) |H(i2πf)|² df by mpmath.quad at 30 digits over intervals split at ``pts`` (breakpoints and
    resonances), H from (K − ω²M + iωC) X = b solved in mpmath (K and C stamped from the elements),
    G log-log between breakpoints."""
    mpmath.mp.dps = 30
    n = len(masses)

    def H(f):
        w = 2 * mpmath.pi * f
        Z = mpmath.matrix(n, n)
        for i in range(n):
            Z[i, i] = -w * w * masses[i]
        for (a, b), v, fac in [(e, v, 1) for e, v in springs] + [(e, v, 1j * w) for e, v in dampers]:
            for p, sp in ((a, 1), (b, -1)):
                for q, sq in ((a, 1), (b, -1)):
                    if p >= 0 and q >= 0:
                        Z[p, q] += sp * sq * fac * v
        rhs = mpmath.matrix([-masses[i] for i in range(n)]) if ground else mpmath.matrix([1 if i == inp else 0 for i in range(n)])
        X = mpmath.lu_solve(Z, rhs)
        if kind == "displacement":
            return X[out]
        return -w * w * X[out] + (1 if ground else 0)  # absolute acceleration for the base

    def G(f):
        for j in range(len(f_pts) - 1):
            if f_pts[j] <= f <= f_pts[j + 1]:
                al = mpmath.log(mpmath.mpf(g_pts[j + 1]) / g_pts[j]) / mpmath.log(mpmath.mpf(f_pts[j + 1]) / f_pts[j])
                return g_pts[j] * (f / f_pts[j]) ** al
        return 0

    return mpmath.sqrt(mpmath.quad(lambda f: G(f) * abs(H(f)) ** 2, pts))


def test_two_masses_with_a_dashpot_against_an_mpmath_quadrature(tmp_path):
    """Non-proportional damping (a dashpot between the masses), log-log slopes that are not whole
    numbers, a force input and a base input."""
    (tmp_path / "two.toml").write_text('''name = "two"
[parameters]
[masses]
a = 1.0
b = 3.0
[[springs]]
between = ["wall", "a"]
k = 1000.0
[[springs]]
between = ["a", "b"]
k = 400.0
[[dampers]]
between = ["a", "b"]
c = 1.5
[[dampers]]
between = ["wall", "a"]
c = 0.4
''')
    f_pts, g_pts = [0.5, 1.7, 3.1, 9.0, 40.0], [0.2, 1.3, 1.1, 0.35, 0.01]
    # breakpoints inside the band split the quadrature at the resonances too
    wn = np.sqrt(np.linalg.eigvals(np.diag([1, 1 / 3.0]) @ np.array([[1400.0, -400], [-400, 400]]))) / (2 * np.pi)
    pts = sorted(f_pts + [float(w) for w in wn])
    springs = [((-1, 0), 1000.0), ((0, 1), 400.0)]
    dampers = [((0, 1), 1.5), ((-1, 0), 0.4)]
    r = sc.random_response(tmp_path / "two.toml", np.column_stack([f_pts, g_pts]), on="b")
    for out, name in ((0, "a"), (1, "b")):
        ref = _mp_reference([1.0, 3.0], springs, dampers, f_pts, g_pts, pts, 1, out, "displacement")
        assert abs(r.rms(name, "displacement") / float(ref) - 1) < 1e-10, name
    rg = sc.random_response(tmp_path / "two.toml", np.column_stack([f_pts, g_pts]))
    for out, name in ((0, "a"), (1, "b")):
        ref = _mp_reference([1.0, 3.0], springs, dampers, f_pts, g_pts, pts, None, out, "acceleration", ground=True)
        assert abs(rg.rms(name, "acceleration") / float(ref) - 1) < 1e-10, name


def test_monte_carlo_rms_lands_within_its_statistical_error(tmp_path):
    """A force with a flat one-sided PSD G = 2σ²dt up to Nyquist, synthesized as Gaussian samples of
    variance σ² held over each step, drives the oscillator in a long simulation (scipy.signal.lsim, exact for
    piecewise-linear input); the mean square over many seeds lands within 3 standard errors of the
    exact value, and a 10 % wrong value lies outside."""
    from scipy import signal

    m, k, zeta = 1.0, (2 * math.pi) ** 2, 0.05  # f_n = 1 Hz
    path, fn = sdof(tmp_path, m, k, zeta)
    dt, T, seeds = 0.01, 400.0, 24
    f_c = 1 / (2 * dt)  # white up to Nyquist: one-sided G = 2 σ² dt
    sigma = 1.0
    G = 2 * sigma**2 * dt
    exact = sc.random_response(path, {"f": [1e-9, f_c], "psd": [G, G]}, on="m1").rms("m1", "displacement")
    wn, c = 2 * math.pi * fn, 2 * zeta * 2 * math.pi * fn * m
    sys_ = signal.StateSpace([[0, 1], [-k / m, -c / m]], [[0], [1 / m]], [[1, 0]], [[0]])
    t = np.arange(0, T, dt)
    skip = int(20 / (zeta * wn) / dt)  # drop the start-up transient (20 decay times)
    ms = []
    for seed in range(seeds):
        u = np.random.default_rng(seed).normal(0, sigma, t.shape[0])
        _, y, _ = signal.lsim(sys_, u, t, interp=False)  # zero-order hold: the samples' own white PSD
        ms.append(np.mean(y[skip:] ** 2))
    ms = np.asarray(ms)
    se = ms.std(ddof=1) / math.sqrt(seeds)
    # the hold and the sampling leave a bias O((f_n dt)²) ~ 1e-3, far inside the error bar
    assert abs(ms.mean() - exact**2) < 3 * se
    assert abs(ms.mean() - (1.1 * exact) ** 2) > 3 * se


def test_psd_command_g_units_and_one_line_refusals(tmp_path, capsys):
    pytest.importorskip("pint")
    path, fn = sdof(tmp_path)
    (tmp_path / "spec.csv").write_text("f [Hz], psd [g^2/Hz]\n1, 0.01\n100, 0.01\n")
    status, out, err = run_cli(["psd", path, "--input", tmp_path / "spec.csv", "--json"], capsys)
    assert status == 0, err
    import json

    data = json.loads(out)
    acc = [row for row in data["rms"] if row["kind"] == "acceleration"][0]
    assert acc["unit"] == "g" and data["input_unit"] == "g"
    assert data["input_rms"] == pytest.approx(math.sqrt(0.01 * 99), rel=1e-12)
    si = sc.random_response(path, {"f": [1.0, 100.0], "psd": [0.01 * 9.80665**2] * 2})
    assert acc["rms"] == pytest.approx(si.rms("m1", "acceleration") / 9.80665, rel=1e-12)
    (tmp_path / "bad.csv").write_text("f [Hz], psd [kg^2/Hz]\n1, 0.01\n100, 0.01\n")
    one_line_error(*run_cli(["psd", path, "--input", tmp_path / "bad.csv"], capsys), "bad.csv", "--input",
                   "column psd [kg^2/Hz]")
    (tmp_path / "dec.csv").write_text("f,psd\n10, 0.01\n1, 0.01\n")
    one_line_error(*run_cli(["psd", path, "--input", tmp_path / "dec.csv"], capsys), "not strictly increasing")
    one_line_error(*run_cli(["psd", path, "--input", tmp_path / "none.csv"], capsys), "cannot read")
    one_line_error(*run_cli(["psd", "seed", "--input", tmp_path / "spec.csv"], capsys), "rigid-body")


def test_units_as_the_command_line_writes_them(tmp_path):
    """``units="mm,kN,g"`` in to_text, to_json and plot: displacements in mm (1e3 per m), spring forces in
    kN (1e-3 per N), accelerations in g (1/9.80665 per m/s², standard gravity, written here)."""
    pytest.importorskip("pint")
    from springchain.derive.errors import SceneError

    path, fn = sdof(tmp_path)
    r = sc.random_response(path, {"f": [1.0, 100.0], "psd": [0.5, 0.5]})
    rows = {row["kind"]: row for row in r.to_json("mm,kN,g")["rms"]}
    assert rows["displacement"]["unit"] == "mm" and rows["spring force"]["unit"] == "kN"
    assert rows["displacement"]["rms"] == pytest.approx(1e3 * r.rms("m1", "displacement"), rel=1e-14)
    assert rows["spring force"]["rms"] == pytest.approx(1e-3 * r.rms("spring 0", "spring force"), rel=1e-14)
    assert rows["acceleration"]["unit"] == "g"
    assert rows["acceleration"]["rms"] == pytest.approx(r.rms("m1", "acceleration") / 9.80665, rel=1e-14)
    assert r.to_json(["mm", "kN", "g"]) == r.to_json("mm,kN,g")
    text = r.to_text("mm,kN,g")
    assert "RMS displacement (relative to the base) [mm]" in text and "[kN]" in text
    fig = r.plot("displacement", "mm,kN,g")
    assert fig.axes[1].get_ylabel() == "response PSD [mm²/Hz]" and fig.axes[0].get_ylabel() == "input PSD [g²/Hz]"
    with pytest.raises(SceneError, match="units: 'mm,zorks': unknown unit"):
        r.to_text("mm,zorks")


def test_the_input_keeps_the_unit_its_file_gave(tmp_path, capsys):
    """A force PSD in kN²/Hz reports its input RMS in kN (√(0.01 · 99) kN) and spring forces in kN (the SI
    run with 0.01e6 N²/Hz, over 1000); a base acceleration in (mm/s²)²/Hz reports its input in mm/s² and
    accelerations in mm/s² (SI × 1000); other outputs stay SI; ``units=`` still wins."""
    pytest.importorskip("pint")
    import json

    path, fn = sdof(tmp_path)
    (tmp_path / "kn.csv").write_text("f [Hz], psd [kN^2/Hz]\n1, 0.01\n100, 0.01\n")
    status, out, err = run_cli(["psd", path, "--input", tmp_path / "kn.csv", "--on", "m1", "--json",
                                "--no-figures"], capsys)
    assert status == 0, err
    data = json.loads(out)
    assert data["input_unit"] == "kN" and data["input_rms"] == pytest.approx(math.sqrt(0.01 * 99), rel=1e-12)
    si = sc.random_response(path, {"f": [1.0, 100.0], "psd": [0.01e6] * 2}, on="m1")
    rows = {row["kind"]: row for row in data["rms"]}
    assert rows["spring force"]["unit"] == "kN" and rows["displacement"]["unit"] == "m"
    assert rows["spring force"]["rms"] == pytest.approx(si.rms("spring 0", "spring force") / 1e3, rel=1e-12)
    assert rows["displacement"]["rms"] == pytest.approx(si.rms("m1", "displacement"), rel=1e-12)
    (tmp_path / "mm.csv").write_text("f [Hz], psd [(mm/s^2)^2/Hz]\n1, 0.01\n100, 0.01\n")
    r = sc.random_response(path, tmp_path / "mm.csv")
    data = r.to_json()
    assert data["input_unit"] == "mm/s^2" and data["input_rms"] == pytest.approx(math.sqrt(0.01 * 99), rel=1e-12)
    si = sc.random_response(path, {"f": [1.0, 100.0], "psd": [0.01e-6] * 2})
    acc = [row for row in data["rms"] if row["kind"] == "acceleration"][0]
    assert acc["unit"] == "mm/s^2" and acc["rms"] == pytest.approx(1e3 * si.rms("m1", "acceleration"), rel=1e-12)
    assert r.to_json("m")["input_unit"] == "m/s^2"  # units= chooses
    (tmp_path / "odd.csv").write_text("f [Hz], psd [N^2*s]\n1, 0.01\n100, 0.01\n")  # no U^2/Hz form: SI shown
    assert sc.random_response(path, tmp_path / "odd.csv", on="m1").to_json()["input_unit"] == "N"
