"""``springchain animate`` / ``springchain.animate``: GIFs open with PIL, with the frames drawn."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from helpers import one_line_error, run_cli
import springchain as sc
from springchain.cli import main


def _gif(path):
    im = Image.open(path)
    assert im.format == "GIF"
    return im.n_frames, im.size


def test_mode_gif(tmp_path):
    a = sc.animate("seed", mode=2, out=tmp_path, frames=7, fps=10)
    assert a.path == tmp_path / "seed-mode2.gif"
    assert _gif(a.path) == (7, (512, 208))
    assert a.omega == pytest.approx(np.sqrt(5 / 3), rel=1e-14)  # k = m = 1


def test_rigid_mode_and_default(tmp_path):
    a = sc.animate("seed", mode=0, out=tmp_path, frames=4)
    assert a.omega == 0.0 and _gif(a.path)[0] == 4
    b = sc.animate("seed", out=tmp_path, frames=4)  # default: the lowest elastic mode
    assert b.what == "mode 1" and b.omega == pytest.approx(1.0, rel=1e-14)


def test_method_gif(tmp_path):
    a = sc.animate("building", method="verlet", out=tmp_path, frames=6)
    assert a.path.name == "building-verlet.gif"
    assert _gif(a.path) == (6, (512, 208))


@pytest.mark.parametrize("kwargs", [{"mode": 3}, {"method": "rk4"}])
def test_chain_gif(tmp_path, make_chain_toml, kwargs):
    path = tmp_path / "ch.toml"
    path.write_text('name = "ch"\n[parameters]\nm = 1.0\nk = 1.0\n[chain]\nn = 3000\nmass = "m*(1 + i % 2)"\n'
                    'k = "k"\nleft = "wall"\nright = "free"\n[initial]\nx = "0.01*sin(pi*(i + 1)/(n + 1))"\n'
                    'v = "0"\n[simulation]\ndt = 0.5\nsteps = 40\n')
    a = sc.animate(path, out=tmp_path / "o", frames=5, **kwargs)
    assert _gif(a.path) == (5, (512, 240))
    assert not [p for p in (tmp_path / "o").iterdir() if p.name.startswith(".")]  # no temporary left


def test_chain_mode_shape_against_closed_form():
    from springchain._modules import system_of as _system
    from springchain.numeric.plots.animation import decimate, mode_shape

    system, _ = _system(sc.load("chain100k"))
    n = system.n
    omega, shape, rigid = mode_shape(system, 3)
    i = np.arange(n)
    ref = np.cos(3 * np.pi * (i + 0.5) / n)  # free-free uniform chain
    ref /= ref[np.argmax(np.abs(ref))]
    assert not rigid and np.max(np.abs(shape - ref)) < 1e-6
    assert omega == pytest.approx(2 * np.sin(3 * np.pi / (2 * n)), rel=1e-12)
    idx = decimate(n)
    assert idx.shape[0] == 1000 and idx[0] == 0 and idx[-1] == n - 1


@pytest.mark.parametrize("argv,needle", [
    (["animate", "seed", "--mode", "3"], "--mode: mode 3: accepted: a mode number 0 ... 2"),
    (["animate", "seed", "--method", "nope"], "--method: method 'nope' is unknown"),
    (["animate", "seed", "--mode", "-1"], "--mode"),
    (["animate", "seed", "--frames", "1"], "--frames"),
    (["animate", "seed", "--mode", "1", "--method", "verlet"], "not allowed with"),
])
def test_errors_one_line(tmp_path, capsys, argv, needle):
    one_line_error(*run_cli(argv + ["--out", tmp_path], capsys), needle)
    assert not any(tmp_path.iterdir())


def test_cli_writes_gif_and_keeps_backend(tmp_path, capsys):
    import matplotlib

    before = matplotlib.get_backend()
    assert main(["animate", "ring4", "--mode", "1", "--frames", "3", "--fps", "5", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "wrote" in out and _gif(tmp_path / "ring4-mode1.gif")[0] == 3
    assert matplotlib.get_backend() == before
