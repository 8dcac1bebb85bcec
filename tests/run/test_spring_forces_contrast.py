"""Time-history spring forces at stiffness contrast (issue 31): ``simulate --springs`` on six unit masses hung
by springs from 1e-6 to 1e6 N/m under gravity.

Formed from positions, the force of a stiff spring is ``k·(x_b − x_a)`` with the drift a tiny difference of
displacements of ~1e8 m (the soft wall spring's sag): 2.4e-4 of the force scale off at t = 100 s, without a
note. The exact method now forms them by the load path from its own modal coordinates (each spring's
tension = the loads and inertia forces beyond it) where the positions' rounding would exceed 1e-10 of
the force scale; any other method's run says in a note how far float64 rounding may take them.

Reference: the exact modal solution of ``M ẍ + K x = M g`` from rest, built here from the TOML values
(exact binary fractions) and evaluated by mpmath at 50 digits (``mpmath.eigsy`` of M^-1/2 K M^-1/2,
x(t) = x_s − Σ φ_j φ_jᵀ M x_s cos ω_j t), spring forces k_s(x_b − x_a) in mpmath.
"""

from __future__ import annotations

import tomllib
from fractions import Fraction

import mpmath
import numpy as np
import pytest

from helpers import run_cli

DPS = 50
#: Spring forces relative to the run's largest spring force.
FORCE_TOL = 1e-10


def scene(order: str, steps: int = 100, dt: float = 1.0, extra: str = "") -> str:
    ks = [10 ** (-6 + 12 * i / 5) for i in range(6)]
    if order == "stiff-at-the-wall":
        ks = ks[::-1]
    lines = ['name = "hang6"', "[parameters]", "g = 9.81", "m = 1.0"]
    lines += [f"k{i} = {k!r}" for i, k in enumerate(ks)]
    lines += ["[masses]"] + [f'm{i} = "m"' for i in range(6)]
    ends = ["wall"] + [f"m{i}" for i in range(6)]
    for i in range(6):
        lines += ["[[springs]]", f'between = ["{ends[i]}", "{ends[i + 1]}"]', f'k = "k{i}"']
    lines += ["[gravity]", 'g = "g"', "[simulation]", f"dt = {dt!r}", f"steps = {steps}"]
    return "\n".join(lines) + "\n" + extra


def reference_forces(text: str, t: np.ndarray) -> np.ndarray:
    """Spring forces (S frames, 6 springs) of the exact solution from rest, in mpmath."""
    data = tomllib.loads(text)
    p = {k: mpmath.mpf(Fraction(v).numerator) / Fraction(v).denominator for k, v in data["parameters"].items()}
    n = 6
    with mpmath.workdps(DPS):
        ks = [p[f"k{i}"] for i in range(n)]
        m, g = p["m"], p["g"]
        K = mpmath.matrix(n, n)
        for i, k in enumerate(ks):  # spring i between mass i-1 (wall for i = 0) and mass i
            K[i, i] += k
            if i > 0:
                K[i - 1, i - 1] += k
                K[i - 1, i] -= k
                K[i, i - 1] -= k
        xs = mpmath.lu_solve(K, mpmath.matrix([m * g] * n))
        E, Q = mpmath.eigsy(K / m)  # M = m I
        coef = [sum(Q[i, j] * xs[i] for i in range(n)) for j in range(n)]
        out = np.empty((t.shape[0], n))
        for r, tt in enumerate(t):
            tm = mpmath.mpf(float(tt))
            x = [xs[i] - sum(Q[i, j] * coef[j] * mpmath.cos(mpmath.sqrt(E[j]) * tm) for j in range(n))
                 for i in range(n)]
            out[r] = [float(ks[i] * (x[i] - (x[i - 1] if i > 0 else 0))) for i in range(n)]
    return out


@pytest.mark.parametrize("order", ["soft-at-the-wall", "stiff-at-the-wall"])
def test_exact_spring_forces_at_contrast(order, tmp_path, capsys):
    text = scene(order)
    path = tmp_path / "hang6.toml"
    path.write_text(text)
    status, out, err = run_cli(["simulate", path, "--springs", "--method", "modal", "--no-figures",
                                "--out", tmp_path / "out"], capsys)
    assert status == 0, err
    data = np.load(tmp_path / "out" / "hang6.npz")
    t = data["t"]
    rows = np.unique(np.r_[0, np.linspace(0, t.shape[0] - 1, 9).astype(int), t.shape[0] - 1])
    ref = reference_forces(text, t[rows])
    scale = np.max(np.abs(ref))
    force = data["spring_force_modal"][rows]
    assert np.max(np.abs(force - ref)) <= FORCE_TOL * scale
    # base shear: the wall spring's pull on the ground; drifts: the forces over k
    assert np.max(np.abs(data["base_shear_modal"][rows] - ref[:, 0])) <= FORCE_TOL * scale
    k = np.array([tomllib.loads(text)["parameters"][f"k{i}"] for i in range(6)])
    assert np.max(np.abs(data["drift_modal"][rows] * k - ref)) <= FORCE_TOL * scale
    assert "notes" not in data.files or not any("spring forces" in s for s in data["notes"])
    assert "note:" not in out


def test_forces_from_positions_say_their_float64_limit(tmp_path, capsys):
    """Verlet's forces are formed from its positions: the run names how far float64 rounding may take them
    (at least the error the exact reference shows for them at the last frame)."""
    text = scene("soft-at-the-wall", steps=400, dt=0.001)
    path = tmp_path / "hang6.toml"
    path.write_text(text)
    status, out, err = run_cli(["simulate", path, "--springs", "--method", "verlet", "--no-figures",
                                "--out", tmp_path / "out"], capsys)
    assert status == 0, err
    data = np.load(tmp_path / "out" / "hang6.npz")
    [note] = [s for s in data["notes"] if "spring forces" in s]
    assert note.startswith("verlet:") and "float64 rounding of x_b - x_a" in note
    assert "note: verlet: spring forces" in out


def test_potential_spring_forces_are_their_tensions(tmp_path, capsys):
    """A spring potential's force is its tension V'(d) at the drift d (it was V''(d_eq)·d, the linearisation
    at x_eq, which is not even zero at rest for a pre-stressed spring)."""
    k, T = 2.0, 0.5
    text = ('name = "pre"\n[parameters]\nk = 2.0\nT = 0.5\nm = 1.0\n[masses]\np0 = "m"\np1 = "m"\n'
            '[[springs]]\nbetween = ["wall", "p0"]\npotential = "k*d**2/2 + T*d + d**4"\n'
            '[[springs]]\nbetween = ["p0", "p1"]\npotential = "k*d**2/2 + T*d"\n'
            "[simulation]\ndt = 0.01\nsteps = 300\n")
    path = tmp_path / "pre.toml"
    path.write_text(text)
    status, out, err = run_cli(["simulate", path, "--springs", "--method", "verlet", "--no-figures",
                                "--out", tmp_path / "out"], capsys)
    assert status == 0, err
    data = np.load(tmp_path / "out" / "pre.npz")
    x = data["x_verlet"]
    d = np.stack([x[:, 0], x[:, 1] - x[:, 0]], axis=1)
    assert np.allclose(data["drift_verlet"], d, rtol=0, atol=1e-15)
    tension = np.stack([k * d[:, 0] + T + 4 * d[:, 0] ** 3, k * d[:, 1] + T], axis=1)
    assert np.allclose(data["spring_force_verlet"], tension, rtol=1e-13, atol=1e-15)
    assert np.allclose(data["base_shear_verlet"], tension[:, 0], rtol=1e-13, atol=1e-15)
