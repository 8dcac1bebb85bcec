"""Every folder of the import namespace ships in the wheel.

The package list in ``pyproject.toml`` is written by hand (the design card's top-level folders install
as ``springchain.<folder>``); a new subpackage missing from it imports from a clone but not from an
installed wheel. This reads the list and compares it with the folders that hold an ``__init__.py``.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _folders() -> set[str]:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    mapped = config["package-dir"]
    found = set()
    for name, folder in mapped.items():
        base = ROOT / folder
        for init in base.rglob("__init__.py"):
            rel = init.parent.relative_to(base).parts
            if any(part in {"build", "__pycache__"} or part.startswith(".") for part in rel):
                continue
            found.add(".".join((name, *rel)) if name else ".".join(rel))
    return found


def test_every_subpackage_is_listed():
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    assert _folders() - listed == set()
