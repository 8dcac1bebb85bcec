"""Every output of springchain on one scene, against the oracle (:mod:`oracle.reference`).

:func:`check_scene` writes a generated scene to a folder, loads it through the public API, runs ``modes``,
``frf``, ``simulate(springs=True)``, ``rsa`` (and the command line when asked) and compares each number with
the oracle within the output's stated tolerance. What it finds is a list of :class:`Finding`: a traceback, a
leaked warning, a refusal that is not one line (or refuses what the oracle computes), or a number off by
more than its tolerance. Each finding is classified by :func:`classify` as one of issue 31's listed
findings (being fixed) or as new. Worst errors per output are kept in :data:`STATS` for the report.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import subprocess
import sys
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from mpmath import mp

from . import reference as R

#: Tolerances (relative, unless said) per output: the README's stated guarantee, with a margin of its own.
TOL = {
    "modes.omega2": 1e-13,  # README: <= 1e-16 printed
    "modes.shape": 1e-11,  # sin(angle) * min(relative gap, 1); README: 5.6e-17 printed
    "modes.zeta": 1e-10,  # README: <= 1e-13, absolute floor ZETA_FLOOR = 1e-72
    "modes.complex": 1e-10,
    "modes.gamma": 1e-11,  # settled to float64
    "modes.equilibrium": 1e-11,  # mpmath refinement to 1e-18
    "frf.H": 1e-9,  # README: <= 1e-10 relative (complex)
    "frf.peak": 1e-9,
    "simulate.x": 1e-9,  # README: <= 1e-9 of the amplitude (or a note naming the float64 limit)
    "simulate.aabs": 1e-8,  # derived from x and v: the forces over the masses
    "simulate.springs": 1e-8,  # of each series' own size
    "simulate.spring_eval": 1e-12,  # the tension of a given trajectory (no solve involved)
    "spectrum.sd": 1e-9,  # "exact" for piecewise-linear input (tested 2.8e-13)
    "rsa": 1e-9,  # README: random wall chains to 1e-10
}

#: Worst error seen per output (and how many comparisons), for the report.
STATS: dict = {}


def note_error(output: str, err: float) -> None:
    """Keep the worst error of the comparisons that passed (failures are findings, reported apart)."""
    if float(err) > TOL.get(output, math.inf):
        return
    worst, count = STATS.get(output, (0.0, 0))
    STATS[output] = (max(worst, float(err)), count + 1)


@dataclass
class Finding:
    output: str
    detail: str
    known: str | None = None

    def __str__(self):
        return f"[{self.known or 'NEW, unlisted'}] {self.output}: {self.detail}"


@dataclass
class Report:
    findings: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    refusals: list = field(default_factory=list)

    def add(self, output: str, detail: str, features=frozenset()) -> None:
        f = Finding(output, detail)
        f.known = classify(f, features)
        if output in ("modes.shape", "modes.gamma", "modes.zeta", "modes.complex") and "[chain]" not in detail:
            # wrong shapes, participation and damping follow from wrong frequencies: the same finding
            first = next((g.known for g in self.findings if g.output == "modes.omega2"), None)
            f.known = first or f.known
        if output == "frf" and "warning leaked" in detail:  # warnings on the way to the frf's traceback
            first = next((g.known for g in self.findings if g.output == "frf" and "traceback" in g.detail), None)
            f.known = first or f.known
        self.findings.append(f)

    @property
    def new(self) -> list:
        return [f for f in self.findings if f.known is None]


# -- calling the product ----------------------------------------------------------------------------------
class Refused(Exception):
    def __init__(self, message: str):
        super().__init__(message)
        self.message = message


def _api():
    import springchain as sc

    return sc


#: Seconds one product call may take before it counts as a hang (the longest seen in normal use: ~15 s).
HANG_SECONDS = float(os.environ.get("ORACLE_HANG_SECONDS", "90"))


class _Hang(BaseException):
    """Raised by the alarm inside a product call that ran past :data:`HANG_SECONDS`."""


def _alarm(signum, frame):
    raise _Hang()


@contextlib.contextmanager
def _watchdog(seconds: float):
    """SIGALRM after ``seconds`` (main thread only; elsewhere no watchdog). The tests using it take pytest-timeout's
    thread method, whose own timer does not use the signal."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "setitimer"):
        yield
        return
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


@contextlib.contextmanager
def product(report: Report, output: str, features=frozenset()):
    """Run a product call: a SceneError/RunRefused becomes :class:`Refused` (checked to be one line); any
    other exception, a leaked warning or a call past :data:`HANG_SECONDS` becomes a finding."""
    sc = _api()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with _watchdog(HANG_SECONDS):
                yield
        except _Hang:
            report.add(output, f"a hang: no answer in {HANG_SECONDS:g} s", features)
            raise Refused("traceback hang") from None
        except (sc.SceneError, sc.RunRefused) as exc:
            msg = str(exc)
            if "\n" in msg.strip() or not msg.strip():
                report.add(output, f"refusal is not one line: {msg!r}", features)
            report.refusals.append(f"{output}: {msg}")
            raise Refused(msg) from None
        except Refused:
            raise
        except Exception as exc:  # noqa: BLE001 - a traceback is what we look for
            report.add(output, f"traceback {type(exc).__name__}: {str(exc)[:300]}", features)
            raise Refused(f"traceback {type(exc).__name__}") from None
        finally:
            for w in caught:
                if issubclass(w.category, (RuntimeWarning, UserWarning)) and "springchain" not in str(w.filename) \
                        or issubclass(w.category, RuntimeWarning):
                    report.add(output, f"warning leaked: {w.category.__name__}: {str(w.message)[:200]}", features)


def _rel(p, o, floor=0.0) -> float:
    """|p - o| / max(|o|, floor) for a product number p and an oracle mpf/mpc o."""
    if p is None or (isinstance(p, float) and not math.isfinite(p)):
        return math.inf
    d = abs(mp.mpmathify(p) - o)
    s = max(abs(o), mp.mpf(floor))
    if s == 0:
        return 0.0 if d == 0 else math.inf
    return float(d / s)


# -- the scene -------------------------------------------------------------------------------------------
def check_scene(gen, folder: Path, *, frf_pair=None, record=None, cli: bool = False, outputs=None) -> Report:
    """Every output of ``gen`` (a :class:`oracle.scenes.GeneratedScene`) against the oracle.

    ``frf_pair``: (input, output) mass indices; ``record``: a :class:`oracle.scenes.GeneratedRecord` for
    rsa; ``outputs``: a subset of {"modes", "frf", "simulate", "rsa", "cli"} (default all that apply).
    """
    with mp.workdps(50):
        return _check_scene(gen, folder, frf_pair, record, cli, outputs)


def _check_scene(gen, folder, frf_pair, record, cli, outputs) -> Report:
    sc = _api()
    rep = Report()
    feats = gen.features
    outputs = set(outputs or ("modes", "frf", "simulate", "rsa")) | ({"cli"} if cli else set())
    path = gen.write(folder)
    try:
        md = R.read(gen.text, gen.tables)
    except R.Rejected as exc:
        md, rejected = None, str(exc)
    else:
        rejected = None
    try:
        with product(rep, "load", feats):
            scene = sc.load(path)
    except Refused as exc:
        if rejected is None and not exc.message.startswith("traceback"):
            if not _documented_refusal(exc.message):
                rep.add("load", f"refused a scene the oracle reads: {exc.message}", feats)
        if "cli" in outputs:
            check_cli(rep, path, feats, md)
        return rep
    if rejected is not None:
        rep.add("load", f"accepted a scene the README refuses ({rejected})", feats)
        return rep
    # the static equilibrium and the modes about it
    eq, eq_error = None, None
    if R.needs_equilibrium(md) and not md.linear:
        try:
            eq = R.static_equilibrium(md)
            if not eq.stable:
                eq_error = "unstable"
        except R.NoEquilibrium as exc:
            eq_error = str(exc)
        except R.OracleError as exc:
            rep.skipped.append(f"equilibrium: {type(exc).__name__}: {exc}")
            return rep
    stages = [("modes", lambda: _check_modes(rep, sc, scene, md, eq, eq_error, feats)),
              ("frf", lambda: frf_pair is not None and eq_error is None
               and _check_frf(rep, sc, scene, md, eq, frf_pair, feats)),
              ("simulate", lambda: _check_simulate(rep, sc, scene, md, eq, eq_error, feats, folder)),
              ("rsa", lambda: record is not None and eq_error is None
               and _check_rsa(rep, sc, scene, md, eq, record, feats, folder))]
    for name, stage in stages:
        if name not in outputs:
            continue
        try:
            stage()
        except R.OracleError as exc:  # what the oracle cannot compute is skipped and listed, never failed
            rep.skipped.append(f"{name}: oracle: {type(exc).__name__}: {exc}")
    if "cli" in outputs:
        check_cli(rep, path, feats, md)
    return rep


#: Refusals the README documents as limits of the product (a one-line refusal is the right answer there).
DOCUMENTED = (
    r"a cubic \(k3\) spring in a scene whose equilibrium is away from x = 0",
    r"pre-stressed chain with a free end|constant load on a potential chain|tension structure",
    r"constant load on a chain with a potential .* not supported yet",
    r"constant load on a chain with cubic \(k3\) springs .* not supported yet",  # scene reference: chain.k3
    r"not yet supported",
    r"would start at rest.* with nothing driving it",
    r"is not finite at the rest configuration",
    r"no static equilibrium found",
    r"accelerates, so there is no static equilibrium",
    r"not positive \(this spring is not stable there\)|is not positive for the spring",
    r"would be unstable|stability limit|omega_max\*dt|ω_max",
    r"free piece|rigid",
    r"past the symbolic work cap|work cap",
    r"at most \d+ masses|more than \d+ masses",
    r"critically damped",
    r"targets that need|alpha < 0|beta < 0|gives (alpha|beta) = \S+ < 0|elastic modes|two modes of equal",
    r"float64",
    r"no elastic mode",
    # not in the README (a documentation gap, reported): the chain frf's dynamic stiffness takes neighbours only
    r"dashpots couple masses further apart than neighbours",
)


def _documented_refusal(msg: str) -> bool:
    return any(re.search(p, msg) for p in DOCUMENTED)


# -- modes -----------------------------------------------------------------------------------------------
def _check_modes(rep, sc, scene, md, eq, eq_error, feats):
    try:
        with product(rep, "modes", feats):
            m = sc.modes(scene)
            js = m.to_json()
    except Refused as exc:
        if exc.message.startswith("traceback"):
            return
        if eq_error is not None and re.search(r"equilibrium|accelerates|not positive|not stable", exc.message):
            return  # the oracle agrees: no stable equilibrium on the branch from rest
        if not _documented_refusal(exc.message) or (eq is not None and "no static equilibrium found" in exc.message):
            rep.add("modes", f"refused, but the oracle has an answer: {exc.message}", feats)
        return
    if eq_error is not None:
        rep.add("modes.equilibrium", f"printed modes, but the oracle finds no stable equilibrium ({eq_error})", feats)
        return
    ms = R.modes(md, eq)
    n = md.n
    # the equilibrium
    if eq is not None and not eq.closed_form_zero and md.has_potential:
        je = js.get("equilibrium")
        if je is None:
            rep.add("modes.equilibrium", "modes --json has no 'equilibrium' although the scene has one "
                                         f"(x_eq = {[float(v) for v in eq.x]})", feats)
        elif "springs" in je:  # [masses] scenes: each spring's extension and stiffness ([chain]: the law's)
            scale = max(abs(v) for v in eq.extensions) if eq.extensions else 1
            for j, (s, d, k) in enumerate(zip(je["springs"], eq.extensions, eq.stiffness)):
                e1 = _rel(s.get("extension_value"), d, floor=scale * 1e-3)
                e2 = _rel(s.get("stiffness_value"), k)
                note_error("modes.equilibrium", max(e1, e2))
                if max(e1, e2) > TOL["modes.equilibrium"]:
                    rep.add("modes.equilibrium", f"spring {j}: extension {s.get('extension_value')!r} (oracle "
                                                 f"{mp.nstr(d, 17)}), stiffness {s.get('stiffness_value')!r} "
                                                 f"(oracle {mp.nstr(k, 17)})", feats)
    recs = js.get("modes", [])
    listed = [r["omega2_value"] for r in recs]
    if md.chain is not None and n > 40:
        rep.skipped.append("modes: long chain (10 lowest, 10 highest listed)")
        return
    if len(listed) != n:
        rep.add("modes.omega2", f"{len(listed)} modes listed for {n} masses", feats)
        return
    top = max(ms.omega2) if ms.omega2 else 0
    worst, bad = 0.0, []
    for j, (p, o) in enumerate(zip(listed, ms.omega2)):
        err = _rel(p, o) if o != 0 else (float(abs(p) / top) if top else abs(p))
        worst = max(worst, err)
        if err > TOL["modes.omega2"]:
            bad.append(f"mode {j}: {p!r} (oracle {mp.nstr(o, 17)})")
    note_error("modes.omega2", worst)
    if bad:
        rep.add("modes.omega2", "; ".join(bad[:4]), feats)
    _check_shapes(rep, md, ms, recs, feats)
    if md.damped:
        _check_damping(rep, md, ms, eq, js, recs, feats)
    _check_participation(rep, md, ms, js, recs, m, feats)


def _clusters(omega2, rel=1e-8):
    """Index groups of (nearly) equal ω²."""
    groups, cur = [], [0]
    for j in range(1, len(omega2)):
        a, b = omega2[cur[-1]], omega2[j]
        if abs(b - a) <= rel * max(abs(a), abs(b), mp.mpf(10) ** -300):
            cur.append(j)
        else:
            groups.append(cur)
            cur = [j]
    groups.append(cur)
    return groups if omega2 else []


def _check_shapes(rep, md, ms, recs, feats):
    n = md.n
    if not recs or recs[0].get("shape_value") is None:
        if md.chain is not None and n <= 40 and recs:
            rep.add("modes.shape", f"a [chain] of {n} masses lists no shape_value (README: listed for chains of at "
                                   "most 40 masses)", feats)
        return
    sq = [mp.sqrt(v) for v in md.m]
    worst = 0.0
    for group in _clusters(ms.omega2):
        lo, hi = ms.omega2[group[0]], ms.omega2[group[-1]]
        gaps = []
        if group[0] > 0:
            gaps.append((lo - ms.omega2[group[0] - 1]) / max(lo, mp.mpf(10) ** -300))
        if group[-1] + 1 < n:
            gaps.append((ms.omega2[group[-1] + 1] - hi) / ms.omega2[group[-1] + 1])
        gap = min([mp.mpf(1)] + gaps)
        for j in group:
            sv = recs[j].get("shape_value")
            if sv is None:
                continue
            y = [mp.mpf(float(v)) * sq[i] for i, v in enumerate(sv)]
            norm = mp.sqrt(mp.fsum(v * v for v in y))
            if norm == 0:
                rep.add("modes.shape", f"mode {j}: a zero shape", feats)
                continue
            coef = {c: mp.fsum(ms.Phi[i, c] * y[i] for i in range(n)) for c in group}
            resid = [y[i] - mp.fsum(coef[c] * ms.Phi[i, c] for c in group) for i in range(n)]
            sin = float(mp.sqrt(mp.fsum(v * v for v in resid)) / norm)
            err = sin * float(gap)
            worst = max(worst, err)
            if err > TOL["modes.shape"]:
                rep.add("modes.shape", f"mode {j}: sin(angle to the oracle's eigenspace) = {sin:.3g} (gap "
                                       f"{float(gap):.3g})", feats)
    note_error("modes.shape", worst)


def _check_damping(rep, md, ms, eq, js, recs, feats):
    dm = R.damped(md, eq)
    proportional = js.get("damping", {}).get("proportional")
    if proportional is not None and ((proportional and not (dm.proportional or dm.nearly_proportional))
                                     or (not proportional and dm.proportional)):
        rep.add("modes.zeta", f"damping said proportional = {proportional}, oracle {dm.proportional}", feats)
    if dm.proportional or (proportional and dm.nearly_proportional):
        worst = 0.0
        order = list(range(len(recs)))
        for g in _clusters(ms.omega2):  # inside a repeated ω the ratios pair up in sorted order
            got = sorted(g, key=lambda j: recs[j].get("damping_ratio") if recs[j].get("damping_ratio") is not None
                         else -1.0)
            ref = sorted(g, key=lambda j: dm.zeta_diag[j])
            for a, b in zip(got, ref):
                order[a] = b
        for j, r in enumerate(recs):
            p, o = r.get("damping_ratio"), dm.zeta_diag[order[j]]
            if ms.omega2[j] == 0:
                continue
            if p is None:
                rep.add("modes.zeta", f"mode {j}: zeta not given (oracle {mp.nstr(o, 10)})", feats)
                continue
            err = _rel(p, o, floor=1e-72 / TOL["modes.zeta"])
            wd = r.get("omega_damped")
            if wd is not None and o < 1:
                err = max(err, _rel(wd, mp.sqrt(ms.omega2[j]) * mp.sqrt(1 - o * o)))
            worst = max(worst, err)
            if err > TOL["modes.zeta"]:
                owd = mp.nstr(mp.sqrt(ms.omega2[j]) * mp.sqrt(1 - o * o), 17) if o < 1 else "0 (overdamped)"
                rep.add("modes.zeta", f"mode {j}: zeta {p!r}, omega_d {wd!r} (oracle {mp.nstr(o, 17)}, {owd})", feats)
        note_error("modes.zeta", worst)
        return
    cm = js.get("complex_modes")
    if cm is None and md.chain is not None:  # a chain lists ζ, ω_d beside each mode: one of the state's pairs
        cm = []
        for r in recs:
            z, wd = r.get("damping_ratio"), r.get("omega_damped")
            if z is not None and wd and z < 1:
                wn = wd / math.sqrt(1 - z * z)
                cm.append({"eigenvalue": [-z * wn, wd], "damping_ratio": z})
    if cm is None:
        rep.add("modes.complex", "non-proportional damping but no complex_modes", feats)
        return
    oracle = [lam for lam in dm.eigenvalues if mp.im(lam) > mp.mpf(10) ** -30 * abs(lam)]
    worst = 0.0
    cm = [c for c in cm if c.get("eigenvalue") is not None]  # rigid modes: "no restoring force"
    for c in cm:
        re_, im_ = c["eigenvalue"]
        lam = mp.mpc(re_, im_)
        best = min(oracle, key=lambda o: abs(o - lam)) if oracle else None
        if best is None:
            rep.add("modes.complex", f"eigenvalue {re_!r} + {im_!r}i: the oracle has no complex mode", feats)
            continue
        err = float(abs(best - lam) / abs(best))
        zeta_err = _rel(c.get("damping_ratio"), -mp.re(best) / abs(best), floor=1e-72 / TOL["modes.zeta"])
        worst = max(worst, err, zeta_err)
        if err > TOL["modes.complex"] or zeta_err > TOL["modes.zeta"]:
            rep.add("modes.complex", f"eigenvalue {re_!r} {im_!r}i, zeta {c.get('damping_ratio')!r} (oracle "
                                     f"{mp.nstr(best, 17)}, zeta {mp.nstr(-mp.re(best) / abs(best), 17)})", feats)
    if len(cm) != len(oracle) and md.chain is None:
        rep.add("modes.complex", f"{len(cm)} complex modes listed, oracle has {len(oracle)} "
                                 f"(eigenvalues {[mp.nstr(v, 8) for v in dm.eigenvalues]})", feats)
    note_error("modes.complex", worst)


def _check_participation(rep, md, ms, js, recs, m, feats):
    if md.chain is not None:  # README: open chains with a wall end or [ground]
        applies = "wall" in (md.chain["left"], md.chain["right"]) or md.ground is not None
    else:
        applies = md.has_wall() or md.ground is not None
    part = js.get("participation")
    if not applies:
        if part is not None:
            rep.add("modes.gamma", "participation listed for a scene whose supports cannot move", feats)
        return
    if part is None:
        if md.chain is None or (md.chain["left"] != "ring" and md.n <= 40):
            rep.add("modes.gamma", "no participation for a scene with a wall or [ground]", feats)
        return
    gam = R.participation(md, ms)
    floor = float(mp.sqrt(md.total_mass)) * 1e-13
    worst = 0.0
    for group in _clusters(ms.omega2):
        pg = [recs[j].get("participation_factor") for j in group]
        if any(v is None for v in pg):
            rep.add("modes.gamma", f"modes {group}: participation factor missing", feats)
            continue
        o_m = mp.fsum(gam[j] ** 2 for j in group)
        p_m = sum(float(v) ** 2 for v in pg)
        err = _rel(p_m, o_m, floor=floor**2 / TOL["modes.gamma"])
        if len(group) == 1:
            j = group[0]
            sv = recs[j].get("shape_value") or recs[j].get("shape_mass_normalised")
            sign = 1
            if sv is not None:
                dot = mp.fsum(mp.mpf(float(sv[i])) * mp.sqrt(md.m[i]) * ms.Phi[i, j] for i in range(md.n))
                sign = 1 if dot >= 0 else -1
            err = max(err, _rel(pg[0], sign * gam[j], floor=floor / TOL["modes.gamma"]))
            mn = recs[j].get("shape_mass_normalised")
            if mn is not None:  # phi^T M phi = 1: compare M^1/2 phi with the oracle's unit vector
                dev = mp.sqrt(mp.fsum((mp.mpf(float(mn[i])) * mp.sqrt(md.m[i]) - sign * ms.Phi[i, j]) ** 2
                                      for i in range(md.n)))
                err = max(err, float(dev))
            em = recs[j].get("effective_mass")
            err = max(err, _rel(em, gam[j] ** 2, floor=floor**2 / TOL["modes.gamma"]))
        worst = max(worst, err)
        if err > TOL["modes.gamma"]:
            rep.add("modes.gamma", f"modes {group}: Gamma {pg} M* {[recs[j].get('effective_mass') for j in group]} "
                                   f"(oracle Gamma {[mp.nstr(gam[j], 17) for j in group]})", feats)
    note_error("modes.gamma", worst)


# -- frequency response -------------------------------------------------------------------------------
def _stated_sensitivity(notes) -> float:
    """The relative change of |H| under a last-bit change of every element that the frf's notes state
    (the scene's own conditioning: the product's values are those of the elements as float64 rounds
    them; the oracle evaluates the expressions exactly), or 0."""
    for note in notes:
        hit = re.match(r"\|H\| at some frequencies moves by up to (\S+) relative", note)
        if hit:
            return float(hit.group(1))
    return 0.0


def _check_frf(rep, sc, scene, md, eq, pair, feats):
    i, o = pair
    name = (lambda k: k) if md.chain is not None else (lambda k: md.names[k])
    try:
        with product(rep, "frf", feats):
            h = sc.frf(scene, name(i), name(o), transfer=False)
            omega, H, phase = np.asarray(h.omega), np.asarray(h.H), np.asarray(h.phase)
            res = list(h.resonances)
            text = h.to_text()
            stated = _stated_sensitivity(h.notes)
    except Refused as exc:
        if not exc.message.startswith("traceback") and not _documented_refusal(exc.message):
            rep.add("frf", f"refused: {exc.message}", feats)
        return
    if md.chain is not None and md.n > 24:
        rep.skipped.append("frf: long chain")
    connected = any(i in p and o in p for p, _ in md.pieces())
    ms = R.modes(md, eq)
    # H at a sample of the grid: evenly spread, plus the points nearest each resonance
    picks = set(np.linspace(0, len(omega) - 1, 8).round().astype(int).tolist())
    for r in res:
        k = int(np.argmin(abs(omega - r.omega_n)))
        picks |= {max(0, k - 1), k, min(len(omega) - 1, k + 1)}
    picks = sorted(picks)[:30]
    ref = R.receptance(md, [float(omega[k]) for k in picks], i, o, eq)
    hmax = max(abs(v) for v in ref)
    worst = 0.0
    for k, r in zip(picks, ref):
        err = _rel(complex(H[k]), r) if r != 0 else (0.0 if H[k] == 0 else math.inf)
        if not connected:
            err = abs(H[k]) / max(float(hmax), 1e-300) if hmax else (0.0 if H[k] == 0 else math.inf)
        worst = max(worst, err)
        if err > max(TOL["frf.H"], stated):  # or the sensitivity to the elements' last bit the notes state
            rep.add("frf.H", f"H({omega[k]!r}) = {complex(H[k])!r} (oracle {mp.nstr(r, 17)})", feats)
            break
        if connected and r != 0:  # the phase in degrees, unwrapped: the oracle's arg modulo 360
            dphi = (phase[k] - float(mp.degrees(mp.arg(r))) + 180.0) % 360.0 - 180.0
            if abs(dphi) > max(1e-6, math.degrees(stated)):  # H's stated sensitivity bounds its angle too
                rep.add("frf.phase", f"phase({omega[k]!r}) = {phase[k]!r} deg (oracle {mp.nstr(mp.degrees(mp.arg(r)), 12)} "
                                     "mod 360)", feats)
                break
    note_error("frf.H", worst)
    if md.chain is not None and md.damped and "ζ not computed" in text:
        rep.add("frf.resonances", "a damped [chain]'s resonance table says 'ζ not computed' (modes computes it)", feats)
    if not connected and any(r.participates for r in res):
        rep.add("frf.resonances", "input and output on unconnected pieces (H = 0): the table lists resonances "
                                  f"{[r.omega_n for r in res if r.participates]}", feats)
        return
    for r in res:
        if not r.participates:
            continue
        j = min(range(md.n), key=lambda c: abs(mp.sqrt(ms.omega2[c]) - r.omega_n))
        if r.undamped:  # the claim |H| = inf: the oracle's H at its own ω_j, beside ω_j (1 ± 1e-3)
            wj = mp.sqrt(ms.omega2[j])
            vals = R.receptance(md, [wj * (1 - mp.mpf("1e-3")), wj, wj * (1 + mp.mpf("1e-3"))], i, o, eq,
                                dps=max(60, 40 + 2 * R.contrast_digits(md)), settle=False)
            side = max(abs(vals[0]), abs(vals[2]))
            if mp.isfinite(abs(vals[1])) and abs(vals[1]) <= 1e6 * side:
                rep.add("frf.resonances", f"'|H| = inf' at omega_n = {r.omega_n!r}, but the oracle's |H| there is "
                                          f"{mp.nstr(abs(vals[1]), 6)} (beside it {mp.nstr(side, 6)}): a node at the "
                                          "input or output, or a damped mode", feats)
        if r.peak_omega is not None:
            w = r.peak_omega
            vals = R.receptance(md, [w * (1 - 1e-7), w, w * (1 + 1e-7)], i, o, eq)
            mags = [abs(v) for v in vals]
            err = _rel(r.peak_magnitude, mags[1])
            note_error("frf.peak", err)
            if err > max(TOL["frf.peak"], stated):
                rep.add("frf.peak", f"peak |H| = {r.peak_magnitude!r} at {w!r} (oracle |H| there "
                                    f"{mp.nstr(mags[1], 17)})", feats)
            if max(mags[0], mags[2]) > mags[1] * (1 + mp.mpf("1e-13")):
                rep.add("frf.peak", f"'exact peak' at omega = {w!r} is not a local maximum of |H| (|H| "
                                    f"{mp.nstr(mags[0], 12)}, {mp.nstr(mags[1], 12)}, {mp.nstr(mags[2], 12)})", feats)


# -- time histories -----------------------------------------------------------------------------------------
def _check_simulate(rep, sc, scene, md, eq, eq_error, feats, folder):
    # the exact method applies to linear scenes; a potential counts as linear only when quadratic with V'(0) = 0
    exact = md.linear and not any(isinstance(ld.signal, R._Opaque) for ld in md.loads) \
        and all(s.potential is None or s.tension(mp.mpf(0)) == 0 for s in md.springs)
    methods = ["modal"] if exact else None
    zero_motion = (not md.initial_given or (all(v == 0 for v in md.x0) and all(v == 0 for v in md.v0))) \
        and not md.loads and all(v == 0 for v in md.prestress())
    try:
        with product(rep, "simulate", feats):
            run = sc.simulate(scene, methods=methods, springs=True, progress=False, out=folder / "out")
    except Refused as exc:
        msg = exc.message
        if msg.startswith("traceback"):
            return
        if "nothing driving it" in msg and not zero_motion:
            rep.add("simulate", f"refused as motionless, but it moves (x0, loads or prestress): {msg}", feats)
        elif not _documented_refusal(msg) and eq_error is None:
            rep.add("simulate", f"refused: {msg}", feats)
        return
    notes = " ".join(run.summary.get("notes", []))
    method = run.methods[0]
    rows = sorted(set(np.linspace(0, len(run.t) - 1, 4).round().astype(int).tolist()))
    times = [float(run.t[r]) for r in rows]
    limited = "float64" in notes
    if exact and method == "modal":
        try:
            tr = R.trajectory(md, times)
        except R.Unsupported as exc:
            rep.skipped.append(f"trajectory: {exc}")
            tr = None
        if tr is not None:
            xs = np.asarray(run.x["modal"])[rows]
            vs = np.asarray(run.v["modal"])[rows]
            ax = max(abs(v) for row in tr.x for v in row) or mp.mpf(1)
            av = max(abs(v) for row in tr.v for v in row) or mp.mpf(1)
            ex = max(float(abs(mp.mpf(float(xs[a][b])) - tr.x[a][b]) / ax) for a in range(len(rows)) for b in range(md.n))
            ev = max(float(abs(mp.mpf(float(vs[a][b])) - tr.v[a][b]) / av) for a in range(len(rows)) for b in range(md.n))
            err = max(ex, ev)
            if not limited:
                note_error("simulate.x", err)
            if err > TOL["simulate.x"] and not limited:
                rep.add("simulate.x", f"exact method off by {err:.3g} of the amplitude (x {ex:.3g}, v {ev:.3g}) "
                                      f"at t = {times}; no float64 note", feats)
            ref_x = tr.x
            _compare_springs(rep, md, run, "modal", rows, ref_x, feats, limited, TOL["simulate.springs"])
            if md.ground is not None and "aabs_modal" in run.extra and not limited:
                _compare_aabs(rep, md, run, rows, tr, feats)
    elif md.springs:
        # no exact solution: the spring outputs of the run's own trajectory, evaluated by the oracle
        xs = np.asarray(run.x[method])[rows]
        if np.all(np.isfinite(xs)):
            ref_x = [[mp.mpf(float(v)) for v in row] for row in xs]
            _compare_springs(rep, md, run, method, rows, ref_x, feats, False, TOL["simulate.spring_eval"])


def _compare_aabs(rep, md, run, rows, tr, feats):
    """Absolute accelerations ẍ + a_g = (every force but the ground's inertial one) / m (README, Loads)."""
    pa = np.asarray(run.extra["aabs_modal"])
    ms = R.modes(md)
    C = R.damping_matrix(md, ms) if md.damped else None
    ref = []
    for a, t in enumerate(tr.times):
        x, v = tr.x[a], tr.v[a]
        g = R.gradient(md, x)
        row = []
        for i in range(md.n):
            f = -g[i] - (mp.fsum(C[i, j] * v[j] for j in range(md.n)) if C is not None else 0)
            for ld in md.loads:
                if ld.key != "ground":
                    f += ld.b[i] * (ld.signal.value(t) if isinstance(ld.signal, R.Harm) else ld.signal.value(t, 1))
            row.append(f / md.m[i])
        ref.append(row)
    scale = max(abs(v) for row in ref for v in row) or mp.mpf(1)
    err = max(float(abs(mp.mpf(float(pa[r][i])) - ref[a][i]) / scale) for a, r in enumerate(rows) for i in range(md.n))
    note_error("simulate.aabs", err)
    if err > TOL["simulate.x"] * 10:
        rep.add("simulate.aabs", f"aabs_modal off by {err:.3g} of its size", feats)


def _compare_springs(rep, md, run, method, rows, ref_x, feats, limited, tol):
    keys = [f"drift_{method}", f"spring_force_{method}", f"base_shear_{method}"]
    if not all(k in run.extra for k in keys):
        rep.add("simulate.springs", f"springs=True but {', '.join(k for k in keys if k not in run.extra)} missing",
                feats)
        return
    drifts, forces, shear = R.spring_series(md, ref_x)
    pd, pf, ps = (np.asarray(run.extra[k]) for k in keys)
    worst = 0.0
    for label, prod_rows, ref_rows in (("drift", pd, drifts), ("spring force", pf, forces)):
        for s in range(len(md.springs)):
            scale = max(abs(ref_rows[a][s]) for a in range(len(rows)))
            if scale == 0:
                continue
            err = max(float(abs(mp.mpf(float(prod_rows[r][s])) - ref_rows[a][s]) / scale) for a, r in enumerate(rows))
            worst = max(worst, err)
            if err > tol and not limited:
                rep.add("simulate.springs", f"{label} of {md.springs[s].key} off by {err:.3g} of its size "
                                            f"({method}; product {[float(prod_rows[r][s]) for r in rows]}, oracle "
                                            f"{[mp.nstr(ref_rows[a][s], 12) for a in range(len(rows))]})", feats)
                break
    scale = max(abs(v) for v in shear)
    if scale:
        err = max(float(abs(mp.mpf(float(ps[r])) - shear[a]) / scale) for a, r in enumerate(rows))
        worst = max(worst, err)
        if err > tol and not limited:
            rep.add("simulate.springs", f"base shear off by {err:.3g} of its size ({method}; product "
                                        f"{[float(ps[r]) for r in rows]}, oracle {[mp.nstr(v, 12) for v in shear]})",
                    feats)
    if not limited:
        note_error("simulate.springs" if tol == TOL["simulate.springs"] else "simulate.spring_eval", worst)


# -- response-spectrum analysis ----------------------------------------------------------------------------
#: Most periods of the stiffest mode per record the rsa check runs (the product's spectrum cost grows with
#: record length over period: issue 31's resource finding; the oracle's too).
MAX_RSA_CYCLES = 200
#: Largest period over record step the rsa check asks the product for (its cost grows as T/step).
MAX_PERIOD_OVER_STEP = 1e6


def _check_rsa(rep, sc, scene, md, eq, record, feats, folder):
    if md.free_pieces():
        return _check_rsa_refused(rep, sc, scene, record, feats, folder)
    w2 = R.modes(md, eq).omega2
    cycles = float(mp.sqrt(max(w2))) * (record.t[-1] - record.t[0]) / (2 * math.pi)
    if cycles > MAX_RSA_CYCLES:
        rep.skipped.append(f"rsa: {cycles:.3g} periods of the stiffest mode in the record")
        return
    slowest = 2 * math.pi / float(mp.sqrt(min(w2)))
    if slowest / min(b - a for a, b in zip(record.t, record.t[1:])) > MAX_PERIOD_OVER_STEP:
        rep.skipped.append(f"rsa: the slowest mode's period {slowest:.3g} s is {MAX_PERIOD_OVER_STEP:g}+ record steps "
                           "(the product's free-vibration tail then costs ~T/step: issue 31's resource finding, "
                           "test_finding[spectrum_time_long_period])")
        return
    csv_path = folder / "record.csv"
    csv_path.write_text(record.csv(), encoding="utf-8")
    try:
        with product(rep, "rsa", feats):
            r = sc.rsa(scene, spectrum=str(csv_path))
            js = r.to_json()
    except Refused as exc:
        if not exc.message.startswith("traceback") and not _documented_refusal(exc.message):
            rep.add("rsa", f"refused: {exc.message}", feats)
        return
    if eq is not None and any(v != 0 for v in eq.x) and any("about x = 0" in n for n in r.notes):
        rep.add("rsa.note", "notes say 'the linearization about x = 0' while the scene's equilibrium is away from 0",
                feats)
    if any(len(g) > 1 for g in _clusters(R.modes(md, eq).omega2, 1e-6)):
        rep.skipped.append("rsa: repeated frequencies (the per-mode split is not unique)")
        return
    free_part = {}

    def sd_of(T, z):
        parts = R.sdof_parts(record.t, record.a, float(T), float(z))
        free_part[float(T)] = parts[1] > parts[0]
        return max(parts)

    ref = R.rsa(md, sd_of, eq)
    J = len(ref.omega)
    modal = js["modes"]
    worst, bad = 0.0, []
    for j in range(J):
        for key, o in (("zeta", ref.zeta[j]), ("sd", ref.sd[j]), ("base_shear", ref.base_shear[j])):
            err = _rel(modal[j][key], o, floor=1e-72 if key == "zeta" else 0)
            worst = max(worst, err)
            if err > TOL["rsa"]:
                bad.append(f"mode {j + 1} {key} {modal[j][key]!r} (oracle {mp.nstr(o, 12)})")
        err = _rel(abs(modal[j]["participation_factor"]), abs(ref.gamma[j]))
        worst = max(worst, err)
        if err > TOL["rsa"]:
            bad.append(f"mode {j + 1} Gamma {modal[j]['participation_factor']!r} (oracle {mp.nstr(ref.gamma[j], 12)})")
    for how in ("srss", "cqc"):
        comb = ref.combined(how)
        got = js[how]
        for key in ("displacement", "drift", "spring_force"):
            scale = max([abs(v) for v in comb[key]] + [mp.mpf(0)])
            for s, o in enumerate(comb[key]):
                err = _rel(got[key][s], o, floor=scale * 1e-6)
                worst = max(worst, err)
                if err > TOL["rsa"]:
                    bad.append(f"{how} {key}[{s}] {got[key][s]!r} (oracle {mp.nstr(o, 12)})")
        err = _rel(got["base_shear"], comb["base_shear"])
        worst = max(worst, err)
        if err > TOL["rsa"]:
            bad.append(f"{how} base shear {got['base_shear']!r} (oracle {mp.nstr(comb['base_shear'], 12)})")
    note_error("rsa", worst)
    after = any(free_part.values()) and any(" sd " in b for b in bad)
    for b in bad[:6]:  # a wrong SD carries into everything after it: said on each line
        rep.add("rsa", b + (" [an SD whose oracle peak is in the free vibration after the record]" if after else ""),
                feats)


def _check_rsa_refused(rep, sc, scene, record, feats, folder):
    """A scene with a free piece: rsa must refuse in one line (rigid modes have no spectral ordinate)."""
    csv_path = folder / "record.csv"
    csv_path.write_text(record.csv(), encoding="utf-8")
    try:
        with product(rep, "rsa", feats):
            sc.rsa(scene, spectrum=str(csv_path))
    except Refused:
        return
    rep.add("rsa", "an analysis of a scene with a free piece (rigid modes) instead of a refusal", feats)


# -- response spectra ----------------------------------------------------------------------------------
def check_record(rec, features=frozenset()) -> Report:
    """``response_spectrum`` of a record (t, a) at its periods and damping ratios against the oracle."""
    sc = _api()
    rep = Report()
    import numpy as np

    try:
        with product(rep, "spectrum", features):
            res = sc.response_spectrum((np.array(rec.t), np.array(rec.a)), zeta=list(rec.zeta),
                                       periods=list(rec.periods))
            sd = np.asarray(res.sd)
    except Refused as exc:
        if not exc.message.startswith("traceback"):
            rep.add("spectrum", f"refused: {exc.message}", features)
        return rep
    worst = 0.0
    with mp.workdps(40):
        for z, zeta in enumerate(rec.zeta):
            for p, period in enumerate(rec.periods):
                try:
                    parts = R.sdof_parts(rec.t, rec.a, period, zeta)
                except R.Unsupported as exc:
                    rep.skipped.append(f"spectrum T = {period}: {exc}")
                    continue
                o = max(parts)
                err = _rel(float(sd[z, p]), o)
                worst = max(worst, err)
                if err > TOL["spectrum.sd"]:
                    where = ("its peak is in the free vibration after the record" if parts[1] > parts[0]
                             else "its peak is inside the record")
                    rep.add("spectrum.sd", f"T = {period!r}, zeta = {zeta!r}: SD = {float(sd[z, p])!r} (oracle "
                                           f"{mp.nstr(o, 12)}; {where})", features)
    note_error("spectrum.sd", worst)
    return rep


def check_spectrum_time(rec, budget: float = 20.0, features=frozenset()) -> Report:
    """``response_spectrum`` of ``rec`` in a fresh process: an answer or a one-line refusal within ``budget``
    seconds (the issue's item 5: time bounded whatever the periods and the record)."""
    rep = Report()
    code = ("import sys\nimport springchain as sc\ntry:\n"
            f"    sc.response_spectrum(({list(rec.t)!r}, {list(rec.a)!r}), zeta={list(rec.zeta)!r}, "
            f"periods={list(rec.periods)!r})\n"
            "except (sc.RunRefused, sc.SceneError) as exc:\n    print(exc, file=sys.stderr)\n    sys.exit(2)\n")
    env = dict(os.environ, SPRINGCHAIN_PROGRESS="0")
    try:
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=budget, env=env)
    except subprocess.TimeoutExpired:
        rep.add("spectrum.time", f"no answer within {budget:g} s (periods {list(rec.periods)}, record "
                                 f"{rec.t[0]:g} ... {rec.t[-1]:g} s in {len(rec.t)} rows)", features)
        return rep
    err = proc.stderr.strip().splitlines()
    if proc.returncode not in (0, 2) or (proc.returncode and len(err) != 1):
        rep.add("spectrum.time", f"exit {proc.returncode}: {proc.stderr[-300:]!r}", features)
    return rep


# -- the command line -------------------------------------------------------------------------------------
def run_cli(args, cwd: Path, timeout: float = 300):
    env = dict(os.environ, SPRINGCHAIN_PROGRESS="0")
    return subprocess.run([sys.executable, "-m", "springchain", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout, env=env)


def check_cli(rep, path: Path, feats, md=None, argv=("modes", "{scene}", "--json"), timeout: float = 300) -> None:
    """``springchain ARGV`` (default ``modes PATH --json``): exit 0 (with ``--json``: one JSON object on stdout),
    or exit 2 with one line on stderr naming the error."""
    args = [a.replace("{scene}", str(path)) for a in argv]
    try:
        proc = run_cli(args, path.parent, timeout)
    except subprocess.TimeoutExpired:
        rep.add("cli", f"springchain {' '.join(argv)} did not finish in {timeout:g} s (a hang)", feats)
        return
    if proc.returncode == 0:
        if "--json" in args:
            try:
                json.loads(proc.stdout)
            except ValueError:
                rep.add("cli", f"exit 0 but stdout is not one JSON object: {proc.stdout[:200]!r}", feats)
        return
    err = proc.stderr.strip().splitlines()
    if proc.returncode != 2 or len(err) != 1 or not err[0].startswith("springchain: error:"):
        rep.add("cli", f"springchain {argv[0]}: exit {proc.returncode}, stderr {len(err)} lines, ending "
                       f"{proc.stderr.strip().splitlines()[-1][:200] if err else ''!r}", feats)


# -- the findings -----------------------------------------------------------------------------------
#: (id, predicate on (output, detail, features)) for the findings issue 31 lists (being fixed).
KNOWN = (
    ("response spectra miss the peak after the record ends",
     lambda o, d, f: o in ("spectrum.sd", "rsa") and "free vibration after the record" in d),
    ("response spectra: time and memory grow without bound with period over step",
     lambda o, d, f: o == "spectrum.time" or (o in ("rsa", "spectrum") and "MemoryError" in d)),
    ("contrast inside the accepted range breaks the core outputs",
     lambda o, d, f: ("is not a prime factor" in d or "numerically singular" in d
                      or (o == "modes.omega2" and (": 0.0 (oracle" in d or "regime:extreme" in f))
                      or ("OverflowError" in d and any(x.startswith("potential:") for x in f)))),
    ("Lennard-Jones springs under any constant load are refused",
     lambda o, d, f: o == "modes" and "no static equilibrium found" in d and "potential:lennard_jones" in f),
    ("time-history spring forces at contrast",
     lambda o, d, f: o == "simulate.springs" and ("regime:wide" in f or "regime:extreme" in f)),
    ("frf's resonance table says false things",
     lambda o, d, f: o in ("frf.resonances", "frf.peak") and ("node" in d or "unconnected" in d
                                                              or "not a local maximum" in d or "inf'" in d)),
    ("contrast inside the accepted range breaks the core outputs (the command line: a traceback)",
     lambda o, d, f: o == "cli" and "numerically singular" in d),
    ("smaller: damped [chain] frf says 'zeta not computed'; rsa on a potential scene says 'about x = 0'",
     lambda o, d, f: (o == "frf.resonances" and "ζ not computed" in d) or o == "rsa.note"),
    ("pre-stressed potential scene without [initial] told its motion is zero",
     lambda o, d, f: o == "simulate" and "refused as motionless" in d),
)


#: Findings of this oracle that issue 31 does not list; each has a minimal reproducer in test_oracle.py
#: (``FINDINGS``, strict xfail). Generated scenes that hit them are counted, not failed.
FOUND = (
    ("N1 modes --json drops 'equilibrium' of a damped potential scene",
     lambda o, d, f: o == "modes.equilibrium" and "has no 'equilibrium'" in d),
    ("N3 simulate springs=True: AttributeError cubic_constants",
     lambda o, d, f: o in ("simulate", "cli") and "cubic_constants" in d),
    ("N4 simulate springs=True: a potential spring's tension is V''(0) d, not V'(d)",
     lambda o, d, f: o == "simulate.springs" and any(x.startswith("potential:") for x in f)
     and "spring:cubic" in f),
    ("N5 exact method: last frame = the initial state (table load, steps not a multiple of record_every)",
     lambda o, d, f: o in ("simulate.x", "simulate.springs") and any(x.endswith(":table") for x in f)),
    ("N6 modes of a strongly overdamped [chain] leak a ComplexWarning",
     lambda o, d, f: o == "modes" and "ComplexWarning" in d),
    ("N7 frf relative error above 1e-10 at wide contrast",
     lambda o, d, f: o in ("frf.H", "frf.peak") and ("regime:wide" in f or "regime:extreme" in f)
     and "not a local maximum" not in d),
    ("N8 [chain] modes --json: no shape_value (index-dependent) / shape_value in reversed order (free-wall)",
     lambda o, d, f: o == "modes.shape" and "form:chain" in f),
    ("N12 participation factors attached to the wrong modes at extreme contrast (omega^2 right)",
     lambda o, d, f: o == "modes.gamma" and "regime:extreme" in f),
    ("N13/N14 modes hangs in SymPy (damping ratios' or Rayleigh targets' closed forms)",
     lambda o, d, f: o in ("cli", "modes") and "a hang" in d),
    ("N15 damped [chain]: zeta of an overdamped mode is wrong",
     lambda o, d, f: o == "modes.zeta" and "form:chain" in f and "omega_d 0.0" in d),
    ("N16 exact method, damped, under a constant load with an enormous sag: positions off by decades, no note",
     lambda o, d, f: o in ("simulate.x", "simulate.aabs") and "regime:extreme" in f
     and any(x.startswith("damping:") for x in f)
     and any(x in f for x in ("gravity", "ground:const", "force:const", "force:harmonic2"))),
    ("N17 simulate: a damped rigid mode alone (a free mass with a dashpot to the wall) ends in a TypeError",
     lambda o, d, f: o in ("simulate", "cli") and "not 'complex'" in d),
    ("N9 Rayleigh damping called non-proportional (complex modes) when a pre-stressed potential moves x_eq",
     lambda o, d, f: o in ("modes.zeta", "modes.complex") and ("said proportional = False" in d
                                                               or "oracle has no complex mode" in d
                                                               or "complex modes listed" in d)
     and any(x.startswith("potential:") for x in f) and ("damping:rayleigh" in f or "damping:rayleigh_targets" in f)),
)


#: Findings whose root is the model the product builds (wrong equilibrium): their consequences in every
#: output are theirs, checked before issue 31's symptoms.
ROOTS = (
    ("N11 a constant ground acceleration is left out of a potential scene's equilibrium",
     lambda o, d, f: "ground:const" in f and any(x.startswith("potential:") for x in f)
     and (o.startswith("modes") or o.startswith("frf") or o.startswith("rsa"))),
    ("N2 cubic (k3) springs under constant loads: modes about the linear sag",
     lambda o, d, f: o in ("modes.omega2", "modes.shape", "modes.gamma", "modes.zeta", "modes.complex",
                           "modes.equilibrium", "frf.H", "frf.peak", "frf.resonances", "rsa") and "spring:cubic" in f
     and any(x in f for x in ("gravity", "force:const", "force:harmonic2", "ground:const"))),
    ("N10 a constant load on a potential [chain] is not refused: modes and frf about x = 0",
     lambda o, d, f: "form:chain" in f and any(x.startswith("potential:") for x in f)
     and any(x in f for x in ("gravity", "force:const", "force:harmonic2", "ground:const"))
     and (o.startswith("modes") or o.startswith("frf"))),
)


def classify(finding: Finding, features) -> str | None:
    for name, pred in ROOTS:
        if pred(finding.output, finding.detail, features):
            return "oracle " + name
    for name, pred in KNOWN:
        if pred(finding.output, finding.detail, features):
            return "issue 31: " + name
    for name, pred in FOUND:
        if pred(finding.output, finding.detail, features):
            return "oracle " + name
    return None


__all__ = ["check_scene", "check_cli", "run_cli", "Report", "Finding", "TOL", "STATS", "KNOWN", "classify"]
