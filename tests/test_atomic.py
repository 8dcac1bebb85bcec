"""Nothing lost: files are written to a temporary file and renamed into place.

* an exception (or Ctrl-C) mid-write leaves the previous file byte-identical
  and no temporary file behind, for text, NPZ output and generated modules;
* two ``springchain derive`` processes started together on the same scene
  leave one valid module equal to a fresh render;
* ``springchain derive --check`` never writes, whether the module is fresh,
  stale or missing.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import springchain.numeric.io.files as files
from springchain.cli import main
from springchain.derive.scene import load_scene
from springchain.numeric.io.files import atomic_path, atomic_write_bytes, atomic_write_text

OLD = "old content\nline 2\n"


def listing(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


@pytest.fixture
def old_file(tmp_path) -> Path:
    path = tmp_path / "out" / "module.py"
    path.parent.mkdir()
    path.write_text(OLD, encoding="utf-8")
    os.chmod(path, 0o640)
    return path


def _fail_after_temp_file(monkeypatch, exc: BaseException, seen: list[Path]) -> None:
    """Make the fsync before the rename fail, once the temporary file holds the new data."""

    def failing(fd):
        for p in Path(seen[0]).iterdir():
            if p.name.startswith(files.TEMP_PREFIX):
                seen.append(p)
        raise exc

    monkeypatch.setattr(files.os, "fsync", failing)


@pytest.mark.parametrize("exc", [OSError(28, "No space left on device"), KeyboardInterrupt(),
                                 RuntimeError("boom")], ids=["ENOSPC", "ctrl-c", "error"])
def test_failure_mid_write_keeps_the_old_file(old_file, monkeypatch, exc):
    seen: list[Path] = [old_file.parent]
    _fail_after_temp_file(monkeypatch, exc, seen)
    with pytest.raises(type(exc)):
        atomic_write_text(old_file, "new content that must not appear\n" * 100)
    assert len(seen) == 2, "the temporary file existed while writing"
    assert old_file.read_text(encoding="utf-8") == OLD
    assert listing(old_file.parent) == ["module.py"]  # no temporary file left


def test_partial_write_keeps_the_old_file(old_file):
    """The writer dies after writing half of the data into the temporary file."""
    with pytest.raises(ZeroDivisionError):
        with atomic_path(old_file) as tmp:
            assert tmp.parent == old_file.parent and tmp.exists()
            tmp.write_text("half of the new", encoding="utf-8")
            1 / 0
    assert old_file.read_text(encoding="utf-8") == OLD
    assert listing(old_file.parent) == ["module.py"]


def test_success_replaces_and_keeps_the_mode(old_file, tmp_path):
    atomic_write_text(old_file, "new\n")
    assert old_file.read_text(encoding="utf-8") == "new\n"
    assert old_file.stat().st_mode & 0o777 == 0o640
    assert listing(old_file.parent) == ["module.py"]
    fresh = tmp_path / "deep" / "er" / "x.bin"
    atomic_write_bytes(fresh, b"\x00\x01")
    umask = os.umask(0)
    os.umask(umask)
    assert fresh.read_bytes() == b"\x00\x01" and fresh.stat().st_mode & 0o777 == 0o666 & ~umask


def test_npz_failure_keeps_the_old_output(tmp_path, monkeypatch):
    from springchain.numeric.io import npz as simulate  # the NPZ writer of `springchain simulate`

    path = tmp_path / "scene.npz"
    np.savez(path, t=np.arange(3.0))
    before = path.read_bytes()

    def dying_savez(fh, **arrays):
        fh.write(b"PK\x03\x04 partial zip")
        raise MemoryError("out of memory while writing")

    monkeypatch.setattr(simulate.np, "savez", dying_savez)

    class Run:
        t = np.arange(5.0)
        x = v = np.zeros((5, 2))

    with pytest.raises(MemoryError):
        simulate.write_npz(path, {"verlet": Run()})
    assert path.read_bytes() == before
    assert listing(tmp_path) == ["scene.npz"]


def test_generated_module_survives_a_failed_derive(seed_derivation, tmp_path, monkeypatch):
    """pipeline.write: an error mid-write keeps the previous module; the retry writes the new one."""
    from springchain import _modules as pipeline

    out = tmp_path / "gen"
    path = pipeline.write(seed_derivation, out)
    first = path.read_bytes()
    assert first == seed_derivation.source.encode("utf-8")
    path.write_bytes(first + b"# previous version\n")
    previous = path.read_bytes()
    monkeypatch.setattr(files.os, "fsync", lambda fd: (_ for _ in ()).throw(OSError(5, "I/O error")))
    with pytest.raises(OSError):
        pipeline.write(seed_derivation, out)
    assert path.read_bytes() == previous and listing(out) == [path.name]
    monkeypatch.undo()
    pipeline.write(seed_derivation, out)
    assert path.read_bytes() == first and listing(out) == [path.name]


def test_ctrl_c_during_cli_derive_keeps_the_module(seed_path, tmp_path, monkeypatch, capsys):
    out = tmp_path / "gen"
    out.mkdir()
    module = out / "seed.py"
    module.write_text(OLD, encoding="utf-8")

    def interrupted(fd):
        raise KeyboardInterrupt

    monkeypatch.setattr(files.os, "fsync", interrupted)
    status = main(["derive", str(seed_path), "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 130 and "interrupted" in err and "Traceback" not in err
    assert module.read_text(encoding="utf-8") == OLD and listing(out) == ["seed.py"]


# -- derive --check ------------------------------------------------------------------------------
@pytest.fixture
def forbid_writes(monkeypatch):
    """Any atomic write or rename during the test fails it."""

    def refuse(*args, **kwargs):
        raise AssertionError("--check tried to write")

    monkeypatch.setattr(files.os, "replace", refuse)
    monkeypatch.setattr(files.tempfile, "mkstemp", refuse)


def _snapshot(folder: Path) -> dict[str, tuple[int, bytes]]:
    return {p.name: (p.stat().st_mtime_ns, p.read_bytes()) for p in sorted(folder.iterdir())}


@pytest.mark.parametrize("state", ["fresh", "stale", "missing"])
def test_check_never_writes(state, seed_path, seed_derivation, tmp_path, monkeypatch, capsys, forbid_writes):
    monkeypatch.setenv("SPRINGCHAIN_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "gen"
    out.mkdir()
    (out / "other.py").write_text("# unrelated\n", encoding="utf-8")
    if state != "missing":
        text = seed_derivation.source if state == "fresh" else seed_derivation.source.replace("def ", "def  ", 1)
        (out / "seed.py").write_bytes(text.encode("utf-8"))
    for p in out.iterdir():
        os.utime(p, ns=(1_000_000_000, 1_000_000_000))  # an old mtime: any rewrite would change it
    before = _snapshot(out)
    status = main(["derive", str(seed_path), "--out", str(out), "--check"])
    printed = capsys.readouterr().out
    assert status == (0 if state == "fresh" else 1)
    assert state in printed
    assert _snapshot(out) == before
    assert not (tmp_path / "cache").exists() or listing(tmp_path / "cache") == []


# -- concurrent writers ------------------------------------------------------------------------------
def test_two_concurrent_derives_leave_one_valid_module(seed_path, tmp_path):
    scene_file = tmp_path / "twin.toml"
    scene_file.write_text(seed_path.read_text(encoding="utf-8").replace('name = "seed"', 'name = "twin"'),
                          encoding="utf-8")
    out = tmp_path / "gen"
    env = {**os.environ, "SPRINGCHAIN_CACHE": str(tmp_path / "cache"), "OPENBLAS_NUM_THREADS": "1",
           "PYTHONDONTWRITEBYTECODE": "1"}
    cmd = [sys.executable, "-c", "import sys; from springchain.cli import main; raise SystemExit(main(sys.argv[1:]))",
           "derive", str(scene_file), "--out", str(out)]
    procs = [subprocess.Popen(cmd, env=env, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True)
             for _ in range(2)]
    results = [p.communicate(timeout=300) for p in procs]
    for p, (stdout, stderr) in zip(procs, results):
        assert p.returncode == 0, stderr
        assert "Traceback" not in stderr
    assert listing(out) == ["twin.py"]  # one module, no temporary files
    from springchain import _modules as pipeline

    fresh = pipeline.derive(load_scene(scene_file)).source
    text = (out / "twin.py").read_text(encoding="utf-8")
    assert text == fresh
    compile(text, "twin.py", "exec")  # valid Python
