"""The symbolic side's deterministic work caps (issue 32): sizes, never a clock.

Each symbolic step (static sag, closed-form modes, participation, damping ratios, transfer functions,
potentials) is gated by a size from :mod:`derive.caps`; past it the value comes from the accurate
numeric route. These tests check the caps by expression sizes and operation counts on adversarial
scenes (distinct names for every mass and spring), and that the values past a cap equal the closed
forms where both exist — both against references computed here in mpmath from hand-derived formulas.
No test measures time.
"""

from __future__ import annotations

import json
from fractions import Fraction

import mpmath as mp
import pytest
import sympy as sp

import springchain
from springchain.derive import modes as modes_mod
from springchain.derive import participation as part_mod
from springchain.derive import transfer as transfer_mod
from springchain.derive.caps import CAPS, Caps
from springchain.derive.model import Model
from springchain.derive.sag import capped_solve, static_sag
from springchain.derive.scene import load_scene
from springchain.derive.work import WorkCapExceeded

DPS = 50


def _q(x: float) -> mp.mpf:
    """A float parameter exactly (its binary fraction), as the scene reads it."""
    f = Fraction(x)
    return mp.mpf(f.numerator) / f.denominator


def hanging_text(n: int, *, masses=None, springs=None, g=9.81) -> str:
    """n masses hung from a ceiling by springs k1..kn under gravity, every value named."""
    masses = masses or [1.0 + 0.1 * i for i in range(1, n + 1)]
    springs = springs or [50.0 + 3.0 * i for i in range(1, n + 1)]
    out = [f'name = "hang{n}"', "[parameters]"]
    out += [f"m{i} = {m!r}" for i, m in enumerate(masses, 1)] + [f"k{i} = {k!r}" for i, k in enumerate(springs, 1)]
    out += [f"g = {g!r}", "[masses]"] + [f'a{i} = "m{i}"' for i in range(1, n + 1)]
    ends = ["wall"] + [f"a{i}" for i in range(1, n + 1)]
    for i, (a, b) in enumerate(zip(ends, ends[1:]), 1):
        out += ["[[springs]]", f'between = ["{a}", "{b}"]', f'k = "k{i}"']
    out += ["[gravity]", 'g = "g"']
    return "\n".join(out) + "\n"


def hand_sag(masses, springs, g) -> list:
    """x_i = Σ_{j ≤ i} g Σ_{l ≥ j} m_l / k_j (spring j carries the weight hung below it), in mpmath."""
    m = [_q(v) for v in masses]
    k = [_q(v) for v in springs]
    x, acc = [], mp.mpf(0)
    for j in range(len(m)):
        acc += _q(g) * mp.fsum(m[j:]) / k[j]
        x.append(acc)
    return x


def _scene(tmp_path, text: str, name: str = "s.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


# -- static sag ----------------------------------------------------------------------------------------
def test_caps_are_one_frozen_dataclass_and_the_modules_alias_them():
    assert isinstance(CAPS, Caps)
    with pytest.raises(Exception):
        CAPS.sag_terms = 1  # frozen
    from springchain.derive import damping_report, printing, work

    assert work.MAX_DET_TERMS == CAPS.det_terms and work.MAX_NUMBER_DIGITS == CAPS.number_digits
    assert modes_mod.MAX_ROOT_OPS == CAPS.root_ops and modes_mod.MAX_SYMBOLIC_BLOCK == CAPS.symbolic_block
    assert damping_report.MAX_ZETA_OPS == CAPS.zeta_ops and part_mod.MAX_OPS == CAPS.participation_ops
    assert transfer_mod.MAX_MASSES == CAPS.transfer_masses
    assert printing.MAX_TEXT_CLOSED_FORM == CAPS.text_closed_form


def test_sag_closed_form_equals_the_hand_formula(tmp_path):
    """Three hung masses: the closed form within the caps, equal to Σ (weight below)/k at 30 digits."""
    masses, springs = [1.1, 1.2, 1.3], [53.0, 56.0, 59.0]
    model = Model(load_scene(_scene(tmp_path, hanging_text(3, masses=masses, springs=springs))))
    sag = static_sag(model)
    assert sag.closed is not None and sag.why == ""
    assert all(len(sp.sstr(e)) <= CAPS.sag_chars for e in sag.closed)
    subs = {model.params[k]: sp.Rational(Fraction(v)) for k, v in model.scene.parameters.items()}
    with mp.workdps(DPS):
        ref = hand_sag(masses, springs, 9.81)
        for e, r in zip(sag.closed, ref):
            got = mp.mpf(sp.N(e.subs(subs), 40))
            assert abs(got - r) <= mp.mpf(10) ** -30 * abs(r)
        # the values printed beside it: correctly rounded
        assert [float(r) for r in ref] == list(sag.values)


def test_six_hung_masses_with_names_past_the_print_cap_are_exact_values(tmp_path):
    """The issue's hang (>300 s in cancel): the elimination stays within its term cap, the closed form is past
    the print cap (so the note gives values), and the exact values equal the hand formula."""
    masses, springs = [1.0 + 0.1 * i for i in range(1, 7)], [50.0 + 3.0 * i for i in range(1, 7)]
    model = Model(load_scene(_scene(tmp_path, hanging_text(6, masses=masses, springs=springs))))
    sol = capped_solve(model.K, sp.Matrix(model.gravity_force), CAPS.sag_terms)  # within the cap: no raise
    longest = max(len(sp.sstr(sp.cancel(e))) for e in sol)
    assert longest > CAPS.sag_chars
    sag = static_sag(model)
    assert sag.closed is None and "characters" in sag.why
    with mp.workdps(DPS):
        ref = hand_sag(masses, springs, 9.81)
        for x, r in zip(sag.exact, ref):
            assert abs(mp.mpf(x.p) / x.q - r) <= mp.mpf(10) ** -40 * abs(r)
        assert [float(r) for r in ref] == list(sag.values)
    note = next(n for n in springchain.modes(_scene(tmp_path, hanging_text(6, masses=masses, springs=springs),
                                                    "h6.toml")).to_json()["notes"] if n.startswith("gravity:"))
    inner = note.split("x_eq = K^-1 M g = (")[1].split("); modes")[0]
    assert [float(v) for v in inner.split(", ")] == list(sag.values)


def test_forty_hung_masses_past_the_mass_cap(tmp_path):
    n = 40
    masses = [10.0 ** (-3 + 6 * i / (n - 1)) for i in range(n)]  # 1e-3 … 1e3
    springs = [50.0 + 3.0 * i for i in range(1, n + 1)]
    model = Model(load_scene(_scene(tmp_path, hanging_text(n, masses=masses, springs=springs))))
    sag = static_sag(model)
    assert sag.closed is None and f"more than {CAPS.sag_masses} masses" in sag.why
    with mp.workdps(DPS):
        ref = hand_sag(masses, springs, 9.81)
    assert [float(r) for r in ref] == list(sag.values)


def test_dense_eight_masses_stop_at_the_term_cap(tmp_path):
    """Adversarial: 8 masses joined pairwise by 28 springs of distinct names, each also to the wall (44 symbols):
    the elimination's entries run past the term cap, and the sag falls back to exact values."""
    n = 8
    out = ['name = "dense8"', "[parameters]"] + [f"m{i} = {1.0 + 0.1 * i!r}" for i in range(n)] + ["g = 9.81"]
    pairs = [(i, j) for i in range(n) for j in range(i + 1, n)] + [(i, -1) for i in range(n)]
    out += [f"k{p} = {10.0 + p!r}" for p in range(len(pairs))] + ["[masses]"] + [f'a{i} = "m{i}"' for i in range(n)]
    for p, (i, j) in enumerate(pairs):
        out += ["[[springs]]", f'between = ["a{i}", "{"wall" if j < 0 else f"a{j}"}"]', f'k = "k{p}"']
    out += ["[gravity]", 'g = "g"']
    model = Model(load_scene(_scene(tmp_path, "\n".join(out) + "\n")))
    assert len(model.K.free_symbols) == len(pairs)
    with pytest.raises(WorkCapExceeded):
        capped_solve(model.K, sp.Matrix(model.gravity_force), CAPS.sag_terms)
    sag = static_sag(model)
    assert sag.closed is None and "past its cap" in sag.why
    # independent check: K x = M g in mpmath from the scene's numbers
    with mp.workdps(DPS):
        k = [_q(10.0 + p) for p in range(len(pairs))]
        K = mp.zeros(n, n)
        for p, (i, j) in enumerate(pairs):
            K[i, i] += k[p]
            if j >= 0:
                K[j, j] += k[p]
                K[i, j] -= k[p]
                K[j, i] -= k[p]
        F = mp.matrix([_q(1.0 + 0.1 * i) * _q(9.81) for i in range(n)])
        ref = mp.lu_solve(K, F)
        for i in range(n):
            assert abs(sag.values[i] - ref[i]) <= 1e-15 * abs(ref[i])


# -- modes, participation, damping ratios: past a cap equal to the closed form ----------------------------
TWO = """name = "two"
[parameters]
m1 = 1.1
m2 = 2.3
k1 = 50.0
k2 = 70.0
alpha = 0.1
beta = 0.002
[masses]
a1 = "m1"
a2 = "m2"
[[springs]]
between = ["wall", "a1"]
k = "k1"
[[springs]]
between = ["a1", "a2"]
k = "k2"
[damping]
rayleigh = ["alpha", "beta"]
"""


def _two_reference():
    """ω², |Γ|, M*, ζ of the two-mass chain by hand: m1 m2 λ² − (m1 k2 + m2 (k1 + k2)) λ + k1 k2 = 0,
    φ = (k2, k1 + k2 − λ m1), Γ = φᵀM1/√(φᵀMφ), ζ = α/(2ω) + βω/2."""
    m1, m2, k1, k2, a, b = (_q(v) for v in (1.1, 2.3, 50.0, 70.0, 0.1, 0.002))
    A, B, C = m1 * m2, -(m1 * k2 + m2 * (k1 + k2)), k1 * k2
    disc = mp.sqrt(B * B - 4 * A * C)
    out = []
    for lam in sorted([(-B - disc) / (2 * A), 2 * C / (-B - disc)]):
        phi = (k2, k1 + k2 - lam * m1)
        gamma = abs(m1 * phi[0] + m2 * phi[1]) / mp.sqrt(m1 * phi[0] ** 2 + m2 * phi[1] ** 2)
        w = mp.sqrt(lam)
        out.append({"omega2": lam, "gamma": gamma, "meff": gamma ** 2, "zeta": a / (2 * w) + b * w / 2})
    return out


def _check_against(records, ref, with_exprs: bool, m):
    subs = {sp.Symbol(k, positive=True): sp.Rational(Fraction(v)) for k, v in m.scene.parameters.items()}
    for rec, r in zip(records, ref):
        for key, field, expr_field in (("omega2", "omega2_value", "omega2"), ("gamma", "participation_factor",
                                                                               "participation_factor_expr"),
                                       ("meff", "effective_mass", "effective_mass_expr"),
                                       ("zeta", "damping_ratio", "damping_ratio_expr")):
            assert abs(abs(rec[field]) - r[key]) <= 2e-16 * r[key], (field, rec[field], r[key])
            if with_exprs:
                e = m.parse(rec[expr_field])
                got = mp.mpf(sp.N(abs(e.subs(subs)), 40))
                assert abs(got - r[key]) <= mp.mpf(10) ** -30 * r[key], expr_field


def test_two_masses_closed_forms_and_values_past_the_caps_agree(tmp_path, monkeypatch):
    path = _scene(tmp_path, TWO)
    with mp.workdps(DPS):
        ref = _two_reference()
    m = springchain.modes(path)
    data = m.to_json()
    assert data["closed_form_parts"] == {"modes": [2, 2], "damping_ratios": [2, 2], "participation": [2, 2]}
    assert all(sp.count_ops(m.parse(r["omega2"])) <= CAPS.root_ops for r in data["modes"])
    with mp.workdps(DPS):
        _check_against(data["modes"], ref, True, m)
    # every cap at zero: the same values from the numeric route, no closed forms
    monkeypatch.setattr(modes_mod, "MAX_ROOT_OPS", 0)
    monkeypatch.setattr(part_mod, "MAX_INPUT_OPS", 0)
    past = springchain.modes(path)
    pdata = past.to_json()
    assert pdata["closed_form"] is False
    assert pdata["closed_form_parts"]["modes"] == [0, 2] and pdata["closed_form_parts"]["participation"] == [0, 2]
    assert pdata["closed_form_summary"].startswith("closed form: ")
    assert "values only" in pdata["closed_form_summary"] and "Γ, M*" in pdata["closed_form_summary"]
    with mp.workdps(DPS):
        _check_against(pdata["modes"], ref, False, past)
    text = past.to_text().splitlines()
    assert sum(line.startswith("closed form:") for line in text) == 1


def test_participation_input_cap_is_an_operation_count(tmp_path, monkeypatch):
    """Γ and M* are attempted exactly when Σ mφ plus Σ mφ² have at most participation_input_ops operations."""
    path = _scene(tmp_path, TWO)
    m = springchain.modes(path)
    sizes = []
    for mode in m.modes.modes:
        s = mode.shapes[0]
        a = sp.Add(*(mi * c for mi, c in zip(m.model.masses, s)))
        b = sp.Add(*(mi * c ** 2 for mi, c in zip(m.model.masses, s)))
        sizes.append(int(sp.count_ops(a)) + int(sp.count_ops(b)))
    monkeypatch.setattr(part_mod, "MAX_INPUT_OPS", min(sizes) - 1)
    parts = springchain.modes(path).to_json()["closed_form_parts"]["participation"]
    assert parts == [0, 2]
    monkeypatch.setattr(part_mod, "MAX_INPUT_OPS", max(sizes))
    assert springchain.modes(path).to_json()["closed_form_parts"]["participation"] == [2, 2]


def test_transfer_function_cap_by_masses(tmp_path, monkeypatch):
    """H(s) in closed form up to transfer_masses masses; past it None, and frf's |H| still equals the hand
    receptance (Z = K − ω²M + iω(αM + βK), H = (Z⁻¹)_{21})."""
    path = _scene(tmp_path, TWO)
    model = Model(load_scene(path))
    tf = transfer_mod.transfer_function(model, 0, 1)
    assert tf is not None
    monkeypatch.setattr(transfer_mod, "MAX_MASSES", 1)
    assert transfer_mod.transfer_function(model, 0, 1) is None
    h = springchain.frf(path, "a1", "a2", points=20, transfer=False)
    m1, m2, k1, k2, a, b = (_q(v) for v in (1.1, 2.3, 50.0, 70.0, 0.1, 0.002))
    with mp.workdps(DPS):
        for w, mag in list(zip(h.omega, h.magnitude))[::7]:
            w = _q(float(w))
            iw = mp.mpc(0, 1) * w
            z11 = k1 + k2 - w * w * m1 + iw * (a * m1 + b * (k1 + k2))
            z22 = k2 - w * w * m2 + iw * (a * m2 + b * k2)
            z12 = -k2 - iw * b * k2
            ref = abs(-z12 / (z11 * z22 - z12 * z12))
            assert abs(mag - ref) <= 1e-10 * ref


def test_potential_zero_test_skips_simplify_past_the_cap():
    """A gradient entry past simplify_ops operations is not simplified (unproven zero: the loading path decides);
    within the cap SymPy's simplify proves it."""
    from springchain.derive.equilibrium import _simplifies_to_zero

    x = sp.Symbol("x", positive=True)
    small = sp.sin(x) ** 2 + sp.cos(x) ** 2 - 1
    big = sp.Add(*(sp.sin(i * x) ** 2 + sp.cos(i * x) ** 2 - 1 for i in range(1, 40)))
    assert sp.count_ops(small) <= CAPS.simplify_ops < sp.count_ops(big)
    assert _simplifies_to_zero(small) is True
    assert _simplifies_to_zero(big) is False
    assert _simplifies_to_zero(sp.Integer(0)) is True


def test_json_and_text_share_the_closed_form_line(tmp_path):
    path = _scene(tmp_path, hanging_text(6))
    m = springchain.modes(path)
    line = next(ln for ln in m.to_text().splitlines() if ln.startswith("closed form:"))
    data = json.loads(json.dumps(m.to_json()))
    assert data["closed_form_summary"] == line
    assert data["closed_form_parts"]["sag"] is False and "static sag x_eq" in line.split("values only")[1]


def test_sag_with_irrational_constants_settles_in_mpmath(tmp_path):
    """Springs sqrt(2)*k2 and pi*k3: no rational solve; the values settle in mpmath, equal to the hand formula."""
    masses, springs = [1.1, 1.2, 1.3], [53.0, 56.0, 59.0]
    text = hanging_text(3, masses=masses, springs=springs).replace('k = "k2"', 'k = "sqrt(2)*k2"').replace(
        'k = "k3"', 'k = "pi*k3"')
    model = Model(load_scene(_scene(tmp_path, text)))
    sag = static_sag(model)
    assert sag.exact is None
    with mp.workdps(DPS):
        k = [_q(springs[0]), mp.sqrt(2) * _q(springs[1]), mp.pi * _q(springs[2])]
        m = [_q(v) for v in masses]
        ref, acc = [], mp.mpf(0)
        for j in range(3):
            acc += _q(9.81) * mp.fsum(m[j:]) / k[j]
            ref.append(acc)
    for v, r in zip(sag.values, ref):
        assert abs(v - r) <= 1.2e-16 * abs(r)


def test_frf_of_a_forty_mass_chain_is_certified_not_refused(tmp_path):
    """Past the dense mpmath limit (24 masses) a chain's Z is tridiagonal: the extended-precision solve is
    offered (it was refused at the near-resonance frequencies the float64 certificate rejects), and |H| equals
    an independent mpmath elimination at 50 digits."""
    n = 40
    out = ['name = "c40"', "[parameters]"] + [f"m{i} = {1.0 + 0.1 * i!r}" for i in range(1, n + 1)]
    out += [f"k{i} = {50.0 + 3.0 * i!r}" for i in range(1, n + 2)] + ["[masses]"]
    out += [f'a{i} = "m{i}"' for i in range(1, n + 1)]
    ends = ["wall"] + [f"a{i}" for i in range(1, n + 1)] + ["wall"]
    for i, (a, b) in enumerate(zip(ends, ends[1:]), 1):
        out += ["[[springs]]", f'between = ["{a}", "{b}"]', f'k = "k{i}"']
    h = springchain.frf(_scene(tmp_path, "\n".join(out) + "\n"), "a1", f"a{n}", points=200, transfer=False)
    m = [_q(1.0 + 0.1 * i) for i in range(1, n + 1)]
    k = [_q(50.0 + 3.0 * i) for i in range(1, n + 2)]
    omega, mag = list(h.omega), list(h.magnitude)
    with mp.workdps(DPS):
        for j in range(0, len(omega), max(1, len(omega) // 25)):
            w = _q(float(omega[j]))
            Z = mp.zeros(n, n)
            for i in range(n):
                Z[i, i] = k[i] + k[i + 1] - w * w * m[i]
                if i + 1 < n:
                    Z[i, i + 1] = Z[i + 1, i] = -k[i + 1]
            e = mp.matrix(n, 1)
            e[0] = 1
            ref = abs(mp.lu_solve(Z, e)[n - 1])
            assert abs(mag[j] - ref) <= 1e-10 * ref, (omega[j], mag[j], ref)
