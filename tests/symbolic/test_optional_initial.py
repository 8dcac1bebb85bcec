"""``[initial]`` is optional: a scene written only to read its modes needs none.

Without it the scene starts at rest; ``modes`` and ``derive`` never ask for it, and the commands
that run (``simulate``, ``plan``, ``bench``) refuse in one line only when nothing would move
(no ``[initial]`` and no load), naming the missing table.
"""

from __future__ import annotations

import numpy as np
import pytest

import springchain as sc
from springchain.cli import main

HEAD = """name = "plain"
[parameters]
K = 3.0
w = 2.0
[masses]
a = "w"
x = "2*w"
[[springs]]
between = ["wall", "a"]
k = "K"
[[springs]]
between = ["a", "x"]
k = "K"
"""


pytestmark = pytest.mark.usefixtures("fresh_cache")


def test_modes_without_initial(tmp_path, capsys):
    path = tmp_path / "plain.toml"
    path.write_text(HEAD)
    scene = sc.load(path)
    assert not scene.initial_given
    np.testing.assert_array_equal(scene.x0, 0.0)
    np.testing.assert_array_equal(scene.v0, 0.0)
    # K = [[2K, -K], [-K, K]], M = diag(w, 2w): omega^2 = K/(4w) * (5 -+ sqrt(17))
    want = sorted(3.0 / 8.0 * (5 + s * np.sqrt(17.0)) for s in (-1, 1))
    np.testing.assert_allclose(sc.modes(scene).omega2_values, want, rtol=1e-14)
    assert main(["modes", str(path), "--json"]) == 0
    capsys.readouterr()


@pytest.mark.parametrize("argv", [["simulate"], ["plan", "--tol", "1e-6"]])
def test_run_from_rest_with_nothing_driving_is_refused(tmp_path, capsys, argv):
    path = tmp_path / "plain.toml"
    path.write_text(HEAD)
    status = main([argv[0], str(path), *argv[1:], "--out", str(tmp_path / "o")] if argv[0] == "simulate"
                  else [argv[0], str(path), *argv[1:]])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1, err
    assert "initial: missing" in err[0] and "[initial]" in err[0] and "plain.toml" in err[0], err
    with pytest.raises(sc.RunRefused, match="initial: missing"):
        sc.simulate(path)


def test_partial_initial_defaults_to_zero(tmp_path):
    path = tmp_path / "plain.toml"
    path.write_text(HEAD + "[initial]\nx = [0.1, 0.0]\n")
    scene = sc.load(path)
    np.testing.assert_array_equal(scene.v0, 0.0)
    run = sc.simulate(scene, methods=["modal"], steps=20)
    assert abs(run.x["modal"][0, 0] - 0.1) < 1e-15
    assert np.all(np.isfinite(run.x["modal"]))


def test_loaded_scene_starts_at_rest(tmp_path):
    path = tmp_path / "plain.toml"
    path.write_text(HEAD + '[[forces]]\non = "x"\nf = "sin(t)"\n')
    run = sc.simulate(path, methods=["modal", "verlet"], dt=0.01, steps=200)
    x = run.x["modal"]
    np.testing.assert_array_equal(x[0], 0.0)
    assert np.abs(x[-1]).max() > 1e-3  # the force moved it
    assert np.abs(run.x["verlet"] - x).max() < 1e-3
