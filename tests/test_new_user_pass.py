"""A new user's pass: a scene written from the README alone, checked against mpmath.

The scene (below, as TOML text) is what a user would write after reading the README's
"Scene format" section: four masses from a wall, stiff and soft springs alternating at a
stiffness contrast of 1e10, a dashpot to the wall, Rayleigh damping, gravity and a harmonic
force, with parameter names a user picks without thinking of internals (``a``, ``K``, ``w``,
``x``, ``np``). The reference builds M, K and C BY HAND from the TOML's numbers (read with
``tomllib``) and works in mpmath at 50+ digits: ω², ζ (state-space eigenvalues), |H| of the
frequency response, the static sag under gravity and the exact trajectory (augmented matrix
exponential). Nothing of springchain is used to build the reference.
"""

from __future__ import annotations

import tomllib
import types

import mpmath as mp
import numpy as np
import pytest

import springchain as sc

SCENE = """
name = "contrast"
description = "4-mass chain, stiffness contrast 1e10, dashpot + Rayleigh, gravity, harmonic force"

[parameters]
a = 2.0          # mass
K = 3.0e9        # stiff spring
w = 0.3          # soft spring (K/w = 1e10)
x = 0.2          # dashpot constant
np = 0.01        # Rayleigh alpha
beta = 1.0e-12   # Rayleigh beta
g = 9.81
F = 0.7          # force amplitude
Om = 1.3         # force frequency

[masses]
m1 = "a"
m2 = "a"
m3 = "3*a"
m4 = "a"

[[springs]]
between = ["wall", "m1"]
k = "K"
[[springs]]
between = ["m1", "m2"]
k = "w"
[[springs]]
between = ["m2", "m3"]
k = "K"
[[springs]]
between = ["m3", "m4"]
k = "w"

[[dampers]]
between = ["m4", "wall"]
c = "x"

[damping]
rayleigh = ["np", "beta"]

[gravity]
g = "g"

[[forces]]
on = "m4"
f = "F*cos(Om*t)"

[initial]
x = [1e-6, 0.0, -2e-6, 0.5]
v = [0.0, 0.01, 0.0, -0.3]

[simulation]
dt = 1e-6
steps = 1000
"""

DPS = 50


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    path = tmp_path_factory.mktemp("new_user") / "contrast.toml"
    path.write_text(SCENE)
    return sc.load(path)


class Reference:
    """M, K, C, forcing and initial state of SCENE, written by hand from its TOML numbers."""

    def __init__(self):
        d = tomllib.loads(SCENE)
        p = {k: mp.mpf(v) for k, v in d["parameters"].items()}
        a, K, w = p["a"], p["K"], p["w"]
        self.p = p
        self.M = mp.diag([a, a, 3 * a, a])
        self.K = mp.matrix([[K + w, -w, 0, 0],
                            [-w, w + K, -K, 0],
                            [0, -K, K + w, -w],
                            [0, 0, -w, w]])
        self.C = p["np"] * self.M + p["beta"] * self.K
        self.C[3, 3] += p["x"]                                  # dashpot m4 -- wall
        self.gravity = self.M * mp.matrix([p["g"]] * 4)          # M g 1
        self.force = mp.matrix([0, 0, 0, p["F"]])                # F cos(Om t) on m4
        self.x0 = mp.matrix([mp.mpf(v) for v in d["initial"]["x"]])
        self.v0 = mp.matrix([mp.mpf(v) for v in d["initial"]["v"]])

    def omega2(self):
        s = mp.diag([1 / mp.sqrt(self.M[i, i]) for i in range(4)])
        e, _ = mp.eigsy(s * self.K * s)
        return sorted(e)

    def state_matrix(self):
        Minv = mp.inverse(self.M)
        A = mp.zeros(8, 8)
        for i in range(4):
            A[i, 4 + i] = 1
        A[4:8, 0:4] = -Minv * self.K
        A[4:8, 4:8] = -Minv * self.C
        return A

    def zeta(self):
        lam = mp.eig(self.state_matrix(), left=False, right=False)
        upper = sorted((z for z in lam if mp.im(z) > 0), key=abs)
        return [-mp.re(z) / abs(z) for z in upper], [mp.im(z) for z in upper]

    def receptance(self, omega, i_in, i_out):
        Z = self.K - omega ** 2 * self.M + 1j * omega * self.C
        e = mp.matrix(4, 1)
        e[i_in] = 1
        return mp.lu_solve(Z, e)[i_out]

    def sag(self):
        return mp.lu_solve(self.K, self.gravity)

    def trajectory(self, t):
        """x(t): exp of the augmented matrix [[A, B], [0, S]] with u = (cos Om t, sin Om t, 1)."""
        Om = self.p["Om"]
        Minv = mp.inverse(self.M)
        G = mp.zeros(11, 11)
        G[0:8, 0:8] = self.state_matrix()
        f = Minv * self.force
        g = Minv * self.gravity
        for i in range(4):
            G[4 + i, 8] = f[i]      # cos
            G[4 + i, 10] = g[i]     # 1
        G[8, 9] = -Om               # d/dt cos = -Om sin
        G[9, 8] = Om                # d/dt sin = Om cos
        z0 = mp.matrix(list(self.x0) + list(self.v0) + [1, 0, 1])
        z = mp.expm(G * t) * z0
        return np.array([float(z[i]) for i in range(4)])


@pytest.fixture(scope="module")
def ref():
    with mp.workdps(DPS):
        yield Reference()


def test_reference_is_sane(ref):
    """The hand-built reference: trajectory at t = 0 is x0, and two precisions agree."""
    with mp.workdps(DPS):
        np.testing.assert_allclose(ref.trajectory(mp.mpf(0)), [float(v) for v in ref.x0], rtol=0, atol=1e-30)
        t = mp.mpf("1e-3")
        x50 = ref.trajectory(t)
    with mp.workdps(DPS + 20):
        x70 = Reference().trajectory(t)
    np.testing.assert_allclose(x50, x70, rtol=1e-14, atol=0)


def test_modes_omega2_and_zeta(scene, ref):
    m = sc.modes(scene)
    with mp.workdps(DPS):
        w2 = ref.omega2()
        zeta, wd = ref.zeta()
    got = np.asarray(m.omega2_values, dtype=float)
    expected = np.array([float(v) for v in w2])
    rel = np.abs(got - expected) / expected
    assert rel.max() < 1e-12, rel
    data = m.to_json()
    got_zeta = np.array([c["damping_ratio"] for c in data["complex_modes"]])
    got_wd = np.array([c["omega_damped"] for c in data["complex_modes"]])
    np.testing.assert_allclose(got_zeta, [float(z) for z in zeta], rtol=1e-10)
    np.testing.assert_allclose(got_wd, [float(z) for z in wd], rtol=1e-12)
    per_mode = np.array([md["damping_ratio"] for md in data["modes"]])
    np.testing.assert_allclose(per_mode, [float(z) for z in zeta], rtol=1e-10)
    # participation (the scene has a wall): |Γ_j| = |φ_jᵀ M 1| of the mass-normalised shapes
    with mp.workdps(DPS):
        s = mp.diag([1 / mp.sqrt(ref.M[i, i]) for i in range(4)])
        e, Q = mp.eigsy(s * ref.K * s)
        gamma = [abs(mp.fsum(ref.M[i, i] * s[i, i] * Q[i, j] for i in range(4)))
                 for j in sorted(range(4), key=lambda j: e[j])]
        total = float(mp.fsum(ref.M[i, i] for i in range(4)))
    got_gamma = np.abs(np.array(m.participation.gamma))
    assert np.abs(got_gamma - np.array([float(g) for g in gamma])).max() <= 1e-13 * np.sqrt(total)


def test_frf_magnitude(scene, ref):
    h = sc.frf(scene, input="m4", output="m1", omega_min=0.05, omega_max=1e5, points=40, transfer=False)
    omega = np.asarray(h.omega)
    with mp.workdps(DPS):
        expected = np.array([float(abs(ref.receptance(mp.mpf(float(o)), 3, 0))) for o in omega])
    rel = np.abs(np.asarray(h.magnitude) - expected) / expected
    assert rel.max() < 1e-9, (rel.max(), omega[np.argmax(rel)])


def test_static_sag(scene, ref):
    """gravity: the closed form x_eq = K^-1 M g that `modes` prints, at the scene's values."""
    m = sc.modes(scene)
    note = next(s for s in m.to_json()["notes"] if s.startswith("gravity: static equilibrium"))
    inner = note.split("x_eq = K^-1 M g = (")[1].split("); modes")[0]
    got = []
    for text in inner.split(", "):
        e = m.parse(text)
        got.append(float(e.subs({s: scene.parameters[str(s)] for s in e.free_symbols})))
    with mp.workdps(DPS):
        expected = np.array([float(v) for v in ref.sag()])
    np.testing.assert_allclose(got, expected, rtol=1e-13)


@pytest.mark.parametrize("times", [(1e-4, 5e-4, 1e-3)])
def test_exact_trajectory(scene, ref, times):
    dt = 1e-5
    run = sc.simulate(scene, methods=["modal"], dt=dt, steps=100, progress=False)
    for t in times:
        i = int(round(t / dt))
        with mp.workdps(DPS):
            expected = ref.trajectory(mp.mpf(i) * mp.mpf(dt))
        err = np.abs(run.x["modal"][i] - expected) / np.abs(expected).max()
        assert err.max() < 1e-10, (t, err)


def test_exact_trajectory_long_horizon(scene, ref):
    """Past the fast modes' 10^5 periods: the soft modes, damping, force and sag all matter."""
    dt = 0.05
    run = sc.simulate(scene, methods=["modal"], dt=dt, steps=200, progress=False)
    for i in (100, 200):
        with mp.workdps(DPS):
            expected = ref.trajectory(mp.mpf(i) * mp.mpf(dt))
        err = np.abs(run.x["modal"][i] - expected) / np.abs(expected).max()
        assert err.max() < 1e-12, (i * dt, err)


def test_verlet_converges_to_exact(scene, ref):
    t_end = 1e-3
    with mp.workdps(DPS):
        expected = ref.trajectory(mp.mpf(t_end))
    errs = []
    hs = [4e-6, 2e-6, 1e-6]
    for h in hs:
        steps = int(round(t_end / h))
        run = sc.simulate(scene, methods=["verlet"], dt=h, steps=steps, progress=False)
        errs.append(np.abs(run.x["verlet"][-1] - expected).max() / np.abs(expected).max())
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert 1.85 < slope < 2.15, (slope, errs)
    assert errs[-1] < 1e-4, errs


# -- defects a new user met on the command line -------------------------------------------------
def test_spectrum_missing_record_says_what_a_record_is(tmp_path, monkeypatch, capsys):
    """`springchain spectrum nosuch.csv` said "names are relative to the scene file's folder" (there is no
    scene) and did not mention the bundled records."""
    from springchain.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["spectrum", "nosuch.csv"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "nosuch.csv" in err[0] and "not a bundled record" in err[0] and "quake-record" in err[0], err
    assert "scene file" not in err[0], err


def test_progress_final_line_once():
    """A sweep printed its last progress line (8/8 samples) twice: once when the count reached the total
    and again when the driver reported the end."""
    import io

    from springchain.numeric.progress import Reporter

    out = io.StringIO()
    rep = Reporter("sweep", 8, enabled=True, stream=out, quiet_seconds=0, prefix="sweep", interval=0)
    rep.update(2)
    rep.update(8)
    rep.update(8)
    lines = out.getvalue().splitlines()
    assert sum("8/8" in s for s in lines) == 1, lines


# -- issue 20's loose end: participation of [chain] scenes whose supports move ---------------------
CHAIN = """
name = "wchain"
description = "eight alternating masses from a wall, contrast 1e10 in the springs"
[parameters]
m = 2.0
k = 5.0
[chain]
n = 8
mass = "m*(1 + i % 2)"
k = "k*(1 + 1e10*(i % 2))"
left = "wall"
right = "free"
[initial]
x = "0.01*i"
v = "0"
"""


def _chain_reference(text):
    """Γ (first component of each mass-normalised shape positive) and M* by mpmath from the TOML numbers."""
    d = tomllib.loads(text)
    p = {k: mp.mpf(v) for k, v in d["parameters"].items()}
    n = d["chain"]["n"]
    m = [p["m"] * (1 + i % 2) for i in range(n)]
    ks = [p["k"] * (1 + mp.mpf(1e10) * (i % 2)) for i in range(n - 1)]  # spring i joins i and i+1
    K = mp.zeros(n, n)
    if d["chain"]["left"] == "wall":  # README: "a wall spring k at i = -1"
        K[0, 0] += p["k"] * (1 + mp.mpf(1e10) * ((-1) % 2))
    for i, kk in enumerate(ks):
        K[i, i] += kk
        K[i + 1, i + 1] += kk
        K[i, i + 1] -= kk
        K[i + 1, i] -= kk
    s = mp.diag([1 / mp.sqrt(x) for x in m])
    e, Q = mp.eigsy(s * K * s)
    order = sorted(range(n), key=lambda j: e[j])
    gamma = []
    for j in order:
        phi = [Q[i, j] / mp.sqrt(m[i]) for i in range(n)]
        sign = 1 if phi[0] > 0 else -1
        gamma.append(sign * mp.fsum(m[i] * phi[i] for i in range(n)))
    return [e[j] for j in order], gamma, mp.fsum(m)


def test_chain_with_wall_reports_participation(tmp_path):
    path = tmp_path / "wchain.toml"
    path.write_text(CHAIN)
    m = sc.modes(sc.load(path))
    with mp.workdps(DPS):
        w2, gamma, total = _chain_reference(CHAIN)
        w2 = np.array([float(v) for v in w2])
        gamma = np.array([float(g) for g in gamma])
        total = float(total)
    p = m.participation
    assert p is not None
    np.testing.assert_allclose(p.omega2, w2, rtol=1e-12)
    assert np.abs(np.array(p.gamma) - gamma).max() <= 1e-12 * np.sqrt(total), (p.gamma, gamma)
    assert abs(p.effective_mass_sum - total) <= 1e-13 * total
    data = m.to_json()
    assert data["participation"]["total_mass"] == pytest.approx(total, rel=1e-15)
    got = np.array([rec["participation_factor"] for rec in data["modes"]])
    np.testing.assert_allclose(got, p.gamma, rtol=0, atol=0)
    text = m.to_text()
    assert "Modal participation (ground direction" in text and "not reported" not in text


def test_chain_participation_only_where_it_applies(tmp_path):
    """A free chain without [ground] has none; a long chain with a wall keeps the note pointing to rsa."""
    free = tmp_path / "free.toml"
    free.write_text(CHAIN.replace('left = "wall"', 'left = "free"'))
    m = sc.modes(sc.load(free))
    assert m.participation is None and "participation" not in m.to_json()
    long = tmp_path / "long.toml"
    long.write_text(CHAIN.replace("n = 8", "n = 60"))
    m = sc.modes(sc.load(long))
    assert m.participation is None
    assert any("springchain rsa" in s for s in m.to_json()["notes"])


def test_free_chain_with_ground_rigid_mode_carries_all_mass(tmp_path):
    """r = 1 is the rigid mode of a free-free chain: Γ = (√M, 0, ..., 0) exactly, not rounding noise."""
    path = tmp_path / "gchain.toml"
    path.write_text('name = "gchain"\n[parameters]\nm = 1.0\nk = 3.0\nA = 0.5\n[chain]\nn = 5\n'
                    'mass = "m*(1 + i)"\nk = "k*(1 + 1e10*(i % 2))"\nleft = "free"\nright = "free"\n'
                    '[ground]\nacceleration = "A*sin(2*t)"\n')
    p = sc.modes(sc.load(path)).participation
    assert p.gamma[0] == pytest.approx(np.sqrt(15.0), rel=1e-15)
    assert p.gamma[1:] == (0.0,) * 4 and p.omega2[0] == 0.0


def test_numba_import_is_outside_the_method_clock(monkeypatch):
    """`springchain run` printed `verlet 574-1015 ms` (README: 6.56 ms): the first compiled method's clock
    included importing numba (about 1 s). The import now happens before any method's clock starts."""
    from springchain.numeric.compiled import fast_kernels
    from springchain.numeric.run import simulate as sim

    events = []
    real_available, real_clock = fast_kernels.available, sim.time.perf_counter
    monkeypatch.setattr(fast_kernels, "available", lambda: events.append("import numba") or real_available())
    monkeypatch.setattr(sim, "time", types.SimpleNamespace(perf_counter=lambda: events.append("clock") or real_clock()))
    sc.simulate("seed", methods=["verlet"], steps=20, progress=False)
    assert "import numba" in events and "clock" in events
    assert events.index("import numba") < events.index("clock"), events


def test_rsa_modal_spring_forces_at_contrast(scene, ref):
    r = sc.rsa(scene, spectrum="quake-record")
    data = r.to_json()
    K, w = ref.p["K"], ref.p["w"]
    worst = 0.0
    with mp.workdps(DPS):
        s = mp.diag([1 / mp.sqrt(ref.M[i, i]) for i in range(4)])
        e, Q = mp.eigsy(s * ref.K * s)
        for rec, j in zip(data["modes"], sorted(range(4), key=lambda j: e[j])):
            phi = [s[i, i] * Q[i, j] for i in range(4)]
            phi = [-c for c in phi] if phi[0] < 0 else phi
            x = [mp.fsum(ref.M[i, i] * c for i, c in enumerate(phi)) * mp.mpf(rec["sd"]) * c for c in phi]
            force = [K * x[0], w * (x[1] - x[0]), K * (x[2] - x[1]), w * (x[3] - x[2])]
            worst = max(worst, max(float(abs(g - f) / abs(f)) for g, f in zip(rec["spring_force"], force)))
    assert worst < 1e-10, worst


DAMPED_CHAIN = """
name = "damped"
description = "five masses alternating a and a*w, springs K, a heavy dashpot to the wall"
[parameters]
a = 1.0
K = 2.0
w = 1e10
[chain]
n = 5
mass = "a*(1 + w*(i % 2))"
k = "K"
left = "wall"
right = "free"
[[dampers]]
between = [0, "wall"]
c = "K*40"
[initial]
x = "0.01*i"
v = "0"
"""


def test_damped_chain_zeta_at_mass_contrast_1e10(tmp_path):
    """`modes` of a [chain] at mass contrast 1e10 with a heavy dashpot: every oscillatory mode's ζ (from
    4.5e-5 down to 8.8e-43) equals the 60-digit state-matrix eigenvalues built here from the TOML."""
    path = tmp_path / "damped.toml"
    path.write_text(DAMPED_CHAIN)
    p = tomllib.loads(DAMPED_CHAIN)["parameters"]
    n = 5
    with mp.workdps(60):
        a, K, w = (mp.mpf(p[k]) for k in ("a", "K", "w"))
        m = [a * (1 + w * (i % 2)) for i in range(n)]
        stiff, damp = mp.zeros(n, n), mp.zeros(n, n)
        stiff[0, 0] += K  # the wall spring
        for i in range(n - 1):
            stiff[i, i] += K
            stiff[i + 1, i + 1] += K
            stiff[i, i + 1] -= K
            stiff[i + 1, i] -= K
        damp[0, 0] += 40 * K
        A = mp.zeros(2 * n, 2 * n)
        for i in range(n):
            A[i, n + i] = 1
            for j in range(n):
                A[n + i, j] = -stiff[i, j] / m[i]
                A[n + i, n + j] = -damp[i, j] / m[i]
        lam = mp.eig(A, left=False, right=False)
        osc = sorted((v for v in lam if v.imag > mp.mpf("1e-30") * abs(v)), key=abs)
        want = np.array([float(-v.real / abs(v)) for v in osc])
    got = [r["damping_ratio"] for r in sc.modes(path).to_json()["modes"] if r.get("omega_damped")]
    assert None not in got and len(got) == len(want)
    np.testing.assert_allclose(got, want, rtol=1e-12)
