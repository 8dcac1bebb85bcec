"""The modal assurance criterion between two mode sets: ``sc.mac`` and ``springchain mac``.

A mode set is a scene (its mass-normalised shapes), a measured-modes CSV file (shapes at its sensor
masses, :mod:`numeric.updating.measured`) or an array of shapes (columns). Sets sampled at different
masses are compared at the masses they share (or at ``masses=``); the numbers come from
:mod:`numeric.sensitivity.mac`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from .derive.errors import SceneError, show


@dataclass(frozen=True)
class ModeSet:
    """Shapes sampled at named degrees of freedom.

    Attributes
    ----------
    label : str
    dofs : tuple of str
        Mass names (indices as text for ``[chain]`` scenes and arrays).
    shapes : ndarray, shape (D, J)
    omega : ndarray, shape (J,) or None
        Natural frequencies [rad/s] where known.
    modes : ndarray of int, shape (J,) or None
        Mode positions (0-based, ascending ω²) of a scene's modes.
    """

    label: str
    dofs: tuple[str, ...]
    shapes: object = field(repr=False)
    omega: object = field(default=None, repr=False)
    modes: object = field(default=None, repr=False)

    def at(self, dofs: tuple[str, ...], key: str) -> "ModeSet":
        """The same modes sampled at ``dofs`` (refused in one line when one is missing)."""
        index = {d: i for i, d in enumerate(self.dofs)}
        missing = [d for d in dofs if d not in index]
        if missing:
            raise SceneError(None, key, f"{show(missing[0])}: not a degree of freedom of {self.label}; accepted: "
                                        + ", ".join(self.dofs[:12]) + (" ..." if len(self.dofs) > 12 else ""))
        rows = [index[d] for d in dofs]
        return ModeSet(self.label, tuple(dofs), self.shapes[rows], self.omega, self.modes)


def _is_csv(source) -> bool:
    return isinstance(source, (str, Path)) and str(source).lower().endswith(".csv")


def mode_set(source, label: str | None = None) -> ModeSet:
    """A :class:`ModeSet` from a scene, a measured CSV file or an array (D, J)."""
    import numpy as np

    if isinstance(source, ModeSet):
        return source
    if isinstance(source, np.ndarray) or (isinstance(source, (list, tuple)) and not isinstance(source, str)):
        arr = np.asarray(source, dtype=float)
        arr = arr[:, None] if arr.ndim == 1 else arr
        if arr.ndim != 2 or not np.all(np.isfinite(arr)):
            raise SceneError(None, "mac", f"an array of shape {arr.shape}: accepted: finite shapes as columns, (D, J)")
        return ModeSet(label or "array", tuple(str(i) for i in range(arr.shape[0])), arr)
    if _is_csv(source):
        from .numeric.updating.measured import read_measured

        m = read_measured(source)
        keep = m.with_shapes()
        if not keep.size:
            raise SceneError(str(source), "mac", "no measured shapes (no sensor columns filled); accepted: one "
                                                 "column per sensor mass holding the shape")
        return ModeSet(label or str(source), m.sensors, m.shapes[:, keep], m.omega[keep])
    from ._modules import system_of
    from ._scenes import load
    from ._sensitivity import default_modes
    from .numeric.sensitivity.compute import mode_shapes

    scene = load(source)
    system, _ = system_of(scene)
    idx, w2, shapes = mode_shapes(system, default_modes(system.n))
    dofs = scene.mass_names if scene.chain is None else tuple(str(i) for i in range(scene.n))
    return ModeSet(label or scene.name, tuple(dofs), shapes, np.sqrt(np.maximum(w2, 0.0)), idx)


@dataclass(frozen=True)
class MAC:
    """MAC of two mode sets and their optimal pairing.

    Attributes
    ----------
    a, b : ModeSet
        Sampled at the compared degrees of freedom.
    matrix : ndarray, shape (Ja, Jb)
    pairs : list of (int, int, float)
        ``(column of a, column of b, MAC)`` maximising the summed MAC.
    """

    a: ModeSet
    b: ModeSet
    matrix: object = field(repr=False)
    pairs: list = field(repr=False)

    def _name(self, s: ModeSet, j: int) -> str:
        return f"mode {int(s.modes[j])}" if s.modes is not None else f"#{j + 1}"

    def to_json(self) -> dict:
        """What ``springchain mac A B --json`` prints."""
        def side(s: ModeSet) -> dict:
            return {"label": s.label, "modes": None if s.modes is None else [int(v) for v in s.modes],
                    "omega": None if s.omega is None else [float(v) for v in s.omega]}

        return {"a": side(self.a), "b": side(self.b), "dofs": list(self.a.dofs),
                "mac": self.matrix.tolist(),
                "pairs": [{"a": i, "b": j, "mac": v,
                           "omega_a": None if self.a.omega is None else float(self.a.omega[i]),
                           "omega_b": None if self.b.omega is None else float(self.b.omega[j])}
                          for i, j, v in self.pairs]}

    def to_text(self) -> str:
        """What ``springchain mac A B`` prints: the pairs, then the matrix (up to 20 × 20)."""
        lines = [f"MAC of {self.a.label} ({self.matrix.shape[0]} modes) and {self.b.label} "
                 f"({self.matrix.shape[1]} modes) at {len(self.a.dofs)} degrees of freedom: "
                 + ", ".join(self.a.dofs[:10]) + (" ..." if len(self.a.dofs) > 10 else ""),
                 "", f"{'a':>10} {'omega_a':>14} {'b':>10} {'omega_b':>14} {'MAC':>10}"]
        for i, j, v in self.pairs:
            wa = "-" if self.a.omega is None else f"{self.a.omega[i]:.8g}"
            wb = "-" if self.b.omega is None else f"{self.b.omega[j]:.8g}"
            lines.append(f"{self._name(self.a, i):>10} {wa:>14} {self._name(self.b, j):>10} {wb:>14} {v:>10.6f}")
        ja, jb = self.matrix.shape
        if ja <= 20 and jb <= 20:
            lines += ["", "matrix (rows a, columns b):"]
            lines += ["  " + " ".join(f"{v:5.3f}" for v in row) for row in self.matrix]
        return "\n".join(lines) + "\n"


def mac(a, b, masses=None) -> MAC:
    """The modal assurance criterion between two mode sets, and their optimal pairing.

    Parameters
    ----------
    a, b : scene (str, Path, Scene), measured CSV file (str or Path ending in .csv) or ndarray (D, J)
        Shapes as columns; a scene gives its mass-normalised shapes (every mode up to 40 masses, else the
        10 lowest and 10 highest), a measured file its shapes at the sensor masses.
    masses : sequence of str, optional
        The degrees of freedom compared (mass names; indices for chains and arrays). Default: those both
        sets have (all of them when both are arrays of the same height).

    Returns
    -------
    MAC
        ``.matrix`` (Ja, Jb), ``.pairs`` [(i, j, MAC)], ``.to_json()``, ``.to_text()``.

    Raises
    ------
    SceneError
        Sets with no degree of freedom in common, an unknown mass, arrays of different heights.
    """
    from .numeric.sensitivity.mac import mac_matrix, pair

    sa, sb = mode_set(a, None), mode_set(b, None)
    arrays = [s.label == "array" for s in (sa, sb)]
    named = tuple(str(m).strip() for m in (masses.split(",") if isinstance(masses, str) else masses)) \
        if masses is not None else None
    for i, s in enumerate((sa, sb)):  # an array takes the other set's degrees of freedom (or masses=) by height
        other = (sb, sa)[i]
        if arrays[i] and not arrays[1 - i]:
            dofs = named if named is not None and len(named) == len(s.dofs) else other.dofs
            if len(dofs) != len(s.dofs):
                raise SceneError(None, "masses", f"an array of {len(s.dofs)} rows against {other.label} with "
                                 f"{len(other.dofs)} degrees of freedom; accepted: as many rows, or the masses "
                                 "compared, one per row (--masses on the command line, masses= in Python)")
            s = ModeSet(s.label, tuple(dofs), s.shapes, s.omega, s.modes)
            sa, sb = (s, sb) if i == 0 else (sa, s)
    if all(arrays) and len(sa.dofs) != len(sb.dofs):
        raise SceneError(None, "mac", f"arrays of {len(sa.dofs)} and {len(sb.dofs)} rows; accepted: shapes sampled "
                                      "at the same degrees of freedom (as many rows)")
    if sa.label == sb.label:
        sa, sb = ModeSet(sa.label + " (a)", sa.dofs, sa.shapes, sa.omega, sa.modes), \
            ModeSet(sb.label + " (b)", sb.dofs, sb.shapes, sb.omega, sb.modes)
    if masses is not None:
        dofs = tuple(str(m).strip() for m in (masses.split(",") if isinstance(masses, str) else masses))
        if not dofs or any(not d for d in dofs) or len(set(dofs)) != len(dofs):
            raise SceneError(None, "masses", f"{show(masses)}: accepted: distinct mass names separated by commas")
    else:
        shared = set(sb.dofs)
        dofs = tuple(d for d in sa.dofs if d in shared)
        if not dofs:
            raise SceneError(None, "masses", f"{sa.label} and {sb.label} share no degree of freedom ({sa.label}: "
                             f"{', '.join(sa.dofs[:6])}; {sb.label}: {', '.join(sb.dofs[:6])}); accepted: sets "
                             "sampled at common masses, or the masses to compare (--masses on the command line, "
                             "masses= in Python)")
    sa, sb = sa.at(dofs, "masses"), sb.at(dofs, "masses")
    matrix = mac_matrix(sa.shapes, sb.shapes)
    return MAC(sa, sb, matrix, pair(matrix))


__all__ = ["mac", "MAC", "ModeSet", "mode_set"]
