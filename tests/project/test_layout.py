"""The source tree's layout rules, read with :mod:`ast` (nothing is imported but the contract's list).

**Only ``numeric/system.py`` touches a generated module.** "Touch" means: call one of its functions or
read one of its attributes. Everywhere else in ``springchain/``, ``derive/`` and ``numeric/`` (the
contract's own reader ``generated/contract.py``, which :func:`numeric.system.interface` calls, excepted):

1. no attribute read ``X.module`` on anything: ``module`` is the :class:`~numeric.system.System` field
   that holds the generated module, and no other object of the project has an attribute of that name
   (the compiled force file is ``Compiled.kernels``);
2. no attribute read, ``getattr`` or ``hasattr`` on a *name bound to a module* — a parameter annotated
   ``ModuleType``, a parameter or assigned name spelt ``module`` or ``mod`` (the project's names for a
   generated module), or a name assigned from a loader (``load_module``, ``bundled_module``,
   ``module_of``, ``import_file``, ``importlib.import_module``), also as the first item of a tuple — of a
   contract item (:data:`springchain.generated.contract.ITEMS`), ``__file__``, or a private name a
   checked-in generated module binds at its top level (its helpers, e.g. ``_scalar_force_terms``);
3. no import of a generated scene module (``springchain.generated.<scene>``; the contract is not one).

A module may be *held* (loaded, passed on, handed to ``System.from_module`` or ``interface``): that
touches nothing.

**No private name crosses a module boundary**: no ``from M import _name`` where ``M`` is another
module of the project (``_name`` a function, class or constant; dunders such as ``__version__``
allowed; importing a private *module* such as ``springchain._api`` is not a private name).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
#: Folder -> package, as pyproject.toml installs them.
PACKAGES = {"springchain": "springchain", "derive": "springchain.derive", "numeric": "springchain.numeric",
            "generated": "springchain.generated"}
#: The one reader of generated modules, and the contract's own reader that it calls.
READERS = {ROOT / "numeric" / "system.py", ROOT / "generated" / "contract.py"}
#: The project's names for a generated module.
MODULE_NAMES = {"module", "mod"}
#: Calls that return a generated module (or ``(module, origin)``).
LOADERS = {"load_module", "bundled_module", "module_of", "import_file", "_import_file", "import_module"}


def _files() -> dict[str, Path]:
    """Dotted name -> path of every project module (generated scene modules included)."""
    out = {}
    for folder, package in PACKAGES.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            parts = list(path.relative_to(ROOT / folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join([package, *parts])] = path
    return out


FILES = _files()
GENERATED = {name for name, path in FILES.items() if path.parent == ROOT / "generated"
             and path.stem not in ("__init__", "contract")}


def _generated_private_names() -> set[str]:
    """Private (single underscore) names bound at the top level of the checked-in generated modules."""
    out = set()
    for name in GENERATED:
        for node in ast.parse(FILES[name].read_text(encoding="utf-8")).body:
            if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
                out.add(node.name)
            elif isinstance(node, ast.Assign):
                out |= {t.id for t in node.targets if isinstance(t, ast.Name)}
    return {n for n in out if n.startswith("_") and not n.startswith("__")}


def _forbidden() -> set[str]:
    from springchain.generated import contract

    return {item.name for item in contract.ITEMS} | {"__file__"} | _generated_private_names()


def _is_module_annotation(node: ast.AST | None) -> bool:
    return node is not None and "ModuleType" in ast.unparse(node)


def _loader_call(value: ast.AST) -> bool:
    if isinstance(value, ast.Subscript):  # load_module(scene)[0]
        value = value.value
    if not isinstance(value, ast.Call):
        return False
    f = value.func
    return (isinstance(f, ast.Name) and f.id in LOADERS) or (isinstance(f, ast.Attribute) and f.attr in LOADERS)


def _module_names(scope: ast.AST) -> set[str]:
    """Names bound to a module in one function (or a module body): see the module docstring, rule 2."""
    names = set(MODULE_NAMES)
    if isinstance(scope, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
        a = scope.args
        for arg in a.posonlyargs + a.args + a.kwonlyargs:
            if _is_module_annotation(arg.annotation):
                names.add(arg.arg)
    for node in ast.walk(scope):
        if isinstance(node, ast.Assign) and _loader_call(node.value):
            for t in node.targets:
                if isinstance(t, ast.Name):
                    names.add(t.id)
                elif isinstance(t, ast.Tuple) and t.elts and isinstance(t.elts[0], ast.Name):
                    names.add(t.elts[0].id)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) \
                and _is_module_annotation(node.annotation):
            names.add(node.target.id)
    return names


def _touches(path: Path, forbidden: set[str], root: Path = ROOT) -> list[str]:
    """Every access to a generated module in one source file (rules 1-3), as ``path:line: what``."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    rel = path.relative_to(root)
    out = []
    scopes = [tree] + [n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]
    for scope in scopes:
        bound = _module_names(scope)
        for node in ast.walk(scope):
            if isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Load):
                if node.attr == "module":
                    out.append(f"{rel}:{node.lineno}: {ast.unparse(node)} (rule 1)")
                elif isinstance(node.value, ast.Name) and node.value.id in bound and node.attr in forbidden:
                    out.append(f"{rel}:{node.lineno}: {ast.unparse(node)} (rule 2)")
            elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name) \
                    and node.func.id in ("getattr", "hasattr") and len(node.args) >= 2 \
                    and isinstance(node.args[0], ast.Name) and node.args[0].id in bound:
                key = node.args[1]
                if not (isinstance(key, ast.Constant) and key.value not in forbidden):
                    out.append(f"{rel}:{node.lineno}: {ast.unparse(node)} (rule 2)")
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            mods = [node.module or ""] + [f"{node.module or ''}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Import):
            mods = [a.name for a in node.names]
        else:
            continue
        for m in mods:
            if any(m == g or m.endswith("generated." + g.rsplit(".", 1)[1]) for g in GENERATED):
                out.append(f"{rel}:{node.lineno}: imports {m} (rule 3)")
    return sorted(set(out))


def _checked() -> list[Path]:
    return [path for name, path in FILES.items() if name not in GENERATED and path not in READERS]


def test_only_system_touches_a_generated_module():
    forbidden = _forbidden()
    assert {"masses", "damping_matrix", "PARAMETERS", "SCENE", "DEFAULTS", "SPRING_ENDS", "DAMPER_ENDS",
            "__file__", "_scalar_force_terms"} <= forbidden
    bad = [line for path in _checked() for line in _touches(path, forbidden)]
    assert not bad, "generated modules touched outside numeric/system.py (ask the System):\n" + "\n".join(bad)


def test_the_rule_catches_what_it_names(tmp_path):
    """The reader is not vacuous: each rule fires on a file that breaks it, and not on one that holds a
    module only."""
    forbidden = _forbidden()
    broken = tmp_path / "broken.py"
    broken.write_text(
        "from types import ModuleType\nfrom springchain.generated import duffing\n\n"
        "def a(system):\n    return system.module.masses(**system.params)\n\n"
        "def b(gen: ModuleType, p):\n    return gen.damping_matrix(**p)\n\n"
        "def c(scene):\n    m, _ = load_module(scene)\n    return m.PARAMETERS, getattr(m, 'SCENE')\n\n"
        "def d(mod):\n    return mod.__file__, mod._scalar_force_terms\n", encoding="utf-8")
    held = tmp_path / "held.py"
    held.write_text("def e(scene):\n    module, origin = load_module(scene)\n"
                    "    return System.from_module(module, scene.parameters), interface(module).n\n",
                    encoding="utf-8")
    found = _touches(broken, forbidden, tmp_path)
    assert _touches(held, forbidden, tmp_path) == []
    rules = [line.rsplit("(", 1)[1] for line in found]
    assert rules.count("rule 1)") == 1 and rules.count("rule 2)") == 5 and rules.count("rule 3)") >= 1, found


# -- no private name imported across modules --------------------------------------------------------
def _private_imports() -> list[str]:
    """``from M import _name`` where M is another project module (see the module docstring)."""
    out = []
    for name, path in FILES.items():
        if name in GENERATED:
            continue
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.ImportFrom):
                continue
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("springchain"):
                continue
            for a in node.names:
                private = a.name.startswith("_") and not (a.name.startswith("__") and a.name.endswith("__"))
                if private and f"{target}.{a.name}" not in FILES and target != name:
                    out.append(f"{path.relative_to(ROOT)}:{node.lineno}: from {target} import {a.name}")
    return sorted(out)


def test_no_private_name_crosses_a_module_boundary():
    bad = _private_imports()
    assert not bad, "private names imported from another module (make them public or move them):\n" + \
        "\n".join(bad)


# -- each fact once ------------------------------------------------------------------------------------
#: Calls that only the one import-from-path and the one atomic write make.
ONE_PLACE = {"spec_from_file_location": ROOT / "numeric" / "io" / "imports.py",
             "mkstemp": ROOT / "numeric" / "io" / "files.py", "replace": ROOT / "numeric" / "io" / "files.py",
             "rename": ROOT / "numeric" / "io" / "files.py"}


def test_one_import_from_path_and_one_atomic_write():
    """``importlib.util.spec_from_file_location`` only in ``numeric/io/imports.py``; ``tempfile.mkstemp``
    and ``os.replace``/``os.rename`` only in ``numeric/io/files.py`` (everyone else calls them)."""
    bad = []
    for name, path in FILES.items():
        if name in GENERATED:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
                f = node.func
                owner = ast.unparse(f.value)
                if f.attr in ONE_PLACE and (f.attr not in ("replace", "rename") or owner == "os") \
                        and path != ONE_PLACE[f.attr]:
                    bad.append(f"{path.relative_to(ROOT)}:{node.lineno}: {ast.unparse(f)}")
    assert not bad, "\n".join(bad)


def test_the_integrator_list_is_the_registry():
    """The package :mod:`numeric.integrators` exports every integrator of the registry's table (and the
    names it exported before), and the horizon study's methods are read from the table."""
    import springchain.numeric.integrators as integrators
    from springchain.numeric.bench import workprecision
    from springchain.numeric.run import registry

    before = {"Integrator", "Problem", "State", "LinearChain", "VelocityVerlet", "CompensatedVerlet", "Yoshida4",
              "BlanesMoan4", "BlanesMoan6", "KahanLi8", "RK4", "MatrixExponential", "ChebyshevPropagator",
              "AdaptiveMethod", "AdaptiveResult", "RK45", "DOP853", "LSODA", "DPRKN6", "DPRKN8", "DPRKN12"}
    assert before <= set(integrators.__all__)
    for name in registry.names():
        cls = registry.implementation(name)
        if cls.__module__.startswith("springchain.numeric.integrators."):
            assert getattr(integrators, cls.__name__) is cls, name
    assert all(getattr(integrators, n) is not None for n in integrators.__all__)
    assert workprecision.HORIZON_METHODS == ("verlet", "yoshida4", "blanes-moan4", "blanes-moan6", "kahan-li8",
                                             "rk4")


# -- no import circle at import time -------------------------------------------------------------------
def _run_at_import(node: ast.AST):
    """The nodes under ``node`` that run when the module is imported (not inside a function's body)."""
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
        return
    yield node
    for child in ast.iter_child_nodes(node):
        if not isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            yield from _run_at_import(child)


def _import_time_graph() -> dict[str, set[str]]:
    """Module -> the project modules its module-level imports run (``TYPE_CHECKING`` blocks left out),
    with the packages on the way: importing ``a.b.c`` runs ``a/__init__`` and ``a/b/__init__`` first.
    (tests/test_imports.py checks the graph of every import, functions included, without package edges.)"""
    graph = {}
    for name, path in FILES.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        targets: set[str] = set()
        for statement in tree.body:
            if isinstance(statement, ast.If) and "TYPE_CHECKING" in ast.unparse(statement.test):
                continue
            for node in _run_at_import(statement):
                if isinstance(node, ast.Import):
                    found = [a.name for a in node.names]
                elif isinstance(node, ast.ImportFrom):
                    if node.level:
                        parts = package.split(".")
                        base = ".".join(parts[: len(parts) - (node.level - 1)] + ([node.module] if node.module else []))
                    else:
                        base = node.module or ""
                    found = [base] + [f"{base}.{a.name}" for a in node.names]
                else:
                    continue
                for t in found:
                    bits = t.split(".")
                    for i in range(1, len(bits) + 1):
                        p = ".".join(bits[:i])
                        if p in FILES and p != name and not name.startswith(p + "."):
                            targets.add(p)
        graph[name] = targets
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (iterative Tarjan)."""
    index, low, on, stack, out, counter = {}, {}, set(), [], [], 0
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in graph:
                    continue
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(sorted(comp))
    return out


def test_no_import_circle_at_import_time():
    graph = _import_time_graph()
    assert "springchain.numeric.run.registry" in graph["springchain.numeric.integrators"]  # edges are read
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]  # and circles found
    circles = _cycles(graph)
    assert not circles, f"import circles at import time: {circles}"


# -- what the System answers instead ---------------------------------------------------------------
def test_the_system_answers_for_the_module():
    """The System's methods pass the parameter values (and a chain's n) and return the hand-written
    matrices and closed forms: the building (three storeys k, a dashpot c at the ground floor) and the
    free uniform chain (ω_j = 2√(k/m)·sin(jπ/2n), j = 0 … n-1) at a size other than the module's."""
    import importlib
    import math

    import numpy as np

    from springchain.numeric.system import System

    b = System.from_module(importlib.import_module("springchain.generated.building"), {"k": 3.0, "c": 0.5})
    k = 3.0
    assert np.allclose(b.stiffness_matrix(), [[2 * k, -k, 0], [-k, 2 * k, -k], [0, -k, k]], rtol=1e-15, atol=0)
    assert np.allclose(b.damping_matrix(), [[0.5, 0, 0], [0, 0, 0], [0, 0, 0]], rtol=1e-15, atol=0)
    ends, c = b.dampers()
    assert ends.tolist() == [[0, -1]] and np.allclose(c, [0.5], rtol=1e-15)
    assert b.rayleigh_coefficients() is None and b.modal_damping_ratios() is None
    assert b.with_params({"k": 5.0}).stiffness_matrix()[2, 2] == pytest.approx(5.0, rel=1e-15)

    chain = System.from_module(importlib.import_module("springchain.generated.chain100k"), {"k": 4.0, "m": 1.0})
    assert chain.n == 100000
    short = chain.with_n(7)
    assert short.n == 7 and short.masses.shape == (7,) and short.spring_ends.shape == (6, 2)
    diag, off = short.stiffness_bands()
    assert np.allclose(diag, [4, 8, 8, 8, 8, 8, 4], rtol=1e-15) and np.allclose(off, -4.0, rtol=1e-15)
    expected = sorted(2 * math.sqrt(4.0) * math.sin(j * math.pi / 14) for j in range(7))
    assert np.allclose(np.sort(short.mode_omega()), expected, rtol=1e-14, atol=1e-15)
    assert short.make_acceleration()(np.arange(7.0)).shape == (7,)
    assert len(short.parameter_vector()) == 2 and short.scene_name == "chain100k"
