"""Sphinx glue: the generated reference pages and the benchmark tables, written before the build reads.

At ``builder-inited`` this writes, into ``docs/_generated/`` (not under version control):

* ``scene-keys.md`` — every scene table and key the loader accepts, described by
  ``reference/scene_keys.toml`` (:mod:`springchain_reference`);
* ``commands.md`` — every command and argument of ``springchain.cli.build_parser()``;
* ``benchmarks.md`` — per script in ``benchmarks/``, the file it wrote with ``--markdown``
  (``docs/benchmarks/<script>.md``: machine, date, command, tables), or the command that writes it.

The pages include them (MyST ``{include}``). Every problem — a key or a flag in the code but not
described, or described but not in the code; a flag without help — is a Sphinx warning, so the
build (run with ``-W``) fails on it.
"""

from __future__ import annotations

import ast
from pathlib import Path

from sphinx.util import logging

import springchain_reference as ref

logger = logging.getLogger(__name__)
OUT = ref.DOCS / "_generated"
BENCHMARKS = ref.ROOT / "benchmarks"
RESULTS = ref.DOCS / "benchmarks"


def _write(name: str, text: str) -> None:
    OUT.mkdir(exist_ok=True)
    path = OUT / name
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")


def scene_page() -> tuple[str, list[str]]:
    meta = ref.scene_meta()
    seen = ref.loader_keys(meta)
    base = ["Each table's example below is merged into one of these scenes (its top-level tables replaced):", ""]
    for form in meta["base"]:
        base += ["```{code-block} toml", f":caption: the {form} form", "", meta["base"][form].strip(), "```", ""]
    return "\n".join(base) + "\n" + ref.render_scene_reference(meta, seen), ref.scene_problems(meta, seen)


def benchmarks_page() -> str:
    lines = []
    for script in sorted(BENCHMARKS.glob("[a-z]*.py")):
        doc = ast.get_docstring(ast.parse(script.read_text(encoding="utf-8"))) or ""
        title = doc.strip().split("\n\n")[0].replace("\n", " ") if doc.strip() else script.stem
        lines += [f"## `benchmarks/{script.name}`", "", title, ""]
        result = RESULTS / f"{script.stem}.md"
        if result.is_file():
            lines += [result.read_text(encoding="utf-8").strip(), ""]
        else:
            lines += ["Not run for this documentation yet; to add its tables here, run from the repository root:", "",
                      "```bash", f"python benchmarks/{script.name} --markdown docs/benchmarks/{script.stem}.md", "```", ""]
    return "\n".join(lines)


def generate(app) -> None:
    text, problems = scene_page()
    _write("scene-keys.md", text)
    p = ref.parser()
    _write("commands.md", ref.render_command_reference(p))
    _write("benchmarks.md", benchmarks_page())
    for problem in problems + ref.command_problems(p):
        logger.warning(problem, type="springchain", subtype="reference")


def setup(app):
    app.connect("builder-inited", generate)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
