"""Scenes with many explicit masses: matrices are assembled from the spring list, never printed N×N."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest
import sympy

from springchain.derive.codegen import MAX_PRINTED_MATRIX
from springchain._modules import derive
from springchain.derive.scene import load_scene


def scene_text(n: int, gravity: bool) -> str:
    lines = [f'name = "c{n}"', "[parameters]", "m = 1.5", "k = 2.0", "g = 9.8", "[masses]"]
    lines += [f'm{i} = "m*{1 + i % 3}"' for i in range(n)]
    lines += ["[[springs]]", 'between = ["wall", "m0"]', 'k = "k"']
    for i in range(n - 1):
        lines += ["[[springs]]", f'between = ["m{i}", "m{i + 1}"]', f'k = "k*{1 + i % 2}"']
    lines += ["[[springs]]", f'between = ["m0", "m{n - 1}"]', 'k = "k/2"']  # a long-range spring
    if gravity:
        lines += ["[gravity]", 'g = "g"']
    lines += ["[initial]", f"x = {[0.0] * n}", f"v = {[0.0] * n}"]
    return "\n".join(lines) + "\n"


def load(source: str, name: str, tmp_path):
    path = tmp_path / f"{name}.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("gravity", [False, True])
def test_large_scene_assembles_matrices_and_binds_acceleration(tmp_path, gravity):
    n = 3 * MAX_PRINTED_MATRIX
    d = derive(load_scene("c.toml", text=scene_text(n, gravity)), budget=1.0)
    module = load(d.source, f"c{n}{int(gravity)}", tmp_path)
    p = dict(module.DEFAULTS)
    values = {d.model.params[k]: v for k, v in p.items()}
    K_ref = np.array(d.model.K.subs(values).evalf().tolist(), dtype=float)
    np.testing.assert_allclose(module.stiffness_matrix(**p), K_ref, rtol=1e-14, atol=0)
    x = np.random.default_rng(3).standard_normal((n, 5))
    a = module.acceleration(x, **p)
    np.testing.assert_allclose(module.make_acceleration(**p)(x), a, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(module.make_acceleration(**p)(x[:, 0]), a[:, 0], rtol=1e-12, atol=1e-12)
    g = np.asarray(module.gravity_forces(**p)) / module.masses(**p) if gravity else 0.0
    np.testing.assert_allclose(a, -(K_ref @ x) / module.masses(**p)[:, None] + np.reshape(g, (-1, 1)) * (1 if gravity else 0),
                               rtol=1e-12, atol=1e-12)


def test_source_grows_linearly_not_quadratically():
    small = derive(load_scene("c.toml", text=scene_text(20, False)), budget=1.0).source
    large = derive(load_scene("c.toml", text=scene_text(80, False)), budget=1.0).source
    # four times the masses: the text may grow about four times, never sixteen
    assert len(large) < 6 * len(small)
