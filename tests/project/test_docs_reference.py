"""The documentation's references against the code: scene keys, commands and flags.

The scene reference lists what the loader accepts (recorded from the loader's own key checks) and
describes it from ``docs/reference/scene_keys.toml``; the command reference is rendered from
``springchain.cli.build_parser()``. These tests fail when a scene key or a command flag exists in
the code but not in the reference, or the reverse; when an example of the reference does not load;
when a documented default is not the loader's; and when the README or a documentation page names
a command or flag that does not exist. They need no Sphinx (the docs build checks the same).
"""

from __future__ import annotations

import copy
import importlib.util
import re
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("springchain_reference", ROOT / "docs" / "_ext" / "springchain_reference.py")
ref = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(ref)


@pytest.fixture(scope="module")
def meta():
    return ref.scene_meta()


@pytest.fixture(scope="module")
def seen(meta):
    return ref.loader_keys(meta)


# -- scene keys --------------------------------------------------------------------------------------
def test_every_scene_key_the_loader_accepts_is_described_and_the_reverse(meta, seen):
    # the loader checks keys in these tables at least (a hand-written floor, independent of the recorder)
    floor = {"": {"name", "parameters", "masses", "springs", "chain", "simulation"},
             "springs[]": {"between", "k", "k3", "potential"}, "simulation": {"dt", "steps", "record_every"},
             "chain": {"n", "mass", "k", "left", "right"}, "damping.rayleigh_targets": {"zeta", "modes"}}
    for path, keys in floor.items():
        assert keys <= seen[path], (path, seen.get(path))
    assert ref.scene_problems(meta, seen) == []


def test_a_key_added_to_the_loader_fails_until_described(monkeypatch, meta):
    import springchain.derive.scene as scene_mod

    monkeypatch.setattr(scene_mod, "SIMULATION_KEYS", (*scene_mod.SIMULATION_KEYS, "units"))
    monkeypatch.setattr(scene_mod, "TOP_KEYS", (*scene_mod.TOP_KEYS, "bands"))
    problems = ref.scene_problems(meta, ref.loader_keys(meta))
    assert any("'simulation.units'" in p and "not described" in p for p in problems), problems
    assert any("'bands'" in p and "not described" in p for p in problems), problems
    text = ref.render_scene_reference(meta, ref.loader_keys(meta))
    assert "`units`" in text and "Not described yet" in text  # listed at once, flagged


def test_a_described_key_the_loader_does_not_accept_fails(meta, seen):
    stale = copy.deepcopy(meta)
    stale["tables"]["simulation"]["keys"]["t_end"] = dict(stale["tables"]["simulation"]["keys"]["dt"])
    stale["tables"]["bands"] = {"meaning": "x", "example": "[bands]\n"}
    problems = ref.scene_problems(stale, seen)
    assert any("'simulation.t_end'" in p and "does not accept" in p for p in problems), problems
    assert any("'bands'" in p for p in problems), problems


def test_every_key_is_fully_described_and_every_table_has_an_example(meta):
    for path, entry in meta["tables"].items():
        assert "example" in entry or "example_chain" in entry, path
        for key, info in entry.get("keys", {}).items():
            for field in ("type", "default", "units", "meaning", "example"):
                assert info.get(field), (path, key, field)


def test_the_reference_examples_load(meta, tmp_path):
    n = 0
    for path, label, scene in ref.example_scenes(meta):
        loaded = ref.load_dict(scene, tmp_path)
        assert loaded.name == scene["name"], (path, label)
        n += 1
    assert n >= len(meta["tables"])


def test_each_key_example_loads_in_its_table(meta, tmp_path):
    """A key's one-line example, put into its table's example, still loads (modal damping needs one
    ratio per mode, so scalar examples only)."""
    examples = {(p, lab): s for p, lab, s in ref.example_scenes(meta)}
    for path, entry in meta["tables"].items():
        if path in ("", "damping.rayleigh_targets") or entry.get("kind") == "map":
            continue
        label = "example" if "example" in entry else "example_chain"
        for key, info in entry.get("keys", {}).items():
            scene = copy.deepcopy(examples[(path, label)])
            value = tomllib.loads(info["example"])[key]
            target = scene
            for part in path.removesuffix("[]").split("."):  # a table inside a table: "cell.springs[]"
                target = target[part]
            if isinstance(target, list):
                target = target[0]
                if key in ("k", "k3"):
                    target.pop("potential", None)
                if key == "potential":
                    target.pop("k", None), target.pop("k3", None)
                if key == "between":
                    continue  # the ends depend on the scene's masses
                if key in ("f", "table"):
                    target.pop("f", None), target.pop("table", None)
            elif path == "chain" and key == "potential":
                target.pop("k", None), target.pop("k3", None)
            elif path == "ground":
                target.clear()
            elif path == "damping":
                target.clear()
            if path == "chain" and key == "n":
                value = 20
            if path == "chain" and key == "potential":
                scene["parameters"]["alpha"] = 0.25
            target[key] = value
            ref.load_dict(scene, tmp_path)


def test_documented_defaults_are_the_loaders(meta, tmp_path):
    """With the key left out and with the key set to its documented default, the same scene."""
    examples = {(p, lab): s for p, lab, s in ref.example_scenes(meta)}
    checked = 0
    for path, entry in meta["tables"].items():
        label = "example" if "example" in entry else "example_chain"
        for key, info in entry.get("keys", {}).items():
            if "default_value" not in info:
                continue
            without = copy.deepcopy(examples[(path, label)])
            table = without if path == "" else without[path]
            table.pop(key, None)
            with_default = copy.deepcopy(without)
            (with_default if path == "" else with_default[path])[key] = info["default_value"]
            a, b = ref.load_dict(without, tmp_path), ref.load_dict(with_default, tmp_path)
            assert ref.scene_signature(a) == ref.scene_signature(b), (path, key)
            checked += 1
            # and another value would change the scene (the comparison can fail)
            if isinstance(info["default_value"], (int, float)) and not isinstance(info["default_value"], bool):
                other = copy.deepcopy(without)
                (other if path == "" else other[path])[key] = info["default_value"] * 2
                assert ref.scene_signature(ref.load_dict(other, tmp_path)) != ref.scene_signature(a), (path, key)
    assert checked >= 5


# -- commands and flags ------------------------------------------------------------------------------
def test_every_command_and_flag_is_in_the_command_reference():
    parser = ref.parser()
    text = ref.render_command_reference(parser)
    cmds = ref.commands(parser)
    assert {"run", "modes", "derive", "simulate", "bench", "plan", "frf", "sweep", "rsa"} <= set(cmds)
    for name, c in cmds.items():
        section = text.split(f"(command-{name})=\n", 1)[1].split("\n(command-", 1)[0]
        for a in c["arguments"]:
            shown = a["dest"].upper() if a["positional"] else a["flags"][0]
            assert f"`{shown}`" in section, (name, shown)
        assert c["summary"], name
    assert ref.command_problems(parser) == []
    assert "`--version`" in text


def test_a_flag_added_to_the_parser_appears_and_without_help_fails():
    parser = ref.parser()
    sub = ref._subparsers(parser)
    sub.choices["simulate"].add_argument("--bands", metavar="B")
    assert "`--bands`" in ref.render_command_reference(parser)
    assert any("--bands" in p and "no help" in p for p in ref.command_problems(parser))


def test_documentation_names_only_existing_commands_and_flags():
    files = ref.documentation_files()
    assert ROOT / "README.md" in files and len(files) > 10
    assert ref.mention_problems(files) == []


def test_a_removed_flag_named_in_the_docs_is_caught(tmp_path):
    page = ref.DOCS / "_probe_page.md"
    try:
        page.write_text("Run `springchain simulate seed --dt 0.1 --no-such-flag`.\n"
                        "```bash\nspringchain bogus seed\n```\n", encoding="utf-8")
        problems = ref.mention_problems([page])
    finally:
        page.unlink()
    assert any("no flag --no-such-flag" in p for p in problems), problems
    assert any("no command 'bogus'" in p for p in problems), problems
    assert not any("no flag --dt" in p for p in problems), problems


def test_readme_command_table_lists_every_command():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\| `springchain ([a-z]+)", readme, re.M)
    assert set(rows) == set(ref.commands()), sorted(rows)


# -- benchmark tables: written by the scripts, with their provenance ------------------------------------
def _report_module():
    spec = importlib.util.spec_from_file_location("springchain_benchmarks__report_test", ROOT / "benchmarks" / "_report.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_benchmark_script_writes_its_markdown_file():
    scripts = sorted((ROOT / "benchmarks").glob("[a-z]*.py"))
    assert len(scripts) >= 10
    for script in scripts:
        text = script.read_text(encoding="utf-8")
        assert "_report.add_option(" in text and "_report.recorded(" in text, script.name


def test_benchmark_tables_in_the_docs_name_their_script_command_machine_and_date():
    results = sorted((ROOT / "docs" / "benchmarks").glob("*.md"))
    assert results, "the Benchmarks page includes at least one script-written table"
    for f in results:
        head = f.read_text(encoding="utf-8").splitlines()[:6]
        assert head[0] == f"<!-- written by benchmarks/{f.stem}.py --markdown: do not edit; run the command to regenerate -->", f
        assert head[1].startswith(f"- **command:** `python benchmarks/{f.stem}.py ") and "--markdown" in head[1], f
        assert head[2].startswith("- **date:** ") and head[3].startswith("- **machine:** "), f
        assert (ROOT / "benchmarks" / f"{f.stem}.py").is_file(), f


def test_report_keeps_tables_and_fences_text(tmp_path, capsys):
    report = _report_module()
    out = tmp_path / "x.md"
    with report.recorded(str(out), "benchmarks/x.py", ["--n", "3"]):
        print("N = 3, two rounds")
        print("| a | b |\n|---|---|\n| 1 | 2 |")
        print("ratio 1.5")
    assert "N = 3, two rounds" in capsys.readouterr().out  # still printed
    text = out.read_text(encoding="utf-8")
    assert "- **command:** `python benchmarks/x.py --n 3`" in text
    assert "```text\nN = 3, two rounds\n```\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\n```text\nratio 1.5\n```" in text
