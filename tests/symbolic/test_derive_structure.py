"""The symbolic side's shape, read from its source: no import circle inside
derive/, no import of the numeric side, small functions, and renderers made of section writers."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

DERIVE = Path(__file__).resolve().parents[2] / "derive"
#: Longest function allowed in derive/ (lines, decorators and docstring included).
MAX_FUNCTION_LINES = 80


def _trees() -> dict[str, ast.Module]:
    return {f.stem: ast.parse(f.read_text(encoding="utf-8"), str(f)) for f in sorted(DERIVE.glob("*.py"))}


def _runtime_nodes(tree: ast.AST):
    """Every node of ``tree`` except those under ``if TYPE_CHECKING:`` (never run)."""
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, ast.If) and isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING":
            continue
        yield node
        yield from _runtime_nodes(node)


def _imports(tree: ast.Module, modules) -> set[str]:
    """The derive/ modules a module imports when it runs, at top level or inside functions."""
    out = set()
    for node in _runtime_nodes(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            names = [node.module] if node.module else [a.name for a in node.names]
            out |= {name.split(".")[0] for name in names}
        elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("springchain.derive."):
            out.add(node.module.split(".")[2])
    return out & set(modules)


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import circle of ``graph`` (module -> imported modules), or None."""
    state: dict[str, int] = {}
    path: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        path.append(m)
        for dep in sorted(graph[m]):
            if state.get(dep) == 1:
                return path[path.index(dep):] + [dep]
            if dep not in state and (found := visit(dep)) is not None:
                return found
        state[m] = 2
        path.pop()
        return None

    for m in sorted(graph):
        if m not in state and (found := visit(m)) is not None:
            return found
    return None


def test_cycle_finder_finds_a_circle():
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": set()}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set()}) is None


def test_no_import_circle_inside_derive():
    trees = _trees()
    graph = {name: _imports(tree, trees) - {name} for name, tree in trees.items()}
    assert _cycle(graph) is None, " -> ".join(_cycle(graph))


def test_derive_never_imports_the_numeric_side():
    for name, tree in _trees().items():
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                target = "." * node.level + (node.module or "")
                assert not target.startswith(("..numeric", "springchain.numeric", "numeric")), (name, target)
            elif isinstance(node, ast.Import):
                assert not any(a.name.startswith(("springchain.numeric", "numeric")) for a in node.names), name


def test_no_long_function_in_derive():
    long = [(name, node.name, node.end_lineno - node.lineno + 1)
            for name, tree in _trees().items() for node in ast.walk(tree)
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
            and node.end_lineno - node.lineno + 1 > MAX_FUNCTION_LINES]
    assert long == []


@pytest.mark.parametrize("module", ["codegen", "chain_codegen"])
def test_renderers_are_section_writers_with_one_header(module):
    """Each renderer lists its section writers in SECTIONS and writes its header only through
    module_text.module_head (the do-not-edit header is written in one place)."""
    import importlib

    mod = importlib.import_module(f"springchain.derive.{module}")
    assert len(mod.SECTIONS) >= 8 and all(callable(s) for s in mod.SECTIONS)
    source = (DERIVE / f"{module}.py").read_text(encoding="utf-8")
    assert "module_head(" in source and "DO NOT EDIT" not in source
    assert "DO NOT EDIT" in (DERIVE / "module_text.py").read_text(encoding="utf-8")
