"""FRF forms (issue 37, item 3): mobility, accelerance, dynamic stiffness and the transmissibilities of a
moving base against (K − ω²M + iωC) solved in mpmath from the elements written here; Hz, dB, units
and labels; the CLI's flags and refusals.
"""

from __future__ import annotations

import json
import math

import mpmath
import numpy as np
import pytest
from helpers import one_line_error, run_cli

import springchain as sc

# the bundled building: floors m, storey springs k, a base dashpot c (read from the scene, SI)
P = sc.load("building").parameters
M, K, C = P["m"], P["k"], P["c"]


def _mp_solve(w: float, rhs):
    """X of (K − ω²M + iωC) X = rhs for the building, in mpmath at 40 digits."""
    mpmath.mp.dps = 40
    w = mpmath.mpf(w)
    Z = mpmath.matrix(3, 3)
    for i in range(3):
        Z[i, i] = -w * w * M
    for a, b in ((-1, 0), (0, 1), (1, 2)):
        for p, sp in ((a, 1), (b, -1)):
            for q, sq in ((a, 1), (b, -1)):
                if p >= 0 and q >= 0:
                    Z[p, q] += sp * sq * K
    Z[0, 0] += 1j * w * C
    return mpmath.lu_solve(Z, mpmath.matrix(rhs))


@pytest.mark.parametrize("form, of", [
    ("receptance", lambda w, x: x), ("mobility", lambda w, x: 1j * w * x),
    ("accelerance", lambda w, x: -w * w * x), ("dynamic-stiffness", lambda w, x: 1 / x)])
def test_force_forms_against_mpmath(form, of):
    r = sc.frf_form("building", form, input="floor1", output="floor3")
    assert r.unit == {"receptance": "m/N", "mobility": "(m/s)/N", "accelerance": "(m/s^2)/N",
                      "dynamic-stiffness": "N/m"}[form]
    for j in range(0, r.omega.shape[0], 23):
        w = float(r.omega[j])
        ref = complex(of(mpmath.mpf(w), _mp_solve(w, [1, 0, 0])[2]))
        assert abs(r.values[j] - ref) <= 1e-12 * abs(ref), (w, r.values[j], ref)


def test_transmissibilities_against_mpmath_and_each_other():
    """Absolute: X_abs = Z⁻¹ (K1 + iωC1) X_g with K1 = (k, 0, 0), C1 = (c, 0, 0); relative:
    Z_rel = Z⁻¹ (−M 1) Ẍ_g = ω² Z⁻¹ M 1 X_g. Each to 1e-12 relative where it is 1e-5 small as well."""
    t = sc.frf_form("building", "transmissibility", output="floor3")
    r = sc.frf_form("building", "relative-transmissibility", input="ground", output="floor3")
    assert np.array_equal(t.omega, r.omega) and t.unit == "1"
    assert np.max(np.abs(t.values - r.values - 1)) < 1e-12
    for j in list(range(0, t.omega.shape[0], 29)) + [t.omega.shape[0] - 1]:
        w = float(t.omega[j])
        W = mpmath.mpf(w)
        absolute = complex(_mp_solve(w, [K + 1j * W * C, 0, 0])[2])
        relative = complex(W * W * _mp_solve(w, [M, M, M])[2])
        assert abs(t.values[j] - absolute) <= 1e-12 * abs(absolute)
        assert abs(r.values[j] - relative) <= 1e-12 * abs(relative)
    assert abs(t.values[-1]) < 1e-4 and abs(r.values[0]) < 2e-2  # the small ends are resolved, not cancelled


def test_hz_db_units_and_labels():
    pytest.importorskip("pint")
    from springchain.derive.units.output import OutputUnits

    r = sc.frf_form("building", "accelerance", input="floor3", output="floor3", hz=True, db=True)
    assert np.allclose(r.frequency, r.omega / (2 * math.pi), rtol=1e-15)
    assert np.allclose(r.magnitude(), 20 * np.log10(r.omega**2 * np.abs(sc.frf("building", "floor3", "floor3").H)),
                       rtol=1e-12, atol=1e-12)
    assert r.magnitude_label() == "accelerance A_out / F_in [dB re 1 (m/s^2)/N]"
    u = OutputUnits.parse("mm, kN")
    assert r.magnitude_label(u) == "accelerance A_out / F_in [dB re 1 (mm/s^2)/kN]"
    # (mm/s²)/kN is 1e6 (m/s²)/N: +120 dB
    assert np.allclose(r.magnitude(u) - r.magnitude(), 120.0, atol=1e-9)
    data = r.to_json(u)
    assert data["units"] == {"frequency": "Hz", "magnitude": "dB re 1 (mm/s^2)/kN", "phase": "deg"}


def test_frf_cli_forms_and_refusals(tmp_path, capsys):
    status, out, err = run_cli(["frf", "building", "--input", "ground", "--output", "floor3", "--form",
                                "transmissibility", "--hz", "--json", "--out", tmp_path], capsys)
    assert status == 0, err
    data = json.loads(out)
    assert data["form"] == "transmissibility" and data["units"]["frequency"] == "Hz"
    assert (tmp_path / "building-frf-transmissibility-ground-floor3.png").is_file()
    one_line_error(*run_cli(["frf", "building", "--input", "floor1", "--output", "floor3", "--form", "bogus"],
                            capsys), "--form", "accepted: receptance, mobility")
    one_line_error(*run_cli(["frf", "building", "--input", "floor1", "--output", "floor3", "--form",
                             "transmissibility"], capsys), "driven by the base")
    one_line_error(*run_cli(["frf", "building", "--input", "ground", "--output", "floor3", "--form", "mobility"],
                            capsys), "driven by a force")
    # without any new flag the receptance output is exactly as before
    status, out, _ = run_cli(["frf", "building", "--input", "floor1", "--output", "floor3", "--json", "--out",
                              tmp_path], capsys)
    assert set(json.loads(out)) == {"scene", "input", "output", "omega", "magnitude", "phase", "units", "resonances",
                                    "connected", "other_peaks", "transfer_function", "notes"}


def test_units_as_the_command_line_writes_them():
    """``units="mm,kN"`` (the --units text) works in every method: a mobility (m/s)/N shown in (mm/s)/kN is
    1e-3/1e3 = 1e-6 of the SI unit per unit, so the numbers are 1e6 larger (mm = 1e-3 m, kN = 1e3 N written
    here); a list of texts is the same; a bad text is one line naming units and what is accepted."""
    pytest.importorskip("pint")
    from springchain.derive.errors import SceneError

    r = sc.frf_form("building", "mobility", input="floor1", output="floor3")
    si = r.magnitude()
    assert np.allclose(r.magnitude("mm,kN"), si * 1e6, rtol=1e-13, atol=0)
    assert np.allclose(r.magnitude(["mm", "kN"]), si * 1e6, rtol=1e-13, atol=0)
    assert r.magnitude_label("mm, kN") == "|mobility V_out / F_in| [(mm/s)/kN]"
    assert r.to_json("mm,kN")["units"]["magnitude"] == "(mm/s)/kN"
    assert "[(mm/s)/kN]" in r.to_text("mm,kN")
    assert r.plot("mm,kN").axes[0].get_ylabel() == "|mobility V_out / F_in| [(mm/s)/kN]"
    assert np.array_equal(r.magnitude(""), si) and np.array_equal(r.magnitude(None), si)
    for bad, words in (("mm,zorks", "unknown unit"), ("Hz", "frequency"), ("mm,cm", "two units"),
                       (3.0, "accepted: a text such as 'mm,kN,g'")):
        with pytest.raises(SceneError) as exc:
            r.magnitude(bad)
        text = str(exc.value)
        assert "units" in text and words in text and "\n" not in text, text


def test_frf_says_what_its_largest_magnitude_is_and_describes_the_forms(capsys):
    """The text's largest magnitude is the grid's, said so; equal to the largest |iω H| on the grid."""
    r = sc.frf_form("building", "mobility", input="floor1", output="floor3")
    line = next(x for x in r.to_text().splitlines() if x.startswith("largest magnitude"))
    assert "on the grid (not an exact peak" in line
    assert float(line.split("): ")[1].split(" at ")[0]) == pytest.approx(np.max(np.abs(r.values)), rel=1e-5)
    status, out, _ = run_cli(["frf", "--help"], capsys)
    assert status == 0 and all(w in out for w in ("mobility", "accelerance", "dynamic stiffness", "transmissibility"))
