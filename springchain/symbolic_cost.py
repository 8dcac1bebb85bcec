"""Symbolic cost is work too: derive + codegen time against N, beside SymPy's LagrangesMethod.

Three ways to get the equations of motion of the same chain (N equal masses
m, N−1 equal springs k, free ends):

* ``chain`` — a ``[chain]`` scene: :mod:`derive.chain` derives one element
  and renders a stencil module; the work does not grow with N;
* ``elements`` — the same chain as ``[masses]`` + ``[[springs]]``:
  :class:`derive.model.Model` (element-wise Euler–Lagrange), the normal
  modes (:func:`derive.modes.closed_form_modes`, which falls back to numeric
  eigenvalues past its work caps or block size, exactly as ``springchain
  derive`` runs it) and :func:`derive.codegen.render_module`; the modes are
  also reported on their own;
* ``lagrange`` — ``sympy.physics.mechanics.LagrangesMethod`` on the chain's
  Lagrangian with dynamic symbols: forming the equations, the mass matrix and
  the forcing vector (no code generation).

**Work** is measured the same way for all three: each case runs in a fresh
Python process (no SymPy cache shared between cases), which first imports
what it needs (SymPy, ``sympy.physics.mechanics`` or ``derive``) and then
times only the work with ``time.perf_counter`` — i.e. the command's time
minus the time to start Python and import (for ``elements`` that includes
NumPy and ``scipy.linalg.lapack``, which the numeric mode fallback uses). The parent also records each
process's wall time minus that of a process that only imports SymPy, as a
cross-check (it then counts the extra imports as work).

:func:`lagrange_matrices` and :func:`model_matrices` give M and K of both
routes for the equality test that ties the timing comparison to correctness.
"""

from __future__ import annotations

import enum
import json
import math
import os
import subprocess
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable

#: Cases of the default run (LagrangesMethod takes ≈ 5 s at N = 40 and ≈ 13 s at N = 80).
DEFAULT_SIZES = (3, 10, 20, 40)
#: [chain] sizes of the default run (the template does not depend on N).
DEFAULT_CHAIN_SIZES = (3, 10, 40, 100, 1000, 10_000)
#: Seconds one case may run before it is stopped and reported as over budget.
CASE_TIMEOUT = 300.0

#: Index-dependent ("random") chain of the scaling benchmark: irregular masses and springs in [½, 3/2]·(m, k).
RANDOM_MASS = "m*(1 + 0.5*sin(12.9898*i))"
RANDOM_K = "k*(1 + 0.5*cos(78.233*i))"


class Route(enum.Enum):
    """A way to derive a chain's equations of motion."""

    CHAIN = "chain"  #: [chain] template + stencil codegen
    ELEMENTS = "elements"  #: [masses]/[[springs]]: Model + modes + render_module
    LAGRANGE = "lagrange"  #: sympy.physics.mechanics.LagrangesMethod

    @property
    def label(self) -> str:
        return {Route.CHAIN: "[chain] template + codegen", Route.ELEMENTS: "[masses]/[[springs]] derive + codegen",
                Route.LAGRANGE: "sympy LagrangesMethod"}[self]


# -- scenes -------------------------------------------------------------------------------------------
def masses_scene_text(n: int) -> str:
    """TOML of a free–free chain of n equal masses m and n−1 equal springs k ([masses] form)."""
    lines = [f'name = "cost{n}"', "[parameters]", "m = 1.0", "k = 1.0", "[masses]"]
    lines += [f'm{i} = "m"' for i in range(1, n + 1)]
    for i in range(1, n):
        lines += ["[[springs]]", f'between = ["m{i}", "m{i + 1}"]', 'k = "k"']
    zeros = ", ".join("0.0" for _ in range(n))
    lines += ["[initial]", f"x = [{zeros}]", f"v = [{zeros}]"]
    return "\n".join(lines) + "\n"


def chain_scene_text(n: int, *, mass: str = "m", k: str = "k", left: str = "free", right: str = "free",
                     name: str | None = None) -> str:
    """TOML of a ``[chain]`` scene (parameters m = k = 1; half-sine initial displacement)."""
    lines = [f'name = "{name or f"costchain{n}"}"', "[parameters]", "m = 1.0", "k = 1.0", "[chain]",
             f"n = {n}", f'mass = "{mass}"', f'k = "{k}"', f'left = "{left}"', f'right = "{right}"',
             "[initial]", 'x = "0.01*sin(pi*(i + 1)/(n + 1))"', 'v = "0"']
    return "\n".join(lines) + "\n"


def scaling_cases():
    """The uniform (bundled ``chain100k``) and index-dependent chains of ``springchain scaling``.

    Returns
    -------
    uniform, random : numeric.bench.scaling.ChainCase
    """
    from .numeric.bench.scaling import ChainCase

    from ._modules import load_module
    from ._scenes import bundled_scene_dir
    from .derive.scene import load_scene

    uniform, _ = load_module(load_scene(bundled_scene_dir() / "chain100k.toml"))
    text = chain_scene_text(1000, mass=RANDOM_MASS, k=RANDOM_K, name="scaling_random")
    random, _ = load_module(load_scene("scaling_random.toml", text))
    return ChainCase("uniform", uniform), ChainCase("random", random)


# -- the routes, in process ---------------------------------------------------------------------------
def lagrange_system(n: int):
    """LagrangesMethod on the chain: returns (LagrangesMethod, coordinates q(t), m, k) after forming everything."""
    import sympy as sp
    from sympy.physics.mechanics import LagrangesMethod, dynamicsymbols

    t = dynamicsymbols._t
    q = dynamicsymbols(f"q0:{n}")
    m, k = sp.symbols("m k", positive=True)
    T = sum((m * qi.diff(t) ** 2 / 2 for qi in q), sp.Integer(0))
    V = sum((k * (q[i + 1] - q[i]) ** 2 / 2 for i in range(n - 1)), sp.Integer(0))
    lm = LagrangesMethod(T - V, q)
    lm.form_lagranges_equations()
    lm.mass_matrix  # noqa: B018 - forming it is the work being timed
    lm.forcing  # noqa: B018
    return lm, q, m, k


def lagrange_matrices(n: int):
    """M and K (``K = −∂forcing/∂q``) from LagrangesMethod, in the symbols of :func:`model_matrices`."""
    import sympy as sp

    lm, q, m, k = lagrange_system(n)
    x = [sp.Symbol(f"x_m{i + 1}", real=True) for i in range(n)]
    K = (-lm.forcing.jacobian(q)).xreplace(dict(zip(q, x)))
    return lm.mass_matrix, K


def model_matrices(n: int):
    """M and K of :class:`derive.model.Model` for the ``[masses]`` chain of :func:`masses_scene_text`."""
    from .derive.model import Model
    from .derive.scene import load_scene

    model = Model(load_scene(f"cost{n}.toml", masses_scene_text(n)))
    return model.M, model.K


def work(route: Route, n: int) -> dict:
    """Run one route on the N-mass chain in this process; seconds of each phase (imports excluded)."""
    if route is Route.LAGRANGE:
        import sympy  # noqa: F401
        import sympy.physics.mechanics  # noqa: F401

        t0 = time.perf_counter()
        lagrange_system(n)
        total = time.perf_counter() - t0
        return {"equations": total, "total": total}
    import sympy  # noqa: F401

    from .derive.scene import load_scene

    if route is Route.CHAIN:
        from .derive.chain import ChainModel, chain_modes
        from .derive.chain_codegen import render_chain_module

        t0 = time.perf_counter()
        scene = load_scene(f"costchain{n}.toml", chain_scene_text(n))
        t1 = time.perf_counter()
        model = ChainModel(scene)
        model.interior_equation()
        modes = chain_modes(model)
        t2 = time.perf_counter()
        source = render_chain_module(model, bundled=False)
        t3 = time.perf_counter()
        return {"scene": t1 - t0, "equations": t2 - t1, "codegen": t3 - t2, "total": t3 - t0,
                "modes": 0.0, "closed_form": modes.closed_form, "source_lines": source.count("\n")}
    import scipy.linalg.lapack  # noqa: F401 - the numeric mode fallback's import, not work
    from .derive.codegen import render_module
    from .derive.model import Model
    from .derive.modes import closed_form_modes

    t0 = time.perf_counter()
    scene = load_scene(f"cost{n}.toml", masses_scene_text(n))
    t1 = time.perf_counter()
    model = Model(scene)
    model.euler_lagrange()
    model.M  # noqa: B018
    model.K  # noqa: B018
    t2 = time.perf_counter()
    modes = closed_form_modes(model)
    t3 = time.perf_counter()
    source = render_module(model, modes, bundled=False)
    t4 = time.perf_counter()
    return {"scene": t1 - t0, "equations": t2 - t1, "modes": t3 - t2, "codegen": t4 - t3, "total": t4 - t0,
            "total_without_modes": (t4 - t0) - (t3 - t2), "closed_form": modes.closed_form,
            "modes_notes": list(modes.notes), "source_lines": source.count("\n")}


# -- the routes, each in a fresh process ------------------------------------------------------------
def _python_env() -> dict:
    env = dict(os.environ)
    # the child imports the same springchain as this process (installed or editable)
    root = str(Path(__file__).resolve().parent.parent)
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def baseline_seconds(repeats: int = 3) -> float:
    """Wall time of a fresh Python that only imports SymPy (minimum of repeats)."""
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", "import sympy"], check=True, env=_python_env(),
                       stdout=subprocess.DEVNULL)
        best = min(best, time.perf_counter() - t0)
    return best


def measure(route: Route, n: int, timeout: float = CASE_TIMEOUT) -> dict:
    """Run :func:`work` in a fresh process; its phase times plus the process wall time ("wall").

    A case that exceeds ``timeout`` is stopped and reported with ``"timeout": True``.
    """
    t0 = time.perf_counter()
    try:
        done = subprocess.run([sys.executable, "-m", "springchain.symbolic_cost", route.value, str(n)],
                              capture_output=True, text=True, timeout=timeout, env=_python_env())
    except subprocess.TimeoutExpired:
        return {"timeout": True, "wall": time.perf_counter() - t0, "total": None}
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        raise RuntimeError(f"symbolic cost case {route.value} N={n} failed: {done.stderr.strip()[-400:]}")
    out = json.loads(done.stdout.strip().splitlines()[-1])
    out["wall"] = wall
    return out


@dataclass(frozen=True)
class SymbolicResult:
    """Records (route, N, phase seconds) and the Python+SymPy start-up baseline."""

    baseline: float
    records: list[dict] = field(repr=False)
    ratios: dict

    def to_json(self) -> dict:
        return asdict(self)


def run(sizes: tuple[int, ...] = DEFAULT_SIZES, chain_sizes: tuple[int, ...] = DEFAULT_CHAIN_SIZES,
        progress: Callable[[str], None] | None = None, timeout: float = CASE_TIMEOUT) -> SymbolicResult:
    """Measure all routes side by side (one fresh process per case)."""
    say = progress or (lambda line: None)
    base = baseline_seconds()
    say(f"Python + SymPy start-up baseline: {base:.2f} s")
    records = []
    cases = [(Route.CHAIN, n) for n in sorted(set(chain_sizes) | set(sizes))]
    cases += [(r, n) for n in sorted(set(sizes)) for r in (Route.ELEMENTS, Route.LAGRANGE)]
    for route, n in cases:
        rec = {"route": route.value, "n": n, **measure(route, n, timeout)}
        rec["wall_minus_baseline"] = rec["wall"] - base
        records.append(rec)
        total = rec.get("total")
        say(f"{route.label:<40s} N = {n:>6d}: work {'over budget' if total is None else f'{total:8.3f} s'} "
            f"(wall − baseline {rec['wall_minus_baseline']:.2f} s)")
    return SymbolicResult(base, records, _ratios(records))


def _ratios(records: list[dict]) -> dict:
    """LagrangesMethod work over each of our routes' work, per N where both ran."""
    by = {(r["route"], r["n"]): r for r in records}
    out: dict = {}
    for (route, n), rec in sorted(by.items(), key=lambda kv: kv[0][1]):
        lag = by.get((Route.LAGRANGE.value, n))
        if route == Route.LAGRANGE.value or lag is None or not lag.get("total") or not rec.get("total"):
            continue
        entry = out.setdefault(str(n), {})
        entry[route] = lag["total"] / rec["total"]
        if route == Route.ELEMENTS.value and rec.get("total_without_modes"):
            entry["elements_without_modes"] = lag["total"] / rec["total_without_modes"]
        entry[route + "_wall"] = (lag["wall_minus_baseline"] / rec["wall_minus_baseline"]
                                  if rec["wall_minus_baseline"] > 0 else None)
    return out


def markdown(result: SymbolicResult) -> str:
    """Table of work seconds per route and N, and the LagrangesMethod ratios."""
    by = {(r["route"], r["n"]): r for r in result.records}
    sizes = sorted({r["n"] for r in result.records})

    def cell(route, n, key="total"):
        r = by.get((route.value, n))
        if r is None:
            return "–"
        if r.get("timeout"):
            return "> budget"
        v = r.get(key)
        return "–" if v is None else f"{v:.3g}"

    lines = ["### Symbolic cost: derive + codegen vs sympy LagrangesMethod (seconds of work)", "",
             "Each case runs in a fresh Python process and times its work after its imports; "
             f"\"wall − baseline\" subtracts a process that only imports SymPy ({result.baseline:.2f} s).", "",
             "| N | [chain] template + codegen | [masses] derive + codegen (all) | of which modes | "
             "without modes | LagrangesMethod | Lagrange / [chain] | Lagrange / [masses] | "
             "Lagrange / [masses] w/o modes |",
             "|---|---|---|---|---|---|---|---|---|"]
    for n in sizes:
        ratio = result.ratios.get(str(n), {})

        def fr(key):
            v = ratio.get(key)
            return "–" if v is None else f"{v:.1f}×"

        lines.append(f"| {n} | {cell(Route.CHAIN, n)} | {cell(Route.ELEMENTS, n)} | "
                     f"{cell(Route.ELEMENTS, n, 'modes')} | {cell(Route.ELEMENTS, n, 'total_without_modes')} | "
                     f"{cell(Route.LAGRANGE, n)} | {fr('chain')} | {fr('elements')} | "
                     f"{fr('elements_without_modes')} |")
    lines += ["", "Wall time minus the SymPy-import baseline (same processes):", "",
              "| N | [chain] | [masses] | LagrangesMethod |", "|---|---|---|---|"]
    for n in sizes:
        lines.append(f"| {n} | {cell(Route.CHAIN, n, 'wall_minus_baseline')} | "
                     f"{cell(Route.ELEMENTS, n, 'wall_minus_baseline')} | "
                     f"{cell(Route.LAGRANGE, n, 'wall_minus_baseline')} |")
    return "\n".join(lines) + "\n"


def figure(result: SymbolicResult):
    """Work seconds vs N (log–log), one line per route (and the modes share of [masses])."""
    import matplotlib

    from .numeric.plots import figures as plots
    from .numeric.plots.figures import new_figure

    fig, ax = new_figure(figsize=(8, 5))
    styles = {Route.CHAIN: ("C2", "o-"), Route.ELEMENTS: ("C0", "s-"), Route.LAGRANGE: ("C3", "^-")}
    for route, (color, style) in styles.items():
        pts = sorted((r["n"], r["total"]) for r in result.records if r["route"] == route.value and r.get("total"))
        if pts:
            ax.plot(*zip(*pts), style, color=color, label=route.label)
    pts = sorted((r["n"], r["modes"]) for r in result.records
                 if r["route"] == Route.ELEMENTS.value and r.get("modes"))
    if pts:
        ax.plot(*zip(*pts), "s:", color="C0", alpha=0.6, label="  of which: normal modes")
    ax.set_xscale("log")
    ax.set_yscale("log")
    plots.finish(ax, "chain size N", "seconds of work (imports excluded)", "Deriving the equations of motion: work vs N")
    return fig


def write(result: SymbolicResult, out: Path) -> list[Path]:
    """Write symbolic-cost.json, symbolic-cost.md and symbolic-cost.png into ``out``."""
    from .numeric.plots import figures as plots
    from .numeric.io.files import atomic_write_text

    out = Path(out)
    paths = [out / "symbolic-cost.json", out / "symbolic-cost.md", out / "symbolic-cost.png"]
    atomic_write_text(paths[0], json.dumps(result.to_json(), indent=1) + "\n")
    atomic_write_text(paths[1], markdown(result))
    plots.save(figure(result), paths[2])
    return paths


def _main(argv: list[str]) -> int:
    """``python -m derive.symbolic_cost ROUTE N``: print the work of one case as one JSON line."""
    if len(argv) != 2:
        sys.stderr.write("usage: python -m derive.symbolic_cost {chain,elements,lagrange} N\n")
        return 2
    route, n = Route(argv[0]), int(argv[1])
    print(json.dumps(work(route, n)))
    return 0


if __name__ == "__main__":
    raise SystemExit(_main(sys.argv[1:]))
