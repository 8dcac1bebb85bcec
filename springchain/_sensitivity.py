"""Mode sensitivities (∂ω²/∂p, ∂φ/∂p) and the modal assurance criterion: ``sc.sensitivities``, ``sc.mac``,
``springchain modes SCENE --sensitivity`` and ``springchain mac``.

SymPy work (derivatives of the element values, closed-form ∂ω²/∂p) is in
:mod:`springchain.derive.sensitivity`; the numbers in :mod:`springchain.numeric.sensitivity`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from ._modules import check_linear_outputs
from ._scenes import load
from .derive.errors import SceneError, show
from .derive.scene import Scene

#: Modes listed by default: all up to this many masses, else the lowest and highest MODES_EACH_END.
MAX_ALL_MODES = 40
MODES_EACH_END = 10
#: Shapes and their derivatives appear in the JSON up to this many masses.
MAX_SHAPE_MASSES = 40

CONVENTION = ("K phi = omega^2 M phi with phi^T M phi = 1 (mass-normalised), the sign making the largest "
              "mass-weighted component sqrt(m_i) phi_i positive; d omega^2/dp = phi^T (dK/dp - omega^2 dM/dp) phi; "
              "d phi/dp by Nelson's method (particular solution of (K - omega^2 M) v = -(dK/dp - d omega^2/dp M - "
              "omega^2 dM/dp) phi, then d phi/dp = v + c phi with c = -phi^T M v - phi^T dM/dp phi / 2); at a "
              "repeated omega^2 the directional derivatives for increasing p (eigenvalues of the projected "
              "matrix, ascending) and the derivatives of the adapted shapes; normalised: p/omega^2 d omega^2/dp")


def parameter_list(scene: Scene, parameters, key: str = "parameters") -> tuple[str, ...] | None:
    """``parameters`` (None, ``"k,m"`` or a sequence of names) checked against the scene's; None = default."""
    if parameters is None:
        return None
    names = [p.strip() for p in parameters.split(",")] if isinstance(parameters, str) else [str(p) for p in parameters]
    if not names or any(not p for p in names):
        raise SceneError(scene.file, key, f"{show(parameters)}: empty name; accepted: parameter names separated "
                                          f"by commas, e.g. {','.join(scene.parameter_names[:2])}")
    for p in names:
        if p not in scene.parameters:
            raise SceneError(scene.file, key, f"{show(p)}: not a parameter of the scene; accepted: "
                                              + ", ".join(scene.parameter_names))
    if len(set(names)) != len(names):
        raise SceneError(scene.file, key, f"{show(parameters)}: a parameter named twice; accepted: each once")
    return tuple(names)


def default_modes(n: int):
    """Every mode up to :data:`MAX_ALL_MODES` masses, else the lowest and highest :data:`MODES_EACH_END`."""
    import numpy as np

    if n <= MAX_ALL_MODES:
        return np.arange(n)
    return np.concatenate([np.arange(MODES_EACH_END), np.arange(n - MODES_EACH_END, n)])


class Setup:
    """What every evaluation of a scene's sensitivities needs, built once: the generated module, the
    symbolic element derivatives and the closed forms (refitting calls :meth:`at` many times)."""

    def __init__(self, scene: Scene, parameters=None, closed_forms: bool = True):
        from ._modules import derive, system_of
        from .derive.sensitivity.elements import element_law, relevant

        self.scene = scene
        self.system, _ = system_of(scene)
        d = derive(scene)
        self.model, self.modes = d.model, d.modes
        chosen = parameter_list(scene, parameters)
        self.parameters = chosen if chosen is not None else relevant(self.model)
        if not self.parameters and not scene.has_potential:
            raise SceneError(scene.file, "parameters", "no parameter enters the masses or springs; accepted: a "
                                                       "scene whose masses or spring constants use parameters")
        self.law = element_law(self.model, self.parameters)
        self.closed = None
        if closed_forms:
            from .derive.sensitivity.closed_form import closed_form_derivatives

            self.closed = closed_form_derivatives(self.model, self.modes, self.parameters)

    def at(self, values: dict[str, float] | None = None, wanted=None):
        """The numeric sensitivities at ``values`` (default the scene's) of modes ``wanted``."""
        import numpy as np

        from .numeric.sensitivity.compute import compute
        from .numeric.sensitivity.derivatives import ElementDerivatives

        vals = dict(self.scene.parameters)
        vals.update(values or {})
        system = self.system if values is None else self.system.with_params(vals)
        if values is not None and not (np.all(system.masses > 0) and np.all(system.stiffness >= 0)):
            from .numeric.errors import RunRefused

            shown = ", ".join(f"{k} = {v:.6g}" for k, v in (values or {}).items())
            raise RunRefused(f"at {shown} a mass or spring constant of {self.scene.name!r} is not positive; "
                             "accepted: parameter values that keep every mass > 0 and every spring >= 0")
        dm, dk, d2m, d2k = self.law.at(vals, system.spring_ends, system.n)
        derivs = ElementDerivatives(self.parameters, tuple(float(vals[p]) for p in self.parameters), dm, dk, d2m, d2k)
        return compute(system, derivs, default_modes(system.n) if wanted is None else wanted)


def _fmt(v) -> str:
    return "-" if v is None or (isinstance(v, float) and not math.isfinite(v)) else f"{v:.10g}"


def _row(*cells) -> str:
    """Cells of the text table: mode, ω², repeated, parameter, ∂ω²/∂p, normalised, shape change, closed form."""
    mode, w2, rep, p, d, norm, size, closed = cells
    return (f"{mode:>5} {w2:>17} {rep:>3}  {p:<12} {d:>17} {norm:>17} {size:>14}  {closed}").rstrip()


@dataclass(frozen=True)
class Sensitivities:
    """Sensitivities of a scene's modes to its parameters (``sc.sensitivities``).

    Attributes
    ----------
    scene : Scene
    result : numeric.sensitivity.compute.ModeSensitivities
        ``index`` (J,), ``omega2`` (J,), ``shapes`` (N, J), ``d_omega2`` (P, J), ``d_shapes`` (P, N, J),
        ``normalised`` (P, J), ``repeated`` (J,).
    closed : derive.sensitivity.closed_form.ClosedForm or None
    notes : tuple of str
    """

    scene: Scene
    result: object = field(repr=False)
    closed: object = field(default=None, repr=False)
    notes: tuple[str, ...] = ()
    #: The masses, shape (N,) (M-norms of the shape derivatives).
    masses: object = field(default=None, repr=False)

    @property
    def parameters(self) -> tuple[str, ...]:
        return self.result.parameters

    @property
    def d_omega2(self):
        """∂ω²/∂p, ndarray, shape (P, J) (parameters × listed modes)."""
        return self.result.d_omega2

    @property
    def normalised(self):
        """p/ω² · ∂ω²/∂p, shape (P, J) (NaN for rigid modes)."""
        return self.result.normalised

    @property
    def d_shapes(self):
        """∂φ/∂p of the mass-normalised shapes, shape (P, N, J)."""
        return self.result.d_shapes

    @property
    def modes(self):
        """Positions of the listed modes (0-based, ascending ω², rigid first), shape (J,)."""
        return self.result.index

    def _closed(self, slot: int, p: str):
        """(expression text, exact value) of a closed-form ∂ω²/∂p of listed mode ``slot``, else (None, None)."""
        c = self.closed
        if c is None or not c.modes:
            return None, None
        j = int(self.result.index[slot])
        if j >= len(c.modes) or c.modes[j] is None:
            return None, None
        exprs, values = c.modes[j]
        e = exprs.get(p)
        if e is None:
            return None, None
        from .derive.printing import sstr

        return sstr(e), values.get(p)

    def _closed_shape(self, slot: int) -> dict | None:
        """``{p: [text of ∂φ_i/∂p]}`` of a simple closed-form mode (listed mode ``slot``), else None."""
        c = self.closed
        j = int(self.result.index[slot])
        if c is None or not c.shapes or j >= len(c.shapes) or c.shapes[j] is None or self.result.repeated[slot] > 1:
            return None
        from .derive.printing import sstr

        return {p: [sstr(e) for e in exprs] for p, exprs in c.shapes[j].items()}

    def _value(self, p_i: int, slot: int) -> float:
        """∂ω²/∂p of a listed mode: the closed form's exact value for a simple mode, else the numeric one."""
        r = self.result
        text, exact = self._closed(slot, r.parameters[p_i])
        if exact is not None and r.repeated[slot] == 1:
            return float(exact)
        return float(r.d_omega2[p_i, slot])

    def ranking(self) -> list[dict]:
        """Parameters by influence: the largest |p/ω² ∂ω²/∂p| over the listed elastic modes, descending."""
        import numpy as np

        r = self.result
        rows = []
        for i, p in enumerate(r.parameters):
            s = np.array([abs(self._value(i, j)) * abs(r.values[i]) / r.omega2[j] if not r.rigid[j] else np.nan
                          for j in range(r.index.shape[0])])
            if np.all(np.isnan(s)):
                rows.append({"parameter": p, "max_abs_normalised": None, "mode": None})
                continue
            j = int(np.nanargmax(s))
            rows.append({"parameter": p, "max_abs_normalised": float(s[j]), "mode": int(r.index[j])})
        return sorted(rows, key=lambda row: (-(row["max_abs_normalised"] or 0.0), row["parameter"]))

    def to_json(self) -> dict:
        """What ``springchain modes SCENE --sensitivity --json`` prints."""
        r = self.result
        n = r.shapes.shape[0]
        out = {"scene": self.scene.name, "parameters": {p: v for p, v in zip(r.parameters, r.values)},
               "convention": CONVENTION, "route": r.route, "modes": []}
        for slot, j in enumerate(r.index.tolist()):
            rec = {"mode": j, "omega2": float(r.omega2[slot]), "repeated": int(r.repeated[slot]),
                   "rigid": bool(r.rigid[slot]),
                   "d_omega2": {p: self._value(i, slot) for i, p in enumerate(r.parameters)},
                   "normalised": {p: (None if r.rigid[slot] else self._value(i, slot) * r.values[i] / r.omega2[slot])
                                  for i, p in enumerate(r.parameters)}}
            closed = {p: self._closed(slot, p)[0] for p in r.parameters}
            if any(v is not None for v in closed.values()):
                rec["d_omega2_expr"] = closed
            shape_exprs = self._closed_shape(slot)
            if shape_exprs is not None:
                rec["d_shape_expr"] = shape_exprs
            if n <= MAX_SHAPE_MASSES:
                rec["shape"] = r.shapes[:, slot].tolist()
                rec["d_shape"] = {p: r.d_shapes[i, :, slot].tolist() for i, p in enumerate(r.parameters)}
                if r.repeated[slot] > 1:
                    rec["adapted_shape"] = {p: r.adapted[i, :, slot].tolist() for i, p in enumerate(r.parameters)}
            out["modes"].append(rec)
        if self.closed is not None and self.closed.family:
            from .derive.printing import sstr

            out["family"] = {p: (None if e is None else sstr(e)) for p, e in self.closed.family.items()}
        out["ranking"] = self.ranking()
        out["notes"] = list(self.notes)
        return out

    def to_text(self) -> str:
        """What ``springchain modes SCENE --sensitivity`` prints."""
        import numpy as np

        r = self.result
        vals = ", ".join(f"{p} = {v:g}" for p, v in zip(r.parameters, r.values))
        lines = [f"Sensitivities of {self.scene.name!r} ({self.scene.file}) at {vals}",
                 "Convention: phi^T M phi = 1, largest sqrt(m_i) phi_i positive; d phi/dp by Nelson's method; at a "
                 "repeated omega^2: directional derivatives (increasing p), ascending",
                 f"Route: {r.route}", ""]
        lines.append(_row("mode", "omega^2", "rep", "parameter", "d omega^2/dp", "normalised", "p|d phi/dp|_M",
                          "closed form"))
        for slot, j in enumerate(r.index.tolist()):
            for i, p in enumerate(r.parameters):
                first = i == 0
                d = self._value(i, slot)
                norm = None if r.rigid[slot] else d * r.values[i] / r.omega2[slot]
                dphi = r.d_shapes[i, :, slot]
                size = abs(r.values[i]) * float(np.sqrt(np.sum(self.masses * dphi * dphi)))
                text, _ = self._closed(slot, p)
                lead = (str(j), _fmt(float(r.omega2[slot])), str(int(r.repeated[slot]))) if first else ("", "", "")
                lines.append(_row(*lead, p, _fmt(d), _fmt(norm), f"{size:.6g}", text or ""))
        lines += ["", "Ranking: largest |p/omega^2 d omega^2/dp| over the listed elastic modes"]
        for k, row in enumerate(self.ranking(), 1):
            where = f" (mode {row['mode']})" if row["mode"] is not None else ""
            lines.append(f"  {k}. {row['parameter']:<12} {_fmt(row['max_abs_normalised'])}{where}")
        if self.closed is not None and self.closed.family:
            from .derive.printing import sstr

            lines += ["", "Family (uniform chain), d omega_j^2/dp:"]
            lines += [f"  {p}: {sstr(e) if e is not None else '-'}" for p, e in self.closed.family.items()]
        for note in self.notes:
            lines.append(f"note: {note}")
        return "\n".join(lines) + "\n"

    def __repr__(self) -> str:
        return f"Sensitivities(scene={self.scene.name!r}, parameters={self.parameters}, modes={len(self.modes)})"


def sensitivities(scene: str | Path | Scene, parameters=None, modes=None) -> Sensitivities:
    """Sensitivities ∂ω²/∂p and ∂φ/∂p of a scene's modes to its parameters.

    Parameters
    ----------
    scene : str, Path or Scene
        As for :func:`springchain.load`.
    parameters : str or sequence of str, optional
        Scene parameters (``"k,m"`` or ``["k", "m"]``); default: every parameter the masses and springs use.
    modes : sequence of int, optional
        Mode positions (0-based, ascending ω², rigid modes included); default: every mode up to 40
        masses, else the 10 lowest and 10 highest.

    Returns
    -------
    Sensitivities
        ``.d_omega2`` (P, J), ``.normalised`` (P, J), ``.d_shapes`` (P, N, J), ``.ranking()``,
        ``.to_json()``, ``.to_text()``.

    Raises
    ------
    SceneError
        An unknown parameter, a scene with spring potentials (one line).
    """
    import numpy as np

    sc = load(scene)
    check_linear_outputs(sc)  # a cubic [chain] under a constant load: one line
    setup = Setup(sc, parameters)
    wanted = None
    if modes is not None:
        wanted = np.asarray(list(modes), dtype=np.intp)
        if wanted.size == 0 or wanted.min() < 0 or wanted.max() >= sc.n:
            raise SceneError(sc.file, "modes", f"{show(list(modes))}: accepted: mode positions 0 ... {sc.n - 1}")
    from .numeric.progress import phase

    notes = []
    count = len(wanted) if wanted is not None else len(default_modes(sc.n))
    with phase(f"sensitivities of {sc.name!r}: {count} modes x {len(setup.parameters)} parameters"):
        result = setup.at(None, wanted)
    if modes is None and sc.n > MAX_ALL_MODES:
        notes.append(f"{sc.n} masses: the {MODES_EACH_END} lowest and {MODES_EACH_END} highest modes are listed "
                     f"(others: --modes J,K,... on the command line, modes=[...] in Python)")
    if sc.dampers or sc.chain_dampers or sc.damping is not None:
        notes.append("damping is not part of these derivatives: they are those of the undamped modes (K, M)")
    if not sc.linear:
        notes.append("cubic springs: the derivatives are those of the linear part (k)")
    loose = [i for i, s in enumerate(result.settled) if not result.rigid[i] and s > 1e-20]
    if loose:
        notes.append(f"modes {result.index[loose].tolist()}: the double-double refinement stopped at a correction "
                     f"of {max(result.settled[loose]):.1e} (M-norm): their derivatives carry that relative error")
    return Sensitivities(sc, result, setup.closed, tuple(notes), setup.system.masses)


__all__ = ["sensitivities", "Sensitivities", "Setup", "parameter_list", "default_modes", "CONVENTION"]
