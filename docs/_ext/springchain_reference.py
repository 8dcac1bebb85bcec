"""The scene-format and command references, read from the code itself.

Nothing here is a copy of the code's lists, so the reference pages cannot drift from the code:

* **scene keys** — every table and key the scene loader accepts, recorded while the loader
  checks the keys of real scenes (:func:`loader_keys`: each call of the loader's key check is
  recorded with its table and the keys it accepts). What a key *means* (type, default, units,
  meaning, example) is written once, in ``docs/reference/scene_keys.toml``; :func:`scene_problems`
  lists every key the loader accepts that the file does not describe, and the reverse;
* **commands and flags** — read from ``springchain.cli.build_parser()`` (:func:`commands`);
  :func:`command_mentions` finds the commands and flags the documentation names, so a flag that
  no longer exists is caught.

``springchain_sphinx`` writes these as MyST pages when the site is built and reports every problem
as a Sphinx warning (the docs build runs with ``-W``); the tests (``tests/project/test_docs_reference.py``)
call the same functions without Sphinx. A key or command added to the code appears in the
reference on the next build, marked "not described yet", and makes the build and the test fail
until its meaning is written down. Nothing here needs Sphinx.
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import dataclasses
import re
import tempfile
import tomllib
from collections.abc import Iterator
from pathlib import Path

DOCS = Path(__file__).resolve().parent.parent
ROOT = DOCS.parent
SCENE_KEYS = DOCS / "reference" / "scene_keys.toml"

#: Example table files the scene examples may name (written next to them when they are loaded).
EXAMPLE_FILES = {
    "hammer.csv": "t,f\n0.0,0.0\n0.01,50.0\n0.02,0.0\n",
    "record.csv": "t,a\n0.0,0.0\n0.5,1.0\n1.0,-1.0\n1.5,0.0\n",
    # the same with units in the header (the units extra): milliseconds and kilonewtons, g
    "hammer-kN.csv": "t [ms], f [kN]\n0,0\n10,0.05\n20,0\n",
    "record-g.csv": "t [s], a [g]\n0.0,0.0\n0.5,0.1\n1.0,-0.1\n1.5,0.0\n",
}


# -- scene keys ---------------------------------------------------------------------------------
def scene_meta(path: Path = SCENE_KEYS) -> dict:
    """``docs/reference/scene_keys.toml``: ``{"base": {...}, "tables": {path: {...}}}``."""
    return tomllib.loads(path.read_text(encoding="utf-8"))


def table_path(where: str | None) -> str:
    """The loader's ``where`` (``"forces[2]"``, ``"damping.rayleigh_targets"``, None) as a table path
    (``"forces[]"``, ``"damping.rayleigh_targets"``, ``""`` for the top level)."""
    return re.sub(r"\[\d+\]", "[]", where or "")


@contextlib.contextmanager
def _recording() -> Iterator[dict[str, set[str]]]:
    """Record ``{table path: accepted keys}`` from every key check the loader makes meanwhile."""
    from springchain.derive.scene_loader import Loader

    seen: dict[str, set[str]] = {}
    original = Loader.keys

    def keys(self, table, allowed, where, *args, **kwargs):
        seen.setdefault(table_path(where), set()).update(allowed)
        return original(self, table, allowed, where, *args, **kwargs)

    Loader.keys = keys
    try:
        yield seen
    finally:
        Loader.keys = original


def example_scenes(meta: dict) -> Iterator[tuple[str, str, dict]]:
    """``(table path, label, scene dict)`` for the example of every described table: the table's
    ``example`` (TOML) merged into the base scene its ``form`` names (top-level keys replaced)."""
    for path, entry in meta["tables"].items():
        for label in ("example", "example_chain"):
            if label not in entry:
                continue
            form = "chain" if label == "example_chain" else entry.get("form", "masses")
            scene = copy.deepcopy(tomllib.loads(meta["base"][form]))
            scene.update(tomllib.loads(entry[label]))
            yield path, label, scene


def load_dict(scene: dict, folder: Path):
    """A scene dict loaded as the file ``folder/example.toml`` (its table files beside it)."""
    from springchain.derive.scene import scene_from_dict

    for name, text in EXAMPLE_FILES.items():
        (folder / name).write_text(text, encoding="utf-8")
    return scene_from_dict(scene, file=str(folder / "example.toml"))


def loader_keys(meta: dict | None = None) -> dict[str, set[str]]:
    """Every table path the loader checks and the keys it accepts there.

    Recorded while the loader reads every bundled scene and every example of
    ``scene_keys.toml`` (each table's keys are checked only when the table is present, so the
    examples bring every table in; the top level lists every table, described or not).
    """
    import springchain as sc

    meta = meta or scene_meta()
    with _recording() as seen, tempfile.TemporaryDirectory() as tmp:
        for name in sc.bundled_scenes():
            sc.load(name)
        for _path, _label, scene in example_scenes(meta):
            load_dict(scene, Path(tmp))
    return seen


def documented_keys(meta: dict) -> dict[str, set[str]]:
    """``{table path: keys}`` that ``scene_keys.toml`` describes (free-form tables have none)."""
    out = {}
    for path, entry in meta["tables"].items():
        if entry.get("kind") == "map":
            continue
        out[path] = set(entry.get("keys", {}))
    return out


def scene_problems(meta: dict | None = None, seen: dict[str, set[str]] | None = None) -> list[str]:
    """Every difference between what the loader accepts and what the reference describes."""
    meta = meta or scene_meta()
    seen = seen if seen is not None else loader_keys(meta)
    doc = documented_keys(meta)
    tables = meta["tables"]
    problems = []
    top_tables = {path.removesuffix("[]") for path in tables if path and "." not in path}
    for path in sorted(set(seen) | set(doc)):
        code, described = seen.get(path, set()), doc.get(path, set())
        if path == "":  # the top level: its values and its tables
            described = described | top_tables
        if path not in seen:
            problems.append(f"scene table {path or '(top level)'!r}: described, but the loader checks no such table")
            continue
        for key in sorted(code - described):
            problems.append(f"scene key {_dotted(path, key)!r}: accepted by the loader, not described")
        for key in sorted(described - code):
            problems.append(f"scene key {_dotted(path, key)!r}: described, but the loader does not accept it")
    for path in tables:
        top = path.split(".")[0].removesuffix("[]")
        if path and top not in seen.get("", set()):
            problems.append(f"scene table {path!r}: described, but {top!r} is no top-level key of the loader")
    for path, entry in tables.items():
        if path in doc:  # a table with keys: each key fully described
            for key, info in entry.get("keys", {}).items():
                missing = [f for f in ("type", "default", "units", "meaning", "example") if f not in info]
                if missing:
                    problems.append(f"scene key {_dotted(path, key)!r}: no {', '.join(missing)}")
        if "example" not in entry and "example_chain" not in entry:
            problems.append(f"scene table {path or '(top level)'!r}: no example")
    return problems


def _dotted(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def scene_signature(scene) -> dict:
    """A scene's validated content as comparable text (file, hash and raw source left out)."""
    import numpy as np

    out = {}
    for f in dataclasses.fields(scene):
        if f.name in ("file", "sha256", "source", "initial_given"):
            continue
        v = getattr(scene, f.name)
        out[f.name] = repr(np.asarray(v).tolist()) if isinstance(v, np.ndarray) else repr(v)
    return out


def _table_header(path: str, entry: dict) -> str:
    if path == "":
        return "Top level"
    name = path.removesuffix("[]")
    if entry.get("kind") == "array":
        return f"`[[{name}]]`"
    if "." in path:
        return f"`{path}` (inline table)"
    return f"`[{name}]`"


def _md(text) -> str:
    """Text for a Markdown table cell: one line, ``|`` escaped, Sphinx roles in MyST form."""
    text = " ".join(str(text).split()) or "—"
    text = re.sub(r":(doc|ref):`([^`]+)`", r"{\1}`\2`", text)
    parts = re.split(r"(`[^`]+`)", text)
    return "".join(q if q.startswith("`") else q.replace("<", "\\<") for q in parts).replace("|", "\\|")


def anchor(path: str) -> str:
    """The label of a table's section (``scene-simulation``, ``scene-springs``, ``scene-top``)."""
    return "scene-" + (re.sub(r"[^a-z0-9]+", "-", path.lower()).strip("-") or "top")


def render_scene_reference(meta: dict | None = None, seen: dict[str, set[str]] | None = None) -> str:
    """MyST Markdown of the scene reference: per table its meaning, a key table and its example."""
    meta = meta or scene_meta()
    seen = seen if seen is not None else loader_keys(meta)
    tables = meta["tables"]
    top_tables = {path.removesuffix("[]") for path in tables if path and "." not in path}
    order = list(tables) + sorted(k for k in seen.get("", set()) if k not in top_tables
                                  and k not in tables.get("", {}).get("keys", {}) and k not in tables)
    lines: list[str] = []
    for path in order:
        entry = tables.get(path, {"meaning": "**Not described yet** (accepted by the loader)."})
        lines += [f"({anchor(path)})=", f"### {_table_header(path, entry)}", "", _md(entry.get("meaning", "")), ""]
        if entry.get("kind") == "map":
            lines += [_md(entry.get("entries", "")), ""]
        keys = dict(entry.get("keys", {}))
        extra = seen.get(path, set()) - set(keys) - (top_tables if path == "" else set())
        for key in sorted(extra):
            keys[key] = {"meaning": "**Not described yet** (accepted by the loader)."}
        if keys:
            lines += ["| key | type | default | units | meaning | example |", "| --- | --- | --- | --- | --- | --- |"]
            for key, info in keys.items():
                example = f"`{info['example']}`" if info.get("example") else "—"
                lines.append(f"| `{key}` | {_md(info.get('type', ''))} | {_md(info.get('default', ''))} | "
                             f"{_md(info.get('units', ''))} | {_md(info.get('meaning', ''))} | {_md(example)} |")
            lines.append("")
        for label, caption in (("example", "Example"), ("example_chain", "Example in a `[chain]` scene")):
            if label in entry:
                form = "chain" if label == "example_chain" else entry.get("form", "masses")
                lines += [f"{caption} (with the `{form}` base scene above it loads as shown; the tests load it):", "",
                          "```toml", entry[label].strip("\n"), "```", ""]
    return "\n".join(lines)


# -- commands -----------------------------------------------------------------------------------
def parser() -> argparse.ArgumentParser:
    from springchain.cli import build_parser

    return build_parser()


def _subparsers(p: argparse.ArgumentParser) -> argparse._SubParsersAction:
    return next(a for a in p._actions if isinstance(a, argparse._SubParsersAction))


def commands(p: argparse.ArgumentParser | None = None) -> dict[str, dict]:
    """``{command: {"summary", "description", "usage", "arguments": [...]}}`` in the parser's order.

    Each argument: ``{"flags": [...], "dest", "metavar", "default", "choices", "required",
    "help"}`` with ``%(default)s`` expanded as ``--help`` prints it.
    """
    p = p or parser()
    sub = _subparsers(p)
    summaries = {a.dest: a.help for a in sub._choices_actions}
    out = {}
    for name, cp in sub.choices.items():
        fmt = cp._get_formatter()
        args = []
        for a in cp._actions:
            if isinstance(a, argparse._HelpAction):
                continue
            args.append({"flags": list(a.option_strings) or [a.dest], "dest": a.dest,
                         "metavar": a.metavar, "default": a.default, "choices": a.choices,
                         "required": bool(a.required) if a.option_strings else a.nargs not in ("?", "*"),
                         "nargs": a.nargs, "help": fmt._expand_help(a) if a.help else "",
                         "positional": not a.option_strings, "flag_only": a.nargs == 0})
        out[name] = {"summary": summaries.get(name) or "", "description": cp.description or "",
                     "usage": cp.format_usage().strip().removeprefix("usage: "), "arguments": args}
    return out


def global_flags(p: argparse.ArgumentParser | None = None) -> set[str]:
    p = p or parser()
    return {s for a in p._actions for s in a.option_strings}


def command_problems(p: argparse.ArgumentParser | None = None) -> list[str]:
    """Commands or arguments the reference could not describe: no summary or no help text."""
    problems = []
    for name, c in commands(p).items():
        if not c["summary"]:
            problems.append(f"command {name!r}: no summary (its function's docstring)")
        for a in c["arguments"]:
            if not a["help"]:
                problems.append(f"command {name!r}, argument {'/'.join(a['flags'])}: no help text")
    return problems


def _code(value) -> str:
    return "`" + str(value).replace("`", "'") + "`"


def _help(text: str) -> str:
    """argparse help as a Markdown table cell: ``|`` escaped everywhere, ``*`` outside code spans."""
    parts = re.split(r"(`[^`]+`)", " ".join(text.split()))
    return "".join((q if q.startswith("`") else q.replace("*", "\\*").replace("<", "\\<")).replace("|", "\\|")
                   for q in parts)


def render_command_reference(p: argparse.ArgumentParser | None = None) -> str:
    """MyST Markdown of every command: summary, description, usage and a table of its arguments."""
    p = p or parser()
    lines = ["Options of `springchain` itself: " + ", ".join(_code(f) for f in sorted(global_flags(p))) + ".", ""]
    for name, c in commands(p).items():
        lines += [f"(command-{name})=", f"## `springchain {name}`", "", f"*{_help(c['summary'])}.*", ""]
        if c["description"]:
            lines += [_help(c["description"]), ""]
        lines += ["```text", " ".join(c["usage"].split()), "```", ""]
        lines += ["| argument | default | meaning |", "| --- | --- | --- |"]
        for a in c["arguments"]:
            if a["positional"]:
                flag = _code(a["dest"].upper())
            else:
                flag = ", ".join(_code(f) for f in a["flags"])
                if a["metavar"]:
                    flag += " " + _code(a["metavar"])
                elif a["choices"] and not a["flag_only"] and len(a["choices"]) <= 4:
                    flag += " " + _code("{" + ",".join(map(str, a["choices"])) + "}")
            if a["required"]:
                default = "required"
            elif a["default"] in (None, False) or a["flag_only"]:
                default = "—"
            else:
                default = _code(a["default"])
            lines.append(f"| {flag} | {default} | {_help(a['help'])} |")
        lines.append("")
    return "\n".join(lines)


#: ``springchain CMD ...`` in prose or code: the command and the rest of its line.
_MENTION = re.compile(r"(?<![\w./-])(?<!import )(?<!from )springchain\s+(?P<cmd>[a-z][a-z-]*)(?P<rest>[^`\n|]*)")
_FLAG = re.compile(r"(?<![\w-])(--[a-z][a-z0-9-]*)")


_CODE = re.compile(r"^```.*?^```|``[^`\n]+``|`[^`\n]+`", re.S | re.M)


def code_of(text: str, python: bool = False) -> str:
    """The code in a page: fenced and indented blocks and inline literals (all of a Python file)."""
    if python:  # the code, without docstrings and comments (prose)
        text = re.sub(r'"""(?:.|\n)*?"""', "", text)
        return re.sub(r"#.*$", "", text, flags=re.M)
    code = "\n".join(m.group(0) for m in _CODE.finditer(text))
    return re.sub(r"(?:^|\s)#\s.*$", "", code, flags=re.M)  # comments are prose


def command_mentions(text: str) -> Iterator[tuple[str, list[str], str]]:
    """``(command, flags, line)`` for every ``springchain COMMAND ...`` in the code ``text``."""
    for m in _MENTION.finditer(text):
        yield m.group("cmd"), _FLAG.findall(m.group("rest")), m.group(0)


def mention_problems(files, p: argparse.ArgumentParser | None = None) -> list[str]:
    """Commands and flags named in ``files`` that the parser does not have."""
    p = p or parser()
    cmds = commands(p)
    glob = global_flags(p) | {"--help"}
    problems = []
    for f in files:
        text = code_of(Path(f).read_text(encoding="utf-8"), python=Path(f).suffix == ".py")
        for cmd, flags, line in command_mentions(text):
            if cmd not in cmds:
                problems.append(f"{Path(f).relative_to(ROOT)}: {line.strip()!r}: no command {cmd!r}")
                continue
            known = {s for a in cmds[cmd]["arguments"] for s in a["flags"]} | glob
            for flag in flags:
                if flag not in known:
                    problems.append(f"{Path(f).relative_to(ROOT)}: {line.strip()!r}: {cmd} has no flag {flag}")
    return problems


def documentation_files() -> list[Path]:
    """The README and every page and example of the documentation."""
    files = [ROOT / "README.md"]
    for pattern in ("**/*.md", "**/*.rst", "examples/*.py"):
        files += [f for f in DOCS.glob(pattern) if "_build" not in f.parts and "auto_examples" not in f.parts
                  and "generated" not in f.parts]
    return sorted(set(files))
