"""Periodic chains (issue 35): the cell, crossings, the complex band structure against the product's own frf,
finite chains named by band (rings against an extended-precision eigen-solve, edge and defect modes), the density
of states, a wave packet at the group velocity, damped and pre-stressed bands, the generated band functions
against the symbolic forms, the files and the command line, hostile scenes in one line."""

from __future__ import annotations

import json

import mpmath as mp
import numpy as np
import pytest
from helpers import one_line_error, run_cli

import springchain as sc


def diatomic(n=8, m1=1.0, m2=3.0, k1=1.0, k2=2.0, left="free", right="free", **extra):
    return sc.scene_from_dict({
        "name": f"dia{n}{left}", "parameters": {"m1": m1, "m2": m2, "k1": k1, "k2": k2},
        "chain": {"n": n, "mass": "m1*(1 - i % 2) + m2*(i % 2)", "k": "k1*(1 - i % 2) + k2*(i % 2)",
                  "left": left, "right": right}, **extra})


def textbook_lambda(m1, m2, k1, k2, q, dps=60):
    """ω²∓ of the diatomic chain (no cancellation in the lower one: 4 k1 k2 sin²(q/2) / (m1 m2 ω²+))."""
    with mp.workdps(dps):
        m1, m2, k1, k2, q = (mp.mpf(x) for x in (m1, m2, k1, k2, q))
        a = (k1 + k2) * (1 / m1 + 1 / m2) / 2
        top = a + mp.sqrt(a * a - 4 * k1 * k2 * mp.sin(q / 2) ** 2 / (m1 * m2))
        return [4 * k1 * k2 * mp.sin(q / 2) ** 2 / (m1 * m2 * top), top]


# -- the cell ---------------------------------------------------------------------------------------
def test_the_period_follows_the_symbols_not_the_values():
    from springchain.derive.bands.model import band_cell

    def period(mass, k="k"):
        s = sc.scene_from_dict({"name": "c", "parameters": {"m": 1.0, "m1": 2.0, "m2": 2.0, "k": 1.0},
                                "chain": {"n": 12, "mass": mass, "k": k}})
        return band_cell(s).size

    assert period("m1*(1 - i % 2) + m2*(i % 2)") == 2  # m1 = m2 at the scene's values: still two masses
    assert period("m") == 1
    assert period("m", "k*(2 + cos(2*pi*i/3))") == 3
    assert period("m*(1 + (i % 3)*(i % 2))", "k*(1 + i % 4)") == 12
    cell = band_cell(sc.load("mass_in_mass"))
    assert cell.names == ("a", "r") and [(s.a, s.b, s.reach) for s in cell.springs] == [(0, 0, 1), (0, 1, 0)]


def test_cell_expansion_and_ends():
    scene = sc.load("mass_in_mass")
    assert scene.n == 60 and scene.mass_names[:4] == ("a_0", "r_0", "a_1", "r_1")
    walls = sc.scene_from_dict({"name": "w", "parameters": {"m": 1.0, "k": 1.0},
                                "cell": {"cells": 3, "left": "wall", "right": "wall", "masses": {"a": "m", "b": "m"},
                                         "springs": [{"between": ["a", "b"], "k": "k"},
                                                     {"between": ["b", "a+1"], "k": "k"},
                                                     {"between": ["a", "a+2"], "k": "k"}]}})
    ends = sorted((s.a, s.b) for s in walls.springs)
    # b_2 -> wall (the missing a_3); wall -> a_0 (from b_-1) and from a_-2; wall -> a_1 (index 2) from a_-1;
    # a_1 -> wall and a_2 -> wall (a+2 past the end)
    assert ends.count((-1, 0)) == 2 and ends.count((-1, 2)) == 1 and (5, -1) in ends
    assert ends.count((2, -1)) == 1 and ends.count((4, -1)) == 1
    assert len(walls.springs) == 3 + 4 + 5  # inside; to the next cell (two on walls); two cells on (four on walls)


def test_characteristic_polynomial_is_sympys_determinant_with_positive_coefficients():
    import sympy as sp
    from springchain.derive.bands.dispersion import dispersion
    from springchain.derive.bands.model import band_cell

    for name in ("diatomic", "triatomic", "mass_in_mass", "next_nearest"):
        d = dispersion(band_cell(sc.load(name)))
        assert not any(isinstance(a, sp.Number) and a < 0 for c in d.coefficients for a in sp.preorder_traversal(c))
        w2 = sp.Symbol("w2")
        ref = (d.K - w2 * d.M).det()
        poly = d.polynomial.subs(d.omega ** 2, w2)
        rng = np.random.default_rng(1)
        for _ in range(3):
            sub = {d.q: sp.Float(rng.uniform(-3, 3), 30), w2: sp.Float(rng.uniform(0, 4), 30)}
            sub.update({s: sp.Float(rng.uniform(0.5, 2), 30) for s in d.cell.params.values()})
            a, b = complex(sp.N(poly.subs(sub), 30)), complex(sp.N(ref.subs(sub), 30))
            assert abs(a - b) <= 1e-20 * max(1.0, abs(b))


# -- crossings ----------------------------------------------------------------------------------------
def test_crossing_branches_keep_their_identity():
    """Two chains in one cell, not coupled: ω_a = 2 sqrt(k1/m1)|sin(q/2)| and ω_b = 2 sqrt(k2/m2)|sin q| (springs
    over two cells) cross at cos(q/2) = 1/2; followed by eigenvector continuity, each branch stays on its formula
    (sorting would swap them at q = 2π/3)."""
    scene = sc.scene_from_dict({"name": "cross", "parameters": {"m1": 1.0, "m2": 1.0, "k1": 1.0, "k2": 1.0},
                                "cell": {"cells": 4, "masses": {"a": "m1", "b": "m2"},
                                         "springs": [{"between": ["a", "a+1"], "k": "k1"},
                                                     {"between": ["b", "b+2"], "k": "k2"}]}})
    qs = np.linspace(0, np.pi, 61)[1:]
    b = sc.bands(scene, q=qs, finite=False, density=False)
    wa, wb = 4 * np.sin(qs / 2) ** 2, 4 * np.sin(qs) ** 2
    branch_a = int(np.argmin(np.abs(b.omega2[-1] - wa[-1])))
    np.testing.assert_allclose(b.omega2[:, branch_a], wa, rtol=1e-14)
    np.testing.assert_allclose(b.omega2[:, 1 - branch_a], wb, rtol=1e-13, atol=1e-300)
    ascending = np.sort(b.omega2, axis=1)
    assert not np.allclose(ascending[:, branch_a], wa)  # sorting would have swapped them


# -- Im q in the gaps against the product's own frf -------------------------------------------------
@pytest.mark.parametrize("name, cells", [("diatomic", 2), ("triatomic", 3)])
def test_attenuation_is_the_decay_of_the_frf_of_finite_chains(name, cells):
    """|H| from the first to the last mass of N cells falls as e^{-N Im q}: the slope of log|H| against N, over N
    with N Im q from 10 to 60, within 1e-9 of Im q (and of arccosh|cos q| of the textbook formula)."""
    base = sc.load(name)
    b = sc.bands(base, finite=False, density=False)
    gap = b.gaps[0]
    w = gap.centre
    kappa = float(b.attenuation([w])[0][0])
    assert kappa > 0
    if name == "diatomic":
        with mp.workdps(40):
            m1, m2, k1, k2, lam = 1, 3, 1, 2, mp.mpf(w) ** 2
            cos_q = 1 - (lam * (k1 + k2) * (m1 + m2) - lam ** 2 * m1 * m2) / (2 * k1 * k2)
            assert abs(float(mp.acosh(abs(cos_q))) - kappa) <= 1e-12 * kappa
    data = dict(base.source)
    ns = [int(x) for x in np.unique(np.linspace(10 / kappa, 60 / kappa, 6).round())]
    logs = []
    for N in ns:
        scene = sc.scene_from_dict({**data, "name": f"{name}{N}", "chain": {**data["chain"], "n": cells * N,
                                                                             "left": "free", "right": "free"},
                                    "initial": {}})
        h = sc.frf(scene, input=0, output=cells * N - 1, omega_min=w, omega_max=w * (1 + 1e-9), points=2)
        assert h.omega[0] == w
        logs.append(np.log(abs(h.H[0])))
    slope = np.polyfit(ns, logs, 1)[0]
    assert abs(slope + kappa) <= 1e-9 * kappa, (slope, kappa)


def test_next_nearest_attenuation_against_transfer_polynomial_roots():
    """Springs over one cell: det(K(z) − ω²M) is a polynomial in z = e^{iq} of higher degree; its roots at 50
    digits (mpmath) give Im q = min |ln|z||."""
    b = sc.bands("next_nearest", finite=False, density=False)
    m1, m2, k1, k2 = 1, mp.mpf("1.3"), 1, mp.mpf("0.6")
    omegas = [b.gaps[0].centre, 0.5 * (b.gaps[0].omega_lower + b.gaps[0].centre), 2.5]
    got = b.attenuation(omegas)[0]
    for w, kap in zip(omegas, got):
        with mp.workdps(50):
            lam = mp.mpf(w) ** 2

            def mul(p, q):  # Laurent polynomials as {power: coefficient}
                out = {}
                for i, a in p.items():
                    for j, c in q.items():
                        out[i + j] = out.get(i + j, 0) + a * c
                return out

            # K_aa = 2k1 + k2 (2 - z - 1/z), K_bb likewise, K_ab = -(k1 + k1/z), K_ba = -(k1 + k1 z)
            aa = {0: 2 * k1 + 2 * k2 - lam * m1, 1: -k2, -1: -k2}
            bb = {0: 2 * k1 + 2 * k2 - lam * m2, 1: -k2, -1: -k2}
            ab, ba = {0: -k1, -1: -k1}, {0: -k1, 1: -k1}
            det = mul(aa, bb)
            for p_, c in mul(ab, ba).items():
                det[p_] = det.get(p_, 0) - c
            lo, hi = min(det), max(det)
            roots = mp.polyroots([det.get(p_, 0) for p_ in range(hi, lo - 1, -1)], maxsteps=200, extraprec=200)
            ref = min(abs(mp.log(abs(z))) for z in roots)
        assert abs(kap - float(ref)) <= 1e-10 * max(float(ref), 1e-300), (w, kap, ref)


# -- finite chains named by band ----------------------------------------------------------------------
def _ring_reference(masses, springs, n):
    """Eigenvalues of the ring's D = M^-1/2 K M^-1/2 (n masses) at 50 digits: springs (i, j, k)."""
    with mp.workdps(50):
        K = mp.zeros(n, n)
        for i, j, k in springs:
            k = mp.mpf(k)
            K[i, i] += k
            K[j, j] += k
            K[i, j] -= k
            K[j, i] -= k
        D = mp.matrix(n, n)
        for i in range(n):
            for j in range(n):
                D[i, j] = K[i, j] / mp.sqrt(mp.mpf(masses[i]) * masses[j])
        return sorted(mp.eigsy(D, eigvals_only=True))


@pytest.mark.parametrize("cells", [5, 6])
def test_ring_eigenvalues_are_the_bands_at_2_pi_s_over_n(cells):
    n = 2 * cells
    scene = diatomic(n, left="ring", right="ring")
    b = sc.bands(scene, q=[2 * np.pi * s / cells for s in range(cells)], density=False)
    masses = [1.0, 3.0] * cells
    springs = [(i, (i + 1) % n, 1.0 if i % 2 == 0 else 2.0) for i in range(n)]
    ref = _ring_reference(masses, springs, n)
    bands = np.sort(b.omega2.reshape(-1))
    finite = np.sort([m.omega2 for m in b.finite])
    for got in (bands, finite):
        for g, r in zip(got, ref):
            assert (g == 0 and abs(r) < 1e-40) or abs(g - float(r)) <= 1e-13 * abs(float(r)), (g, r)
    for m in b.finite:  # every mode named by band with q = 2πs/N
        assert m.kind == "band"
        s = m.q * cells / (2 * np.pi)
        assert abs(s - round(s)) <= 1e-6, m


def test_edge_mode_of_the_free_diatomic_chain():
    b = sc.bands("diatomic", density=False)
    (edge,) = [m for m in b.finite if m.kind != "band"]
    assert edge.kind == "edge" and b.gaps[0].omega_lower < edge.omega < b.gaps[0].omega_upper
    kappa = float(b.attenuation([edge.omega])[0][0])
    assert edge.localisation == pytest.approx(1 / kappa, rel=1e-12)
    # its shape decays by e^{-kappa} per cell away from its end
    from springchain._modules import system_of

    spec = system_of(b.scene)[0].spectrum
    k = int(np.argmin(np.abs(spec.omega2 - edge.omega2)))
    amp = np.abs(spec.shapes[:, k]).reshape(-1, 2)[:, 0]
    ends = amp if amp[0] > amp[-1] else amp[::-1]
    ratio = ends[3:9] / ends[2:8]
    np.testing.assert_allclose(ratio, np.exp(-kappa), rtol=1e-6)
    assert sum(m.kind == "band" for m in b.finite) == 79


def test_every_band_mode_carries_its_bloch_weight():
    """``bloch_weight`` is given for every band mode (null only for gap modes): the fraction of the mode in the
    span of its band's Bloch waves at ±q. Reference written here: the finite chain's modes from the 50-digit
    eigen-solve of its D, the cell vector from the 2 x 2 D(q) of the textbook diatomic chain, the projection by
    least squares. A ring's modes are Bloch waves: weight 1."""
    n = 16
    b = sc.bands(diatomic(n), density=False)
    data = b.to_json()["finite"]["modes"]
    assert all((m["bloch_weight"] is None) == (m["kind"] != "band") for m in data)
    masses = [1.0, 3.0] * (n // 2)
    springs = [(i, i + 1, 1.0 if i % 2 == 0 else 2.0) for i in range(n - 1)]
    with mp.workdps(50):
        K = mp.zeros(n, n)
        for i, j, k in springs:
            K[i, i] += k
            K[j, j] += k
            K[i, j] -= k
            K[j, i] -= k
        D = mp.matrix(n, n)
        for i in range(n):
            for j in range(n):
                D[i, j] = K[i, j] / mp.sqrt(mp.mpf(masses[i]) * masses[j])
        w2, vecs = mp.eigsy(D)
        order = sorted(range(n), key=lambda c: w2[c])
        modes = np.array([[float(vecs[i, c]) for c in order] for i in range(n)])
    for m, col in zip(b.finite, modes.T):
        if m.kind != "band":
            continue
        q = m.q
        off = -(1.0 + 2.0 * np.exp(-1j * q)) / np.sqrt(3.0)  # D(q)[0, 1]: k1 inside the cell, k2 to the next
        Dq = np.array([[3.0, off], [np.conj(off), 1.0]])
        lam, U = np.linalg.eigh(Dq)
        u = U[:, m.band]
        c = np.arange(n // 2)[:, None]
        W = np.stack([(np.exp(1j * q * c) * u).ravel(), (np.exp(-1j * q * c) * u.conj()).ravel()], axis=1)
        coef = np.linalg.lstsq(W, col.astype(complex), rcond=1e-8)[0]
        ref = np.linalg.norm(W @ coef) ** 2 / np.linalg.norm(col) ** 2
        assert 0.0 <= m.weight <= 1.0 and m.weight == pytest.approx(ref, abs=1e-8), (m, ref)
    ring = sc.bands(diatomic(12, left="ring", right="ring"), q=[0.0], density=False)
    assert all(m.kind == "band" and abs(m.weight - 1.0) < 1e-12 for m in ring.finite)


def test_a_defect_cell_gives_a_defect_mode_in_the_gap():
    """A ring of diatomic cells with one heavy mass changed, read against the perfect chain's bands."""
    cells = 24
    n = 2 * cells
    masses = {f"x{i}": ("m1" if i % 2 == 0 else "m2") for i in range(n)}
    masses["x24"] = "md"  # cell 12's first mass
    springs = [{"between": [f"x{i}", f"x{(i + 1) % n}"], "k": "k1" if i % 2 == 0 else "k2"} for i in range(n)]
    defect = sc.scene_from_dict({"name": "defect", "parameters": {"m1": 1.0, "m2": 3.0, "md": 0.4, "k1": 1.0,
                                                                  "k2": 2.0}, "masses": masses, "springs": springs})
    b = sc.bands(diatomic(n, left="ring", right="ring"), finite=defect, density=False)
    gap_modes = [m for m in b.finite if m.kind != "band"]
    assert gap_modes and all(m.kind == "defect" for m in gap_modes)
    for m in gap_modes:
        assert any(g.omega_lower < m.omega < g.omega_upper for g in b.gaps) or m.omega > b.edges[-1].omega_high
        assert m.localisation == pytest.approx(1 / float(b.attenuation([m.omega])[0][0]), rel=1e-12)


# -- density of states ----------------------------------------------------------------------------
def test_density_of_states_monatomic_closed_form_and_diatomic_formula():
    mono = sc.scene_from_dict({"name": "mono", "parameters": {"m": 2.0, "k": 3.0}, "chain": {"n": 4, "mass": "m",
                                                                                          "k": "k"}})
    b = sc.bands(mono, finite=False)
    top = 2 * np.sqrt(3.0 / 2.0)
    inside = b.omega_grid < top
    ref = 2 / (np.pi * np.sqrt(top ** 2 - b.omega_grid[inside] ** 2))
    np.testing.assert_allclose(b.dos[inside, 0], ref, rtol=1e-10)
    assert np.all(b.dos[~inside] == 0)
    # diatomic: g(ω) = 1/(π |dω/dq|) at q(ω) from cos q = 1 − (ω²(k1+k2)(m1+m2) − ω⁴ m1 m2)/(2 k1 k2)
    d = sc.bands("diatomic", finite=False)
    m1, m2, k1, k2 = 1.0, 3.0, 1.0, 2.0
    for w, g in zip(d.omega_grid, d.dos.sum(axis=1)):
        with mp.workdps(40):
            lam = mp.mpf(w) ** 2
            c = 1 - (lam * (k1 + k2) * (m1 + m2) - lam ** 2 * m1 * m2) / (2 * k1 * k2)
            if abs(c) >= 1:
                assert g == 0
                continue
            q = mp.acos(c)
            dc = -(2 * mp.mpf(w) * (k1 + k2) * (m1 + m2) - 4 * mp.mpf(w) ** 3 * m1 * m2) / (2 * k1 * k2)  # dc/dω
            ref = abs(dc) / (mp.pi * mp.sin(q))  # |dq/dω| / π
        assert g == pytest.approx(float(ref), rel=1e-9)


# -- a wave packet moves at the group velocity ------------------------------------------------------
def test_wave_packet_moves_at_the_group_velocity(tmp_path):
    cells, q0, width, start = 600, 1.0, 25.0, 150
    m1, m2, k1, k2 = 1.0, 3.0, 1.0, 2.0
    scene = diatomic(2 * cells)
    # the acoustic Bloch wave at q0 from D(q0) (the textbook 2 x 2, numpy here)
    kab = -(k1 + k2 * np.exp(-1j * q0))
    D = np.array([[(k1 + k2) / m1, kab / np.sqrt(m1 * m2)], [np.conj(kab) / np.sqrt(m1 * m2), (k1 + k2) / m2]])
    lam, vec = np.linalg.eigh(D)
    w0, u = np.sqrt(lam[0]), vec[:, 0] / np.sqrt([m1, m2])
    c = np.arange(cells)
    env = np.exp(-((c - start) ** 2) / (2 * width ** 2)) * np.exp(1j * q0 * c)
    wave = (env[:, None] * u[None, :]).reshape(-1)
    x0, v0 = wave.real.copy(), (-1j * w0 * wave).real.copy()
    t_end = 180.0
    run = sc.simulate(scene.with_initial(x=x0, v=v0), methods=["modal"], dt=t_end / 12, steps=12, out=tmp_path,
                      progress=False)
    x, v = run.x["modal"], run.v["modal"]
    m = np.tile([m1, m2], cells)
    energy = (0.5 * m * (v ** 2 + w0 ** 2 * x ** 2)).reshape(len(run.t), cells, 2).sum(axis=2)
    centre = (energy * c).sum(axis=1) / energy.sum(axis=1)
    speed = np.polyfit(run.t, centre, 1)[0]
    vg = sc.bands(scene, q=[q0], finite=False, density=False).velocity[0, 0]
    assert abs(speed - vg) <= 0.01 * vg, (speed, vg)


# -- damped and pre-stressed bands --------------------------------------------------------------------
def test_rayleigh_damping_per_band_closed_form():
    scene = diatomic(8, damping={"rayleigh": [0.05, 0.02]})
    qs = [0.3, 1.2, 2.7]
    b = sc.bands(scene, q=qs, finite=False, density=False)
    for k, q in enumerate(qs):
        for j, lam in enumerate(textbook_lambda(1, 3, 1, 2, q)):
            with mp.workdps(40):
                zeta = (mp.mpf("0.05") + mp.mpf("0.02") * lam) / (2 * mp.sqrt(lam))
            assert b.damped.zeta[k, j] == pytest.approx(float(zeta), rel=1e-13)
    assert b.to_json()["damped"]["model"] == "rayleigh"


def test_dashpots_to_the_ground_proportional_to_the_masses():
    """Dashpots eta*m_i to the ground make C = eta M: the general (quadratic-eigenproblem) route gives
    zeta = eta/(2 omega) per band."""
    scene = diatomic(8, dampers=[{"between": ["i", "wall"], "c": "0.04*(m1*(1 - i % 2) + m2*(i % 2))"}])
    qs = [0.4, 2.0]
    b = sc.bands(scene, q=qs, finite=False, density=False)
    for k, q in enumerate(qs):
        for j, lam in enumerate(textbook_lambda(1, 3, 1, 2, q)):
            assert b.damped.zeta[k, j] == pytest.approx(0.04 / (2 * float(mp.sqrt(lam))), rel=1e-9)


def test_pre_stressed_potential_ring_bands_are_those_of_its_stiffness():
    scene = sc.scene_from_dict({
        "name": "prestress", "parameters": {"m1": 1.0, "m2": 3.0, "k1": 1.0, "k2": 2.0, "T": 0.7, "b": 0.2},
        "chain": {"n": 8, "mass": "m1*(1 - i % 2) + m2*(i % 2)", "left": "ring", "right": "ring",
                  "potential": "T*d + (k1*(1 - i % 2) + k2*(i % 2))*d**2/2 + b*d**4/4"}})
    qs = [0.0, 0.8, 2.2, np.pi]
    b = sc.bands(scene, q=qs, finite=False, density=False)
    for k, q in enumerate(qs):
        for j, lam in enumerate(textbook_lambda(1, 3, 1, 2, q)):
            assert (lam == 0 and b.omega2[k, j] == 0) or b.omega2[k, j] == pytest.approx(float(lam), rel=1e-14)
    assert any("linearised" in n for n in b.notes)


# -- generated band functions against the symbolic forms ---------------------------------------------
@pytest.mark.parametrize("name", ["diatomic", "mass_in_mass", "next_nearest", "chain100k"])
def test_generated_band_functions_against_the_symbolic_forms(name):
    import sympy as sp
    from springchain.derive.bands.dispersion import dispersion
    from springchain.derive.bands.model import band_cell

    from springchain._modules import system_of

    scene = sc.load(name)
    system = system_of(scene)[0]
    d = dispersion(band_cell(scene))
    assert system.band_closed_form and d.branches is not None
    q = np.random.default_rng(7).uniform(-np.pi, np.pi, 9)
    got = {"omega2": system.band_omega2(q), "omega": system.band_omega(q), "velocity": system.group_velocity(q)}
    values = d.cell.values
    for what, exprs in (("omega2", d.branches), ("omega", d.frequencies), ("velocity", d.velocities)):
        for j, e in enumerate(exprs):
            f = sp.lambdify(d.q, e.subs(values), "mpmath")
            for k, qk in enumerate(q):
                with mp.workdps(30):
                    ref = f(mp.mpf(abs(qk))) * (np.sign(qk) if what == "velocity" else 1)
                assert got[what][k, j] == pytest.approx(float(ref), rel=1e-11, abs=1e-14)
    accurate = sc.bands(scene, q=q, finite=False, density=False)
    np.testing.assert_allclose(np.sort(accurate.omega2, axis=1), got["omega2"], rtol=1e-12)


def test_generated_group_velocity_is_finite_where_two_branches_touch():
    """The diatomic module with m1 = m2 = m, k1 = k2 = k: a monatomic chain folded into cells of two. By hand,
    with Q = q/2 the monatomic phase, ω = 2√(k/m) sin(Q/2): the lower branch is 2√(k/m) sin(|q|/4) and the upper
    2√(k/m) cos(|q|/4), so dω/dq = ±√(k/m) cos(|q|/4)/2 and ∓√(k/m) sin(|q|/4)/2 (odd in q). At q = π they touch
    and the closed form divides by the root of a vanishing discriminant (it gave ±inf): now each branch's limit
    from inside (0, π), finite, to 1e-15 at q = π and within 1e-9 from it, with no warning."""
    import warnings

    from springchain._modules import system_of

    k, m = 2.0, 3.0
    system = system_of(sc.load("diatomic").with_parameters(m1=m, m2=m, k1=k, k2=k))[0]
    eps = np.array([0.0, 1e-12, 1e-9, 1e-7, 1e-5, 1e-3, 3e-2, 0.5, 2.0])
    q = np.concatenate([np.pi - eps, -(np.pi - eps)])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        v = system.group_velocity(q)
    a, sign = np.abs(q), np.sign(q)
    lower = np.sqrt(k / m) * np.cos(a / 4) / 2 * sign
    upper = -np.sqrt(k / m) * np.sin(a / 4) / 2 * sign
    assert np.all(np.isfinite(v))
    scale = np.sqrt(k / m) / 2
    for got, ref in ((v[:, 0], lower), (v[:, 1], upper)):
        err = np.abs(got - ref) / scale
        assert np.all(err[np.tile(eps, 2) == 0] < 1e-15) and np.all(err < 1e-9), err
    # the textbook diatomic (m1 != m2): a gap at q = pi, where both velocities vanish (closed form kept)
    system = system_of(sc.load("diatomic"))[0]
    assert np.all(np.abs(system.group_velocity(np.array([np.pi]))) < 1e-15)


def test_generated_band_omega2_without_closed_form():
    from springchain._modules import system_of

    system = system_of(sc.load("triatomic"))[0]
    assert not system.band_closed_form
    q = np.linspace(-3, 3, 7)
    accurate = sc.bands("triatomic", q=q, finite=False, density=False)
    np.testing.assert_allclose(system.band_omega2(q), np.sort(accurate.omega2, axis=1), rtol=1e-12, atol=1e-14)


# -- files, xarray, the command line --------------------------------------------------------------
def test_files_and_xarray(tmp_path):
    b = sc.bands("mass_in_mass", points=101)
    paths = b.save(tmp_path)
    assert [p.name for p in paths] == ["mass_in_mass-bands.npz", "mass_in_mass-bands.json", "mass_in_mass-bands.png"]
    data = np.load(paths[0])
    assert data["q"].shape == (101,) and data["omega2"].shape == data["group_velocity"].shape == (101, 2)
    assert data["edges"].shape == (2, 2) and data["gaps"].shape == (1, 2) and data["finite_band"].shape == (60,)
    doc = json.loads(paths[1].read_text())
    assert doc["p"] == 2 and doc["closed_form"] and len(doc["branches"]) == 2 and doc["gaps"][0]["width"] > 0
    assert paths[2].stat().st_size > 10_000
    ds = b.to_xarray()
    assert ds["omega2"].dims == ("q", "branch") and ds["dos"].dims == ("frequency", "branch")
    assert float(ds["omega2"].sel(q=0.0, method="nearest").sel(branch=0)) == 0.0


def test_command_line(capsys, tmp_path):
    status, out, err = run_cli(["bands", "diatomic", "--json", "--out", tmp_path, "--no-figures"], capsys)
    assert status == 0, err
    doc = json.loads(out)
    assert doc["scene"] == "diatomic" and doc["finite"]["modes"][0]["band"] == 0 and len(doc["files"]) == 2
    assert doc["branches"][0]["omega2_expr"].startswith("4*k1*k2*sin(q/2)**2")
    status, out, _ = run_cli(["bands", "triatomic", "--out", tmp_path, "--no-figures"], capsys)
    assert status == 0 and "No closed-form branches" in out and "Gaps:" in out and "wrote" in out
    status, out, _ = run_cli(["bands", "mass_in_mass", "--latex", "--out", tmp_path, "--no-figures"], capsys)
    assert status == 0 and out.startswith("\\begin{align*}")
    status, out, _ = run_cli(["bands", "diatomic", "--set", "m2=1", "--set", "k2=1", "--json", "--out", tmp_path,
                              "--no-figures"], capsys)
    assert status == 0 and json.loads(out)["gaps"] == []  # the monatomic chain folded: no gap


HOSTILE = [
    ({"chain": {"n": 6, "mass": "m*(1 + i/100)", "k": "k"}}, ["chain.mass", "not periodic in i"]),
    ({"masses": {"a": "m"}, "springs": [{"between": ["a", "wall"], "k": "k"}]}, ["has no unit cell"]),
    ({"cell": {"cells": 3, "masses": {"a": "m", "r": "m"}, "springs": [{"between": ["a", "a+1"], "k": "k"}]}},
     ["cell.masses.r", "no spring holds this mass"]),
    ({"cell": {"cells": 3, "masses": {"a": "m", "r": "m - m"},
               "springs": [{"between": ["a", "a+1"], "k": "k"}, {"between": ["a", "r"], "k": "k"}]}},
     ["cell.masses.r"]),
    ({"cell": {"cells": 3, "masses": {"a": "m", "b": "m"}, "springs": [{"between": ["a", "b"], "k": "k"}]}},
     ["falls apart"]),
    ({"cell": {"cells": 3, "masses": {"a": "m"}, "springs": [{"between": ["a", "c+1"], "k": "k"}]}},
     ["cell.springs[0].between", "not a mass of the cell"]),
    ({"cell": {"cells": 30, "masses": {"a": "m"}, "springs": [{"between": ["a", "a+9"], "k": "k"}]}},
     ["reaches 9 cells on"]),
    ({"cell": {"cells": 2, "left": "ring", "right": "ring", "masses": {"a": "m"},
               "springs": [{"between": ["a", "a+2"], "k": "k"}]}}, ["cell.cells", "cells > 2"]),
    ({"cell": {"cells": 2, "masses": {"a": "m"}, "springs": [{"between": ["a", "a+1"], "k": "k"}]},
      "masses": {"b": "m"}}, ["both forms"]),
    ({"cell": {"cells": 3, "masses": {"a": "m", "b": "m"},
               "springs": [{"between": ["a", "b"], "potential": "k*d + k*d**2/2"},
                           {"between": ["b", "a+1"], "potential": "k*d**2/2"}]}},
     ["net force", "cell.masses.a"]),
]


@pytest.mark.parametrize("body, expect", HOSTILE, ids=range(len(HOSTILE)))
def test_hostile_periodic_scenes_are_refused_in_one_line(body, expect, capsys, tmp_path):
    from springchain.derive.errors import SceneError

    data = {"name": "bad", "parameters": {"m": 1.0, "k": 1.0}, **body}
    with pytest.raises(SceneError) as exc:
        sc.bands(sc.scene_from_dict(data), finite=False, density=False)
    line = str(exc.value)
    assert "\n" not in line and all(part in line for part in expect), line
    path = tmp_path / "bad.toml"
    path.write_text(_toml(data))
    one_line_error(*run_cli(["bands", path, "--out", tmp_path], capsys), *expect)


def _toml(data) -> str:
    """TOML text of a scene dict (tables of tables, arrays of tables)."""
    from helpers import toml_value

    lines = [f"name = {toml_value(data['name'])}", "[parameters]"]
    lines += [f"{k} = {toml_value(v)}" for k, v in data["parameters"].items()]
    for top, value in data.items():
        if top in ("name", "parameters"):
            continue
        if isinstance(value, list):
            for entry in value:
                lines.append(f"[[{top}]]")
                lines += [f"{k} = {toml_value(v)}" for k, v in entry.items()]
            continue
        lines.append(f"[{top}]")
        subs = {k: v for k, v in value.items() if isinstance(v, (dict, list)) and k != "between"
                and not (isinstance(v, list) and v and not isinstance(v[0], dict))}
        lines += [f"{k} = {toml_value(v)}" for k, v in value.items() if k not in subs]
        for k, v in subs.items():
            if isinstance(v, dict):
                lines.append(f"[{top}.{k}]")
                lines += [f"{kk} = {toml_value(vv)}" for kk, vv in v.items()]
            else:
                for entry in v:
                    lines.append(f"[[{top}.{k}]]")
                    lines += [f"{kk} = {toml_value(vv)}" for kk, vv in entry.items()]
    return "\n".join(lines) + "\n"


def test_points_out_of_range_are_refused(capsys, tmp_path):
    one_line_error(*run_cli(["bands", "diatomic", "--points", "2", "--out", tmp_path], capsys), "--points")


# -- modes of a periodic scene named by band -------------------------------------------------------------
@pytest.mark.parametrize("cells", [5, 8])
def test_modes_of_a_ring_are_named_by_band_at_2_pi_s_over_n(cells, capsys):
    """``modes`` of a diatomic ring of N cells: every mode a band mode with q = 2πs/N, and its ω² that of the
    ring's D from a 50-digit eigen-solve written here and ω²_j(2πs/N) of the textbook formula, to 1e-13."""
    n = 2 * cells
    scene = diatomic(n, left="ring", right="ring")
    data = sc.modes(scene).to_json()
    masses = [1.0, 3.0] * cells
    springs = [(i, (i + 1) % n, 1.0 if i % 2 == 0 else 2.0) for i in range(n)]
    ref = _ring_reference(masses, springs, n)
    assert len(data["modes"]) == n and data["gap_modes"] == []
    for rec, r in zip(data["modes"], ref):
        assert rec["kind"] == "band" and rec["localisation_length"] is None and rec["bloch_weight"] > 1 - 1e-12
        s = rec["q"] * cells / (2 * np.pi)
        assert abs(s - round(s)) <= 1e-6, rec
        lam = textbook_lambda(1, 3, 1, 2, 2 * mp.pi * round(s) / cells)[rec["band"]]
        for want in (r, lam):
            want = float(want)
            assert (rec["omega2_value"] == 0 and abs(want) < 1e-40) or \
                abs(rec["omega2_value"] - want) <= 1e-13 * abs(want), (rec, want)
    text = sc.modes(scene).to_text()
    assert "Modes named by band (unit cell of 2 masses" in text and text.count(" band 1, q = ") == cells


def test_modes_names_gap_modes_and_costs_nothing_without_a_cell(monkeypatch):
    """The free diatomic chain's edge mode is named with its localisation length (1/Im q of the attenuation);
    a [masses] scene and a non-periodic [chain] get no band fields, and a [masses] scene never loads a module
    for them; past MAX_MASSES masses a note says where the names are."""
    import springchain._mode_bands as mb

    m = sc.modes("diatomic")
    data = m.to_json()
    (edge,) = data["gap_modes"]
    b = sc.bands("diatomic", finite=False, density=False)
    kappa = float(b.attenuation([np.sqrt(edge["omega2"])])[0][0])
    assert edge["kind"] == "edge" and edge["localisation_length"] == pytest.approx(1 / kappa, rel=1e-12)
    assert "edge mode in a gap, localisation length" in m.to_text()
    assert all(r["kind"] == "band" for r in data["modes"])  # the listed ends: 10 lowest, 10 highest
    cell = sc.modes("mass_in_mass").to_json()
    assert len(cell["modes"]) == 60 and {r["band"] for r in cell["modes"]} == {0, 1}
    calls = []
    monkeypatch.setattr("springchain._modules.system_of", lambda *a, **k: calls.append(a) or 1 / 0)
    plain = sc.modes("building").to_json()
    assert calls == [] and not any("band" in r for r in plain["modes"]) and "gap_modes" not in plain
    monkeypatch.undo()
    bumpy = sc.scene_from_dict({"name": "bumpy", "parameters": {"m": 1.0, "k": 1.0},
                                "chain": {"n": 12, "mass": "m*(1 + i**2/100)", "k": "k"}})
    assert not any("band" in r for r in sc.modes(bumpy).to_json()["modes"])
    monkeypatch.setattr(mb, "MAX_MASSES", 10)
    long = sc.modes(diatomic(12)).to_json()
    assert not any("band" in r for r in long["modes"]) and any("named by band up to 10" in n for n in long["notes"])
