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


# -- structural zeros: free pieces (findings F3, /work/wt/nu/findings.md) -------------------------------------
# An elastic mode of a free piece (masses joined by springs, none to a wall) carries no momentum: K_p 1 = 0, so
# ω² 1ᵀM_pφ_p = 1ᵀK_pφ_p = 0. Its Γ is exactly 0, a structural zero, so the claim below is exact equality
# (== 0.0), not a tolerance. The other references are in mpmath, piece by piece, at 50 digits (a
# precision doubled until two successive ones agree to 1e-50), from the values written in the TOML text.

_S03 = """name = "s03_pieces"
[parameters]
m = 1.5
k = 3.0
kk = 7e6
eps = 1e-9
[masses]
p1 = "m"
p2 = "2*m"
q1 = "m"
q2 = "m/3"
q3 = "5*m"
r = "0.25"
[[springs]]
between = ["p1", "p2"]
k = "k"
[[springs]]
between = ["q1", "q2"]
k = "kk"
[[springs]]
between = ["q2", "q3"]
k = "k"
[[springs]]
between = ["q3", "q1"]
k = "eps"
[[springs]]
between = ["wall", "r"]
k = "k"
[[springs]]
between = ["r", "wall"]
k = "eps"
[initial]
x = [0.1, 0, 0, 0.2, 0, 0.3]
v = [1, 0, 0, 0, 0, 0]
"""


def _frac(v):
    from fractions import Fraction

    return v if isinstance(v, Fraction) else Fraction(float(v))


def _piece_list(n, springs):
    """Connected pieces of the spring graph as (indices, free)."""
    parent = list(range(n))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b, _ in springs:
        if a >= 0 and b >= 0:
            parent[find(a)] = find(b)
    groups = {}
    for i in range(n):
        groups.setdefault(find(i), []).append(i)
    walled = {a for a, b, _ in springs if b < 0} | {b for a, b, _ in springs if a < 0}
    return [(g, not walled.intersection(g)) for g in groups.values()]


def _piece_eig(masses, springs, piece, dps):
    """(ω², Γ) of one piece at ``dps`` digits: eigsy of D = M^-1/2 K M^-1/2 on the piece; Γ = Σ mᵢφᵢ."""
    loc = {g: i for i, g in enumerate(piece)}
    with mpmath.workdps(dps):
        m = [mpmath.mpf(_frac(masses[g]).numerator) / _frac(masses[g]).denominator for g in piece]
        r = [1 / mpmath.sqrt(x) for x in m]
        D = mpmath.zeros(len(piece), len(piece))
        for a, b, k in springs:
            if a not in loc and b not in loc:
                continue
            kv = mpmath.mpf(_frac(k).numerator) / _frac(k).denominator
            ends = [(loc[e], s) for e, s in ((a, 1), (b, -1)) if e in loc]
            for i, si in ends:
                for j, sj in ends:
                    D[i, j] += si * sj * kv * r[i] * r[j]
        w, E = mpmath.eigsy(D)
        out = []
        for j in sorted(range(len(piece)), key=lambda j: w[j]):
            out.append((w[j], abs(mpmath.fsum(m[i] * E[i, j] * r[i] for i in range(len(piece))))))
        return out, mpmath.fsum(m)


def _pieces_reference(masses, springs):
    """Per piece: ('free' | 'walled', [(ω², |Γ|)], piece mass), walled pieces' values settled to 50 digits
    (relative for ω², relative to √(piece mass) for Γ); free pieces: ω² of their elastic modes."""
    out = []
    for piece, free in _piece_list(len(masses), springs):
        dps, prev = 120, None
        while True:
            cur, mass = _piece_eig(masses, springs, piece, dps)
            if prev is not None:
                with mpmath.workdps(dps):
                    tol = mpmath.mpf(10) ** -50
                    start = 1 if free else 0  # a free piece's lowest is its rigid mode (0 up to rounding)
                    if all(abs(a[0] - b[0]) <= tol * abs(b[0]) and abs(a[1] - b[1]) <= tol * mpmath.sqrt(mass)
                           for a, b in zip(prev[start:], cur[start:])):
                        break
            assert dps < 8000, "reference not settled"
            prev, dps = cur, 2 * dps
        out.append(("free" if free else "walled", cur[1:] if free else cur, mass))
    return out


def _check_structural(data: dict, text: str, masses, springs, *, rel=1e-14):
    """The claims of this section on a ``modes --json`` result (see the section comment); returns the worst
    relative error of the walled pieces' Γ against the reference (modes of multiplicity one; relative to
    max(|Γ|, 1e-30 √M)) and the worst absolute error over √M (M the total mass)."""
    recs = data["modes"]
    n = len(masses)
    assert len(recs) == n
    ref = _pieces_reference(masses, springs)
    with mpmath.workdps(60):
        total = mpmath.fsum(mpmath.mpf(_frac(x).numerator) / _frac(x).denominator for x in masses)
        free_mass = mpmath.fsum(mass for kind, _, mass in ref if kind == "free")
    n_free = sum(kind == "free" for kind, _, _ in ref)
    gamma = [r["participation_factor"] for r in recs]
    w2 = [r["omega2_value"] for r in recs]
    # groups of one ω² (repeated ω may mix pieces), rigid modes first
    groups = []
    for j, w in enumerate(w2):
        if groups and (w == w2[groups[-1][0]] == 0.0 or (w > 0 and abs(w - w2[groups[-1][0]]) <= 1e-12 * w)):
            groups[-1].append(j)
        else:
            groups.append([j])
    assert [w2[j] for j in range(n_free)] == [0.0] * n_free
    worst = worst_abs = 0.0
    for g in groups:
        w = w2[g[0]]
        walled = [gm for kind, modes, _ in ref if kind == "walled" for wr, gm in modes
                  if abs(float(wr) - w) <= 1e-12 * abs(float(wr))]
        free_el = sum(1 for kind, modes, _ in ref if kind == "free" for wr, _ in modes
                      if abs(float(wr) - w) <= 1e-12 * abs(float(wr)))
        if w == 0.0:
            assert len(g) == n_free
            # the rotated rigid basis: 1_F/√M_F carries √M_F, every other rigid shape exactly 0
            assert abs(abs(gamma[g[0]]) - float(mpmath.sqrt(free_mass))) <= 2.3e-16 * float(mpmath.sqrt(free_mass))
            assert all(gamma[j] == 0.0 for j in g[1:]), [gamma[j] for j in g]
            continue
        assert len(g) == len(walled) + free_el, (w, len(g), len(walled), free_el)
        zeros = sum(gamma[j] == 0.0 for j in g)
        # structural zeros: an elastic ω of free pieces only has Γ exactly 0; a repeated ω shared with walled
        # pieces has at most (number of walled modes there) non-zero Γ
        assert zeros >= len(g) - len(walled), (w, [gamma[j] for j in g], walled)
        with mpmath.workdps(60):
            want = mpmath.fsum(x * x for x in walled)
            got = mpmath.fsum(mpmath.mpf(gamma[j]) ** 2 for j in g)
            assert abs(got - want) <= rel * total, (w, got, want)
            if len(g) == 1 and walled:
                err = abs(abs(mpmath.mpf(gamma[g[0]])) - walled[0])
                worst = max(worst, float(err / max(walled[0], mpmath.mpf(10) ** -30 * mpmath.sqrt(total))))
                worst_abs = max(worst_abs, float(err / mpmath.sqrt(total)))
    for r in recs:  # no contradiction between the value and its closed form; M* of a zero is 0
        if r["participation_factor"] == 0.0:
            assert r["effective_mass"] == 0.0 and math.copysign(1.0, r["participation_factor"]) == 1.0
        if r.get("participation_factor_expr") == "0":
            assert r["participation_factor"] == 0.0
    assert abs(math.fsum(r["effective_mass"] for r in recs) - float(total)) <= 4e-16 * float(total)
    # the text table prints the same exact zeros ("0", never 1e-74 nor -0)
    rows = [line.split() for line in text.splitlines() if line.startswith("    ") and len(line.split()) == 6]
    table = {int(t[0]): t[2] for t in rows if t[0].isdigit()}
    for j, g in enumerate(gamma, start=1):
        if g == 0.0:
            assert table[j] == "0", (j, table[j])
    return worst, worst_abs


def test_s03_free_pieces_gamma_exactly_zero(tmp_path):
    """s03_pieces (a free pair, a free ring of three, a mass on two parallel wall springs): modes 2, 3, 4, 6 have
    Γ == 0 exactly (they read 2.3e-74 and ±1e-81 beside a closed form "0"), mode 1 Γ = √14 (the free pieces'
    mass, rotated rigid basis), mode 5 Γ = 1/2 = √(0.25) (the walled mass: φ = 1/√m, Γ = √m)."""
    path = tmp_path / "s03.toml"
    path.write_text(_S03)
    m = sc.modes(str(path))
    data, text = m.to_json(), m.to_text()
    gamma = [r["participation_factor"] for r in data["modes"]]
    assert [gamma[j] for j in (1, 2, 3, 5)] == [0.0] * 4
    assert gamma[0] == pytest.approx(math.sqrt(14.0), rel=2.3e-16)
    assert abs(gamma[4]) == pytest.approx(0.5, rel=2.3e-16)
    masses = [1.5, 3.0, 1.5, 0.5, 7.5, 0.25]  # q2 = m/3 = 0.5 exactly
    springs = [(0, 1, 3.0), (2, 3, 7e6), (3, 4, 3.0), (4, 2, 1e-9), (-1, 5, 3.0), (5, -1, 1e-9)]
    worst, _ = _check_structural(data, text, masses, springs)
    assert worst <= 1e-14, worst
    assert list(m.participation.gamma) == gamma


_dec40 = st.integers(-40, 40)


@st.composite
def _piece_scenes(draw, max_masses=12):
    """Several pieces: free pairs/triples (a path, or a ring of three), walled paths of 1-3 masses (a wall at
    one or both ends, sometimes two parallel wall springs), masses and stiffnesses 10^e·c over e in -40…40."""
    masses, springs = [], []
    n_pieces = draw(st.integers(2, 4))
    kinds = [draw(st.sampled_from(["free", "walled"])) for _ in range(n_pieces)]
    if "free" not in kinds:
        kinds[0] = "free"
    if "walled" not in kinds:
        kinds[-1] = "walled"
    val = lambda: float(draw(st.sampled_from([1.0, 1.5, 3.0, 7.25]))) * 10.0 ** draw(_dec40)
    for kind in kinds:
        size = draw(st.integers(2 if kind == "free" else 1, 3))
        if len(masses) + size > max_masses:
            size = 2 if kind == "free" else 1
        base = len(masses)
        masses += [val() for _ in range(size)]
        springs += [(base + i, base + i + 1, val()) for i in range(size - 1)]
        if kind == "free":
            if size == 3 and draw(st.booleans()):
                springs.append((base + 2, base, val()))
        else:
            springs.append((-1, base, val()))
            if draw(st.booleans()):
                springs.append((base + size - 1, -1, val()))
    return masses, springs


def _scene_text(masses, springs):
    names = [f"x{i}" for i in range(len(masses))]
    params = {f"m{i}": v for i, v in enumerate(masses)} | {f"k{j}": k for j, (_, _, k) in enumerate(springs)}
    lines = ['name = "pieces"', "[parameters]"] + [f"{p} = {v!r}" for p, v in params.items()] + ["[masses]"]
    lines += [f'{x} = "m{i}"' for i, x in enumerate(names)]
    for j, (a, b, _) in enumerate(springs):
        ea = "wall" if a < 0 else names[a]
        eb = "wall" if b < 0 else names[b]
        lines += ["[[springs]]", f'between = ["{ea}", "{eb}"]', f'k = "k{j}"']
    return "\n".join(lines) + "\n"


@settings(max_examples=8)
@given(scene=_piece_scenes())
def test_pieces_hypothesis_gamma_structural(tmp_path_factory, scene):
    """Hypothesis scenes of 2-4 pieces (walled and free), values over 1e-40…1e40, at most 12 masses (the
    mpmath route): Γ == 0 exactly for every elastic mode of free pieces, the rigid basis as for s03, the
    walled pieces' Γ against the 50-digit reference to 1e-14 relative (of max(|Γ|, 1e-30 √M)), Σ M* = total
    mass to 4e-16."""
    masses, springs = scene
    path = tmp_path_factory.mktemp("pc") / "pieces.toml"
    path.write_text(_scene_text(masses, springs))
    m = sc.modes(str(path))
    worst, _ = _check_structural(m.to_json(), m.to_text(), masses, springs)
    assert worst <= 1e-14, worst


@settings(max_examples=3)
@given(scene=_piece_scenes(max_masses=24), extra=st.integers(0, 3))
def test_pieces_spring_factor_route_gamma_structural(tmp_path_factory, scene, extra):
    """The same past the mpmath route (more than 16 masses: the spring-factor SVD, piece by piece): further
    free triples and walled pairs are appended so that the scene has at least 17 masses. The walled Γ to
    1e-15 √M (this route's accuracy), the structural zeros exact as on the mpmath route."""
    masses, springs = (list(x) for x in scene)
    i = 0
    while len(masses) < 17 + extra:
        base = len(masses)
        if i % 2 == 0:  # a free triple
            masses += [2.0 ** (i + 1), 3.0 * 10.0 ** (-i), 5.0]
            springs += [(base, base + 1, 10.0 ** (3 * i)), (base + 1, base + 2, 7.0)]
        else:  # a walled pair
            masses += [1.5 * 10.0 ** i, 0.75]
            springs += [(-1, base, 11.0), (base, base + 1, 10.0 ** (-5 * i))]
        i += 1
    path = tmp_path_factory.mktemp("pcs") / "pieces.toml"
    path.write_text(_scene_text(masses, springs))
    m = sc.modes(str(path))
    data = m.to_json()
    assert "spring-factor" in data["participation"]["route"]
    _, worst_abs = _check_structural(data, m.to_text(), masses, springs, rel=1e-13)
    # this route's Γ (float64 shapes, compensated sums) is accurate relative to √M, not to a tiny Γ of a mode
    # nearly orthogonal to r (a walled pair with a 1e33 spring: Γ ~ 1e-33 read with 3e17 relative error)
    assert worst_abs <= 1e-15, worst_abs


def test_free_free_chain_with_ground_gamma_exactly_zero(tmp_path):
    """A [chain] free at both ends under [ground] motion (the chain route, numeric.structural.modal_quantities):
    Γ = (√M, 0, …, 0) with the zeros exact, Σ M* = M."""
    path = tmp_path / "ff.toml"
    path.write_text('name = "ff"\n[parameters]\nm = 1.0\nk = 1.0\n[chain]\nn = 6\nmass = "m*(1 + i % 3) + i/8"\n'
                    'k = "k*(2 + i)"\nleft = "free"\nright = "free"\n[ground]\nacceleration = "sin(t)"\n')
    data = sc.modes(str(path)).to_json()
    gamma = [r["participation_factor"] for r in data["modes"]]
    total = math.fsum((1 + i % 3) + i / 8 for i in range(6))
    assert gamma[0] == pytest.approx(math.sqrt(total), rel=2.3e-16)
    assert gamma[1:] == [0.0] * 5 and all(math.copysign(1.0, g) == 1.0 for g in gamma[1:])
    assert math.fsum(r["effective_mass"] for r in data["modes"]) == pytest.approx(total, rel=4e-16)
