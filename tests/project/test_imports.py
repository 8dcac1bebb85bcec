"""The layers, read from the source (every ``import``, at module level or inside a function):

* no import circle anywhere in springchain;
* no back edge: ``derive/``, ``numeric/`` and ``generated/`` never import the top package
  ``springchain/`` (API and command line); ``numeric/`` never imports ``derive/`` and ``derive/``
  never imports ``numeric/``; generated modules import NumPy/SciPy only;
* the generated-module contract is read only through ``numeric/system.py``: other numeric modules
  take only its shared facts (``End``, ``MAX_DENSE``, ...) and never ``getattr``/``hasattr`` a name
  of the contract on a module.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
#: Folder -> package, as pyproject.toml installs them.
PACKAGES = {"springchain": "springchain", "derive": "springchain.derive", "numeric": "springchain.numeric",
            "generated": "springchain.generated", "scenes": "springchain.scenes"}
#: The layers below the top package.
LOWER = ("springchain.derive", "springchain.numeric", "springchain.generated", "springchain.scenes")
#: What numeric modules other than system.py may take from the contract: facts both sides share.
SHARED_FACTS = {"MAX_DENSE", "End", "END_WORDS", "Ground", "SCALAR_HELPERS"}


def _modules() -> dict[str, Path]:
    out = {}
    for folder, package in PACKAGES.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            parts = list(path.relative_to(ROOT / folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join([package, *parts])] = path
    return out


MODULES = _modules()


def _type_checking_only(tree: ast.AST) -> set[int]:
    """ids of the import nodes under ``if TYPE_CHECKING:`` (annotations only: no edge at run time)."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            out |= {id(n) for st in node.body for n in ast.walk(st)}
    return out


def _imports(name: str, path: Path) -> list[tuple[str, tuple[str, ...]]]:
    """``(imported module, names taken from it)`` for every import statement of a module that runs
    (at module level or inside a function; not the ``TYPE_CHECKING`` ones)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    skip = _type_checking_only(tree)
    out = []
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            out += [(a.name, ()) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            names = tuple(a.name for a in node.names)
            subs = [f"{target}.{n}" for n in names if f"{target}.{n}" in MODULES]
            out += [(s, ()) for s in subs] + ([(target, names)] if len(subs) < len(names) else [])
    return out


def _graph() -> dict[str, set[str]]:
    graph = {}
    for name, path in MODULES.items():
        graph[name] = {t for t, _ in _imports(name, path) if t in MODULES and t != name}
    return graph


def _circles(graph: dict[str, set[str]]) -> list[frozenset[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = set()
            while True:
                w = stack.pop()
                on.discard(w)
                comp.add(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(frozenset(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def _layer(module: str) -> str:
    for lower in LOWER:
        if module == lower or module.startswith(lower + "."):
            return lower
    return "springchain"


def test_the_reader_sees_every_module():
    assert len(MODULES) > 100 and "springchain.numeric.run.registry" in MODULES
    graph = _graph()
    assert "springchain.numeric.system" in graph["springchain.numeric.run.exact"]  # relative imports resolved
    assert "springchain.generated.contract" in graph["springchain.numeric.system"]


def test_no_import_circles():
    circles = [sorted(c) for c in _circles(_graph())]
    assert not circles, f"import circles: {circles}"


@pytest.mark.parametrize("lower", ["springchain.derive", "springchain.numeric", "springchain.generated"])
def test_no_back_edges(lower):
    bad = []
    for name, targets in _graph().items():
        if _layer(name) != lower:
            continue
        for t in targets:
            layer = _layer(t)
            if layer == "springchain" or {lower, layer} == {"springchain.derive", "springchain.numeric"} \
                    or (lower == "springchain.generated" and layer != lower):
                bad.append((name, t))
    assert not bad, f"back edges: {sorted(bad)}"


def test_generated_modules_import_numpy_and_scipy_only():
    for name, path in MODULES.items():
        if _layer(name) == "springchain.generated" and not name.endswith((".contract", ".generated")):
            tops = {t.split(".")[0] for t, _ in _imports(name, path)}
            assert tops <= {"numpy", "scipy"}, (name, tops)
    contract = {t.split(".")[0] for t, _ in _imports("springchain.generated.contract", MODULES[
        "springchain.generated.contract"])}
    assert contract <= {"__future__", "enum", "dataclasses", "types"}, contract  # stdlib only


def test_the_contract_is_read_only_through_system():
    from springchain.generated import contract

    names = set(contract.BY_NAME)
    for name, path in MODULES.items():
        if _layer(name) != "springchain.numeric" or name == "springchain.numeric.system":
            continue
        for target, taken in _imports(name, path):
            if target == "springchain.generated.contract":
                assert set(taken) <= SHARED_FACTS, (name, taken)
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in ("getattr", "hasattr") \
                    and len(node.args) >= 2 and isinstance(node.args[1], ast.Constant) and node.args[1].value in names:
                pytest.fail(f"{name}:{node.lineno}: {node.func.id}(..., {node.args[1].value!r}) on a generated "
                            "module; ask numeric.system.System")
