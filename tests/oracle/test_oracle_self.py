"""The oracle checked on its own: closed forms derived by hand reproduce to 30+ digits (issue 31, item 2).

Before the oracle judges springchain it must be right itself: each test here builds a scene whose every
output has a closed form written in the test (none from the oracle, none from springchain) and compares.
No springchain import: these run in milliseconds and fail only if the oracle is wrong.
"""

from __future__ import annotations

import pytest
from mpmath import mp

from oracle import reference as R

pytestmark = pytest.mark.timeout(120)

TIGHT = mp.mpf("1e-28")


def near(a, b, tol=TIGHT) -> bool:
    return abs(mp.mpmathify(a) - mp.mpmathify(b)) <= tol * max(abs(mp.mpmathify(b)), mp.mpf(1e-300))


def scene(body: str, params: str) -> str:
    return f'name = "t"\n[parameters]\n{params}\n{body}'


SEED = scene('''
[masses]
a = "m"
b = "3*m"
c = "m"
[[springs]]
between = ["a", "b"]
k = "K"
[[springs]]
between = ["b", "c"]
k = "K"
[initial]
x = [0.8552, 1.5376, 0.8834]
v = [-1.9255, 0.6991, -0.2460]
''', "m = 2.0\nK = 5.0")


def test_seed_modes_closed_form():
    """m, 3m, m with two springs k: ω² = 0, k/m, 5k/(3m); shapes (1, 1, 1), (1, 0, -1), (1, -2/3, 1)."""
    with mp.workdps(50):
        ms = R.modes(R.read(SEED))
        m, k = mp.mpf(2), mp.mpf(5)
        assert ms.omega2[0] == 0 and ms.rigid == 1
        assert near(ms.omega2[1], k / m) and near(ms.omega2[2], 5 * k / (3 * m))
        for j, shape in ((1, (1, 0, -1)), (2, (1, mp.mpf(-2) / 3, 1))):
            ratio = ms.shapes[0, j] / shape[0]
            assert all(near(ms.shapes[i, j], ratio * shape[i], mp.mpf("1e-28")) or abs(ms.shapes[i, j]) < 1e-40
                       for i in range(3))
        mass = [m, 3 * m, m]
        for j in range(3):  # mass-normalised
            assert near(mp.fsum(mass[i] * ms.shapes[i, j] ** 2 for i in range(3)), 1)


def test_seed_free_vibration_closed_form():
    """x(t) = Σ φ_j (q_j cos ω_j t + q̇_j sin(ω_j t)/ω_j), rigid: q + q̇ t, with the hand-normalised shapes."""
    with mp.workdps(50):
        md = R.read(SEED)
        times = [mp.mpf(0), mp.mpf("1.25"), mp.mpf(100)]
        tr = R.trajectory(md, [float(t) for t in times])
        m, k = mp.mpf(2), mp.mpf(5)
        M = [m, 3 * m, m]
        x0 = [mp.mpf(float(v)) for v in (0.8552, 1.5376, 0.8834)]
        v0 = [mp.mpf(float(v)) for v in (-1.9255, 0.6991, -0.2460)]
        shapes = [(1, 1, 1), (1, 0, -1), (1, mp.mpf(-2) / 3, 1)]
        omegas = [0, mp.sqrt(k / m), mp.sqrt(5 * k / (3 * m))]
        for r, t in enumerate(times):
            x = [mp.mpf(0)] * 3
            for s, w in zip(shapes, omegas):
                nrm = mp.sqrt(mp.fsum(M[i] * s[i] ** 2 for i in range(3)))
                phi = [s[i] / nrm for i in range(3)]
                q = mp.fsum(phi[i] * M[i] * x0[i] for i in range(3))
                qd = mp.fsum(phi[i] * M[i] * v0[i] for i in range(3))
                qt = q + qd * t if w == 0 else q * mp.cos(w * t) + qd * mp.sin(w * t) / w
                x = [x[i] + phi[i] * qt for i in range(3)]
            assert all(near(tr.x[r][i], x[i], mp.mpf("1e-25")) for i in range(3))


SDOF = scene('''
[masses]
p = "m"
[[springs]]
between = ["wall", "p"]
k = "k"
[[dampers]]
between = ["p", "wall"]
c = "c"
[[forces]]
on = "p"
f = "F*cos(W*t)"
[initial]
x = [0.1]
v = [0.2]
''', "m = 2.0\nk = 8.0\nc = 0.4\nF = 3.0\nW = 1.5")


def test_sdof_frf_and_damping_closed_form():
    """H(ω) = 1/(k − mω² + icω); ζ = c/(2√(km)); λ = −ζω_n ± iω_n√(1 − ζ²)."""
    with mp.workdps(50):
        md = R.read(SDOF)
        m, k, c = mp.mpf(2), mp.mpf(8), mp.mpf(0.4)  # the TOML numbers are binary floats
        ws = [mp.mpf("0.5"), mp.mpf(2), mp.mpf(7)]
        H = R.receptance(md, ws, 0, 0)
        for w, h in zip(ws, H):
            assert near(h, 1 / (k - m * w * w + 1j * c * w), mp.mpf("1e-14"))
            assert near(mp.arg(h), -mp.atan2(c * w, k - m * w * w), mp.mpf("1e-14"))
        dm = R.damped(md)
        wn = mp.sqrt(k / m)
        zeta = c / (2 * mp.sqrt(k * m))
        assert dm.proportional and near(dm.zeta_diag[0], zeta, mp.mpf("1e-17"))
        assert near(dm.eigenvalues[0], mp.mpc(-zeta * wn, wn * mp.sqrt(1 - zeta**2)), mp.mpf("1e-17"))


def test_sdof_forced_trajectory_closed_form():
    """x = Re(X e^{iWt}) + e^{−ζω t}(A cos ω_d t + B sin ω_d t), X = F/(k − mW² + icW), A, B from x(0), v(0)."""
    with mp.workdps(50):
        md = R.read(SDOF)
        m, k, c, F, W = mp.mpf(2), mp.mpf(8), mp.mpf(0.4), mp.mpf(3), mp.mpf(1.5)
        X = F / (k - m * W * W + 1j * c * W)
        wn, zeta = mp.sqrt(k / m), c / (2 * mp.sqrt(k * m))
        wd = wn * mp.sqrt(1 - zeta**2)
        x0, v0 = mp.mpf(0.1), mp.mpf(0.2)
        A = x0 - mp.re(X)
        B = (v0 - mp.re(1j * W * X) + zeta * wn * A) / wd
        for t in (mp.mpf(0), mp.mpf(3), mp.mpf(30)):
            tr = R.trajectory(md, [float(t)])
            exact = mp.re(X * mp.expj(W * t)) + mp.exp(-zeta * wn * t) * (A * mp.cos(wd * t) + B * mp.sin(wd * t))
            assert near(tr.x[0][0], exact, mp.mpf("1e-25"))


HANGING = scene('''
[masses]
p = "m1"
q = "m2"
[[springs]]
between = ["wall", "p"]
k = "k1"
[[springs]]
between = ["p", "q"]
k = "k2"
[gravity]
g = "g"
''', "m1 = 1.5\nm2 = 0.25\nk1 = 1e-6\nk2 = 1e6\ng = -9.81")


def test_hanging_sag_and_spring_forces_closed_form():
    """Sag on a tree: x_p = (m1 + m2) g/k1, x_q = x_p + m2 g/k2 (contrast 1e12); started at rest the wall
    spring's tension at the top of the swing is twice the static one; the base shear is the wall spring's."""
    with mp.workdps(60):
        md = R.read(HANGING)
        m1, m2, k1, k2, g = (mp.mpf(v) for v in (1.5, 0.25, 1e-6, 1e6, -9.81))
        eq = R.static_equilibrium(md)
        assert near(eq.x[0], (m1 + m2) * g / k1) and near(eq.x[1], (m1 + m2) * g / k1 + m2 * g / k2)
        assert near(eq.extensions[1], m2 * g / k2)
        ms = R.modes(md)
        dr, fo, sh = R.spring_series(md, [eq.x])
        assert near(fo[0][0], (m1 + m2) * g) and near(fo[0][1], m2 * g)
        assert near(sh[0], (m1 + m2) * g)  # a wall at the spring's end a: +V' on the ground
        # released from rest: the slow mode swings to twice the sag; the spring forces stay finite
        w1 = mp.sqrt(ms.omega2[0])
        t = float(mp.pi / w1)
        tr = R.trajectory(md, [t])
        assert abs(tr.x[0][0] / eq.x[0] - 2) < mp.mpf("1e-6")  # the stiff mode's share is 1e-12


FREE_TABLE = scene('''
[masses]
p = "m"
[[forces]]
on = "p"
table = "f.csv"
''', "m = 4.0")


def test_free_mass_table_force_closed_form():
    """A free mass pushed by a triangle 0 → F → 0 over [0, 1], [1, 2]: x = F t³/(6m) up to t = 1, then the
    momentum F/m · 1 once the force is over: x(3) = F/m · (1 + (3 − 2))... integrated by hand."""
    tables = {"f.csv": "t,f\n0,0\n1,2\n2,0\n"}
    with mp.workdps(50):
        md = R.read(FREE_TABLE, tables)
        m, F = mp.mpf(4), mp.mpf(2)
        # a(t) = F t/m on [0, 1], F (2 - t)/m on [1, 2], 0 after
        v1, x1 = F / (2 * m), F / (6 * m)
        v2 = v1 + F / (2 * m)
        x2 = x1 + v1 + (F / m) * (mp.mpf(1) / 2 - mp.mpf(1) / 6)
        tr = R.trajectory(md, [0.5, 1.0, 2.0, 3.5])
        assert near(tr.x[0][0], F * mp.mpf(0.5) ** 3 / (6 * m))
        assert near(tr.x[1][0], x1) and near(tr.x[2][0], x2) and near(tr.v[2][0], v2)
        assert near(tr.x[3][0], x2 + v2 * mp.mpf("1.5"))


def test_equilibria_closed_forms():
    """FPUT-β under a load F: k d + β d³ = F (the real root of the cubic, by Cardano); the issue's Lennard-Jones
    pair: x_eq ≈ (0.026770, 0.038421), ω² ≈ 2.3211, 18.6456."""
    text = scene('''
[masses]
p = "m"
[[springs]]
between = ["wall", "p"]
potential = "k*d**2/2 + beta*d**4/4"
[[forces]]
on = "p"
f = "F"
''', "m = 1.0\nk = 2.0\nbeta = 0.5\nF = 3.0")
    with mp.workdps(50):
        md = R.read(text)
        eq = R.static_equilibrium(md)
        k, b, F = mp.mpf(2), mp.mpf(0.5), mp.mpf(3)
        p, qq = k / b, -F / b  # d³ + p d + q = 0
        disc = mp.sqrt(qq**2 / 4 + p**3 / 27)
        rcbrt = lambda v: mp.sign(v) * mp.cbrt(abs(v))  # noqa: E731 - the real cube root
        d = rcbrt(-qq / 2 + disc) + rcbrt(-qq / 2 - disc)
        assert near(eq.x[0], d) and eq.stable
        assert near(eq.stiffness[0], k + 3 * b * d**2)
    lj = scene('''
[masses]
a = "m"
b = "m"
[[springs]]
between = ["wall", "a"]
potential = "eps*((r0/(r0 + d))**12 - 2*(r0/(r0 + d))**6)"
[[springs]]
between = ["a", "b"]
potential = "eps*((r0/(r0 + d))**12 - 2*(r0/(r0 + d))**6)"
[gravity]
g = "g"
''', "m = 0.3\neps = 0.05\nr0 = 1.12\ng = 0.1")
    with mp.workdps(50):
        md = R.read(lj)
        eq = R.static_equilibrium(md)
        assert abs(eq.x[0] - mp.mpf("0.026770")) < 1e-6 and abs(eq.x[1] - mp.mpf("0.038421")) < 1e-6
        ms = R.modes(md, eq)
        assert abs(ms.omega2[0] - mp.mpf("2.3211")) < 1e-4 and abs(ms.omega2[1] - mp.mpf("18.6456")) < 1e-4
        # each spring's tension carries the weight below it: V'(d1) = 2 m g, V'(d2) = m g
        eps, r0, m, g = (mp.mpf(v) for v in (0.05, 1.12, 0.3, 0.1))
        lj_prime = lambda d: mp.diff(lambda x: eps * ((r0 / (r0 + x)) ** 12 - 2 * (r0 / (r0 + x)) ** 6), d)  # noqa: E731
        assert near(lj_prime(eq.extensions[0]), 2 * m * g, mp.mpf("1e-20"))
        assert near(lj_prime(eq.extensions[1]), m * g, mp.mpf("1e-20"))


def test_no_equilibrium_past_a_fold():
    """A Morse spring holds at most D·w/2 (its largest tension): a larger load has no equilibrium."""
    text = scene('''
[masses]
p = "m"
[[springs]]
between = ["wall", "p"]
potential = "D*(1 - exp(-w*d))**2"
[gravity]
g = "g"
''', "m = 1.0\nD = 1.0\nw = 2.0\ng = {g}")
    with mp.workdps(40):
        R.static_equilibrium(R.read(text.format(g=0.9)))  # below D w / 2 = 1: exists
        with pytest.raises(R.NoEquilibrium):
            R.static_equilibrium(R.read(text.format(g=1.1)))


@pytest.mark.parametrize("period, zeta", [(0.5, 0.0), (3.0, 0.0), (1.0, 0.2)])
def test_spectrum_rectangular_pulse_closed_form(period, zeta):
    """a_g = a0 on [0, t_d] (rows (0, a0), (t_d, a0); zero after): undamped u = −(a0/ω²)(1 − cos ωt) in the
    pulse, SD = 2a0/ω² if t_d >= T/2 else 2(a0/ω²) sin(ω t_d / 2) (the free vibration after it). Damped: the
    pulse response and the free decay from its end state, extrema located by hand."""
    a0, td = mp.mpf(0.7), mp.mpf(0.6)
    with mp.workdps(40):
        sd = R.sdof_peak([0.0, 0.6], [0.7, 0.7], period, zeta)
        w = 2 * mp.pi / period
        if zeta == 0:
            exact = 2 * a0 / w**2 if td >= period / 2 else 2 * a0 / w**2 * mp.sin(w * td / 2)
        else:
            z = mp.mpf(zeta)
            wd = w * mp.sqrt(1 - z * z)
            def u(t):  # the step response
                return -(a0 / w**2) * (1 - mp.exp(-z * w * t) * (mp.cos(wd * t) + z * w / wd * mp.sin(wd * t)))

            du = lambda t: mp.diff(u, t)  # noqa: E731
            cands = [abs(u(td))]
            t1 = mp.pi / wd  # first stationary point of the step response
            if t1 <= td:
                cands.append(abs(u(t1)))
            u1, v1 = u(td), du(td)
            A, B = u1, (v1 + z * w * u1) / wd
            free = lambda s: mp.exp(-z * w * s) * (A * mp.cos(wd * s) + B * mp.sin(wd * s))  # noqa: E731
            s1 = mp.findroot(lambda s: mp.diff(free, s), (mp.mpf(0), mp.pi / wd), solver="anderson")
            cands.append(abs(free(s1)))
            exact = max(cands)
        assert near(sd, exact, mp.mpf("1e-15"))
        parts = R.sdof_parts([0.0, 0.6], [0.7, 0.7], period, zeta)
        assert (parts[1] > parts[0]) == (td < period / 2 and zeta == 0) or zeta != 0


def test_rsa_single_mass_closed_form():
    """One mass on a wall spring: Γ = √m (φ = 1/√m), M* = m, peak x = SD, base shear = k·SD = m ω² SD; SRSS =
    CQC for one mode; ρ = 1 on the diagonal."""
    text = scene('''
[masses]
p = "m"
[[springs]]
between = ["wall", "p"]
k = "k"
[damping]
modal = 0.05
''', "m = 3.0\nk = 12.0")
    with mp.workdps(40):
        md = R.read(text)
        ref = R.rsa(md, lambda T, z: mp.mpf("0.01") * T)
        m, k = mp.mpf(3), mp.mpf(12)
        T = 2 * mp.pi / mp.sqrt(k / m)
        # a number in an expression field is its decimal (0.05 = 1/20), a [parameters] value its binary float
        assert near(abs(ref.gamma[0]), mp.sqrt(m)) and near(ref.zeta[0], mp.mpf("0.05"))
        sd = mp.mpf("0.01") * T
        assert near(ref.sd[0], sd)
        for how in ("srss", "cqc"):
            c = ref.combined(how)
            assert near(c["displacement"][0], sd)
            assert near(c["spring_force"][0], k * sd)
            assert near(c["base_shear"], k * sd)
        assert near(R.cqc_rho(mp.mpf(2), mp.mpf(2), mp.mpf("0.05"), mp.mpf("0.05")), 1)


def test_participation_sums_to_the_total_mass():
    """Σ M*_j = Σ m_i for any scene (r = 1 lies in the span of the modes), here at a 1e16 contrast."""
    text = scene('''
[masses]
a = "m"
b = "1e8*m"
c = "m/1e8"
[[springs]]
between = ["wall", "a"]
k = "k"
[[springs]]
between = ["a", "b"]
k = "k*1e8"
[[springs]]
between = ["b", "c"]
k = "k"
''', "m = 1.0\nk = 1.0")
    with mp.workdps(60):
        md = R.read(text)
        ms = R.modes(md)
        gam = R.participation(md, ms)
        assert near(mp.fsum(g * g for g in gam), md.total_mass, mp.mpf("1e-40"))


LOADED = scene('''
[masses]
a = "m"
b = "2*m"
c = "m/2"
[[springs]]
between = ["wall", "a"]
k = "k"
[[springs]]
between = ["a", "b"]
k = "3*k"
[[dampers]]
between = ["b", "c"]
c = "cd"
[[forces]]
on = "b"
f = "F/2 + F*sin(W*t + 0.3)"
[[forces]]
on = "c"
table = "f.csv"
[ground]
table = "g.csv"
[gravity]
g = "grav"
[damping]
rayleigh = ["0.05", "0.002"]
[initial]
x = [0.1, -0.2, 0.05]
v = [0.0, 0.3, -0.1]
''', "m = 1.5\nk = 4.0\ncd = 0.7\nF = 0.8\nW = 2.3\ngrav = -0.5")


def test_loaded_trajectory_against_dop853():
    """The trajectory engine (modal state space, harmonics in closed form, tables piece by piece, a damped free
    piece: c hangs on b by a dashpot only) against SciPy's DOP853 at rtol 1e-12, integrated row to row of the
    tables on M x'' = F(t) − C x' − K x assembled here by hand."""
    import numpy as np
    from scipy.integrate import solve_ivp

    tables = {"f.csv": "t,f\n0.2,0\n0.7,1.5\n1.1,-0.5\n1.6,0\n", "g.csv": "t,a\n0,0.3\n0.9,-0.6\n1.3,0.2\n"}
    md = R.read(LOADED, tables)
    m, k, cd, F, W, grav = 1.5, 4.0, 0.7, 0.8, 2.3, -0.5
    M = np.diag([m, 2 * m, m / 2])
    K = np.array([[4 * k, -3 * k, 0], [-3 * k, 3 * k, 0], [0, 0, 0]])
    C = np.array([[0, 0, 0], [0, cd, -cd], [0, -cd, cd]]) + 0.05 * M + 0.002 * K
    fT = lambda t: np.interp(t, [0.2, 0.7, 1.1, 1.6], [0, 1.5, -0.5, 0]) if 0.2 <= t <= 1.6 else 0.0  # noqa: E731
    gT = lambda t: np.interp(t, [0, 0.9, 1.3], [0.3, -0.6, 0.2]) if 0 <= t <= 1.3 else 0.0  # noqa: E731

    def rhs(t, y):
        x, v = y[:3], y[3:]
        f = M @ np.full(3, grav) - M @ np.ones(3) * gT(t)
        f[1] += F / 2 + F * np.sin(W * t + 0.3)
        f[2] += fT(t)
        return np.concatenate([v, np.linalg.solve(M, f - C @ v - K @ x)])

    times = [0.5, 1.2, 2.5, 4.0]
    breaks = [0.0, 0.2, 0.7, 0.9, 1.1, 1.3, 1.6, 4.0]
    y = np.array([0.1, -0.2, 0.05, 0.0, 0.3, -0.1])
    ref = {}
    for a, b in zip(breaks, breaks[1:]):
        sol = solve_ivp(rhs, (a, b), y, method="DOP853", rtol=1e-12, atol=1e-14, dense_output=True)
        for t in times:
            if a <= t <= b:
                ref[t] = sol.sol(t)[:3]
        y = sol.y[:, -1]
    tr = R.trajectory(md, times)
    for r, t in enumerate(times):
        assert np.allclose([float(v) for v in tr.x[r]], ref[t], rtol=0, atol=1e-9), (t, tr.x[r], ref[t])


@pytest.mark.parametrize("left, right, family", [
    ("wall", "wall", lambda j, n: mp.sin(j * mp.pi / (2 * (n + 1))) ** 2),
    ("free", "free", lambda j, n: mp.sin((j - 1) * mp.pi / (2 * n)) ** 2),
    ("wall", "free", lambda j, n: mp.sin((2 * j - 1) * mp.pi / (2 * (2 * n + 1))) ** 2),
    ("ring", "ring", None),
])
def test_chain_closed_forms(left, right, family):
    """Uniform [chain] of 7 masses: ω_j² = (4k/m)·sin²(...) for fixed–fixed, free–free, fixed–free ends; a ring's
    ω² = (4k/m)·sin²(πj/n) each twice but 0 and (n even) the top; so the oracle's [chain] reading is the README's."""
    text = f'name = "ch"\n[parameters]\nm = 2.0\nk = 3.0\n[chain]\nn = 7\nmass = "m"\nk = "k"\nleft = "{left}"\nright = "{right}"\n'
    with mp.workdps(40):
        ms = R.modes(R.read(text))
        n, m, k = 7, mp.mpf(2), mp.mpf(3)
        if family is None:
            expected = sorted(4 * k / m * mp.sin(mp.pi * j / n) ** 2 for j in range(n))
        else:
            expected = [4 * k / m * family(j, n) for j in range(1, n + 1)]
        assert all(near(a, b, mp.mpf("1e-30")) or abs(a - b) < mp.mpf("1e-35") for a, b in zip(ms.omega2, expected))
