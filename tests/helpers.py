"""Helpers shared by the test modules (``from helpers import ...``; pytest puts tests/ on the path).

* **Scene text**: :func:`scene_toml` writes a scene's TOML from plain Python values,
  :func:`chain_toml` a ``[chain]`` scene, :func:`write_scene` puts one (and its CSV tables) in a folder.
* **An independent reference from the TOML text**: :class:`TomlScene` reads the raw file with
  ``tomllib`` and evaluates its expressions with SymPy (no springchain code);
  :func:`stamp` / :func:`assemble` build element matrices, :func:`dop853` integrates a
  first-order right-hand side at rtol 1e-12; :func:`free_pieces` finds the rigid-body pieces and
  :func:`mp_dynamical_matrix` forms D in mpmath for extended-precision spectra.
* **The command line**: :func:`run_cli` runs ``main`` in process, :func:`one_line_error` checks a
  refusal is the one line the command promises.
* **Generated modules**: :func:`system_of` loads a scene's generated module and binds it as a
  :class:`~springchain.numeric.system.System` (with the scene's tables).
"""

from __future__ import annotations

import json
import os
import tomllib
from pathlib import Path

import mpmath
import numpy as np
import sympy
from scipy.integrate import solve_ivp


# -- scene text -----------------------------------------------------------------------------------
def toml_value(value) -> str:
    """A TOML literal of a bool, int, float, string or list of those."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    raise TypeError(f"no TOML literal for {value!r}")


def _table(name: str, entries: dict) -> list[str]:
    return [f"[{name}]"] + [f"{k} = {toml_value(v)}" for k, v in entries.items()]


def scene_toml(name: str, parameters: dict, *, masses: dict | None = None, springs=(), dampers=(),
               forces=(), chain: dict | None = None, tables: dict | None = None, initial: dict | None = None,
               simulation: dict | None = None, description: str | None = None, extra: str = "") -> str:
    """The TOML text of a scene.

    Parameters
    ----------
    name : str
    parameters : dict
        Parameter name -> value (floats are written as floats).
    masses, chain : dict, optional
        ``[masses]`` (name -> expression) or ``[chain]`` (key -> value).
    springs, dampers, forces : sequence of dict
        ``[[springs]]``, ``[[dampers]]``, ``[[forces]]`` entries (key -> value).
    tables : dict, optional
        Further tables by name (``{"gravity": {"g": "g"}, "damping": {...}}``).
    initial, simulation : dict, optional
        ``[initial]`` and ``[simulation]`` (left out when None).
    description : str, optional
    extra : str
        TOML text appended before ``[initial]`` as it is.
    """
    lines = [f"name = {toml_value(name)}"]
    if description is not None:
        lines.append(f"description = {toml_value(description)}")
    lines += _table("parameters", {k: float(v) for k, v in parameters.items()})
    if masses is not None:
        lines += _table("masses", masses)
    if chain is not None:
        lines += _table("chain", chain)
    for array, entries in (("springs", springs), ("dampers", dampers), ("forces", forces)):
        for entry in entries:
            lines += [f"[[{array}]]"] + [f"{k} = {toml_value(v)}" for k, v in entry.items()]
    for table, entries in (tables or {}).items():
        lines += _table(table, entries)
    if extra:
        lines.append(extra.strip())
    for table, entries in (("initial", initial), ("simulation", simulation)):
        if entries is not None:
            lines += _table(table, entries)
    return "\n".join(lines) + "\n"


#: Scale of the ``slow`` tests (``SPRINGCHAIN_SLOW_BUDGET``; default 0.25: the bounded form CI runs, a
#: quarter of the scale 1 that the README's numbers were first measured at; 2 or more: the full form).
SLOW_BUDGET = float(os.environ.get("SPRINGCHAIN_SLOW_BUDGET", "0.25"))

#: The initial state of the chain test scenes: the lowest wall-wall mode's shape, at rest.
CHAIN_INITIAL = {"x": "0.01*sin(pi*(i + 1)/(n + 1))", "v": "0"}


def chain_toml(n: int, left: str = "free", right: str = "free", *, name: str = "ch", parameters: dict | None = None,
               mass: str = "m", k: str = "k", k3: str | None = None, initial: dict | None = CHAIN_INITIAL,
               simulation: dict | None = None, extra: str = "") -> str:
    """A ``[chain]`` scene's TOML (parameters default to m = 1.7, k = 2.3)."""
    chain = {"n": n, "mass": mass, "k": k, "left": left, "right": right}
    if k3 is not None:
        chain["k3"] = k3
    parameters = {"m": 1.7, "k": 2.3} if parameters is None else parameters
    return scene_toml(name, parameters, chain=chain, initial=initial, simulation=simulation,
                      extra=extra)


#: Three masses m, 2m, m hanging from a wall by springs k, k, 2k (the damping and load tests' scene):
#: keyword arguments of :func:`scene_toml`.
WALL_THREE = {"masses": {"m1": "m", "m2": "2*m", "m3": "m"},
              "springs": [{"between": ["wall", "m1"], "k": "k"}, {"between": ["m1", "m2"], "k": "k"},
                          {"between": ["m2", "m3"], "k": "2*k"}]}


def write_scene(folder: Path, name: str, text: str, tables: dict[str, str] | None = None) -> Path:
    """Write ``folder/name.toml`` (and the CSV ``tables``, file name -> content); return its path."""
    for fname, body in (tables or {}).items():
        (folder / fname).write_text(body)
    path = folder / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return path


# -- an independent reference from the TOML text --------------------------------------------------
class TomlScene:
    """A scene file read with ``tomllib`` only; its expressions evaluated with SymPy.

    ``data`` is the raw TOML; :meth:`value` evaluates an expression of the parameters (and of
    ``i`` or other names given as keywords) to a float; :meth:`of_t` makes a NumPy function of t.
    """

    def __init__(self, text: str, folder: Path | None = None):
        self.data = tomllib.loads(text)
        self.folder = folder
        self.params = {k: float(v) for k, v in self.data["parameters"].items()}
        self.symbols = {k: sympy.Symbol(k) for k in self.params}
        self.t = sympy.Symbol("t")

    @classmethod
    def read(cls, path: str | Path) -> "TomlScene":
        path = Path(path)
        return cls(path.read_text(), path.parent)

    def expr(self, text, **names) -> sympy.Expr:
        """The SymPy expression of ``text`` at the scene's parameter values (other names free)."""
        local = {**self.symbols, "t": self.t, **{k: sympy.Symbol(k) for k in names}}
        return sympy.sympify(str(text), locals=local).subs(self.params)

    def value(self, text, **names) -> float:
        """The number ``text`` means, with ``names`` (e.g. ``i=3``) substituted."""
        return float(self.expr(text, **names).subs({sympy.Symbol(k): v for k, v in names.items()}))

    def of_t(self, text):
        """``text`` as a NumPy function of t."""
        return sympy.lambdify(self.t, self.expr(text), "numpy")

    def csv(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """The two columns of a CSV table named by the scene (relative to its folder)."""
        data = np.loadtxt(self.folder / name, delimiter=",", skiprows=1, ndmin=2)
        return data[:, 0], data[:, 1]

    def mass_index(self) -> dict[str, int]:
        """Mass name -> coordinate index (``wall`` -> -1) of a ``[masses]`` scene."""
        return {**{name: j for j, name in enumerate(self.data["masses"])}, "wall": -1}

    def matrices(self) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
        """``(mass names, M, K, C)`` of a ``[masses]`` scene, assembled element by element from its
        springs (linear part) and dashpots; ``[damping]`` models are not in C."""
        idx = self.mass_index()
        names = list(self.data["masses"])
        n = len(names)

        def elements(entries, key):
            return [(tuple(idx[x] for x in e["between"]), self.value(e[key])) for e in entries]

        M = np.diag([self.value(e) for e in self.data["masses"].values()])
        return (names, M, assemble(n, elements(self.data.get("springs", []), "k")),
                assemble(n, elements(self.data.get("dampers", []), "c")))


def stamp(A: np.ndarray, a: int, b: int, c: float) -> None:
    """Add ``c (e_a - e_b)(e_a - e_b)ᵀ`` to A; an end -1 is a wall (left out)."""
    for p, sp_ in ((a, 1), (b, -1)):
        for q, sq in ((a, 1), (b, -1)):
            if p >= 0 and q >= 0:
                A[p, q] += sp_ * sq * c


def assemble(n: int, elements) -> np.ndarray:
    """Σ c (e_a - e_b)(e_a - e_b)ᵀ over ``elements`` ``((a, b), c)``: an (n, n) matrix."""
    A = np.zeros((n, n))
    for (a, b), c in elements:
        stamp(A, a, b, c)
    return A


def dop853(rhs, n: int, x0, v0, t, *, rtol: float = 1e-12, atol: float = 1e-14):
    """Integrate z' = rhs(t, z), z = (x, v), by DOP853; returns x, v of shape (len(t), n)."""
    sol = solve_ivp(rhs, (t[0], t[-1]), np.concatenate([x0, v0]), method="DOP853", rtol=rtol, atol=atol,
                    t_eval=t)
    assert sol.success
    return sol.y[:n].T, sol.y[n:].T


def free_pieces(n: int, ends) -> list[list[int]]:
    """Masses of each connected piece without a spring to a wall (one rigid-body mode each), by a
    union-find of the test's own; ``ends`` are ``(a, b, ...)`` rows, -1 a wall."""
    parent = list(range(n))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    pairs = [(int(e[0]), int(e[1])) for e in ends]
    for a, b in pairs:
        if a >= 0 and b >= 0:
            parent[root(a)] = root(b)
    walled = {root(max(a, b)) for a, b in pairs if (a < 0) != (b < 0)}
    groups: dict[int, list[int]] = {}
    for i in range(n):
        groups.setdefault(root(i), []).append(i)
    return [g for r, g in groups.items() if r not in walled]


def mp_dynamical_matrix(masses, ends, k):
    """``D = M^-1/2 K M^-1/2`` in mpmath at the working precision from the springs ``ends`` (rows
    (a, b), -1 a wall) and ``k``; the float inputs taken as exact."""
    n = len(masses)
    K = mpmath.zeros(n, n)
    for (a, b), kk in zip(np.asarray(ends).reshape(-1, 2), k):
        kk = mpmath.mpf(float(kk))
        for i in (a, b):
            if i >= 0:
                K[i, i] += kk
        if a >= 0 and b >= 0:
            K[a, b] -= kk
            K[b, a] -= kk
    s = [1 / mpmath.sqrt(mpmath.mpf(float(m))) for m in masses]
    D = mpmath.matrix(n, n)
    for i in range(n):
        for j in range(n):
            D[i, j] = K[i, j] * s[i] * s[j]
    return D


# -- the command line ----------------------------------------------------------------------------
def run_cli(argv, capsys) -> tuple[int, str, str]:
    """``main(argv)`` in-process: (exit status, stdout, stderr); argparse's exits give the status."""
    from springchain.cli import main

    try:
        status = main([str(a) for a in argv])
    except SystemExit as exc:  # argparse errors
        status = exc.code
    out, err = capsys.readouterr()
    return status, out, err


def one_line_error(status, out: str, err: str, *must_contain: str) -> str:
    """Assert a refusal: status 2, no traceback, exactly one line ``springchain: error: ...`` on
    stderr holding every ``must_contain``; returns that line."""
    assert status == 2, (status, err)
    assert "Traceback" not in err and "Traceback" not in out
    lines = err.splitlines()
    assert len(lines) == 1 and err.endswith("\n"), err
    assert lines[0].startswith("springchain: error: "), err
    assert "\r" not in err and "\x1b" not in err
    for part in must_contain:
        assert part in lines[0], (part, lines[0])
    return lines[0]


def refused_scene(path: Path, capsys, *must_contain: str) -> str:
    """Assert a scene file is refused: ``load_scene`` raises SceneError and ``springchain modes``
    prints one error line holding the file name and ``must_contain``, nothing on stdout."""
    import pytest

    from springchain.derive.errors import SceneError
    from springchain.derive.scene import load_scene

    with pytest.raises(SceneError):
        load_scene(path)
    status, out, err = run_cli(["modes", path], capsys)
    assert out == ""
    return one_line_error(status, out, err, str(path), *must_contain)


# -- generated modules ----------------------------------------------------------------------------
def system_of(scene):
    """``(module, System)``: the scene's generated module bound at its parameter values and tables."""
    from springchain._modules import load_tables
    from springchain._modules import load_module
    from springchain.numeric.system import System

    module, _ = load_module(scene)
    return module, System.from_module(module, **load_tables(scene))
