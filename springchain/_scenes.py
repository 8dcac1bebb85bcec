"""The scenes that ship with springchain (package data) and how a SCENE argument is resolved.

A SCENE is a path to a TOML file or the name of a bundled scene (``seed``,
``building``, ...). A path wins when both exist.
"""

from __future__ import annotations

from pathlib import Path

from .derive.errors import SceneError


def bundled_scene_dir() -> Path:
    """The installed folder of the bundled scenes (``springchain.scenes``)."""
    from . import scenes

    return Path(next(iter(scenes.__path__))).resolve()


def bundled_scenes() -> list[Path]:
    """Every bundled scene file, sorted by name."""
    return sorted(bundled_scene_dir().glob("*.toml"))


def bundled_names() -> list[str]:
    return [p.stem for p in bundled_scenes()]


def is_bundled(path: str | Path) -> bool:
    """Whether a scene file is one of the bundled ones."""
    try:
        return Path(path).resolve().parent == bundled_scene_dir()
    except OSError:
        return False


def resolve(source: str | Path) -> Path:
    """The scene file a SCENE argument names: an existing path, else a bundled scene's name.

    Raises
    ------
    SceneError
        When ``source`` is neither (naming the bundled scenes).
    """
    path = Path(source)
    if path.exists() or path.suffix == ".toml" or len(path.parts) > 1:
        return path
    candidate = bundled_scene_dir() / f"{source}.toml"
    if candidate.is_file():
        return candidate
    names = bundled_names()
    from .derive.scene import did_you_mean

    raise SceneError(str(source), None, f"no such file, and not a bundled scene{did_you_mean(str(source), names)}; "
                     f"accepted: a path to a TOML scene or one of {', '.join(names)}")


def load(source):
    """Read and validate a scene (:func:`springchain.load`): a path to a TOML file, the name of a
    bundled scene, a :class:`~springchain.derive.scene.Scene` (returned as it is) or a dict (through
    :func:`springchain.scene_from_dict`).

    Raises
    ------
    SceneError
        (a ``ValueError``) with the one-line message the command prints.
    """
    from .derive.scene import Scene, load_scene
    from .numeric.progress import phase

    if isinstance(source, Scene):
        return source
    if isinstance(source, dict):
        from .derive.scene import scene_from_dict

        return scene_from_dict(source)
    path = resolve(source)
    with phase(f"reading {Path(path).name}"):  # a long chain's expressions are checked at every index
        return load_scene(path)


def display_path(path: Path) -> Path:
    """``path`` relative to the current folder when it lies below it (shorter messages)."""
    try:
        return path.resolve().relative_to(Path.cwd().resolve())
    except ValueError:
        return path
