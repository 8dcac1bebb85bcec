"""Model updating and chain reconstruction (issue 36), against references written here.

* Exact synthetic data (frequencies and shapes of the true scene from 50-digit mpmath eigenpairs of its
  TOML text) recover the parameters to 1e-10.
* Noisy synthetic data: over many seeds the fitted parameters land within the reported uncertainty at
  the nominal rate — binomial and χ² tests whose false-failure probability is stated at each check.
* Parameters the data cannot fix are reported as such (a combination named), not given wild values.
* Bad measured files and spectra: one line, exit status 2.
* Reconstruction: random chains from 50-digit spectra to 1e-12; from float64 spectra within the stated
  bound; non-interlacing spectra refused.
"""

from __future__ import annotations

import json

import mpmath
import numpy as np
import pytest
from helpers import one_line_error, run_cli, scene_toml
from sensitivity_reference import Reference

import springchain as sc
from springchain.numeric.updating.measured import Measured

#: The worked example: five storeys, storeys 2 and 4 weaker than designed.
NOMINAL = {"m": 2.0e4, "k1": 3.0e7, "k2": 3.0e7, "k3": 3.0e7, "k4": 3.0e7, "k5": 3.0e7}
TRUE = dict(NOMINAL, k2=2.4e7, k4=2.1e7)


def storeys(params: dict, n: int = 5) -> str:
    masses = {f"f{i}": ("0.8*m" if i == n else "m") for i in range(1, n + 1)}
    springs = [{"between": ["wall" if i == 1 else f"f{i - 1}", f"f{i}"], "k": f"k{i}"} for i in range(1, n + 1)]
    return ("# a shear building: floors f1 ... (the top one lighter), storey stiffnesses k1 ... (k1 to the ground)\n"
            + scene_toml("storeys", params, masses=masses, springs=springs))


def true_modes(text: str, dps: int = 50):
    """ω (rad/s) and M-normalised shapes of the scene in the text, from mpmath (independent of springchain)."""
    with mpmath.workdps(dps):
        w2, shapes, _ = Reference(text).modes()
        return np.array([float(mpmath.sqrt(x)) for x in w2]), np.array([[float(c) for c in s] for s in shapes]).T


def measured_csv(path, omega, shapes=None, sensors=(), omega_std=None, shape_std=None):
    head = ["omega"] + (["omega_std"] if omega_std is not None else []) + \
        (["shape_std"] if shape_std is not None else []) + list(sensors)
    rows = [",".join(head)]
    for j, w in enumerate(omega):
        cells = [repr(float(w))]
        if omega_std is not None:
            cells.append(repr(float(omega_std[j])))
        if shape_std is not None:
            cells.append(repr(float(shape_std)))
        if shapes is not None:
            cells += [repr(float(v)) for v in shapes[:, j]]
        rows.append(",".join(cells))
    path.write_text("\n".join(rows) + "\n")
    return path


def test_exact_synthetic_data_recover_the_parameters_to_1e_10(tmp_path):
    """The worked example: the nominal design fitted to exact frequencies and shapes at three floors of the
    building with storeys 2 and 4 weakened (20 % and 30 %) comes back to the true stiffnesses."""
    nominal = tmp_path / "storeys.toml"
    nominal.write_text(storeys(NOMINAL))
    omega, phi = true_modes(storeys(TRUE))
    sensors = ("f1", "f3", "f5")
    meas = measured_csv(tmp_path / "m.csv", omega, phi[[0, 2, 4]], sensors, omega_std=1e-3 * omega, shape_std=0.01)
    r = sc.update(nominal, meas, parameters="k1,k2,k3,k4,k5", out=tmp_path / "out")
    for p, v in zip(r.parameters, r.values):
        assert abs(v / TRUE[p] - 1) <= 1e-10, (p, v)
    assert r.fit.chi2 < 1e-16 and all(r.fit.identifiable)
    assert np.all(np.abs(r.omega_after / omega - 1) < 1e-12) and np.all(r.mac_after > 1 - 1e-14)
    assert list(r.modes) == [0, 1, 2, 3, 4]
    # the updated scene file: written, comments kept, loads with the fitted values
    path = tmp_path / "out" / "storeys-updated.toml"
    text = path.read_text()
    assert text.startswith("# a shear building") and (tmp_path / "out" / "storeys-update.png").stat().st_size > 0
    back = sc.load(path)
    assert back.parameters["k4"] == pytest.approx(2.1e7, rel=1e-10) and back.parameters["m"] == 2.0e4


def test_noisy_data_land_within_the_reported_uncertainty_at_the_nominal_rate(tmp_path):
    """60 noise draws (σ = 0.2 % of each frequency, 1 % on each normalised shape value at two floors) on a
    three-storey building, three stiffnesses fitted each time.

    Under the linearised theory the fitted log-parameters are Gaussian with the reported covariance, so
    (a) the joint statistic d = Δθᵀ Cov⁻¹ Δθ exceeds the χ²₃ 95 % quantile with probability 5 %, (b) each
    parameter misses its ±1.96 SE interval with probability 5 %, (c) Σ d is χ² with 3 × 60 degrees of
    freedom (180). Each count is checked against its binomial (χ²) distribution with acceptance bounds whose
    false-failure probability is at most 1e-4 per check, 5e-4 for the five checks together (the noise
    level keeps the nonlinearity far below what these tests can see).
    """
    from scipy import stats

    text = storeys(dict(m=1.0e4, k1=2.0e7, k2=1.5e7, k3=1.0e7), n=3)
    true = {"k1": 2.0e7, "k2": 1.5e7, "k3": 1.0e7}
    omega, phi = true_modes(text)
    sensors = ("f2", "f3")
    shapes = phi[[1, 2]] / np.max(np.abs(phi[[1, 2]]), axis=0)
    path = tmp_path / "storeys.toml"
    path.write_text(text)
    from springchain._updating import prepare

    setup = prepare(path, "k1,k2,k3")
    rng = np.random.default_rng(2024)
    seeds, d_all, misses = 60, [], np.zeros(3, int)
    joint = 0
    limit = stats.chi2.ppf(0.95, 3)
    theta_true = np.log([true[p] for p in ("k1", "k2", "k3")])
    for _ in range(seeds):
        sd = 2e-3 * omega
        noisy = omega + sd * rng.standard_normal(3)
        s = shapes + 0.01 * rng.standard_normal(shapes.shape)
        m = Measured("synthetic", noisy, sd, sensors, s, np.full(3, 0.01))
        r = sc.update(path, m, parameters="k1,k2,k3", out=None, setup=setup)
        dtheta = np.log(r.values) - theta_true
        d = float(dtheta @ np.linalg.solve(r.fit.covariance_log, dtheta))
        d_all.append(d)
        joint += d > limit
        misses += np.abs(r.values - np.exp(theta_true)) > 1.96 * r.standard_errors
    lo, hi = stats.binom.ppf(5e-5, seeds, 0.05), stats.binom.isf(5e-5, seeds, 0.05)
    assert lo <= joint <= hi, (joint, lo, hi)
    for count in misses:
        assert lo <= count <= hi, (misses, lo, hi)
    total = sum(d_all)
    assert stats.chi2.ppf(5e-5, 3 * seeds) <= total <= stats.chi2.isf(5e-5, 3 * seeds), total


def test_unidentifiable_parameters_are_reported_not_fitted_wild(tmp_path):
    """Two springs from one mass to the walls act together (only k1 + k2 moves the frequencies), and k with
    m changes no ω² of the reference scene when both scale alike: each is reported as a named combination
    the data do not fix, kept at its start, with no standard error — while the combination the data do fix
    is fitted."""
    text = scene_toml("pair", {"m": 1.0, "k1": 2.0, "k2": 3.0, "k3": 1.0}, masses={"a": "m", "b": "2*m"},
                      springs=[{"between": ["wall", "a"], "k": "k1"}, {"between": ["a", "wall"], "k": "k2"},
                               {"between": ["a", "b"], "k": "k3"}])
    scene = tmp_path / "pair.toml"
    scene.write_text(text)
    omega, _ = true_modes(text.replace("k1 = 2.0", "k1 = 2.5"))  # the truth: k1 + k2 = 5.5
    meas = measured_csv(tmp_path / "m.csv", omega, omega_std=1e-4 * omega)
    r = sc.update(scene, meas, parameters="k1,k2", out=None)
    ident = r.identifiability()
    assert len(ident["unidentifiable"]) == 1 and "log k1" in ident["unidentifiable"][0]
    assert not any(r.fit.identifiable) and np.all(np.isnan(r.standard_errors))
    assert abs(r.values.sum() / 5.5 - 1) < 1e-9  # the combination the frequencies fix: k1 + k2
    assert 2.0 < r.values[0] < 3.5 and 2.0 < r.values[1] < 3.5  # moved along the fixed direction only
    text_out = r.to_text()
    assert "not identifiable" in text_out and "fixed by the data" in text_out
    meas2 = measured_csv(tmp_path / "m2.csv", [1.0005, 1.2905])
    r2 = sc.update("seed", meas2, parameters="k,m", out=None)
    combo = r2.identifiability()["unidentifiable"][0]
    assert combo.startswith("+0.707·log k +0.707·log m")


def test_bad_measured_files_are_refused_in_one_line(tmp_path, capsys):
    cases = {
        "missing.csv": ("floor1,floor3\n1.0,2.0\n", "exactly one of the columns 'omega'"),
        "nan.csv": ("omega\nnan\n", "'nan' is not a number"),
        "neg.csv": ("omega\n-3\n", "is not > 0"),
        "ragged.csv": ("omega,floor1\n9.0\n", "1 cells for 2 columns"),
        "sensor.csv": ("omega,roof\n9.0,1.0\n", "'roof'"),
        "empty.csv": ("# nothing\n", "empty"),
        "many.csv": ("omega\n" + "\n".join(str(float(i)) for i in range(1, 5)) + "\n", "4 measured modes"),
        "std.csv": ("omega,shape_std,floor1\n9.0,0.1,1.0\n", "shape_std"),
    }
    for name, (body, words) in cases.items():
        path = tmp_path / name
        path.write_text(body)
        status, out, err = run_cli(["update", "building", "--measured", path, "--parameters", "k",
                                    "--out", tmp_path / "o"], capsys)
        one_line_error(status, out, err, words)
    path = tmp_path / "two.csv"
    path.write_text("omega\n9.0\n25.0\n")
    status, out, err = run_cli(["update", "building", "--measured", path, "--parameters", "k", "--modes", "3",
                                "--out", tmp_path / "o"], capsys)
    one_line_error(status, out, err, "more modes asked than measured")
    status, out, err = run_cli(["update", "building", "--measured", path, "--parameters", "k",
                                "--bounds", "k=5e6:1e7", "--out", tmp_path / "o"], capsys)
    one_line_error(status, out, err, "outside")
    assert not (tmp_path / "o").exists()


def _chain_spectra_text(m, k, digits):
    """The two spectra of a fixed–free chain at 80+ digits (mpmath, independent of springchain), as text."""
    n = len(m)
    with mpmath.workdps(max(80, digits + 30)):
        def eig(size):
            r = [1 / mpmath.sqrt(x) for x in m[:size]]
            D = mpmath.zeros(size, size)
            for i in range(size):
                D[i, i] = (k[i] + (k[i + 1] if i + 1 < n else 0)) * r[i] ** 2
                if i + 1 < size:
                    D[i, i + 1] = D[i + 1, i] = -k[i + 1] * r[i] * r[i + 1]
            return sorted(mpmath.eigsy(D, eigvals_only=True))

        lam, mu = eig(n), eig(n - 1)
        fmt = (lambda x: mpmath.nstr(x, digits, min_fixed=1, max_fixed=0)) if digits > 17 else \
            (lambda x: repr(float(x)))
        rows = ["omega2_free,omega2_clamped"] + [f'"{fmt(lam[i])}","{fmt(mu[i])}"' if i < n - 1 else
                                                 f'"{fmt(lam[i])}",' for i in range(n)]
    return "\n".join(rows) + "\n"


@pytest.mark.parametrize("n,seed", [(3, 0), (12, 1), (50, 2)])
def test_random_chains_from_50_digit_spectra_to_1e_12(tmp_path, n, seed):
    rng = np.random.default_rng(seed)
    with mpmath.workdps(60):
        m = [mpmath.mpf(float(x)) for x in rng.uniform(0.8, 1.2, n)]
        k = [mpmath.mpf(float(x)) for x in rng.uniform(0.8, 1.2, n)]
        total = mpmath.fsum(m)
    path = tmp_path / "spectra.csv"
    path.write_text(_chain_spectra_text(m, k, 50))
    r = sc.reconstruct(path, total_mass=float(total), out=tmp_path)
    with mpmath.workdps(60):
        # the total mass is given as a float: its own rounding (≤ 1.1e-16) is part of the scale
        err = max(abs(mpmath.mpf(a) / b - 1) for a, b in zip(r.masses_text + r.springs_text, m + k))
    assert err < 1e-12, err
    assert r.bound < 1e-20  # 50 digits: the inputs' own rounding is far below
    scene = sc.load(tmp_path / "reconstructed.toml")  # a scene file of the chain, loadable
    assert scene.n == n


def test_float64_spectra_state_a_bound_that_holds_and_bad_spectra_are_refused(tmp_path, capsys):
    rng = np.random.default_rng(7)
    n = 12
    with mpmath.workdps(60):
        m = [mpmath.mpf(float(x)) for x in rng.uniform(0.5, 1.5, n)]
        k = [mpmath.mpf(float(x)) for x in rng.uniform(0.5, 1.5, n)]
        total = float(mpmath.fsum(m))
    path = tmp_path / "f64.csv"
    path.write_text(_chain_spectra_text(m, k, 17))
    status, out, err = run_cli(["reconstruct", path, "--total-mass", repr(total), "--out", tmp_path, "--json"], capsys)
    assert status == 0, err
    data = json.loads(out)
    with mpmath.workdps(60):
        worst = max(abs(mpmath.mpf(a) / b - 1) for a, b in zip(data["masses"] + data["springs"], m + k))
    assert data["input_accuracy"] == pytest.approx(2.0**-53)
    assert 1 < data["condition"] and worst <= data["error_bound"], (worst, data["error_bound"])
    bad = tmp_path / "bad.csv"
    bad.write_text("omega2_free,omega2_clamped\n1.0,2.5\n2.0,\n")
    status, out, err = run_cli(["reconstruct", bad, "--total-mass", "2"], capsys)
    one_line_error(status, out, err, "do not interlace")
    bad.write_text("omega2_free,omega2_clamped\n1.0,1.5\nnan,\n")
    status, out, err = run_cli(["reconstruct", bad, "--total-mass", "2"], capsys)
    one_line_error(status, out, err, "'nan' is not a decimal number")
    status, out, err = run_cli(["reconstruct", path], capsys)
    assert status == 2 and "--total-mass" in err
    bad.write_text("omega2_free,omega2_clamped\n1." + "1" * 5000 + ",1.5\n2.0,\n")  # bounded work: refused
    status, out, err = run_cli(["reconstruct", bad, "--total-mass", "2"], capsys)
    one_line_error(status, out, err, "significant digits")


def test_one_spectrum_and_end_components_fix_the_chain_and_its_scale(tmp_path):
    """With the free-end components of the mass-normalised shapes, m_n = 1/Σφ_n² fixes the scale too."""
    rng = np.random.default_rng(3)
    n = 6
    with mpmath.workdps(80):
        m = [mpmath.mpf(float(x)) for x in rng.uniform(0.8, 1.2, n)]
        k = [mpmath.mpf(float(x)) for x in rng.uniform(0.8, 1.2, n)]
        r_ = [1 / mpmath.sqrt(x) for x in m]
        D = mpmath.zeros(n, n)
        for i in range(n):
            D[i, i] = (k[i] + (k[i + 1] if i + 1 < n else 0)) * r_[i] ** 2
            if i + 1 < n:
                D[i, i + 1] = D[i + 1, i] = -k[i + 1] * r_[i] * r_[i + 1]
        w, E = mpmath.eigsy(D)
        order = sorted(range(n), key=lambda j: w[j])
        rows = ["omega2_free,end_component"] + [f'"{mpmath.nstr(w[j], 50)}","{mpmath.nstr(E[n - 1, j] * r_[n - 1], 50)}"'
                                                for j in order]
    path = tmp_path / "end.csv"
    path.write_text("\n".join(rows) + "\n")
    r = sc.reconstruct(path, out=None)
    with mpmath.workdps(60):
        err = max(abs(mpmath.mpf(a) / b - 1) for a, b in zip(r.masses_text + r.springs_text, m + k))
    assert err < 1e-19  # the texts carry 20 significant digits


def test_a_measured_frf_is_reduced_to_modes_and_updated(tmp_path):
    """A receptance "measured" at three floors (modal sum written here from the 50-digit modes of the true
    building, 1 % modal damping, force on the top floor) is reduced to its resonance peaks and
    shapes (one mode and the others' tails fitted around each peak: frequencies to 4e-6, shapes to 2e-4
    measured), and the nominal model updated to it (stiffnesses to 1.2e-4 measured)."""
    nominal = tmp_path / "storeys.toml"
    nominal.write_text(storeys(NOMINAL))
    omega_n, phi = true_modes(storeys(TRUE))
    w = np.linspace(0.5 * omega_n[0], 1.2 * omega_n[-1], 20000)
    zeta, top = 0.01, 4
    head = ["omega"] + [f"{s}.{part}" for s in ("f1", "f3", "f5") for part in ("re", "im")]
    rows = [",".join(head)]
    H = np.zeros((w.size, 3), dtype=complex)
    for r in range(5):
        H += np.outer(1 / (omega_n[r] ** 2 - w**2 + 2j * zeta * omega_n[r] * w), phi[[0, 2, 4], r] * phi[top, r])
    for i in range(w.size):
        rows.append(",".join([repr(float(w[i]))] + [repr(float(v)) for c in H[i] for v in (c.real, c.imag)]))
    path = tmp_path / "frf.csv"
    path.write_text("\n".join(rows) + "\n")
    r = sc.update(nominal, path, parameters="k1,k2,k3,k4,k5", out=None)
    assert list(r.modes) == [0, 1, 2, 3, 4] and r.measured.rows == 5
    assert any("resonance peaks" in n for n in r.notes)
    assert np.all(np.abs(r.measured.omega / omega_n - 1) < 1e-5)  # the natural frequencies, not the peaks
    for p, v in zip(r.parameters, r.values):
        assert abs(v / TRUE[p] - 1) < 1e-3, (p, v)
    assert np.all(r.mac_after > 0.999)
    bad = tmp_path / "badfrf.csv"
    bad.write_text("omega,f1.re\n" + "\n".join(f"{x},1.0" for x in range(1, 7)) + "\n")
    with pytest.raises(ValueError, match="needs both f1.re and f1.im"):
        sc.update(nominal, bad, parameters="k1", out=None)


def test_each_model_evaluation_happens_once(tmp_path, monkeypatch):
    """SciPy asks for the residuals and then the Jacobian at one point; each model evaluation yields both,
    so no (parameter values, modes asked) pair is evaluated twice — neither in the fit nor for the
    before/after tables (measured: 19 evaluations of the five-storey example before, 9 after)."""
    from springchain._sensitivity import Setup

    seen = []
    original = Setup.at

    def at(self, values=None, wanted=None):
        seen.append((None if values is None else tuple(sorted(values.items())),
                     None if wanted is None else tuple(np.asarray(wanted).tolist())))
        return original(self, values, wanted)

    monkeypatch.setattr(Setup, "at", at)
    nominal = tmp_path / "storeys.toml"
    nominal.write_text(storeys(NOMINAL))
    omega, phi = true_modes(storeys(TRUE))
    meas = measured_csv(tmp_path / "m.csv", omega, phi[[0, 2, 4]], ("f1", "f3", "f5"), omega_std=1e-3 * omega,
                        shape_std=0.01)
    r = sc.update(nominal, meas, parameters="k1,k2,k3,k4,k5", out=None)
    assert abs(r.values[3] / TRUE["k4"] - 1) < 1e-10
    assert len(seen) == len(set(seen)), [s for s in seen if seen.count(s) > 1][:2]
    fitted = [s for s in seen if s[0] is not None and s[1] == tuple(r.modes.tolist())]
    assert len(fitted) == r.fit.evaluations


def test_the_fit_evaluates_each_point_once():
    """:func:`numeric.updating.fit.solve` on a problem written here (a straight line in log p): every point
    asked is evaluated once, the start with the given values themselves."""
    from springchain.numeric.updating.fit import Problem, solve

    points = []
    x = np.linspace(0.0, 1.0, 7)
    y = 2.0 * np.exp(0.5 * x)

    def residual(p):
        points.append(np.array(p, dtype=float))
        model = p[0] * p[1] ** x
        J = np.stack([model, model * x], axis=1)  # with respect to log a, log b
        return (model - y) / y, J / y[:, None]

    start = np.array([1.5, 1.3])
    fit = solve(Problem(("a", "b"), start, residual, np.zeros(2), np.full(2, np.inf), True))
    assert np.allclose(fit.values, [2.0, np.exp(0.5)], rtol=1e-10)
    keys = [p.tobytes() for p in points]
    assert len(keys) == len(set(keys)) == fit.evaluations
    assert points[0] is not None and np.array_equal(points[0], start)


def test_the_interlacing_refusal_shows_the_values_apart(tmp_path, capsys):
    """Spectra that fail to interlace by 1e-15 relative: the refusal prints the three values with digits
    enough to tell them apart (at 12 digits they read alike) and the signed difference that fails."""
    bad = tmp_path / "close.csv"
    bad.write_text('omega2_free,omega2_clamped\n"1.0","2.0000000000000010"\n"2.0000000000000005",\n')
    status, out, err = run_cli(["reconstruct", bad, "--total-mass", "2"], capsys)
    one_line_error(status, out, err, "do not interlace")
    assert "2.000000000000001" in err and "2.0000000000000005" in err, err
    assert "omega2_free[1] - omega2_clamped[0] = -5.0e-16" in err, err


def test_the_report_speaks_in_its_own_words(tmp_path):
    """Two measured frequencies, one fitted parameter, the noise estimated: 2 − 1 = 1 degree of freedom
    (singular), and why the fit stopped in the report's words, not SciPy's message with its backticks."""
    from springchain.numeric.updating.fit import STOPPED

    meas = tmp_path / "two.csv"
    meas.write_text("omega\n1.0005\n1.2905\n")
    r = sc.update("seed", meas, parameters="k", out=None)
    text = r.to_text()
    assert r.fit.dof == 1 and "for 1 degree of freedom" in text and "1 degrees" not in text
    assert "`" not in text and r.fit.status in STOPPED.values() and r.fit.status in text
    assert "1 parameter (" in text and "2 measured modes" in text
