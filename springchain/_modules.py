"""Generated modules on disk: the checked-in ones of bundled scenes, a per-user cache for any other
scene, freshness checks and atomic writes.

Bundled scenes use the checked-in ``springchain.generated.<name>`` when it matches the scene's
hash (no SymPy needed). Any other scene (a user's file anywhere on disk) is derived into a
per-user cache (``$SPRINGCHAIN_CACHE`` or ``~/.cache/springchain``), never into the installed
package.
"""

from __future__ import annotations

import hashlib
import importlib
import os
import sys
from pathlib import Path
from types import ModuleType

from ._scenes import is_bundled
from .derive.scene import Scene
from .numeric.io.files import atomic_write_text
from .numeric.io.imports import import_file

GENERATED = __package__ + ".generated"


def derive(scene: Scene):
    """:func:`springchain.derive.pipeline.derive` with the bundled flag filled in."""
    from .derive.pipeline import derive as _derive

    return _derive(scene, bundled=is_bundled(scene.file))


def check_linear_outputs(scene: Scene) -> None:
    """Refuse in one line the outputs of the linearisation (modes, frf, rsa, state space, sensitivities)
    of a cubic ``[chain]`` under a constant load (:func:`springchain.derive.chain.check_linear_outputs`);
    SymPy is imported only for such chains."""
    if scene.chain is None or scene.chain.k3 is None:
        return
    from .derive.chain import check_linear_outputs as check  # SymPy (~0.5 s): only for cubic chains

    check(scene)


def generated_dir() -> Path:
    """The folder of the checked-in generated modules (``springchain.generated``)."""
    from . import generated

    return Path(next(iter(generated.__path__))).resolve()


def module_path(scene: Scene, out_dir: Path | None = None) -> Path:
    return (out_dir or generated_dir()) / f"{scene.name}.py"


def _code_version() -> str:
    """Hash of the derive/ sources (subpackages included): cached modules are redone when the generator changes."""
    from . import derive as derive_pkg

    h = hashlib.sha256()
    for p in sorted(Path(next(iter(derive_pkg.__path__))).rglob("*.py")):  # subpackages (derive/bands) too
        h.update(p.read_bytes())
    return h.hexdigest()[:12]


def cache_dir() -> Path:
    base = os.environ.get("SPRINGCHAIN_CACHE")
    if base:
        return Path(base)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "springchain"


def bundled_module(scene: Scene) -> ModuleType | None:
    """The checked-in generated module of a bundled scene if its scene hash matches."""
    if not is_bundled(scene.file) or not module_path(scene).exists():
        return None
    from .generated.contract import ContractError
    from .numeric.system import interface

    module = importlib.import_module(f"{GENERATED}.{scene.name}")
    try:
        return module if interface(module).scene_sha256 == scene.sha256 else None
    except ContractError:  # written by another version: derive it afresh
        return None


def load_module(scene: Scene) -> tuple[ModuleType, str]:
    """The generated module for a scene, and where it came from ("generated" or "cache")."""
    module = bundled_module(scene)
    if module is not None:
        return module, "generated"
    path = cache_dir() / f"{scene.name}-{scene.sha256[:16]}-{_code_version()}.py"
    if not path.exists():
        atomic_write_text(path, derive(scene).source)
    return import_file(path, f"springchain_cache_{scene.name}_{scene.sha256[:16]}"), "cache"


def load_tables(scene: Scene) -> dict:
    """The scene's tables as keyword arguments of ``System.from_module`` (data, never source)."""
    ground = scene.ground
    return {"tables": tuple((tf.table.t, tf.table.y) for tf in scene.table_forces),
            "ground_table": None if ground is None or ground.table is None else (ground.table.t, ground.table.y)}


def system_of(scene: Scene):
    """The generated module bound to the scene's parameters and tables (no SymPy for fresh bundled
    scenes), and where the module came from: ``(System, "generated" | "cache")``."""
    from .numeric.system import System

    module, origin = load_module(scene)  # keyed by the scene's whole content: a changed scene has its own
    return System.from_module(module, scene.parameters, **load_tables(scene)), origin


def check(scene: Scene, out_dir: Path | None = None) -> tuple[bool, str]:
    """Whether the module on disk equals a fresh render. Writes nothing."""
    path = module_path(scene, out_dir)
    fresh = derive(scene).source
    default = out_dir is None or Path(out_dir).resolve() == (Path.cwd() / "generated").resolve()
    fix = f"run `springchain derive {scene.file}" + ("" if default else f" --out {out_dir}") + "`"
    if not path.exists():
        return False, f"{path}: missing ({fix})"
    if path.read_text(encoding="utf-8") != fresh:
        return False, f"{path}: stale ({fix})"
    return True, f"{path}: fresh"


def write(derivation, out_dir: Path | None = None) -> Path:
    """Write a derivation's module atomically into ``out_dir`` (default: the package's generated/)."""
    path = module_path(derivation.scene, out_dir)
    atomic_write_text(path, derivation.source)
    sys.modules.pop(f"{GENERATED}.{derivation.scene.name}", None)  # a re-import must see the new text
    return path
