"""Bands of periodic chains at any contrast (issue 35): ω²_j(q), band edges and gap widths against 50-digit
references written here from the scene's numbers (the textbook diatomic formula; mpmath eigen-solves of D(q)),
the acoustic branch exactly 0 at q = 0, group velocities against the formula's derivative."""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest

import springchain as sc

CONTRASTS = [1e-12, 1e-8, 1e-4, 0.5, 3.0, 1e4, 1e8, 1e12]
#: Sampled q (the ends, tiny q where the acoustic branch is O(q²), and the interior).
Q = [0.0, 1e-9, 1e-5, 0.01, 0.7, 1.9, 2.9, np.pi, -1.3]
TOL = 1e-13


def diatomic(m1, m2, k1, k2, n=8):
    return sc.scene_from_dict({
        "name": "dia", "parameters": {"m1": m1, "m2": m2, "k1": k1, "k2": k2},
        "chain": {"n": n, "mass": "m1*(1 - i % 2) + m2*(i % 2)", "k": "k1*(1 - i % 2) + k2*(i % 2)"}})


def mass_in_mass(m1, m2, k1, k2, cells=4):
    return sc.scene_from_dict({
        "name": "mim", "parameters": {"m1": m1, "m2": m2, "k1": k1, "k2": k2},
        "cell": {"cells": cells, "masses": {"a": "m1", "r": "m2"},
                 "springs": [{"between": ["a", "a+1"], "k": "k1"}, {"between": ["a", "r"], "k": "k2"}]}})


def textbook(m1, m2, k1, k2, q):
    """The diatomic chain's ω²∓(q) at 60 digits: (k1 + k2)(1/m1 + 1/m2)/2 ∓ sqrt(that² − 4 k1 k2 sin²(q/2)/(m1 m2))."""
    with mp.workdps(60):
        m1, m2, k1, k2, q = (mp.mpf(x) for x in (m1, m2, k1, k2, q))
        a = (k1 + k2) * (1 / m1 + 1 / m2) / 2
        r = mp.sqrt(a * a - 4 * k1 * k2 * mp.sin(q / 2) ** 2 / (m1 * m2))
        return [a - r, a + r]


def eig_reference(masses, springs, q):
    """Eigenvalues of D(q) = M^-1/2 K(q) M^-1/2 at 60 digits; springs (a, b, reach, k), -1 the ground."""
    with mp.workdps(60):
        p = len(masses)
        K = mp.matrix(p, p)
        for a, b, r, k in springs:
            k = mp.mpf(k)
            if a < 0 or b < 0:
                c = b if a < 0 else a
                K[c, c] += k
                continue
            e = mp.expj(mp.mpf(q) * r)
            K[a, a] += k
            K[b, b] += k
            K[a, b] -= k * e
            K[b, a] -= k * mp.conj(e)
        m = [mp.mpf(x) for x in masses]
        D = mp.matrix(p, p)
        for i in range(p):
            for j in range(p):
                D[i, j] = K[i, j] / mp.sqrt(m[i] * m[j])
        return sorted(mp.re(x) for x in mp.eighe(D, eigvals_only=True))


def rel(got, ref):
    with mp.workdps(60):
        return 0.0 if ref == 0 and got == 0 else float(abs(mp.mpf(got) - ref) / abs(ref))


@pytest.mark.parametrize("which", ["mass", "stiffness"])
@pytest.mark.parametrize("c", CONTRASTS)
def test_diatomic_bands_edges_and_gap_at_any_contrast(c, which):
    m1, m2, k1, k2 = (1.0, c, 1.0, 1.7) if which == "mass" else (1.0, 2.5, 1.0, c)
    b = sc.bands(diatomic(m1, m2, k1, k2), q=Q, finite=False, density=False)
    for k, q in enumerate(Q):
        ref = textbook(m1, m2, k1, k2, q)
        got = b.omega2[k]  # the textbook branches never cross: continuity order = ascending
        for j in range(2):
            if q == 0 and j == 0:
                assert got[0] == 0.0  # exactly, by structure
            else:
                assert rel(got[j], ref[j]) <= TOL, (q, j, got[j], ref[j])
    lo_pi, hi_pi = textbook(m1, m2, k1, k2, np.pi)
    top = textbook(m1, m2, k1, k2, 0.0)[1]
    e0, e1 = b.edges
    assert e0.low == 0.0 and rel(e0.high, lo_pi) <= TOL and rel(e1.low, hi_pi) <= TOL and rel(e1.high, top) <= TOL
    (gap,) = b.gaps
    with mp.workdps(60):
        width = mp.sqrt(hi_pi) - mp.sqrt(lo_pi)
    assert rel(gap.width, width) <= TOL and rel(gap.lower, lo_pi) <= TOL and rel(gap.upper, hi_pi) <= TOL


@pytest.mark.parametrize("which", ["mass", "stiffness"])
@pytest.mark.parametrize("c", CONTRASTS)
def test_mass_in_mass_against_eigen_solves_of_D(c, which):
    m1, m2, k1, k2 = (1.0, c, 1.0, 0.3) if which == "mass" else (1.0, 0.5, 1.0, c)
    springs = [(0, 0, 1, k1), (0, 1, 0, k2)]
    b = sc.bands(mass_in_mass(m1, m2, k1, k2), q=Q, finite=False, density=False)
    for k, q in enumerate(Q):
        ref = eig_reference([m1, m2], springs, q)
        for j in range(2):
            if q == 0 and j == 0:
                assert b.omega2[k, 0] == 0.0
            else:
                assert rel(b.omega2[k, j], ref[j]) <= TOL, (q, j)
    at0, atpi = eig_reference([m1, m2], springs, 0.0), eig_reference([m1, m2], springs, np.pi)
    e0, e1 = b.edges  # both branches rise monotonically from q = 0 to pi
    assert e0.low == 0.0 and rel(e0.high, atpi[0]) <= TOL
    assert rel(e1.low, at0[1]) <= TOL and rel(e1.high, atpi[1]) <= TOL
    (gap,) = b.gaps
    with mp.workdps(60):
        assert rel(gap.width, mp.sqrt(at0[1]) - mp.sqrt(atpi[0])) <= TOL


def test_acoustic_branch_is_exactly_zero_and_nothing_is_negative():
    for c in CONTRASTS:
        b = sc.bands(diatomic(1.0, c, 1.0, 1 / c), points=1001, finite=False, density=False)
        zero = np.flatnonzero(b.q == 0.0)
        assert zero.size == 1 and b.omega2[zero[0], 0] == 0.0
        assert np.all(b.omega2 >= 0) and np.all(b.omega2[b.q != 0] > 0)
        assert np.isrealobj(b.omega2) and np.all(np.isfinite(b.velocity))
    # q = 2π is q = 0 (the bands are 2π-periodic)
    assert sc.bands(diatomic(1.0, 3.0, 1.0, 2.0), q=[2 * np.pi, -4 * np.pi], finite=False,
                    density=False).omega2[:, 0].tolist() == [0.0, 0.0]


@pytest.mark.parametrize("c", [1e-10, 1.0, 1e10])
def test_group_velocity_is_the_derivative_of_the_branch(c):
    """dω/dq against the textbook formula differentiated at 60 digits; at q = 0 the sound speed
    sqrt(k1 k2 / ((k1 + k2)(m1 + m2))) cells/s (the long-wave limit, no division by ω)."""
    m1, m2, k1, k2 = 1.0, 2.0 * c, 1.0, 3.0
    qs = [0.0, 1e-7, 0.4, 1.5, 2.8, -0.9]
    b = sc.bands(diatomic(m1, m2, k1, k2), q=qs, finite=False, density=False)
    for k, q in enumerate(qs):
        if q == 0:
            with mp.workdps(60):
                ref = [mp.sqrt(mp.mpf(k1) * k2 / ((k1 + k2) * (mp.mpf(m1) + m2))), 0]
        else:  # dr/dq = -k1 k2 sin q / (m1 m2 r), dλ∓/dq = ∓dr/dq, dω/dq = (dλ/dq)/(2ω), at 80 digits
            with mp.workdps(80):
                a = (k1 + k2) * (1 / mp.mpf(m1) + 1 / mp.mpf(m2)) / 2
                r = mp.sqrt(a * a - 4 * k1 * k2 * mp.sin(mp.mpf(q) / 2) ** 2 / (m1 * mp.mpf(m2)))
                lam = [4 * k1 * k2 * mp.sin(mp.mpf(q) / 2) ** 2 / (m1 * mp.mpf(m2) * (a + r)), a + r]
                dr = -k1 * k2 * mp.sin(mp.mpf(q)) / (m1 * mp.mpf(m2) * r)
                ref = [-dr / (2 * mp.sqrt(lam[0])), dr / (2 * mp.sqrt(lam[1]))]
        for j in range(2):
            if ref[j] == 0:
                assert b.velocity[k, j] == 0.0
            else:
                assert rel(b.velocity[k, j], ref[j]) <= 1e-11, (q, j)
    assert rel(b.sound_speed, mp.sqrt(mp.mpf(k1) * k2 / ((k1 + k2) * (mp.mpf(m1) + m2)))) <= 1e-13


def test_triatomic_and_next_nearest_against_eigen_solves():
    """Cells without a closed form (p = 3) and with springs over one cell (next-nearest), bundled, at random q."""
    rng = np.random.default_rng(35)
    qs = np.concatenate([[0.0, 1e-6, np.pi], rng.uniform(-np.pi, np.pi, 8)])
    tri = sc.bands("triatomic", q=qs, finite=False, density=False)
    nn = sc.bands("next_nearest", q=qs, finite=False, density=False)
    cases = [(tri, [1.0, 2.0, 3.0], [(0, 1, 0, 1.0), (1, 2, 0, 1.0), (2, 0, 1, 1.0)]),
             (nn, [1.0, 1.3], [(0, 1, 0, 1.0), (1, 0, 1, 1.0), (0, 0, 1, 0.6), (1, 1, 1, 0.6)])]
    for b, masses, springs in cases:
        got = np.sort(b.omega2, axis=1)
        for k, q in enumerate(qs):
            ref = eig_reference(masses, springs, q)
            for j, r in enumerate(ref):
                if q == 0 and j == 0:
                    assert got[k, 0] == 0.0
                else:
                    assert rel(got[k, j], r) <= TOL


def test_random_cells_at_random_contrast_against_eigen_solves():
    """Cells of 1 to 4 masses, masses and stiffnesses log-uniform over 12 decades, springs to the next cell and
    the one after, self-springs, springs to the ground: every ω²_j(q) within 1e-13 of the 60-digit eigen-solve
    (measured: 1.2e-15 worst), exact zeros where the reference is 0."""
    from springchain.numeric.bands.cell import Cell
    from springchain.numeric.bands.spectrum import spectrum

    rng = np.random.default_rng(3)
    for _ in range(25):
        p = int(rng.integers(1, 5))
        masses = 10 ** rng.uniform(-6, 6, p)
        springs = [(a, a + 1, 0, 10 ** rng.uniform(-6, 6)) for a in range(p - 1)]
        springs.append((p - 1, 0, 1, 10 ** rng.uniform(-6, 6)))
        for _ in range(int(rng.integers(0, 3))):
            a, b = int(rng.integers(0, p)), int(rng.integers(0, p))
            springs.append((a, b, int(rng.integers(0 if a != b else 1, 3)), 10 ** rng.uniform(-6, 6)))
        if rng.uniform() < 0.3:
            springs.append((int(rng.integers(0, p)), -1, 0, 10 ** rng.uniform(-6, 6)))
        cell = Cell.from_lists([str(i) for i in range(p)], masses, [s[:3] for s in springs], [s[3] for s in springs])
        qs = np.concatenate([[0.0, 1e-7, np.pi], rng.uniform(-np.pi, np.pi, 3)])
        got = spectrum(cell, qs).omega2
        for k, q in enumerate(qs):
            ref = eig_reference(masses, springs, q)
            for j in range(p):
                if abs(ref[j]) <= mp.mpf(10) ** -40 * max(abs(x) for x in ref):
                    assert got[k, j] == 0.0
                else:
                    assert rel(got[k, j], ref[j]) <= TOL, (p, springs, q, j)
