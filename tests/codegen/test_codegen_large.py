"""Scenes with many explicit masses: matrices are assembled from the spring list, never printed N×N."""

from __future__ import annotations

import importlib.util
import re

import numpy as np
import pytest
import sympy

from helpers import scene_toml
from springchain.derive.codegen import MAX_PRINTED_MATRIX
from springchain._modules import derive
from springchain.derive.scene import load_scene


def many_masses_text(n: int, gravity: bool) -> str:
    springs = [{"between": ["wall", "m0"], "k": "k"}]
    springs += [{"between": [f"m{i}", f"m{i + 1}"], "k": f"k*{1 + i % 2}"} for i in range(n - 1)]
    springs.append({"between": ["m0", f"m{n - 1}"], "k": "k/2"})  # a long-range spring
    return scene_toml(f"c{n}", {"m": 1.5, "k": 2.0, "g": 9.8}, masses={f"m{i}": f"m*{1 + i % 3}" for i in range(n)},
                      springs=springs, tables={"gravity": {"g": "g"}} if gravity else None,
                      initial={"x": [0.0] * n, "v": [0.0] * n})


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
    d = derive(load_scene("c.toml", text=many_masses_text(n, gravity)))
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
    small = derive(load_scene("c.toml", text=many_masses_text(20, False))).source
    large = derive(load_scene("c.toml", text=many_masses_text(80, False))).source
    # four times the masses: the text may grow about four times, never sixteen
    assert len(large) < 6 * len(small)


def nonlinear_scene_text(n: int) -> str:
    """n masses between walls: cubic springs on every other link, dampers, gravity."""
    lines = [f'name = "nl{n}"', "[parameters]", "m = 1.5", "k = 2.0", "kappa = 0.3", "c = 0.05", "g = 9.8",
             "[masses]"]
    lines += [f'm{i} = "m*{1 + i % 3}"' for i in range(n)]
    nodes = ["wall"] + [f"m{i}" for i in range(n)] + ["wall"]
    for j, (a, b) in enumerate(zip(nodes[:-1], nodes[1:])):
        lines += ["[[springs]]", f'between = ["{a}", "{b}"]', f'k = "k*{1 + j % 2}"']
        if j % 2:
            lines.append('k3 = "kappa"')
    for j in range(0, n - 1, 3):
        lines += ["[[dampers]]", f'between = ["m{j}", "m{j + 1}"]', 'c = "c"']
    lines += ["[gravity]", 'g = "g"', "[initial]", f"x = {[0.0] * n}", f"v = {[0.0] * n}"]
    return "\n".join(lines) + "\n"


def test_large_scene_incidence_form_matches_the_symbolic_model(tmp_path):
    """Past MAX_PRINTED_MATRIX masses acceleration, damping_acceleration and energy are generated in
    incidence form (no per-mass expressions): they must equal the model's own expressions (lambdify)."""
    n = 2 * MAX_PRINTED_MATRIX + 1
    d = derive(load_scene("nl.toml", text=nonlinear_scene_text(n)))
    # no expression per mass was printed (grouped index lists, as a cubic spring under gravity's law writes
    # its tensions, are one expression per group)
    assert not re.search(r"_out\[\d+\]", d.source)
    module = load(d.source, f"nl{n}", tmp_path)
    p = dict(module.DEFAULTS)
    model = d.model
    from springchain.derive.model import Effect

    params = [model.params[k] for k in sorted(p)]
    vals = [p[k] for k in sorted(p)]
    masses = sympy.Matrix(model.masses)
    acc = sympy.lambdify([*model.x, *params], [f / m for f, m in zip(
        model.force_expressions(Effect.SPRING, Effect.CUBIC, Effect.POTENTIAL, Effect.GRAVITY), masses)], "numpy")
    damp = sympy.lambdify([*model.v, *params], [f / m for f, m in zip(model.force_expressions(Effect.DAMPER), masses)],
                          "numpy")
    energy = sympy.lambdify([*model.x, *model.v, *params], model.energy, "numpy")
    rng = np.random.default_rng(5)
    x, v = rng.standard_normal((n, 4)), rng.standard_normal((n, 4))
    np.testing.assert_allclose(module.acceleration(x, **p), np.array(acc(*x, *vals)), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(module.damping_acceleration(v, **p),
                               np.array([np.broadcast_to(r, (4,)) for r in damp(*v, *vals)]), rtol=1e-12,
                               atol=1e-13)
    np.testing.assert_allclose(module.energy(x, v, **p), energy(*x, *v, *vals), rtol=1e-12)
    np.testing.assert_allclose(module.energy(x[:, 0], v[:, 0], **p), energy(*x[:, 0], *v[:, 0], *vals), rtol=1e-12)
    np.testing.assert_allclose(module.make_acceleration(**p)(x), module.acceleration(x, **p), rtol=1e-14)
