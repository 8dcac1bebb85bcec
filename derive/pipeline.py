"""From a scene file to a generated module: derive, render, check freshness, write, load.

Bundled scenes use the checked-in ``generated/<name>.py`` when it matches the
scene's hash. Any other scene (a user's file anywhere on disk) is derived
into a per-user cache (``$SPRINGCHAIN_CACHE`` or ``~/.cache/springchain``),
never into the installed package or the repository.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

from numeric.files import atomic_write_text

from .scene import Scene, bundled_scene_dir, load_scene

GENERATED_PACKAGE = "generated"


@dataclass(frozen=True)
class Derivation:
    """A scene's symbolic model, its modes and the rendered module source."""

    scene: Scene
    model: object
    modes: object
    source: str


def is_bundled(scene: Scene) -> bool:
    try:
        return Path(scene.file).resolve().parent == bundled_scene_dir().resolve()
    except OSError:
        return False


def derive(scene: Scene, budget: float | None = None) -> Derivation:
    """Build the model, its modes and the module text (SymPy is imported here)."""
    if scene.chain is not None:
        from .chain import ChainModel, chain_modes, render_chain_module

        model = ChainModel(scene)
        modes = chain_modes(model)
        return Derivation(scene, model, modes, render_chain_module(model, bundled=is_bundled(scene)))
    from .codegen import render_module
    from .model import Model
    from .modes import DEFAULT_BUDGET, closed_form_modes

    model = Model(scene)
    modes = closed_form_modes(model, budget=DEFAULT_BUDGET if budget is None else budget)
    return Derivation(scene, model, modes, render_module(model, modes, bundled=is_bundled(scene)))


def generated_dir() -> Path:
    """The folder of the checked-in generated modules."""
    return Path(__file__).resolve().parent.parent / GENERATED_PACKAGE


def module_path(scene: Scene, out_dir: Path | None = None) -> Path:
    return (out_dir or generated_dir()) / f"{scene.name}.py"


def _code_version() -> str:
    """Hash of the derive/ sources: cached modules are redone when the generator changes."""
    h = hashlib.sha256()
    for p in sorted(Path(__file__).resolve().parent.glob("*.py")):
        h.update(p.read_bytes())
    return h.hexdigest()[:12]


def cache_dir() -> Path:
    base = os.environ.get("SPRINGCHAIN_CACHE")
    if base:
        return Path(base)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "springchain"


def _import_file(path: Path, name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def bundled_module(scene: Scene) -> ModuleType | None:
    """The checked-in generated module of a bundled scene if its scene hash matches."""
    if not is_bundled(scene) or not module_path(scene).exists():
        return None
    module = importlib.import_module(f"{GENERATED_PACKAGE}.{scene.name}")
    return module if getattr(module, "SCENE_SHA256", None) == scene.sha256 else None


def load_module(scene: Scene) -> tuple[ModuleType, str]:
    """The generated module for a scene, and where it came from ("generated" or "cache").

    A bundled scene with a matching checked-in module needs no SymPy at all.
    """
    module = bundled_module(scene)
    if module is not None:
        return module, "generated"
    path = cache_dir() / f"{scene.name}-{scene.sha256[:16]}-{_code_version()}.py"
    if not path.exists():
        atomic_write_text(path, derive(scene).source)
    return _import_file(path, f"springchain_cache_{scene.name}_{scene.sha256[:16]}"), "cache"


def check(scene: Scene, out_dir: Path | None = None) -> tuple[bool, str]:
    """Whether the module on disk equals a fresh render. Writes nothing."""
    path = module_path(scene, out_dir)
    fresh = derive(scene).source
    if not path.exists():
        return False, f"{path}: missing (run `springchain derive {scene.file}`)"
    if path.read_text(encoding="utf-8") != fresh:
        return False, f"{path}: stale (run `springchain derive {scene.file}`)"
    return True, f"{path}: fresh"


def write(derivation: Derivation, out_dir: Path | None = None) -> Path:
    path = module_path(derivation.scene, out_dir)
    atomic_write_text(path, derivation.source)
    # a re-import in this process must see the new text
    sys.modules.pop(f"{GENERATED_PACKAGE}.{derivation.scene.name}", None)
    return path


__all__ = ["Derivation", "derive", "load_module", "check", "write", "load_scene", "is_bundled"]
