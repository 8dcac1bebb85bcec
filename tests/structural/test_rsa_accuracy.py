"""Response-spectrum analysis at any stiffness contrast (issue 20/18): every modal number rsa prints
against an independent mpmath reference built here from the scene's TOML.

The reference: M and K written from the TOML's numbers (each float an exact binary fraction),
``mpmath.eigsy`` of M^-1/2 K M^-1/2 at 120 digits, checked against 240; Γ = φᵀM1, M* = Γ²,
extensions and forces from the shapes in that precision, SD = Sa/ω² of a flat design spectrum,
ζ of Rayleigh damping (α/ω + βω)/2 and Der Kiureghian's ρ written out. Nothing of springchain
is used to build it.
"""

from __future__ import annotations

import tomllib

import mpmath as mp
import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import springchain as sc

SA = 3.0  # flat design spectrum [m/s2]
SPECTRUM = (np.array([0.0, 1e15]), np.array([SA, SA]))


def rayleigh_chain_text(masses, springs, alpha, beta) -> str:
    """A wall chain: wall - m0 - m1 - ... (springs[i] below mass i)."""
    n = len(masses)
    out = ['name = "acc"', "[parameters]"]
    out += [f"m{i} = {v!r}" for i, v in enumerate(masses)] + [f"k{i} = {v!r}" for i, v in enumerate(springs)]
    out += [f"al = {alpha!r}", f"be = {beta!r}", "[masses]"] + [f'x{i} = "m{i}"' for i in range(n)]
    for i in range(n):
        out += ["[[springs]]", f'between = ["{"wall" if i == 0 else f"x{i - 1}"}", "x{i}"]', f'k = "k{i}"']
    out += ["[damping]", 'rayleigh = ["al", "be"]', "[simulation]", "dt = 1e-3", "steps = 10"]
    return "\n".join(out) + "\n"


def reference(text: str, dps: int) -> dict:
    """Modal peaks of the scene ``text`` (a wall chain) for SPECTRUM, at ``dps`` digits."""
    d = tomllib.loads(text)
    p = d["parameters"]
    n = len(d["masses"])
    with mp.workdps(dps):
        m = [mp.mpf(p[f"m{i}"]) for i in range(n)]
        k = [mp.mpf(p[f"k{i}"]) for i in range(n)]
        al, be = mp.mpf(p["al"]), mp.mpf(p["be"])
        K = mp.zeros(n, n)
        for i in range(n):  # spring i between mass i-1 (or the wall) and mass i
            K[i, i] += k[i]
            if i:
                K[i - 1, i - 1] += k[i]
                K[i - 1, i] -= k[i]
                K[i, i - 1] -= k[i]
        s = [1 / mp.sqrt(v) for v in m]
        D = mp.matrix(n, n)
        for i in range(n):
            for j in range(n):
                D[i, j] = s[i] * K[i, j] * s[j]
        lam, Q = mp.eigsy(D)
        modes = []
        for j in sorted(range(n), key=lambda j: lam[j]):
            phi = [s[i] * Q[i, j] for i in range(n)]
            big = max(abs(c) for c in phi)
            if next(c for c in phi if abs(c) > mp.mpf("1e-12") * big) < 0:
                phi = [-c for c in phi]
            w = mp.sqrt(lam[j])
            sd = mp.mpf(SA) / lam[j]
            g = mp.fsum(mi * c for mi, c in zip(m, phi))
            x = [g * sd * c for c in phi]
            drift = [x[0]] + [x[i] - x[i - 1] for i in range(1, n)]
            modes.append({"omega": w, "zeta": (al / w + be * w) / 2, "gamma": g, "mstar": g * g,
                          "x": x, "drift": drift, "force": [ki * e for ki, e in zip(k, drift)],
                          "base": k[0] * x[0]})
        rho = [[None] * n for _ in range(n)]
        for i, a in enumerate(modes):
            for j, b in enumerate(modes):
                r, zi, zj = b["omega"] / a["omega"], a["zeta"], b["zeta"]
                rho[i][j] = (8 * mp.sqrt(zi * zj) * (zi + r * zj) * r ** mp.mpf(1.5)
                             / ((1 - r * r) ** 2 + 4 * zi * zj * r * (1 + r * r) + 4 * (zi * zi + zj * zj) * r * r))
        comb = {}
        for key in ("x", "drift", "force"):
            comb[("srss", key)] = [mp.sqrt(mp.fsum(md[key][c] ** 2 for md in modes)) for c in range(n)]
            comb[("cqc", key)] = [mp.sqrt(mp.fsum(rho[i][j] * modes[i][key][c] * modes[j][key][c]
                                                  for i in range(n) for j in range(n))) for c in range(n)]
        comb[("srss", "base")] = mp.sqrt(mp.fsum(md["base"] ** 2 for md in modes))
        comb[("cqc", "base")] = mp.sqrt(mp.fsum(rho[i][j] * modes[i]["base"] * modes[j]["base"]
                                                for i in range(n) for j in range(n)))
        return {"modes": modes, "comb": comb, "total": mp.fsum(m)}


def _rel(got, want, scale):
    """Error of ``got`` relative to ``want``, or to 1e-2 of ``scale`` where ``want`` is tiny
    (so that 1e-10 relative or 1e-12 of the scale passes)."""
    return float(abs(mp.mpf(got) - want) / max(abs(want), mp.mpf("1e-2") * scale))


def check(tmp_path, text, tol=1e-10) -> float:
    path = tmp_path / "acc.toml"
    path.write_text(text)
    data = sc.rsa(sc.load(path), spectrum=SPECTRUM).to_json()
    ref = reference(text, 120)
    again = reference(text, 240)  # the reference itself settled
    worst = 0.0
    with mp.workdps(120):
        for a, b in zip(ref["modes"], again["modes"]):
            assert _rel(a["gamma"], b["gamma"], mp.sqrt(ref["total"])) < 1e-20
        gmax = max(abs(md["gamma"]) for md in ref["modes"])
        bmax = max(abs(md["base"]) for md in ref["modes"])
        for rec, md in zip(data["modes"], ref["modes"]):
            errs = [_rel(rec["omega"], md["omega"], md["omega"]),
                    _rel(rec["participation_factor"], md["gamma"], gmax),
                    _rel(rec["effective_mass"], md["mstar"], gmax**2),
                    _rel(rec["base_shear"], md["base"], bmax)]
            for key, ref_key in (("spring_force", "force"), ("drift", "drift"), ("displacement", "x")):
                big = max(abs(v) for v in md[ref_key])
                errs += [_rel(g, w, big) for g, w in zip(rec[key], md[ref_key])]
            worst = max(worst, *errs)
        for how in ("srss", "cqc"):
            for key, ref_key in (("spring_force", "force"), ("drift", "drift"), ("displacement", "x")):
                want = ref["comb"][(how, ref_key)]
                big = max(abs(v) for v in want)
                worst = max(worst, *[_rel(g, w, big) for g, w in zip(data[how][key], want)])
            worst = max(worst, _rel(data[how]["base_shear"], ref["comb"][(how, "base")], 0))
    assert worst < tol, worst
    return worst


def test_four_masses_contrast_1e10(tmp_path):
    """Stiff and soft springs alternating (contrast 1e10): the stiff springs' forces are no longer
    k times a difference of nearly equal float64 components (was 1e-5 relative)."""
    check(tmp_path, rayleigh_chain_text([2.0, 2.0, 6.0, 2.0], [3e9, 0.3, 3e9, 0.3], 0.01, 1e-12))


log_value = st.floats(-5.0, 5.0).map(lambda e: float(10.0**e))


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(n=st.integers(2, 6), data=st.data())
def test_random_wall_chains(tmp_path, n, data):
    """Masses and stiffnesses over 1e-5 ... 1e5 (contrast up to 1e10), Rayleigh damping."""
    masses = data.draw(st.lists(log_value, min_size=n, max_size=n))
    springs = data.draw(st.lists(log_value, min_size=n, max_size=n))
    alpha = data.draw(st.floats(1e-3, 0.5))
    beta = data.draw(st.floats(0.0, 1e-3))
    check(tmp_path, rayleigh_chain_text(masses, springs, alpha, beta))


def test_long_chain_notes_float_route(tmp_path):
    """Past the mpmath limit the float route says which numbers are not certified; the storey shears
    of the wall-hung chain (inertia sums) and the base shear still match the reference."""
    from springchain.numeric.structural.modal_quantities import MP_MAX_MASSES

    n = MP_MAX_MASSES + 1
    rng = np.random.default_rng(7)
    text = rayleigh_chain_text([float(v) for v in 10 ** rng.uniform(0, 1, n)], [3e9 if i % 2 == 0 else 0.3 for i in range(n)],
                      0.05, 1e-12)  # contrast 1e10: k·(φ_b − φ_a) from float64 shapes was 4e-4 off in SRSS
    path = tmp_path / "long.toml"
    path.write_text(text)
    r = sc.rsa(sc.load(path), spectrum=SPECTRUM)
    assert any("not certified" in s for s in r.notes)
    data = r.to_json()
    ref = reference(text, 60)
    with mp.workdps(60):  # to the largest modal force and base shear (Γ of a high mode is float64-absolute)
        fmax = max(abs(v) for md in ref["modes"] for v in md["force"])
        bmax = max(abs(md["base"]) for md in ref["modes"])
        for rec, md in zip(data["modes"], ref["modes"]):
            assert max(float(abs(g - w) / fmax) for g, w in zip(rec["spring_force"], md["force"])) < 1e-12
            assert float(abs(rec["base_shear"] - md["base"]) / bmax) < 1e-12
        for how in ("srss", "cqc"):
            want = ref["comb"][(how, "force")]
            assert max(float(abs(g - w) / w) for g, w in zip(data[how]["spring_force"], want)) < 1e-10
            assert float(abs(data[how]["base_shear"] - ref["comb"][(how, "base")]) / ref["comb"][(how, "base")]) < 1e-10
