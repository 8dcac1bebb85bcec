"""Scene files: load, validate at the boundary, and hold as immutable data.

A scene is a TOML file (see the scene format reference, docs/reference/scene-format.md). Every key is checked
when the file is loaded; a bad scene raises :class:`~derive.errors.SceneError`
whose one-line message names the file, the key, the bad value and what would
be accepted::

    scene.toml: springs[0].stiffness: unknown key (did you mean 'k'?); accepted: between, k, k3

Expressions are parsed by :mod:`derive.expr` (an ``ast`` whitelist), never
evaluated as code, and checked at the scene's parameter values with a bound
on their rounding error, so that e.g. a mass ``sin(pi)`` (1.2e-16 in floating
point, exactly 0) is refused. SymPy is not imported here.
"""

from __future__ import annotations

import contextvars
import hashlib
import math
import os
import stat
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..generated.contract import END_WORDS, End
from .errors import SceneError
from .expr import CONSTANTS, Expr, Num, accepted_form
from .expr_tree import RESERVED_FUNCTIONS
from .expr import parse_expression
from .scene_loader import INDEX_CHUNK, Loader, did_you_mean
from .pieces import pieces
from .damping import DampingModel, parse_damping
from .loads import FORCE_KEYS, Force, Ground, TableForce, parse_forces, parse_ground  # noqa: F401
from .scene_edit import DICT_FILE, from_dict
from .units.dimension import LENGTH

WALL = -1

#: Names with a meaning in the scene language (expression variables, functions, constants).
#: (The functions added for potentials, log tanh cosh sinh, and the extension ``d`` of a potential are
#: not reserved: a parameter of that name only stops the scene from calling or using them.)
VOCABULARY = frozenset({"t", "i", "n", *RESERVED_FUNCTIONS, *CONSTANTS})
#: Names a parameter may not take. Everything generated code binds for itself is private
#: (starts with "_", which scene names never do), so any other identifier is safe: a parameter
#: only has to stay clear of the scene language and of "wall".
RESERVED = VOCABULARY | {"wall"}
#: Prefixes of coordinate names (x_m1, v_m1, a_m1): a parameter ``x_m1`` is refused only
#: when a mass ``m1`` exists (reports print coordinates by these names).
RESERVED_PREFIXES = ("x_", "v_", "a_")
#: Names a mass may not take (masses appear only as strings in ``between``/``on``).
MASS_RESERVED = frozenset({"wall"})

#: Largest scene file read.
MAX_FILE_BYTES = 64 * 2**20
#: Largest description (characters).
MAX_DESCRIPTION = 2000
MAX_STEPS = 10**12
#: True while the loader builds a Scene (any other construction is validated or refused).
_BUILDING = contextvars.ContextVar("springchain_scene_building", default=False)
MAX_CHAIN = 10**7

TOP_KEYS = ("name", "description", "parameters", "masses", "springs", "dampers", "forces",
            "gravity", "ground", "damping", "chain", "initial", "simulation", "cell")
SPRING_KEYS = ("between", "k", "k3", "potential")
DAMPER_KEYS = ("between", "c")
GRAVITY_KEYS = ("g",)
CHAIN_KEYS = ("n", "mass", "k", "k3", "potential", "left", "right")
#: The extension of a spring in a ``potential`` expression: d = x_b - x_a for between = [a, b]
#: (a wall end counts 0); in a [chain], d = x_{i+1} - x_i for the spring i between masses i and i+1.
EXTENSION = "d"
CHAIN_ENDS = END_WORDS
INITIAL_KEYS = ("x", "v")
SIMULATION_KEYS = ("dt", "steps", "record_every")

@dataclass(frozen=True)
class Spring:
    """A spring between masses ``a`` and ``b`` (``WALL`` = -1 for a fixed point).

    Either linear/cubic: force on ``a`` is ``-(k*d + k3*d**3)`` with ``d = x_a - x_b`` (the sign
    does not matter for these even energies); or given by its energy ``potential`` = V(d), an
    expression of the extension ``d = x_b - x_a`` (then ``k`` and ``k3`` are None).
    """

    a: int
    b: int
    k: Expr | None
    k3: Expr | None
    key: str
    potential: Expr | None = None


@dataclass(frozen=True)
class Damper:
    """A viscous dashpot: force on ``a`` is ``-c*(v_a - v_b)``."""

    a: int
    b: int
    c: Expr
    key: str


@dataclass(frozen=True)
class Chain:
    """A long chain in compact form; ``mass`` and ``k`` may use the index ``i``."""

    n: int
    mass: Expr
    k: Expr | None
    k3: Expr | None
    left: End
    right: End
    #: The spring energy V(d) of every spring (d = x_{i+1} - x_i; may use i), instead of k/k3.
    potential: Expr | None = None

    @property
    def uniform(self) -> bool:
        return all("i" not in e.symbols() for e in (self.mass, self.k, self.k3, self.potential) if e is not None)


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
    #: Tabulated forces (``[[forces]]`` with ``table``) and ground motion (``[ground]``).
    table_forces: tuple[TableForce, ...] = ()
    ground: Ground | None = None
    #: ``[damping]``: Rayleigh or modal damping (None without the table).
    damping: DampingModel | None = None
    #: ``[[dampers]]`` of a ``[chain]`` scene (families indexed by i, or single dashpots).
    chain_dampers: tuple = ()
    #: Whether the file has an ``[initial]`` table (without one the scene starts at rest).
    initial_given: bool = True
    #: ``[cell]``: the unit cell of a periodic chain (its copies are the masses and springs above).
    cell: object = None
    #: What the scene was built from (the TOML data as a dict): :meth:`with_parameters`,
    #: :meth:`with_initial` and ``dataclasses.replace`` rebuild the scene from it, validated.
    source: object = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        # Built by the loader: trusted. Otherwise this is ``dataclasses.replace(scene, ...)`` or a
        # direct call: the change goes through the loader's validation, or is refused.
        if not _BUILDING.get():
            from .scene_edit import validate_replaced

            validate_replaced(self)

    def with_parameters(self, values: dict | None = None, /, **more) -> "Scene":
        """A new scene with some parameter values changed, validated like a scene file.

        ``scene.with_parameters(k=4.0, m=2.0)`` (or a dict). Every function of springchain
        (modes, simulate, frf, plan, bench, sweep, animate, the generated-module cache) uses
        the new values. Raises :class:`SceneError` (one line) for an unknown name or a value
        the scene file would not accept (e.g. a mass that becomes negative).
        """
        from .scene_edit import with_parameters

        return with_parameters(self, {**(values or {}), **more})

    @classmethod
    def from_data(cls, data: dict, file: str, sha: str) -> "Scene":
        """A scene validated from TOML-shaped ``data`` by the loader of scene files (:func:`build_scene`);
        what :mod:`derive.scene_edit` rebuilds changed scenes with (it never imports this module)."""
        return build_scene(data, file, sha)

    def with_initial(self, x=None, v=None) -> "Scene":
        """A new scene with another initial state (``x``, ``v``: arrays of shape (N,), lists, or, for
        ``[chain]`` scenes, expressions of ``i`` and ``n``), validated like ``[initial]``.
        A state left out (None) keeps the scene's."""
        from .scene_edit import with_initial

        return with_initial(self, x=x, v=v)

    def __repr__(self) -> str:  # short: the arrays and expressions are attributes
        form = (f"chain n={self.chain.n} ({self.chain.left.value}-{self.chain.right.value})" if self.chain
                else f"{len(self.mass_names)} masses, {len(self.springs)} springs")
        return f"Scene({self.name!r}, {form}, parameters={self.parameters}, file={self.file!r})"

    @property
    def loaded(self) -> bool:
        """Whether anything drives the scene from outside (forces, tables, ground, gravity)."""
        return bool(self.forces or self.table_forces or self.ground is not None or self.gravity is not None)

    @property
    def n(self) -> int:
        """Number of masses (coordinates)."""
        return self.chain.n if self.chain is not None else len(self.mass_names)

    @property
    def linear(self) -> bool:
        if self.chain is not None:
            return self.chain.k3 is None and self.chain.potential is None
        return all(s.k3 is None and s.potential is None for s in self.springs)

    @property
    def has_potential(self) -> bool:
        """Whether some spring is given by its energy (``potential = "EXPR"``)."""
        if self.chain is not None:
            return self.chain.potential is not None
        return any(s.potential is not None for s in self.springs)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(sorted(self.parameters))


def load_scene(path: str | Path, text: str | None = None) -> Scene:
    """Read and validate a scene file.

    Parameters
    ----------
    path : str or Path
        The scene file; shown in error messages as given.
    text : str, optional
        The file's content, if already read.

    Returns
    -------
    Scene
        Validated and immutable; expressions parsed, not evaluated as code.

    Raises
    ------
    SceneError
        For any problem, with a one-line message. No other exception escapes
        for any file content.
    """
    file = str(path)
    if text is None:
        try:  # a FIFO, a device or a folder would block or fail inside open()/read(): refuse first
            mode = os.stat(path).st_mode
        except OSError as exc:
            raise SceneError(file, None, f"cannot read the scene file ({exc.strerror or exc}); "
                                         "accepted: a readable TOML file") from None
        if not stat.S_ISREG(mode):
            kind = ("a folder" if stat.S_ISDIR(mode) else "a FIFO (named pipe)" if stat.S_ISFIFO(mode)
                    else "a socket" if stat.S_ISSOCK(mode) else "a device" if stat.S_ISCHR(mode)
                    or stat.S_ISBLK(mode) else "not a regular file")
            raise SceneError(file, None, f"cannot read the scene file ({kind}, not a regular file); "
                                         "accepted: a regular TOML file")
        try:
            with open(path, "rb") as fh:
                raw = fh.read(MAX_FILE_BYTES + 1)
        except OSError as exc:
            raise SceneError(file, None, f"cannot read the scene file ({exc.strerror or exc}); "
                                         "accepted: a readable TOML file") from None
    else:
        raw = text.encode("utf-8", "surrogatepass")
    if len(raw) > MAX_FILE_BYTES:
        raise SceneError(file, None, f"larger than {MAX_FILE_BYTES // 2**20} MiB; accepted: smaller "
                                     "files (a long chain's initial state can be an expression of i)")
    try:
        decoded = raw.decode("utf-8")
        # a UTF-8 byte order mark (written by some Windows editors) is not TOML: accept and skip it
        data = tomllib.loads(decoded[1:] if decoded.startswith("\ufeff") else decoded)
    except UnicodeDecodeError as exc:
        raise SceneError(file, None, f"byte {exc.start} is not UTF-8; accepted: a UTF-8 TOML file") from None
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(file, None, f"TOML syntax error: {exc}; accepted: a TOML file "
                                     "(https://toml.io)") from None
    except RecursionError:
        raise SceneError(file, None, "TOML arrays or tables nested too deeply; accepted: "
                                     "a flat scene file") from None
    except (ValueError, MemoryError):  # e.g. an integer of more than 4300 digits
        raise SceneError(file, None, "a TOML value too large to read (e.g. a number of thousands of "
                                     "digits); accepted: numbers of ordinary size") from None
    sha = hashlib.sha256(raw).hexdigest()
    return build_scene(data, file, sha)


class SceneSource(dict):
    """The TOML data a Scene was built from, and the Scene built (what ``dataclasses.replace`` compares to)."""

    __slots__ = ("scene",)


def scene_from_dict(data: dict, *, file: str = DICT_FILE) -> Scene:
    """A scene from a dict with the TOML schema (see docs/reference/scene-format.md).

    Parameters
    ----------
    data : dict
        ``{"name": ..., "parameters": {...}, "masses": {...}, "springs": [{...}, ...], ...}``
        or the ``[chain]`` form. Beyond what TOML can say: ``initial.x`` / ``initial.v`` may be
        NumPy arrays of shape (N,); a force's or the ground's ``table`` may be an array of
        shape (R, 2) (columns t and f, or t and a) or a dict ``{"t": ..., "f": ...}``
        (``{"t": ..., "a": ...}`` for the ground) instead of a CSV file name.
    file : str
        How messages name the scene; table files named by a string are read relative to its
        folder (the current folder for the default ``"<dict>"``).

    Returns
    -------
    Scene
        Keyed (``sha256``) by a hash of its whole content.

    Raises
    ------
    SceneError
        The one-line message a scene file with the same content would get.
    """
    return from_dict(data, file, build_scene)


def build_scene(data: dict, file: str, sha: str) -> Scene:
    """Validate TOML-shaped ``data`` (as :func:`load_scene` reads it) into a Scene whose cache key is ``sha``."""
    token = _BUILDING.set(True)
    try:
        scene = _build(Loader(file, SceneSource(data)), sha)
        scene.source.scene = scene
        return scene
    except RecursionError:
        raise SceneError(file, None, "nested too deeply; accepted: a flat scene file") from None
    finally:
        _BUILDING.reset(token)


def _build(ld: Loader, sha: str) -> Scene:
    """The scene from its TOML data, each table checked in the order of the file format."""
    data = ld.data
    ld.keys(data, TOP_KEYS, None, required=("name", "parameters"), what="a scene")
    name = ld.identifier("name", data["name"], "scene name")
    description = _description(ld, data.get("description", ""))
    parameters = _parameters(ld)
    pnames = frozenset(parameters)
    env = dict(parameters)
    dt, steps, record_every = _simulation(ld)

    chain = None
    if "cell" in data:
        cell, mass_names, mass_exprs, cell_springs, cell_dampers = _cell(ld, pnames, env)
    elif "chain" in data:
        if "masses" in data or "springs" in data:
            both = "masses" if "masses" in data else "springs"
            raise ld.bad("chain", f"[chain] with [{both}]", "both forms given",
                         "either [chain] or [masses] with [[springs]]")
        chain = _chain(ld, pnames, env)
        mass_names: tuple[str, ...] = ()
        mass_exprs: tuple[Expr, ...] = ()
    else:
        mass_names, mass_exprs = _masses(ld, pnames, env)
    n = chain.n if chain is not None else len(mass_names)
    index = {m: j for j, m in enumerate(mass_names)}
    ends = _Ends(ld, index)
    springs = _springs(ld, ends, pnames, env)
    dampers, chain_dampers = _dampers(ld, ends, chain, pnames, env)
    if "cell" in data:
        springs, dampers = cell_springs + springs, cell_dampers + dampers
    if chain is not None and isinstance(data.get("damping"), dict) and "modal" in data["damping"]:
        raise ld.bad("damping.modal", data["damping"]["modal"], "modal damping on a [chain] is not yet supported",
                     "rayleigh = [ALPHA, BETA] or [[dampers]] on a [chain]; modal with [masses]")
    damping = parse_damping(ld, pnames, env, n, chain=chain is not None,
                            elastic=None if chain is not None else n - _free_pieces(n, springs))

    times = np.linspace(0.0, dt * steps, 257)
    forces, table_forces = parse_forces(ld, ld.array_of_tables("forces"),
                                        chain_n=None if chain is None else chain.n, index=index,
                                        pnames=pnames, env=env, times=times)
    gravity = _gravity(ld, pnames, env)
    ground = parse_ground(ld, pnames, env, times)
    x0, v0, initial_given = _initial_state(ld, n, chain is not None, pnames, env)

    return Scene(file=ld.file, sha256=sha, name=name, description=description,
                 parameters=parameters, mass_names=mass_names, mass_exprs=mass_exprs,
                 springs=springs, dampers=dampers, forces=forces,
                 gravity=gravity, chain=chain, x0=x0, v0=v0, dt=dt, steps=steps,
                 record_every=record_every, table_forces=table_forces, ground=ground,
                 damping=damping, chain_dampers=chain_dampers, initial_given=initial_given,
                 cell=cell if "cell" in data else None, source=data)


def _cell(ld: Loader, pnames: frozenset[str], env: dict):
    """``[cell]`` (:mod:`derive.bands.cell`): the cell, and its finite chain as mass names, mass expressions,
    springs and dashpots. Refused beside ``[masses]``/``[[springs]]`` (two descriptions of the masses)."""
    from .bands.cell import expand, parse_cell

    other = next((k for k in ("masses", "springs", "chain") if k in ld.data), None)
    if other is not None:
        raise ld.bad("cell", f"[cell] with [{other}]", "both forms given",
                     "either [cell] (a periodic chain by its unit cell), [chain] or [masses] with [[springs]]")
    cell = parse_cell(ld, pnames, env, potential_expression)
    names, exprs, springs, dampers = expand(cell)
    for a, name in enumerate(cell.names):  # the finite chain's names must stay clear of the parameters
        clash = next((f"{name}_{c}" for c in range(cell.cells) if f"{name}_{c}" in pnames), None)
        clash = clash or next((q for c in range(cell.cells) for q in (f"x_{name}_{c}", f"v_{name}_{c}",
                                                                      f"a_{name}_{c}") if q in pnames), None)
        if clash:
            raise ld.bad(f"parameters.{clash}", clash, f"the name of a copy of cell mass {name!r} (or its coordinate)",
                         f"a parameter name other than {name}_<cell> and x_/v_/a_{name}_<cell>")
    springs = tuple(Spring(i, j, s.k, s.k3, s.key, s.potential) for s, i, j in springs)
    dampers = tuple(Damper(i, j, d.k, d.key) for d, i, j in dampers)
    return cell, names, exprs, springs, dampers


def _description(ld: Loader, description) -> str:
    if not isinstance(description, str):
        raise ld.bad("description", description, "not a string", "a string")
    if len(description) > MAX_DESCRIPTION:
        raise ld.bad("description", description, f"longer than {MAX_DESCRIPTION} characters",
                     f"a string of at most {MAX_DESCRIPTION} characters")
    control = [ch for ch in description if not ch.isprintable() and ch not in "\n\t"]
    if control:
        raise ld.bad("description", description, f"holds the control character {control[0]!r}",
                     "printable text (newlines and tabs allowed)")
    return description


def _parameters(ld: Loader) -> dict[str, float]:
    """``[parameters]``: name -> value, in sorted order; names outside the scene language."""
    params_raw = ld.table("parameters", required=True, example=" of name = number, e.g. m = 1.0")
    parameters: dict[str, float] = {}
    for pname in sorted(params_raw):
        key = f"parameters.{pname}"
        ld.identifier(key, pname, "parameter name")
        if pname in RESERVED:
            why = ("the end 'wall' of springs" if pname == "wall"
                   else "a variable, function or constant of expressions")
            raise ld.bad(key, pname, f"reserved ({why})",
                         f"any other identifier (not {', '.join(sorted(RESERVED))}), e.g. {pname}0")
        parameters[pname] = float(ld.number(key, params_raw[pname]))
    return parameters


def _simulation(ld: Loader) -> tuple[float, int, int]:
    """``[simulation]``: dt, steps and record_every (defaults 0.1, 1000, 1)."""
    sim = ld.table("simulation")
    ld.keys(sim, SIMULATION_KEYS, "simulation", what="[simulation]")
    dt = float(ld.number("simulation.dt", sim.get("dt", 0.1), positive=True))
    steps = int(ld.number("simulation.steps", sim.get("steps", 1000), positive=True, integer=True,
                          maximum=MAX_STEPS))
    record_every = int(ld.number("simulation.record_every", sim.get("record_every", 1),
                                 positive=True, integer=True, maximum=MAX_STEPS))
    if not math.isfinite(dt * steps) or not math.isfinite(1.0 / dt):
        raise ld.bad("simulation.dt", dt, f"dt x steps = {dt:g} x {steps} is not a finite time",
                     "dt and steps whose product is a finite number")
    return dt, steps, record_every


def _masses(ld: Loader, pnames: frozenset[str], env: dict) -> tuple[tuple[str, ...], tuple[Expr, ...]]:
    """``[masses]``: the names (the coordinate order) and their positive expressions."""
    masses_raw = ld.table("masses", required=True, example=" of name = expression, e.g. m1 = \"m\"")
    if not masses_raw:
        raise ld.bad("masses", masses_raw, "no masses", "at least one entry such as m1 = \"m\"")
    names = []
    exprs = []
    for mname, mexpr in masses_raw.items():
        key = f"masses.{mname}"
        ld.identifier(key, mname, "mass name")
        if mname in MASS_RESERVED:
            raise ld.bad(key, mname, "reserved (the fixed end of springs)",
                         f"another mass name, e.g. {mname}1")
        if mname in pnames:
            raise ld.bad(key, mname, "also the name of a parameter",
                         "a mass name different from every parameter name")
        clash = next((p for p in (f"x_{mname}", f"v_{mname}", f"a_{mname}") if p in pnames), None)
        if clash:
            raise ld.bad(f"parameters.{clash}", clash, f"the name of mass {mname!r}'s coordinate",
                         "a parameter name other than x_<mass>, v_<mass>, a_<mass>")
        names.append(mname)
        exprs.append(ld.expression(key, mexpr, pnames, positive=True, bounded=True, env=env))
    return tuple(names), tuple(exprs)


class _Ends:
    """``between = [END, END]`` of a spring or damper as two indices (``WALL`` for "wall")."""

    def __init__(self, ld: Loader, index: dict[str, int]):
        self.ld, self.index = ld, index
        self.accepted = ", ".join(repr(m) for m in (*index, "wall"))

    def __call__(self, key: str, value) -> tuple[int, int]:
        ld, index = self.ld, self.index
        if not isinstance(value, list) or len(value) != 2:
            raise ld.bad(key, value, "not a list of two ends", f'two names, e.g. ["{(*index, "m1")[0]}", "wall"]')
        idx = []
        for v in value:
            if v == "wall":
                idx.append(WALL)
            elif isinstance(v, str) and v in index:
                idx.append(index[v])
            else:
                raise ld.bad(key, v, f"not a mass{did_you_mean(v, index)}", self.accepted)
        if idx[0] == idx[1]:
            what = "both ends are walls" if idx[0] == WALL else f"joins {value[0]!r} to itself"
            raise ld.bad(key, value, what, "two different ends")
        return idx[0], idx[1]


def _entries(ld: Loader, ends: _Ends, table: str, allowed: tuple[str, ...], required: tuple[str, ...]):
    """``(key, entry, (a, b))`` of each ``[[table]]`` entry between two ends, its keys checked."""
    for j, entry in enumerate(ld.array_of_tables(table)):
        key = f"{table}[{j}]"
        ld.keys(entry, allowed, key, required=required, what=f"a [[{table}]] entry")
        yield key, entry, ends(f"{key}.between", entry["between"])


def _springs(ld: Loader, ends: _Ends, pnames: frozenset[str], env: dict) -> tuple[Spring, ...]:
    """``[[springs]]``: linear stiffness k > 0 and an optional cubic k3 != 0, or the spring's energy
    ``potential`` = V(d) instead (:func:`potential_expression`)."""
    springs = []
    for j, s in enumerate(ld.array_of_tables("springs")):
        key = f"springs[{j}]"
        if "potential" in s:
            ld.keys(s, ("between", "potential"), key, required=("between", "potential"),
                    what="a [[springs]] entry with a potential (instead of k, k3)")
            a, b = ends(f"{key}.between", s["between"])
            springs.append(Spring(a, b, None, None, key, potential_expression(ld, f"{key}.potential",
                                                                            s["potential"], pnames)))
            continue
        ld.keys(s, SPRING_KEYS, key, required=("between", "k"), what="a [[springs]] entry")
        a, b = ends(f"{key}.between", s["between"])
        k = ld.expression(f"{key}.k", s["k"], pnames, positive=True, bounded=True, env=env)
        k3 = (ld.expression(f"{key}.k3", s["k3"], pnames, nonzero=True, bounded=True, env=env)
              if "k3" in s else None)
        springs.append(Spring(a, b, k, k3, key))
    return tuple(springs)


def _dampers(ld: Loader, ends: _Ends, chain: Chain | None, pnames: frozenset[str], env: dict):
    """``[[dampers]]``: dashpots between masses, or for a ``[chain]`` its families and single dashpots."""
    if chain is not None:
        from .chain_dampers import parse_chain_dampers

        return (), parse_chain_dampers(ld, ld.array_of_tables("dampers"), chain.n, pnames, env)
    dampers = tuple(Damper(a, b, ld.expression(f"{key}.c", d["c"], pnames, positive=True, bounded=True, env=env), key)
                    for key, d, (a, b) in _entries(ld, ends, "dampers", DAMPER_KEYS, ("between", "c")))
    return dampers, ()


def _gravity(ld: Loader, pnames: frozenset[str], env: dict) -> Expr | None:
    if "gravity" not in ld.data:
        return None
    g = ld.table("gravity", example=' with g = "g"')
    ld.keys(g, GRAVITY_KEYS, "gravity", required=("g",), what="[gravity]")
    return ld.expression("gravity.g", g["g"], pnames, nonzero=True, bounded=True, env=env)


def _initial_state(ld: Loader, n: int, chain: bool, pnames: frozenset[str], env: dict):
    """``(x0, v0, given)`` from ``[initial]``; a missing table or key means rest.

    Whether a run from rest is worth making is decided by the commands that run (simulate,
    plan, bench), not here: modes and derive never need it.
    """
    init = ld.table("initial", example=" with x = [...] and v = [...]")
    ld.keys(init, INITIAL_KEYS, "initial", what="[initial]")
    x0 = _initial(ld, "initial.x", init["x"], n, chain, pnames, env) if "x" in init else np.zeros(n)
    v0 = _initial(ld, "initial.v", init["v"], n, chain, pnames, env) if "v" in init else np.zeros(n)
    return x0, v0, bool(init)


def _free_pieces(n: int, springs) -> int:
    """Connected pieces of the spring graph with no spring to a wall (one rigid-body mode each)."""
    walled = {i for s in springs if WALL in (s.a, s.b) for i in (s.a, s.b) if i != WALL}
    return sum(1 for piece in pieces(n, ((s.a, s.b) for s in springs)) if walled.isdisjoint(piece))


def _chain(ld: Loader, pnames: frozenset[str], env: dict) -> Chain:
    c = ld.table("chain")
    if "potential" in c:
        ld.keys(c, tuple(k for k in CHAIN_KEYS if k not in ("k", "k3")), "chain",
                required=("n", "mass", "potential"), what="[chain] with a potential (instead of k, k3)")
    else:
        ld.keys(c, CHAIN_KEYS, "chain", required=("n", "mass", "k"), what="[chain]")
    n = int(ld.number("chain.n", c["n"], positive=True, integer=True, maximum=MAX_CHAIN))
    left, right = c.get("left", "free"), c.get("right", "free")
    for key, v in (("chain.left", left), ("chain.right", right)):
        if not isinstance(v, str) or v not in CHAIN_ENDS:
            raise ld.bad(key, v, f"not a chain end{did_you_mean(v, CHAIN_ENDS)}", ", ".join(CHAIN_ENDS))
    left, right = End(left), End(right)
    if (left is End.RING) != (right is End.RING):
        raise ld.bad("chain.right" if left is End.RING else "chain.left", right if left is End.RING else left,
                     "a ring closes both ends", 'left = right = "ring"')
    names = pnames | {"i"}
    # springs: i = 0 .. n-2 between masses i, i+1; i = -1 for a left wall; i = n-1 for a
    # right wall or the ring's closing spring
    spring_idx = range(-1 if left is End.WALL else 0, n if right.has_spring else n - 1)
    mass = ld.expression("chain.mass", c["mass"], names, positive=True, bounded=True, env=env,
                         index_range=range(n))
    if "potential" in c:
        return Chain(n, mass, None, None, left, right,
                     potential_expression(ld, "chain.potential", c["potential"], names))
    k = ld.expression("chain.k", c["k"], names, positive=True, bounded=True, env=env,
                      index_range=spring_idx)
    k3 = (ld.expression("chain.k3", c["k3"], names, bounded=False, env=env, index_range=spring_idx)
          if "k3" in c else None)
    return Chain(n, mass, k, k3, left, right)


def potential_expression(ld: Loader, key: str, text, names: frozenset[str]) -> Expr:
    """A spring's energy V(d): a whitelisted expression of the extension ``d`` and ``names``.

    Checked here: the syntax, and that V depends on d. Whether V is finite and twice
    differentiable at the equilibrium, and stiff there (V'' > 0), needs the derivatives and the
    equilibrium: the derivation checks it (:mod:`springchain.derive.equilibrium`), in one line too.
    """
    if EXTENSION in names:
        raise ld.bad(f"parameters.{EXTENSION}", EXTENSION, "in a potential, d is the spring's extension",
                     "another parameter name (e.g. d0) in a scene with potentials")
    expr = ld.literals(key, text, parse_expression(text, names | {EXTENSION}, file=ld.file, key=key))
    ld.units.check(key, text, expr, {EXTENSION: LENGTH})
    if EXTENSION not in expr.symbols():
        raise ld.bad(key, text, "does not depend on the extension d",
                     "the spring's energy as an expression of its extension d, e.g. "
                     "\"k*d**2/2 + beta*d**4/4\"")
    return expr


def _initial(ld: Loader, key: str, value, n: int, chain: bool, pnames, env) -> np.ndarray:
    if isinstance(value, np.ndarray):  # from Python (Scene.with_initial): checked as a whole, no loop
        if value.dtype.kind not in "iuf" or value.shape != (n,):
            raise ld.bad(key, value, f"an array of {value.dtype} with shape {value.shape} for {n} masses",
                         f"an array of {n} finite numbers (one per mass, in mass order)")
        out = value.astype(float)
        bad = ~np.isfinite(out)
        if bad.any():
            j = int(np.argmax(bad))
            raise ld.bad(f"{key}[{j}]", float(out[j]), "not a finite number", "a finite number")
        return out
    if isinstance(value, list):
        if len(value) != n:
            raise ld.bad(key, value, f"{len(value)} values for {n} masses",
                         f"a list of {n} numbers (one per mass, in mass order)")
        out = np.empty(n)
        for j, v in enumerate(value):
            out[j] = ld.number(f"{key}[{j}]", v)
        return out
    if chain and isinstance(value, (str, int, float)) and not isinstance(value, bool):
        allowed = pnames | {"i", "n"}
        expr = ld.expression(key, value, allowed, env={**env, "n": float(n)}, index_range=range(n))
        out = np.empty(n)
        for s in range(0, n, INDEX_CHUNK):
            i = np.arange(s, min(s + INDEX_CHUNK, n), dtype=float)
            out[s:s + len(i)] = np.broadcast_to(expr.evaluate({**env, "n": float(n), "i": i}), i.shape)
        return out
    accepted = f"a list of {n} numbers" + (f" or an expression of {accepted_form(pnames | {'i', 'n'})}"
                                            if chain else "")
    raise ld.bad(key, value, "not a list of numbers", accepted)


__all__ = ["Scene", "Spring", "Damper", "Force", "Chain", "WALL", "load_scene", "scene_from_dict", "build_scene", "Num",
           "RESERVED", "VOCABULARY", "did_you_mean"]
