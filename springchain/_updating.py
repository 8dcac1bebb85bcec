"""Model updating from measured modes (``sc.update``, ``springchain update``) and a chain rebuilt from its
two spectra (``sc.reconstruct``, ``springchain reconstruct``).

The numbers come from :mod:`springchain.numeric.updating` (least squares, statistics, identifiability;
Lanczos in extended precision) on the sensitivities of :mod:`springchain.numeric.sensitivity`; this module
reads the files, wires the scene in, writes the updated scene and the figure.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from ._defaults import DEFAULT_OUT
from ._scenes import load
from .derive.errors import SceneError, show
from .derive.scene import DICT_FILE, Scene  # noqa: F401  (DICT_FILE: scenes without a file)


# -- the updated scene file ---------------------------------------------------------------------------
_HEADER = re.compile(r"^\s*\[\s*parameters\s*\]\s*(#.*)?$")
_TABLE = re.compile(r"^\s*\[")


def updated_text(text: str, values: dict[str, float], file: str) -> str:
    """The scene text with the ``[parameters]`` values of ``values`` replaced (comments and layout kept).

    Raises
    ------
    SceneError
        A parameter that is not a bare ``name = number`` line of the ``[parameters]`` table.
    """
    lines = text.splitlines(keepends=True)
    inside, done = False, set()
    for i, line in enumerate(lines):
        if _HEADER.match(line):
            inside = True
            continue
        if inside and _TABLE.match(line):
            inside = False
        if not inside:
            continue
        for name, v in values.items():
            m = re.match(rf"^(\s*{re.escape(name)}\s*=\s*)([^#\r\n]*?)(\s*(#.*)?)(\r?\n)?$", line)
            if m:
                lines[i] = m.group(1) + repr(float(v)) + (m.group(3) or "") + (m.group(5) or "")
                done.add(name)
    missing = [n for n in values if n not in done]
    if missing:
        raise SceneError(file, f"parameters.{missing[0]}", "not written as `name = number` in the [parameters] "
                         "table, so the updated file cannot be written; accepted: one `name = value` line per "
                         "parameter under [parameters]")
    return "".join(lines)


def write_updated(scene: Scene, values: dict[str, float], out: Path) -> Path | None:
    """Write ``out/<name>-updated.toml`` atomically, checked by loading it back; None for a scene without a file."""
    from .derive.scene import load_scene
    from .numeric.io.files import atomic_write_text

    src = Path(scene.file)
    if scene.file == DICT_FILE or not src.is_file():
        return None
    text = updated_text(src.read_text(encoding="utf-8"), values, scene.file)
    path = Path(out) / f"{scene.name}-updated.toml"
    back = load_scene(path, text)  # the loader's every check, before anything is written
    for name, v in values.items():
        if back.parameters[name] != float(v):  # pragma: no cover - repr round-trips exactly
            raise SceneError(str(path), f"parameters.{name}", f"{back.parameters[name]!r} read back for {v!r}")
    atomic_write_text(path, text)
    return path


# -- update -------------------------------------------------------------------------------------------
def parse_bounds(items, names: tuple[str, ...], start: dict[str, float]):
    """``NAME=LO:HI`` items as (lower, upper) arrays over ``names`` (either side may be empty)."""
    import numpy as np

    lower, upper = np.zeros(len(names)), np.full(len(names), np.inf)
    seen = set()
    for item in items:
        name, eq, rng = str(item).partition("=")
        name = name.strip()
        lo, colon, hi = rng.partition(":")
        bad = SceneError(None, "bounds", f"{show(item)}: accepted: NAME=LO:HI with NAME a fitted parameter "
                                         f"({', '.join(names)}) and 0 <= LO < HI (either may be left empty)")
        if not eq or not colon or name not in names or name in seen:
            raise bad
        try:
            a = float(lo) if lo.strip() else 0.0
            b = float(hi) if hi.strip() else math.inf
        except ValueError:
            raise bad from None
        if not (math.isfinite(a) and a >= 0 and b > a and not math.isnan(b)):
            raise bad
        if not a <= start[name] <= b:
            raise SceneError(None, "bounds", f"{show(item)}: the starting value {name} = {start[name]:g} is outside; "
                                             "accepted: bounds around the scene's value")
        seen.add(name)
        i = names.index(name)
        lower[i], upper[i] = a, b
    return lower, upper


def _sensor_index(scene: Scene, sensors: tuple[str, ...], file: str) -> list[int]:
    if scene.chain is not None:
        out = []
        for s in sensors:
            if not s.isdigit() or int(s) >= scene.n:
                raise SceneError(file, f"column {s!r}", f"not a mass of the [chain] scene {scene.name!r}; accepted: "
                                                        f"indices 0 ... {scene.n - 1}")
            out.append(int(s))
        return out
    index = {m: i for i, m in enumerate(scene.mass_names)}
    for s in sensors:
        if s not in index:
            raise SceneError(file, f"column {s!r}", f"not a mass of {scene.name!r}; accepted: omega or frequency, "
                                                    f"omega_std, frequency_std, shape_std and the masses "
                                                    + ", ".join(scene.mass_names[:12]))
    return [index[s] for s in sensors]


@dataclass(frozen=True)
class Update:
    """The result of :func:`update`.

    Attributes
    ----------
    scene : Scene
        The updated scene (validated; the fitted parameters replaced).
    parameters : tuple of str
    start, values, standard_errors : ndarray, shape (P,)
    fit : numeric.updating.fit.Fit
    measured : numeric.updating.measured.Measured
    modes : ndarray of int, shape (R,)
        The model mode paired with each measured row.
    omega_before, omega_after : ndarray, shape (R,)
    mac_before, mac_after : ndarray, shape (R,)
        NaN for rows without a measured shape.
    files : tuple of Path
    notes : tuple of str
    """

    scene: Scene
    parameters: tuple[str, ...]
    start: object = field(repr=False)
    values: object = field(repr=False)
    standard_errors: object = field(repr=False)
    fit: object = field(repr=False)
    measured: object = field(repr=False)
    modes: object = field(repr=False)
    omega_before: object = field(repr=False)
    omega_after: object = field(repr=False)
    mac_before: object = field(repr=False)
    mac_after: object = field(repr=False)
    files: tuple = ()
    notes: tuple[str, ...] = ()

    def identifiability(self) -> dict:
        """Singular values (relative) and the combinations the data do not fix, named."""
        from .numeric.updating.fit import describe

        s = self.fit.singular_values
        top = float(s[0]) if s.size and s[0] > 0 else 1.0
        return {"singular_values": [float(v) for v in s], "relative": [float(v) / top for v in s],
                "directions": [{p: float(v) for p, v in zip(self.parameters, self.fit.directions[:, i])}
                               for i in range(len(self.parameters))],
                "unidentifiable": [describe(v, self.parameters) for v in self.fit.unidentifiable],
                "identifiable": [{"combination": describe(v, self.parameters), "value": val, "standard_error": se}
                                 for v, val, se in self.fit.combinations]}

    def to_json(self) -> dict:
        """What ``springchain update ... --json`` prints."""
        import numpy as np

        f = self.fit
        nan = lambda v: None if v is None or not np.isfinite(v) else float(v)  # noqa: E731
        return {"scene": self.scene.name, "measured": self.measured.file,
                "parameters": [{"name": p, "start": float(a), "value": float(b), "standard_error": nan(se),
                                "identifiable": bool(ok)}
                               for p, a, b, se, ok in zip(self.parameters, self.start, self.values,
                                                          self.standard_errors, f.identifiable)],
                "correlations": [[nan(v) for v in row] for row in f.correlations],
                "identifiability": self.identifiability(),
                "noise": {"known": self.measured.omega_std is not None, "scale": nan(f.noise_scale),
                          "chi2": f.chi2, "dof": f.dof},
                "modes": [{"measured_omega": float(w), "mode": int(j), "omega_before": float(a),
                           "omega_after": float(b), "mac_before": nan(ma), "mac_after": nan(mb)}
                          for w, j, a, b, ma, mb in zip(self.measured.omega, self.modes, self.omega_before,
                                                        self.omega_after, self.mac_before, self.mac_after)],
                "status": f.status, "evaluations": f.evaluations,
                "files": [str(p) for p in self.files], "notes": list(self.notes)}

    def to_text(self) -> str:
        """What ``springchain update`` prints."""
        import numpy as np

        f = self.fit
        known = self.measured.omega_std is not None
        lines = [f"Updated {self.scene.name!r} to {self.measured.file}: {self.measured.rows} measured mode{'' if self.measured.rows == 1 else 's'}, "
                 f"{len(self.parameters)} parameter{'' if len(self.parameters) == 1 else 's'} (least squares in log p, "
                 f"analytic Jacobian; {f.evaluations} model evaluation{'' if f.evaluations == 1 else 's'}: {f.status})",
                 "noise: " + ("standard deviations from the file" if known else
                              f"unknown, estimated from the fit: s = {f.noise_scale:.3g} (relative)")
                 + f"; chi^2 = {f.chi2:.4g} for {f.dof} degree{'' if f.dof == 1 else 's'} of freedom", "",
                 f"{'parameter':<14}{'start':>16}{'updated':>18}{'std. error':>14}{'rel.':>10}"]
        for p, a, b, se, ok in zip(self.parameters, self.start, self.values, self.standard_errors, f.identifiable):
            if ok:
                lines.append(f"{p:<14}{a:>16.8g}{b:>18.10g}{se:>14.4g}{se / abs(b):>10.2%}")
            else:
                lines.append(f"{p:<14}{a:>16.8g}{b:>18.10g}{'not identifiable':>24}")
        if len(self.parameters) > 1:
            lines += ["", "correlations:"]
            lines += [f"  {p:<12}" + " ".join("     -" if not np.isfinite(v) else f"{v:6.3f}" for v in row)
                      for p, row in zip(self.parameters, f.correlations)]
        ident = self.identifiability()
        lines += ["", "identifiability: singular values of the weighted Jacobian (relative) "
                  + ", ".join(f"{v:.3g}" for v in ident["relative"])]
        if ident["unidentifiable"]:
            for combo in ident["unidentifiable"]:
                lines.append(f"  not identifiable from these data: {combo} (kept at its starting value)")
            for rec in ident["identifiable"]:
                lines.append(f"  fixed by the data: {rec['combination']} = {rec['value']:.10g} "
                             f"+- {rec['standard_error']:.3g}")
        else:
            lines.append("  every parameter is fixed by the data")
        lines += ["", f"{'measured omega':>15}{'mode':>6}{'before':>16}{'error':>10}{'after':>16}{'error':>10}"
                  f"{'MAC before':>12}{'MAC after':>11}"]
        for w, j, a, b, ma, mb in zip(self.measured.omega, self.modes, self.omega_before, self.omega_after,
                                      self.mac_before, self.mac_after):
            mac = (f"{ma:>12.6f}{mb:>11.6f}" if np.isfinite(ma) else f"{'-':>12}{'-':>11}")
            lines.append(f"{w:>15.8g}{int(j):>6}{a:>16.8g}{a / w - 1:>10.2e}{b:>16.8g}{b / w - 1:>10.2e}{mac}")
        for note in self.notes:
            lines.append(f"note: {note}")
        for p in self.files:
            lines.append(f"wrote {p}")
        return "\n".join(lines) + "\n"


def prepare(scene: str | Path | Scene, parameters):
    """What :func:`update` builds before fitting (generated module, symbolic element derivatives), for many
    fits of one scene: ``update(..., setup=prepare(scene, "k1,k2"))``."""
    from ._sensitivity import Setup, parameter_list

    sc = load(scene)
    return Setup(sc, parameter_list(sc, parameters), closed_forms=False)


def _read_measured(path):
    """A measured-modes CSV, or a measured FRF reduced to modes by peak and quadrature picking
    (:mod:`numeric.updating.frf_peaks`): ``(Measured, note or None)``."""
    from .numeric.updating.frf_peaks import is_frf, modes_from_frf, read_frf
    from .numeric.updating.measured import read_measured, read_text, rows_of

    header, _ = rows_of(read_text(Path(path), str(path)), str(path))
    if not is_frf(header):
        return read_measured(path), None
    m = modes_from_frf(*read_frf(path))
    return m, (f"{m.file}: a measured FRF; {m.rows} resonance peaks picked at omega = "
               + ", ".join(f"{w:.6g}" for w in m.omega) + " rad/s (one mode plus a constant fitted around each peak: "
               "frequencies and shapes)")


def update(scene: str | Path | Scene, measured, parameters, bounds=(), modes: int | None = None,
           out: str | Path | None = DEFAULT_OUT, figure: bool = True, setup=None) -> Update:
    """Fit scene parameters to measured natural frequencies (and shapes) by least squares.

    Parameters
    ----------
    scene : str, Path or Scene
    measured : str, Path or Measured
        Measured-modes CSV (:mod:`springchain.numeric.updating.measured`: ``omega`` or ``frequency``,
        optional ``omega_std``/``frequency_std`` and ``shape_std``, one column per sensor mass), a measured
        FRF CSV (``omega`` or ``frequency``, ``<mass>.re`` and ``<mass>.im`` per sensor: modes by peak and
        quadrature picking, :mod:`springchain.numeric.updating.frf_peaks`), or a
        :class:`~springchain.numeric.updating.measured.Measured`.
    parameters : str or sequence of str
        The scene parameters to fit (``"k1,k2"``).
    bounds : sequence of str
        ``"NAME=LO:HI"`` bounds (default 0 < p).
    modes : int, optional
        Use the first ``modes`` measured rows only.
    out : str or Path or None
        Folder of ``<scene>-updated.toml`` and ``<scene>-update.png``; None writes nothing.
    figure : bool
    setup : optional
        From :func:`prepare` (the same scene and parameters): skips the set-up in repeated fits.

    Returns
    -------
    Update

    Raises
    ------
    SceneError, RunRefused
        Bad files and settings, one line each (a missing column, NaN, more modes asked than measured or
        than the model has, an unknown sensor mass, standard deviations given for some residuals only).
    """
    import numpy as np

    from ._sensitivity import Setup, default_modes, parameter_list
    from .numeric.updating.fit import Memo, Problem, solve
    from .numeric.updating.measured import Measured
    from .numeric.updating.residuals import pair, weighted

    sc = load(scene)
    names = parameter_list(sc, parameters)
    if not names:
        raise SceneError(sc.file, "parameters", "none given; accepted: the scene parameters to fit, e.g. "
                                                + ",".join(sc.parameter_names[:2]))
    frf_note = None
    if isinstance(measured, Measured):
        m = measured
    else:
        m, frf_note = _read_measured(measured)
    if modes is not None:
        if modes > m.rows:
            raise SceneError(m.file, "modes", f"{modes}: more modes asked than measured ({m.rows} rows); accepted: "
                                              f"at most {m.rows}")
        m = m.first(modes)
    known = m.omega_std is not None
    with_shapes = m.with_shapes()
    if m.shape_std is not None and not known:
        raise SceneError(m.file, "shape_std", "given without omega_std (or frequency_std); accepted: both standard "
                                              "deviations, or neither (the noise level is then estimated)")
    if known and with_shapes.size and (m.shape_std is None or not np.all(np.isfinite(m.shape_std[with_shapes]))):
        raise SceneError(m.file, "shape_std", "missing for a row with a measured shape while omega_std is given; "
                                              "accepted: shape_std on every row with a shape, or no standard "
                                              "deviations at all")
    sensors = _sensor_index(sc, m.sensors, m.file) if m.sensors else []
    if setup is None or setup.scene.sha256 != sc.sha256 or setup.parameters != names:
        setup = Setup(sc, names, closed_forms=False)
    candidates = default_modes(setup.system.n)
    first = setup.at(None, candidates)
    elastic = ~first.rigid
    positions = first.index[elastic]
    if m.rows > positions.shape[0]:
        raise SceneError(m.file, "rows", f"{m.rows} measured modes but the model lists {positions.shape[0]} elastic "
                                         f"modes; accepted: at most {positions.shape[0]} measured modes (or --modes)")
    start = np.array([sc.parameters[p] for p in names], dtype=float)
    if np.any(start <= 0):
        bad = names[int(np.argmax(start <= 0))]
        raise SceneError(sc.file, f"parameters.{bad}", f"{sc.parameters[bad]!r}: fitted parameters are varied in "
                                                       "log scale; accepted: a positive starting value")
    sensor_shapes = first.shapes[sensors][:, elastic] if sensors else None
    pairing = pair(m, positions, np.sqrt(first.omega2[elastic]), sensor_shapes)
    lower, upper = parse_bounds(bounds, names, sc.parameters)

    def evaluate(p):
        vals = dict(zip(names, (float(v) for v in p)))
        r = setup.at(vals, pairing.modes)
        slots = np.searchsorted(r.index, pairing.modes)
        shapes = r.shapes[sensors][:, slots] if sensors else None
        d_shapes = r.d_shapes[:, sensors][:, :, slots] if sensors else None
        res, jac = weighted(m, p, r.omega2[slots], r.d_omega2[:, slots], shapes, d_shapes, known)
        return (r, slots, shapes, d_shapes), res, jac

    # once per point: the fit's residual, its Jacobian and the before/after tables
    point = Memo(evaluate, score=lambda v: float(v[1] @ v[1]))

    def model(p):
        return point(p)[0]

    def residual(p):
        return point(p)[1:]

    fit = solve(Problem(names, start, residual, lower, upper, known, int(with_shapes.size) if sensors else 0))
    notes = [frf_note] if frf_note else []
    r0, s0, sh0, _ = model(start)
    r1, s1, sh1, _ = model(fit.values)
    from .numeric.sensitivity.mac import mac_matrix

    def macs(shapes):
        out_ = np.full(m.rows, np.nan)
        for row in with_shapes:
            out_[row] = mac_matrix(m.shapes[:, row], shapes[:, row])[0, 0]
        return out_

    mac0 = macs(sh0) if sensors else np.full(m.rows, np.nan)
    mac1 = macs(sh1) if sensors else np.full(m.rows, np.nan)
    same = np.array_equal(np.asarray(candidates), pairing.modes)  # every mode paired: the fit's last evaluation
    after = model(fit.values)[0] if same else setup.at(dict(zip(names, fit.values)), candidates)
    again = pair(m, after.index[~after.rigid], np.sqrt(after.omega2[~after.rigid]),
                 after.shapes[sensors][:, ~after.rigid] if sensors else None)
    if not np.array_equal(again.modes, pairing.modes):
        notes.append("the updated model pairs the measured modes differently from the starting one "
                     f"({pairing.modes.tolist()} -> {again.modes.tolist()}): check the starting values")
    for lo, hi, v, p in zip(lower, upper, fit.values, names):
        if (lo > 0 and v <= lo * (1 + 1e-9)) or (math.isfinite(hi) and v >= hi * (1 - 1e-9)):
            notes.append(f"{p} ended on its bound: its standard error assumes an interior optimum")
    updated = sc.with_parameters({p: float(v) for p, v in zip(names, fit.values)})
    files = []
    if out is not None:
        path = write_updated(sc, dict(zip(names, fit.values)), Path(out))
        if path is None:
            notes.append("the scene has no file: the updated scene is the result's .scene")
        else:
            files.append(path)
        if figure:
            from .numeric.plots import figures as plots
            from .numeric.updating.figure import update_figure

            w = m.omega
            fig = update_figure(f"{sc.name}: updated to {Path(m.file).name}", [f"{j}" for j in pairing.modes],
                                np.sqrt(r0.omega2[s0]) / w - 1, np.sqrt(r1.omega2[s1]) / w - 1,
                                mac0 if sensors else None, mac1 if sensors else None)
            fpath = Path(out) / f"{sc.name}-update.png"
            plots.save(fig, fpath)
            files.append(fpath)
    return Update(updated, names, start, fit.values, fit.standard_errors, fit, m, pairing.modes,
                  np.sqrt(r0.omega2[s0]), np.sqrt(r1.omega2[s1]), mac0, mac1, tuple(files), tuple(notes))


__all__ = ["update", "prepare", "Update", "updated_text", "write_updated", "parse_bounds"]


# -- reconstruct --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Reconstruction:
    """The result of :func:`reconstruct`.

    Attributes
    ----------
    masses, springs : ndarray, shape (n,)
        float64 values (``springs[0]`` is the wall spring k₁).
    masses_text, springs_text : list of str
        The same to 20 significant digits (computed in extended precision).
    condition, bound, input_accuracy : float
        κ, κ·u and u (:mod:`springchain.numeric.updating.reconstruct`).
    scene_text : str
        A scene file of the chain.
    files : tuple of Path
    """

    masses: object = field(repr=False)
    springs: object = field(repr=False)
    masses_text: list = field(repr=False)
    springs_text: list = field(repr=False)
    condition: float = 0.0
    bound: float = 0.0
    input_accuracy: float = 0.0
    scene_text: str = field(default="", repr=False)
    files: tuple = ()

    def to_json(self) -> dict:
        return {"masses": self.masses_text, "springs": self.springs_text, "condition": self.condition,
                "input_accuracy": self.input_accuracy, "error_bound": self.bound,
                "files": [str(p) for p in self.files]}

    def to_text(self) -> str:
        lines = [f"chain of {len(self.masses)} masses (wall - k1 - m1 - k2 - m2 - ... - kn - mn, free end)",
                 f"{'i':>4} {'mass':>26} {'spring k_i':>26}"]
        lines += [f"{i + 1:>4} {m:>26} {k:>26}" for i, (m, k) in enumerate(zip(self.masses_text, self.springs_text))]
        lines.append(f"condition estimate kappa = {self.condition:.3g} (max over parameters of the summed |d log p / "
                     f"d log omega^2|); inputs accurate to {self.input_accuracy:.2g} relative -> every mass and "
                     f"spring within {self.bound:.2g} relative of the chain the exact spectra define")
        lines += [f"wrote {p}" for p in self.files]
        return "\n".join(lines) + "\n"


def read_spectra(path: str | Path):
    """``(free, clamped or None, end components or None)`` as decimal texts from a spectra CSV (one line on error)."""
    from .numeric.errors import RunRefused
    from .numeric.updating.measured import NUMBER, read_text, rows_of

    file = str(path)
    accepted = ("a CSV file with the columns omega2_free (n values) and omega2_clamped (n - 1 values, the last "
                "cell empty) or end_component (n values); values are decimal numbers (quoted strings of any "
                "length are fine)")
    header, rows = rows_of(read_text(Path(path), file), file)
    if "omega2_free" not in header or ("omega2_clamped" in header) == ("end_component" in header) \
            or len(set(header)) != len(header) or len(header) != 2:
        raise RunRefused(f"{file}: header: {', '.join(header)!r}; accepted: {accepted}", "spectra")
    cols = {h: [] for h in header}
    for line, row in rows:
        if len(row) != 2:
            raise RunRefused(f"{file}: line {line}: {len(row)} cells for 2 columns; accepted: {accepted}", "spectra")
        for h, cell in zip(header, row):
            if cell == "":
                cols[h].append(None)
            elif NUMBER.match(cell):
                cols[h].append(cell)
            else:
                raise RunRefused(f"{file}: line {line}, column {h!r}: {cell[:40]!r} is not a decimal number; "
                                 f"accepted: {accepted}", "spectra")
    free = cols["omega2_free"]
    if not free or any(v is None for v in free):
        raise RunRefused(f"{file}: omega2_free: an empty cell (or no rows); accepted: {accepted}", "spectra")
    if "omega2_clamped" in cols:
        cl = cols["omega2_clamped"]
        if cl and cl[-1] is None:
            cl = cl[:-1]
        if any(v is None for v in cl):
            raise RunRefused(f"{file}: omega2_clamped: an empty cell before the last row; accepted: {accepted}",
                             "spectra")
        return free, cl, None
    end = cols["end_component"]
    if any(v is None for v in end):
        raise RunRefused(f"{file}: end_component: an empty cell; accepted: {accepted}", "spectra")
    return free, None, end


def chain_scene_text(name: str, masses, springs) -> str:
    """A ``[masses]`` scene of the fixed–free chain (parameters m1 … mn, k1 … kn)."""
    n = len(masses)
    lines = [f'name = "{name}"', f'description = "Fixed-free chain of {n} masses rebuilt from its spectra"',
             "", "[parameters]"]
    lines += [f"m{i + 1} = {float(m)!r}" for i, m in enumerate(masses)]
    lines += [f"k{i + 1} = {float(k)!r}" for i, k in enumerate(springs)]
    lines += ["", "[masses]"] + [f'x{i + 1} = "m{i + 1}"' for i in range(n)]
    for i in range(n):
        a = "wall" if i == 0 else f"x{i}"
        lines += ["", "[[springs]]", f'between = ["{a}", "x{i + 1}"]', f'k = "k{i + 1}"']
    return "\n".join(lines) + "\n"


def reconstruct(spectra: str | Path, total_mass: float | None = None, out: str | Path | None = DEFAULT_OUT,
                name: str = "reconstructed") -> Reconstruction:
    """Masses and springs of a fixed–free chain from its two spectra (Jacobi inverse eigenvalue problem).

    Parameters
    ----------
    spectra : str or Path
        CSV: ``omega2_free`` (n values) and ``omega2_clamped`` (n − 1: mass n clamped too), or
        ``omega2_free`` and ``end_component`` (the free-end components of the mass-normalised shapes).
        Values are decimal texts of any length (50 digits recover n ≤ 50 chains to 1e-12).
    total_mass : float
        Fixes the one scale two spectra leave free (optional with end components, which fix it).
    out : str or Path or None
        Folder of ``<name>.toml``; None writes nothing.
    name : str

    Returns
    -------
    Reconstruction

    Raises
    ------
    RunRefused
        Non-interlacing spectra, wrong counts, bad cells (one line).
    """
    import mpmath
    import numpy as np

    from .numeric.errors import RunRefused
    from .numeric.io.files import atomic_write_text
    from .numeric.updating.reconstruct import reconstruct as rebuild

    if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]{0,63}", str(name)):
        raise SceneError(None, "name", f"{show(name)}: accepted: a name of letters, digits and _")
    free, clamped, end = read_spectra(spectra)
    if clamped is not None and total_mass is None:
        raise RunRefused("reconstruct: two spectra fix the chain up to one scale; accepted: the total mass "
                         "(--total-mass)", "total_mass")
    if total_mass is not None and not (math.isfinite(total_mass) and total_mass > 0):
        raise RunRefused(f"reconstruct: total mass {total_mass!r}; accepted: a finite number > 0", "total_mass")
    chain = rebuild(free, clamped, total_mass, str(spectra), end)
    with mpmath.workdps(chain.dps):
        mt = [mpmath.nstr(x, 20) for x in chain.masses]
        kt = [mpmath.nstr(x, 20) for x in chain.springs]
    masses = np.array([float(x) for x in chain.masses])
    springs = np.array([float(x) for x in chain.springs])
    text = chain_scene_text(name, masses, springs)
    files = []
    if out is not None:
        path = Path(out) / f"{name}.toml"
        atomic_write_text(path, text)
        files.append(path)
    return Reconstruction(masses, springs, mt, kt, chain.condition, chain.bound, chain.input_accuracy, text,
                          tuple(files))


__all__ += ["reconstruct", "Reconstruction", "read_spectra", "chain_scene_text"]
