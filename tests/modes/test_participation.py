"""Participation factors, effective modal masses and mass-normalised shapes (issue 20, item 1).

References are built in the test from the scene's TOML text: M and K from the element list,
``mpmath.eigsy`` at 60 digits (checked at 120) in tests/modes_reference.py, then
Γⱼ = φⱼᵀ M 1 with M-orthonormal φⱼ. Nothing of springchain's modal code is reused.
"""

from __future__ import annotations

import math
import tomllib

import mpmath
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import springchain as sc
from modes_reference import _mp
from modes_reference import reference as mp_reference
from modes_reference import modes_scene_text


def _elements(text: str):
    """Masses and springs (index ends, -1 wall) at the scene's values, read from the TOML text."""
    data = tomllib.loads(text)
    p = data["parameters"]
    names = list(data["masses"])

    def val(e):
        return float(p[e]) if e in p else float(e)

    masses = [val(data["masses"][n]) for n in names]
    springs = [(-1 if a == "wall" else names.index(a), -1 if b == "wall" else names.index(b), val(s["k"]))
               for s in data["springs"] for a, b in [s["between"]]]
    return masses, springs


def _reference_gamma(masses, springs):
    """ω² and |Γⱼ| (sign-free) at 60 digits."""
    w2, S = mp_reference(masses, springs)
    n = len(masses)
    with mpmath.workdps(60):
        gam = [abs(mpmath.fsum(_mp(masses[i]) * S[i, j] for i in range(n))) for j in range(n)]
    return w2, gam


def _check(data: dict, masses, springs, tol=1e-13):
    w2, gam = _reference_gamma(masses, springs)
    total = math.fsum(masses)
    recs = data["modes"]
    assert len(recs) == len(masses)
    got = [r["effective_mass"] for r in recs]
    # Σ M* = total mass
    assert abs(math.fsum(got) - total) <= tol * total
    assert abs(data["participation"]["effective_mass_sum"] - total) <= tol * total
    for j, r in enumerate(recs):
        g = float(gam[j])
        assert abs(abs(r["participation_factor"]) - g) <= tol * math.sqrt(total), (j, r["participation_factor"], g)
        assert abs(r["effective_mass"] - g * g) <= tol * total
        assert abs(r["effective_mass_fraction"] - g * g / total) <= tol
        phi = r["shape_mass_normalised"]
        assert abs(math.fsum(m * c * c for m, c in zip(masses, phi)) - 1.0) <= 1e-13
    assert recs[-1]["effective_mass_cumulative"] == pytest.approx(1.0, abs=tol)


def test_building_against_mpmath(repo_root):
    text = (repo_root / "scenes" / "building_quake.toml").read_text()
    masses, springs = _elements(text)
    m = sc.modes("building_quake")
    data = m.to_json()
    _check(data, masses, springs)
    # the mass-normalised shape's sign follows the printed shape; Γ₁ > 0 for the first mode of a building
    assert data["modes"][0]["participation_factor"] > 0
    for r in data["modes"]:
        dot = sum(a * b for a, b in zip(r["shape_value"], r["shape_mass_normalised"]))
        assert dot > 0
    # closed forms, read back with the scene's symbols, agree with the values
    for r in data["modes"]:
        assert r["effective_mass_expr"] is not None
        e = m.parse(r["effective_mass_expr"])
        vals = {s: sp.Rational(v) for s, v in zip(sp.symbols("c k m", positive=True), (45000, 4000000, 10000))}
        assert float(e.subs({sym: vals[sp.Symbol(sym.name, positive=True)] for sym in e.free_symbols}).evalf(30)) \
            == pytest.approx(r["effective_mass"], rel=1e-13)


def test_two_storey_closed_form_exact(tmp_path):
    """Two equal storeys: M* in closed form equals a hand derivation exactly (SymPy)."""
    text = modes_scene_text("two", [("m", 2.0)], [("k", 3.0)], ["m", "m"], [("wall", "x0", "k"), ("x0", "x1", "k")])
    path = tmp_path / "two.toml"
    path.write_text(text)
    m = sc.modes(str(path))
    p = m.participation
    k, ms = sp.symbols("k m", positive=True)
    # hand: K = k[[2,-1],[-1,1]], M = m I; ω² = (3 ∓ √5) k / (2m); shapes (1, (1 ± √5)/2)
    for j, (w2, s) in enumerate([((3 - sp.sqrt(5)) / 2, (1 + sp.sqrt(5)) / 2), ((3 + sp.sqrt(5)) / 2, (1 - sp.sqrt(5)) / 2)]):
        phi = sp.Matrix([1, s])
        hand = (ms * (phi[0] + phi[1])) ** 2 / (ms * (phi[0] ** 2 + phi[1] ** 2))
        assert sp.simplify(p.effective_mass_expr[j] - hand) == 0
        assert float(hand.subs(ms, 2)) == pytest.approx(p.effective_mass[j], rel=1e-15)
    assert sp.simplify(p.effective_mass_expr[0] + p.effective_mass_expr[1] - 2 * ms) == 0


def test_repeated_mode_concentrated(tmp_path):
    """Two equal masses on equal wall springs (ω² repeated): one shape carries 2m, the other 0."""
    text = modes_scene_text("twin", [("m", 1.5)], [("k", 2.0)], ["m", "m"], [("wall", "x0", "k"), ("x1", "wall", "k")])
    path = tmp_path / "twin.toml"
    path.write_text(text)
    data = sc.modes(str(path)).to_json()
    meff = sorted(r["effective_mass"] for r in data["modes"])
    assert meff[0] == pytest.approx(0.0, abs=1e-15)
    assert meff[1] == pytest.approx(3.0, rel=1e-15)


def test_free_scene_has_no_participation():
    assert sc.modes("seed").participation is None
    assert "participation" not in sc.modes("seed").to_json()


_decades = st.floats(min_value=-10, max_value=10, allow_nan=False)


@settings(max_examples=6)
@given(n=st.integers(1, 5), mexp=st.lists(_decades, min_size=5, max_size=5),
       kexp=st.lists(_decades, min_size=6, max_size=6), top_wall=st.booleans())
def test_random_shear_buildings(tmp_path_factory, n, mexp, kexp, top_wall):
    """Shear buildings with masses and storey stiffnesses over 20 decades: Σ M* = total mass to 1e-13
    and every Γ against the 60-digit reference."""
    masses = [(f"m{i}", 10.0 ** mexp[i]) for i in range(n)]
    stiff = [(f"k{i}", 10.0 ** kexp[i]) for i in range(n + 1)]
    springs = [("wall", "x0", "k0")] + [(f"x{i}", f"x{i + 1}", f"k{i + 1}") for i in range(n - 1)]
    if top_wall:
        springs.append((f"x{n - 1}", "wall", f"k{n}"))
    text = modes_scene_text("rand", masses, stiff, [f"m{i}" for i in range(n)], springs)
    path = tmp_path_factory.mktemp("p") / "rand.toml"
    path.write_text(text)
    data = sc.modes(str(path)).to_json()
    _check(data, *_elements(text))


def test_chain_scenes_say_where_participation_is(tmp_path):
    """modes of a [chain] with a wall longer than 40 masses (shorter ones print the table, see
    tests/api/test_new_user_pass.py): one note (text and JSON) naming rsa; a free-free chain gets no note."""
    path = tmp_path / "cw.toml"
    path.write_text('name = "cw"\n[parameters]\nm = 1.0\nk = 1.0\n[chain]\nn = 60\nmass = "m"\nk = "k"\n'
                    'left = "wall"\nright = "free"\n')
    m = sc.modes(str(path))
    note = [n for n in m.to_json()["notes"] if n.startswith("Modal participation")]
    assert len(note) == 1 and "springchain rsa" in note[0] and note[0] in m.to_text()
    free = sc.modes("chain100k")
    assert not any(n.startswith("Modal participation") for n in free.to_json()["notes"])


# -- [chain] modes --json: shape_value of every short chain, Γ signed as the printed shape (oracle N8) -------
def _chain_text(name, n, mass, left, right):
    return (f'name = "{name}"\n[parameters]\nm = 1.0\nk = 1.0\n[chain]\nn = {n}\nmass = "{mass}"\nk = "k"\n'
            f'left = "{left}"\nright = "{right}"\n')


def _parallel(a, b):
    """|cos| of the angle between two vectors (1 = parallel)."""
    dot = math.fsum(x * y for x, y in zip(a, b))
    return abs(dot) / math.sqrt(math.fsum(x * x for x in a) * math.fsum(y * y for y in b))


def test_free_wall_chain_shapes_in_mass_order_and_gamma_signed_as_printed(tmp_path):
    """A free–wall chain: shape_value in mass order (mass 0 at the free end), shape_mass_normalised and Γ
    with the sign of shape_value (README: Γ of the mass-normalised shape, 'its sign that of the printed
    shape'); references by hand: φⱼ(i) ∝ sin(π(n − i)(2j − 1)/(2n + 1)) (i' = n − i counted from the wall),
    ω² = 4 sin²(π(2j − 1)/(2(2n + 1))), Γ = Σ φ with φ normalised, in mpmath."""
    n = 5
    path = tmp_path / "fw.toml"
    path.write_text(_chain_text("fw", n, "m", "free", "wall"))
    m = sc.modes(str(path))
    data = m.to_json()
    recs = data["modes"]
    assert len(recs) == n
    with mpmath.workdps(40):
        for j, rec in enumerate(recs, start=1):
            w2 = 4 * mpmath.sin(mpmath.pi * (2 * j - 1) / (2 * (2 * n + 1))) ** 2
            assert rec["omega2_value"] == pytest.approx(float(w2), rel=1e-14)
            ref = [mpmath.sin(mpmath.pi * (n - i) * (2 * j - 1) / (2 * n + 1)) for i in range(n)]
            # the printed shape is the hand formula itself (same order, same sign)
            assert max(abs(float(a) - b) for a, b in zip(ref, rec["shape_value"])) <= 1e-14
            norm = mpmath.sqrt(mpmath.fsum(c * c for c in ref))
            phi = [float(c / norm) for c in ref]
            assert max(abs(a - b) for a, b in zip(phi, rec["shape_mass_normalised"])) <= 1e-14, (j, rec)
            gamma = float(mpmath.fsum(ref) / norm)
            assert abs(rec["participation_factor"] - gamma) <= 1e-14, (j, rec["participation_factor"], gamma)
    # the API's participation is the report's
    assert [rec["participation_factor"] for rec in recs] == list(m.participation.gamma)
    assert [rec["shape_mass_normalised"] for rec in recs] == [list(s) for s in m.participation.shapes]


@pytest.mark.parametrize("left,right", [("wall", "free"), ("free", "free"), ("ring", "ring"), ("wall", "wall")])
def test_index_dependent_chain_lists_shape_value(tmp_path, left, right):
    """An index-dependent [chain] of at most 40 masses (no closed form) lists shape_value too (README), from
    the accurate spectrum: each parallel to the mpmath eigenvector of its (simple) ω², in mass order."""
    n = 5
    path = tmp_path / "idx.toml"
    path.write_text(_chain_text("idx", n, "m*(1 + i % 2) + i/4", left, right))
    data = sc.modes(str(path)).to_json()
    masses = [(1 + i % 2) + i / 4 for i in range(n)]
    springs = [(i, i + 1, 1.0) for i in range(n - 1)]
    if left == "wall":
        springs.append((-1, 0, 1.0))
    if right == "wall":
        springs.append((n - 1, -1, 1.0))
    if left == "ring":
        springs.append((n - 1, 0, 1.0))
    w2, S = mp_reference(masses, springs)
    recs = data["modes"]
    assert len(recs) == n
    for j, rec in enumerate(recs):
        assert rec["omega2_value"] == pytest.approx(float(w2[j]), rel=1e-13, abs=1e-15)
        sv = rec["shape_value"]
        assert len(sv) == n
        ref = [float(S[i, j]) for i in range(n)]
        assert _parallel(sv, ref) >= 1 - 1e-13, (j, sv, ref)
        if "shape_mass_normalised" in rec:  # the same vector, the same sign
            assert _parallel(sv, rec["shape_mass_normalised"]) >= 1 - 1e-13
            assert math.fsum(a * b for a, b in zip(sv, rec["shape_mass_normalised"])) > 0
