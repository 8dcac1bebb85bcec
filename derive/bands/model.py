"""The unit cell of a periodic scene, symbolically: masses, springs and dashpots with their cell offsets.

Two sources give a :class:`BandCell`:

* a ``[cell]`` table (:mod:`.cell`), as written;
* a ``[chain]`` whose expressions (mass, k or the potential's stiffness, dashpot families) repeat in the index
  ``i``: its smallest period p is found from the expressions themselves (:func:`chain_period`), so equal
  parameter values never shrink the cell (``"m1*(1 - i % 2) + m2*(i % 2)"`` has period 2 even when m1 = m2);
  mass ``a`` of the cell is mass ``i = a`` of the chain and spring ``a`` joins it to ``a + 1`` (the last to
  mass 0 of the next cell).

Springs enter by their stiffness at rest: ``k``, or V''(0) of a potential when x = 0 is the equilibrium of the
infinite chain (no pre-stress, or a pre-tension every mass balances); cubic terms and single dashpots do not
enter the bands (a note says so). Rayleigh damping is kept as its two coefficients (C = alpha M + beta K(q)).
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field
from fractions import Fraction

import mpmath
import sympy as sp

from ..errors import SceneError
from ..scene import Scene
from .cell import GROUND

#: Longest period of a [chain] searched for.
MAX_PERIOD = 64
#: Integers i at which a candidate period is tested numerically before SymPy proves it.
_PROBES = 2 * MAX_PERIOD + 3


@dataclass(frozen=True)
class Link:
    """A spring (``k``: stiffness) or dashpot (``k``: c) from mass ``a`` of cell c to mass ``b`` of cell
    c + ``reach`` (any sign); either end -1 for the ground (reach 0)."""

    a: int
    b: int
    reach: int
    k: sp.Expr
    key: str

    @property
    def ground(self) -> bool:
        return GROUND in (self.a, self.b)

    @property
    def mass(self) -> int:
        """The mass end of a ground link."""
        return self.b if self.a == GROUND else self.a


@dataclass(frozen=True)
class BandCell:
    """A periodic scene's unit cell.

    Attributes
    ----------
    scene : Scene
    params : dict of str to sympy.Symbol
    names : tuple of str, shape (p,)
        Cell mass names (``[chain]``: ``"0"``, ``"1"``, ...).
    masses : tuple of sympy.Expr, shape (p,)
    springs, dampers : tuple of Link
    source : str
        How the cell was found (for reports).
    notes : tuple of str
        What the bands leave out (cubic terms, single dashpots, loads).
    """

    scene: Scene
    params: dict = field(repr=False)
    names: tuple[str, ...]
    masses: tuple
    springs: tuple[Link, ...]
    dampers: tuple[Link, ...] = ()
    source: str = ""
    notes: tuple[str, ...] = ()
    #: Rayleigh coefficients (alpha, beta) when the scene has [damping] rayleigh (not among the dampers).
    rayleigh: tuple | None = None

    @property
    def size(self) -> int:
        """p, the masses per cell."""
        return len(self.names)

    @property
    def grounded(self) -> bool:
        """Whether some spring ties a mass to the ground (then no branch reaches 0)."""
        return any(s.ground for s in self.springs)

    @property
    def values(self) -> dict:
        """``{Symbol: Rational}``: the scene's parameter values, exactly."""
        return {self.params[k]: sp.Rational(Fraction(float(v))) for k, v in self.scene.parameters.items()}


def _refuse(scene: Scene, key: str, message: str) -> SceneError:
    return SceneError(scene.file, key, message)


def band_cell(scene: Scene) -> BandCell:
    """The unit cell of ``scene``.

    Raises
    ------
    SceneError
        One line: not a chain, no period found, a pre-stressed cell out of equilibrium at rest.
    """
    if scene.cell is not None:
        return _from_cell(scene)
    if scene.chain is not None:
        return _from_chain(scene)
    raise _refuse(scene, "masses", "a [masses] scene has no unit cell; accepted: a periodic chain, [cell] (a unit "
                  "cell repeated) or [chain] with expressions periodic in i, e.g. mass = \"m*(1 + i % 2)\"")


# -- [chain] ---------------------------------------------------------------------------------------
def chain_period(exprs: list, i: sp.Symbol, params: dict, max_period: int = MAX_PERIOD) -> int | None:
    """The smallest p with ``e(i + p) == e(i)`` for every expression (None if none up to ``max_period``).

    Candidates are screened at random parameter values (30 digits, i = 0 ... 2·max_period) and then proved
    by SymPy (``simplify(e(i + p) - e(i)) == 0`` with i an integer), so the period follows the symbols, not
    the scene's values.
    """
    exprs = [e for e in exprs if e is not None and e.has(i)]
    if not exprs:
        return 1
    rng = random.Random(20240535)
    others = set(params.values()).union(*(e.free_symbols for e in exprs)) - {i}  # parameters, a potential's d
    sub = {s: sp.Rational(rng.randint(1000, 9000), rng.randint(1000, 9000)) for s in sorted(others, key=str)}
    samples = []
    with mpmath.workdps(30):
        for e in exprs:  # exact i (lambdify's printers drop the parentheses of a*Mod(i, 2))
            e = e.subs(sub)
            row = []
            for j in range(_PROBES):
                try:
                    row.append(mpmath.mpmathify(complex(sp.N(e.subs(i, j), 30))))
                except (ZeroDivisionError, ValueError, TypeError, OverflowError):
                    row.append(mpmath.nan)
            samples.append(row)
        for p in range(1, max_period + 1):
            if not all(_repeats(row, p) for row in samples):
                continue
            if all(_proved(e, i, p) for e in exprs):
                return p
    return None


def _repeats(row, p: int) -> bool:
    tol = mpmath.mpf(10) ** -24
    return all(abs(row[j + p] - row[j]) <= tol * (1 + abs(row[j])) for j in range(len(row) - p))


def _proved(e, i, p: int) -> bool:
    n = sp.Symbol("_n", integer=True)  # i as an integer of any sign: the infinite chain
    ei = e.subs(i, n)
    try:
        return sp.simplify(sp.expand(ei.subs(n, n + p)) - sp.expand(ei)) == 0
    except (TypeError, ValueError, RecursionError):
        return False


def _from_chain(scene: Scene) -> BandCell:
    from ..chain import ChainModel
    from ..chain_dampers import ALONG
    from ..chain_dampers import GROUND as GROUND_FAMILY

    model = ChainModel(scene)  # refuses a potential chain out of equilibrium at x = 0, in one line
    i = model.i
    families = [d for d in model.dampers if d[0] in (ALONG, GROUND_FAMILY)]
    # everything that repeats: the bands read mass, k (V''(0)) and the dashpot families; the cubic terms and the
    # whole potential belong to the cell too (the cell follows the scene's symbols)
    exprs = [model.mass, model.k, model.k3, None if model.law is None else model.law.energy]
    exprs += [c for _, _, _, c, _ in families]
    p = chain_period(exprs, i, model.params)
    if p is None:
        key = next((k for k, e in (("chain.mass", model.mass), ("chain.k" if model.law is None else
                                                                 "chain.potential", model.k))
                    if chain_period([e], i, model.params) is None), "chain")
        raise _refuse(scene, key, f"not periodic in i (no period up to {MAX_PERIOD} found from the expressions); "
                      "accepted: expressions that repeat in i, e.g. \"m*(1 + i % 2)\", or a [cell] table")
    names = tuple(str(a) for a in range(p))
    masses = tuple(sp.factor(model.mass.subs(i, a)) for a in range(p))
    key = "chain.k" if model.law is None else "chain.potential"
    springs = tuple(Link(a, (a + 1) % p, 1 if a == p - 1 else 0, sp.factor(model.k.subs(i, a)), key)
                    for a in range(p))
    dampers = []
    for kind, _, _, c, dkey in families:
        for a in range(p):
            ca = sp.factor(c.subs(i, a))
            dampers.append(Link(a, GROUND, 0, ca, dkey) if kind == GROUND_FAMILY else
                           Link(a, (a + 1) % p, 1 if a == p - 1 else 0, ca, dkey))
    notes = []
    if len(families) != len(model.dampers):
        notes.append("single dashpots ([[dampers]] between two mass indices) are not part of the periodic cell: "
                     "the bands leave them out")
    if model.k3 is not None:
        notes.append("cubic springs: the bands of the linear chain (k3 left out)")
    if model.law is not None:
        notes.append("spring potential: the bands of the chain linearised about its equilibrium x = 0 "
                     "(k = V''(0))")
    notes += _load_notes(scene)
    rayleigh = model.rayleigh
    how = "uniform [chain]: one mass per cell" if p == 1 else \
        f"[chain] periodic in i with period {p} (found from the expressions)"
    return BandCell(scene, model.params, names, masses, springs, tuple(dampers), how, tuple(notes), rayleigh)


# -- [cell] ----------------------------------------------------------------------------------------
def _from_cell(scene: Scene) -> BandCell:
    from ..model import parameter_symbols
    from ..potential import D, SpringLaw

    cell, params = scene.cell, parameter_symbols(scene)
    masses = tuple(e.to_sympy(params) for e in cell.masses)
    notes, springs, laws = [], [], []
    for s in cell.springs:
        if s.potential is None:
            springs.append(Link(s.a, s.b, s.reach, s.k.to_sympy(params), s.key))
            continue
        law = SpringLaw(s.key, s.potential.to_sympy({**params, "d": D}))
        laws.append((s, law))
        springs.append(Link(s.a, s.b, s.reach, sp.factor(law.stiffness.subs(D, 0)), s.key))
    if laws:
        _check_rest(scene, laws, params)
        notes.append("spring potentials: the bands of the chain linearised about its equilibrium x = 0 "
                     "(k = V''(0) of each spring)")
    if any(s.k3 is not None for s in cell.springs):
        notes.append("cubic springs: the bands of the linear chain (k3 left out)")
    dampers = [Link(d.a, d.b, d.reach, d.k.to_sympy(params), d.key) for d in cell.dampers]
    if len(scene.dampers) != sum(1 for d in scene.dampers if d.key.startswith("cell.")):
        notes.append("[[dampers]] outside [cell] are not part of the periodic cell: the bands leave them out")
    rayleigh = None
    if scene.damping is not None:
        if scene.damping.rayleigh is not None:
            rayleigh = tuple(e.to_sympy(params) for e in scene.damping.rayleigh)
        else:
            notes.append("[damping] other than rayleigh has no Bloch form: the bands leave it out")
    notes += _load_notes(scene)
    p = cell.size
    how = f"[cell] of {p} mass{'es' if p > 1 else ''}"
    return BandCell(scene, params, cell.names, masses, tuple(springs), tuple(dampers), how, tuple(notes), rayleigh)


def _check_rest(scene: Scene, laws, params) -> None:
    """x = 0 must be the equilibrium of the infinite chain: every cell mass balances the springs' V'(0)."""
    from ..accurate import exact_values
    from ..equilibrium import check_law
    from ..potential import D

    if scene.gravity is not None:
        raise _refuse(scene, "gravity", "gravity moves the equilibrium of a chain with spring potentials, which "
                      "the bands do not follow yet; accepted: [cell] without [gravity], or linear springs")
    net = [sp.Integer(0)] * scene.cell.size
    for s, law in laws:
        t = law.force.subs(D, 0)
        if s.a != GROUND:  # d = x_b - x_a: the tension V'(d) pulls a towards b (+) and b back (-)
            net[s.a] += t
        if s.b != GROUND:
            net[s.b] -= t
    for a, f in enumerate(net):
        if sp.simplify(f) != 0:
            raise _refuse(scene, f"cell.masses.{scene.cell.names[a]}",
                          f"the springs' pre-tensions V'(0) leave a net force {sp.sstr(sp.simplify(f))} on this mass "
                          "at x = 0, so the infinite chain is not at rest there (its equilibrium is not solved "
                          "yet); accepted: potentials with V'(0) = 0, or tensions that balance at every mass")
    subs = exact_values(params, scene.parameters)
    for _, law in laws:
        check_law(scene.file, law, sp.Integer(0), subs)


def _load_notes(scene: Scene) -> list[str]:
    loads = [w for w, on in (("forces", scene.forces or scene.table_forces), ("ground motion", scene.ground),
                             ("gravity", scene.gravity is not None)) if on]
    return [f"{', '.join(loads)}: loads do not change the bands (free waves of the linear chain)"] if loads else []


__all__ = ["MAX_PERIOD", "BandCell", "Link", "band_cell", "chain_period"]
