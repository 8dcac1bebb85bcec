"""UFF files (issue 37, item 4): FRFs as binary dataset 58 round trip exactly, modes as ASCII dataset 55
to the format's six printed digits; files read back by pyuff itself as its users read them; the
command-line flags; unreadable files refused in one line.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import one_line_error, run_cli

import springchain as sc

pyuff = pytest.importorskip("pyuff")


def test_frf_dataset_58_round_trip_is_exact(tmp_path):
    h = sc.frf("building", "floor1", "floor3")
    path = sc.write_frf_uff(h, tmp_path / "h.uff")
    raw = pyuff.UFF(str(path)).read_sets(0)  # as pyuff's users read it
    assert raw["type"] == 58 and raw["func_type"] == 4 and raw["binary"] == 1
    assert raw["rsp_node"] == 3 and raw["ref_node"] == 1
    assert np.array_equal(raw["x"], h.omega / (2 * math.pi)) and np.array_equal(raw["data"], h.H)
    frfs, modes = sc.read_uff(path)
    assert len(frfs) == 1 and not modes
    f = frfs[0]
    assert (f.ordinate, f.denominator) == ("displacement", "force") and np.array_equal(f.H, h.H)


def test_a_form_is_written_with_its_data_types(tmp_path):
    t = sc.frf_form("building", "accelerance", input="floor2", output="floor3")
    (f,), _ = sc.read_uff(sc.write_frf_uff(t, tmp_path / "a.uff"))
    assert (f.ordinate, f.denominator) == ("acceleration", "force") and np.array_equal(f.H, t.values)


def test_modes_dataset_55_round_trip_to_six_digits(tmp_path):
    """Frequencies [Hz] and mass-normalised shapes (φᵀMφ = 1, checked here against the scene's masses)
    come back to the 6 significant digits pyuff prints; the frequencies against the closed form of the
    building's fixed-free shear chain, ω_j = 2 √(k/m) sin((2j − 1)π/14)."""
    path, notes = sc.write_modes_uff("building", tmp_path / "m.uff")
    assert any("six significant digits" in n for n in notes)
    _, modes = sc.read_uff(path)
    p = sc.load("building").parameters
    m, k = p["m"], p["k"]
    assert [md.number for md in modes] == [1, 2, 3]
    for j, md in enumerate(modes, start=1):
        f = 2 * math.sqrt(k / m) * math.sin((2 * j - 1) * math.pi / 14) / (2 * math.pi)
        assert abs(md.frequency / f - 1) < 5e-6
        phi = md.shape[:, 0]
        assert abs(m * float(phi @ phi) - 1) < 2e-5 and np.all(md.shape[:, 1:] == 0)
        assert list(md.nodes) == [1, 2, 3]


def test_cli_flags_write_uff_and_bad_files_are_one_line(tmp_path, capsys):
    status, out, err = run_cli(["frf", "building", "--input", "floor1", "--output", "floor3", "--uff",
                                tmp_path / "c.uff", "--out", tmp_path], capsys)
    assert status == 0 and "dataset 58, binary" in out
    status, out, err = run_cli(["modes", "building", "--uff", tmp_path / "m.uff"], capsys)
    assert status == 0 and "dataset 55" in err
    frfs, modes = sc.read_uff(tmp_path / "c.uff")
    assert len(frfs) == 1 and len(sc.read_uff(tmp_path / "m.uff")[1]) == 3
    (tmp_path / "junk.uff").write_text("    -1\n    58\nnot a dataset\n")
    with pytest.raises(sc.RunRefused, match="junk.uff") as info:
        sc.read_uff(tmp_path / "junk.uff")
    assert "\n" not in str(info.value)
    with pytest.raises(sc.RunRefused, match="not a readable file"):
        sc.read_uff(tmp_path / "missing.uff")


def test_without_pyuff_the_flag_says_what_to_install(monkeypatch, capsys, tmp_path):
    import sys

    monkeypatch.setitem(sys.modules, "pyuff", None)
    one_line_error(*run_cli(["frf", "building", "--input", "floor1", "--output", "floor3", "--uff",
                             tmp_path / "x.uff", "--out", tmp_path], capsys), 'pip install "springchain[uff]"')
