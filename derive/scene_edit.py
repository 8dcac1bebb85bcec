"""Scenes made or changed from Python, validated by the very loader of scene files.

* :func:`from_dict` (behind :func:`derive.scene.scene_from_dict`) — the TOML schema as a dict (tables
  may be arrays, initial states arrays);
* :func:`with_parameters`, :func:`with_initial` — a copy of a scene with some values changed;
* :func:`validate_replaced` — what ``dataclasses.replace(scene, ...)`` goes through.

Each returns a new :class:`~springchain.derive.scene.Scene` built from TOML-shaped data by
:func:`~springchain.derive.scene.build_scene`, so every check and every one-line
:class:`~springchain.derive.errors.SceneError` of a scene file applies. This module sits below
:mod:`derive.scene` (which calls it from ``Scene``'s methods): it reaches the loader through the
scene's class (``Scene.from_data``) or, for a dict, the builder :func:`derive.scene.scene_from_dict`
passes in, and never imports it. A changed scene's
``sha256`` (the key of the generated-module cache) is a hash of its whole content, so it never
shares a cached module with the file it came from. SymPy is not imported here.
"""

from __future__ import annotations

import copy
import hashlib
import math
from dataclasses import fields
from numbers import Real
from typing import TYPE_CHECKING, Callable

import numpy as np

from .errors import SceneError, show
from .scene_loader import did_you_mean

if TYPE_CHECKING:  # the class only: scene.py imports this module
    from .scene import Scene

#: What a dict scene is called in messages when no file name is given.
DICT_FILE = "<dict>"
#: Scene fields ``dataclasses.replace`` may change, and where each lives in the TOML data.
REPLACEABLE = {"parameters": ("parameters",), "x0": ("initial", "x"), "v0": ("initial", "v"),
               "dt": ("simulation", "dt"), "steps": ("simulation", "steps"),
               "record_every": ("simulation", "record_every"), "name": ("name",),
               "description": ("description",)}


def content_sha256(data) -> str:
    """SHA-256 of TOML-shaped data in its order (mass order is coordinate order), arrays by value."""
    h = hashlib.sha256(b"springchain scene content v1\0")

    def feed(v) -> None:
        if isinstance(v, dict):
            h.update(b"{%d" % len(v))
            for k, item in v.items():
                feed(str(k))
                feed(item)
            h.update(b"}")
        elif isinstance(v, (list, tuple)):
            h.update(b"[%d" % len(v))
            for item in v:
                feed(item)
            h.update(b"]")
        elif isinstance(v, np.ndarray):
            a = np.ascontiguousarray(v, dtype=float)
            h.update(b"a" + repr(a.shape).encode() + a.tobytes())
        elif isinstance(v, bool):
            h.update(b"T" if v else b"F")
        elif isinstance(v, int):
            h.update(b"i%d;" % v)
        elif isinstance(v, float):
            h.update(b"f" + repr(v).encode() + b";")
        else:
            text = str(v).encode("utf-8", "surrogatepass")
            h.update(b"s%d:" % len(text) + text)

    feed(data)
    return h.hexdigest()


def _plain(value, path: tuple):
    """``value`` as TOML-shaped data: NumPy scalars as Python numbers, tuples as lists; arrays kept as
    arrays only where an array is data (initial states, tables), elsewhere as lists."""
    if isinstance(value, dict):
        return {k: _plain(v, path + (k,)) for k, v in value.items()}
    array_ok = path[:1] == ("initial",) or "table" in path
    if isinstance(value, np.ndarray):
        return np.array(value) if array_ok and value.dtype.kind in "iuf" else _plain(value.tolist(), path)
    if isinstance(value, (list, tuple)):
        return [_plain(v, path + (j,)) for j, v in enumerate(value)]
    if isinstance(value, np.generic):
        return value.item()
    return value


def _data(scene: Scene) -> dict:
    """A deep copy of the TOML data ``scene`` was built from (plain dicts and lists)."""
    return copy.deepcopy(dict(scene.source))


def _finish(data: dict, file: str, build: Callable, key_of_file: str | None = None) -> Scene:
    """Build (``build(data, file, sha)``, the scene loader) and key a scene: ``key_of_file`` (a file's
    own hash) or the hash of ``data``."""
    scene = build(data, file, "0" * 64)
    object.__setattr__(scene, "sha256", key_of_file or content_sha256(data))
    return scene


def from_dict(data: dict, file: str, build: Callable) -> Scene:
    """:func:`derive.scene.scene_from_dict` with the loader ``build`` passed in."""
    if not isinstance(data, dict):
        raise SceneError(file, None, f"{show(data)}: a {type(data).__name__}, not a dict; accepted: a dict "
                                     "with the keys of a scene file (name, parameters, masses, springs, ...)")
    return _finish(_plain(copy.deepcopy(data), ()), file, build)


def _number(file: str, key: str, value):
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, bool) or not isinstance(value, Real):
        raise SceneError(file, key, f"{show(value)}: a {type(value).__name__}, not a number; accepted: a number")
    return int(value) if isinstance(value, int) else float(value)


def with_parameters(scene: Scene, values: dict, how: str | None = None) -> Scene:
    """``scene`` with the parameters in ``values`` changed (names must be the scene's parameters).

    ``how`` names the change in messages (default ``with_parameters(k = 4.0, ...)``).
    """
    if not values:
        return scene
    data = _data(scene)
    params = data.setdefault("parameters", {})
    for name, value in values.items():
        if name not in scene.parameters:
            raise SceneError(scene.file, f"{how}: {name}" if how else f"parameters.{name}",
                             f"not a parameter of scene {scene.name!r}{did_you_mean(name, scene.parameters)}; "
                             f"accepted: {', '.join(sorted(scene.parameters)) or 'none (the scene has no parameters)'}")
        params[name] = _number(scene.file, f"parameters.{name}", value)
        params[name] = _keep_unit(scene, name, params[name])
    if all(params[p] == scene.parameters[p] and not (isinstance(params[p], float) and math.isnan(params[p]))
           for p in values):
        return scene
    changes = ", ".join(f"{k} = {values[k]!r}" for k in values)
    return _rebuild(scene, data, how or f"with_parameters({changes})")


def _keep_unit(scene: Scene, name: str, value):
    """A parameter given with a unit (``"10 t"``) gets its new SI ``value`` with the SI unit of the same
    dimension, so the expressions that use it keep their dimension checks; otherwise ``value``."""
    old = scene.source.get("parameters", {}).get(name) if isinstance(scene.source, dict) else None
    from .units import parse_unit, split_quantity
    from .units.registry import si_unit_text

    split = split_quantity(old)
    return value if split is None else f"{float(value)!r} {si_unit_text(parse_unit(split[1]).dimension)}"


def with_initial(scene: Scene, x=None, v=None) -> Scene:
    """``scene`` starting from ``x`` and/or ``v`` (arrays of shape (N,), lists, or chain expressions)."""
    if x is None and v is None:
        return scene
    data = _data(scene)
    init = data.get("initial")
    init = data["initial"] = dict(init) if isinstance(init, dict) else {}
    for key, value in (("x", x), ("v", v)):
        if value is not None:
            init[key] = _plain(value, ("initial", key))
    return _rebuild(scene, data, "with_initial")


def _same(a, b) -> bool:
    """Whether two TOML-shaped values are equal (arrays by value, order kept)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.shape(a) == np.shape(b) and bool(np.all(np.asarray(a) == np.asarray(b)))
    if isinstance(a, dict) and isinstance(b, dict):
        return list(a) == list(b) and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return type(a) is type(b) and a == b


def _rebuild(scene: Scene, data: dict, how: str) -> Scene:
    """Build from changed data; a refusal names the scene file and the change that made it. Data equal to
    the scene's own keeps its key (a file's hash: the checked-in or cached module stays in use)."""
    try:
        return _finish(data, scene.file, type(scene).from_data,
                       scene.sha256 if _same(data, dict(scene.source)) else None)
    except SceneError as exc:
        raise SceneError(f"{exc.file} {how}" if exc.file else how, exc.key, exc.detail) from None


def validate_replaced(scene: Scene) -> None:
    """Check, in place, a Scene made by ``dataclasses.replace`` (or directly): rebuild it from its
    source data with the replaced values, or refuse a change that only a new scene can make."""
    original = getattr(scene.source, "scene", None)
    if not isinstance(original, type(scene)):
        raise SceneError(None, "Scene(...)", "a Scene is made by springchain.load (a file), "
                                             "springchain.scene_from_dict (a dict) or scene.with_parameters / "
                                             "with_initial; accepted: one of those")
    names = [f.name for f in fields(scene) if f.name != "source"]
    changed = [n for n in names if getattr(scene, n) is not getattr(original, n)]
    if not changed:
        return
    fixed = [n for n in changed if n not in REPLACEABLE]
    if fixed:
        raise SceneError(scene.file, f"dataclasses.replace({fixed[0]}=...)",
                         f"{fixed[0]} is derived from the scene's content and cannot be replaced alone; accepted: "
                         f"replace(scene, {'=..., '.join(REPLACEABLE)}=...), scene.with_parameters(...), "
                         "scene.with_initial(...) or springchain.scene_from_dict(...)")
    data = _data(scene)
    for n in changed:
        value = getattr(scene, n)
        path = REPLACEABLE[n]
        if n == "parameters":
            value = dict(value) if isinstance(value, dict) else value
        elif n in ("x0", "v0"):
            value = _plain(value, path)
        elif isinstance(value, np.generic):
            value = value.item()
        table = data
        for part in path[:-1]:
            table = table.setdefault(part, {}) if isinstance(table.get(part, {}), dict) else {}
        table[path[-1]] = value
    new = _rebuild(original, data, f"dataclasses.replace({', '.join(changed)})")
    for f in fields(scene):
        object.__setattr__(scene, f.name, getattr(new, f.name))


__all__ = ["from_dict", "with_parameters", "with_initial", "validate_replaced", "content_sha256",
           "DICT_FILE", "REPLACEABLE"]
