"""Issue 31, modes at extreme contrast: the named findings, each against an mpmath reference written here.

1. A wall spring 1e-70 … 1e-150 times its neighbour printed ω² = 0.0 (true ≈ 1e-90): the closed form
   ``(2k + kw)/(2m) − sqrt(4k² + kw²)/(2m)`` cancels to noise below ~100 digits, and the evaluation
   took noise that shrank with the precision for an exact zero. Checked: text, ``--json``
   ``omega2_value``, ``Modes.omega2_values`` and the participation table's ω, on the closed-form, the
   mpmath and the spring-factor routes.
2. Two masses joined by ``k = "2e-70"`` (also 2e-100, 2e-120) ended ``modes`` in a SymPy traceback
   ("... is not a prime factor of ..."): SymPy 1.14's ``sqrt`` of the characteristic polynomial's
   large discriminant goes through ``factorint(limit=2**15)``, whose factor cache raises on some
   composite cofactors (sympy/sympy#28621), and with gmpy2 ``math.log`` of an ``mpz`` past 1e308
   overflows. Such failures now mean "no closed form": the accurate numeric route answers.
3. A potential ``1e200*d**2`` skipped the range check (an OverflowError traceback): every number
   written in an expression, every parameter value and a potential's stiffness at the equilibrium
   are held to the range of masses and springs, 1e-150 … 1e150.
4. ``mass = "m0*q**i"`` in ``[chain]`` was refused: a parameter to a power of the index is accepted.

The reference: ``D = M^-1/2 K M^-1/2`` assembled here from the values written in the scene (exact
binary fractions of the floats, exact decimals of the literals) and diagonalised by ``mpmath.eigsy``
at a precision that covers the contrast, re-solved at twice it and required to agree to 1e-30.
"""

from __future__ import annotations

import json
import re
from fractions import Fraction

import mpmath
import numpy as np
import pytest

import springchain
from springchain.cli import main as cli_main

#: Relative error allowed on every ω² read at full precision (JSON, API): a few ulps.
RTOL = 1e-14


def _exact(v) -> Fraction:
    """The exact value a scene number stands for: a float's binary value, a literal's decimal text."""
    return Fraction(v) if isinstance(v, str) else Fraction(float(v))


def reference_omega2(masses, springs, digits: int) -> list:
    """ω² ascending of ``K φ = ω² M φ``: mpmath at ``digits`` and ``2 * digits``, required to agree.

    Parameters
    ----------
    masses : list of Fraction
    springs : list of (int, int, Fraction), -1 = wall
    digits : int
        Working precision; must exceed the decades of contrast plus ~40.
    """
    out = []
    for dps in (digits, 2 * digits):
        with mpmath.workdps(dps):
            n = len(masses)
            r = [1 / mpmath.sqrt(mpmath.mpf(m.numerator) / m.denominator) for m in masses]
            D = mpmath.zeros(n, n)
            for a, b, k in springs:
                kv = mpmath.mpf(k.numerator) / k.denominator
                for i, si in ((a, 1), (b, -1)):
                    for j, sj in ((a, 1), (b, -1)):
                        if i >= 0 and j >= 0:
                            D[i, j] += si * sj * kv * r[i] * r[j]
            w = sorted(mpmath.eigsy(D, eigvals_only=True))
            out.append(w)
    lo, hi = out
    with mpmath.workdps(2 * digits):
        for a, b in zip(lo, hi):
            assert abs(a - b) <= mpmath.mpf(10) ** -30 * abs(b) + mpmath.mpf(10) ** (-digits + 5), \
                "reference not settled: raise its precision"
    return hi


def _rel(got, want) -> float:
    return float(abs(mpmath.mpf(got) - want) / abs(want))


def _write(tmp_path, name: str, text: str):
    path = tmp_path / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _masses_scene(name: str, params: dict, masses: list, springs: list) -> str:
    """TOML of a [masses] scene: masses and springs are expression strings (parameters or literals)."""
    lines = [f'name = "{name}"', "[parameters]"]
    lines += [f"{p} = {v!r}" for p, v in params.items()]
    lines += ["[masses]"] + [f'x{i} = "{m}"' for i, m in enumerate(masses)]
    for a, b, k in springs:
        ea, eb = ("wall" if e < 0 else f"x{e}" for e in (a, b))
        lines += ["[[springs]]", f'between = ["{ea}", "{eb}"]', f'k = "{k}"']
    return "\n".join(lines) + "\n"


def _printed_text_values(text: str) -> list[float]:
    """The ``(= value at the scene's values)`` of every ``ω² =`` line of the text report."""
    return [float(m) for m in re.findall(r"^\s*ω² = .*\(= (\S+) at the scene's values\)", text, re.M)]


def _participation_omegas(text: str) -> list[float]:
    """The ω column of the participation table (10 significant digits)."""
    rows = text.split("Modal participation", 1)[1].splitlines()[2:]
    out = []
    for row in rows:
        parts = row.split()
        if len(parts) != 6 or not parts[0].isdigit():
            break
        out.append(float(parts[1]))
    return out


def _check_modes(path, masses, springs, digits, *, participation=True):
    """Text, JSON, API (and the participation table's ω) against the reference; returns the reference."""
    want = reference_omega2(masses, springs, digits)
    m = springchain.modes(path)
    data = m.to_json()
    printed = [rec["omega2_value"] for rec in data["modes"]]
    assert len(printed) == len(want)
    for got, w in zip(printed, want):
        assert got > 0 and _rel(got, w) <= RTOL, (printed, [mpmath.nstr(x, 17) for x in want])
    api = m.omega2_values
    assert all(_rel(g, w) <= RTOL for g, w in zip(api, want)), api
    text = m.to_text()
    shown = _printed_text_values(text)
    assert len(shown) == len(want) and all(_rel(g, w) <= 6e-10 for g, w in zip(shown, want)), shown
    if participation:
        omegas = _participation_omegas(text)
        assert len(omegas) == len(want)
        assert all(_rel(o * o, w) <= 2e-9 for o, w in zip(omegas, want)), omegas
    # the command prints the same numbers in one JSON object
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert cli_main(["modes", str(path), "--json"]) == 0
    assert [r["omega2_value"] for r in json.loads(buf.getvalue())["modes"]] == printed
    return want


# -- 1. a wall spring far softer than its neighbour ---------------------------------------------------
@pytest.mark.parametrize("ratio", [1e-70, 1e-90, 1e-120, 1e-140, 1e-150])
def test_soft_wall_spring_closed_form(tmp_path, ratio):
    """Two equal masses, wall spring kw = ratio·k: the lower ω² ≈ kw/(2m) in closed form."""
    params = {"k": 1.0, "kw": ratio, "m": 1.0}
    path = _write(tmp_path, "softwall", _masses_scene("softwall", params, ["m", "m"], [(-1, 0, "kw"), (0, 1, "k")]))
    masses = [_exact(1.0)] * 2
    springs = [(-1, 0, _exact(ratio)), (0, 1, _exact(1.0))]
    want = _check_modes(path, masses, springs, digits=360)
    assert springchain.modes(path).to_json()["closed_form"] is True
    assert abs(float(want[0]) / (ratio / 2) - 1) < 1e-6  # the physics: ω² ≈ kw/(2m)


@pytest.mark.parametrize("ratio", [1e-90, 1e-140])
def test_soft_wall_spring_numeric_route(tmp_path, ratio):
    """Four different masses (a quartic: the mpmath route), the soft wall spring at one end."""
    params = {"a": 1.0, "b": 2.5, "c": 0.7, "e": 3.1, "k": 2.0, "kw": ratio}
    path = _write(tmp_path, "softwall4", _masses_scene("softwall4", params, ["a", "b", "c", "e"],
                                                        [(-1, 0, "kw"), (0, 1, "k"), (1, 2, "k"), (2, 3, "k")]))
    masses = [_exact(params[p]) for p in "abce"]
    springs = [(-1, 0, _exact(ratio))] + [(i, i + 1, _exact(2.0)) for i in range(3)]
    _check_modes(path, masses, springs, digits=360)
    assert springchain.modes(path).to_json()["closed_form"] is False


def test_soft_wall_spring_spring_factor_route(tmp_path):
    """Eighteen masses (past the mpmath route's 16: the spring-factor SVD), the soft spring at the wall."""
    n = 18
    params = {"k": 1.0, "kw": 1e-120, "m": 1.0, "mh": 3.0}
    masses_expr = ["m" if i % 2 else "mh" for i in range(n)]
    springs_expr = [(-1, 0, "kw")] + [(i, i + 1, "k") for i in range(n - 1)]
    path = _write(tmp_path, "softwall18", _masses_scene("softwall18", params, masses_expr, springs_expr))
    masses = [_exact(params[e]) for e in masses_expr]
    springs = [(a, b, _exact(params[k])) for a, b, k in springs_expr]
    want = reference_omega2(masses, springs, 300)
    got = springchain.modes(path).omega2_values
    errs = [_rel(g, w) for g, w in zip(got, want)]
    assert len(got) == n and max(errs) <= 2e-14, errs  # a few ulps of relative accuracy, the smallest included


# -- 2. SymPy's number theory on large exact numbers -------------------------------------------------------
@pytest.mark.parametrize("m1, m2, kwall, kc", [
    ("3", "5", "0.3", "2e-70"),       # "937499...0001 is not a prime factor" (sympy/sympy#28621)
    ("3", "1", "1.5", "2e-100"),
    ("0.2", "5", "0.5", "2e-120"),
    ("3e-150", "7", "1e150", "3e-150"),  # OverflowError: 'mpz' too large to convert to float
])
@pytest.mark.parametrize("cap", ["digits", "lifted"])
def test_sympy_number_failures_fall_back_to_the_accurate_route(tmp_path, monkeypatch, m1, m2, kwall, kc, cap):
    """With the 40-digit cap on exact numbers the closed form is not attempted at all; with the cap
    lifted, SymPy's own failure (ValueError / OverflowError inside sympy) is the fallback's cause."""
    import springchain.derive.modes as modes_module

    if cap == "lifted":
        monkeypatch.setattr(modes_module, "MAX_NUMBER_DIGITS", 10**9)
    path = _write(tmp_path, "lit", _masses_scene("lit", {}, [m1, m2], [(-1, 0, kwall), (0, 1, kc)]))
    masses = [_exact(m1), _exact(m2)]
    springs = [(-1, 0, _exact(kwall)), (0, 1, _exact(kc))]
    _check_modes(path, masses, springs, digits=700)
    data = springchain.modes(path).to_json()
    note = " ".join(data["notes"])
    if cap == "digits":
        assert "more than 40 digits" in note, note
    else:  # SymPy's factor cache is global: whether it raises depends on what it factored before
        assert data["closed_form"] or "SymPy's arithmetic failed" in note, note
    assert cli_main(["modes", str(path)]) == 0


def test_sympy_failure_is_not_swallowed_outside_sympy():
    """Only SymPy's own ValueError/OverflowError become a fallback; springchain's propagate."""
    from springchain.derive.work import SymbolicNumbersFailed, sympy_numbers

    with pytest.raises(ValueError, match="ours"):
        with sympy_numbers():
            raise ValueError("ours")
    with pytest.raises(SymbolicNumbersFailed):
        with sympy_numbers():
            from sympy.ntheory.factor_ import factor_cache

            factor_cache[15] = 6  # SymPy's own check raises "6 is not a prime factor of 15"


# -- 3. every number in range ------------------------------------------------------------------------------
@pytest.mark.parametrize("entry, key, says", [
    ('[[springs]]\nbetween = ["wall", "m1"]\npotential = "1e200*d**2"\n', "springs[0].potential", "1e+200"),
    ('[[springs]]\nbetween = ["wall", "m1"]\npotential = "1e150*1e150*d**2"\n', "springs[0].potential",
     "stiffness"),
    ('[[springs]]\nbetween = ["wall", "m1"]\npotential = "1e-100*1e-100*d**2"\n', "springs[0].potential",
     "stiffness"),
    ('[[springs]]\nbetween = ["wall", "m1"]\nk = "1"\n[[forces]]\non = "m1"\nf = "1e-200*cos(t)"\n',
     "forces[0].f", "1e-200"),
    ('[[springs]]\nbetween = ["wall", "m1"]\nk = "1e160*1e-20"\n', "springs[0].k", "1e+160"),
])
def test_numbers_outside_the_range_are_refused(tmp_path, capsys, entry, key, says):
    text = 'name = "big"\n[parameters]\nm = 1.0\n[masses]\nm1 = "m"\n' + entry
    path = _write(tmp_path, "big", text)
    assert cli_main(["modes", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert key in err and says in err and "1e-150" in err and "1e+150" in err, err


@pytest.mark.parametrize("value", [1e200, 1e-200])
def test_parameter_values_are_checked_by_what_they_make(tmp_path, capsys, value):
    """A parameter may be any finite number (a phase of 1e-167 is harmless); a potential's stiffness made
    from it is held to the range of a spring's k."""
    text = (f'name = "par"\n[parameters]\nm = 1.0\nbig = {value!r}\n[masses]\nm1 = "m"\n'
            '[[springs]]\nbetween = ["wall", "m1"]\npotential = "big*d**2"\n')
    path = _write(tmp_path, "par", text)
    assert cli_main(["modes", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "springs[0].potential" in err and "stiffness" in err and "1e-150" in err, err


def test_range_edges_are_accepted(tmp_path):
    """0, ±1e-150 and 1e150 are inside."""
    text = ('name = "edge"\n[parameters]\nm = 1e150\nz = 0.0\nlo = -1e-150\n[masses]\nm1 = "m + z"\n'
            '[[springs]]\nbetween = ["wall", "m1"]\nk = "1e150 - lo"\n')
    path = _write(tmp_path, "edge", text)
    got = springchain.modes(path).omega2_values
    want = (Fraction("1e150") + Fraction(1e-150)) / Fraction(1e150)
    assert abs(got[0] - float(want)) <= 1e-15 * float(want)


def test_values_beyond_float64_raise_its_limit():
    """An ω² float64 cannot hold with its relative accuracy is said (Float64Limit), never printed as 0."""
    from springchain.derive.accurate import Float64Limit, value
    import sympy as sp

    with pytest.raises(Float64Limit, match="normal range"):
        value(sp.Rational(1, 10**320), {}, nonzero=True)
    with pytest.raises(Float64Limit, match="normal range"):
        value(sp.Integer(10) ** 320, {})
    # the numeric routes hold the same limit
    from springchain.derive.accurate import numeric_modes

    with pytest.raises(Float64Limit):
        numeric_modes([sp.Integer(10) ** 150, sp.Integer(10) ** 150],
                      [(-1, 0, sp.Rational(1, 10**150)), (0, 1, sp.Rational(1, 10**150) / 10**20)], 0)


# -- 4. geometric growth along a chain ---------------------------------------------------------------------
def _chain_reference(n, mass, k, left, right, digits=80):
    masses = [mass(i) for i in range(n)]
    springs = [(i, i + 1, k(i)) for i in range(n - 1)]
    if left == "wall":
        springs.append((-1, 0, k(-1)))
    if right == "wall":
        springs.append((n - 1, -1, k(n - 1)))
    if left == "ring":
        springs.append((n - 1, 0, k(n - 1)))
    return reference_omega2(masses, springs, digits)


@pytest.mark.parametrize("n, left, right, q", [
    (6, "wall", "free", 2.0), (9, "wall", "wall", 0.1), (7, "free", "free", 37.5), (5, "ring", "ring", 3.0),
    (40, "wall", "free", 1.7),
])
def test_geometric_chain_masses(tmp_path, n, left, right, q):
    text = (f'name = "geo"\n[parameters]\nm0 = 0.75\nq = {q!r}\nk = 2.0\nk0 = 1.5\n'
            f'[chain]\nn = {n}\nmass = "m0*q**i"\nk = "k0 + k*(i % 2)"\nleft = "{left}"\nright = "{right}"\n')
    path = _write(tmp_path, "geo", text)
    mass = lambda i: Fraction(0.75) * Fraction(q) ** i  # noqa: E731
    k = lambda i: Fraction(1.5) + Fraction(2.0) * (i % 2)  # noqa: E731  (Python's % as the scene's)
    want = _chain_reference(n, mass, k, left, right, digits=120)
    m = springchain.modes(path)
    got = m.omega2_values
    n_rigid = 1 if (left, right) in (("free", "free"), ("ring", "ring")) else 0
    assert len(got) == n and all(v == 0.0 for v in got[:n_rigid])
    # masses m0*q**i are rounded once in float64 (q**i by NumPy's power): ω² move by a few ulps
    errs = [_rel(g, w) for g, w in zip(got[n_rigid:], want[n_rigid:])]
    assert max(errs) <= 1e-13, errs
    assert "q**i" in m.to_text()


@pytest.mark.parametrize("expr, ok", [
    ("m0*q**i", True), ("m0*q**(i/2)", True), ("m0*q**(7 - i)", True), ("m0*q**-i", True),
    ("m0*2**i", False),          # a number base: its exact powers would be computed digit by digit
    ("m0*q**m0", False),         # an exponent with a parameter
    ("m0*i**q", False),          # the index as the base
    ("m0*q**t", False),
])
def test_power_of_the_index_whitelist(tmp_path, expr, ok):
    from springchain.derive.errors import SceneError

    text = (f'name = "w"\n[parameters]\nm0 = 1.0\nq = 1.1\nk = 1.0\n[chain]\nn = 8\nmass = "{expr}"\n'
            'k = "k"\nleft = "wall"\n')
    path = _write(tmp_path, "w", text)
    if ok:
        springchain.load(path)
    else:
        with pytest.raises(SceneError, match="chain.mass"):
            springchain.load(path)


def test_power_of_the_index_out_of_range_is_refused(tmp_path):
    """q**i is range-checked at every index like any chain value."""
    from springchain.derive.errors import SceneError

    text = ('name = "w"\n[parameters]\nm0 = 1.0\nq = 10.0\nk = 1.0\n[chain]\nn = 200\nmass = "m0*q**i"\n'
            'k = "k"\nleft = "wall"\n')
    with pytest.raises(SceneError, match=r"chain.mass.*at i = 151"):
        springchain.load(_write(tmp_path, "w", text))


def test_geometric_chain_simulates_against_its_modes(tmp_path):
    """The generated module evaluates q**i (NumPy) and its exact run matches the modal reference."""
    n = 6
    text = ('name = "geosim"\n[parameters]\nm0 = 1.0\nq = 3.0\nk = 2.0\n'
            f'[chain]\nn = {n}\nmass = "m0*q**i"\nk = "k"\nleft = "wall"\nright = "free"\n'
            '[initial]\nx = "0.01*(i + 1)"\nv = "0"\n[simulation]\ndt = 0.05\nsteps = 40\n')
    path = _write(tmp_path, "geosim", text)
    sim = springchain.simulate(path, methods=["modal"], out=tmp_path / "out", figures=False)
    # reference: the modal solution in mpmath from M, K assembled here
    with mpmath.workdps(60):
        M = mpmath.diag([mpmath.mpf(3) ** i for i in range(n)])
        K = mpmath.zeros(n, n)
        for a, b in [(-1, 0)] + [(i, i + 1) for i in range(n - 1)]:
            for i, si in ((a, 1), (b, -1)):
                for j, sj in ((a, 1), (b, -1)):
                    if i >= 0 and j >= 0:
                        K[i, j] += si * sj * 2
        r = mpmath.diag([1 / mpmath.sqrt(M[i, i]) for i in range(n)])
        w, E = mpmath.eigsy(r * K * r)
        x0 = mpmath.matrix([mpmath.mpf("0.01") * (i + 1) for i in range(n)])
        q0 = E.T * (mpmath.diag([mpmath.sqrt(M[i, i]) for i in range(n)]) * x0)
        for row, t in enumerate(sim.t):
            q = mpmath.matrix([q0[j] * mpmath.cos(mpmath.sqrt(w[j]) * mpmath.mpf(float(t))) for j in range(n)])
            x = r * (E * q)
            assert np.allclose(sim.x["modal"][row], [float(c) for c in x], rtol=0, atol=1e-14)


# -- float64's own range, at the edges of the accepted domain -------------------------------------------------
def test_long_chain_below_float64_normal_range_says_so(tmp_path, capsys):
    """Masses 1e150, springs 1e-150, 1e5 masses: the lowest ω² ~ 2.5e-310 is subnormal in float64. The
    listed values are the closed form's, and a note names the limit instead of passing them off as accurate."""
    n = 100_000
    text = (f'name = "sub"\n[parameters]\nm = 1e150\nk = 1e-150\n[chain]\nn = {n}\nmass = "m"\nk = "k"\n'
            'left = "wall"\nright = "free"\n')
    path = _write(tmp_path, "sub", text)
    assert cli_main(["modes", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    notes = " ".join(data["notes"])
    assert "float64 limit" in notes and "2.23e-308" in notes, notes
    with mpmath.workdps(60):  # ω_j² = (4k/m) sin²((2j-1)π/(2(2n+1))), the normal ones to full accuracy
        for rec in data["modes"]:
            want = 4 * mpmath.mpf(Fraction(1e-150).numerator) / Fraction(1e-150).denominator \
                / (mpmath.mpf(Fraction(1e150).numerator) / Fraction(1e150).denominator) \
                * mpmath.sin((2 * rec["j"] - 1) * mpmath.pi / (2 * (2 * n + 1))) ** 2
            if want > 2.3e-308:
                assert _rel(rec["omega2_value"], want) <= 1e-14


def test_long_chain_beyond_the_bisection_range_is_refused(tmp_path, capsys):
    """sqrt(k/m) spanning more than 1e140 in a chain past 4000 masses: no float64 route here keeps relative
    accuracy in O(n) per value, so one line names the limit instead of 20 wrong numbers."""
    text = ('name = "far"\n[parameters]\nma = 1.0\nmb = 3e149\nka = 1e80\nkb = 1e-80\n[chain]\nn = 5000\n'
            'mass = "ma*(1 - i % 2) + mb*(i % 2)"\nk = "ka*(1 - i % 2) + kb*(i % 2)"\nleft = "wall"\nright = "free"\n')
    path = _write(tmp_path, "far", text)
    assert cli_main(["modes", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "1e+140" in err and "4000" in err and "Traceback" not in err, err


def test_extreme_chain_within_the_dense_route_is_accurate(tmp_path):
    """The same contrast on 60 masses (listed 10 + 10, by dbdsqr's QR) against mpmath."""
    n = 60
    text = ('name = "far60"\n[parameters]\nma = 1.0\nmb = 3e149\nka = 1e80\nkb = 1e-80\n[chain]\n'
            f'n = {n}\nmass = "ma*(1 - i % 2) + mb*(i % 2)"\nk = "ka*(1 - i % 2) + kb*(i % 2)"\n'
            'left = "wall"\nright = "free"\n')
    path = _write(tmp_path, "far60", text)
    mass = lambda i: Fraction(3e149) if i % 2 else Fraction(1.0)  # noqa: E731
    k = lambda i: Fraction(1e-80) if i % 2 else Fraction(1e80)  # noqa: E731  (i = -1: the wall, odd)
    want = _chain_reference(n, mass, k, "wall", "free", digits=400)
    got = springchain.modes(path).omega2_values
    listed = list(range(10)) + list(range(n - 10, n))
    errs = [_rel(g, want[p]) for g, p in zip(got, listed)]
    assert len(got) == 20 and max(errs) <= 1e-13, errs
