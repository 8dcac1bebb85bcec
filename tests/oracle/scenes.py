"""Hypothesis strategies for scenes over the whole domain the README accepts, emitted as TOML text.

Every topology (pieces, walls, loops and rings, ``[chain]`` with free/wall/ring ends, free masses),
every element kind (linear springs, cubic ``k3`` terms, the potential families of the docs — FPUT-α/β,
Toda, Morse, Lennard-Jones, exp/log/cosh/sqrt forms, pre-stressed laws — dashpots, Rayleigh, Rayleigh
from targets and modal damping, expression and table forces, ground motion by expression or table,
gravity, initial states or none) and parameter values log-uniform over a regime drawn per scene:
moderate (1e-2 … 1e2), wide (1e-12 … 1e12) or extreme (the loader's whole 1e-150 … 1e150). Parameter
and mass names are what users write (``a``, ``K``, ``w``, ``E``, ``beta``, ``np``, ``floor1`` ...).

Nothing here imports springchain: the oracle decides what a scene means, the product is asked.
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field
from pathlib import Path

from hypothesis import strategies as st

#: Parameter names a user might write (none reserved by the scene language: t, i, n, pi, sqrt, sin, cos,
#: exp, wall; log, tanh, cosh, sinh and d are legal names but would block those functions).
PARAM_NAMES = ("m", "a", "K", "k", "w", "E", "I", "beta", "gamma", "zeta", "S", "Q", "N", "x", "np", "mu",
               "nu", "lam", "c", "kappa", "alpha", "F0", "Omega", "g", "L", "eps", "r0", "D", "b", "h", "rho",
               "omega", "phi", "A", "B", "M", "T", "V", "G", "out", "float", "energy", "m0", "k1", "c2", "W")
MASS_NAMES = ("p", "q", "r", "s", "u", "floor1", "floor2", "floor3", "top", "base", "m1", "m2", "m3", "bob",
              "atom", "left", "right", "cart", "z1", "y")

REGIMES = {"moderate": (-2.0, 2.0), "wide": (-12.0, 12.0), "extreme": (-140.0, 140.0)}

#: Spring laws given as potentials: (family, template); the placeholders are parameter names.
POTENTIALS = {
    "fput_alpha": ("{k}*d**2/2 + {s}*d**3/3", ("k", "s")),
    "fput_beta": ("{k}*d**2/2 + {s}*d**4/4", ("k", "s")),
    "toda": ("{a}/{b}*exp(-{b}*d) + {a}*d", ("a", "b")),
    "morse": ("{D}*(1 - exp(-{w}*d))**2", ("D", "w")),
    "lennard_jones": ("{e}*(({r}/({r} + d))**12 - 2*({r}/({r} + d))**6)", ("e", "r")),
    "cosh": ("{k}*(cosh({w}*d) - 1)/{w}**2", ("k", "w")),
    "log_cosh": ("{k}*log(cosh({w}*d))/{w}**2", ("k", "w")),
    "exp": ("{k}*(exp({w}*d) - 1 - {w}*d)/{w}**2", ("k", "w")),
    "log_fene": ("-{k}*{L}**2*log(1 - (d/{L})**2)/2", ("k", "L")),
    "sqrt": ("{k}*(sqrt(1 + ({w}*d)**2) - 1)/{w}**2", ("k", "w")),
    "prestressed": ("{T}*d + {k}*d**2/2", ("T", "k")),
    "quadratic": ("{k}*d**2/2", ("k",)),
}
#: Placeholders of shape parameters (lengths, rates) drawn moderate whatever the regime: a law's own
#: length scale is not a stiffness contrast.
SHAPE_KEYS = {"w", "b", "r", "L"}


@dataclass(frozen=True)
class GeneratedScene:
    """A scene as text, its tables, its mass names (chain: indices as text) and the features drawn."""

    text: str
    tables: dict = field(default_factory=dict)
    masses: tuple = ()
    features: frozenset = frozenset()
    label: str = ""

    def write(self, folder: Path) -> Path:
        folder.mkdir(parents=True, exist_ok=True)
        name = self.text.split('"', 2)[1]
        for fname, body in self.tables.items():
            (folder / fname).write_text(body, encoding="utf-8")
        path = folder / f"{name}.toml"
        path.write_text(self.text, encoding="utf-8")
        return path


def q(text: str) -> str:
    """A TOML basic string."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def num(v: float) -> str:
    return repr(float(v))


class _Names:
    """Fresh parameter names with values, the scene's [parameters]."""

    def __init__(self, c, regime):
        self.c, self.regime, self.values, self.pool = c, regime, {}, list(PARAM_NAMES)

    def new(self, value: float, hint: str | None = None) -> str:
        free = [p for p in self.pool if p not in self.values]
        if hint in free and self.c.boolean():
            name = hint
        else:
            name = self.c.pick(free) if free else f"p{len(self.values)}"
        self.values[name] = float(value)
        return name

    def magnitude(self, regime=None) -> float:
        lo, hi = REGIMES[regime or self.regime]
        e = self.c.real(lo, hi)
        mant = self.c.pick((1.0, 1.5, 2.0, 3.0, 1.25, 7.0, 0.5))
        return mant * 10.0**e

    def positive(self, hint: str, regime=None) -> str:
        """An expression of a positive value: a parameter, a multiple of one, or a product of two."""
        form = self.c.pick(("p", "p", "cp", "pp", "p/c", "sqrt"))
        existing = [p for p in self.values if self.values[p] > 0]
        reuse = existing and self.c.integer(0, 3) == 0
        p = self.c.pick(existing) if reuse else self.new(self.magnitude(regime), hint)
        if form == "cp":
            return f"{self.c.pick(('2', '3', '0.5', '1.5', '4'))}*{p}"
        if form == "p/c":
            return f"{p}/{self.c.pick(('2', '3', '10'))}"
        if form == "pp" and len(existing) >= 1:
            other = self.c.pick(existing)
            return f"{p}*{other}" if other != p else f"{p}**2"
        if form == "sqrt":
            return f"sqrt({p})" if self.values[p] > 0 else p
        return p


def _end(names, j):
    return "wall" if j < 0 else names[j]


def build_masses(c, max_masses: int = 6, regime: str | None = None, allow: frozenset | None = None):
    """A ``[masses]`` scene from the choices of ``c`` (:class:`DrawChooser` or :class:`SeededChooser`)."""
    regime = regime or c.pick(("moderate", "moderate", "moderate", "wide", "wide", "extreme"))
    P = _Names(c, regime)
    feats = {f"regime:{regime}", "form:masses"}
    n = c.integer(1, max_masses)
    mass_names = c.distinct(MASS_NAMES, n)
    P.pool = [p for p in P.pool if p not in mass_names and not any(p == f"{c}_{m}" for c in "xva" for m in mass_names)]
    lines_masses = [f"{nm} = {q(P.positive('m'))}" for nm in mass_names]
    # pieces and their springs
    order = list(range(n))
    cuts = sorted(c.subset(range(1, n), min(2, n - 1))) if n > 1 else []
    pieces = [order[a:b] for a, b in zip([0, *cuts], [*cuts, n])]
    ends = []
    for piece in pieces:
        shape = c.pick(("path", "path", "tree", "loop", "none")) if len(piece) > 1 else "single"
        if shape in ("path", "loop"):
            ends += [(piece[j], piece[j + 1]) for j in range(len(piece) - 1)]
            if shape == "loop" and len(piece) > 2:
                ends.append((piece[-1], piece[0]))
                feats.add("topology:loop")
        elif shape == "tree":
            for j in range(1, len(piece)):
                ends.append((piece[c.integer(0, j - 1)], piece[j]))
            feats.add("topology:tree")
        elif shape == "none":
            feats.add("topology:free_masses")
        walls = c.integer(0, 2)
        for _ in range(walls):
            j = c.pick(piece)
            ends.append((-1, j) if c.boolean() else (j, -1))
        if walls:
            feats.add("topology:wall")
        if shape == "single" and not walls:
            feats.add("topology:free_masses")
    if ends and c.integer(0, 5) == 0:
        ends.append(c.pick(ends))
        feats.add("topology:duplicate_spring")
    if len(pieces) > 1:
        feats.add("topology:pieces")
    spring_lines = []
    nonlinear_ok = allow is None or "nonlinear" in allow
    for a, b in ends:
        kind = c.pick(("k", "k", "k", "k3", "potential")) if nonlinear_ok else "k"
        body = [f"between = [{q(_end(mass_names, a))}, {q(_end(mass_names, b))}]"]
        if kind == "potential":
            fam = c.pick(sorted(POTENTIALS))
            body.append(f"potential = {q(_potential(c, P, fam))}")
            feats.add(f"potential:{fam}")
        else:
            body.append(f"k = {q(P.positive('k'))}")
            if kind == "k3":
                v = P.magnitude() * c.pick((1.0, -1.0))
                body.append(f"k3 = {q(P.new(v, 'kappa'))}")
                feats.add("spring:cubic")
        spring_lines.append(body)
    return _finish(c, P, feats, mass_names, "[masses]\n" + "\n".join(lines_masses), spring_lines, n,
                   chain=False, regime=regime)


def _potential(c, P: _Names, fam: str) -> str:
    template, keys = POTENTIALS[fam]
    subs = {}
    for key in keys:
        if key in SHAPE_KEYS:
            subs[key] = P.new(10.0 ** c.real(-1.0, 1.0), {"w": "w", "b": "b", "r": "r0", "L": "L"}[key])
        elif key == "s":  # FPUT coefficients of either sign
            subs[key] = P.new(P.magnitude() * c.pick((1.0, -1.0)), "beta")
        elif key == "T":
            subs[key] = P.new(P.magnitude() * c.pick((1.0, -1.0)), "T")
        else:
            subs[key] = P.new(P.magnitude(), {"k": "K", "a": "a", "D": "D", "e": "eps"}[key])
    return template.format(**subs)


def build_chain(c, max_n: int = 12, regime: str | None = None, allow: frozenset | None = None):
    """A ``[chain]`` scene from the choices of ``c``."""
    regime = regime or c.pick(("moderate", "moderate", "wide", "extreme"))
    P = _Names(c, regime)
    feats = {f"regime:{regime}", "form:chain"}
    n = c.integer(1, max_n)
    left = c.pick(("free", "wall", "ring"))
    right = "ring" if left == "ring" else c.pick(("free", "wall"))
    if left == "ring" and n < 3:
        left = right = "wall"
    feats.add(f"chain:{left}-{right}")
    m = P.positive("m")
    mass = c.pick((m, f"{m}*(1 + i % 2)", f"{m}*(1 + 0.25*i)", f"{m}*exp(i*log(1.5))"))
    k = P.positive("k")
    kexpr = c.pick((k, f"{k}*(2 + i % 3)", f"{k}*(3 + i)"))
    if mass != m or kexpr != k:
        feats.add("chain:index_dependent")
    body = [f"n = {n}", f"mass = {q(mass)}"]
    nonlinear_ok = allow is None or "nonlinear" in allow
    law = c.pick(("k", "k", "k", "k3", "potential")) if nonlinear_ok else "k"
    if law == "potential":
        fam = c.pick(("fput_alpha", "fput_beta", "toda", "morse", "lennard_jones", "cosh", "quadratic"))
        body.append(f"potential = {q(_potential(c, P, fam))}")
        feats.add(f"potential:{fam}")
    else:
        body.append(f"k = {q(kexpr)}")
        if law == "k3":
            body.append(f"k3 = {q(P.new(P.magnitude(), 'kappa'))}")
            feats.add("spring:cubic")
    body += [f"left = {q(left)}", f"right = {q(right)}"]
    return _finish(c, P, feats, tuple(str(i) for i in range(n)), "[chain]\n" + "\n".join(body), [], n,
                   chain=True, regime=regime)


def _finish(c, P: _Names, feats: set, mass_names, head: str, spring_lines, n: int, *, chain: bool, regime: str):
    tables: dict = {}
    blocks = [head]
    for body in spring_lines:
        blocks.append("[[springs]]\n" + "\n".join(body))
    ends = ["wall", *mass_names] if not chain else ["wall", *range(n)]
    # dashpots
    for _ in range(c.integer(0, 2) if c.boolean() else 0):
        if chain:
            between = c.pick((["i", "i+1"], ["i", "wall"], [0, "wall"], [0, n - 1]))
            if between == [0, n - 1] and n < 2 or between == ["i", "i+1"] and n < 2:
                between = ["i", "wall"]
            cval = P.positive("c")
            text = ", ".join(q(e) if isinstance(e, str) else str(e) for e in between)
            blocks.append(f"[[dampers]]\nbetween = [{text}]\nc = {q(cval)}")
        else:
            a, b = c.distinct(ends, 2)
            blocks.append(f"[[dampers]]\nbetween = [{q(a)}, {q(b)}]\nc = {q(P.positive('c'))}")
        feats.add("damping:dashpot")
    model = c.pick(("none", "none", "none", "rayleigh", "targets", "modal"))
    if chain and model in ("targets", "modal"):
        model = "rayleigh"
    if model == "rayleigh":
        al = P.new(10.0 ** c.real(-4, 0), "alpha") if c.boolean() else None
        be = P.new(10.0 ** c.real(-5, -1), "beta") if (al is None or c.boolean()) else None
        blocks.append(f"[damping]\nrayleigh = [{q(al or '0')}, {q(be or '0')}]")
        feats.add("damping:rayleigh")
    elif model == "targets":
        za, zb = c.pick(((0.05, 0.05), (0.02, 0.05), (0.03, 0.02), (0.1, 0.1)))
        blocks.append(f"[damping]\nrayleigh_targets = {{zeta = [{za}, {zb}], modes = [1, {c.integer(2, 3)}]}}")
        feats.add("damping:rayleigh_targets")
    elif model == "modal":
        if c.boolean():
            blocks.append(f"[damping]\nmodal = {num(10.0 ** c.real(-3, -0.5))}")
        else:
            zs = [num(10.0 ** c.real(-3, -0.5)) for _ in range(n)]
            blocks.append(f"[damping]\nmodal = [{', '.join(zs)}]")
        feats.add("damping:modal")
    # loads
    for j in range(c.integer(0, 2) if c.integer(0, 2) == 0 else 0):
        on = c.pick(range(n)) if chain else c.pick(mass_names)
        on_text = str(on) if chain else q(on)
        form = c.pick(("const", "harmonic", "harmonic2", "table"))
        F = P.new(P.magnitude("moderate") * c.pick((1.0, -1.0)), "F0")
        if form == "table":
            fname = f"force{j}.csv"
            tables[fname] = _table_csv(c, "f", float(P.values[F]))
            blocks.append(f"[[forces]]\non = {on_text}\ntable = {q(fname)}")
        else:
            W = P.new(10.0 ** c.real(-1, 1), "Omega") if form != "const" else None
            f = {"const": F, "harmonic": f"{F}*cos({W}*t)", "harmonic2": f"{F}/2 + {F}*sin({W}*t + 0.3)"}[form]
            blocks.append(f"[[forces]]\non = {on_text}\nf = {q(f)}")
        feats.add(f"force:{form}")
    if c.integer(0, 4) == 0:
        form = c.pick(("const", "harmonic", "table"))
        A = P.new(P.magnitude("moderate") * c.pick((1.0, -1.0)), "A")
        if form == "table":
            tables["ground.csv"] = _table_csv(c, "a", float(P.values[A]))
            blocks.append('[ground]\ntable = "ground.csv"')
        else:
            W = P.new(10.0 ** c.real(-1, 1), "W")
            blocks.append(f"[ground]\nacceleration = {q(A if form == 'const' else f'{A}*sin({W}*t)')}")
        feats.add(f"ground:{form}")
    if c.integer(0, 3) == 0:
        g = P.new(P.magnitude("moderate") * c.pick((1.0, -1.0)), "g")
        blocks.append(f"[gravity]\ng = {q(g)}")
        feats.add("gravity")
    if c.integer(0, 4) > 0:
        amp = 10.0 ** c.real(-3, 0)
        if chain and c.boolean():
            blocks.append(f'[initial]\nx = "{amp!r}*sin(pi*(i + 1)/(n + 1))"\nv = "0"')
        else:
            xs = c.reals(-1, 1, n)
            vs = c.reals(-1, 1, n)
            blocks.append(f"[initial]\nx = [{', '.join(num(amp * v) for v in xs)}]\n"
                          f"v = [{', '.join(num(amp * v) for v in vs)}]")
        feats.add("initial")
    dt = 10.0 ** c.real(-3, 0)
    steps = c.integer(1, 60)
    blocks.append(f"[simulation]\ndt = {num(dt)}\nsteps = {steps}\nrecord_every = {c.integer(1, 3)}")
    name = c.pick(("gen", "scene", "mine", "test1", "trial"))
    params = "\n".join(f"{k} = {num(v)}" for k, v in P.values.items())
    text = (f'name = "{name}"\ndescription = "generated ({regime})"\n\n[parameters]\n{params}\n\n'
            + "\n\n".join(blocks) + "\n")
    return GeneratedScene(text, tables, tuple(mass_names), frozenset(feats))


def _table_csv(c, column: str, scale: float) -> str:
    rows = c.integer(2, 6)
    t0 = c.pick((0.0, 0.0, 0.05, -0.1))
    steps = c.reals(0.01, 0.5, rows - 1)
    ts = [t0]
    for h in steps:
        ts.append(ts[-1] + h)
    ys = c.reals(-1, 1, rows)
    if c.boolean():
        ys[-1] = 0.0
    return f"t,{column}\n" + "".join(f"{t!r},{scale * y!r}\n" for t, y in zip(ts, ys))


def build_scene(c, max_masses: int = 6, max_chain: int = 12):
    """Any scene: ``[masses]`` (3 in 4) or ``[chain]``."""
    return build_chain(c, max_chain) if c.integer(0, 3) == 0 else build_masses(c, max_masses)


# -- where the choices come from -----------------------------------------------------------------------------
class DrawChooser:
    """Choices drawn by hypothesis (``draw`` of a composite strategy): searched, edge values included."""

    def __init__(self, draw):
        self.draw = draw

    def integer(self, lo: int, hi: int) -> int:
        return self.draw(st.integers(lo, hi))

    def real(self, lo: float, hi: float) -> float:
        return self.draw(st.floats(lo, hi, allow_nan=False, allow_subnormal=False))

    def boolean(self) -> bool:
        return self.draw(st.booleans())

    def pick(self, seq):
        return self.draw(st.sampled_from(list(seq)))

    def distinct(self, seq, k: int) -> list:
        return self.draw(st.lists(st.sampled_from(list(seq)), min_size=k, max_size=k, unique=True))

    def subset(self, seq, max_size: int) -> set:
        return self.draw(st.sets(st.sampled_from(list(seq)), max_size=max_size)) if list(seq) else set()

    def reals(self, lo: float, hi: float, k: int) -> list:
        return self.draw(st.lists(st.floats(lo, hi, allow_nan=False, allow_subnormal=False), min_size=k, max_size=k))


class SeededChooser:
    """The same choices from ``random.Random(seed)``: a fixed sample that does not depend on hypothesis's
    search (whose later draws depend on how earlier examples ran), for the CI run."""

    def __init__(self, seed: int):
        self.rng = random.Random(seed)

    def integer(self, lo: int, hi: int) -> int:
        return self.rng.randint(lo, hi)

    def real(self, lo: float, hi: float) -> float:
        return self.rng.uniform(lo, hi)

    def boolean(self) -> bool:
        return self.rng.random() < 0.5

    def pick(self, seq):
        return self.rng.choice(list(seq))

    def distinct(self, seq, k: int) -> list:
        return self.rng.sample(list(seq), k)

    def subset(self, seq, max_size: int) -> set:
        items = list(seq)
        return set(self.rng.sample(items, self.rng.randint(0, min(max_size, len(items))))) if items else set()

    def reals(self, lo: float, hi: float, k: int) -> list:
        return [self.rng.uniform(lo, hi) for _ in range(k)]


@st.composite
def masses_scene(draw, max_masses: int = 6, regime: str | None = None, allow: frozenset | None = None):
    """Hypothesis strategy: a ``[masses]`` scene (:func:`build_masses`)."""
    return build_masses(DrawChooser(draw), max_masses, regime, allow)


@st.composite
def chain_scene(draw, max_n: int = 12, regime: str | None = None, allow: frozenset | None = None):
    """Hypothesis strategy: a ``[chain]`` scene (:func:`build_chain`)."""
    return build_chain(DrawChooser(draw), max_n, regime, allow)


@st.composite
def scenes(draw, max_masses: int = 6, max_chain: int = 12):
    """Hypothesis strategy: any scene (:func:`build_scene`)."""
    return build_scene(DrawChooser(draw), max_masses, max_chain)


def seeded_scene(seed: int, max_masses: int = 6, max_chain: int = 12) -> "GeneratedScene":
    """The scene of ``seed``: the same text on every machine and run."""
    return build_scene(SeededChooser(seed), max_masses, max_chain)


@dataclass(frozen=True)
class GeneratedRecord:
    """An accelerogram (rows t, a), damping ratios and periods to ask for."""

    t: tuple
    a: tuple
    zeta: tuple
    periods: tuple

    def csv(self) -> str:
        return "t,a\n" + "".join(f"{t!r},{a!r}\n" for t, a in zip(self.t, self.a))


def build_record(c, max_rows: int = 14):
    """Piecewise-linear records: uneven or uniform rows, nonzero or zero last value, any start time;
    periods from far below the row spacing to far above the record's length."""
    rows = c.integer(2, max_rows)
    t0 = c.pick((0.0, 0.0, 0.5, -1.0))
    if c.boolean():
        h = c.pick((0.01, 0.02, 0.05, 0.1, 0.125))
        ts = [t0 + j * h for j in range(rows)]
    else:
        ts = [t0]
        for h in c.reals(0.005, 0.4, rows - 1):
            ts.append(ts[-1] + h)
    scale = 10.0 ** c.real(-2, 1)
    a = [scale * v for v in c.reals(-1, 1, rows)]
    if c.boolean():
        a[-1] = 0.0
    zeta = tuple(sorted(set(c.distinct((0.0, 0.02, 0.05, 0.1, 0.3, 0.7), c.integer(1, 2)))))
    span = ts[-1] - ts[0]
    periods = tuple(sorted(set(c.reals(0.02, 4.0 * span + 0.1, c.integer(1, 3)))))
    return GeneratedRecord(tuple(ts), tuple(a), zeta, periods)


@st.composite
def records(draw, max_rows: int = 14):
    """Hypothesis strategy: a record (:func:`build_record`)."""
    return build_record(DrawChooser(draw), max_rows)


def seeded_record(seed: int, max_rows: int = 14) -> GeneratedRecord:
    return build_record(SeededChooser(seed), max_rows)


__all__ = ["scenes", "masses_scene", "chain_scene", "records", "seeded_scene", "seeded_record", "build_scene",
           "GeneratedScene", "GeneratedRecord", "DrawChooser", "SeededChooser", "POTENTIALS", "PARAM_NAMES"]
