"""Sphinx directives that render the references from the code (see :mod:`springchain_reference`).

* ``scene-reference``: every scene table and key the loader accepts, with ``scene_keys.toml``'s
  meaning; a key without a description, or a description without a key, is a warning;
* ``command-reference``: every command and argument of ``springchain.cli.build_parser()``;
* ``include-benchmark``: a file a benchmark script wrote (``docs/benchmarks/NAME.md``), or a
  warning naming the command that writes it.
"""

from __future__ import annotations

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles

import springchain_reference as ref

logger = logging.getLogger(__name__)


class _Rendered(SphinxDirective):
    has_content = False

    def rst(self) -> tuple[str, list[str]]:
        raise NotImplementedError

    def run(self):
        text, problems = self.rst()
        for p in problems:
            logger.warning(p, location=(self.env.docname, self.lineno))
        node = nodes.section() if "\n---" in text or "\n===" in text else nodes.container()
        node.document = self.state.document
        nested_parse_with_titles(self.state, StringList(text.splitlines(), source=self.env.docname), node)
        return node.children


class SceneReference(_Rendered):
    def rst(self):
        self.env.note_dependency(str(ref.SCENE_KEYS))
        meta = ref.scene_meta()
        seen = ref.loader_keys(meta)
        base = ["The examples below are merged into one of these two scenes (their top-level tables replaced):", "",
                ".. code-block:: toml", "   :caption: the [masses] form", ""]
        base += ["   " + ln if ln else "" for ln in meta["base"]["masses"].strip().splitlines()]
        base += ["", ".. code-block:: toml", "   :caption: the [chain] form", ""]
        base += ["   " + ln if ln else "" for ln in meta["base"]["chain"].strip().splitlines()]
        return "\n".join(base) + "\n\n" + ref.render_scene_reference(meta, seen), ref.scene_problems(meta, seen)


class CommandReference(_Rendered):
    def rst(self):
        p = ref.parser()
        return ref.render_command_reference(p), ref.command_problems(p)


def setup(app):
    app.add_directive("scene-reference", SceneReference)
    app.add_directive("command-reference", CommandReference)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
