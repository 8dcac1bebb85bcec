"""Structural dynamics in the public API: Rayleigh damping from targets, response spectra of a record,
response-spectrum analysis (SRSS, CQC) and the storey outputs of a time history (drifts, spring
forces, base shear).

The numbers come from :mod:`springchain.numeric.structural.response_spectrum`, :mod:`springchain.numeric.structural.rsa`
and :mod:`springchain.derive.rayleigh_targets`; this module checks inputs, reads files and packages
results (text, JSON, figures). The command line (``springchain spectrum``, ``springchain rsa``)
only parses flags, calls these and prints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from ._modules import check_linear_outputs
from .derive.errors import SceneError
from .derive.scene import Scene

#: The SD convention as the text and the figure state it.
SD_NOTE = "SD = max |u| over the record and the free vibration after it"
#: Header columns of the two spectrum files ``rsa --spectrum`` takes.
RECORD_COLUMNS = ("t", "a")
DESIGN_COLUMNS = ("t", "sa")
_FORMS = "a record CSV with the header 't,a' (s, m/s^2) or a design spectrum CSV with the header 'T,Sa' (s, m/s^2)"


# -- files ------------------------------------------------------------------------------------------
def _header(path: Path, key: str) -> tuple[str, ...]:
    """The lower-cased header columns of a CSV file (first line that is not blank or a # comment)."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(4096)
    except OSError as exc:
        raise SceneError(str(path), key, f"cannot read the file ({exc.strerror or exc}); accepted: {_FORMS}") from None
    text = head.decode("utf-8", errors="replace").lstrip("\ufeff")
    for line in text.splitlines():
        line = line.strip()
        if line and not line.startswith("#"):
            return tuple(c.strip().lower() for c in line.split(","))
    return ()


def resolve_csv(path: str | Path) -> Path:
    """An existing CSV path, else a bundled data file of that name (``quake-record`` or
    ``quake-record.csv``: the scenes' folder); otherwise the path as given (reading it then fails
    with the one-line error)."""
    from ._scenes import bundled_scene_dir

    p = Path(path)
    if p.exists() or len(p.parts) > 1:
        return p
    for name in (p.name, p.name + ".csv"):
        candidate = bundled_scene_dir() / name
        if candidate.is_file() and candidate.suffix == ".csv":
            return candidate
    return p


def read_record(path: str | Path, key: str = "RECORD"):
    """An accelerogram CSV (header ``t,a``; seconds, m/s²) as a :class:`numeric.structural.response_spectrum.Record`.

    The rules of ``[ground]`` tables: rows of two finite numbers, times strictly increasing.

    Raises
    ------
    SceneError
        Naming the file, ``key``, the problem and the accepted form.
    """
    from .derive.loads import read_table
    from .numeric.structural.response_spectrum import Record

    p = resolve_csv(path).resolve()
    if not p.exists():  # not a scene's table: say what a RECORD may be (a path, or a bundled record)
        from ._scenes import bundled_scene_dir

        bundled = ", ".join(sorted(f.stem for f in bundled_scene_dir().glob("*.csv")))
        raise SceneError(str(path), key, f"{str(path)!r}: no such file, and not a bundled record; accepted: "
                                         f"a CSV file with a header line 't,a' (rows of two numbers, times "
                                         f"strictly increasing) or a bundled record ({bundled})")
    table = read_table(str(p), key, p.name, "a")
    return Record(table.t, table.y, p.stem)


def read_spectrum_file(path: str | Path, key: str = "--spectrum"):
    """``("record", Record)`` or ``("design", (periods, sa), name)`` by the file's header."""
    from .derive.loads import read_table

    p = resolve_csv(path).resolve()
    cols = _header(p, key)
    if cols == RECORD_COLUMNS:
        return "record", read_record(p, key), p.stem
    if cols == DESIGN_COLUMNS:
        table = read_table(str(p), key, p.name, "sa")
        if table.t[0] < 0 or (table.y < 0).any():
            raise SceneError(str(path), key, f"{p.name!r}: a negative period or Sa; accepted: {_FORMS}, T >= 0, Sa >= 0")
        return "design", (table.t, table.y), p.stem
    raise SceneError(str(path), key, f"{p.name!r}: header {','.join(cols)[:40]!r}; accepted: {_FORMS}")


def _as_record(record):
    from .numeric.structural.response_spectrum import Record

    if isinstance(record, Record):
        return record
    if isinstance(record, (str, Path)):
        return read_record(record)
    t, a = record
    return Record(t, a)


# -- Rayleigh from targets --------------------------------------------------------------------------
def _ratio(scene: Scene, z):
    """A target ratio as SymPy: a number (its decimal text, 0.05 -> 1/20) or an expression of the parameters."""
    import sympy as sp

    from .numeric.errors import RunRefused

    if isinstance(z, str):
        from ._api import parse_expression

        e = parse_expression(z, scene)
    elif isinstance(z, (int, float)) and not isinstance(z, bool) and math.isfinite(z):
        e = sp.Rational(repr(float(z)))
    else:
        raise RunRefused(f"zeta {z!r}: accepted: numbers 0 <= zeta < 1 or expressions of the parameters",
                         quantity="zeta")
    return e


def rayleigh_coefficients(scene, zeta=(0.05, 0.05), modes=(1, 2)):
    """α, β of Rayleigh damping C = αM + βK giving damping ratios ``zeta`` at elastic ``modes``.

    Parameters
    ----------
    scene : str, Path or Scene
        As for :func:`springchain.load` (a ``[masses]`` scene).
    zeta : (float or str, float or str)
        Target damping ratios ζ_a, ζ_b (numbers, or expressions of the scene's parameters).
    modes : (int, int)
        Two different elastic modes, counted from 1 in ascending ω (as ``springchain modes`` prints
        them; rigid-body modes are not counted).

    Returns
    -------
    springchain.derive.rayleigh_targets.RayleighFit
        ``.alpha``, ``.beta`` (values on the accurate route), ``.alpha_expr``, ``.beta_expr``
        (closed forms in the scene's parameters, or None), ``.zeta`` (the ratio every elastic
        mode gets), ``.to_json()``.
    """
    from ._api import modes as derive_modes
    from .derive.rayleigh_targets import fit
    from .numeric.errors import RunRefused

    m = derive_modes(scene)
    if m.chain:
        raise RunRefused("rayleigh_coefficients of a [chain] scene: not yet supported; accepted: a [masses] scene",
                         quantity="scene")
    if len(zeta) != 2 or len(modes) != 2:
        raise RunRefused(f"zeta {zeta!r}, modes {modes!r}: accepted: two ratios and two mode numbers",
                         quantity="zeta")
    ratios = tuple(_ratio(m.scene, z) for z in zeta)
    from .derive.accurate import exact_values, value

    subs = exact_values(m.model.params, m.scene.parameters)
    vals = [value(r, subs) for r in ratios]
    if not all(0 <= v < 1 for v in vals) or all(v == 0 for v in vals):
        raise RunRefused(f"zeta {list(zeta)!r}: accepted: damping ratios 0 <= zeta < 1, not both 0", quantity="zeta")
    n_el = m.scene.n - len(m.model.free_components)
    if (not all(isinstance(j, int) and not isinstance(j, bool) for j in modes) or modes[0] == modes[1]
            or not all(1 <= j <= n_el for j in modes)):
        raise RunRefused(f"modes {list(modes)!r}: accepted: two different elastic mode numbers 1 ... {n_el}",
                         quantity="modes")
    return fit(m.model, m.modes, ratios, tuple(modes))


# -- response spectra -------------------------------------------------------------------------------
@dataclass(frozen=True)
class SpectrumResult:
    """A record's response spectra (SD, PSV, PSA) with text, JSON and a figure.

    Attributes
    ----------
    spectrum : springchain.numeric.structural.response_spectrum.ResponseSpectrum
        ``.periods`` (P, ascending), ``.zeta`` (Z,), ``.sd``, ``.psv``, ``.psa`` (Z, P): SD the peak over
        the record and the free vibration after it; ``.sd_record`` (Z, P) the peak over the record
        alone; ``.notes`` (float64 limits met).
    seconds : float
    """

    spectrum: object = field(repr=False)
    seconds: float = 0.0

    def __getattr__(self, name):  # periods, zeta, sd, psv, psa, record
        return getattr(self.spectrum, name)

    def to_json(self) -> dict:
        return {**self.spectrum.to_json(), "seconds": self.seconds,
                "method": "exact one-step maps for piecewise-linear input (Nigam-Jennings), peak refined "
                          "between samples, row intervals of many periods in closed form, free vibration "
                          "after the record (its first extremum) in closed form"}

    def to_text(self, rows: int = 12) -> str:
        s = self.spectrum
        r = s.record
        out = [f"response spectrum of {r.name!r}: {r.t.shape[0]} rows, t = {r.t[0]:g} ... {r.t[-1]:g} s, "
               f"PGA = {r.pga:.4g} m/s^2; {s.periods.shape[0]} periods x {s.zeta.shape[0]} damping ratios "
               f"in {self.seconds:.3f} s",
               f"{SD_NOTE}; periods ascending",
               f"{'T [s]':>10}" + "".join(f"{'SD [m]':>14}{'PSV [m/s]':>12}{'PSA [m/s2]':>12}  " for _ in s.zeta)]
        out.append(" " * 10 + "".join(f"{'zeta = ' + format(z, 'g'):>38}  " for z in s.zeta))
        import numpy as np

        pick = np.unique(np.linspace(0, s.periods.shape[0] - 1, min(rows, s.periods.shape[0])).round().astype(int))
        for j in pick:
            out.append(f"{s.periods[j]:>10.4g}" + "".join(
                f"{s.sd[z, j]:>14.5e}{s.psv[z, j]:>12.4g}{s.psa[z, j]:>12.4g}  " for z in range(s.zeta.shape[0])))
        for z, zz in enumerate(s.zeta):
            k = int(np.argmax(s.psa[z]))
            out.append(f"peak PSA at zeta = {zz:g}: {s.psa[z, k]:.4g} m/s^2 at T = {s.periods[k]:.4g} s")
        out.extend(f"note: {n}" for n in s.notes)
        return "\n".join(out) + "\n"

    def plot(self):
        from .numeric.plots import structural as structural_plots

        s = self.spectrum
        return structural_plots.response_spectrum(s.periods, s.zeta, s.sd, s.psv, s.psa,
                                                  f"Response spectra of {s.record.name!r}", s.record.pga,
                                                  note=SD_NOTE)

    def save(self, out: str | Path) -> list[Path]:
        """Write ``<record>-spectrum.png`` and ``<record>-spectrum.json`` into ``out``."""
        import json

        from .numeric.io.files import atomic_path
        from .numeric.plots.figures import save

        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        name = self.spectrum.record.name
        png, js = out / f"{name}-spectrum.png", out / f"{name}-spectrum.json"
        save(self.plot(), png)
        with atomic_path(js) as tmp:
            Path(tmp).write_text(json.dumps(self.to_json()), encoding="utf-8")
        return [png, js]


def parse_periods(text: str):
    """``A:B:N`` (N log-spaced periods from A to B) or a comma list of periods, as an array."""
    import numpy as np

    from .numeric.errors import RunRefused

    form = "A:B:N (N log-spaced periods from A to B s) or a comma list, e.g. 0.1,0.5,1"
    try:
        if ":" in text:
            a, b, n = text.split(":")
            a, b, n = float(a), float(b), int(n)
            if not (0 < a < b and math.isfinite(b) and 2 <= n <= 100_000):
                raise ValueError
            return np.geomspace(a, b, n)
        out = np.array([float(x) for x in text.split(",")])
    except ValueError:
        raise RunRefused(f"periods {text!r}: accepted: {form}", quantity="periods") from None
    if not (out.size and np.all(np.isfinite(out) & (out > 0))):
        raise RunRefused(f"periods {text!r}: accepted: {form}, every period > 0", quantity="periods")
    return out


def response_spectrum(record, zeta=0.05, periods=None) -> SpectrumResult:
    """SD, PSV and PSA of an accelerogram, exact for piecewise-linear input.

    Parameters
    ----------
    record : str, Path, Record or (t, a)
        A CSV file with the header ``t,a`` (seconds, m/s²; the ``[ground]`` table format) or the
        name of a bundled record (``"quake-record"``), a
        :class:`~springchain.numeric.structural.response_spectrum.Record`, or two arrays.
    zeta, periods
        Damping ratios and natural periods [s], as
        :func:`springchain.numeric.structural.response_spectrum.response_spectrum` takes them (default: ζ = 0.05
        at 100 periods log-spaced from 0.02 to 10 s; periods 1e-150 ... 1e150 s, listed ascending
        in the result).

    Returns
    -------
    SpectrumResult
    """
    import time

    from .numeric.structural.response_spectrum import response_spectrum as compute

    rec = _as_record(record)
    t0 = time.perf_counter()
    spec = compute(rec, zeta=zeta, periods=periods)
    return SpectrumResult(spec, time.perf_counter() - t0)


# -- response-spectrum analysis ---------------------------------------------------------------------
def spring_labels(scene: Scene, ends) -> list[str]:
    """``a-b`` per spring (mass names, ``wall``; chain indices)."""
    names = scene.mass_names or tuple(str(i) for i in range(scene.n))
    return [f"{'wall' if a < 0 else names[a]}-{'wall' if b < 0 else names[b]}" for a, b in ends]


@dataclass(frozen=True)
class RSA:
    """A response-spectrum analysis of a scene.

    Attributes
    ----------
    scene : Scene
    result : springchain.numeric.structural.rsa.RSAResult
        Peak modal responses (``.displacement`` (J, N), ``.drift``, ``.spring_force`` (J, S),
        ``.base_shear`` (J,)) and ``.combined(Combination)``.
    combination : str
        ``"cqc"`` or ``"srss"``: the one :meth:`to_text` leads with.
    kind : str
        ``"record"`` or ``"design"``.
    notes : list of str
    """

    scene: Scene
    result: object = field(repr=False)
    combination: str = "cqc"
    kind: str = "record"
    labels: tuple = ()
    notes: tuple = ()

    def combined(self, how: str | None = None) -> dict:
        """``displacement`` (N,), ``drift`` (S,), ``spring_force`` (S,), ``base_shear`` by SRSS or CQC."""
        from .numeric.structural.rsa import Combination

        return self.result.combined(Combination(how or self.combination))

    def to_json(self) -> dict:
        return {"scene": self.scene.name, "spectrum_kind": self.kind, "combination": self.combination,
                "masses": list(self.scene.mass_names), "springs": list(self.labels),
                **self.result.to_json(), "result": {k: (v.tolist() if hasattr(v, "tolist") else v)
                                                    for k, v in self.combined().items()},
                "notes": list(self.notes)}

    def to_text(self) -> str:
        r, m = self.result, self.result.modes
        out = [f"response-spectrum analysis of {self.scene.name!r} with {r.spectrum!r} "
               f"({'a record: exact SD at each mode, ' + SD_NOTE if self.kind == 'record' else 'a design spectrum: SD = Sa/omega^2'})",
               f"{'mode':>4} {'T [s]':>10} {'zeta':>8} {'Gamma':>12} {'M*/M':>8} {'SD [m]':>12} {'PSA [m/s2]':>11} "
               f"{'base shear [N]':>15}"]
        for j in range(m.omega.shape[0]):
            out.append(f"{j + 1:>4} {m.periods[j]:>10.4g} {m.zeta[j]:>8.4f} {m.gamma[j]:>12.6g} "
                       f"{m.effective_mass[j] / m.total_mass:>8.4f} {r.sd[j]:>12.5e} {r.psa[j]:>11.4g} "
                       f"{r.base_shear[j]:>15.6g}")
        srss, cqc = self.combined("srss"), self.combined("cqc")
        names = self.scene.mass_names or tuple(str(i) for i in range(self.scene.n))
        lead = "CQC" if self.combination == "cqc" else "SRSS"
        out.append(f"combined peaks ({lead} is the result; the other beside it):")
        out.append(f"    {'floor':<16}{'SRSS x [m]':>14}{'CQC x [m]':>14}")
        for i, nm in enumerate(names[:40]):
            out.append(f"    {nm:<16}{srss['displacement'][i]:>14.5e}{cqc['displacement'][i]:>14.5e}")
        out.append(f"    {'spring':<16}{'SRSS drift [m]':>16}{'CQC drift [m]':>16}{'SRSS force [N]':>16}{'CQC force [N]':>16}")
        for s, lab in enumerate(self.labels[:40]):
            out.append(f"    {lab:<16}{srss['drift'][s]:>16.5e}{cqc['drift'][s]:>16.5e}"
                       f"{srss['spring_force'][s]:>16.6g}{cqc['spring_force'][s]:>16.6g}")
        out.append(f"    base shear: SRSS {srss['base_shear']:.6g} N, CQC {cqc['base_shear']:.6g} N")
        out += [f"note: {n}" for n in self.notes]
        return "\n".join(out) + "\n"


def rsa(scene, spectrum, combine: str = "cqc") -> RSA:
    """Response-spectrum analysis: peak modal responses, combined by SRSS and CQC.

    Parameters
    ----------
    scene : str, Path or Scene
        As for :func:`springchain.load`; every piece tied to a wall.
    spectrum : str, Path, Record or (periods, sa)
        A record (CSV ``t,a`` or a Record: its exact spectrum at each mode's period and damping
        ratio) or a design spectrum (CSV ``T,Sa`` in m/s², or two arrays, linear between rows).
    combine : {"cqc", "srss"}
        The combination :meth:`RSA.to_text` leads with (both are computed).

    Returns
    -------
    RSA
    """
    import numpy as np

    from ._modules import system_of as _system
    from ._scenes import load
    from .numeric.errors import RunRefused
    from .numeric.structural.response_spectrum import PERIOD_RANGE, Record, design_spectrum_sa, spectral_displacement
    from .numeric.structural.rsa import Combination, ModalProperties, analyse

    if combine not in {c.value for c in Combination}:
        raise RunRefused(f"combine {combine!r}: accepted: 'srss' or 'cqc'", quantity="combine")
    sc = load(scene)
    check_linear_outputs(sc)  # a cubic [chain] under a constant load: one line
    system, _ = _system(sc)
    modes = ModalProperties.from_system(system)
    notes = []
    if not modes.proportional:
        notes.append("damping is not proportional: each mode's zeta is the diagonal of Phi^T C Phi (an approximation)")
    if modes.exact is None:
        from .numeric.structural.modal_quantities import MP_MAX_MASSES

        why = (f"more than {MP_MAX_MASSES} masses" if system.n > MP_MAX_MASSES
               else "repeated frequencies: the per-mode split is not unique")
        notes.append(f"Gamma, drifts and spring forces from float64 shapes ({why}): each mode's values are good to "
                     "float64 of the largest mode's, not certified per mode at high stiffness contrast (the storey "
                     "shears of a chain hung from one wall come from inertia sums, free of that cancellation)")
    if system.potential and not system.linear:
        notes.append(linearisation_note(system.potential_equilibrium()))
    elif not system.linear:
        notes.append("cubic springs: the analysis uses the linear springs (the linearization about x = 0)")
    if isinstance(spectrum, (str, Path)):
        read = read_spectrum_file(spectrum)
        kind, data, name = read[0], read[1], read[2]
    elif isinstance(spectrum, Record):
        kind, data, name = "record", spectrum, spectrum.name
    else:
        kind, data, name = "design", tuple(np.asarray(a, dtype=float) for a in spectrum), "design spectrum"
    if kind == "record":
        if np.any(modes.zeta >= 1):
            raise RunRefused("a mode is critically damped or more (zeta >= 1): no response spectrum ordinate; "
                             "accepted: every mode underdamped", quantity="scene")
        lo, hi = PERIOD_RANGE
        out = np.flatnonzero(~((modes.periods >= lo) & (modes.periods <= hi)))
        if out.size:
            j = int(out[0])
            raise RunRefused(f"spectrum {name!r}: mode {j + 1} has T = {modes.periods[j]:.6g} s; accepted: a record's "
                             f"spectrum at periods {lo:g} ... {hi:g} s (float64's range for the record's times)",
                             quantity="spectrum")
        sd, _, sd_notes = spectral_displacement(data, modes.periods, np.maximum(modes.zeta, 0.0), with_record=True)
        notes.extend(sd_notes)
    else:
        T, Sa = data
        sa = design_spectrum_sa(T, Sa, modes.periods)
        bad = np.flatnonzero(np.isnan(sa))
        if bad.size:
            j = int(bad[0])
            raise RunRefused(f"spectrum {name!r}: mode {j + 1} has T = {modes.periods[j]:.6g} s outside the design "
                             f"spectrum's periods {T[0]:g} ... {T[-1]:g} s; accepted: a table covering every mode's "
                             "period (add a row at T = 0 with Sa = PGA for short periods)", quantity="spectrum")
        sd = sa / modes.omega**2
    result = analyse(system, sd, modes, name)
    return RSA(sc, result, combine, kind, tuple(spring_labels(sc, system.spring_ends)), tuple(notes))


# -- time-history outputs -------------------------------------------------------------------------
def linearisation_note(x_eq) -> str:
    """The note of an analysis of a scene with spring potentials: about its static equilibrium x_eq (N,)."""
    shown = ", ".join(f"{v:.10g}" for v in x_eq[:6]) + (f", ... ({len(x_eq)} masses)" if len(x_eq) > 6 else "")
    where = "x_eq = 0 (every spring at rest)" if not any(x_eq) else f"x_eq = ({shown})"
    return (f"spring potentials: the analysis uses the linearisation about the static equilibrium {where}: K is the "
            "Hessian of V there (each spring's stiffness V''(d) at x_eq); the peaks are of the motion about x_eq")


def spring_series(scene: Scene, x):
    """Drifts, spring forces and base shear of a trajectory ``x`` (S, N) of ``scene``
    (:func:`numeric.structural.storeys.spring_series`)."""
    from ._modules import system_of
    from .numeric.structural.storeys import spring_series as series

    return series(system_of(scene)[0], x)


__all__ = ["rayleigh_coefficients", "response_spectrum", "SpectrumResult", "rsa", "RSA", "read_record",
           "read_spectrum_file", "parse_periods", "spring_series", "spring_labels"]
