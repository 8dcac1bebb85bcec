"""Shared fixtures for the springchain test suite.

* matplotlib is forced to the non-interactive Agg backend before anything imports it;
* BLAS runs on one thread per worker (the workers already use every core);
* bytecode caches are written even under ``PYTHONDONTWRITEBYTECODE`` (one compile per run, not per process);
* ``SPRINGCHAIN_CACHE`` points at a temporary folder of the run (shared by its xdist workers), so no
  test writes into the user's cache (and a subprocess started by a test inherits it); ``fresh_cache``
  gives one test a cache of its own;
* a hypothesis profile ``ci`` (no deadline, a moderate number of examples, derandomized: the
  same draws every run) is registered and loaded unless ``HYPOTHESIS_PROFILE`` names another one
  (``explore``: fresh random draws at each test's own example count; ``thorough``: 500 random draws);
* fixtures for the repository root, the bundled reference scene, its checked-in
  generated module and the :class:`numeric.system.System` bound to it, plus
  helpers that build scenes from TOML text and import rendered module source (``chain_module_of``
  for ``[chain]`` modules). Plain functions shared by the test modules live in :mod:`helpers`.
"""

from __future__ import annotations

import importlib
import importlib.util
import itertools
import os
import sys
from pathlib import Path

# The run keeps bytecode caches even where PYTHONDONTWRITEBYTECODE is set (CI images set it): springchain's
# modules and the rewritten test modules are compiled once and reused by the other worker and by every
# subprocess a test starts (they inherit this environment), not compiled again in each (~40 CPU-s a run).
sys.dont_write_bytecode = False
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
os.environ.setdefault("MPLBACKEND", "Agg")
# `-n auto` starts one worker per core, so each worker's BLAS gets one thread: two workers' OpenBLAS
# threads on two cores would spin-wait against each other (measured: ~25 CPU-s of a run). Set before
# NumPy/SciPy load their OpenBLAS and inherited by every subprocess a test starts.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import matplotlib  # noqa: E402

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from helpers import scene_toml  # noqa: E402
from hypothesis import HealthCheck, settings  # noqa: E402

settings.register_profile(
    "ci",
    derandomize=True,  # the same draws every run: CI's verdict and time do not depend on luck
    deadline=None,
    max_examples=int(os.environ.get("SPRINGCHAIN_HYPOTHESIS_EXAMPLES", "25")),
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
settings.register_profile("thorough", deadline=None, max_examples=500)  # fresh random draws each run
settings.register_profile("explore", deadline=None,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

REPO_ROOT = Path(__file__).resolve().parent.parent

#: The reference numbers of issue 2 (seed scene).
REFERENCE_X0 = np.array([0.8552, 1.5376, 0.8834])
REFERENCE_V0 = np.array([-1.9255, 0.6991, -0.2460])
REFERENCE_DT = 0.1
REFERENCE_STEPS = 1000


@pytest.fixture(scope="session", autouse=True)
def _session_cache(tmp_path_factory):
    """Per-run SPRINGCHAIN_CACHE (restored afterwards), one for all pytest-xdist workers of the run: a
    scene's module is derived and its compiled loops are compiled once, not once per worker (every
    file in it is written through a temporary file and a rename, numba's cache files too)."""
    if os.environ.get("PYTEST_XDIST_WORKER"):  # workers' base temps are folders of the run's
        cache = tmp_path_factory.getbasetemp().parent / "springchain-cache"
        cache.mkdir(exist_ok=True)
    else:
        cache = tmp_path_factory.mktemp("springchain-cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("SPRINGCHAIN_CACHE", str(cache))
        yield cache


@pytest.fixture(scope="session")
def repo_root() -> Path:
    """The repository root (the folder holding derive/, numeric/, scenes/, generated/)."""
    return REPO_ROOT


@pytest.fixture(scope="session")
def seed_path(repo_root) -> Path:
    return repo_root / "scenes" / "seed.toml"


@pytest.fixture(scope="session")
def seed_scene(seed_path):
    """The bundled reference scene (masses m, 3m, m; two springs k; free ends)."""
    from springchain.derive.scene import load_scene

    return load_scene(seed_path)


@pytest.fixture(scope="session")
def seed_derivation(seed_scene):
    """A fresh derivation of the reference scene (model, modes, rendered source)."""
    from springchain._modules import derive

    return derive(seed_scene)


@pytest.fixture(scope="session")
def seed_module():
    """The checked-in generated module of the reference scene."""
    return importlib.import_module("springchain.generated.seed")


@pytest.fixture(scope="session")
def seed_system(seed_module):
    """The reference scene's generated equations at the scene's parameter values (m = k = 1)."""
    from springchain.numeric.system import System

    return System.from_module(seed_module)


@pytest.fixture(scope="session")
def reference():
    """The reference initial state and step: x0, v0 (N,), dt, steps."""
    return {"x0": REFERENCE_X0.copy(), "v0": REFERENCE_V0.copy(), "dt": REFERENCE_DT,
            "steps": REFERENCE_STEPS}


@pytest.fixture(scope="session")
def scene_from_text():
    """``scene_from_text(text, label="test.toml")``: a validated Scene from TOML text."""
    from springchain.derive.scene import load_scene

    def make(text: str, label: str = "test.toml"):
        return load_scene(label, text=text)

    return make


_counter = itertools.count()


@pytest.fixture(scope="session")
def import_source(tmp_path_factory):
    """``import_source(source, name)``: write rendered module source to a temp file and import it."""
    folder = tmp_path_factory.mktemp("rendered")

    def load(source: str, name: str):
        unique = f"springchain_test_{name}_{next(_counter)}"
        path = folder / f"{unique}.py"
        path.write_text(source, encoding="utf-8")
        spec = importlib.util.spec_from_file_location(unique, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module

    return load


@pytest.fixture(scope="session")
def chain_module_of(import_source):
    """``chain_module_of(text, label)``: a ``[chain]`` scene's module rendered afresh from its TOML
    text (never the cache's), imported once per text."""
    from springchain.derive.chain import ChainModel
    from springchain.derive.chain_codegen import render_chain_module
    from springchain.derive.scene import load_scene

    modules: dict = {}

    def get(text: str, label: str = "chain"):
        if text not in modules:
            scene = load_scene(f"{label}.toml", text)
            modules[text] = import_source(render_chain_module(ChainModel(scene), bundled=False), label)
        return modules[text]

    return get


@pytest.fixture
def fresh_cache(tmp_path, monkeypatch):
    """A SPRINGCHAIN_CACHE of the test's own (``pytestmark = pytest.mark.usefixtures("fresh_cache")``)."""
    monkeypatch.setenv("SPRINGCHAIN_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


def masses_toml(name: str, params: dict[str, float], masses: dict[str, str],
                springs: list[tuple[str, ...]], *, extra: str = "") -> str:
    """TOML text for a scene of point masses and springs (initial state: small x, zero v).

    ``springs`` holds ``(end, end, k)`` or ``(end, end, k, k3)`` tuples; ``extra`` is
    TOML appended before ``[initial]`` (e.g. a ``[gravity]`` table).
    """
    entries = [{"between": [a, b], "k": k, **({"k3": k3[0]} if k3 else {})} for a, b, k, *k3 in springs]
    n = len(masses)
    return scene_toml(name, params, masses=masses, springs=entries, extra=extra,
                      initial={"x": [0.1 * (j + 1) for j in range(n)], "v": [0.0] * n})


@pytest.fixture(scope="session")
def make_chain_toml():
    """The :func:`masses_toml` helper (point masses along a line) as a fixture."""
    return masses_toml


#: Small scenes built from TOML text, shared by the symbolic and generated-code tests.
EXAMPLE_SCENES: dict[str, str] = {
    # wall - ka - p - kb - q (free end), general masses and springs: a quadratic in ω²
    "wall2": masses_toml("wall2", {"ma": 1.0, "mb": 2.0, "ka": 3.0, "kb": 0.5},
                        {"p": "ma", "q": "mb"}, [("wall", "p", "ka"), ("p", "q", "kb")]),
    # wall - k - p - k - q - k - wall, equal masses: ω² = k/m, 3k/m (mirror symmetric)
    "sym2": masses_toml("sym2", {"m": 1.0, "k": 1.0}, {"p": "m", "q": "m"},
                       [("wall", "p", "k"), ("p", "q", "k"), ("q", "wall", "k")]),
    # wall-m-m-m-m-wall: ω²_j = (2 - 2 cos(jπ/5)) k/m
    "four": masses_toml("four", {"m": 1.0, "k": 1.0},
                       {"m1": "m", "m2": "m", "m3": "m", "m4": "m"},
                       [("wall", "m1", "k"), ("m1", "m2", "k"), ("m2", "m3", "k"),
                        ("m3", "m4", "k"), ("m4", "wall", "k")]),
    # a spring joining non-neighbours, and two springs between the same pair (K adds)
    "nonneigh": masses_toml("nonneigh", {"m": 1.0, "k": 1.0}, {"p1": "m", "p2": "2*m", "p3": "m"},
                           [("p1", "p3", "k"), ("p1", "p2", "k"), ("p2", "p1", "2*k")]),
    "one_wall": masses_toml("one_wall", {"m": 2.0, "k": 3.0}, {"p": "m"}, [("wall", "p", "k")]),
    "one_free": masses_toml("one_free", {"m": 2.0}, {"p": "m"}, []),
    # two identical free pairs: two rigid modes and a repeated ω² = 2k/m
    "pairs": masses_toml("pairs", {"m": 1.0, "k": 1.0}, {"p1": "m", "p2": "m", "p3": "m", "p4": "m"},
                        [("p1", "p2", "k"), ("p3", "p4", "k")]),
    # hanging from a wall under gravity (a negative parameter: declared real, not positive)
    "hanging": masses_toml("hanging", {"m": 1.0, "k": 10.0, "g": -9.81}, {"p": "m", "q": "2*m"},
                          [("wall", "p", "k"), ("p", "q", "k")], extra='[gravity]\ng = "g"'),
    # a cubic (hardening) spring: nonlinear acceleration and energy
    "cubic": masses_toml("cubic", {"m": 1.0, "k": 1.0, "c": 0.5}, {"p": "m", "q": "m"},
                        [("wall", "p", "k"), ("p", "q", "k", "c")]),
}


@pytest.fixture(scope="session")
def example_texts() -> dict[str, str]:
    """The TOML text of each example scene, by name."""
    return dict(EXAMPLE_SCENES)


@pytest.fixture(scope="session")
def example_scene(scene_from_text):
    """``example_scene(name)``: one of :data:`EXAMPLE_SCENES` as a Scene (label ``<name>.toml``)."""
    cache = {}

    def get(name: str):
        if name not in cache:
            cache[name] = scene_from_text(EXAMPLE_SCENES[name], f"{name}.toml")
        return cache[name]

    return get


@pytest.fixture(scope="session")
def derived(example_scene, seed_derivation):
    """``derived(name)``: a cached derivation of an example scene (``"seed"``: the bundled one)."""
    from springchain._modules import derive

    cache = {"seed": seed_derivation}

    def get(name: str):
        if name not in cache:
            cache[name] = derive(example_scene(name))
        return cache[name]

    return get
