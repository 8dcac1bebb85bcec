"""What a generated module provides: the one description that ``derive/`` writes to and
``numeric/`` reads (through :class:`springchain.numeric.system.System` only).

Standard library only, and below both sides: ``derive`` imports it to write the shared facts
into modules (the chain-end words, the dense limit), ``numeric.system`` imports it to read a
module. Generated modules themselves never import it; they import NumPy/SciPy only.

A generated module is one of two layouts (:class:`Layout`): a ``[masses]`` scene (dense
matrices, ``SPRING_ENDS``) or a ``[chain]`` scene (stencils at any ``n``, ``spring_ends(n)``).
:data:`ITEMS` lists every constant and function a module may bind, its shape and when it is
present (:class:`When`); :func:`read` checks a module against the list and returns a typed
:class:`Provided` (what numeric code asks instead of ``getattr``/``hasattr`` on the module).

Extension point: a new effect (a potential, a nonlinear force, a damping model) adds its items
here with the :class:`When` that names its scene entry, its section writer in ``derive/codegen``
and the :class:`~springchain.numeric.system.System` property that numeric code reads. A test
checks that every public name a bundled module binds is an item of this list and that every
item a module must have for its effects is present.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from types import MappingProxyType, ModuleType

#: Dense N × N matrices (mass, stiffness, damping; eigenvector fallbacks of index-dependent chains)
#: are built for at most this many masses; beyond it chains use stencils, bands and closed forms.
MAX_DENSE = 4000
#: The helpers a spring potential's printed tension may call (``derive.law_helpers``), by their array
#: name, and the scalar form of each (which ``scalar_force`` and the compiled chain kernels call).
SCALAR_HELPERS = MappingProxyType({"_expm1mx": "_expm1mx_s", "_log1pmx": "_log1pmx_s"})


class End(enum.StrEnum):
    """How a chain ends. The value is the scene's word and the generated ``LEFT``/``RIGHT``
    constant; :attr:`code` is the integer the compiled kernels see.

    ``FREE``: no spring beyond the end mass. ``WALL``: a spring to a fixed wall (``k(-1)`` on the
    left, ``k(n-1)`` on the right). ``RING``: the spring ``k(n-1)`` closes mass n-1 to mass 0
    (both ends, or neither).
    """

    FREE = "free"
    WALL = "wall"
    RING = "ring"

    @property
    def code(self) -> int:
        """0, 1, 2 for free, wall, ring (the compiled kernels' argument)."""
        return _CODES[self]

    @property
    def has_spring(self) -> bool:
        """Whether a spring lies beyond the end mass (to a wall, or closing the ring)."""
        return self is not End.FREE


_CODES = {End.FREE: 0, End.WALL: 1, End.RING: 2}

#: The scene words, in the order the error messages list them.
END_WORDS = tuple(e.value for e in End)


class Layout(enum.StrEnum):
    """Which renderer wrote the module."""

    MASSES = "masses"
    CHAIN = "chain"


class Ground(enum.StrEnum):
    """How ``[ground]`` gives the support's acceleration (the generated ``GROUND`` constant)."""

    EXPRESSION = "expression"
    TABLE = "table"


class When(enum.Enum):
    """When a module binds an item."""

    ALWAYS = "always"
    MASSES = "[masses] scenes"
    CHAIN = "[chain] scenes"
    PRINTED = "[masses] scenes of at most 12 masses (printed per mass)"
    UNIFORM_CHAIN = "uniform [chain] scenes (closed-form spectrum)"
    CUBIC = "[masses] scenes with cubic springs"
    CUBIC_CHAIN = "[chain] scenes with cubic springs"
    POTENTIALS = "scenes with spring potentials (potential = \"EXPR\")"
    POTENTIAL = "[masses] scenes with spring potentials"
    POTENTIAL_CHAIN = "[chain] scenes with a spring potential"
    EQUILIBRIUM_SOLVED = "[masses] potentials whose equilibrium has no closed form"
    DAMPED = "dampers or a damping model"
    DAMPER_LIST = "[[dampers]] entries"
    RAYLEIGH = "[damping] rayleigh"
    MODAL_DAMPING = "[damping] modal"
    GRAVITY = "[gravity]"
    FORCES = "[[forces]] given as expressions"
    HARMONIC_FORCES = "[[forces]] expressions that are constant + harmonic"
    TABLE_FORCES = "[[forces]] given as tables"
    GROUND = "[ground]"
    GROUND_EXPRESSION = "[ground] acceleration given as an expression"
    GROUND_HARMONIC = "[ground] acceleration that is constant + harmonic"
    GROUND_MOTION = "[ground] acceleration whose double integral is known"
    GROUND_TABLE = "[ground] given as a table"
    BANDS = "periodic scenes: [cell], or [chain] whose expressions repeat in i"
    BAND_CLOSED_FORM = "periodic scenes whose branches have closed forms (BAND_CLOSED_FORM)"


@dataclass(frozen=True)
class Item:
    """One name a generated module binds.

    Attributes
    ----------
    name : str
    signature : str or None
        The call (``**parameters`` are the scene's parameters as keywords); None for a constant.
    returns : str
        Type and shape (N masses, S springs, H harmonics, ``t.shape`` for time arguments).
    when : When
    """

    name: str
    signature: str | None
    returns: str
    when: When = When.ALWAYS

    @property
    def function(self) -> bool:
        return self.signature is not None


_C, _F = None, "(**parameters)"

#: Every public name a generated module may bind. ``n=N`` is an extra keyword of every
#: function of a ``[chain]`` module that returns per-mass arrays.
ITEMS: tuple[Item, ...] = (
    # -- constants ---------------------------------------------------------------------------
    Item("SCENE", _C, "str: the scene's name"),
    Item("SCENE_SHA256", _C, "str: sha256 of the scene file's bytes (the freshness key)"),
    Item("PARAMETERS", _C, "tuple of str: keyword arguments of every function"),
    Item("DEFAULTS", _C, "dict of str to float: the scene's parameter values"),
    Item("N", _C, "int: number of masses (a chain's default n)"),
    Item("EFFECTS", _C, "tuple of str: the Lagrangian's effects ('spring', 'damper', 'gravity', ...)"),
    Item("LINEAR", _C, "bool: no cubic springs, no spring potentials other than quadratic ones"),
    Item("RIGID_MODES", _C, "int: rigid-body modes (free pieces)"),
    Item("MASS_NAMES", _C, "tuple of str, (N,)", When.MASSES),
    Item("SPRING_ENDS", _C, "tuple of (int, int), (S, 2): mass indices, -1 a wall", When.MASSES),
    Item("DAMPER_ENDS", _C, "tuple of (int, int): dashpot ends, -1 a wall", When.DAMPER_LIST),
    Item("CLOSED_FORM", _C, "bool: omega2() and mode_shapes() are closed forms", When.MASSES),
    Item("RIGID_PIECES", _C, "tuple of tuples of int: the masses of each free piece", When.MASSES),
    Item("CHAIN", _C, "True", When.CHAIN),
    Item("LEFT", _C, "str: an End word", When.CHAIN),
    Item("RIGHT", _C, "str: an End word", When.CHAIN),
    Item("UNIFORM", _C, "bool: masses and springs independent of the index", When.CHAIN),
    Item("MAX_DENSE", _C, "int: the dense limit (contract.MAX_DENSE)", When.CHAIN),
    Item("FORCING_HARMONIC", _C, "bool: the expression forces are constant + harmonic", When.FORCES),
    Item("TABLE_FORCE_ON", _C, "tuple of int: the mass of each force table", When.TABLE_FORCES),
    Item("GROUND", _C, "str: a Ground word", When.GROUND),
    Item("GROUND_HARMONIC", _C, "bool: a_g(t) is constant + harmonic", When.GROUND_EXPRESSION),
    Item("GROUND_DISPLACEMENT", _C, "bool: ground_motion() exists", When.GROUND_EXPRESSION),
    Item("EQUILIBRIUM_CLOSED_FORM", _C, "bool: equilibrium() is a closed form (any parameter values)",
         When.POTENTIAL),
    Item("EQUILIBRIUM_AT_DEFAULTS", _C, "tuple of float, (N,): x_eq solved at DEFAULTS", When.EQUILIBRIUM_SOLVED),
    Item("POTENTIAL_LAW_INDEXED", _C, "bool: the spring law depends on the spring index i", When.POTENTIAL_CHAIN),
    # -- functions: springs and modes --------------------------------------------------------
    Item("masses", _F, "ndarray (N,)"),
    Item("spring_constants", _F, "ndarray (S,), in SPRING_ENDS / spring_ends() order"),
    Item("spring_ends", "(n=N)", "ndarray of int (S, 2)", When.CHAIN),
    Item("spring_cubic_constants", _F, "ndarray (S,): k3 of each spring", When.CUBIC_CHAIN),
    Item("cubic_constants", _F, "ndarray (S,): k3 of each spring", When.CUBIC),
    Item("acceleration", "(x, **parameters)", "ndarray (N, ...): a(x) = -M^-1 dV/dx"),
    Item("scalar_force", "(x, t, out, p)", "None: writes a(x) + a_ext(t) into out (N,); p the parameter values "
         "in PARAMETERS order; straight-line scalar code (numba-compilable)", When.PRINTED),
    Item("make_acceleration", _F, "callable x (N, ...) -> (N, ...): a(x) with constants bound"),
    Item("energy", "(x, v, **parameters)", "ndarray (...): T + V"),
    Item("mass_matrix", _F, "ndarray (N, N); chains: n <= MAX_DENSE"),
    Item("stiffness_matrix", _F, "ndarray (N, N); chains: n <= MAX_DENSE"),
    Item("stiffness_bands", _F, "(diag (n,), off (n-1,)) of K", When.CHAIN),
    Item("dynamical_matrix", _F, "ndarray (N, N): M^-1/2 K M^-1/2", When.MASSES),
    Item("omega2", _F, "ndarray (N,): squared angular frequencies, ascending"),
    Item("mode_shapes", _F, "ndarray (N, N): shapes as columns, in omega2() order", When.MASSES),
    Item("mode_omega", _F, "ndarray (n,): angular frequency of mode j, j = 0 ... n-1", When.UNIFORM_CHAIN),
    # -- functions: spring potentials --------------------------------------------------------
    Item("equilibrium", _F, "ndarray (N,): the static equilibrium x_eq (displacements)", When.POTENTIALS),
    Item("spring_tensions", "(x, **parameters)", "ndarray (S, ...): V'(d) of each spring", When.POTENTIAL),
    Item("spring_stiffnesses", "(x, **parameters)", "ndarray (S, ...): V''(d) of each spring", When.POTENTIAL),
    Item("spring_force", "(d, [i,] **parameters)", "ndarray d.shape: the chain law's tension V'(d)",
         When.POTENTIAL_CHAIN),
    Item("spring_energy", "(d, [i,] **parameters)", "ndarray d.shape: V(d) - V(0)", When.POTENTIAL_CHAIN),
    Item("spring_stiffness", "(d, [i,] **parameters)", "ndarray d.shape: V''(d)", When.POTENTIAL_CHAIN),
    # -- functions: damping --------------------------------------------------------------------
    Item("damping_matrix", _F, "ndarray (N, N): C; chains: n <= MAX_DENSE", When.DAMPED),
    Item("damping_acceleration", "(v, **parameters)", "ndarray (N, ...): -M^-1 C v", When.DAMPED),
    Item("damper_constants", _F, "ndarray: c of each dashpot in DAMPER_ENDS / damper_ends() order",
         When.DAMPER_LIST),
    Item("damper_ends", "(n=N)", "ndarray of int (D, 2): dashpot ends, -1 a wall", When.DAMPER_LIST),
    Item("rayleigh_coefficients", _F, "(alpha, beta): C = alpha M + beta K", When.RAYLEIGH),
    Item("modal_damping_ratios", _F, "ndarray (N,): zeta per mode, ascending omega", When.MODAL_DAMPING),
    # -- functions: loads ----------------------------------------------------------------------
    Item("gravity_forces", _F, "ndarray (N,): m_i g", When.GRAVITY),
    Item("external_acceleration", "(t, **parameters)", "ndarray (N, *t.shape): M^-1 F(t)", When.FORCES),
    Item("forcing_harmonics", _F, "omega (H,), cos_amp (H, N), sin_amp (H, N), const (N,) of F(t)",
         When.HARMONIC_FORCES),
    Item("table_acceleration", "(t, _tables, **parameters)", "ndarray (N, *t.shape): M^-1 F of the tables",
         When.TABLE_FORCES),
    Item("ground_acceleration", "(t, **parameters)", "ndarray t.shape: a_g(t)", When.GROUND_EXPRESSION),
    Item("ground_harmonics", _F, "omega (H,), cos_amp (H,), sin_amp (H,), const: a_g(t)", When.GROUND_HARMONIC),
    Item("ground_motion", "(t, **parameters)", "(v_g, x_g), each t.shape, from rest at 0", When.GROUND_MOTION),
    Item("ground_table_acceleration", "(t, _table)", "ndarray t.shape: a_g(t) of the table", When.GROUND_TABLE),
    # -- periodic chains: the unit cell and its bands ----------------------------------------------
    Item("CELL_NAMES", _C, "tuple of str, (p,): the unit cell's masses", When.BANDS),
    Item("CELL_SPRINGS", _C, "tuple of (a, b, reach), (S,): from mass a of cell c to mass b of cell c + reach, "
         "-1 the ground", When.BANDS),
    Item("CELL_DAMPERS", _C, "tuple of (a, b, reach): the cell's dashpots", When.BANDS),
    Item("BAND_CLOSED_FORM", _C, "bool: band_omega2() is a closed form (band_omega, group_velocity exist)",
         When.BANDS),
    Item("cell_masses", _F, "ndarray (p,)", When.BANDS),
    Item("cell_stiffness", _F, "ndarray (S,): linear stiffness of each CELL_SPRINGS spring", When.BANDS),
    Item("cell_damping", _F, "ndarray (D,): constant of each CELL_DAMPERS dashpot", When.BANDS),
    Item("cell_rayleigh", _F, "(alpha, beta): Rayleigh damping C = alpha M + beta K (zeros without)", When.BANDS),
    Item("band_omega2", "(q, **parameters)", "ndarray q.shape + (p,): omega_j^2(q) of each branch", When.BANDS),
    Item("band_omega", "(q, **parameters)", "ndarray q.shape + (p,): omega_j(q), closed form", When.BAND_CLOSED_FORM),
    Item("group_velocity", "(q, **parameters)", "ndarray q.shape + (p,): d omega_j / dq [cells/s], closed form",
         When.BAND_CLOSED_FORM),
)

#: Items by name.
BY_NAME: MappingProxyType = MappingProxyType({item.name: item for item in ITEMS})
#: The names every module binds.
REQUIRED = tuple(item.name for item in ITEMS if item.when is When.ALWAYS)


class ContractError(ValueError):
    """A module that is not a generated module of this version (regenerate it)."""


@dataclass(frozen=True)
class Provided:
    """What one generated module provides, read once by :func:`read`.

    Attributes
    ----------
    scene, scene_sha256 : str
    parameters : tuple of str
    defaults : mapping of str to float
    n : int
    effects : frozenset of str
    linear : bool
    layout : Layout
    rigid_modes : int
    closed_form : bool
        ``[masses]``: closed-form modes; always False for chains.
    uniform : bool
        ``[chain]``: masses and springs independent of the index (False for ``[masses]``).
    left, right : End or None
        ``[chain]`` ends (None for ``[masses]``).
    max_dense : int
    ground : Ground or None
    ground_harmonic, ground_displacement, forcing_harmonic : bool
    table_force_on : tuple of int
    equilibrium_closed_form : bool
        ``equilibrium()`` holds for any parameter values (True without potentials: x_eq = 0 or none).
    law_indexed : bool
        A ``[chain]`` potential whose law depends on the spring index (not compiled into the kernels).
    functions : frozenset of str
        The contract functions the module defines.
    """

    scene: str
    scene_sha256: str
    parameters: tuple[str, ...]
    defaults: MappingProxyType = field(repr=False)
    n: int
    effects: frozenset[str]
    linear: bool
    layout: Layout
    rigid_modes: int
    closed_form: bool = False
    uniform: bool = False
    left: End | None = None
    right: End | None = None
    max_dense: int = MAX_DENSE
    ground: Ground | None = None
    ground_harmonic: bool = False
    ground_displacement: bool = False
    forcing_harmonic: bool = False
    table_force_on: tuple[int, ...] = ()
    equilibrium_closed_form: bool = True
    law_indexed: bool = False
    functions: frozenset[str] = field(default=frozenset(), repr=False)

    @property
    def chain(self) -> bool:
        return self.layout is Layout.CHAIN

    @property
    def potential(self) -> bool:
        """Spring potentials (``potential = "EXPR"``): the module binds ``equilibrium()``."""
        return "equilibrium" in self.functions

    def has(self, name: str) -> bool:
        """Whether the module defines the contract function ``name``."""
        if name not in BY_NAME or not BY_NAME[name].function:
            raise KeyError(f"{name!r} is not a function of the generated-module contract")
        return name in self.functions


def read(module: ModuleType) -> Provided:
    """Check ``module`` against :data:`ITEMS` and return what it provides.

    Raises
    ------
    ContractError
        Naming the module and the first required name it lacks.
    """
    label = getattr(module, "SCENE", getattr(module, "__name__", "?"))
    missing = [name for name in REQUIRED if not hasattr(module, name)]
    if missing:
        raise ContractError(f"generated module {label!r} lacks {missing[0]!r}: it was written by another "
                            f"version of springchain; regenerate it with `springchain derive`")
    chain = bool(getattr(module, "CHAIN", False))

    def end(name: str) -> End | None:
        return End(str(getattr(module, name))) if chain else None

    ground = getattr(module, "GROUND", None)
    return Provided(
        scene=str(module.SCENE), scene_sha256=str(module.SCENE_SHA256), parameters=tuple(module.PARAMETERS),
        defaults=MappingProxyType(dict(module.DEFAULTS)), n=int(module.N), effects=frozenset(module.EFFECTS),
        linear=bool(module.LINEAR), layout=Layout.CHAIN if chain else Layout.MASSES,
        rigid_modes=int(module.RIGID_MODES), closed_form=bool(getattr(module, "CLOSED_FORM", False)),
        uniform=bool(getattr(module, "UNIFORM", False)), left=end("LEFT"), right=end("RIGHT"),
        max_dense=int(getattr(module, "MAX_DENSE", MAX_DENSE)), ground=None if ground is None else Ground(ground),
        ground_harmonic=bool(getattr(module, "GROUND_HARMONIC", False)),
        ground_displacement=bool(getattr(module, "GROUND_DISPLACEMENT", False)),
        forcing_harmonic=bool(getattr(module, "FORCING_HARMONIC", False)),
        table_force_on=tuple(int(i) for i in getattr(module, "TABLE_FORCE_ON", ())),
        equilibrium_closed_form=bool(getattr(module, "EQUILIBRIUM_CLOSED_FORM", True)),
        law_indexed=bool(getattr(module, "POTENTIAL_LAW_INDEXED", False)),
        functions=frozenset(item.name for item in ITEMS if item.function and callable(getattr(module, item.name, None))))


__all__ = ["MAX_DENSE", "End", "END_WORDS", "Layout", "Ground", "When", "Item", "ITEMS", "BY_NAME", "REQUIRED",
           "Provided", "ContractError", "read"]
