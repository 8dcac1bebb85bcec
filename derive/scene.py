"""Scene files: load, validate at the boundary, and hold as immutable data.

A scene is a TOML file (see README, "Scene format"). Every key is checked
when the file is loaded; a bad scene raises :class:`~derive.errors.SceneError`
whose one-line message names the file, the key, the bad value and what would
be accepted. Expressions are parsed by :mod:`derive.expr` (an ``ast``
whitelist), never evaluated as code. SymPy is not imported here.
"""

from __future__ import annotations

import difflib
import hashlib
import keyword
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import SceneError
from .expr import CONSTANTS, FUNCTIONS, Expr, Num, parse_expression

WALL = -1
#: Names a parameter or mass may not take: free variables, functions and
#: the local names used inside generated code.
RESERVED = frozenset({"t", "i", "n", "x", "v", "a", "np", "numpy", "wall", *FUNCTIONS, *CONSTANTS})
#: Largest number of floats all recorded trajectories of one run may hold.
MAX_RECORDED_BYTES = 4 * 2**30

TOP_KEYS = ("name", "description", "parameters", "masses", "springs", "dampers", "forces",
            "gravity", "chain", "initial", "simulation")
SPRING_KEYS = ("between", "k", "k3")
DAMPER_KEYS = ("between", "c")
FORCE_KEYS = ("on", "f")
GRAVITY_KEYS = ("g",)
CHAIN_KEYS = ("n", "mass", "k", "k3", "left", "right")
CHAIN_ENDS = ("free", "wall", "ring")
INITIAL_KEYS = ("x", "v")
SIMULATION_KEYS = ("dt", "steps", "record_every")


@dataclass(frozen=True)
class Spring:
    """A spring between masses ``a`` and ``b`` (``WALL`` = -1 for a fixed point).

    Force on ``a`` is ``-(k*d + k3*d**3)`` with extension ``d = x_a - x_b``.
    """

    a: int
    b: int
    k: Expr
    k3: Expr | None
    key: str


@dataclass(frozen=True)
class Damper:
    """A viscous dashpot: force on ``a`` is ``-c*(v_a - v_b)``."""

    a: int
    b: int
    c: Expr
    key: str


@dataclass(frozen=True)
class Force:
    """An external force ``f(t, parameters)`` on mass ``on``."""

    on: int
    f: Expr
    key: str


@dataclass(frozen=True)
class Chain:
    """A long chain in compact form; ``mass`` and ``k`` may use the index ``i``."""

    n: int
    mass: Expr
    k: Expr
    k3: Expr | None
    left: str
    right: str

    @property
    def uniform(self) -> bool:
        return "i" not in self.mass.symbols() and "i" not in self.k.symbols() and (
            self.k3 is None or "i" not in self.k3.symbols())


@dataclass(frozen=True)
class Scene:
    """A validated scene. Coordinates are displacements from the springs' rest
    configuration, in the order of ``mass_names``."""

    file: str
    sha256: str
    name: str
    description: str
    parameters: dict[str, float]
    mass_names: tuple[str, ...]
    mass_exprs: tuple[Expr, ...]
    springs: tuple[Spring, ...]
    dampers: tuple[Damper, ...]
    forces: tuple[Force, ...]
    gravity: Expr | None
    chain: Chain | None
    x0: np.ndarray = field(repr=False)
    v0: np.ndarray = field(repr=False)
    dt: float
    steps: int
    record_every: int

    @property
    def n(self) -> int:
        """Number of masses (coordinates)."""
        return self.chain.n if self.chain is not None else len(self.mass_names)

    @property
    def linear(self) -> bool:
        if self.chain is not None and self.chain.k3 is not None:
            return False
        return all(s.k3 is None for s in self.springs)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(sorted(self.parameters))


def _close(word: str, options) -> str:
    near = difflib.get_close_matches(word, list(options), n=1)
    return f" (did you mean {near[0]!r}?)" if near else ""


class _Loader:
    def __init__(self, file: str, data: dict):
        self.file = file
        self.data = data

    def err(self, key: str | None, message: str) -> SceneError:
        return SceneError(self.file, key, message)

    def keys(self, table: dict, allowed: tuple[str, ...], where: str | None, required=()) -> None:
        for k in table:
            if k not in allowed:
                raise self.err(f"{where}.{k}" if where else k,
                               f"unknown key{_close(k, allowed)}; accepted: {', '.join(allowed)}")
        for k in required:
            if k not in table:
                raise self.err(f"{where}.{k}" if where else k, "missing required key")

    def table(self, key: str, required=False) -> dict:
        value = self.data.get(key)
        if value is None:
            if required:
                raise self.err(key, "missing required table")
            return {}
        if not isinstance(value, dict):
            raise self.err(key, f"{value!r} is not a table; write [{key}]")
        return value

    def array_of_tables(self, key: str) -> list[dict]:
        value = self.data.get(key, [])
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise self.err(key, f"must be an array of tables, written [[{key}]]")
        return value

    def identifier(self, key: str, value) -> str:
        if not isinstance(value, str) or not value.isascii() or not value.isidentifier():
            raise self.err(key, f"{value!r} is not accepted; accepted: an ASCII Python identifier such as 'm1'")
        if keyword.iskeyword(value) or keyword.issoftkeyword(value):
            raise self.err(key, f"{value!r} is a Python keyword; choose another name")
        if value.startswith("_"):
            raise self.err(key, f"{value!r}: names may not start with '_'")
        return value

    def number(self, key: str, value, *, positive=False, integer=False, minimum=None) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.err(key, f"{value!r} is not a number")
        if integer and not isinstance(value, int):
            raise self.err(key, f"{value!r} is not accepted; accepted: a whole number")
        if not math.isfinite(value):
            raise self.err(key, f"{value!r} is not accepted; accepted: a finite number")
        if positive and value <= 0:
            raise self.err(key, f"{value!r} is not accepted; accepted: a number > 0")
        if minimum is not None and value < minimum:
            raise self.err(key, f"{value!r} is not accepted; accepted: a number >= {minimum}")
        return value

    def expression(self, key: str, text, allowed, *, positive=False, nonzero=False, env=None,
                   index_range=None) -> Expr:
        expr = parse_expression(text, allowed, file=self.file, key=key)
        env = dict(env or {})
        if index_range is not None:
            env["i"] = np.arange(index_range, dtype=float)
            env["n"] = float(index_range)
        try:
            value = np.asarray(expr.evaluate(env), dtype=float)
        except (OverflowError, ZeroDivisionError, ValueError, TypeError):
            value = np.asarray(np.nan)
        if not np.all(np.isfinite(value)):
            raise self.err(key, f"{text!r} is not finite at the scene's parameter values")
        if positive and not np.all(value > 0):
            raise self.err(key, f"{text!r} = {float(np.min(value)):g} is not accepted; accepted: a value > 0")
        if nonzero and np.any(value == 0):
            raise self.err(key, f"{text!r} is zero; leave the key out instead")
        return expr


def load_scene(path: str | Path, text: str | None = None) -> Scene:
    """Read and validate a scene file.

    Parameters
    ----------
    path : str or Path
        The scene file; shown in error messages as given.
    text : str, optional
        The file's content, if already read.

    Raises
    ------
    SceneError
        For any problem, with a one-line message.
    """
    file = str(path)
    if text is None:
        try:
            raw = Path(path).read_bytes()
        except OSError as exc:
            raise SceneError(file, None, f"cannot read scene file ({exc.strerror or exc})") from None
    else:
        raw = text.encode()
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except UnicodeDecodeError:
        raise SceneError(file, None, "not UTF-8 text; a scene is a TOML file") from None
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(file, None, f"TOML syntax error: {exc}") from None
    sha = hashlib.sha256(raw).hexdigest()
    return _build(_Loader(file, data), sha)


def _build(ld: _Loader, sha: str) -> Scene:
    data = ld.data
    ld.keys(data, TOP_KEYS, None, required=("name", "parameters", "initial"))
    name = ld.identifier("name", data["name"])
    description = data.get("description", "")
    if not isinstance(description, str):
        raise ld.err("description", f"{description!r} is not a string")

    params_raw = ld.table("parameters", required=True)
    parameters: dict[str, float] = {}
    for pname in sorted(params_raw):
        key = f"parameters.{pname}"
        ld.identifier(key, pname)
        if pname in RESERVED or pname.startswith(("x_", "v_")):
            raise ld.err(key, f"{pname!r} is reserved; choose another name "
                              f"(reserved: {', '.join(sorted(RESERVED))}, x_*, v_*)")
        parameters[pname] = float(ld.number(key, params_raw[pname]))
    pnames = frozenset(parameters)
    env = dict(parameters)

    chain = None
    if "chain" in data:
        if "masses" in data or "springs" in data:
            raise ld.err("chain", "use either [chain] or [masses] with [[springs]], not both")
        chain = _chain(ld, pnames, env)
        mass_names: tuple[str, ...] = ()
        mass_exprs: tuple[Expr, ...] = ()
        n = chain.n
    else:
        masses_raw = ld.table("masses", required=True)
        if not masses_raw:
            raise ld.err("masses", "no masses; accepted: at least one entry like m1 = \"m\"")
        names = []
        exprs = []
        for mname, mexpr in masses_raw.items():
            key = f"masses.{mname}"
            ld.identifier(key, mname)
            if mname in RESERVED:
                raise ld.err(key, f"{mname!r} is reserved; choose another mass name")
            names.append(mname)
            exprs.append(ld.expression(key, mexpr, pnames, positive=True, env=env))
        mass_names, mass_exprs = tuple(names), tuple(exprs)
        n = len(names)

    index = {m: j for j, m in enumerate(mass_names)}
    accepted_ends = ", ".join(repr(m) for m in (*mass_names, "wall"))

    def ends(key: str, value) -> tuple[int, int]:
        if not isinstance(value, list) or len(value) != 2:
            raise ld.err(key, f"{value!r} is not accepted; accepted: two names, e.g. [\"m1\", \"m2\"]")
        idx = []
        for v in value:
            if v == "wall":
                idx.append(WALL)
            elif isinstance(v, str) and v in index:
                idx.append(index[v])
            else:
                near = _close(v, index) if isinstance(v, str) else ""
                raise ld.err(key, f"{v!r} is not a mass{near}; accepted: {accepted_ends}")
        if idx[0] == idx[1]:
            what = "both ends are walls" if idx[0] == WALL else f"joins {value[0]!r} to itself"
            raise ld.err(key, f"{value!r} {what}; accepted: two different ends")
        return idx[0], idx[1]

    springs = []
    for j, s in enumerate(ld.array_of_tables("springs")):
        key = f"springs[{j}]"
        if chain is not None:
            raise ld.err(key, "not accepted with [chain]")
        ld.keys(s, SPRING_KEYS, key, required=("between", "k"))
        a, b = ends(f"{key}.between", s["between"])
        k = ld.expression(f"{key}.k", s["k"], pnames, positive=True, env=env)
        k3 = ld.expression(f"{key}.k3", s["k3"], pnames, nonzero=True, env=env) if "k3" in s else None
        springs.append(Spring(a, b, k, k3, key))

    dampers = []
    for j, d in enumerate(ld.array_of_tables("dampers")):
        key = f"dampers[{j}]"
        if chain is not None:
            raise ld.err(key, "dampers are not yet accepted with [chain]")
        ld.keys(d, DAMPER_KEYS, key, required=("between", "c"))
        a, b = ends(f"{key}.between", d["between"])
        c = ld.expression(f"{key}.c", d["c"], pnames, positive=True, env=env)
        dampers.append(Damper(a, b, c, key))

    forces = []
    for j, f in enumerate(ld.array_of_tables("forces")):
        key = f"forces[{j}]"
        if chain is not None:
            raise ld.err(key, "forces are not yet accepted with [chain]")
        ld.keys(f, FORCE_KEYS, key, required=("on", "f"))
        on = f["on"]
        if not isinstance(on, str) or on not in index:
            near = _close(on, index) if isinstance(on, str) else ""
            raise ld.err(f"{key}.on", f"{on!r} is not a mass{near}; accepted: "
                                      f"{', '.join(repr(m) for m in mass_names)}")
        expr = ld.expression(f"{key}.f", f["f"], pnames | {"t"}, env={**env, "t": 0.0})
        forces.append(Force(index[on], expr, key))

    gravity = None
    if "gravity" in data:
        g = ld.table("gravity")
        ld.keys(g, GRAVITY_KEYS, "gravity", required=("g",))
        gravity = ld.expression("gravity.g", g["g"], pnames, nonzero=True, env=env)

    sim = ld.table("simulation")
    ld.keys(sim, SIMULATION_KEYS, "simulation")
    dt = float(ld.number("simulation.dt", sim.get("dt", 0.1), positive=True))
    steps = int(ld.number("simulation.steps", sim.get("steps", 1000), positive=True, integer=True))
    record_every = int(ld.number("simulation.record_every", sim.get("record_every", 1),
                                 positive=True, integer=True))
    check_memory(ld.file, n, steps, record_every)

    init = ld.table("initial", required=True)
    ld.keys(init, INITIAL_KEYS, "initial", required=("x", "v"))
    x0 = _initial(ld, "initial.x", init["x"], n, chain is not None, pnames, env)
    v0 = _initial(ld, "initial.v", init["v"], n, chain is not None, pnames, env)

    used = set()
    for e in (*mass_exprs, *(s.k for s in springs), *(s.k3 for s in springs if s.k3),
              *(d.c for d in dampers), *(f.f for f in forces), *([gravity] if gravity else []),
              *((chain.mass, chain.k) if chain else ()), *((chain.k3,) if chain and chain.k3 else ())):
        used |= e.symbols()
    return Scene(file=ld.file, sha256=sha, name=name, description=description,
                 parameters=parameters, mass_names=mass_names, mass_exprs=mass_exprs,
                 springs=tuple(springs), dampers=tuple(dampers), forces=tuple(forces),
                 gravity=gravity, chain=chain, x0=x0, v0=v0, dt=dt, steps=steps,
                 record_every=record_every)


def check_memory(file: str | None, n: int, steps: int, record_every: int, methods: int = 2) -> None:
    """Refuse runs whose recorded trajectories would not fit in memory."""
    frames = steps // record_every + 1
    need = frames * n * 8 * 2 * methods
    if need > MAX_RECORDED_BYTES:
        raise SceneError(file, "simulation.steps",
                         f"{steps} steps x {n} masses (recorded every {record_every}) would need "
                         f"{need / 2**30:.1f} GiB for the trajectories; accepted: at most "
                         f"{MAX_RECORDED_BYTES / 2**30:.0f} GiB - raise simulation.record_every "
                         f"or lower the steps")


def _chain(ld: _Loader, pnames: frozenset[str], env: dict) -> Chain:
    c = ld.table("chain")
    ld.keys(c, CHAIN_KEYS, "chain", required=("n", "mass", "k"))
    n = int(ld.number("chain.n", c["n"], positive=True, integer=True))
    if n > 10**7:
        raise ld.err("chain.n", f"{n} is not accepted; accepted: 1 to 10000000 masses")
    names = pnames | {"i"}
    mass = ld.expression("chain.mass", c["mass"], names, positive=True, env=env, index_range=n)
    k = ld.expression("chain.k", c["k"], names, positive=True, env=env, index_range=n)
    k3 = (ld.expression("chain.k3", c["k3"], names, env=env, index_range=n) if "k3" in c else None)
    left, right = c.get("left", "free"), c.get("right", "free")
    for key, v in (("chain.left", left), ("chain.right", right)):
        if v not in CHAIN_ENDS:
            raise ld.err(key, f"{v!r} is not accepted; accepted: {', '.join(CHAIN_ENDS)}")
    if (left == "ring") != (right == "ring"):
        raise ld.err("chain.right", "a ring closes both ends; set left = right = \"ring\"")
    return Chain(n, mass, k, k3, left, right)


def _initial(ld: _Loader, key: str, value, n: int, chain: bool, pnames, env) -> np.ndarray:
    if isinstance(value, list):
        if len(value) != n:
            raise ld.err(key, f"has {len(value)} values; accepted: {n} (one per mass, in mass order)")
        out = np.empty(n)
        for j, v in enumerate(value):
            out[j] = ld.number(f"{key}[{j}]", v)
        return out
    if chain and isinstance(value, (str, int, float)) and not isinstance(value, bool):
        expr = ld.expression(key, value, pnames | {"i", "n"}, env=env, index_range=n)
        env2 = {**env, "i": np.arange(n, dtype=float), "n": float(n)}
        return np.broadcast_to(np.asarray(expr.evaluate(env2), dtype=float), (n,)).copy()
    accepted = f"a list of {n} numbers" + (" or an expression of i and n" if chain else "")
    raise ld.err(key, f"{value!r} is not accepted; accepted: {accepted}")


def bundled_scene_dir() -> Path:
    """The ``scenes/`` folder shipped beside the packages."""
    return Path(__file__).resolve().parent.parent / "scenes"


def bundled_scenes() -> list[Path]:
    return sorted(bundled_scene_dir().glob("*.toml"))


__all__ = ["Scene", "Spring", "Damper", "Force", "Chain", "WALL", "load_scene", "bundled_scenes",
           "bundled_scene_dir", "check_memory", "Num"]
