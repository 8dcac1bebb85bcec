"""``springchain.state_space``: a scene as a state-space model for SciPy or python-control.

The matrices come from :mod:`springchain.numeric.interop.state_space`; this module reads the
inputs and outputs by name, picks the form and says, in one warning line, where the state-space
form itself loses accuracy (wide element contrast).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from ._modules import check_linear_outputs
from .derive.scene import Scene

FORMS = ("scipy", "control", "matrices")
#: Most masses of a dense model (a ``[chain]`` beyond this is given as sparse matrices only).
MAX_DENSE_STATES = 2000


class AccuracyWarning(UserWarning):
    """A result that is correct for its form but less accurate than springchain's own route."""


def _names(sc: Scene) -> tuple[str, ...]:
    return tuple(sc.mass_names) if sc.chain is None else tuple(str(j) for j in range(sc.n))


def _inputs(sc: Scene, inputs) -> list:
    from ._frf import mass_index
    from .numeric.errors import RunRefused
    from .numeric.interop.state_space import GROUND

    items = [inputs] if isinstance(inputs, str | int) else list(inputs)
    if not items:
        raise RunRefused("inputs: none given; accepted: mass names (a force on each) and/or 'ground'",
                         quantity="inputs")
    out = []
    for item in items:
        text = str(item).strip()
        if text == GROUND:
            out.append(GROUND)
            continue
        name, _, kind = text.partition(":")
        if kind and kind != "force":
            raise RunRefused(f"inputs {item!r}: accepted: a mass name (a force on it), 'NAME:force' or 'ground' "
                             "(a base acceleration)", quantity="inputs")
        out.append(mass_index(sc, name, "inputs"))
    return out


def _outputs(sc: Scene, outputs) -> list:
    from ._frf import mass_index
    from .numeric.errors import RunRefused
    from .numeric.interop.state_space import KINDS

    items = [outputs] if isinstance(outputs, str | int) else list(outputs)
    if not items:
        raise RunRefused("outputs: none given; accepted: 'NAME' or 'NAME:KIND' (x, v, a)", quantity="outputs")
    out = []
    for item in items:
        name, _, kind = str(item).strip().partition(":")
        kind = kind or "x"
        if kind not in KINDS:
            raise RunRefused(f"outputs {item!r}: kind {kind!r}; accepted: NAME or NAME:KIND with KIND one of "
                             f"{', '.join(KINDS)}", quantity="outputs")
        out.append((mass_index(sc, name, "outputs"), KINDS[kind]))
    return out


def _scipy_state_space():
    """``scipy.signal.StateSpace`` whose conversion to zeros, poles and gain (what ``freqresp``, ``bode``
    use for a SISO model) is by eigenvalue problems (:func:`numeric.interop.state_space.siso_zpk`)."""
    import scipy.signal

    from .numeric.interop.state_space import siso_zpk

    continuous = type(scipy.signal.StateSpace([[0.0]], [[1.0]], [[1.0]], [[0.0]]))  # its continuous-time class

    class StateSpace(continuous):
        """scipy.signal.StateSpace; SISO zeros and poles by eigenvalue problems, not polynomial roots."""

        #: ``(C_x, k)`` when the single output is the k-th derivative of a displacement (set by state_space)
        derivative = None

        def to_zpk(self, **kwargs):
            if self.inputs != 1 or self.outputs != 1 or kwargs:
                return super().to_zpk(**kwargs)
            return scipy.signal.ZerosPolesGain(*siso_zpk(self.A, self.B, self.C, self.D, self.derivative))

    return StateSpace


def state_space(scene: str | Path | Scene, inputs, outputs, *, form: str | None = None, sparse: bool | None = None):
    """The linear scene as ``ẋ = A x + B u``, ``y = C x + D u`` with state ``(x, v)`` of every mass.

    Parameters
    ----------
    scene : str, Path or Scene
    inputs : str, int or list
        Mass names (a force on each; ``"NAME:force"`` alike; indices for ``[chain]`` scenes) and/or
        ``"ground"`` (a base acceleration a_g).
    outputs : str or list
        ``"NAME"`` (displacement) or ``"NAME:KIND"`` with KIND ``x``/``displacement``, ``v``/``velocity``,
        ``a``/``acceleration``. Under a base input displacements and velocities are relative to the
        base, accelerations absolute.
    form : {"scipy", "control", "matrices"}, optional
        Default "scipy" for ``[masses]`` scenes, "matrices" (sparse) for ``[chain]`` scenes.
        ``scipy.signal.StateSpace`` (a subclass whose SISO zeros and poles come from eigenvalue problems,
        so ``scipy.signal.freqresp`` and ``bode`` keep full accuracy); a python-control ``StateSpace`` with named inputs, outputs and
        states (the extra ``springchain[control]``); or a
        :class:`~springchain.numeric.interop.state_space.StateSpaceModel` (matrices and names).
    sparse : bool, optional
        CSR matrices (form "matrices" only). Default: sparse for ``[chain]`` scenes.

    Returns
    -------
    scipy.signal.StateSpace, control.StateSpace or StateSpaceModel

    Warns
    -----
    AccuracyWarning
        One line where the element contrast exceeds 1e6: A holds M⁻¹K in float64 and its frequency
        response loses about contrast × ε (``springchain.frf`` does not).
    """
    from ._modules import system_of
    from ._scenes import load
    from .numeric.modes.elements import Elements
    from .numeric.errors import RunRefused
    from .numeric.interop.state_space import state_space as build

    if form is not None and form not in FORMS:
        raise RunRefused(f"form {form!r}; accepted: {', '.join(FORMS)}", quantity="form")
    sc = load(scene)
    check_linear_outputs(sc)  # a cubic [chain] under a constant load: one line
    form = form or ("matrices" if sc.chain is not None else "scipy")
    ins, outs = _inputs(sc, inputs), _outputs(sc, outputs)
    if sparse is None:
        sparse = sc.chain is not None and form == "matrices"
    if sparse and form != "matrices":
        raise RunRefused(f"sparse matrices come with form 'matrices' (scipy.signal and python-control hold dense "
                         f"arrays); asked: form {form!r}", quantity="form")
    if not sparse and sc.n > MAX_DENSE_STATES:
        raise RunRefused(f"a dense state-space model of {sc.n} masses ({2 * sc.n} states): at most "
                         f"{MAX_DENSE_STATES} masses; accepted: form='matrices' (sparse CSR)", quantity="form")
    system, _ = system_of(sc)
    model = build(Elements.from_system(system), _names(sc), ins, outs, sparse=sparse)
    for note in model.notes + ([] if system.linear else ["nonlinear springs: the linearisation (linear stiffness)"]):
        warnings.warn(note, AccuracyWarning, stacklevel=2)
    if form == "matrices":
        return model
    A, B, C, D = model.dense()
    if form == "scipy":
        out = _scipy_state_space()(A, B, C, D)
        (i, kind), = outs if len(outs) == 1 else [(None, None)]
        if len(ins) == 1 and ins[0] != "ground" and kind in ("velocity", "acceleration"):
            cx = np.zeros((1, A.shape[0]))
            cx[0, i] = 1.0
            out.derivative = (cx, 1 if kind == "velocity" else 2)
        return out
    from ._data import require

    control = require("control", "state_space(..., form='control')")
    return control.ss(A, B, C, D, inputs=list(model.inputs), outputs=list(model.outputs),
                      states=list(model.states), name=sc.name)


__all__ = ["state_space", "AccuracyWarning", "FORMS"]
