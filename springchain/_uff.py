"""``springchain.write_uff`` / ``read_uff``: FRFs (dataset 58, binary) and modes (dataset 55, ASCII) as
Universal File Format files, through pyuff (the extra ``springchain[uff]``).

What is written: node n is mass n − 1 (``[masses]`` in file order; ``[chain]`` indices), direction +X;
FRF abscissae in Hz (exact doubles, 58b); modes mass-normalised (modal mass 1) with frequencies in Hz
and the viscous damping ratio where the damping is proportional (0 otherwise: complex modes are not
written), six significant digits as pyuff prints dataset 55.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .derive.scene import Scene


def _names(scene: Scene) -> tuple[str, ...]:
    return tuple(scene.mass_names) if scene.chain is None else tuple(str(j) for j in range(scene.n))


def write_frf_uff(result, path: str | Path) -> Path:
    """Write a :class:`~springchain.FrequencyResponse` or :class:`~springchain.FrfForm` as one binary
    dataset 58 (frequencies in Hz); returns the path."""
    from ._frf import FrequencyResponse
    from .numeric.interop import uff

    names = _names(result.scene)
    if isinstance(result, FrequencyResponse):
        form, values = "receptance", result.H
    else:
        form, values = result.form, result.values
    node = lambda name: names.index(name) + 1 if name in names else 0  # noqa: E731 - 0: the base
    ids = (f"springchain {result.scene.name}: {form}", f"response node {node(result.output)} = mass {result.output}",
           f"reference node {node(result.input)} = " + ("the base" if result.input == "ground" else f"mass {result.input}"),
           "abscissa: frequency [Hz]; SI units")
    return uff.write(path, [uff.frf_set(result.omega / (2 * math.pi), values, node(result.output), node(result.input),
                                        form, ids)])


def write_modes_uff(scene, path: str | Path) -> tuple[Path, list[str]]:
    """Write every mode of ``scene`` (the accurate spectrum: frequencies ascending, rigid ones at 0 Hz) as
    ASCII datasets 55; returns the path and notes."""
    from ._modules import system_of
    from ._scenes import load
    from .numeric.modes.elements import Elements, modal_damping
    from .numeric.interop import uff

    sc = load(scene)
    system, _ = system_of(sc)
    el = Elements.from_system(system)
    spec = system.spectrum
    notes = ["dataset 55 is ASCII with six significant digits (pyuff's %13.5e); shapes mass-normalised (modal mass 1)"]
    zeta = np.zeros(spec.omega.shape[0])
    if el.damped and el.proportional:
        g = np.diag(modal_damping(el, spec.omega, spec.shapes))
        zeta = np.where(spec.omega > 0, g / (2 * np.where(spec.omega > 0, spec.omega, 1.0)), 0.0)
    elif el.damped:
        notes.append("dashpots: non-proportional damping has complex modes; damping ratios written as 0")
    if not system.linear:
        notes.append("nonlinear springs: the modes of the linear stiffness")
    ids = (f"springchain {sc.name}: normal modes", "node n = mass n-1 in scene order, direction +X",
           ", ".join(f"{j + 1}={m}" for j, m in enumerate(_names(sc)))[:80])
    path = uff.write(path, uff.mode_sets(spec.omega / (2 * math.pi), spec.shapes, zeta, ids))
    return path, notes


def read_uff(path: str | Path):
    """The FRFs (dataset 58) and normal modes (dataset 55) of a UFF file, e.g. measured ones.

    Returns
    -------
    (list of springchain.numeric.interop.uff.UffFrf, list of springchain.numeric.interop.uff.UffMode)
        ``UffFrf.f`` [Hz], ``.H`` complex, nodes and directions, data types; ``UffMode.frequency`` [Hz],
        ``.damping``, ``.nodes``, ``.shape`` (P, 3).

    Raises
    ------
    RunRefused
        A file that cannot be read (one line naming it).
    """
    from .numeric.errors import RunRefused
    from .numeric.interop import uff

    p = Path(path)
    if not p.is_file():
        raise RunRefused(f"{path}: not a readable file; accepted: a UFF file (datasets 55, 58)", quantity="uff")
    try:
        return uff.read(p)
    except ValueError as exc:
        raise RunRefused(f"{path}: {exc}; accepted: a UFF file (datasets 55, 58)", quantity="uff") from None


__all__ = ["write_frf_uff", "write_modes_uff", "read_uff"]
