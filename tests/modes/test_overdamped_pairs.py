"""ζ of overdamped modes of [masses] scenes with non-proportional damping: the real eigenvalues of the quadratic
eigenproblem (λ²M + λC + K)φ = 0 are grouped two by two by the undamped mode that carries most of their
eigenvectors (an optimal assignment, two per mode), ω_n = √(λ₁λ₂), ζ = −(λ₁ + λ₂)/(2ω_n). They were paired by
value (the slowest with the fastest): three masses with C ≈ 3M gave ζ = 1.586 for ≈ 1.5.

The references are written here: ω_j from mpmath eigsy at 50 digits (C = γM: ζ_j = γ/(2ω_j)), and for the
non-proportional scenes mpmath's eigen-solve of the 2N state matrix [[0, I], [−M⁻¹K, −M⁻¹C]] at 50 digits, each
real eigenvalue's eigenvector x (the displacement half) projected on the M-orthonormal undamped modes
(q = ΦᵀMx) and assigned by scipy's linear_sum_assignment with every mode taken twice.
"""

from __future__ import annotations

import json

import mpmath
import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from helpers import scene_toml, write_scene
from springchain.cli import main

DPS = 50


def masses_scene(masses, springs, dampers, name="od"):
    """A [masses] scene: masses (values), springs (a, b, k) and dashpots (a, b, c), "wall" for the ground."""
    names = [f"p{i}" for i in range(len(masses))]
    def end(a):
        return "wall" if a == "wall" else names[a]
    return scene_toml(name, {"u": 1.0}, masses={nm: repr(float(v)) for nm, v in zip(names, masses)},
                      springs=[{"between": [end(a), end(b)], "k": repr(float(k))} for a, b, k in springs],
                      dampers=[{"between": [end(a), end(b)], "c": repr(float(c))} for a, b, c in dampers])


def matrix(n, elements):
    A = mpmath.zeros(n, n)
    for a, b, v in elements:
        v = mpmath.mpf(v)
        for i, si in ((a, 1), (b, -1)):
            for j, sj in ((a, 1), (b, -1)):
                if i != "wall" and j != "wall":
                    A[i, j] += si * sj * v
    return A


def undamped(masses, springs):
    """ω² ascending and M-orthonormal Φ (columns) at DPS digits."""
    n = len(masses)
    K = matrix(n, springs)
    r = [1 / mpmath.sqrt(mpmath.mpf(m)) for m in masses]
    D = mpmath.matrix([[r[a] * K[a, b] * r[b] for b in range(n)] for a in range(n)])
    E, U = mpmath.eigsy(D)
    order = sorted(range(n), key=lambda j: E[j])
    w2 = [E[j] for j in order]
    Phi = mpmath.matrix([[r[i] * U[i, j] for j in order] for i in range(n)])
    return w2, Phi


def reference_rows(masses, springs, dampers):
    """(ω_n, ζ) per mode, ascending ω_n, ζ None for a rigid mode, from the 2N state matrix at DPS digits."""
    n = len(masses)
    with mpmath.workdps(DPS):
        M = mpmath.diag([mpmath.mpf(m) for m in masses])
        K, C = matrix(n, springs), matrix(n, dampers)
        w2, Phi = undamped(masses, springs)
        Minv = mpmath.inverse(M)
        A = mpmath.zeros(2 * n, 2 * n)
        for i in range(n):
            A[i, n + i] = 1
        A[n:, :n] = -Minv * K
        A[n:, n:] = -Minv * C
        lam, V = mpmath.eig(A)
        scale = max(abs(v) for v in lam)
        tiny = mpmath.mpf(10) ** (-DPS // 2) * scale
        rows = [(abs(v), -mpmath.re(v) / abs(v)) for v in lam if mpmath.im(v) > tiny]
        real = [k for k, v in enumerate(lam) if abs(mpmath.im(v)) <= tiny]
        share = np.zeros((len(real), n))
        for r, k in enumerate(real):
            x = mpmath.matrix([mpmath.re(V[i, k]) for i in range(n)])
            q = Phi.T * M * x
            share[r] = [float(q[j] ** 2) for j in range(n)]
            share[r] /= share[r].sum()
        got, slot = linear_sum_assignment(-np.repeat(share, 2, axis=1))
        pairs: dict[int, list] = {}
        for r, s in zip(got, slot):
            pairs.setdefault(int(s) // 2, []).append(mpmath.re(lam[real[r]]))
        assert all(len(p) == 2 for p in pairs.values())
        for j, (r1, r2) in pairs.items():
            if abs(w2[j]) <= tiny:
                rows.append((mpmath.mpf(0), None))
            else:
                wn = mpmath.sqrt(r1 * r2)
                rows.append((wn, -(r1 + r2) / (2 * wn)))
    rows.sort(key=lambda r: r[0])
    return [(float(w), None if z is None else float(z)) for w, z in rows]


def modes_json(text, tmp_path, capsys):
    path = write_scene(tmp_path, "od", text)
    assert main(["modes", str(path), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def chain(n, left_wall=False):
    springs = [(i, i + 1, 1.0 + 0.1 * i) for i in range(n - 1)] + ([("wall", 0, 0.7)] if left_wall else [])
    return springs


# three equal masses, free, a dashpot to the ground from each (the brief's scene), and five unequal masses
SCENES = {
    "three": ([1.0, 1.0, 1.0], [(0, 1, 1.0), (1, 2, 1.0)], [3.0, 3.0, 3.03], None),
    "five_wall": ([1.0, 1.3, 0.8, 1.1, 0.9], chain(5, True), [5.0, 9.0, 4.0, 7.0, 6.0], None),
    "five_wall_equal_c": ([1.0, 1.3, 0.8, 1.1, 0.9], chain(5, True), [8.0] * 5, None),
    "five_wall_near_proportional": ([1.0, 1.3, 0.8, 1.1, 0.9], chain(5, True), [
        6.0 * m * (1 + d) for m, d in zip([1.0, 1.3, 0.8, 1.1, 0.9], [0.02, -0.01, 0.03, 0.0, -0.02])], None),
    # past accurate.MAX_MPMATH_MODES = 16 masses: the float64 route (_rows_float)
    "seventeen_free": ([1.0 + 0.05 * i for i in range(17)], chain(17), [
        3.0 * (1.0 + 0.05 * i) * (1 + 0.01 * (-1) ** i) for i in range(17)], 1e-11),
    "six_free": ([1.0 + 0.1 * i for i in range(6)], chain(6), [4.0 * (1.0 + 0.1 * i) * (1 + 0.01 * (-1) ** i)
                                                             for i in range(6)], None),
}


@pytest.mark.parametrize("name", sorted(SCENES))
def test_overdamped_pairs_follow_the_modes(name, tmp_path, capsys):
    masses, springs, c, rel = SCENES[name]
    rel = rel or 1e-12
    dampers = [(i, "wall", ci) for i, ci in enumerate(c)]
    out = modes_json(masses_scene(masses, springs, dampers), tmp_path, capsys)
    assert out["damping"]["proportional"] is False
    ref = reference_rows(masses, springs, dampers)
    got = [(m["damping_ratio"], m["omega_damped"]) for m in out["modes"]]
    cm = out["complex_modes"]
    assert len(got) == len(ref) == len(cm) == len(masses)
    over = 0
    for (wn, zeta), (z, wd), c_row in zip(ref, got, cm):
        assert c_row["omega_n"] == pytest.approx(wn, rel=rel, abs=1e-300)
        if zeta is None:
            assert z is None and c_row["damping_ratio"] is None
            continue
        assert z == pytest.approx(zeta, rel=rel), (name, ref, got)
        assert c_row["damping_ratio"] == z
        if zeta > 1:
            over += 1
            assert wd == 0.0 and c_row["eigenvalue"] is None
            assert c_row["sigma"] == pytest.approx(zeta * wn, rel=rel)
    assert over >= 1


def test_three_masses_near_proportional_values(tmp_path, capsys):
    """The brief's numbers: C = diag(3, 3, 3.03) is close to 3M, ζ close to c/(2mω): 1.5 and 0.866 (not 1.586)."""
    masses, springs, c, _ = SCENES["three"]
    out = modes_json(masses_scene(masses, springs, [(i, "wall", ci) for i, ci in enumerate(c)]), tmp_path, capsys)
    zeta = [m["damping_ratio"] for m in out["modes"]]
    assert zeta[0] is None
    assert zeta[1] == pytest.approx(1.5, rel=5e-3)
    assert zeta[2] == pytest.approx(3 / (2 * np.sqrt(3)), rel=5e-3)


@pytest.mark.parametrize("name, gamma", [("three", 3.0), ("five_wall", 6.0), ("six_free", 4.0), ("seventeen_free", 3.0)])
def test_proportional_zeta_is_gamma_over_two_omega(name, gamma, tmp_path, capsys):
    """C = γM exactly: ζ_j = γ/(2ω_j), ω_j from mpmath eigsy at 50 digits; several modes overdamped."""
    masses, springs, _, _ = SCENES[name]
    dampers = [(i, "wall", gamma * m) for i, m in enumerate(masses)]
    out = modes_json(masses_scene(masses, springs, dampers), tmp_path, capsys)
    with mpmath.workdps(DPS):
        w2, _ = undamped(masses, springs)
    over = 0
    for m, ref in zip(out["modes"], w2):
        if abs(ref) < mpmath.mpf(10) ** -30:
            assert m["damping_ratio"] is None
            continue
        zeta = float(gamma / (2 * mpmath.sqrt(ref)))
        over += zeta > 1
        assert m["damping_ratio"] == pytest.approx(zeta, rel=SCENES[name][3] or 1e-12)
    assert over >= 1
