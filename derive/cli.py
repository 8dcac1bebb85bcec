"""The ``springchain`` command. Names (methods, sources) are looked up here, at the edge, only.

Every failure the user can fix prints one line on stderr and exits 2.
SymPy is imported only by the subcommands that derive.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

from .errors import SceneError

EXIT_USAGE = 2


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2, no usage dump
        sys.stderr.write(f"springchain: error: {message} (see `{self.prog} --help`)\n")
        raise SystemExit(EXIT_USAGE)


def _positive_float(flag):
    def conv(text):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{flag} {text!r}: not a number; accepted: a number > 0") from None
        if not math.isfinite(value) or value <= 0:
            raise argparse.ArgumentTypeError(f"{flag} {text!r}: accepted: a finite number > 0")
        return value
    return conv


def _positive_int(flag):
    def conv(text):
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{flag} {text!r}: accepted: a whole number > 0") from None
        if value <= 0:
            raise argparse.ArgumentTypeError(f"{flag} {text!r}: accepted: a whole number > 0")
        return value
    return conv


def _seed_scene() -> Path:
    from .scene import bundled_scene_dir

    return bundled_scene_dir() / "seed.toml"


# -- commands ---------------------------------------------------------------------------
def cmd_derive(args) -> int:
    from . import pipeline
    from .scene import bundled_scenes, load_scene

    paths = [Path(p) for p in args.scene] or bundled_scenes()
    scenes = [load_scene(p) for p in paths]  # validate everything before writing anything
    out = Path(args.out) if args.out else Path.cwd() / "generated"
    status = 0
    for scene in scenes:
        t0 = time.perf_counter()
        if args.check:
            ok, msg = pipeline.check(scene, out)
            print(("ok     " if ok else "STALE  ") + msg)
            status |= 0 if ok else 1
        else:
            d = pipeline.derive(scene)
            path = pipeline.write(d, out)
            print(f"wrote {path} ({len(d.source.splitlines())} lines, {time.perf_counter() - t0:.2f} s)")
    return status


def cmd_modes(args) -> int:
    from . import pipeline
    from .scene import load_scene

    scene = load_scene(args.scene)
    d = pipeline.derive(scene)
    if scene.chain is not None:
        from .chain import chain_report

        text, data = chain_report(d.model, d.modes)
        print(json.dumps(data, indent=2) if args.json else text, end="" if not args.json else "\n")
        return 0
    from .report import modes_json, render_latex, render_text

    if args.json:
        print(json.dumps(modes_json(d.model, d.modes), indent=2))
    elif args.latex:
        print(render_latex(d.model, d.modes), end="")
    else:
        print(render_text(d.model, d.modes), end="")
    return 0


def _simulate(scene, args, out: Path, quiet_json: bool) -> dict:
    import numpy as np

    from numeric.simulate import compare, method_names, run_methods, stream_methods, write_figures, write_npz
    from numeric.system import System

    from .pipeline import load_module
    from .scene import check_memory

    module, origin = load_module(scene)
    system = System.from_module(module)
    dt = args.dt if args.dt is not None else scene.dt
    steps = args.steps if args.steps is not None else scene.steps
    record_every = args.record_every or scene.record_every
    methods = args.method or (method_names()[:2] if system.exact_available and not
                              (system.chain and system.n > 4000) else ["verlet"])
    unknown = [m for m in methods if m not in method_names()]
    if unknown:
        raise SceneError(None, "--method", f"{unknown[0]!r} is not a method; accepted: {', '.join(method_names())}")
    check_memory(scene.file, scene.n, steps, record_every, methods=len(methods))
    out.mkdir(parents=True, exist_ok=True)
    if system.chain:
        summary = stream_methods(system, scene.x0, scene.v0, dt, steps, methods, record_every, out,
                                 scene.name, figures=not args.no_figures)
        npz, figures = Path(summary["npz"]), [Path(p) for p in summary["figures"]]
    else:
        runs = run_methods(system, scene.x0, scene.v0, dt, steps, methods, record_every,
                           spectrum_source=args.spectrum, rtol=args.rtol, atol=args.atol)
        summary = compare(system, runs)
        npz = out / f"{scene.name}.npz"
        write_npz(npz, runs)
        figures = [] if args.no_figures else write_figures(out, scene.name, scene.mass_names, system, runs)
    summary.update({"scene": scene.name, "module": origin, "dt": dt, "steps": steps,
                    "t_end": steps * dt, "npz": str(npz), "figures": [str(p) for p in figures]})
    if not quiet_json:
        long_chain = system.chain and system.n > 4000
        applies = ("integrators (the exact solution is offered up to 4000 masses)" if long_chain
                   else "modal (exact) and every integrator") if system.exact_available else (
            "integrators only (" + ("cubic springs" if not system.linear else "non-harmonic forces")
            + ": no exact solution)")
        print(f"simulated {scene.name!r}: {', '.join(methods)}; dt = {dt:g}, {steps} steps, "
              f"t_end = {steps * dt:g} (module: {origin}); methods that apply: {applies}")
        for name, rec in summary["methods"].items():
            line = f"  {name:<13} {rec['seconds'] * 1e3:9.2f} ms"
            if "max_position_difference" in rec:
                line += (f"   max |x - x_exact| = {rec['max_position_difference']:.3e}"
                         f"   max |v - v_exact| = {rec['max_velocity_difference']:.3e}")
            if system.damped or system.forced:
                line += f"   energy change = {rec['energy_drift']:.3e} (not conserved: damping/forcing)"
            else:
                line += f"   energy drift = {rec['energy_drift']:.3e} (rel {rec['energy_drift_relative']:.2e})"
            print(line)
        print(f"  wrote {npz}")
        for p in figures:
            print(f"  wrote {p}")
    del np
    return summary


def cmd_simulate(args) -> int:
    from .scene import load_scene

    scene = load_scene(args.scene)
    summary = _simulate(scene, args, Path(args.out), args.json)
    if args.json:
        print(json.dumps(summary, indent=2))
    return 0


def cmd_run(args) -> int:
    from . import pipeline
    from .report import render_text
    from .scene import load_scene

    t0 = time.perf_counter()
    seed = _seed_scene()
    try:
        shown = seed.relative_to(Path.cwd())
    except ValueError:
        shown = seed
    scene = load_scene(shown)
    d = pipeline.derive(scene)
    print(render_text(d.model, d.modes))
    path = pipeline.module_path(scene)
    fresh = path.exists() and path.read_text(encoding="utf-8") == d.source
    if fresh:
        print(f"generated module {path} is fresh (equals a new render)")
    else:
        print(f"generated module {path} is STALE: regenerate with `springchain derive` in the repository root")
    print()
    args.method, args.dt, args.steps, args.record_every = None, None, None, None
    args.spectrum, args.no_figures, args.rtol, args.atol = "svd", False, 1e-10, 1e-12
    _simulate(scene, args, Path(args.out), False)
    print(f"\nfigures and data are in {Path(args.out).resolve()}  ({time.perf_counter() - t0:.2f} s in all)")
    return 0


# -- parser ---------------------------------------------------------------------------------
def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="springchain",
                description="Mass-spring chains: a scene file -> equations of motion and closed-form "
                            "normal modes (SymPy) -> generated NumPy code -> exact and numerical "
                            "simulations with plots.",
                epilog="Start with `springchain run` (the bundled three-mass reference scene).")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    r = sub.add_parser("run", help="the main job on the bundled reference scene",
                       description="Derive the bundled reference scene (masses m, 3m, m; springs k), print "
                                   "its equations and closed-form modes, check the checked-in generated "
                                   "module is fresh, simulate with the exact modal solution and velocity "
                                   "Verlet, and write figures.")
    r.add_argument("--out", default="springchain-out", help="folder for figures and data (default: %(default)s)")
    r.set_defaults(func=cmd_run)

    d = sub.add_parser("derive", help="generate NumPy modules from scenes",
                       description="Derive each scene and write DIR/<name>.py (plain NumPy, deterministic). "
                                   "With no SCENE: every bundled scene.")
    d.add_argument("scene", nargs="*", help="scene files (default: all bundled scenes)")
    d.add_argument("--out", help="folder for the modules (default: ./generated under the current folder)")
    d.add_argument("--check", action="store_true",
                   help="write nothing; exit 1 if a module on disk differs from a fresh render")
    d.set_defaults(func=cmd_derive)

    m = sub.add_parser("modes", help="print equations of motion and closed-form normal modes",
                       description="Print the Lagrangian derivation and the normal modes of a scene.")
    m.add_argument("scene", help="scene file (TOML)")
    g = m.add_mutually_exclusive_group()
    g.add_argument("--json", action="store_true", help="print one JSON object (see README) and nothing else")
    g.add_argument("--latex", action="store_true", help="print the derivation as LaTeX (amsmath)")
    m.set_defaults(func=cmd_modes)

    from numeric.simulate import method_names

    s = sub.add_parser("simulate", help="simulate a scene with exact and numerical methods",
                       description="Run the chosen methods from the scene's initial state and write "
                                   "DIR/<name>.npz (t, x_<method>, v_<method>) and PNG figures: positions, "
                                   "velocities, method - exact, energy.")
    s.add_argument("scene", help="scene file (TOML)")
    s.add_argument("--method", action="append", choices=method_names(), metavar="NAME",
                   help=f"method to run, repeatable ({', '.join(method_names())}; default: modal and verlet "
                        "for linear scenes, verlet otherwise)")
    s.add_argument("--dt", type=_positive_float("--dt"), help="time step (default: the scene's)")
    s.add_argument("--steps", type=_positive_int("--steps"), help="number of steps (default: the scene's)")
    s.add_argument("--record-every", type=_positive_int("--record-every"),
                   help="keep every K-th step (default: the scene's, else 1)")
    s.add_argument("--spectrum", choices=("svd", "closed-form"), default="svd",
                   help="modes for the exact solution: SVD of the spring factor (accurate, default) or the "
                        "generated closed forms")
    s.add_argument("--rtol", type=_positive_float("--rtol"), default=1e-10,
                   help="relative tolerance of the adaptive methods rk45, dop853, lsoda (default: %(default)g)")
    s.add_argument("--atol", type=_positive_float("--atol"), default=1e-12,
                   help="absolute tolerance of the adaptive methods (default: %(default)g)")
    s.add_argument("--out", default="springchain-out", help="output folder (default: %(default)s)")
    s.add_argument("--no-figures", action="store_true", help="write only the NPZ")
    s.add_argument("--json", action="store_true", help="print a JSON summary instead of text")
    s.set_defaults(func=cmd_simulate)
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except SceneError as exc:
        sys.stderr.write(f"springchain: error: {exc}\n")
        return EXIT_USAGE
    except ValueError as exc:  # numeric refusals (RunRefused) and other input problems
        from numeric.errors import RunRefused

        if isinstance(exc, RunRefused):
            sys.stderr.write(f"springchain: error: {exc}\n")
            return EXIT_USAGE
        raise
    except BrokenPipeError:  # output piped into e.g. `head`
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:
        sys.stderr.write("springchain: interrupted\n")
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
