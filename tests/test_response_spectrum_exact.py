"""Response spectra exact over the record and the free vibration after it, at bounded cost (issue 31).

Every SD is checked against :mod:`sdof_reference` (tests/sdof_reference.py): the oscillator solved in
closed form on each row interval at 50 digits, every extremum of u isolated between the exact zeros
of ü and located to the working precision, the free vibration after the last row searched the same
way over three damped periods. The records are written here as decimal text; the reference reads
that text exactly. Nothing of springchain builds a reference.

Before this work the spectrum stopped short of the free vibration's peak for unequal rows (a 16-row
record: 0.44 % low over 72 pairs), asked for 477 GiB on rows at t = 0, 0.1, 1e9, ran without end on
``--periods 1e-9`` and gave SD = 0 with a NumPy warning for a 2e-300 s pulse.
"""

from __future__ import annotations

import json
import math
import warnings

import mpmath as mp
import numpy as np
import pytest
import sdof_reference as ref

import springchain as sc
from springchain.cli import main
from springchain.numeric.structural import response_spectrum as rsmod
from springchain.numeric.errors import RunRefused
from springchain.numeric.structural.sdof_peak import free_peak

#: A 16-row record with unequal rows up to t = 2 s (as in the issue): at T = 1.7 s, ζ = 0.05 its peak
#: is in the free vibration after the last row, 6.5 % above the peak inside the record.
T16 = "0,0.04,0.12,0.14,0.28,0.56,0.58,0.66,0.68,0.69,0.89,1.48,1.66,1.79,1.82,2".split(",")
A16 = "0,-0.02,-0.72,-0.53,0.77,-0.18,0.22,0.81,-0.59,-1.45,0.57,-0.31,1.65,0.82,0.34,-0.51".split(",")
#: The grid of the issue's 72 (period, ζ) pairs.
GRID_T = [0.05, 0.1, 0.2, 0.3, 0.5, 0.8, 1.2, 1.7, 2.5, 4.0, 6.0, 10.0]
GRID_Z = [0.0, 0.02, 0.05, 0.1, 0.2, 0.5]


def write(tmp_path, t, a, name="rec16"):
    path = tmp_path / f"{name}.csv"
    path.write_text("t,a\n" + "".join(f"{ti},{ai}\n" for ti, ai in zip(t, a)))
    return path


def rel(got, want) -> float:
    return float(abs(mp.mpf(float(got)) - want) / abs(want))


def test_issue_case_peak_is_in_the_free_vibration(tmp_path):
    """T = 1.7 s, ζ = 0.05: the true SD is the free vibration's first extremum after the last row
    (0.0595291; the product gave 0.0594696, 1.0e-3 low); the in-record peak is 0.0559204."""
    sd, in_record, tail = ref.sd(T16, A16, "1.7", "0.05")
    assert tail == sd and sd > 1.06 * in_record  # the case is the one the issue describes
    res = sc.response_spectrum(write(tmp_path, T16, A16), zeta=[0.05], periods=[1.7])
    assert rel(res.sd[0, 0], sd) < 1e-14 and rel(res.sd_record[0, 0], in_record) < 1e-14
    w = 2 * math.pi / 1.7
    assert res.psv[0, 0] == pytest.approx(w * float(sd), rel=1e-14)
    assert res.psa[0, 0] == pytest.approx(w * w * float(sd), rel=1e-14)


def test_72_pairs_at_rounding_level(tmp_path):
    """Every ordinate of a 12 × 6 grid (periods 0.05–10 s, ζ 0–0.5), over the record and after it."""
    res = sc.response_spectrum(write(tmp_path, T16, A16), zeta=GRID_Z, periods=GRID_T)
    worst = 0.0
    for zi, z in enumerate(GRID_Z):
        for pj, T in enumerate(GRID_T):
            sd, in_record, _ = ref.sd(T16, A16, repr(T), repr(z))
            worst = max(worst, rel(res.sd[zi, pj], sd), rel(res.sd_record[zi, pj], in_record))
    print(f"worst relative SD error over {len(GRID_T) * len(GRID_Z)} pairs: {worst:.2e}")
    assert worst < 2e-14, worst


@pytest.mark.parametrize("z", [0.0, 1e-6, 0.05, 0.5, 0.99, 0.999999])
def test_free_vibration_closed_form(z):
    """The tail's closed form (first extremum after the end, or the end itself) against the free
    vibration's extrema located over three damped periods, for states of every sign and size."""
    rng = np.random.default_rng(int(z * 1e6) + 1)
    for _ in range(12 if z < 0.99 else 4):  # near ζ = 1 the reference's roots need bisection (~1 s each)
        u, v = rng.normal(size=2) * 10.0 ** rng.uniform(-200, 200)
        if rng.random() < 0.2:
            v = 0.0
        om = rng.uniform(4.4, 8.9)
        with mp.workdps(50):
            seg = ref.Segment(mp.mpf(om), mp.mpf(z), mp.mpf(u), mp.mpf(v), mp.mpf(0), mp.mpf(0))
            periods = 3 if z < 0.9 else 1.5  # past ζ = 0.9 each extremum is < 1e-5 of the one before
            want = seg.peak(periods * 2 * mp.pi / (mp.mpf(om) * mp.sqrt(1 - mp.mpf(z) ** 2)))
        assert rel(free_peak(u, v, om, z), want) < 1e-14, (u, v, om, z)


@pytest.mark.parametrize("seed", range(8))
def test_row_intervals_of_many_periods(seed):
    """Rows with gaps of 17–120 periods (the closed-form route with its windows) against the reference
    that searches every extremum of every interval."""
    rng = np.random.default_rng(seed)
    t = [0.0]
    for _ in range(5):
        t.append(t[-1] + (rng.uniform(17, 120) if rng.random() < 0.5 else rng.uniform(0.05, 0.8)))
    t = [f"{x:.3f}" for x in t]
    a = [f"{x:.3f}" for x in rng.normal(0, 1, len(t))]
    if rng.random() < 0.5:
        a[2] = a[1]  # a constant stretch: many equal local maxima at ζ = 0
    z = [0.0, 0.003, 0.05, 0.3, 0.9, 0.999][seed % 6]
    rec = rsmod.Record(np.array(t, dtype=float), np.array(a, dtype=float))
    sd, in_record, notes = rsmod.spectral_displacement(rec, np.array([1.0]), np.array([z]), with_record=True)
    want, want_record, _ = ref.sd(t, a, "1", repr(z))
    assert rel(sd[0], want) < 1e-13 and rel(in_record[0], want_record) < 1e-13 and not notes


@pytest.mark.parametrize("T, z", [("1", "0"), ("1", "0.2"), ("1e-9", "0.05"), ("1e-9", "0"), ("0.01", "0.05")])
def test_rows_at_0_0p1_1e9(tmp_path, T, z):
    """Rows at t = 0, 0.1, 1e9 s (a MemoryError asking 477 GiB before): 1e18 periods in one interval."""
    t, a = ["0", "0.1", "1e9"], ["0", "1", "0"]
    res = sc.response_spectrum(write(tmp_path, t, a, "gap"), zeta=[float(z)], periods=[float(T)])
    sd, in_record, _ = ref.sd(t, a, T, z, long_cycles=200)
    assert rel(res.sd[0, 0], sd) < 1e-14 and rel(res.sd_record[0, 0], in_record) < 1e-14


def test_tiny_periods_are_cheap_and_follow_the_ground(tmp_path, capsys):
    """--periods 1e-9 on the bundled 2001-row record (ran > 100 s with no message): one closed-form
    interval per row; a stiff oscillator follows the ground, PSA → PGA."""
    assert main(["spectrum", "quake-record", "--periods", "1e-9,1e-6", "--zeta", "0", "--zeta", "0.05",
                 "--json", "--out", str(tmp_path)]) == 0
    data = json.loads(capsys.readouterr().out)
    psa = np.array(data["psa"])
    assert np.all(np.abs(psa / data["pga"] - 1) < 1e-5), psa


def test_work_beyond_the_limit_is_refused(tmp_path, capsys, monkeypatch):
    """A grid whose sub-steps exceed the limit: one line naming the limit, exit 2 (before any work)."""
    monkeypatch.chdir(tmp_path)
    assert main(["spectrum", "quake-record", "--periods", "1e-9:1e-8:100000"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "accepted: at most 4e+09" in err[0] and "sub-steps" in err[0], err
    monkeypatch.setattr(rsmod, "MAX_WORK", 1e3)
    with pytest.raises(RunRefused, match="accepted: at most"):
        sc.response_spectrum("quake-record", periods=[0.1, 1.0])


@pytest.mark.parametrize("cold", [False, True])
def test_ctrl_c_during_a_long_spectrum(tmp_path, cold):
    """SIGINT while the compiled sweep runs (about 2e9 sub-steps; called in chunks of ~0.2 s, so
    the interrupt is honoured at once) or, with an empty numba cache, while numba compiles it (an
    interrupt inside llvmlite's ctypes callbacks was printed as "Exception ignored" with a traceback
    and waited for the 10 s grace timer): one line, exit 130, no traceback."""
    import os
    import signal
    import subprocess
    import sys
    import time

    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")} if cold else None
    proc = subprocess.Popen([sys.executable, "-m", "springchain", "spectrum", "quake-record", "--periods",
                             "1e-4:1e-3:2000", "--out", str(tmp_path)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    time.sleep(3.0 if cold else 4.0)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    if proc.returncode == 0:  # finished before the signal (a very fast machine): nothing to check
        pytest.skip("the spectrum ended before the signal")
    assert proc.returncode == 130, err
    lines = [ln for ln in err.splitlines() if not ln.startswith("springchain: ") or "interrupted" in ln]
    assert lines == ["springchain: interrupted"] and "Traceback" not in err, err


def test_2e300_s_pulse_gives_the_tiny_number_without_warnings(tmp_path):
    """A triangle pulse of 2e-300 s and 1 m/s²: an impulse I = 1e-300 m/s, whose peak response is
    (I/ω)·exp(−ζ·acos ζ/√(1−ζ²)) (the unit impulse response e^{−ζωt} sin(ω_d t)/ω_d at
    ω_d t = acos ζ); the pulse's width changes it by (ω·2e-300)² relative. SD was 0 with a warning."""
    path = write(tmp_path, ["0", "1e-300", "2e-300"], ["0", "1", "0"], "pulse")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = sc.response_spectrum(path, zeta=[0.0, 0.05, 0.7], periods=[1e-3, 1.0, 100.0])
    for zi, z in enumerate([0.0, 0.05, 0.7]):
        for pj, T in enumerate([1e-3, 1.0, 100.0]):
            with mp.workdps(30):
                w, zz = 2 * mp.pi / mp.mpf(T), mp.mpf(z)
                want = mp.mpf("1e-300") / w * mp.exp(-zz * mp.acos(zz) / mp.sqrt(1 - zz * zz))
            assert rel(res.sd[zi, pj], want) < 1e-14, (T, z, res.sd[zi, pj], want)
    assert not res.notes


def test_below_the_normal_range_is_said(tmp_path, capsys, monkeypatch):
    """An SD below float64's smallest normal number is printed with a one-line note naming the limit."""
    monkeypatch.chdir(tmp_path)
    write(tmp_path, ["0", "1e-300", "2e-300"], ["0", "1e-10", "0"], "faint")
    assert main(["spectrum", "faint.csv", "--periods", "1e-5", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    want = 1e-310 * 1e-5 / (2 * math.pi) * math.exp(-0.05 * math.acos(0.05) / math.sqrt(1 - 0.0025))
    assert data["sd"][0][0] == pytest.approx(want, rel=1e-3) and 0 < data["sd"][0][0] < 2.2250738585072014e-308
    assert any("smallest normal number (2.2e-308" in n for n in data["notes"]), data["notes"]


def test_unsorted_periods_are_sorted_everywhere(tmp_path, capsys, monkeypatch):
    """`--periods 2,0.5,1`: text, JSON and figure list the periods ascending (the figure joined them in
    the order given), each ordinate with its own period."""
    monkeypatch.chdir(tmp_path)
    path = write(tmp_path, T16, A16)
    assert main(["spectrum", str(path), "--periods", "2,0.5,1", "--json", "--out", "o"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["periods"] == [0.5, 1.0, 2.0]
    assert "free vibration after its last row" in data["sd_convention"]
    for j, T in enumerate(data["periods"]):
        assert rel(data["sd"][0][j], ref.sd(T16, A16, repr(T), "0.05")[0]) < 1e-14
    res = sc.response_spectrum(path, periods=[2, 0.5, 1])
    fig = res.plot()
    for ax in fig.axes[:3]:
        x = ax.lines[0].get_xdata()
        assert list(x) == [0.5, 1.0, 2.0]
    assert "free vibration after it" in fig._suptitle.get_text()
    assert main(["spectrum", str(path), "--periods", "2,0.5,1", "--out", "o"]) == 0
    text = capsys.readouterr().out
    assert "SD = max |u| over the record and the free vibration after it" in text


@pytest.mark.parametrize("rows, args, fragment", [
    ("0,0\n1,nan\n2,0\n", [], "accepted"),
    ("0,0\n2,1\n1,0\n", [], "times not strictly increasing"),
    ("0,0\n1,1\n1,0\n", [], "times not strictly increasing"),
    ("0,1\n", [], "at least 2 needed"),
    ("", [], "accepted"),
    ("0,0\n1,1e200\n", [], "accepted"),
    ("0,0\n1,1\n2,0\n", ["--periods", "-1"], "every period > 0"),
    ("0,0\n1,1\n2,0\n", ["--periods", "0"], "every period > 0"),
    ("0,0\n1,1\n2,0\n", ["--periods", "1e-200"], "accepted: periods 1e-150 <= T <= 1e+150 s"),
    ("0,0\n1,1\n2,0\n", ["--periods", "inf"], "every period > 0"),
    ("0,0\n1,1\n2,0\n", ["--periods", "nan"], "every period > 0"),
    ("0,0\n1,1\n2,0\n", ["--zeta", "1"], "accepted: a damping ratio 0 <= zeta < 1"),
    ("0,0\n1,1\n2,0\n", ["--zeta", "-0.1"], "accepted: a damping ratio 0 <= zeta < 1"),
    ("0,0\n1,1\n2,0\n", ["--zeta", "nan"], "accepted: a damping ratio 0 <= zeta < 1"),
])
def test_hostile_records_one_line(tmp_path, capsys, monkeypatch, rows, args, fragment):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad.csv").write_text("t,a\n" + rows)
    try:
        code = main(["spectrum", "bad.csv", *args])
    except SystemExit as exc:  # argparse's own refusals
        code = exc.code
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and fragment in err[0], (code, err)


def test_api_record_limits():
    """A Record from arrays: the loader's value limit (times and accelerations within ±1e150)."""
    with pytest.raises(ValueError, match="1e\\+150"):
        rsmod.Record(np.array([0.0, 1e200]), np.array([0.0, 1.0]))
    with pytest.raises(ValueError, match="strictly increasing"):
        rsmod.Record(np.array([0.0, 0.0]), np.array([0.0, 1.0]))


# -- rsa against a record inherits the spectrum ------------------------------------------------------
def chain_text(masses, springs) -> str:
    """wall - x0 - x1 - ... (springs[i] below mass i), undamped."""
    out = ['name = "undamped"', "[parameters]"]
    out += [f"m{i} = {v!r}" for i, v in enumerate(masses)] + [f"k{i} = {v!r}" for i, v in enumerate(springs)]
    out += ["[masses]"] + [f'x{i} = "m{i}"' for i in range(len(masses))]
    for i in range(len(masses)):
        out += ["[[springs]]", f'between = ["{"wall" if i == 0 else f"x{i - 1}"}", "x{i}"]', f'k = "k{i}"']
    return "\n".join(out + ["[simulation]", "dt = 1e-3", "steps = 10"]) + "\n"


def chain_base_shears(masses, springs, dps=50):
    """Per-mode base shear M*ⱼ·ωⱼ²·SDⱼ of the undamped wall chain under the 16-row record: modes from
    mpmath.eigsy of M^-1/2 K M^-1/2 (K assembled here), SDⱼ from the reference oscillator at Tⱼ = 2π/ωⱼ."""
    n = len(masses)
    with mp.workdps(dps):
        m = [mp.mpf(v) for v in masses]
        k = [mp.mpf(v) for v in springs]
        K = mp.zeros(n, n)
        for i in range(n):
            K[i, i] += k[i]
            if i:
                K[i - 1, i - 1] += k[i]
                K[i - 1, i] -= k[i]
                K[i, i - 1] -= k[i]
        s = [1 / mp.sqrt(v) for v in m]
        lam, Q = mp.eigsy(mp.matrix([[s[i] * K[i, j] * s[j] for j in range(n)] for i in range(n)]))
        out = []
        for j in sorted(range(n), key=lambda j: lam[j]):
            gamma = mp.fsum(m[i] * s[i] * Q[i, j] for i in range(n))
            period = 2 * mp.pi / mp.sqrt(lam[j])
            sd = ref.sd(T16, A16, period, 0, dps=dps)[0]
            out.append(gamma**2 * lam[j] * sd)
        return out


def check_chain(tmp_path, n):
    masses = [1.0 + i / 8 for i in range(n)]
    springs = [2000.0 - 24.0 * i for i in range(n)]
    path = tmp_path / "undamped.toml"
    path.write_text(chain_text(masses, springs))
    data = sc.rsa(sc.load(path), spectrum=write(tmp_path, T16, A16)).to_json()
    want = chain_base_shears(masses, springs)
    got = [md["base_shear"] for md in data["modes"]]
    with mp.workdps(50):
        srss = mp.sqrt(mp.fsum(v * v for v in want))
        worst = max(float(abs(mp.mpf(g) - w) / max(abs(w), srss * mp.mpf("1e-3"))) for g, w in zip(got, want))
        for how in ("srss", "cqc"):  # undamped: no correlation between distinct modes, CQC = SRSS
            worst = max(worst, rel(data[how]["base_shear"], srss))
    return worst


def test_rsa_record_base_shear_of_an_undamped_chain(tmp_path):
    """A 6-mass undamped chain against the 16-row record: per-mode and combined base shear against
    the reference built here (it was low by the spectrum's missing free vibration)."""
    worst = check_chain(tmp_path, 6)
    print(f"worst relative base-shear error: {worst:.2e}")
    assert worst < 1e-13, worst


@pytest.mark.slow
def test_rsa_record_base_shear_of_a_40_mass_chain(tmp_path):
    """The issue's size: an undamped 40-mass chain (float shapes past 24 masses; base shear was 1.2e-4
    low; 4.3e-3 here before). 25 masses in CI's bounded form, 40 from SPRINGCHAIN_SLOW_BUDGET 1 on."""
    from helpers import SLOW_BUDGET

    worst = check_chain(tmp_path, 40 if SLOW_BUDGET >= 1 else 25)
    print(f"worst relative base-shear error: {worst:.2e}")
    assert worst < 1e-11, worst
