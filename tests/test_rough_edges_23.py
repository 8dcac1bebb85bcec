"""The rough edges a new user hit in issue 23: each one a test that failed before its fix."""

from __future__ import annotations

import json
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

import springchain as sc
from springchain.cli import main

ROOT = Path(__file__).resolve().parent.parent


def _strict_json(text: str):
    def refuse(name):
        raise ValueError(f"not JSON: {name}")

    return json.loads(text, parse_constant=refuse)


@pytest.fixture()
def capture_figures(monkeypatch):
    """Figures handed to ``plots.save`` (labels can be read; nothing is drawn to disk)."""
    from springchain.numeric.plots import figures as plots

    figures = {}
    monkeypatch.setattr(plots, "save", lambda fig, path: figures.__setitem__(Path(path).name, fig))
    return figures


# -- derive --check checks the folder derive writes ------------------------------------------------
def test_derive_check_reads_where_derive_writes(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    text = (ROOT / "scenes" / "seed.toml").read_text().replace('name = "seed"', 'name = "my"')
    Path("my.toml").write_text(text)
    assert main(["derive", "--check", "my.toml"]) == 1  # nothing written yet
    assert "generated/my.py: missing (run `springchain derive my.toml`)" in capsys.readouterr().out
    assert main(["derive", "my.toml"]) == 0  # following the advice ...
    capsys.readouterr()
    assert main(["derive", "--check", "my.toml"]) == 0  # ... helps
    assert "fresh" in capsys.readouterr().out
    assert Path("generated/my.py").exists()
    Path("generated/my.py").write_text(Path("generated/my.py").read_text().replace("5/3", "5/4"))
    assert main(["derive", "--check", "my.toml"]) == 1
    assert "stale" in capsys.readouterr().out
    assert main(["derive", "my.toml", "--out", "elsewhere"]) == 0
    capsys.readouterr()
    assert main(["derive", "--check", "my.toml", "--out", "elsewhere"]) == 0
    assert main(["derive", "--check", "my.toml", "--out", "nowhere"]) == 1
    assert "run `springchain derive my.toml --out nowhere`" in capsys.readouterr().out


# -- generated text independent of where springchain is installed ----------------------------------
@pytest.mark.parametrize("name", ["seed", "building_quake"])
def test_generated_text_is_independent_of_install_location(tmp_path, monkeypatch, name):
    from springchain._modules import derive

    clone = tmp_path / "clone" / "scenes"  # a clone whose scenes/ is not the installed package's
    clone.mkdir(parents=True)
    for p in (ROOT / "scenes").glob(f"{name}*"):
        shutil.copy(p, clone / p.name)
    shutil.copy(ROOT / "scenes" / "quake-record.csv", clone / "quake-record.csv")
    want = (ROOT / "generated" / f"{name}.py").read_text(encoding="utf-8")
    for cwd in (tmp_path, clone, tmp_path / "clone"):
        monkeypatch.chdir(cwd)
        scene = sc.load(clone / f"{name}.toml")
        assert derive(scene).source == want
    # relative paths as a user types them in the clone's root
    monkeypatch.chdir(tmp_path / "clone")
    assert derive(sc.load(f"scenes/{name}.toml")).source == want


# -- the energy figure says what it plots -------------------------------------------------------------
def test_energy_figure_of_a_forced_damped_run_from_rest_plots_E_and_the_work(tmp_path, capture_figures):
    run = sc.simulate("building", steps=400, out=tmp_path, figures=True, progress=False)
    assert float(np.abs(run.x["modal"][0]).max()) == 0.0  # starts at rest: E(0) = 0
    ax = capture_figures["building-energy.png"].axes[0]
    assert "error" not in ax.get_title().lower() and "work of forces and damping" in ax.get_title()
    assert ax.get_ylabel() == "energy E(t) = T + V [J]"
    labels = [line.get_label() for line in ax.get_lines()]
    assert "E(t), modal" in labels and any(lbl.startswith("E(0) + W(t)") for lbl in labels)
    e = {line.get_label(): line.get_ydata() for line in ax.get_lines()}
    w = next(v for k, v in e.items() if k.startswith("E(0) + W(t)"))
    # the energy balance holds (trapezoid work vs the exact solution's energy)
    assert np.max(np.abs(e["E(t), modal"] - w)) < 1e-3 * np.max(np.abs(e["E(t), modal"]))


def test_energy_figure_of_a_conservative_run_is_the_relative_error(tmp_path, capture_figures):
    sc.simulate("seed", steps=50, out=tmp_path, figures=True, progress=False)
    ax = capture_figures["seed-energy.png"].axes[0]
    assert ax.get_ylabel() == "(E(t) − E(0)) / |E(0)|" and "Energy error" in ax.get_title()


# -- no warnings from figures ---------------------------------------------------------------------------
def test_figures_raise_no_warnings(tmp_path, capture_figures):
    text = 'name = "c6"\n[parameters]\nm = 1.0\nk = 1.0\n[chain]\nn = 6\nmass = "m"\nk = "k"\n[initial]\nx = "0.01*i"\n'
    (tmp_path / "c6.toml").write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        crun = sc.simulate(tmp_path / "c6.toml", out=tmp_path / "o", figures=True, progress=False)
        crun.plot(), crun.plot("v")
        sc.simulate("building_quake", steps=100, out=tmp_path / "q", figures=True, progress=False).plot()
        sc.frf("ring4", "m1", "m2", points=50, transfer=False).plot()
    assert capture_figures


# -- strict JSON and no empty panel -------------------------------------------------------------------
def test_sweep_of_a_ring_writes_strict_json_and_no_empty_panel(tmp_path, capture_figures):
    text = ('name = "ring"\n[parameters]\nm = 1.0\nk = 1.0\n[chain]\nn = 12\nmass = "m"\nk = "k"\n'
            'left = "ring"\nright = "ring"\n')
    (tmp_path / "ring.toml").write_text(text)
    r = sc.sweep(tmp_path / "ring.toml", disorder=["mass=uniform(0.5, 1.5)"], samples=4, workers=1,
                 out=tmp_path / "s", progress=False)
    raw = (tmp_path / "s" / "summary.json").read_text()
    data = _strict_json(raw)
    assert "NaN" not in raw and data["inverse_localisation_length"]["mean"][3] is None
    assert "not computed for rings" in data["inverse_localisation_length"]["note"]
    fig = capture_figures["localisation.png"]
    assert len(fig.axes) == 1 and "not computed for rings" in fig.axes[0].get_title()
    assert r.rows == 4


def test_every_json_output_is_strict(tmp_path, capsys):
    text = ('name = "dc"\n[parameters]\nm = 1.0\nk = 1.0\nc = 0.05\n[chain]\nn = 500\nmass = "m"\nk = "k"\n'
            '[[dampers]]\nbetween = ["i", "wall"]\nc = "c"\n')
    (tmp_path / "dc.toml").write_text(text)
    assert main(["frf", str(tmp_path / "dc.toml"), "--input", "0", "--output", "3", "--points", "40",
                 "--json", "--out", str(tmp_path)]) == 0
    data = _strict_json(capsys.readouterr().out)
    assert any(r["zeta"] is None for r in data["resonances"])  # ζ not computed on a damped chain: null
    from springchain.numeric.io.strict_json import dumps

    assert dumps({"a": float("nan"), "b": [np.float64(np.inf), np.int64(3)]}) == '{"a": null, "b": [null, 3]}'


# -- pieces drawn as they are connected ------------------------------------------------------------------
def test_animation_layout_draws_each_piece_apart():
    from springchain.numeric.plots.animation import layout

    # masses 0-1 joined, 2-3 joined with a wall at mass 2, mass 4 alone between two walls, mass 5 free;
    # a wall spring in the middle of piece 6-7-8 (mass 7)
    ends = np.array([[0, 1], [2, 3], [-1, 2], [4, -1], [-1, 4], [6, 7], [7, 8], [7, -1]])
    rest, walls = layout(9, ends)
    pieces = [[0, 1], [2, 3], [4], [5], [6, 7, 8]]
    spans = [(rest[p].min(), rest[p].max()) for p in pieces]
    for (a0, a1), (b0, b1) in zip(spans, spans[1:]):
        assert a1 < b0  # pieces in order, apart
    for j, m, side, x in walls:  # no wall spring passes over a mass
        lo, hi = sorted((x, rest[m]))
        others = [r for i, r in enumerate(rest) if i != m]
        assert side == "below" or not any(lo < r < hi for r in others), (j, m, side, x)
        if side == "left":
            assert x < rest[m]
    for a, b in ends[ends.min(axis=1) >= 0]:  # every mass-to-mass spring stays inside its piece's stretch
        lo, hi = sorted((rest[a], rest[b]))
        piece = next(p for p in pieces if a in p)
        assert all(lo <= rest[i] <= hi for i in range(9) if lo < rest[i] < hi) and all(
            i in piece for i in range(9) if lo < rest[i] < hi)
    assert [side for _, m, side, _ in walls if m == 7] == ["below"]


def test_animation_of_two_pieces_writes(tmp_path):
    text = ('name = "two"\n[parameters]\nm = 1.0\nk = 1.0\n[masses]\na = "m"\nb = "m"\nc = "m"\nd = "m"\n'
            '[[springs]]\nbetween = ["a", "b"]\nk = "k"\n[[springs]]\nbetween = ["wall", "c"]\nk = "k"\n'
            '[[springs]]\nbetween = ["c", "d"]\nk = "k"\n')
    (tmp_path / "two.toml").write_text(text)
    a = sc.animate(tmp_path / "two.toml", mode=3, frames=3, out=tmp_path)
    assert a.path.exists() and a.frames == 3


# -- chain profiles readable for narrow features ----------------------------------------------------------
def test_narrow_pulse_on_a_long_chain_keeps_its_height_and_gets_a_zoom():
    from matplotlib.collections import PolyCollection

    from springchain.numeric.plots import figures as plots
    from springchain.numeric.plots.animation import profile_envelopes

    n = 200_000
    i = np.arange(n)
    pulse = np.exp(-(((i - 123_457) / 15.0) ** 2))  # about 40 masses wide
    fig = plots.profiles({0.0: pulse, 1.0: 0.5 * pulse})
    assert len(fig.axes) == 2
    top, zoom = fig.axes
    heights = [float(np.max(c.get_paths()[0].vertices[:, 1])) for c in top.collections if isinstance(c, PolyCollection)]
    assert max(heights) == pytest.approx(1.0, abs=1e-3)  # a decimated line (every 200th mass) shows < 0.2 here
    lo, hi = zoom.get_xlim()
    assert lo <= 123_457 - 30 and hi >= 123_457 + 30 and hi - lo < 1000
    (line, _) = zoom.get_lines()
    assert np.all(np.diff(line.get_xdata()) == 1)  # every mass in the window
    centre, low, high = profile_envelopes([pulse, -pulse])
    assert centre.shape == (1000,) and high[0].max() == pulse.max() and low[1].min() == -pulse.max()
    decimated = pulse[np.linspace(0, n - 1, 1000).round().astype(int)]
    assert decimated.max() < 0.5  # what the old drawing showed


# -- text modes: frequencies for every form, i % 2 as written ------------------------------------------------
CHAINS = {
    "open": 'name = "alt"\n[parameters]\nm = 1.0\nk = 1.0\n[chain]\nn = 8\nmass = "m*(1 + i % 2)"\nk = "k"\n'
            'left = "wall"\nright = "free"\n',
    "ring": 'name = "altring"\n[parameters]\nm = 1.0\nk = 1.0\n[chain]\nn = 8\nmass = "m*(1 + i % 2)"\nk = "k"\n'
            'left = "ring"\nright = "ring"\n',
    "long": 'name = "altlong"\n[parameters]\nm = 1.0\nk = 1.0\n[chain]\nn = 60\nmass = "m*(1 + 2*(i % 3))"\nk = "k"\n',
    "uniform": 'name = "uni"\n[parameters]\nm = 1.0\nk = 1.0\n[chain]\nn = 8\nmass = "m"\nk = "k"\n',
}


@pytest.mark.parametrize("form", sorted(CHAINS))
def test_text_modes_print_frequencies_for_every_chain_form(tmp_path, capsys, form):
    path = tmp_path / f"{form}.toml"
    path.write_text(CHAINS[form])
    assert main(["modes", str(path)]) == 0
    text = capsys.readouterr().out
    assert main(["modes", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    listed = [f"ω² = {r['omega2_value']:.10g}" for r in data["modes"]]
    assert listed and all(item in text for item in listed)
    assert "Mod(" not in text
    if form != "uniform":
        assert "i % 2" in text or "i % 3" in text
        assert data["family"]["omega2"] is None
        assert "the family" not in " ".join(data["notes"]) and "the family" not in text


def test_dense_scene_text_prints_percent_as_written(tmp_path, capsys):
    text = ('name = "pm"\n[parameters]\nm = 1.0\nk = 1.0\n[masses]\na = "m*(1 + 7 % 3)"\nb = "m"\n'
            '[[springs]]\nbetween = ["a", "b"]\nk = "k"\n')
    (tmp_path / "pm.toml").write_text(text)
    assert main(["modes", str(tmp_path / "pm.toml")]) == 0
    assert "Mod(" not in capsys.readouterr().out


# -- messages without enum reprs ---------------------------------------------------------------------------
def test_chain_end_error_shows_the_word_not_the_enum(tmp_path, capsys):
    (tmp_path / "bad.toml").write_text('name = "bad"\n[parameters]\nm = 1.0\nk = 1.0\n[chain]\nn = 8\nmass = "m"\n'
                                       'k = "k"\nleft = "ring"\nright = "free"\n')
    assert main(["modes", str(tmp_path / "bad.toml")]) == 2
    err = capsys.readouterr().err
    assert "<End." not in err and "chain.right: 'free': a ring closes both ends" in err
    from springchain.derive.errors import show
    from springchain.generated.contract import End

    assert show(End.WALL) == "'wall'"


# -- LaTeX: multi-letter names upright, matrices bold --------------------------------------------------------
def test_latex_sets_words_upright_and_matrices_apart_from_a_parameter_K(tmp_path):
    text = ('name = "names"\n[parameters]\nsum = 1.0\nK = 2.0\nkappa = 3.0\n[masses]\nfloor1 = "sum"\nm2 = "sum"\n'
            '[[springs]]\nbetween = ["floor1", "m2"]\nk = "K"\n[[springs]]\nbetween = ["m2", "wall"]\nk = "kappa"\n')
    (tmp_path / "names.toml").write_text(text)
    m = sc.modes(tmp_path / "names.toml")
    tex = m.to_latex()
    assert r"\mathrm{sum}" in tex and r"\kappa" in tex and "s u m" not in tex
    assert r"x_{\mathrm{floor}1}" in tex or r"v_{\mathrm{floor}1}" in tex
    assert r"\mathbf{K} &=" in tex and r"\mathbf{M} &=" in tex
    assert r"K &=" not in tex.replace(r"\mathbf{K} &=", "")
    words = m.to_text()
    assert "𝐊 = d²V/dx² (stiffness matrix) =" in words and "𝐌 x'' + 𝐊 x = 0" in words
    assert "\n    K*a_" not in words  # the parameter K prints as K, the matrix as 𝐊


# -- user-facing bench shows the table, not the project's targets ---------------------------------------------
def test_bench_prints_no_project_targets(tmp_path, capsys):
    assert main(["bench", "seed", "--quick", "--method", "verlet", "--t-end", "5", "--no-progress",
                 "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "| method | setting | error |" in out and "Cheapest run per accuracy" in out
    assert "required" not in out and "| NO |" not in out and "met" not in out.split("## Cheapest")[1]
    md = next(tmp_path.glob("bench-seed.md")).read_text()
    assert "required" not in md
    from springchain.numeric.bench.workprecision import markdown_table

    result = sc.bench("seed", 5.0, quick=True, methods=["verlet"])
    assert "required" in markdown_table(result, targets=True) and "required" not in markdown_table(result)


# -- plan refusals give the true reason ----------------------------------------------------------------------
def test_plan_on_a_forced_cubic_scene_says_why(tmp_path, capsys):
    text = ('name = "cf"\n[parameters]\nm = 1.0\nk = 1.0\nkappa = 0.5\nF0 = 0.1\nOmega = 0.7\n[masses]\np = "m"\n'
            'q = "m"\n[[springs]]\nbetween = ["wall", "p"]\nk = "k"\nk3 = "kappa"\n[[springs]]\nbetween = ["p", "q"]\n'
            'k = "k"\n[[forces]]\non = "q"\nf = "F0*cos(Omega*t)"\n[simulation]\ndt = 0.05\nsteps = 100\n')
    (tmp_path / "cf.toml").write_text(text)
    assert main(["plan", str(tmp_path / "cf.toml"), "--tol", "1e-6"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "forces put it outside the closed-form error models" in err[0] and "cubic springs" in err[0]
    assert "this scene has none (cubic springs)" not in err[0]


# -- the participation ratio's convention is written down --------------------------------------------------------
def test_participation_ratio_convention_is_documented(tmp_path):
    text = 'name = "c20"\n[parameters]\nm = 1.0\nk = 1.0\n[chain]\nn = 20\nmass = "m"\nk = "k"\n'
    (tmp_path / "c20.toml").write_text(text)
    r = sc.sweep(tmp_path / "c20.toml", disorder=["mass=uniform(0.9, 1.1)"], samples=2, workers=1,
                 out=tmp_path / "s", progress=False)
    conv = r.summary["participation_ratio"]["convention"]
    assert "1 / (N * sum_i psi_i^4)" in conv and "divided by N" in conv
    pr = np.asarray(r.summary["participation_ratio"]["mean"])
    assert np.all((pr > 1 / 20) & (pr <= 1.0))  # normalised: 1/N ... 1
    guide = (ROOT / "docs" / "guide" / "sweeps.md").read_text(encoding="utf-8")  # the user guide's sweep chapter
    assert "1/(N Σψ⁴)" in guide
