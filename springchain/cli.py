"""The ``springchain`` command. Names (methods, sources) are looked up here, at the edge, only.

Every failure the user can fix prints one line on stderr and exits 2.
SymPy is imported only by the subcommands that derive.
"""

from __future__ import annotations

import argparse
import inspect
import math
import sys
import time
from pathlib import Path

from . import __version__
from ._defaults import DEFAULT_BENCH_OUT, DEFAULT_OUT, DEFAULT_SWEEP_OUT
from .derive.errors import SceneError
from .numeric.run.protocol import DEFAULT_ATOL, DEFAULT_RTOL

EXIT_USAGE = 2


def _dumps(obj, **kwargs) -> str:
    """Strict JSON (no NaN or Infinity: null), for every ``--json``."""
    from .numeric.io.strict_json import dumps

    return dumps(obj, **kwargs)


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2, no usage dump
        sys.stderr.write(f"springchain: error: {message} (see `{self.prog} --help`)\n")
        raise SystemExit(EXIT_USAGE)


def _number(flag: str, parse, ok, accepted: str):
    """An argparse type: ``parse(text)`` checked by ``ok(value)``; one line naming the flag otherwise."""
    def conv(text):
        try:
            value = parse(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{flag} {text!r}: accepted: {accepted}") from None
        if not ok(value):
            raise argparse.ArgumentTypeError(f"{flag} {text!r}: accepted: {accepted}")
        return value
    return conv


def _positive_float(flag):
    return _number(flag, float, lambda v: math.isfinite(v) and v > 0, "a finite number > 0")


def _positive_int(flag):
    return _number(flag, int, lambda v: v > 0, "a whole number > 0")


def _whole(flag):
    return _number(flag, int, lambda v: v >= 0, "a whole number >= 0")


#: The commands that take a SCENE, and so ``--set NAME=VALUE``.
SCENE_COMMANDS = ("derive", "modes", "simulate", "bench", "plan", "sweep", "frf", "animate", "rsa", "bands", "update",
                  "psd")


def _set_values(items: list[str]) -> dict[str, float]:
    """``--set NAME=VALUE`` options as {name: number} (names are checked against the scene later)."""
    values = {}
    for item in items:
        name, eq, text = item.partition("=")
        name = name.strip()
        try:
            value = float(text) if eq and name else None
        except ValueError:
            value = None
        if value is None or not math.isfinite(value):
            raise SceneError(None, "--set", f"{item!r}: not NAME=NUMBER; accepted: a parameter and a finite "
                                            "number, e.g. --set k=4 (repeatable)")
        if name in values:
            raise SceneError(None, "--set", f"{item!r}: {name} given twice; accepted: each parameter once")
        values[name] = value
    return values


def _apply_set(args) -> None:
    """Replace ``args.scene`` by the scene(s) with the ``--set`` parameter values (validated as a file)."""
    from ._api import load
    from ._scenes import bundled_scenes
    from .derive.scene_edit import with_parameters

    values = _set_values(args.set)
    how = "with --set " + " ".join(f"{k}={v:g}" for k, v in values.items())
    one = lambda source: with_parameters(load(source), values, how)  # noqa: E731
    if isinstance(args.scene, list):  # derive: several scenes, default every bundled one
        args.scene = [one(s) for s in (args.scene or bundled_scenes())]
    else:
        args.scene = one(args.scene if args.scene is not None else "seed")


# -- commands: parse, call the API, print -------------------------------------------------------
def cmd_derive(args) -> int:
    """generate NumPy modules from scenes

    Derive each scene and write DIR/<name>.py (plain NumPy, deterministic). With no SCENE: every bundled
    scene. --check compares with the same DIR.
    """
    from ._api import generate

    results = generate(args.scene, args.out, check=args.check)
    for d in results:
        if args.check:
            print(("ok     " if d.fresh else "STALE  ") + d.message)
        else:
            print(f"wrote {d.path} ({d.lines} lines, {d.seconds:.2f} s)")
    return 0 if all(d.fresh is not False for d in results) else 1


def cmd_modes(args) -> int:
    """print equations of motion and closed-form normal modes

    Print the Lagrangian derivation and the normal modes of a scene.
    """
    from ._api import modes

    if getattr(args, "sensitivity", False) or getattr(args, "parameters", None) is not None:
        return cmd_modes_sensitivity(args)
    if getattr(args, "modes", None) is not None:
        raise SceneError(None, "--modes", "without --sensitivity: accepted: --modes with --sensitivity (the modes "
                                          "report lists every mode)")
    m = modes(args.scene)
    if args.uff:
        from ._uff import write_modes_uff

        uff_path, uff_notes = write_modes_uff(args.scene, args.uff)
        sys.stderr.write(f"wrote {uff_path} (UFF dataset 55 per mode, ASCII; {'; '.join(uff_notes)})\n")
    if args.json:
        print(_dumps(m.to_json(), indent=2))
    elif args.latex:
        print(m.to_latex(), end="")
    else:
        print(m.to_text(), end="")
    return 0


def _print_simulation(result) -> None:
    s = result.summary
    print(f"simulated {s['scene']!r}: {', '.join(s['methods'])}; dt = {s['dt']:g}, {s['steps']} steps, "
          f"t_end = {s['t_end']:g} (module: {s['module']}); methods that apply: {s['methods_that_apply']}")
    conservative = s["energy_conserved"]
    for name, rec in s["methods"].items():
        line = f"  {name:<13} {rec['seconds'] * 1e3:9.2f} ms"
        if "max_position_difference" in rec:
            line += (f"   max |x - x_exact| = {rec['max_position_difference']:.3e}"
                     f"   max |v - v_exact| = {rec['max_velocity_difference']:.3e}")
        if not conservative:
            line += f"   energy change = {rec['energy_drift']:.3e} (not conserved: damping/forcing)"
        else:
            line += f"   energy drift = {rec['energy_drift']:.3e} (rel {rec['energy_drift_relative']:.2e})"
        print(line)
    for note in s.get("notes", ()):
        print(f"  note: {note}")
    if s["npz"]:
        print(f"  wrote {s['npz']}")
    for p in s["figures"]:
        print(f"  wrote {p}")


def cmd_simulate(args) -> int:
    """simulate a scene with exact and numerical methods

    Run the chosen methods from the scene's initial state and write DIR/<name>.npz (t, x_<method>,
    v_<method>) and PNG figures: positions, velocities, method - exact, energy.
    """
    from ._api import simulate

    try:
        result = simulate(args.scene, methods=args.method, dt=args.dt, steps=args.steps, record_every=args.record_every,
                          spectrum=args.spectrum, rtol=args.rtol, atol=args.atol, out=args.out,
                          figures=not args.no_figures, modal_energy=getattr(args, "modal_energy", False),
                          springs=args.springs, alpha=args.alpha)
    except SceneError as exc:  # name the flag that set the value, when one did
        flag = {"steps": "--steps" if args.steps is not None else "simulation.steps"}.get(exc.key)
        if flag and flag != exc.key:
            raise SceneError(exc.file, flag, exc.detail) from None
        raise
    if args.json:
        print(_dumps(result.summary, indent=2))
    else:
        _print_simulation(result)
    return 0


def cmd_run(args) -> int:
    """the main job on the bundled reference scene

    Derive the bundled reference scene (masses m, 3m, m; springs k), print its equations and closed-form
    modes, check the checked-in generated module is fresh, simulate with the exact modal solution and
    velocity Verlet, and write figures.
    """
    from ._api import generate, load, modes, simulate
    from ._modules import generated_dir
    from ._scenes import display_path, resolve

    t0 = time.perf_counter()
    scene = load(display_path(resolve("seed")))
    print(modes(scene).to_text())
    d = generate([scene], generated_dir(), check=True)[0]  # the package's own module
    print(f"generated module {display_path(d.path)} is " + ("fresh (equals a new render)" if d.fresh else
                                                           "STALE: regenerate with `springchain derive`"))
    print()
    _print_simulation(simulate(scene, out=args.out, figures=True))
    print(f"\nfigures and data are in {Path(args.out).resolve()}  ({time.perf_counter() - t0:.2f} s in all)")
    return 0


def cmd_bench(args) -> int:
    """work-precision benchmark of every method (figures and a table)

    Sweep the step of every fixed-step method and the tolerance of the adaptive ones, measure the
    largest position error against an exact (extended-precision) or very accurate reference, count force
    evaluations and time each run (min of repeats, single-threaded BLAS). Writes bench-<scene>.md,
    .json, a work-precision figure and an error-vs-horizon figure.
    """
    from ._api import bench
    from .numeric.bench.workprecision import markdown_table, write_outputs

    result = bench(args.scene or "seed", args.t_end, quick=args.quick, methods=args.method,
                   progress=not args.no_progress, alpha=args.alpha)
    paths = write_outputs(result, Path(args.out))
    if args.json:
        print(_dumps(result.as_json(), indent=1))
    else:
        print(markdown_table(result), end="")
        for path in paths:
            print(f"wrote {path}")
    return 0


def cmd_plan(args) -> int:
    """cheapest method and step to reach a tolerance

    Predict, from closed-form error models and measured costs, the step (or tolerance) each method needs
    to keep the largest position error below TOL over the horizon, and recommend the cheapest.
    """
    from ._api import load, plan

    scene = load(args.scene)
    result = plan(scene, args.tol, args.t_end, alpha=args.alpha)
    if args.json:
        print(_dumps(result.as_json(), indent=2))
        return 0
    horizon = args.t_end if args.t_end is not None else scene.dt * scene.steps
    print(f"plan for {scene.name!r}: largest position error <= {args.tol:g} over t = 0 ... {horizon:g} "
          f"(error as in `springchain bench`: max over every step, or the output grid)")
    print(f"{'method':<14}{'dt / rtol':>14}{'steps':>14}{'predicted error':>17}{'predicted s':>14}  model")
    for c in sorted(result.candidates, key=lambda c: c.predicted_seconds):
        setting = f"{c.dt:.6g}" if c.dt is not None else (f"rtol {c.rtol:.2g}" if c.rtol is not None else "-")
        steps = str(c.steps) if c.steps is not None else "-"
        print(f"{c.name:<14}{setting:>14}{steps:>14}{c.predicted_error:>17.3e}{c.predicted_seconds:>14.3e}  {c.model}")
    for c in result.unreachable:
        print(f"{c.name:<14} cannot reach {args.tol:g}: best predicted {c.predicted_error:.2e} ({c.model or 'floor'})")
    r = result.recommended
    how = f"dt = {r.dt:.6g}" if r.dt is not None else (f"rtol = {r.rtol:.2g}" if r.rtol is not None else "no step")
    print(f"recommended: {r.name} ({how}), predicted error {r.predicted_error:.2e} in {r.predicted_seconds:.3g} s")
    return 0


def cmd_scaling(args) -> int:
    """setup-vs-step cost from N = 3 to 10^6, and the symbolic cost

    Time the exact solution's set-up (dense, tridiagonal, transform) against one Verlet step (NumPy
    stencil, fused) and the 32-byte-per-mass memory floor for chains of N masses; the crossover horizon;
    and derive + codegen time against sympy's LagrangesMethod. Writes DIR/scaling.{json,md,png} and
    DIR/symbolic-cost.{json,md,png}; progress on stderr.
    """
    from ._api import scaling

    result = scaling(args.max_n, args.symbolic_max_n, args.out)
    if args.json:
        print(_dumps(result.to_json(), indent=1))
        return 0
    print(result.to_markdown(), end="")
    for path in result.files:
        print(f"wrote {path}")
    return 0


def cmd_sweep(args) -> int:
    """ensembles and parameter studies on Dask (parquet, summary, figures)

    Draw S realisations of a scene (parameters with --vary, per-mass or per-spring disorder of [chain]
    scenes with --disorder), compute every realisation's omega^2 (and, for chains, participation ratios
    and inverse localisation lengths) as Dask tasks of B realisations, and write DIR/sweep.parquet (one
    part per batch), DIR/summary.json and figures (not with --no-figures). DIST: uniform(a, b),
    normal(mu, sigma), lognormal(mu, sigma) or grid(a, b, n). Re-running into the same DIR resumes.
    """
    from ._sweep import sweep

    result = sweep(args.scene, vary=args.vary or (), disorder=args.disorder or (), samples=args.samples,
                   seed=args.seed, batch=args.batch, workers=args.workers, scheduler=args.scheduler,
                   out=args.out, figures=not args.no_figures, progress=not args.no_progress)
    if args.json:
        print(_dumps(result.to_json(), indent=1))
        return 0
    r = result.run
    print(f"sweep of {result.summary['scene']!r}: {result.rows} samples x {result.summary['modes']} modes; "
          f"{r['computed']} batches computed, {r['skipped']} already done, {r['seconds']:.2f} s ({r['scheduler']})")
    print(f"  {'wrote' if r['computed'] else 'kept '} {result.parquet}")
    verb = "kept " if r["summary"] == "kept" else "wrote"
    for p in (result.out / "summary.json", *result.figures):
        print(f"  {verb} {p}")
    return 0


def cmd_frf(args) -> int:
    """frequency response: receptance, mobility, accelerance, dynamic stiffness, transmissibility

    The receptance H(iw) = X_out / F_in of (K - w^2 M + i w C) X = F (a dense solve per frequency; a
    tridiagonal one for [chain] scenes) on a log grid refined around every resonance, with the exact
    peak of |H| of each damped one (undamped resonances are infinite: the grid stops 1e-4 short of
    them). Prints the resonances and, for scenes of at most 6 masses, the transfer function H(s) as a
    ratio of polynomials in s (text and LaTeX); writes the Bode figure DIR/<scene>-frf-<in>-<out>.png.
    With --form, the mobility (V_out/F_in), accelerance (A_out/F_in) or dynamic stiffness (F_in/X_out)
    of the same receptances, or for a moving base (--input ground) the absolute or relative
    transmissibility, in Hz (--hz), dB (--db) and your units (--units); writes
    DIR/<scene>-frf-<form>-<in>-<out>.png.
    """
    from ._frf import frf

    if args.form or args.hz or args.db or args.units:
        return _frf_form(args)
    result = frf(args.scene, args.input, args.output, args.omega_min, args.omega_max, args.points)
    if args.uff:
        from ._uff import write_frf_uff

        uff_path = write_frf_uff(result, args.uff)
    path = result.save(args.out)
    if args.json:
        print(_dumps(result.to_json()))
        return 0
    print(result.to_text(), end="")
    print(f"wrote {path}")
    if args.uff:
        print(f"wrote {uff_path} (UFF dataset 58, binary: frequencies [Hz] and complex values exact)")
    return 0


def _frf_form(args) -> int:
    """``frf`` with --form, --hz, --db or --units: the form's table, figure and JSON."""
    from ._frf_forms import frf_form

    units = _output_units(args)
    form = args.form or "receptance"
    result = frf_form(args.scene, form, input=args.input, output=args.output, hz=args.hz, db=args.db,
                      omega_min=args.omega_min, omega_max=args.omega_max, points=args.points)
    path = result.save(args.out, units)
    uff_path = None
    if args.uff:
        from ._uff import write_frf_uff

        uff_path = write_frf_uff(result, args.uff)
    if args.json:
        print(_dumps(result.to_json(units)))
        return 0
    print(result.to_text(units), end="")
    print(f"wrote {path}")
    if uff_path:
        print(f"wrote {uff_path} (UFF dataset 58, binary, SI units: frequencies [Hz] and complex values exact)")
    return 0


def cmd_animate(args) -> int:
    """a GIF of a mode shape oscillating or of a simulated trajectory

    Write DIR/<scene>-mode<J>.gif (mode J, counted from 0 in ascending frequency, rigid-body modes
    included) or DIR/<scene>-<method>.gif (the scene simulated from its initial state by METHOD, a few
    frames recorded). Masses are dots on a line joined by springs, displacements scaled to be visible;
    [chain] scenes show a decimated displacement profile.
    """
    from ._animate import animate

    result = animate(args.scene, mode=args.mode, method=args.method, out=args.out, frames=args.frames, fps=args.fps)
    print(f"{result.describe()}\nwrote {result.path}")
    return 0


# -- the ecosystem: random vibration, output units ------------------------------------------------
def _output_units(args):
    """The ``--units`` list (None without it); a bad entry is one line naming the flag."""
    from .derive.units.output import output_units

    return output_units(getattr(args, "units", None), "--units")


def cmd_psd(args) -> int:
    """random vibration: response PSD and RMS of every mass and spring force

    Drive the scene by a random input given by its one-sided PSD (a CSV f,psd: frequency [Hz] and PSD
    [unit^2/Hz], piecewise linear on log-log axes; units in the header with the units extra, e.g.
    'f [Hz], psd [g^2/Hz]'): a force on MASS (--on) or, without --on, a base acceleration. Prints the
    RMS displacement, velocity and acceleration of every mass and the RMS force of every spring, from
    the exact modal integral (no frequency sampling error), and writes log-log PSD figures.
    """
    from ._random import random_response

    units = _output_units(args)
    result = random_response(args.scene, args.input, args.on,
                             interpolation="linear" if args.linear else "loglog")
    if args.json:
        print(_dumps(result.to_json(units)))
        return 0
    print(result.to_text(units), end="")
    if not args.no_figures:
        for kind in ("acceleration", "displacement", "spring force"):
            print(f"wrote {result.save(args.out, kind, units)}")
    return 0


def _add_psd(sub) -> None:
    """``springchain psd``: random vibration."""
    ps = _command(sub, "psd", cmd_psd)
    _scene(ps, "building")
    ps.add_argument("--input", required=True, metavar="FILE",
                    help="the input PSD: a CSV f,psd (frequency [Hz], one-sided PSD [unit^2/Hz]; header units "
                         "such as 'f [Hz], psd [g^2/Hz]' need the units extra)")
    ps.add_argument("--on", metavar="MASS",
                    help="the mass a random force drives (a name; an index for [chain] scenes); default: the "
                         "PSD is a base acceleration")
    ps.add_argument("--linear", action="store_true",
                    help="interpolate the PSD linearly between breakpoints (default: straight on log-log axes)")
    _units_flag(ps)
    ps.add_argument("--no-figures", action="store_true", help="print only")
    _json(ps)
    _out(ps, DEFAULT_OUT, metavar="DIR")


def _units_flag(p) -> None:
    p.add_argument("--units", metavar="LIST",
                   help="show results in these units, e.g. 'mm,kN,g' (each result in the listed unit of its "
                        "dimension; ratios and PSDs follow; g is standard gravity; needs the units extra)")


# -- structural dynamics: response spectra and response-spectrum analysis ----------------------
def _zeta(text):
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--zeta {text!r}: not a number; accepted: a damping ratio 0 <= zeta < 1") from None
    if not (math.isfinite(value) and 0 <= value < 1):
        raise argparse.ArgumentTypeError(f"--zeta {text!r}: accepted: a damping ratio 0 <= zeta < 1")
    return value


def cmd_spectrum(args) -> int:
    """response spectra (SD, PSV, PSA) of an accelerogram

    Displacement, pseudo-velocity and pseudo-acceleration response spectra of a ground-acceleration
    record (CSV with header t,a in s and m/s^2, linear between rows, zero outside: the [ground] table
    format), exact for that piecewise-linear input (closed-form one-step maps of the damped oscillator,
    no time-stepping error; the peak between samples is refined). SD is the peak over the record and
    the free vibration after its last row; periods are listed in ascending order. Writes
    DIR/<record>-spectrum.png and .json.
    """
    from ._structural import parse_periods, read_record, response_spectrum

    periods = parse_periods(args.periods) if args.periods else None
    result = response_spectrum(read_record(args.record), zeta=args.zeta or [0.05], periods=periods)
    paths = result.save(args.out)
    if args.json:
        print(_dumps(result.to_json()))
        return 0
    print(result.to_text(), end="")
    for p in paths:
        print(f"wrote {p}")
    return 0


def cmd_rsa(args) -> int:
    """response-spectrum analysis: peak floor displacements, drifts, storey shears, base shear (SRSS, CQC)

    Peak modal responses of a scene (every piece tied to a wall) to a response spectrum: FILE is a
    record (header t,a: its exact spectrum at each mode's period and damping ratio) or a design spectrum
    (header T,Sa; s and m/s^2, linear between rows). Prints per mode T, zeta, Gamma, effective mass, SD,
    PSA and base shear, and the floor displacements, inter-storey drifts, spring forces (storey shears)
    and base shear combined by SRSS and by CQC (Der Kiureghian's correlation).
    """
    from ._structural import rsa

    result = rsa(args.scene, args.spectrum, combine=args.combine)
    print(_dumps(result.to_json()) if args.json else result.to_text(), end="\n" if args.json else "")
    return 0


def add_structural_commands(sub) -> None:
    """The ``spectrum`` and ``rsa`` subcommands."""
    sp_ = _command(sub, "spectrum", cmd_spectrum)
    sp_.add_argument("record", help="the accelerogram CSV (header t,a), or a bundled record's name (quake-record)")
    sp_.add_argument("--zeta", type=_zeta, action="append", metavar="Z",
                     help="damping ratio, repeatable (default: 0.05)")
    sp_.add_argument("--periods", metavar="A:B:N|T1,T2,...",
                     help="periods in s: N log-spaced from A to B, or a comma list (default: 0.02:10:100)")
    sp_.add_argument("--json", action="store_true",
                     help='print one JSON object {"periods", "zeta", "sd", "psv", "psa", ...} and nothing else')
    sp_.add_argument("--out", default="springchain-out", metavar="DIR",
                     help="folder for the figure and JSON file (default: %(default)s)")
    rs = _command(sub, "rsa", cmd_rsa)
    rs.add_argument("scene", help="a scene file (TOML) or the name of a bundled scene, e.g. building_quake")
    rs.add_argument("--spectrum", required=True, metavar="FILE",
                    help="record (t,a) or design spectrum (T,Sa) CSV, or a bundled record's name (quake-record)")
    rs.add_argument("--combine", choices=("cqc", "srss"), default="cqc",
                    help="the combination the result leads with (both are printed; default: %(default)s)")
    rs.add_argument("--json", action="store_true", help="print one JSON object and nothing else")


# -- periodic chains: bands ---------------------------------------------------------------------
def cmd_bands(args) -> int:
    """dispersion relation of a periodic chain: D(q), branches, gaps, Im q, density of states

    The unit cell of a [cell] scene, or of a [chain] whose expressions repeat in i (its period found from the
    expressions), its Bloch matrix D(q), characteristic polynomial and closed-form branches omega_j(q); at the
    scene's values, from a route accurate at any contrast: the branches ordered by continuity, band edges and
    gaps, the attenuation per cell Im q in the gaps, the density of states, the scene's own finite chain with
    every mode named by band and q (or as an edge/defect mode), and damped bands. Writes DIR/<scene>-bands.npz
    (q x branch), .json and the band figure .png.
    """
    from ._bands import bands

    result = bands(args.scene, points=args.points)
    paths = result.save(args.out, figures=not args.no_figures)
    if args.json:
        print(_dumps({**result.to_json(), "files": [str(p) for p in paths]}, indent=1))
    elif args.latex:
        print(result.to_latex(), end="")
    else:
        print(result.to_text(), end="")
        for p in paths:
            print(f"wrote {p}")
    return 0


def _add_bands(sub) -> None:
    """``springchain bands``: dispersion relations of periodic chains."""
    b = _command(sub, "bands", cmd_bands)
    _scene(b, "diatomic")
    b.add_argument("--points", type=_positive_int("--points"), default=401, metavar="P",
                   help="q-points from -pi to pi (default: %(default)s)")
    g = b.add_mutually_exclusive_group()
    g.add_argument("--json", action="store_true", help="print one JSON object and nothing else")
    g.add_argument("--latex", action="store_true", help="print D(q), the polynomial and the branches as LaTeX")
    _out(b, DEFAULT_OUT, metavar="DIR")
    b.add_argument("--no-figures", action="store_true", help="write only the NPZ and JSON files")
# -- sensitivities, MAC, model updating, reconstruction (issue 36) ------------------------------
def add_sensitivity_options(m) -> None:
    """``modes --sensitivity [--parameters P,Q]``."""
    m.add_argument("--sensitivity", action="store_true",
                   help="print d omega^2/dp, p/omega^2 d omega^2/dp and d phi/dp (Nelson's method, mass-normalised "
                        "shapes) of every listed mode for each parameter, and the parameters ranked by influence; "
                        "with --json one JSON object (shapes and their derivatives up to 40 masses)")
    m.add_argument("--parameters", metavar="P,Q,...",
                   help="the parameters of --sensitivity (default: every parameter the masses and springs use)")
    m.add_argument("--modes", metavar="J,K,...", type=_mode_list,
                   help="with --sensitivity: the modes listed, as positions 0, 1, ... in ascending omega^2 (rigid "
                        "modes included; default: every mode up to 40 masses, else the 10 lowest and 10 highest)")


def _mode_list(text: str) -> tuple[int, ...]:
    """``--modes 0,3,5``: distinct mode positions (an argparse type: one line on anything else)."""
    items = [t.strip() for t in str(text).split(",")]
    if not all(t.isdigit() and len(t) < 10 for t in items) or len(set(map(int, items))) != len(items):
        raise argparse.ArgumentTypeError(f"--modes {text[:60]!r}: accepted: distinct mode positions 0, 1, ... "
                                         "separated by commas, e.g. 0,1,2")
    return tuple(int(t) for t in items)


def cmd_modes_sensitivity(args) -> int:
    """``modes SCENE --sensitivity``: the sensitivity report."""
    from ._sensitivity import sensitivities

    if args.latex:
        raise SceneError(None, "--sensitivity", "with --latex: accepted: --sensitivity alone (text) or with --json")
    result = sensitivities(args.scene, parameters=args.parameters, modes=args.modes)
    print(_dumps(result.to_json(), indent=1) if args.json else result.to_text(), end="\n" if args.json else "")
    return 0


def cmd_mac(args) -> int:
    """modal assurance criterion between two mode sets, optimally paired

    MAC(a, b) = (a.b)^2 / ((a.a)(b.b)) between every mode of A and of B, and the pairing that maximises
    the summed MAC (Hungarian method). A and B are scenes (their mass-normalised shapes) or measured-modes
    CSV files (header omega or frequency, then one column per sensor mass); sets are compared at the
    masses they share, or at --masses.
    """
    from ._mac import mac

    result = mac(args.a, args.b, masses=args.masses)
    print(_dumps(result.to_json(), indent=1) if args.json else result.to_text(), end="\n" if args.json else "")
    return 0


def cmd_update(args) -> int:
    """fit scene parameters to measured modes (least squares on analytic sensitivities)

    Pair the measured modes (CSV: omega or frequency [Hz], optional omega_std, optional shapes at sensor
    masses) with the scene's by MAC (or frequency), fit the chosen parameters by least squares (SciPy's
    trust-region method on the analytic Jacobian, parameters in log scale), and print the updated values
    with standard errors and correlations, an identifiability report (singular values of the weighted
    Jacobian, combinations the data do not fix), the before/after frequency and MAC tables. Writes
    DIR/<scene>-updated.toml (atomically) and DIR/<scene>-update.png.
    """
    from ._updating import update

    result = update(args.scene, args.measured, parameters=args.parameters, bounds=args.bounds or (),
                    modes=args.modes, out=args.out)
    print(_dumps(result.to_json(), indent=1) if args.json else result.to_text(), end="\n" if args.json else "")
    return 0


def cmd_reconstruct(args) -> int:
    """masses and springs of a fixed-free chain from its two spectra (Jacobi inverse eigenvalue problem)

    FILE (CSV): a column omega2_free (n values: the chain fixed to a wall at mass 1, free at mass n) and a
    column omega2_clamped (n - 1 values: the same chain with mass n clamped as well), or instead of the
    latter end_component (the free-end components of the mass-normalised shapes, which fix the scale too);
    values may be quoted decimal strings of any length (50 digits recover the chain to 1e-12). The spectra
    must interlace. The Jacobi matrix is rebuilt by Lanczos in extended precision and the one free scale
    fixed by --total-mass.
    Prints the masses and springs (k1 is the wall spring), a condition estimate and the error bound it
    implies for float64 input, and writes DIR/<name>.toml.
    """
    from ._updating import reconstruct

    result = reconstruct(args.spectra, total_mass=args.total_mass, out=args.out, name=args.name)
    print(_dumps(result.to_json(), indent=1) if args.json else result.to_text(), end="\n" if args.json else "")
    return 0


def add_updating_commands(sub) -> None:
    """The ``mac``, ``update`` and ``reconstruct`` subcommands."""
    mc = _command(sub, "mac", cmd_mac)
    mc.add_argument("a", help="a scene (file or bundled name) or a measured-modes CSV file")
    mc.add_argument("b", help="a scene (file or bundled name) or a measured-modes CSV file")
    mc.add_argument("--masses", metavar="M1,M2,...",
                    help="compare at these masses only (indices for [chain] scenes; default: those both sets have)")
    _json(mc)
    up = _command(sub, "update", cmd_update)
    _scene(up, "building")
    up.add_argument("--measured", required=True, metavar="FILE",
                    help="measured modes: CSV with omega (rad/s) or frequency (Hz), optional omega_std / "
                         "frequency_std and shape_std, and one column per sensor mass holding the shape")
    up.add_argument("--parameters", required=True, metavar="P,Q,...", help="the scene parameters to fit")
    up.add_argument("--bounds", action="append", metavar="NAME=LO:HI",
                    help="bounds of a fitted parameter, repeatable (default: 0 < value, no upper bound)")
    up.add_argument("--modes", type=_positive_int("--modes"), metavar="K",
                    help="use the first K measured modes (rows) only (default: all)")
    _out(up, DEFAULT_OUT, metavar="DIR")
    _json(up)
    rc = _command(sub, "reconstruct", cmd_reconstruct)
    rc.add_argument("spectra", help="CSV with columns omega2_free (n values) and omega2_clamped (n - 1 values) or "
                                    "end_component (n values)")
    rc.add_argument("--total-mass", type=_positive_float("--total-mass"), metavar="M",
                    help="the chain's total mass (fixes the one scale two spectra leave free; not needed with "
                         "end_component)")
    rc.add_argument("--name", default="reconstructed", help="name of the scene written (default: %(default)s)")
    _out(rc, DEFAULT_OUT, metavar="DIR")
    _json(rc)


# -- parser: one function per command ---------------------------------------------------------
def _command(sub, name: str, func) -> argparse.ArgumentParser:
    """The subcommand ``name``, run by ``func``, whose docstring is its ``--help`` text: the first line
    the summary in ``springchain --help``, the rest the description (argparse re-wraps it)."""
    summary, _, description = inspect.cleandoc(func.__doc__ or "").partition("\n")
    p = sub.add_parser(name, help=summary or None, description=" ".join(description.split()) or None)
    p.set_defaults(func=func)
    return p


def _scene(p, example: str = "seed") -> None:
    """The SCENE argument: a path or a bundled scene's name."""
    p.add_argument("scene", help="a scene file (TOML) or the name of a bundled scene" + (f", e.g. {example}" if example else ""))


def _out(p, default: str, help: str = "output folder (default: %(default)s)", **kw) -> None:
    p.add_argument("--out", default=default, help=help, **kw)


def _json(p, help: str = "print one JSON object and nothing else") -> None:
    p.add_argument("--json", action="store_true", help=help)


def _no_progress(p) -> None:
    p.add_argument("--no-progress", action="store_true", help="no progress lines on stderr")


def _add_run(sub) -> None:
    """``springchain run``: the main job."""
    r = _command(sub, "run", cmd_run)
    r.add_argument("--out", default=DEFAULT_OUT, help="folder for figures and data (default: %(default)s)")


def _add_derive(sub) -> None:
    """``springchain derive``: write or check generated modules."""
    d = _command(sub, "derive", cmd_derive)
    d.add_argument("scene", nargs="*", help="scene files or bundled names (default: all bundled scenes)")
    d.add_argument("--out", help="folder for the modules (default: ./generated under the current folder)")
    d.add_argument("--check", action="store_true",
                   help="write nothing; exit 1 if a module in the same folder derive writes to (--out, default "
                        "./generated) differs from a fresh render")


def _add_modes(sub) -> None:
    """``springchain modes``: equations and modes."""
    m = _command(sub, "modes", cmd_modes)
    _scene(m)
    g = m.add_mutually_exclusive_group()
    g.add_argument("--json", action="store_true", help="print one JSON object (its fields: the guide's Modes chapter) and nothing else")
    g.add_argument("--latex", action="store_true", help="print the derivation as LaTeX (amsmath)")
    add_sensitivity_options(m)
    m.add_argument("--uff", metavar="FILE",
                   help="also write every mode as UFF dataset 55 (ASCII, Hz, mass-normalised; needs the uff extra)")


def _add_simulate(sub) -> None:
    """``springchain simulate``: run methods."""
    s = _command(sub, "simulate", cmd_simulate)
    _scene(s)
    s.add_argument("--method", action="append", choices=_method_names(), metavar="NAME",
                   help=f"method to run, repeatable ({', '.join(_method_names())}; default: modal and verlet "
                        "for linear scenes, verlet otherwise)")
    s.add_argument("--dt", type=_positive_float("--dt"), help="time step (default: the scene's)")
    s.add_argument("--steps", type=_positive_int("--steps"), help="number of steps (default: the scene's)")
    s.add_argument("--record-every", type=_positive_int("--record-every"),
                   help="keep every K-th step (default: the scene's, else 1)")
    s.add_argument("--spectrum", choices=("svd", "closed-form"), default="svd",
                   help="modes for the exact solution: SVD of the spring factor (accurate, default) or the "
                        "generated closed forms")
    s.add_argument("--rtol", type=_positive_float("--rtol"), default=DEFAULT_RTOL,
                   help="relative tolerance of the adaptive methods rk45, dop853, lsoda (default: %(default)g)")
    s.add_argument("--atol", type=_positive_float("--atol"), default=DEFAULT_ATOL,
                   help="absolute tolerance of the adaptive methods (default: %(default)g)")
    _out(s, DEFAULT_OUT)
    s.add_argument("--no-figures", action="store_true", help="write only the NPZ")
    s.add_argument("--modal-energy", action="store_true",
                   help="also record modal_energy_<method> (S x N): the energy 1/2 (q'^2 + omega^2 q^2) of each "
                        "linear normal mode about the equilibrium (ascending omega), and draw the lowest modes' "
                        "energies over time (DIR/<name>-modal-energy.png)")
    s.add_argument("--json", action="store_true", help="print a JSON summary instead of text")
    s.add_argument("--springs", action="store_true",
                   help="add drift_<method>, spring_force_<method> (S x springs) and base_shear_<method> (S) to the NPZ")
    _alpha(s)


def _alpha(p) -> None:
    """``--alpha`` (HHT-alpha's setting), the same for simulate, plan and bench."""
    p.add_argument("--alpha", type=_number("--alpha", float, math.isfinite, "a finite number"), metavar="A",
                   help="HHT-alpha's alpha for the method hht, -1/3 <= A <= 0: more numerical damping of high "
                        "modes the more negative (default: -0.05)")


def _add_bench(sub) -> None:
    """``springchain bench``: work-precision benchmark."""
    b = _command(sub, "bench", cmd_bench)
    b.add_argument("scene", nargs="?", help="a scene file or bundled name (default: seed, the reference scene)")
    b.add_argument("--t-end", type=_positive_float("--t-end"),
                   help="horizon T (default: the scene's dt x steps)")
    b.add_argument("--quick", action="store_true", help="a small sweep (seconds, for tests)")
    b.add_argument("--method", action="append", choices=_method_names(), metavar="NAME",
                   help="restrict to these methods, repeatable (default: every method that applies; the "
                        "error-vs-horizon study runs only with the default)")
    _out(b, DEFAULT_BENCH_OUT)
    b.add_argument("--json", action="store_true", help="print the records and targets as JSON")
    _alpha(b)
    _no_progress(b)


def _add_plan(sub) -> None:
    """``springchain plan``: the cheapest method for a tolerance."""
    pl = _command(sub, "plan", cmd_plan)
    _scene(pl)
    pl.add_argument("--tol", type=_positive_float("--tol"), required=True, help="largest position error allowed")
    pl.add_argument("--t-end", type=_positive_float("--t-end"), help="horizon T (default: the scene's dt x steps)")
    _alpha(pl)
    _json(pl)


def _add_scaling(sub) -> None:
    """``springchain scaling``: long-chain scaling."""
    sc = _command(sub, "scaling", cmd_scaling)
    sc.add_argument("--max-n", type=_positive_int("--max-n"), default=1_000_000,
                    help="largest chain size (default: %(default)s)")
    sc.add_argument("--symbolic-max-n", type=int, default=40,
                    help="largest N for [masses] derive and LagrangesMethod (0: skip the symbolic part; "
                         "LagrangesMethod takes ~13 s at 80; default: %(default)s)")
    sc.add_argument("--json", action="store_true", help="print one JSON object with both tables")
    _out(sc, DEFAULT_OUT)


def _add_sweep(sub) -> None:
    """``springchain sweep``: Dask studies."""
    sw = _command(sub, "sweep", cmd_sweep)
    _scene(sw, "")
    sw.add_argument("--vary", action="append", metavar="NAME=DIST",
                    help="draw scene parameter NAME per sample, repeatable; grids form their product")
    sw.add_argument("--disorder", action="append", metavar="mass=DIST|k=DIST",
                    help="[chain] scenes: multiply each mass (or spring) by its own draw, per sample")
    sw.add_argument("--samples", type=_positive_int("--samples"), required=True,
                    help="realisations (per grid point)")
    sw.add_argument("--seed", type=_whole("--seed"), default=0, help="seed (default: %(default)s)")
    sw.add_argument("--batch", type=_positive_int("--batch"),
                    help="realisations per Dask task (default: about 64 tasks in all)")
    where = sw.add_mutually_exclusive_group()
    where.add_argument("--workers", type=_positive_int("--workers"),
                       help="processes of the embedded LocalCluster (default: the cores)")
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help="use a running `dask scheduler`, e.g. tcp://127.0.0.1:8786")
    _out(sw, DEFAULT_SWEEP_OUT)
    sw.add_argument("--no-figures", action="store_true", help="write only the parquet parts and summary.json")
    _json(sw)
    _no_progress(sw)


def _add_frf(sub) -> None:
    """``springchain frf``: frequency response."""
    fr = _command(sub, "frf", cmd_frf)
    _scene(fr, "building")
    fr.add_argument("--input", required=True, metavar="MASS",
                    help="the mass the unit harmonic force drives (a name; an index for [chain] scenes)")
    fr.add_argument("--output", required=True, metavar="MASS",
                    help="the mass whose displacement is measured (a name; an index for [chain] scenes)")
    fr.add_argument("--omega-min", type=_positive_float("--omega-min"), metavar="W",
                    help="lowest angular frequency [rad/s] (default: smallest nonzero natural frequency / 10)")
    fr.add_argument("--omega-max", type=_positive_float("--omega-max"), metavar="W",
                    help="highest angular frequency [rad/s] (default: largest natural frequency x 3)")
    fr.add_argument("--points", type=_positive_int("--points"), default=400, metavar="P",
                    help="log-spaced base points; each resonance adds its refinement (default: %(default)s)")
    fr.add_argument("--json", action="store_true",
                    help='print one JSON object {"omega", "magnitude", "phase" (deg), "resonances", '
                         '"transfer_function", ...} and nothing else')
    fr.add_argument("--out", default=DEFAULT_OUT, metavar="DIR", help="folder for the Bode figure (default: %(default)s)")
    fr.add_argument("--form", metavar="FORM",
                    help="receptance, mobility, accelerance, dynamic-stiffness (force on --input), or "
                         "transmissibility, relative-transmissibility (--input ground: the base moves)")
    fr.add_argument("--hz", action="store_true", help="frequencies in Hz (default: rad/s)")
    fr.add_argument("--db", action="store_true", help="magnitudes in dB (20 log10, re 1 of the unit)")
    _units_flag(fr)
    fr.add_argument("--uff", metavar="FILE",
                    help="also write the FRF as a UFF dataset 58 (binary, frequencies in Hz; needs the uff extra)")


def _add_animate(sub) -> None:
    """``springchain animate``: GIFs."""
    an = _command(sub, "animate", cmd_animate)
    _scene(an)
    what = an.add_mutually_exclusive_group()
    what.add_argument("--mode", type=_whole("--mode"), metavar="J",
                      help="animate mode J (0 = lowest frequency; default: the lowest elastic mode)")
    what.add_argument("--method", metavar="NAME",
                      help=f"animate the trajectory of method NAME ({', '.join(_method_names())})")
    an.add_argument("--frames", type=_positive_int("--frames"), default=48, metavar="F",
                    help="frames in the GIF (default: %(default)s)")
    an.add_argument("--fps", type=_positive_float("--fps"), default=16.0, metavar="R",
                    help="frames per second (default: %(default)g)")
    _out(an, DEFAULT_OUT, metavar="DIR")


# -- parser ---------------------------------------------------------------------------------
def _method_names() -> tuple[str, ...]:
    """The registered method names (the registry lists them without importing any integrator)."""
    from .numeric.run import registry

    return registry.names()


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="springchain",
                description="Mass-spring chains: a scene file -> equations of motion and closed-form "
                            "normal modes (SymPy) -> generated NumPy code -> exact and numerical "
                            "simulations with plots.",
                epilog="Start with `springchain run` (the bundled three-mass reference scene).")
    p.add_argument("--version", action="version", version=f"springchain {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for add in (_add_run, _add_derive, _add_modes, _add_simulate, _add_bench, _add_plan, _add_scaling, _add_sweep,
                _add_frf, _add_animate, add_structural_commands, _add_bands, add_updating_commands, _add_psd):
        add(sub)
    for name in SCENE_COMMANDS:  # one option, the same on every command that takes a SCENE
        sub.choices[name].add_argument(
            "--set", action="append", metavar="NAME=VALUE",
            help="use VALUE for the scene's parameter NAME instead of the file's, repeatable (e.g. --set k=4 "
                 "--set m=2); checked like the scene file")
    return p


#: The flag that sets each quantity a library error may name.
FLAGS = {"dt": "--dt", "steps": "--steps", "record_every": "--record-every", "method": "--method",
         "rtol": "--rtol", "atol": "--atol", "tol": "--tol", "spectrum": "--spectrum",
         "input": "--input", "output": "--output", "omega_min": "--omega-min", "omega_max": "--omega-max",
         "points": "--points", "mode": "--mode", "frames": "--frames", "fps": "--fps", "max_n": "--max-n",
         "symbolic_max_n": "--symbolic-max-n", "zeta": "--zeta", "periods": "--periods", "combine": "--combine",
         "springs": "--springs", "alpha": "--alpha", "q": "--points", "on": "--on", "interpolation": "--linear",
         "form": "--form", "uff": "--uff"}


def _flag_for(args, quantity: str | None) -> str | None:
    """The flag behind a refused quantity, when the user set it on the command line."""
    flag = FLAGS.get(quantity or "")
    return flag if flag and getattr(args, quantity, None) is not None else None


def main(argv: list[str] | None = None) -> int:
    """Run one command; Ctrl-C anywhere (parsing, imports, work) ends with one line and 130."""
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
    except KeyboardInterrupt:
        sys.stderr.write("springchain: interrupted\n")
        return 130
    try:
        if getattr(args, "set", None):
            _apply_set(args)
        return args.func(args)
    except SceneError as exc:
        sys.stderr.write(f"springchain: error: {exc}\n")
        return EXIT_USAGE
    except ValueError as exc:  # numeric refusals (RunRefused) and other input problems
        from .numeric.errors import RunRefused

        if isinstance(exc, RunRefused):
            flag = _flag_for(args, exc.quantity)
            sys.stderr.write(f"springchain: error: {flag + ': ' if flag else ''}{exc}\n")
            return EXIT_USAGE
        raise
    except ImportError as exc:  # an optional extra that is not installed: its one line says what to install
        if "springchain installs only on request" not in str(exc):
            raise
        sys.stderr.write(f"springchain: error: {exc}\n")
        return EXIT_USAGE
    except BrokenPipeError:  # output piped into e.g. `head`
        sys.stderr.close()
        return 0
    except OSError as exc:  # e.g. an --out folder that cannot be created
        where = f"{exc.filename}: " if exc.filename else ""
        sys.stderr.write(f"springchain: error: {where}{exc.strerror or exc}\n")
        return EXIT_USAGE
    except KeyboardInterrupt:
        sys.stderr.write("springchain: interrupted\n")
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
