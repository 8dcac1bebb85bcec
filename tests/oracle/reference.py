"""The oracle: every number springchain prints, computed again in mpmath from the scene's TOML text.

Nothing here imports springchain. The scene is read with ``tomllib`` and its expressions are evaluated by
:mod:`oracle.expressions` (an ``ast`` walker of our own); M, K, C, the loads, the ground motion and the
spring laws are assembled element by element at 50+ digits, and each output is computed from its
definition in the README (the spec):

=============================  ==================================================================
output                          oracle
=============================  ==================================================================
ω², shapes                      ``mp.eigsy`` of D = M^-1/2 K M^-1/2 (K the Hessian at x_eq)
ζ, complex modes                ``mp.eig`` of the first-order form of M x'' + C x' + K x = 0
Γ, M*                           Γ = φᵀ M 1 with φᵀ M φ = 1 (influence vector of ones)
equilibrium, stability          Newton on grad V = loads, continued from x = 0 in the load (homotopy)
frf H, phase                    ``mp.lu_solve`` of (K − ω² M + iωC) X = e_in
exact trajectories              modal state space, eigen-decomposed; harmonics and tables in closed form
spring forces, drifts, shear    V'(x_b − x_a) of each spring along the oracle's trajectory
response spectra                the damped oscillator solved in closed form piece by piece, extrema
                                by root finding on u̇, free vibration after the record
rsa                             Γ φ SD per mode; SRSS; CQC with Der Kiureghian's ρ
=============================  ==================================================================

Precision: every result is computed at a working precision chosen from the scene's contrast and again
with more digits; the two must agree (:func:`settled`).
"""

from __future__ import annotations

import csv
import io
import math
import tomllib
from dataclasses import dataclass, field

import mpmath
from mpmath import mp

from .expressions import ExpressionError, Harm, Jet, Lin, NotClosedForm, as_harm, evaluate

WALL = -1
DEBUG = False  # _newton prints its iterates (a debugging aid)
MIN_MAGNITUDE, MAX_MAGNITUDE = mp.mpf("1e-150"), mp.mpf("1e150")


class OracleError(Exception):
    """The oracle has no answer of this kind for the scene."""


class Unsupported(OracleError):
    """Outside what the oracle computes (the comparison is skipped and counted)."""


class NoEquilibrium(OracleError):
    """No stable static equilibrium on the branch continued from the rest configuration."""


class Rejected(OracleError):
    """The scene breaks a documented rule of the format: a one-line refusal is the right answer."""


# -- tables --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Table:
    """Rows (t, y) linear between rows, zero outside [t[0], t[-1]] (values exact binary fractions)."""

    t: tuple
    y: tuple

    @classmethod
    def from_csv(cls, text: str, column: str) -> "Table":
        rows = []
        header = None
        for line in io.StringIO(text.lstrip("\ufeff")):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            if header is None:
                header = [c.strip().lower() for c in line.split(",")]
                if header != ["t", column]:
                    raise Rejected(f"table header {header}")
                continue
            a, b = next(csv.reader([line]))
            rows.append((float(a), float(b)))
        if len(rows) < 2 or any(r2[0] <= r1[0] for r1, r2 in zip(rows, rows[1:])):
            raise Rejected("table rows")
        return cls(tuple(mp.mpf(r[0]) for r in rows), tuple(mp.mpf(r[1]) for r in rows))

    def value(self, t, side: int = 1):
        """y(t), the one-sided limit from the right (side = 1) or left (side = -1) at a row."""
        ts, ys = self.t, self.y
        if t < ts[0] or t > ts[-1] or (side > 0 and t == ts[-1]) or (side < 0 and t == ts[0]):
            return mp.mpf(0)
        for j in range(len(ts) - 1):
            if ts[j] <= t <= ts[j + 1]:
                if t == ts[j + 1] and side > 0:
                    continue
                return ys[j] + (ys[j + 1] - ys[j]) * (t - ts[j]) / (ts[j + 1] - ts[j])
        return mp.mpf(0)


# -- the scene -------------------------------------------------------------------------------------------
@dataclass
class Spring:
    """A spring between ``a`` and ``b`` (``WALL`` = -1): ``k``, ``k3`` or a potential V(d) (text + names)."""

    a: int
    b: int
    k: object = None
    k3: object = None
    potential: str | None = None
    env: dict = field(default_factory=dict, repr=False)
    key: str = ""

    def jet(self, d, order: int = 2) -> Jet:
        """V(d0 + h) as a Taylor jet (V measured from any constant)."""
        x = Jet.variable(d, order)
        if self.potential is None:
            return x * x * (self.k / 2) + (x * x * x * x * (self.k3 / 4) if self.k3 is not None else 0)
        v = evaluate(self.potential, {**self.env, "d": x})
        if not isinstance(v, Jet):
            raise Rejected(f"{self.key}: potential does not depend on d")
        return v

    def tension(self, d):
        """V'(d): k d + k3 d³ for a k/k3 spring."""
        if self.potential is None:
            return self.k * d + (self.k3 * d**3 if self.k3 is not None else 0)
        return self.jet(d, 1).derivative(1)

    def stiffness(self, d):
        if self.potential is None:
            return self.k + (3 * self.k3 * d**2 if self.k3 is not None else 0)
        return self.jet(d, 2).derivative(2)

    @property
    def linear(self) -> bool:
        """k alone, or a potential whose V''' vanishes (checked at a few extensions)."""
        if self.potential is None:
            return self.k3 is None
        def flat(d):  # the third derivative is zero (jets of polynomials are exact); at 400 digits a quartic
            j = self.jet(d, 3)  # term 1e-130 of the quadratic one still shows (the product decides by degree)
            return abs(j.derivative(3)) <= mp.mpf(10) ** (-mp.dps + 20) * abs(j.derivative(2))

        try:
            with mp.workdps(max(mp.dps, 400)):
                return all(flat(d) for d in (mp.mpf(0), mp.mpf("0.37"), mp.mpf("-0.61"), mp.mpf("0.013")))
        except ExpressionError:  # not finite somewhere near the rest length: not a quadratic
            return False


@dataclass
class Load:
    """A load vector ``b`` (N,) times a scalar signal of time (a :class:`Harm` or a :class:`Table`)."""

    b: list
    signal: object
    key: str = ""


@dataclass
class Model:
    """A scene read by the oracle: values are mpf at the precision it was read with."""

    text: str
    tables: dict
    dps: int
    name: str = ""
    names: list = field(default_factory=list)
    m: list = field(default_factory=list)
    springs: list = field(default_factory=list)
    dampers: list = field(default_factory=list)  # (a, b, c)
    rayleigh: tuple | None = None
    targets: tuple | None = None  # ((zeta_a, zeta_b), (mode_a, mode_b))
    modal: list | None = None
    loads: list = field(default_factory=list)  # Load
    ground: object = None  # Harm | Table | None
    gravity: object = None
    x0: list = field(default_factory=list)
    v0: list = field(default_factory=list)
    initial_given: bool = False
    dt: object = None
    steps: int = 1000
    record_every: int = 1
    chain: dict | None = None

    @property
    def n(self) -> int:
        return len(self.m)

    def at(self, dps: int) -> "Model":
        """The same scene read again at ``dps`` digits."""
        return read(self.text, self.tables, dps)

    @property
    def has_potential(self) -> bool:
        return any(s.potential is not None for s in self.springs)

    @property
    def linear(self) -> bool:
        return all(s.linear for s in self.springs)

    @property
    def damped(self) -> bool:
        return bool(self.dampers) or self.rayleigh is not None or self.targets is not None or self.modal is not None

    @property
    def total_mass(self):
        return mp.fsum(self.m)

    def has_wall(self) -> bool:
        """A spring or a dashpot to a wall."""
        return any(WALL in (s.a, s.b) for s in self.springs) or any(WALL in (a, b) for a, b, _ in self.dampers)

    def pieces(self) -> list[tuple[list[int], bool]]:
        """Connected pieces of the spring graph: (masses, tied to a wall)."""
        parent = list(range(self.n))

        def find(i):
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        walled = set()
        for s in self.springs:
            if WALL in (s.a, s.b):
                walled.add(s.b if s.a == WALL else s.a)
            else:
                parent[find(s.a)] = find(s.b)
        groups: dict = {}
        for i in range(self.n):
            groups.setdefault(find(i), []).append(i)
        return [(g, any(find(w) == r for w in walled)) for r, g in groups.items()]

    def free_pieces(self) -> list[list[int]]:
        return [g for g, tied in self.pieces() if not tied]

    # loads
    def constant_load(self) -> list:
        """Gravity, the constant parts of forces and of the ground acceleration (N,), plus the prestress
        V'(0) of the springs (+V' on a, -V' on b)."""
        f = [mp.mpf(0)] * self.n
        for ld in self.loads:
            if isinstance(ld.signal, Harm):
                c = mp.re(ld.signal.terms.get(mp.mpf(0), 0))
                for i in range(self.n):
                    f[i] += ld.b[i] * c
        return f

    def prestress(self) -> list:
        f = [mp.mpf(0)] * self.n
        for s in self.springs:
            if s.potential is None:
                continue
            t0 = s.tension(mp.mpf(0))
            if s.a != WALL:
                f[s.a] += t0
            if s.b != WALL:
                f[s.b] -= t0
        return f


def _bounded(value, key: str, positive=False, nonzero=False):
    if not mp.isfinite(value):
        raise Rejected(f"{key}: not finite")
    if positive and value <= 0:
        raise Rejected(f"{key}: {value} not > 0")
    if nonzero and value == 0:
        raise Rejected(f"{key}: 0")
    if not (MIN_MAGNITUDE <= abs(value) <= MAX_MAGNITUDE):
        raise Rejected(f"{key}: {mpmath.nstr(value, 5)} outside 1e-150 ... 1e150")
    return value


def _ev(text, env, key):
    try:
        return evaluate(text, env)
    except ExpressionError as exc:
        raise Rejected(f"{key}: {exc}") from None


def read(text: str, tables: dict | None = None, dps: int = 60) -> Model:
    """Read a scene's TOML text (``tables``: CSV texts by file name) at ``dps`` digits."""
    tables = dict(tables or {})
    with mp.workdps(dps):
        return _read(text, tables, dps)


def _read(text, tables, dps) -> Model:
    data = tomllib.loads(text)
    md = Model(text=text, tables=tables, dps=dps, name=data.get("name", ""))
    env = {k: mp.mpf(float(v)) for k, v in data.get("parameters", {}).items()}
    chain = data.get("chain")
    if chain is not None:
        _read_chain(md, chain, env)
    else:
        _read_masses(md, data, env)
    n = md.n
    index = {nm: j for j, nm in enumerate(md.names)}

    def mass_of(on):
        if chain is not None:
            return int(on)
        return index[on]

    tenv = {**env, "t": Lin(0, 1)}
    for j, f in enumerate(data.get("forces", [])):
        key = f"forces[{j}]"
        b = [mp.mpf(0)] * n
        b[mass_of(f["on"])] = mp.mpf(1)
        if "table" in f:
            md.loads.append(Load(b, Table.from_csv(tables[f["table"]], "f"), key))
        else:
            md.loads.append(Load(b, _signal(f["f"], tenv, key), key))
    g = data.get("gravity")
    if g is not None:
        md.gravity = _bounded(_ev(g["g"], env, "gravity.g"), "gravity.g", nonzero=True)
        md.loads.append(Load([mi * md.gravity for mi in md.m], Harm.constant(1), "gravity"))
    gr = data.get("ground")
    if gr is not None:
        sig = (Table.from_csv(tables[gr["table"]], "a") if "table" in gr
               else _signal(gr["acceleration"], tenv, "ground"))
        md.ground = sig
        md.loads.append(Load([-mi for mi in md.m], sig, "ground"))
    if chain is not None:
        _chain_dampers(md, data.get("dampers", []), env)
    _read_damping(md, data.get("damping"), env)
    init = data.get("initial", {})
    md.initial_given = bool(init)
    md.x0 = _initial(init.get("x"), n, env, chain is not None)
    md.v0 = _initial(init.get("v"), n, env, chain is not None)
    sim = data.get("simulation", {})
    md.dt = mp.mpf(float(sim.get("dt", 0.1)))
    md.steps = int(sim.get("steps", 1000))
    md.record_every = int(sim.get("record_every", 1))
    return md


def _signal(text, tenv, key):
    try:
        v = evaluate(text, tenv)
    except ExpressionError as exc:
        raise Rejected(f"{key}: {exc}") from None
    except NotClosedForm as exc:
        return _Opaque(str(text), str(exc))
    try:
        return as_harm(v)
    except NotClosedForm as exc:
        return _Opaque(str(text), str(exc))


@dataclass(frozen=True)
class _Opaque:
    """A time function without a closed-form response here (trajectories are not checked)."""

    text: str
    why: str


def _read_masses(md: Model, data: dict, env: dict) -> None:
    for name, expr in data["masses"].items():
        md.names.append(name)
        md.m.append(_bounded(_ev(expr, env, f"masses.{name}"), f"masses.{name}", positive=True))
    index = {nm: j for j, nm in enumerate(md.names)}
    end = lambda e: WALL if e == "wall" else index[e]  # noqa: E731
    for j, s in enumerate(data.get("springs", [])):
        key = f"springs[{j}]"
        a, b = end(s["between"][0]), end(s["between"][1])
        if "potential" in s:
            md.springs.append(Spring(a, b, potential=s["potential"], env=env, key=key))
        else:
            k = _bounded(_ev(s["k"], env, key + ".k"), key + ".k", positive=True)
            k3 = (_bounded(_ev(s["k3"], env, key + ".k3"), key + ".k3", nonzero=True) if "k3" in s else None)
            md.springs.append(Spring(a, b, k, k3, key=key))
    for j, d in enumerate(data.get("dampers", [])):
        key = f"dampers[{j}]"
        md.dampers.append((end(d["between"][0]), end(d["between"][1]),
                           _bounded(_ev(d["c"], env, key + ".c"), key + ".c", positive=True)))


def _read_chain(md: Model, c: dict, env: dict) -> None:
    n = int(c["n"])
    left, right = c.get("left", "free"), c.get("right", "free")
    md.chain = {"n": n, "left": left, "right": right}
    md.names = [str(i) for i in range(n)]
    for i in range(n):
        md.m.append(_bounded(_ev(c["mass"], {**env, "i": mp.mpf(i)}, "chain.mass"), "chain.mass", positive=True))
    ends = []
    if left == "wall":
        ends.append((-1, WALL, 0))
    ends += [(i, i, i + 1) for i in range(n - 1)]
    if right == "wall":
        ends.append((n - 1, n - 1, WALL))
    if right == "ring":
        ends.append((n - 1, n - 1, 0))
    for i, a, b in ends:
        ienv = {**env, "i": mp.mpf(i)}
        if "potential" in c:
            md.springs.append(Spring(a, b, potential=c["potential"], env=ienv, key=f"chain spring {i}"))
        else:
            k = _bounded(_ev(c["k"], ienv, "chain.k"), "chain.k", positive=True)
            k3 = _ev(c["k3"], ienv, "chain.k3") if "k3" in c else None
            md.springs.append(Spring(a, b, k, k3 if k3 != 0 else None, key=f"chain spring {i}"))


def _chain_dampers(md: Model, entries: list, env: dict) -> None:
    n = md.n
    for j, d in enumerate(entries):
        key = f"dampers[{j}]"
        between = d["between"]
        if between in (["i", "i+1"], ["i+1", "i"]):
            for i in range(n - 1):
                md.dampers.append((i, i + 1, _bounded(_ev(d["c"], {**env, "i": mp.mpf(i)}, key), key, positive=True)))
        elif between in (["i", "wall"], ["wall", "i"]):
            for i in range(n):
                md.dampers.append((i, WALL, _bounded(_ev(d["c"], {**env, "i": mp.mpf(i)}, key), key, positive=True)))
        else:
            a, b = (WALL if e == "wall" else int(e) for e in between)
            md.dampers.append((a, b, _bounded(_ev(d["c"], env, key), key, positive=True)))


def _read_damping(md: Model, damping: dict | None, env: dict) -> None:
    if not damping:
        return
    if "rayleigh" in damping:
        a, b = (_ev(v, env, "damping.rayleigh") for v in damping["rayleigh"])
        if not (a >= 0 and b >= 0) or (a == 0 and b == 0):
            raise Rejected("damping.rayleigh: coefficients >= 0, not both 0")
        md.rayleigh = (a, b)
    elif "rayleigh_targets" in damping:
        t = damping["rayleigh_targets"]
        md.targets = (tuple(_ev(z, env, "damping.rayleigh_targets.zeta") for z in t["zeta"]), tuple(t["modes"]))
    elif "modal" in damping:
        z = damping["modal"]
        zs = [_ev(v, env, "damping.modal") for v in z] if isinstance(z, list) else [_ev(z, env, "damping.modal")] * md.n
        if len(zs) != md.n or any(v < 0 for v in zs) or all(v == 0 for v in zs):
            raise Rejected("damping.modal: one ratio >= 0 per mode")
        md.modal = zs


def _initial(value, n: int, env: dict, chain: bool) -> list:
    if value is None:
        return [mp.mpf(0)] * n
    if isinstance(value, list):
        return [mp.mpf(float(v)) for v in value]
    # a [chain] expression of i and n: the product evaluates it in float64, so does the oracle's state
    return [mp.mpf(float(_ev(value, {**env, "i": mp.mpf(i), "n": mp.mpf(n)}, "initial"))) for i in range(n)]


# -- precision -----------------------------------------------------------------------------------------
def close(a, b, rel) -> bool:
    """|a - b| <= rel * max(|a|, |b|) elementwise (nested lists/matrices, mpf or mpc)."""
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(close(x, y, rel) for x, y in zip(a, b))
    return abs(a - b) <= rel * max(abs(a), abs(b)) or a == b


def settled(fn, dps: int, extra: int = 25, rel: float = 1e-22, top: int = 1200, floor: float = 0.0):
    """``fn(dps)`` computed at ``dps`` and ``dps + extra`` digits until two agree: every flattened number to
    ``rel`` relative plus ``floor`` times the largest; returns the higher-precision result."""
    with mp.workdps(dps):
        prev = fn(dps)
    while dps < top:
        dps = dps + extra
        with mp.workdps(dps):
            cur = fn(dps)
        fa, fb = _flat(prev), _flat(cur)
        scale = max((abs(v) for v in fb), default=mp.mpf(0))
        if len(fa) == len(fb) and all(abs(x - y) <= rel * max(abs(x), abs(y)) + floor * scale
                                      for x, y in zip(fa, fb)):
            return cur
        prev, extra = cur, extra * 2
    raise Unsupported(f"not settled at {top} digits")


def _flat(v) -> list:
    if isinstance(v, (list, tuple)):
        return [x for e in v for x in _flat(e)]
    if isinstance(v, mpmath.matrix):
        return [v[i, j] for i in range(v.rows) for j in range(v.cols)]
    if isinstance(v, dict):
        return [x for k in sorted(v) for x in _flat(v[k])]
    if isinstance(v, (mp.mpf, mp.mpc)):
        return [v]
    if hasattr(v, "flat"):
        return v.flat()
    return []


def _digits(x) -> int:
    return int(mp.ceil(mp.log10(x))) if x > 1 else 0


def contrast_digits(md: Model) -> int:
    """Decimal digits of the element contrast (masses, spring constants at rest, dashpots)."""
    vals = [abs(v) for v in md.m]
    vals += [abs(s.k) for s in md.springs if s.k is not None]
    vals += [abs(c) for *_, c in md.dampers]
    vals = [v for v in vals if v > 0]
    return _digits(max(vals) / min(vals)) if vals else 0


# -- statics ---------------------------------------------------------------------------------------------
@dataclass
class Equilibrium:
    """x_eq (N,), each spring's extension and stiffness there, and whether it is stable."""

    x: list
    extensions: list
    stiffness: list
    stable: bool
    closed_form_zero: bool = False
    #: Free pieces under a net constant load: they accelerate as a whole; x is relative to that motion.
    accelerating: list = field(default_factory=list)

    def flat(self):
        return list(self.x) + list(self.extensions) + list(self.stiffness)


def extensions(md: Model, x) -> list:
    return [(x[s.b] if s.b != WALL else 0) - (x[s.a] if s.a != WALL else 0) for s in md.springs]


def gradient(md: Model, x) -> list:
    """dV/dx (N,)."""
    g = [mp.mpf(0)] * md.n
    for s, d in zip(md.springs, extensions(md, x)):
        t = s.tension(d)
        if s.a != WALL:
            g[s.a] -= t
        if s.b != WALL:
            g[s.b] += t
    return g


def hessian(md: Model, x) -> mpmath.matrix:
    """K(x) = d²V/dx² (N × N), stamped spring by spring."""
    K = mp.zeros(md.n, md.n)
    for s, d in zip(md.springs, extensions(md, x)):
        _stamp(K, s.a, s.b, s.stiffness(d))
    return K


def _stamp(A, a, b, c) -> None:
    if a != WALL:
        A[a, a] += c
    if b != WALL:
        A[b, b] += c
    if a != WALL and b != WALL:
        A[a, b] -= c
        A[b, a] -= c


def equilibrium(md: Model, start=None) -> Equilibrium:
    """The static equilibrium under the constant loads, continued from the rest configuration x = 0.

    Free pieces keep their centre of mass at 0 (their position is otherwise undetermined); a free piece
    with a net constant load accelerates (:class:`NoEquilibrium`). With ``start``, Newton from there
    (to check another solver's equilibrium).
    """
    with mp.workdps(md.dps):
        return _equilibrium(md, start)


def _equilibrium(md: Model, start) -> Equilibrium:
    n = md.n
    load = md.constant_load()
    accelerating = []
    for piece in md.free_pieces():  # a free piece under a net load: its equilibrium relative to its own
        net = mp.fsum(load[i] for i in piece)  # uniform acceleration a (each mass feels -m a more)
        if abs(net) > mp.mpf(10) ** (-md.dps // 2) * max(mp.fsum(abs(load[i]) for i in piece), 1e-300):
            a = net / mp.fsum(md.m[i] for i in piece)
            for i in piece:
                load[i] -= md.m[i] * a
            accelerating.append(piece)
    zero = [mp.mpf(0)] * n
    g0 = gradient(md, zero)
    at_rest = all(abs(load[i] - g0[i]) <= mp.mpf(10) ** (-md.dps + 5) * (abs(load[i]) + abs(g0[i]) + 0)
                  for i in range(n))
    if at_rest and start is None:
        return _finish(md, zero, closed_form_zero=True, accelerating=accelerating)
    if start is not None:
        x = _newton(md, [mp.mpf(v) for v in start], load, g0, mp.mpf(1))
        if x is None:
            raise NoEquilibrium("Newton from the given point did not converge")
        return _finish(md, x, accelerating=accelerating)
    tree = _tree_equilibrium(md, load)
    if tree is not None:
        return _finish(md, tree, accelerating=accelerating)
    lam, step, x = mp.mpf(0), mp.mpf(1), zero
    trials = 0
    while lam < 1:
        trials += 1
        if trials > 60:
            raise Unsupported("equilibrium: the continuation in the load needs more than 60 steps")
        trial = min(lam + step, mp.mpf(1))
        y = _newton(md, x, load, g0, trial)
        if y is not None and _stable(md, y):
            x, lam = y, trial
            step = min(step * 2, mp.mpf(1))
        else:
            step /= 4
            if step < mp.mpf("1e-4"):
                raise NoEquilibrium(f"the branch from x = 0 ends at {mpmath.nstr(lam, 6)} of the load (a fold: "
                                    "V'' reaches 0) or Newton fails")
    return _finish(md, x, accelerating=accelerating)


class _Bundle:
    """The springs between one pair of ends (p < q, the wall -1 lowest) as one law of D = x_q − x_p."""

    def __init__(self, p: int, q: int):
        self.p, self.q, self.members = p, q, []  # (spring, +1 if it runs p -> q)

    @property
    def key(self) -> str:
        return "+".join(s.key for s, _ in self.members)

    def tension(self, D):
        return mp.fsum(sg * s.tension(sg * D) for s, sg in self.members)

    def stiffness(self, D):
        return mp.fsum(s.stiffness(sg * D) for s, sg in self.members)


def _tree_equilibrium(md: Model, load):
    """The equilibrium of a statically determinate scene (its graph of spring bundles, the wall one node, has no
    loop; springs between the same two ends act as one): each bundle's tension is the load beyond it, each
    extension solves tension(D) = T on the branch of D = 0 (stiffness > 0 from 0 to D, else
    :class:`NoEquilibrium`), positions follow from the wall (free pieces: their centre of mass at 0). None for a
    scene with a loop (Newton then)."""
    n = md.n
    bundles: dict = {}
    for s in md.springs:
        p, q = sorted((s.a, s.b))
        bundles.setdefault((p, q), _Bundle(p, q)).members.append((s, 1 if (s.a, s.b) == (p, q) else -1))
    adj: dict = {v: [] for v in range(-1, n)}
    for key, b in bundles.items():
        adj[b.p].append((b.q, key))
        adj[b.q].append((b.p, key))
    seen, order, parent = set(), [], {}
    for root in [WALL] + list(range(n)):
        if root in seen:
            continue
        seen.add(root)
        stack = [root]
        parent[root] = None
        while stack:
            v = stack.pop()
            order.append(v)
            for w, key in adj[v]:
                if w in seen:
                    if parent.get(v) is None or parent[v][1] != key:
                        return None  # a loop
                    continue
                seen.add(w)
                parent[w] = (v, key)
                stack.append(w)
    beyond = {v: (load[v] if v != WALL else mp.mpf(0)) for v in range(-1, n)}
    for v in reversed(order):  # loads summed up each subtree
        if parent.get(v) is not None:
            beyond[parent[v][0]] += beyond[v]
    x = {WALL: mp.mpf(0)}
    for v in order:
        if parent.get(v) is None:
            x[v] = x.get(v, mp.mpf(0))
            continue
        u, key = parent[v]
        b = bundles[key]
        # the subtree below v pulls with its load: tension(D) = load if v is the bundle's q end, -load if its p end
        D = _extension_for(b, beyond[v] if b.q == v else -beyond[v])
        x[v] = x[u] + D if b.q == v else x[u] - D
    xs = [x[i] for i in range(n)]
    for piece in md.free_pieces():
        shift = mp.fsum(md.m[i] * xs[i] for i in piece) / mp.fsum(md.m[i] for i in piece)
        for i in piece:
            xs[i] -= shift
    return xs


def _extension_for(s, T):
    """d with V'(d) = T on the branch of d = 0 where V'' > 0 (``s``: a :class:`Spring` or a :class:`_Bundle`)."""
    t0 = s.tension(mp.mpf(0))
    if T == t0:
        return mp.mpf(0)
    sign = 1 if T > t0 else -1
    f = lambda d: s.tension(d) - T  # noqa: E731 - increasing along the branch

    def ok(d):
        try:
            return mp.isfinite(s.tension(d)) and s.stiffness(d) > 0
        except (ExpressionError, ZeroDivisionError):
            return False

    if not ok(mp.mpf(0)):
        raise NoEquilibrium(f"{s.key}: V''(0) <= 0")
    h = mp.mpf(1)
    lo = None
    for _ in range(4000):  # the crossing between h/2 and h, on a doubling/halving search
        crossed = ok(sign * h) and sign * f(sign * h) >= 0
        if not ok(sign * h) or crossed:
            if h < mp.mpf(10) ** -600:
                break
            lo, h = h, h / 2
            continue
        if lo is not None:
            break
        h *= 2
        if h > mp.mpf(10) ** 600:
            raise NoEquilibrium(f"{s.key}: no extension carries the tension {mpmath.nstr(T, 6)}")
    if lo is not None and not ok(sign * lo):  # the law ends (a pole, a fold) between h and lo: is it crossed first?
        for _ in range(4 * mp.prec):
            mid = (h + lo) / 2
            if not ok(sign * mid) or sign * f(sign * mid) >= 0:
                lo = mid
                if ok(sign * lo):
                    break
            else:
                h = mid
    if lo is None or not ok(sign * lo) or not sign * f(sign * lo) >= 0:
        raise NoEquilibrium(f"{s.key}: the tension {mpmath.nstr(T, 6)} is beyond the law's stable branch (a fold)")
    a, b = sign * h, sign * lo
    for k in range(17):  # the branch stays stable between 0 and the root
        if not ok(b * k / 16):
            raise NoEquilibrium(f"{s.key}: V'' <= 0 between 0 and the extension carrying {mpmath.nstr(T, 6)}")
    fa, fb = f(a), f(b)
    if fa == 0:
        return a
    return bracketed_root(f, min(a, b), max(a, b), fa if a < b else fb, fb if a < b else fa)


def _constraints(md: Model) -> list[list]:
    """Rows of Σ m_i x_i = 0 for each free piece."""
    rows = []
    for piece in md.free_pieces():
        r = [mp.mpf(0)] * md.n
        for i in piece:
            r[i] = md.m[i]
        rows.append(r)
    return rows


def _newton(md: Model, x, load, g0, lam, iters: int = 80):
    """Newton on grad V(x) = λ·loads + (1 − λ)·grad V(0), each step halved until the residual decreases
    (a cubic term far beyond the linear one makes the plain Newton step overshoot by decades)."""
    n = md.n
    rows = _constraints(md)
    x = list(x)
    target = [lam * load[i] + (1 - lam) * g0[i] for i in range(n)]
    scale = max([abs(v) for v in target] + [abs(v) for v in g0] + [mp.mpf(10) ** -300])
    tol = mp.mpf(10) ** (-md.dps + 12) * scale

    def residual(y):
        try:
            g = gradient(md, y)
        except (ExpressionError, ZeroDivisionError):
            return None, mp.inf
        r = [target[i] - g[i] for i in range(n)]
        ok = all(mp.isfinite(v) for v in r)
        return r, (mp.fsum(v * v for v in r) if ok else mp.inf)

    r, norm = residual(x)
    stalls = 0
    for _ in range(iters):
        if DEBUG:
            print("newton", [mpmath.nstr(v, 5) for v in x], mpmath.nstr(norm, 5))
        if norm == mp.inf:
            return None
        try:
            H = hessian(md, x)
        except (ExpressionError, ZeroDivisionError):
            return None
        m = len(rows)
        A = mp.zeros(n + m, n + m)
        rhs = mp.zeros(n + m, 1)
        # H and the constraint rows scaled to order one apart (mpmath's LU calls pivots below eps·|A| singular)
        sh = max([abs(H[i, j]) for i in range(n) for j in range(n)] + [mp.mpf(10) ** -300])
        sm = max([abs(v) for row in rows for v in row] + [mp.mpf(1)])
        for i in range(n):
            rhs[i] = r[i] / sh
            for j in range(n):
                A[i, j] = H[i, j] / sh
        for c, row in enumerate(rows):
            for i in range(n):
                A[n + c, i] = row[i] / sm
                A[i, n + c] = row[i] / sm
            rhs[n + c] = -mp.fsum(row[i] * x[i] for i in range(n)) / sm
        try:
            dx = mp.lu_solve(A, rhs)
        except ZeroDivisionError:
            return None
        if max(abs(v) for v in r) <= tol:
            return [x[i] + dx[i] for i in range(n)]
        # a trust region: at most doubling the displacement per step (a law soft at rest and stiff further out,
        # such as cosh or exp with a tiny coefficient, sends the plain Newton step decades too far)
        size = max(abs(dx[i]) for i in range(n))
        cap = 1 + 2 * max(abs(v) for v in x)
        step, halvings = (mp.mpf(1) if size <= cap else cap / size), 0
        if size > cap:  # walking toward where Newton points: the residual may not change in the working digits
            y = [x[i] + step * dx[i] for i in range(n)]
            ry, ny = residual(y)
            if ny < mp.inf:
                x, r, norm = y, ry, ny
                continue
        for halvings in range(220):
            y = [x[i] + step * dx[i] for i in range(n)]
            ry, ny = residual(y)
            if ny < norm or step < mp.mpf(10) ** (-md.dps):
                break
            step /= 2
        if ny >= norm:
            return None
        if halvings > 30 or (ny > norm * mp.mpf("0.999") and size <= cap):  # no progress: past a fold
            stalls += 1
            if stalls > 3:
                return None
        x, r, norm = y, ry, ny
    if max(abs(v) for v in r) <= tol * 1e6:
        return x
    return None


def _stable(md: Model, x) -> bool:
    """The Hessian is positive definite but for the free pieces' translations: so it is when every spring has
    V'' > 0 (a sum of positive rank-one terms over the spring graph); otherwise its elastic eigenvalues decide,
    at the digits the contrast needs."""
    try:
        stiff = [s.stiffness(d) for s, d in zip(md.springs, extensions(md, x))]
        if all(k > 0 for k in stiff):
            return True
        with mp.workdps(max(md.dps, 40 + 2 * contrast_digits(md))):
            lam = _elastic_eigenvalues(md, hessian(md, x))
    except (ZeroDivisionError, ExpressionError):
        return False
    return all(v > 0 for v in lam)


def _elastic_eigenvalues(md: Model, K) -> list:
    D = _dynamical(md, K)
    E = mp.eigsy(D, eigvals_only=True)
    vals = sorted(E[i] for i in range(md.n))
    return vals[len(md.free_pieces()):]


def _finish(md: Model, x, closed_form_zero=False, accelerating=()) -> Equilibrium:
    ext = extensions(md, x)
    stiff = [s.stiffness(d) for s, d in zip(md.springs, ext)]
    return Equilibrium(list(x), ext, stiff, _stable(md, x), closed_form_zero, list(accelerating))


def static_equilibrium(md: Model) -> Equilibrium:
    """:func:`equilibrium` settled in precision."""
    return settled(lambda dps: equilibrium(md.at(dps)), max(md.dps, 50))


# -- modes -----------------------------------------------------------------------------------------------
def _dynamical(md: Model, K) -> mpmath.matrix:
    n = md.n
    s = [1 / mp.sqrt(v) for v in md.m]
    D = mp.zeros(n, n)
    for i in range(n):
        for j in range(n):
            D[i, j] = K[i, j] * s[i] * s[j]
    return D


@dataclass
class ModeSet:
    """Undamped modes about the equilibrium: ω² ascending (rigid zeros exact), orthonormal eigenvectors Φ of D
    (columns), physical mass-normalised shapes φ = M^-1/2 Φ (columns), K and the equilibrium."""

    omega2: list
    Phi: object
    shapes: object
    K: object
    rigid: int
    x_eq: list

    def flat(self):
        return list(self.omega2)


def _modes_at(md: Model, x_eq=None) -> ModeSet:
    n = md.n
    if x_eq is None:
        x_eq = [mp.mpf(0)] * n
    K = hessian(md, x_eq)
    D = _dynamical(md, K)
    E, Q = mp.eigsy(D)
    order = sorted(range(n), key=lambda j: E[j])
    lam = [E[j] for j in order]
    Phi = mp.matrix(n, n)
    for c, j in enumerate(order):
        for i in range(n):
            Phi[i, c] = Q[i, j]
    rigid = len(md.free_pieces())
    top = max([abs(v) for v in lam] + [mp.mpf(10) ** -300])
    if rigid and lam[0] < -mp.mpf(10) ** (-md.dps // 2) * top:
        raise NoEquilibrium(f"unstable: K has the negative eigenvalue {mpmath.nstr(lam[0], 6)} (M-scaled)")
    for j in range(rigid):
        if abs(lam[j]) > mp.mpf(10) ** (-md.dps // 2) * top:
            raise OracleError(f"rigid mode {j}: eigenvalue {lam[j]} is not 0")
        lam[j] = mp.mpf(0)
    _exact_rigid(md, Phi, rigid)
    shapes = mp.matrix(n, n)
    for i in range(n):
        for j in range(n):
            shapes[i, j] = Phi[i, j] / mp.sqrt(md.m[i])
    return ModeSet(lam, Phi, shapes, K, rigid, list(x_eq))


def _exact_rigid(md: Model, Phi, rigid: int) -> None:
    """Rigid columns: the orthonormal translations M^1/2 1_piece of the free pieces (exact by structure)."""
    for c, piece in enumerate(md.free_pieces()[:rigid]):
        norm = mp.sqrt(mp.fsum(md.m[i] for i in piece))
        for i in range(md.n):
            Phi[i, c] = mp.sqrt(md.m[i]) / norm if i in piece else mp.mpf(0)


def modes(md: Model, eq: Equilibrium | None = None) -> ModeSet:
    """ω², Φ and shapes about ``eq`` (None: about x = 0), settled in precision."""
    base = max(md.dps, 40 + 2 * contrast_digits(md))

    def at(dps):
        m2 = md.at(dps)
        return _modes_at(m2, _eq_at(m2, eq, dps))

    with mp.workdps(base):
        first = at(base)
    nz = [v for v in first.omega2 if v > 0]
    need = 40 + (_digits(max(nz) / min(nz)) if nz else 0) + contrast_digits(md)
    return settled(at, max(base, need), extra=20)


def needs_equilibrium(md: Model) -> bool:
    """Constant loads or prestress that a nonlinear spring sees (else the modes are about x = 0 exactly)."""
    load, pre = md.constant_load(), md.prestress()
    return any(v != 0 for v in load) or any(v != 0 for v in pre)


# -- damping ---------------------------------------------------------------------------------------------
def rayleigh_from_targets(md: Model, ms: ModeSet):
    (za, zb), (ja, jb) = md.targets
    el = [mp.sqrt(v) for v in ms.omega2[ms.rigid:]]
    wa, wb = el[ja - 1], el[jb - 1]
    if za == zb:
        return 2 * za * wa * wb / (wa + wb), 2 * za / (wa + wb)
    den = (wb - wa) * (wb + wa)
    return 2 * wa * wb * (za * wb - zb * wa) / den, 2 * (zb * wb - za * wa) / den


def damping_matrix(md: Model, ms: ModeSet) -> mpmath.matrix:
    """C (N × N): dashpots, Rayleigh αM + βK (K the stiffness of the modes), modal M Φ diag(2ζω) Φᵀ M."""
    n = md.n
    C = mp.zeros(n, n)
    for a, b, c in md.dampers:
        _stamp(C, a, b, c)
    ab = md.rayleigh if md.rayleigh is not None else (rayleigh_from_targets(md, ms) if md.targets else None)
    if ab is not None:
        alpha, beta = ab
        for i in range(n):
            C[i, i] += alpha * md.m[i]
            for j in range(n):
                C[i, j] += beta * ms.K[i, j]
    if md.modal is not None:
        w = [2 * z * mp.sqrt(l) for z, l in zip(md.modal, ms.omega2)]
        for i in range(n):
            for j in range(n):
                C[i, j] += mp.sqrt(md.m[i] * md.m[j]) * mp.fsum(ms.Phi[i, k] * w[k] * ms.Phi[j, k] for k in range(n))
    return C


def modal_damping(md: Model, ms: ModeSet, C) -> mpmath.matrix:
    """G = Φᵀ M^-1/2 C M^-1/2 Φ (N × N)."""
    n = md.n
    s = [1 / mp.sqrt(v) for v in md.m]
    Ct = mp.matrix(n, n)
    for i in range(n):
        for j in range(n):
            Ct[i, j] = C[i, j] * s[i] * s[j]
    return ms.Phi.T * Ct * ms.Phi


@dataclass
class Damped:
    """ζ per undamped mode (diagonal of G / 2ω: exact when damping is proportional), whether G is
    diagonal, and the eigenvalues λ of the quadratic problem with Im λ >= 0 (complex modes), by |λ|."""

    zeta_diag: list
    proportional: bool
    eigenvalues: list
    nearly_proportional: bool = False  # off-diagonal ΦᵀCΦ within 1e-10 of the diagonal

    def flat(self):
        return list(self.zeta_diag) + [v for lam in self.eigenvalues for v in (mp.re(lam), mp.im(lam))]


def damped(md: Model, eq: Equilibrium | None = None) -> Damped:
    base = max(60, 40 + 2 * contrast_digits(md))

    def at(dps):
        m2 = md.at(dps)
        ms = _modes_at(m2, _eq_at(m2, eq, dps))
        C = damping_matrix(m2, ms)
        G = modal_damping(m2, ms, C)
        n = m2.n
        top = max([abs(G[i, j]) for i in range(n) for j in range(n)] + [mp.mpf(10) ** -300])
        groups = degenerate_groups(ms.omega2)
        same = {(i, j) for g in groups for i in g for j in g}
        # proportional: G is diagonal between different frequencies (inside a repeated ω any basis is a
        # basis of modes, so the block is diagonalised by a rotation)
        prop = all(abs(G[i, j]) <= mp.mpf(10) ** (-dps // 2) * top for i in range(n) for j in range(n)
                   if (i, j) not in same)
        # the README's test (rsa): off-diagonal terms within 1e-10 of the diagonal (their effect is second order)
        near = all(abs(G[i, j]) <= mp.mpf("1e-10") * mp.sqrt(abs(G[i, i] * G[j, j])) for i in range(n) for j in range(n)
                   if (i, j) not in same)
        zd = [mp.mpf(0)] * n
        for g in groups:
            block = mp.matrix(len(g), len(g))
            for a, i in enumerate(g):
                for b, j in enumerate(g):
                    block[a, b] = G[i, j]
            ev = sorted(mp.eigsy(block, eigvals_only=True)) if len(g) > 1 else [G[g[0], g[0]]]
            for j, v in zip(g, ev):
                zd[j] = v / (2 * mp.sqrt(ms.omega2[j])) if ms.omega2[j] > 0 else mp.mpf(0)
        return Damped(zd, prop, _quadratic_eigenvalues(ms, G), near)

    return settled(at, base, extra=30, rel=1e-18, floor=1e-75)


def degenerate_groups(omega2) -> list[list[int]]:
    """Index groups of equal ω² (to half the working precision: exact symmetry, not near-coincidence)."""
    groups: list = []
    for j, v in enumerate(omega2):
        if groups and abs(v - omega2[groups[-1][-1]]) <= mp.mpf(10) ** (-mp.dps // 2) * max(abs(v), mp.mpf(10) ** -300):
            groups[-1].append(j)
        else:
            groups.append([j])
    return groups


def _eq_at(m2: Model, eq, dps):
    """``eq.x`` refined by Newton at the model's precision (None: x = 0)."""
    if eq is None:
        return None
    x = [mp.mpf(v) for v in eq.x]
    if any(v != 0 for v in x):
        try:
            x = equilibrium(m2, start=x).x
        except NoEquilibrium:  # Newton from the lower-precision point stalls: solve again at this precision
            x = equilibrium(m2).x
    return x


def _quadratic_eigenvalues(ms: ModeSet, G) -> list:
    """Eigenvalues of q'' + G q' + Λ q = 0 with Im >= 0 (decoupled undamped rigid modes left out)."""
    keep = [j for j in range(len(ms.omega2))
            if not (ms.omega2[j] == 0 and all(G[j, k] == 0 or abs(G[j, k]) < mp.mpf(10) ** (-mp.dps // 2)
                                              for k in range(len(ms.omega2))))]
    A, _ = _state_matrix(ms, G, keep)
    if A.rows == 0:
        return []
    E = mp.eig(A, left=False, right=False)
    vals = [E[i] for i in range(A.rows)]
    vals = [v for v in vals if mp.im(v) >= -mp.mpf(10) ** (-mp.dps // 2) * abs(v)]
    return sorted(vals, key=lambda v: (abs(v), mp.re(v)))


def _state_matrix(ms: ModeSet, G, keep):
    """A = [[0, S], [-Λ S^-1, -G]] on the modes ``keep`` (S = ω, or 1 for a rigid mode)."""
    m = len(keep)
    A = mp.zeros(2 * m, 2 * m)
    S = [mp.sqrt(ms.omega2[j]) if ms.omega2[j] > 0 else mp.mpf(1) for j in keep]
    for r, j in enumerate(keep):
        A[r, m + r] = S[r]
        A[m + r, r] = -ms.omega2[j] / S[r]
        for c, k in enumerate(keep):
            A[m + r, m + c] = -G[j, k]
    return A, S


# -- participation ---------------------------------------------------------------------------------------
def participation(md: Model, ms: ModeSet) -> list:
    """Γ_j = φ_jᵀ M 1 (φ mass-normalised; the sign of Φ's column)."""
    return [mp.fsum(ms.Phi[i, j] * mp.sqrt(md.m[i]) for i in range(md.n)) for j in range(md.n)]


# -- frequency response --------------------------------------------------------------------------------
def receptance(md: Model, omegas, i: int, o: int, eq: Equilibrium | None = None, dps: int | None = None,
               settle: bool = True) -> list:
    """H(iω) = X_o / F_i of (K − ω² M + iωC) X = F at each ω (float or mpf), settled in precision (``settle``
    False: once, at ``dps``; for ω on a pole, where more digits only move the pole)."""
    base = dps or max(60, 40 + 2 * contrast_digits(md))

    def at(dps):
        m2 = md.at(dps)
        ms = _modes_at(m2, _eq_at(m2, eq, dps))
        C = damping_matrix(m2, ms) if m2.damped else None
        out = []
        for w in omegas:
            w = mp.mpf(w)
            Z = mp.matrix(m2.n, m2.n)
            for r in range(m2.n):
                for c in range(m2.n):
                    Z[r, c] = ms.K[r, c] + (1j * w * C[r, c] if C is not None else 0)
                Z[r, r] -= w * w * m2.m[r]
            e = mp.zeros(m2.n, 1)
            e[i] = 1
            try:
                out.append(mp.mpc(mp.lu_solve(Z, e)[o]))
            except ZeroDivisionError:
                out.append(mp.mpc(mp.inf))
        return out

    if not settle:
        with mp.workdps(base):
            return at(base)
    return settled(at, base, extra=40, rel=1e-15, floor=1e-30)


# -- exact trajectories (linear scenes) -------------------------------------------------------------------
def _e1(z):
    """(e^z − 1)/z, 1 at z = 0 (no cancellation)."""
    if abs(z) < mp.mpf("0.05"):
        return mp.fsum(z**k / mp.factorial(k + 1) for k in range(60))
    return mp.expm1(z) / z if not isinstance(z, mp.mpc) else (mp.exp(z) - 1) / z


def _e2(z):
    """(e^z − 1 − z)/z², 1/2 at z = 0."""
    if abs(z) < mp.mpf("0.05"):
        return mp.fsum(z**k / mp.factorial(k + 2) for k in range(60))
    return (mp.exp(z) - 1 - z) / z**2


@dataclass
class Trajectory:
    """Positions and velocities (N,) at each requested time."""

    times: list
    x: list
    v: list

    def flat(self):
        return [c for row in self.x + self.v for c in row]


def trajectory(md: Model, times, eq: Equilibrium | None = None) -> Trajectory:
    """The exact motion of a linear scene from its initial state at ``times`` (floats, >= 0), settled."""
    if not md.linear:
        raise Unsupported("nonlinear springs: no exact solution")
    for ld in md.loads:
        if isinstance(ld.signal, _Opaque):
            raise Unsupported(f"{ld.key}: {ld.signal.why}")
    tmax = max(float(t) for t in times) if times else 0.0
    ms0 = modes(md)
    wmax = mp.sqrt(max(ms0.omega2)) if ms0.omega2 else 0
    nz = [v for v in ms0.omega2 if v > 0]
    base = 50 + _digits(wmax * tmax + 1) + (_digits(max(nz) / min(nz)) if nz else 0) + 2 * contrast_digits(md)
    return settled(lambda dps: _trajectory_at(md.at(dps), [mp.mpf(float(t)) for t in times]), base, extra=30,
                   rel=1e-20, floor=1e-30)


def _trajectory_at(md: Model, times) -> Trajectory:
    n = md.n
    ms = _modes_at(md)  # linear: K does not depend on x
    # prestress of linear potentials (V = T0 d + k d²/2) acts as a constant load
    pre = md.prestress()
    loads = list(md.loads) + ([Load(pre, Harm.constant(1), "prestress")] if any(v != 0 for v in pre) else [])
    C = damping_matrix(md, ms) if md.damped else mp.zeros(n, n)
    G = modal_damping(md, ms, C)
    sq = [mp.sqrt(v) for v in md.m]
    to_modal = lambda vec: [mp.fsum(ms.Phi[i, j] * vec[i] for i in range(n)) for j in range(n)]  # noqa: E731
    q0 = to_modal([sq[i] * md.x0[i] for i in range(n)])
    p0 = to_modal([sq[i] * md.v0[i] for i in range(n)])
    fl = [(to_modal([ld.b[i] / sq[i] for i in range(n)]), ld.signal) for ld in loads]
    tiny = mp.mpf(10) ** (-md.dps // 2) * max([abs(G[i, j]) for i in range(n) for j in range(n)] + [mp.mpf(1)])
    free = [j for j in range(n) if ms.omega2[j] == 0 and all(abs(G[j, k]) <= tiny for k in range(n))]
    keep = [j for j in range(n) if j not in free]
    q = {j: [None] * len(times) for j in range(n)}
    p = {j: [None] * len(times) for j in range(n)}
    for j in free:  # q'' = f(t): closed form
        for r, t in enumerate(times):
            qq, pp = q0[j] + p0[j] * t, p0[j]
            for f, sig in fl:
                a1, a2 = _double_integral(sig, t)
                qq += f[j] * a2
                pp += f[j] * a1
            q[j][r], p[j][r] = qq, pp
    if keep:
        A, S = _state_matrix(ms, G, keep)
        m = len(keep)
        undamped = all(abs(G[j, k]) <= tiny for j in keep for k in keep)
        mu, V, W = _eigen(A, m, undamped)
        w0 = [S[r] * q0[j] for r, j in enumerate(keep)] + [p0[j] for j in keep]
        eta0 = [mp.fsum(W[a, b] * w0[b] for b in range(2 * m)) for a in range(2 * m)]
        beta = [[mp.fsum(W[a, m + r] * f[j] for r, j in enumerate(keep)) for a in range(2 * m)] for f, _ in fl]
        for r, t in enumerate(times):
            eta = [mp.exp(mu[a] * t) * eta0[a] for a in range(2 * m)]
            for (f, sig), bet in zip(fl, beta):
                for a in range(2 * m):
                    eta[a] += bet[a] * _forced(mu[a], sig, t)
            w = [mp.fsum(V[c, a] * eta[a] for a in range(2 * m)) for c in range(2 * m)]
            for c, j in enumerate(keep):
                q[j][r] = mp.re(w[c]) / S[c]
                p[j][r] = mp.re(w[m + c])
    xs, vs = [], []
    for r in range(len(times)):
        xs.append([mp.fsum(ms.Phi[i, j] * q[j][r] for j in range(n)) / sq[i] for i in range(n)])
        vs.append([mp.fsum(ms.Phi[i, j] * p[j][r] for j in range(n)) / sq[i] for i in range(n)])
    return Trajectory(list(times), xs, vs)


def _eigen(A, m: int, undamped: bool):
    """Eigenvalues μ, right vectors V and V^-1 of the modal state matrix (analytic when undamped)."""
    if undamped:  # blocks [[0, ω], [-ω, 0]]: μ = ±iω, vectors (1, ±i)/√2
        mu = [mp.mpc(0, A[r, m + r]) for r in range(m)] + [mp.mpc(0, -A[r, m + r]) for r in range(m)]
        V = mp.zeros(2 * m, 2 * m)
        W = mp.zeros(2 * m, 2 * m)
        h = 1 / mp.sqrt(2)
        for r in range(m):
            V[r, r], V[m + r, r] = h, mp.mpc(0, h)
            V[r, m + r], V[m + r, m + r] = h, mp.mpc(0, -h)
            W[r, r], W[r, m + r] = h, mp.mpc(0, -h)
            W[m + r, r], W[m + r, m + r] = h, mp.mpc(0, h)
        return mu, V, W
    E, V = mp.eig(A)
    cond = mp.norm(V, 1) * mp.norm(mp.inverse(V), 1)
    if cond > mp.mpf(10) ** (mp.dps // 3):
        raise Unsupported("a defective state matrix (critical damping)")
    return [E[i] for i in range(2 * m)], V, mp.inverse(V)


def _forced(mu, sig, t):
    """∫_0^t e^{μ(t−s)} u(s) ds for a signal u (Harm or Table)."""
    if isinstance(sig, Harm):
        return mp.fsum(c * mp.exp(mu * t) * t * _e1((1j * w - mu) * t) for w, c in sig.terms.items())
    out = mp.mpc(0)
    for a, b, ya, slope in _pieces(sig, t):
        h = b - a
        out = out * mp.exp(mu * h) + ya * h * _e1(mu * h) + slope * h * h * _e2(mu * h)
    return out


def _pieces(tab: Table, t):
    """(a, b, y(a+), slope) of each linear piece of a table signal over [0, t], zero pieces included."""
    cuts = sorted({mp.mpf(0), t} | {r for r in tab.t if 0 < r < t})
    for a, b in zip(cuts, cuts[1:]):
        ya, yb = tab.value(a, 1), tab.value(b, -1)
        yield a, b, ya, (yb - ya) / (b - a)


def _double_integral(sig, t):
    """(∫_0^t u, ∫_0^t ∫_0^s u) of a signal."""
    if isinstance(sig, Harm):
        i1 = i2 = mp.mpc(0)
        for w, c in sig.terms.items():
            z = 1j * w * t
            i1 += c * t * _e1(z)
            i2 += c * t * t * _e2(z)
        return mp.re(i1), mp.re(i2)
    v = p = mp.mpf(0)  # integrate the piecewise-linear signal twice, piece by piece
    for a, b, ya, slope in _pieces(sig, t):
        h = b - a
        p += v * h + ya * h * h / 2 + slope * h**3 / 6
        v += ya * h + slope * h * h / 2
    return v, p


def spring_series(md: Model, xs) -> tuple[list, list, list]:
    """Drifts x_b − x_a, tensions V'(d) (k d + k3 d³) of every spring, and the base shear Σ of the wall springs'
    force on the ground (+V' for a wall at a, −V' at b), for each row of positions ``xs``."""
    drifts, forces, shear = [], [], []
    for x in xs:
        d = extensions(md, x)
        f = [s.tension(e) for s, e in zip(md.springs, d)]
        drifts.append(d)
        forces.append(f)
        shear.append(mp.fsum((1 if s.a == WALL else -1 if s.b == WALL else 0) * fi for s, fi in zip(md.springs, f)))
    return drifts, forces, shear


# -- response spectra -------------------------------------------------------------------------------------
def sdof_peak(t_rows, a_rows, period, zeta, dps: int = 40) -> mp.mpf:
    """SD = max over t >= t_0 of |u| for u'' + 2ζωu' + ω²u = −a_g(t), a_g linear between the rows, zero
    outside; at rest at the first row; the free vibration after the last row included. Settled."""
    return max(sdof_parts(t_rows, a_rows, period, zeta, dps))


def sdof_parts(t_rows, a_rows, period, zeta, dps: int = 40) -> list:
    """[max |u| over the record (its rows' span), max |u| of the free vibration after it]."""
    t_rows = [mp.mpf(float(v)) for v in t_rows]
    a_rows = [mp.mpf(float(v)) for v in a_rows]

    def at(d):
        with mp.workdps(d):
            return _sdof_peak([+v for v in t_rows], [+v for v in a_rows], 2 * mp.pi / mp.mpf(float(period)),
                              mp.mpf(float(zeta)))

    w = 2 * math.pi / float(period)
    span = float(t_rows[-1] - t_rows[0])
    if w * span / (2 * math.pi) > 20000:
        raise Unsupported(f"{w * span / (2 * math.pi):.3g} periods in the record: too many for the oracle")
    extra = 3 * _digits(mp.mpf(1) / (w * min(float(b - a) for a, b in zip(t_rows, t_rows[1:])))) + _digits(w * span)
    return settled(at, dps + extra, extra=20, rel=1e-20)


def bracketed_root(f, a, b, fa, fb):
    """A root of f in [a, b] (f(a) f(b) < 0) to the working precision: Illinois regula falsi, bisection
    whenever it stalls."""
    for k in range(4 * mp.prec):
        if b - a <= mp.mpf(2) ** (-mp.prec + 4) * max(abs(a), abs(b)):
            break
        c = (a * fb - b * fa) / (fb - fa) if k % 3 != 2 else (a + b) / 2
        if not a < c < b:
            c = (a + b) / 2
        fc = f(c)
        if fc == 0:
            return c
        if (fc > 0) == (fa > 0):
            a, fa = c, fc
            fb /= 2
        else:
            b, fb = c, fc
            fa /= 2
    return (a + b) / 2


def _sdof_segment(u0, v0, a0, s, w, z):
    """u(τ), u'(τ) on a piece with input a0 + s τ: closed form (particular + damped homogeneous)."""
    wd = w * mp.sqrt(1 - z * z)
    up0 = -a0 / w**2 + 2 * z * s / w**3
    vp = -s / w**2
    A = u0 - up0
    B = (v0 - vp + z * w * A) / wd

    def u(tau):
        e = mp.exp(-z * w * tau)
        return up0 - s * tau / w**2 + e * (A * mp.cos(wd * tau) + B * mp.sin(wd * tau))

    def du(tau):
        e = mp.exp(-z * w * tau)
        return vp + e * ((-z * w * A + wd * B) * mp.cos(wd * tau) + (-z * w * B - wd * A) * mp.sin(wd * tau))

    return u, du, wd


def _sdof_peak(ts, az, w, z):
    u0 = v0 = mp.mpf(0)
    best = mp.mpf(0)
    for j in range(len(ts) - 1):
        h = ts[j + 1] - ts[j]
        s = (az[j + 1] - az[j]) / h
        u, du, wd = _sdof_segment(u0, v0, az[j], s, w, z)
        best = max(best, abs(u(h)))
        samples = int(min(200000, 16 * float(h * wd / (2 * mp.pi)) + 16))
        grid = [h * k / samples for k in range(samples + 1)]
        vals = [du(tau) for tau in grid]
        for k in range(samples):
            if vals[k] == 0:
                best = max(best, abs(u(grid[k])))
            elif vals[k] * vals[k + 1] < 0:
                best = max(best, abs(u(bracketed_root(du, grid[k], grid[k + 1], vals[k], vals[k + 1]))))
        u0, v0 = u(h), du(h)
    # free vibration after the record: the first stationary point of u is its largest later extremum
    wd = w * mp.sqrt(1 - z * z)
    A, B = u0, (v0 + z * w * u0) / wd
    P, Q = -z * w * A + wd * B, -z * w * B - wd * A
    theta = (mp.atan2(Q, P) + mp.pi / 2) % mp.pi
    tau = theta / wd
    free = mp.exp(-z * w * tau) * (A * mp.cos(theta) + B * mp.sin(theta))
    return [best, max(abs(u0), abs(free))]


# -- response-spectrum analysis --------------------------------------------------------------------------
def cqc_rho(wi, wj, zi, zj):
    """Der Kiureghian's ρ_ij with r = ω_j/ω_i (as the README writes it)."""
    r = wj / wi
    num = 8 * mp.sqrt(zi * zj) * (zi + r * zj) * r ** mp.mpf(1.5)
    den = (1 - r * r) ** 2 + 4 * zi * zj * r * (1 + r * r) + 4 * (zi * zi + zj * zj) * r * r
    if den == 0:
        return mp.mpf(1)
    return num / den


@dataclass
class RSARef:
    omega: list
    zeta: list
    gamma: list
    sd: list
    displacement: list  # J x N
    drift: list  # J x S
    spring_force: list  # J x S
    base_shear: list  # J
    rho: list

    def combined(self, how: str) -> dict:
        J = len(self.omega)

        def comb(rows):
            if not rows or not rows[0]:
                return []
            out = []
            for c in range(len(rows[0])):
                col = [rows[j][c] for j in range(J)]
                if how == "srss":
                    out.append(mp.sqrt(mp.fsum(v * v for v in col)))
                else:
                    out.append(mp.sqrt(max(mp.mpf(0), mp.fsum(self.rho[a][b] * col[a] * col[b]
                                                              for a in range(J) for b in range(J)))))
            return out

        return {"displacement": comb(self.displacement), "drift": comb(self.drift),
                "spring_force": comb(self.spring_force), "base_shear": comb([[v] for v in self.base_shear])[0]}

    def flat(self):
        return list(self.omega) + list(self.gamma) + list(self.sd)


def rsa(md: Model, sd_of, eq: Equilibrium | None = None, dps: int | None = None) -> RSARef:
    """Response-spectrum analysis: ``sd_of(T, ζ)`` gives each elastic mode's SD (float or mpf).

    ζ_j = φ_jᵀ C φ_j / (2ω_j) (the README's convention; exact for proportional damping); spring forces use
    each spring's stiffness at the equilibrium (the linear springs for cubic ones).
    """
    with mp.workdps(dps or max(60, 40 + 2 * contrast_digits(md))):
        m2 = md.at(mp.dps)
        ms = _modes_at(m2, _eq_at(m2, eq, mp.dps))
        if ms.rigid:
            raise Rejected("a free piece: rigid modes")
        G = modal_damping(m2, ms, damping_matrix(m2, ms)) if m2.damped else mp.zeros(m2.n, m2.n)
        n = m2.n
        om = [mp.sqrt(v) for v in ms.omega2]
        ze = [G[j, j] / (2 * om[j]) for j in range(n)]
        gam = participation(m2, ms)
        sd = [mp.mpf(sd_of(2 * mp.pi / om[j], ze[j])) for j in range(n)]
        x_eq = ms.x_eq
        stiff = [s.stiffness(d) if s.potential is not None else s.k for s, d in zip(m2.springs, extensions(m2, x_eq))]
        disp, drift, force, shear = [], [], [], []
        for j in range(n):
            u = [gam[j] * ms.shapes[i, j] * sd[j] for i in range(n)]
            d = extensions(m2, u)
            disp.append(u)
            drift.append(d)
            force.append([k * e for k, e in zip(stiff, d)])
            shear.append(gam[j] ** 2 * ms.omega2[j] * sd[j])
        rho = [[cqc_rho(om[a], om[b], ze[a], ze[b]) for b in range(n)] for a in range(n)]
        return RSARef(om, ze, gam, sd, disp, drift, force, shear, rho)


__all__ = ["read", "Model", "Spring", "Table", "modes", "damped", "participation", "static_equilibrium",
           "equilibrium", "receptance", "trajectory", "spring_series", "sdof_peak", "sdof_parts", "rsa", "cqc_rho",
           "settled", "Unsupported", "NoEquilibrium", "Rejected", "OracleError", "needs_equilibrium", "WALL"]
