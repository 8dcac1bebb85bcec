"""The symbolic algebra is gated by deterministic work caps, never by a clock.

``springchain derive`` must write the same module on any machine under any load (so that
``derive --check`` never flips): closed-form modes, damping ratios and transfer functions are
decided by sizes measured before the work (:mod:`derive.work`), and no timer or alarm is armed.
"""

from __future__ import annotations

import signal
import time

import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import EXAMPLE_SCENES, masses_toml
from springchain.derive import work
from springchain.derive.model import Model
from springchain.derive.modes import closed_form_modes
from springchain.derive.scene import load_scene
from springchain.derive.transfer import transfer_function


def general_chain(n: int) -> Model:
    """wall - k0 - p0 - k1 - ... - p(n-1) - kn - wall with every mass and spring its own symbol."""
    params = {f"m{i}": 1.0 + i for i in range(n)} | {f"k{i}": 2.0 + 0.5 * i for i in range(n + 1)}
    masses = {f"p{i}": f"m{i}" for i in range(n)}
    ends = ["wall", *masses, "wall"]
    springs = [(ends[i], ends[i + 1], f"k{i}") for i in range(n + 1)]
    return Model(load_scene(f"g{n}.toml", text=masses_toml(f"g{n}", params, masses, springs)))


@pytest.fixture
def no_clock(monkeypatch):
    """Any timer or alarm the algebra would arm fails the test."""
    def refuse(*args, **kwargs):
        raise AssertionError("the symbolic work consulted a clock")

    monkeypatch.setattr(signal, "setitimer", refuse)
    monkeypatch.setattr(signal, "alarm", refuse)
    monkeypatch.setattr(time, "monotonic", refuse)


@pytest.mark.parametrize("name", ["wall2", "four", "pairs", "hanging"])
def test_closed_forms_arm_no_timer(no_clock, name):
    model = Model(load_scene(f"{name}.toml", text=EXAMPLE_SCENES[name]))
    modes = closed_form_modes(model)
    assert modes.closed_form and not modes.notes
    assert transfer_function(model, 0, model.scene.n - 1) is not None


def test_a_large_symbolic_block_falls_back_by_size_not_time(no_clock):
    """A 6-mass chain of 13 distinct symbols: its characteristic polynomial bound (10 000 terms) is
    over the cap, so it falls back to numeric values before any expansion (it took ~17 s of
    algebra, and under load its result depended on a 20 s alarm)."""
    model = general_chain(6)
    t0 = time.perf_counter()
    modes = closed_form_modes(model)
    assert time.perf_counter() - t0 < 60  # a generous sanity bound, not a timing assertion
    assert not modes.closed_form
    assert f"more than {work.MAX_DET_TERMS} terms" in modes.notes[0]
    assert transfer_function(model, 0, 5) is None
    assert len([s for m in modes.modes for s in m.shapes]) == 6


def test_a_small_general_block_is_still_solved():
    """Two distinct masses and three springs: a quadratic with 5 symbols, under every cap."""
    modes = closed_form_modes(general_chain(2))
    assert modes.closed_form and len(modes.modes) == 2


@pytest.mark.parametrize("name", ["building", "building_quake", "building_rayleigh", "duffing", "hanging",
                                  "ring4", "seed"])
def test_bundled_scenes_are_far_under_the_caps(name):
    """The bundled scenes keep their closed forms with a wide margin (≤ 36 of 1000 terms)."""
    from springchain._scenes import bundled_scene_dir
    from springchain.derive.modes import _blocks

    model = Model(load_scene(bundled_scene_dir() / f"{name}.toml"))
    lam = sp.Symbol("lambda")
    for B in _blocks(model):
        A = (B.T * model.K * B).applyfunc(sp.expand) - lam * (B.T * model.M * B).applyfunc(sp.expand)
        assert work.det_terms_bound(A) <= work.MAX_DET_TERMS // 10


_symbols = sp.symbols("a b c d lambda")
_entry = st.lists(st.tuples(st.integers(-3, 3), st.lists(st.sampled_from(_symbols), max_size=2)),
                  max_size=3).map(lambda terms: sp.expand(sp.Add(*(c * sp.Mul(*s) for c, s in terms))))


@settings(deadline=None)
@given(st.integers(1, 4).flatmap(lambda n: st.lists(_entry, min_size=n * n, max_size=n * n)
                                 .map(lambda e: sp.Matrix(n, n, e))))
def test_det_terms_bound_is_an_upper_bound(A):
    assert work.monomials(sp.expand(A.det(method="berkowitz"))) <= work.det_terms_bound(A)


def test_a_cap_raises_past_its_size():
    work.check(work.MAX_DET_TERMS, work.MAX_DET_TERMS)
    with pytest.raises(work.WorkCapExceeded):
        work.check(work.MAX_DET_TERMS + 1, work.MAX_DET_TERMS)
