"""The generated-module contract (generated/contract.py): every name a generated module binds is
described there, and what it declares a module must have, it has."""

from __future__ import annotations

import importlib
import pkgutil
from types import SimpleNamespace

import pytest

import springchain.generated as generated_pkg
from springchain.generated import contract
from springchain.generated.contract import ITEMS, MAX_DENSE, End, Layout, When

BUNDLED = sorted(m.name for m in pkgutil.iter_modules(generated_pkg.__path__) if m.name != "contract")

#: Items every module of a layout binds.
PER_LAYOUT = {Layout.MASSES: {i.name for i in ITEMS if i.when is When.MASSES},
              Layout.CHAIN: {i.name for i in ITEMS if i.when is When.CHAIN}}


def public_names(module) -> set[str]:
    return {k for k in vars(module) if not k.startswith("_")}


@pytest.mark.parametrize("name", BUNDLED)
def test_bundled_modules_bind_only_contract_names(name):
    module = importlib.import_module(f"springchain.generated.{name}")
    assert public_names(module) <= set(contract.BY_NAME), public_names(module) - set(contract.BY_NAME)
    facts = contract.read(module)
    assert set(contract.REQUIRED) <= public_names(module)
    assert PER_LAYOUT[facts.layout] <= public_names(module)
    other = Layout.CHAIN if facts.layout is Layout.MASSES else Layout.MASSES
    assert not (PER_LAYOUT[other] & public_names(module))  # nothing of the other layout
    for item in ITEMS:  # every function the module binds is read as provided, and only those
        if item.function:
            assert facts.has(item.name) == callable(getattr(module, item.name, None)), item.name


@pytest.mark.parametrize("text, expect", [
    ('[[dampers]]\nbetween = ["p", "wall"]\nc = "0.1"', {"damping_matrix", "damping_acceleration", "damper_constants"}),
    ('[[forces]]\non = "p"\nf = "cos(2*t)"', {"external_acceleration", "forcing_harmonics"}),
    ('[ground]\nacceleration = "sin(t)"', {"ground_acceleration", "ground_harmonics", "ground_motion"}),
    ('[gravity]\ng = "9.81"', {"gravity_forces"}),
    ('[[springs]]\nbetween = ["q", "wall"]\npotential = "k*d**2/2 + d**4/4"',
     {"equilibrium", "spring_tensions", "spring_stiffnesses"}),
])
def test_effects_bring_their_items(text, expect, make_chain_toml, scene_from_text, import_source):
    from springchain._modules import derive

    toml = make_chain_toml("eff", {"m": 1.0, "k": 1.0}, {"p": "m", "q": "m"}, [("wall", "p", "k"), ("p", "q", "k")],
                           extra=text)
    module = import_source(derive(scene_from_text(toml, "eff.toml")).source, "eff")
    facts = contract.read(module)
    assert all(facts.has(f) for f in expect), expect - facts.functions
    assert public_names(module) <= set(contract.BY_NAME)
    assert facts.potential == ("equilibrium" in expect)


def test_a_potential_chain_states_its_law():
    import springchain.generated.fput_alpha as fput

    facts = contract.read(fput)
    assert facts.potential and not facts.linear and not facts.law_indexed
    assert all(facts.has(f) for f in ("spring_force", "spring_energy", "spring_stiffness", "equilibrium"))
    seed = contract.read(importlib.import_module("springchain.generated.seed"))
    assert not seed.potential and not seed.law_indexed


def test_the_chain_module_states_the_shared_facts():
    import springchain.generated.chain100k as chain

    facts = contract.read(chain)
    assert chain.MAX_DENSE == MAX_DENSE and facts.max_dense == MAX_DENSE
    assert facts.left is End.FREE and facts.right is End.FREE and facts.uniform and facts.has("mode_omega")
    assert [e.value for e in End] == list(contract.END_WORDS) and [e.code for e in End] == [0, 1, 2]


def test_a_module_of_another_version_is_refused_in_one_line():
    stale = SimpleNamespace(SCENE="old", SCENE_SHA256="0" * 64, PARAMETERS=(), DEFAULTS={}, N=1,
                            EFFECTS=("spring",), LINEAR=True)  # no RIGID_MODES, no functions
    with pytest.raises(contract.ContractError, match="'old' lacks 'RIGID_MODES'.*springchain derive"):
        contract.read(stale)
    facts = contract.read(importlib.import_module("springchain.generated.seed"))
    with pytest.raises(KeyError, match="not a function of the generated-module contract"):
        facts.has("SCENE")
