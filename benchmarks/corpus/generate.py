"""Write the scenes of ``bench_symbolic.py``'s corpus into this folder (``python benchmarks/corpus/generate.py``).

Every scene has NAMED parameters, distinct per mass and per spring (``m1 … mN``, ``k1 … kN``): the
adversarial case for the symbolic algebra, where no two entries cancel. The corpus covers every element
kind of a ``[masses]`` scene — gravity, dampers, Rayleigh, modal and Rayleigh-target damping, spring
potentials, cubic springs, forces, ground motion, free pieces (rigid-body modes, several disconnected
pieces) and rings — at 2 to 40 masses, plus a few high-contrast and literal-number scenes. Values are
deterministic (no random draws): the files are committed and regenerated identically.
"""

from __future__ import annotations

from pathlib import Path

HERE = Path(__file__).resolve().parent


def _num(x: float) -> str:
    return repr(round(float(x), 12))


class Scene:
    """A scene under construction: parameters, masses, springs and extra tables, written as TOML."""

    def __init__(self, name: str, description: str):
        self.name, self.description = name, description
        self.params: dict[str, float] = {}
        self.masses: dict[str, str] = {}
        self.springs: list[dict] = []
        self.dampers: list[dict] = []
        self.forces: list[dict] = []
        self.tables: list[str] = []

    def chain(self, n: int, *, left: bool, right: bool, mass=lambda i: 1.0 + 0.1 * i, k=lambda i: 50.0 + 3.0 * i,
              names: bool = True, ring: bool = False) -> list[str]:
        """n masses a1…an joined in a line by springs k1…; a wall spring at each end asked for."""
        bodies = [f"a{i}" for i in range(1, n + 1)]
        for i, b in enumerate(bodies, 1):
            if names:
                self.params[f"m{i}"] = mass(i)
                self.masses[b] = f"m{i}"
            else:
                self.masses[b] = _num(mass(i))
        ends = (["wall"] if left else []) + bodies + (["wall"] if right else [])
        pairs = list(zip(ends, ends[1:])) + ([(bodies[-1], bodies[0])] if ring else [])
        for j, (a, b) in enumerate(pairs, 1):
            self.spring(a, b, j, k(j), names)
        return bodies

    def spring(self, a: str, b: str, j: int, value: float, names: bool = True, **extra) -> None:
        if names:
            self.params[f"k{j}"] = value
            self.springs.append({"between": [a, b], "k": f"k{j}", **extra})
        else:
            self.springs.append({"between": [a, b], "k": _num(value), **extra})

    def text(self) -> str:
        out = [f'name = "{self.name}"', f'description = "{self.description}"', "", "[parameters]"]
        out += [f"{k} = {_num(v)}" for k, v in self.params.items()]
        out += ["", "[masses]"] + [f'{k} = "{v}"' for k, v in self.masses.items()]
        for table, rows in (("springs", self.springs), ("dampers", self.dampers), ("forces", self.forces)):
            for row in rows:
                out += ["", f"[[{table}]]"]
                for key, value in row.items():
                    out.append(f"{key} = {_toml(value)}")
        for t in self.tables:
            out += ["", t.strip()]
        return "\n".join(out) + "\n"


def _toml(value) -> str:
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, str):
        return f'"{value}"'
    return _num(value)


def hanging(n: int) -> Scene:
    s = Scene(f"hang{n}", f"{n} masses hanging from a ceiling by springs k1..k{n}, gravity g")
    s.chain(n, left=True, right=False)
    s.params["g"] = 9.81
    s.tables.append('[gravity]\ng = "g"')
    return s


def fixed(n: int) -> Scene:
    s = Scene(f"fixed{n}", f"{n} masses between two walls, distinct masses and springs")
    s.chain(n, left=True, right=True)
    return s


def free(n: int) -> Scene:
    s = Scene(f"free{n}", f"free-free chain of {n} distinct masses (one rigid-body mode)")
    s.chain(n, left=False, right=False)
    return s


def pieces(n: int) -> Scene:
    """Two free pieces (no spring between a{n/2} and a{n/2+1}) and one piece held by a wall."""
    s = Scene(f"pieces{n}", f"{n} masses in three pieces: two free, one on a wall")
    third = max(n // 3, 1)
    bodies = [f"a{i}" for i in range(1, n + 1)]
    for i, b in enumerate(bodies, 1):
        s.params[f"m{i}"] = 1.0 + 0.1 * i
        s.masses[b] = f"m{i}"
    j = 0
    for lo, hi, wall in ((0, third, False), (third, 2 * third, False), (2 * third, n, True)):
        group = bodies[lo:hi]
        if wall:
            j += 1
            s.spring("wall", group[0], j, 40.0 + 2.0 * j)
        for a, b in zip(group, group[1:]):
            j += 1
            s.spring(a, b, j, 40.0 + 2.0 * j)
    return s


def ring(n: int) -> Scene:
    s = Scene(f"ring{n}", f"ring of {n} distinct masses and springs")
    s.chain(n, left=False, right=False, ring=True)
    return s


def dampers(n: int) -> Scene:
    s = Scene(f"dampers{n}", f"{n} masses on a wall with a dashpot c_i beside every spring")
    bodies = s.chain(n, left=True, right=False)
    ends = ["wall", *bodies]
    for i, (a, b) in enumerate(zip(ends, ends[1:]), 1):
        s.params[f"c{i}"] = 0.2 + 0.05 * i
        s.dampers.append({"between": [a, b], "c": f"c{i}"})
    return s


def rayleigh(n: int) -> Scene:
    s = Scene(f"rayleigh{n}", f"{n} masses between walls with Rayleigh damping alpha M + beta K")
    s.chain(n, left=True, right=True)
    s.params |= {"alpha": 0.1, "beta": 0.002}
    s.tables.append('[damping]\nrayleigh = ["alpha", "beta"]')
    return s


def modal(n: int) -> Scene:
    s = Scene(f"modal{n}", f"{n} masses on a wall with modal damping zeta")
    s.chain(n, left=True, right=False)
    s.params["zeta"] = 0.05
    s.tables.append('[damping]\nmodal = "zeta"')
    return s


def targets(n: int) -> Scene:
    s = Scene(f"targets{n}", f"{n}-storey shear building with Rayleigh damping fitted to modes 1 and 2")
    s.chain(n, left=True, right=False)
    s.tables.append("[damping]\nrayleigh_targets = {zeta = [0.02, 0.05], modes = [1, 2]}")
    return s


def potential(n: int, *, gravity: bool = True) -> Scene:
    """Springs k_i d²/2 + b_i d⁴/4 hanging under gravity (an equilibrium under load)."""
    s = Scene(f"potential{n}", f"{n} masses hanging by quartic-potential springs under gravity")
    bodies = [f"a{i}" for i in range(1, n + 1)]
    for i, b in enumerate(bodies, 1):
        s.params[f"m{i}"] = 1.0 + 0.1 * i
        s.masses[b] = f"m{i}"
    ends = ["wall", *bodies]
    for i, (a, b) in enumerate(zip(ends, ends[1:]), 1):
        s.params[f"k{i}"] = 50.0 + 3.0 * i
        s.params[f"b{i}"] = 5.0 + 0.5 * i
        s.springs.append({"between": [a, b], "potential": f"k{i}*d**2/2 + b{i}*d**4/4"})
    if gravity:
        s.params["g"] = 9.81
        s.tables.append('[gravity]\ng = "g"')
    return s


def morse(n: int) -> Scene:
    """Morse springs (a tiny-stiffness-like potential) between walls with a constant pull."""
    s = Scene(f"morse{n}", f"{n} masses between walls joined by Morse potentials, a constant force on the last")
    bodies = [f"a{i}" for i in range(1, n + 1)]
    for i, b in enumerate(bodies, 1):
        s.params[f"m{i}"] = 1.0 + 0.1 * i
        s.masses[b] = f"m{i}"
    ends = ["wall", *bodies, "wall"]
    for i, (a, b) in enumerate(zip(ends, ends[1:]), 1):
        s.params[f"D{i}"] = 2.0 + 0.1 * i
        s.params[f"w{i}"] = 1.5 + 0.05 * i
        s.springs.append({"between": [a, b], "potential": f"D{i}*(1 - exp(-w{i}*d))**2"})
    s.params["F"] = 0.3
    s.forces.append({"on": bodies[-1], "f": "F"})
    return s


def tiny(n: int) -> Scene:
    """A potential with a tiny stiffness: k*d**2/2 with k = 1e-9 beside stiff springs."""
    s = Scene(f"tinypot{n}", f"{n} masses between walls, one potential spring of tiny stiffness")
    s.chain(n, left=True, right=False)
    s.params |= {"eps": 1e-9, "q": 1e-3}
    s.springs.append({"between": [f"a{n}", "wall"], "potential": "eps*d**2/2 + q*d**4/4"})
    return s


def cubic(n: int) -> Scene:
    s = Scene(f"cubic{n}", f"{n} masses on a wall, every spring with a cubic term kappa_i")
    bodies = [f"a{i}" for i in range(1, n + 1)]
    for i, b in enumerate(bodies, 1):
        s.params[f"m{i}"] = 1.0 + 0.1 * i
        s.masses[b] = f"m{i}"
    ends = ["wall", *bodies]
    for i, (a, b) in enumerate(zip(ends, ends[1:]), 1):
        s.params[f"kappa{i}"] = 0.5 + 0.1 * i
        s.spring(a, b, i, 50.0 + 3.0 * i, k3=f"kappa{i}")
    return s


def forced(n: int) -> Scene:
    s = Scene(f"forced{n}", f"{n} masses between walls, a harmonic force on the first and a constant one on the last")
    bodies = s.chain(n, left=True, right=True)
    s.params |= {"F0": 1.0, "Omega": 3.0, "P": 0.5}
    s.forces.append({"on": bodies[0], "f": "F0*cos(Omega*t)"})
    s.forces.append({"on": bodies[-1], "f": "P"})
    return s


def ground(n: int) -> Scene:
    s = Scene(f"ground{n}", f"{n}-storey building on moving ground, dashpot on the first storey")
    bodies = s.chain(n, left=True, right=False)
    s.params |= {"A": 0.3, "W": 5.0, "c1": 0.4}
    s.dampers.append({"between": ["wall", bodies[0]], "c": "c1"})
    s.tables.append('[ground]\nacceleration = "A*sin(W*t)"')
    return s


def everything(n: int) -> Scene:
    """Gravity, dashpots, a harmonic force and Rayleigh damping at once."""
    s = Scene(f"mixed{n}", f"{n} hanging masses with dashpots, Rayleigh damping and a harmonic force")
    bodies = s.chain(n, left=True, right=False)
    s.params |= {"g": 9.81, "alpha": 0.05, "beta": 0.001, "F0": 1.0, "Omega": 2.0}
    for i, b in enumerate(bodies[1::2], 1):
        s.params[f"c{i}"] = 0.1 * i
        s.dampers.append({"between": [b, "wall"], "c": f"c{i}"})
    s.forces.append({"on": bodies[-1], "f": "F0*sin(Omega*t)"})
    s.tables += ['[gravity]\ng = "g"', '[damping]\nrayleigh = ["alpha", "beta"]']
    return s


def contrast(n: int) -> Scene:
    """Masses from 1e-6 to 1e6 (named), springs of one order."""
    s = Scene(f"contrast{n}", f"{n} masses from 1e-6 to 1e6 on a wall, named")
    s.chain(n, left=True, right=False, mass=lambda i: 10.0 ** (-6 + 12 * (i - 1) / max(n - 1, 1)))
    return s


def literal(n: int) -> Scene:
    """The hanging chain with numbers written into the masses and springs (no names)."""
    s = Scene(f"literal{n}", f"{n} masses hanging by springs, literal numbers, gravity")
    s.chain(n, left=True, right=False, names=False)
    s.params["g"] = 9.81
    s.tables.append('[gravity]\ng = "g"')
    return s


def uniform(n: int) -> Scene:
    """One m and one k for every element (the derive benchmark's chain, with walls)."""
    s = Scene(f"uniform{n}", f"{n} equal masses m and springs k between walls")
    s.params |= {"m": 1.0, "k": 1.0}
    bodies = [f"a{i}" for i in range(1, n + 1)]
    s.masses |= {b: "m" for b in bodies}
    ends = ["wall", *bodies, "wall"]
    for a, b in zip(ends, ends[1:]):
        s.springs.append({"between": [a, b], "k": "k"})
    return s


#: (builder, sizes): the corpus.
FAMILIES = [
    (hanging, (2, 3, 6, 12, 40)), (fixed, (4, 10, 40)), (free, (3, 8, 20)), (pieces, (6, 12)),
    (ring, (4, 8, 12)), (dampers, (3, 6, 12)), (rayleigh, (4, 12, 30)), (modal, (3, 8, 20)),
    (targets, (5, 12)), (potential, (2, 4, 8)), (morse, (3,)), (tiny, (4,)), (cubic, (3, 10)),
    (forced, (3, 10)), (ground, (4, 12)), (everything, (6, 40)), (contrast, (12,)), (literal, (6,)),
    (uniform, (5, 40)),
]


def scenes() -> list[Scene]:
    return [build(n) for build, sizes in FAMILIES for n in sizes]


def main() -> int:
    for old in HERE.glob("*.toml"):
        old.unlink()
    for s in scenes():
        (HERE / f"{s.name}.toml").write_text(s.text(), encoding="utf-8")
    print(f"wrote {len(scenes())} scenes into {HERE}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
