"""Universal File Format (UFF) files through pyuff (the extra ``springchain[uff]``).

* **Dataset 58** (a function at nodal DOF): an FRF, written **binary** (58b, IEEE doubles): a round
  trip returns the frequencies and complex values exactly. Abscissa: frequency [Hz] (uneven spacing,
  the refined grid); node numbers are mass indices + 1, direction +X (1).
* **Dataset 55** (data at nodes): one normal mode per set, written in **ASCII** as pyuff writes it
  (``%13.5e``: six significant digits — the format's printed precision); modal mass 1 (mass-normalised
  shapes), viscous damping ratio where the damping is proportional.

pyuff's binary writer reopens the file when asked to overwrite and loses the header it has just
written, so files are written by truncating first and adding every set.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

#: UFF specific data types (dataset 58 ordinate / denominator).
DATA_TYPES = {"displacement": 8, "velocity": 11, "acceleration": 12, "force": 13, "frequency": 18, "unknown": 0}
_NAMES = {v: k for k, v in DATA_TYPES.items()}
#: (ordinate, denominator) data type of each FRF form.
FORM_TYPES = {"receptance": ("displacement", "force"), "mobility": ("velocity", "force"),
              "accelerance": ("acceleration", "force"), "dynamic-stiffness": ("force", "displacement"),
              "transmissibility": ("displacement", "displacement"),
              "relative-transmissibility": ("displacement", "displacement")}
_UNITS = {"displacement": "m", "velocity": "m/s", "acceleration": "m/s^2", "force": "N"}


def _pyuff():
    try:
        import pyuff
    except ImportError:
        raise ImportError('UFF files need pyuff, which springchain installs only on request: '
                          'pip install "springchain[uff]"') from None
    return pyuff


@dataclass(frozen=True)
class UffFrf:
    """A dataset 58 FRF: ``f`` [Hz] (W,), ``H`` (W,) complex, nodes and directions, data types, ids."""

    response_node: int
    response_dir: int
    reference_node: int
    reference_dir: int
    f: np.ndarray = field(repr=False)
    H: np.ndarray = field(repr=False)
    ordinate: str = "unknown"
    denominator: str = "unknown"
    ids: tuple = ()


@dataclass(frozen=True)
class UffMode:
    """A dataset 55 mode: ``frequency`` [Hz], viscous damping ratio, ``nodes`` (P,), ``shape`` (P, 3)."""

    number: int
    frequency: float
    damping: float
    nodes: np.ndarray = field(repr=False)
    shape: np.ndarray = field(repr=False)
    ids: tuple = ()


def frf_set(f_hz: np.ndarray, H: np.ndarray, response_node: int, reference_node: int, form: str,
            ids: tuple[str, ...] = ()) -> dict:
    """A pyuff dataset-58 dict (binary) of one FRF."""
    pyuff = _pyuff()
    num, den = FORM_TYPES[form]
    ids = tuple(str(s)[:80] for s in ids) + ("NONE",) * 5
    return pyuff.prepare_58(binary=1, id1=ids[0], id2=ids[1], id3=ids[2], id4=ids[3], id5=ids[4], func_type=4,
                            rsp_node=int(response_node), rsp_dir=1, ref_node=int(reference_node), ref_dir=1,
                            rsp_ent_name="mass", ref_ent_name="mass", ord_data_type=6,
                            abscissa_spacing=0, abscissa_spec_data_type=DATA_TYPES["frequency"],
                            abscissa_axis_units_lab="Hz", ordinate_spec_data_type=DATA_TYPES[num],
                            ordinate_axis_units_lab=_UNITS[num], orddenom_spec_data_type=DATA_TYPES[den],
                            orddenom_axis_units_lab=_UNITS[den],
                            data=np.asarray(H, dtype=complex), x=np.asarray(f_hz, dtype=float))


def mode_sets(freq_hz: np.ndarray, shapes: np.ndarray, zeta: np.ndarray, ids: tuple[str, ...] = ()) -> list[dict]:
    """pyuff dataset-55 dicts, one per mode; ``shapes`` (N, M) mass-normalised, columns the modes."""
    pyuff = _pyuff()
    n = shapes.shape[0]
    ids = tuple(str(s)[:80] for s in ids) + ("NONE",) * 5
    nodes = np.arange(1, n + 1)
    return [pyuff.prepare_55(id1=ids[0], id2=ids[1], id3=ids[2], id4=ids[3], id5=ids[4], model_type=1,
                             analysis_type=2, data_ch=2, spec_data_type=DATA_TYPES["displacement"], data_type=2,
                             n_data_per_node=3, r1=np.asarray(shapes[:, j], dtype=float), r2=np.zeros(n),
                             r3=np.zeros(n), load_case=1, mode_n=j + 1, freq=float(freq_hz[j]), modal_m=1.0,
                             modal_damp_vis=float(zeta[j]), modal_damp_his=0.0, node_nums=nodes)
            for j in range(shapes.shape[1])]


def write(path: str | Path, sets: list[dict]) -> Path:
    """Write ``sets`` to ``path`` (replacing it); returns the path."""
    pyuff = _pyuff()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b"")  # truncate, then add every set (see the module docstring)
    pyuff.UFF(str(path)).write_sets(sets, mode="add")
    return path


def read(path: str | Path) -> tuple[list[UffFrf], list[UffMode]]:
    """The dataset 58 functions and dataset 55 normal modes of a UFF file (other datasets are skipped).

    Raises
    ------
    ValueError
        A file pyuff cannot read (one line).
    """
    pyuff = _pyuff()
    try:
        uff = pyuff.UFF(str(path))
        types = list(uff.get_set_types())
        sets = [uff.read_sets(j) for j in range(len(types))]
    except Exception as exc:  # noqa: BLE001 - pyuff raises bare Exceptions for any malformed file
        raise ValueError(f"not a UFF file pyuff can read ({str(exc).splitlines()[0][:120] if str(exc) else type(exc).__name__})") from None
    if not types:
        raise ValueError("no UFF dataset in it (each starts and ends with a line '    -1')")
    frfs, modes = [], []
    for t, s in zip(types, sets):
        ids = tuple(str(s.get(f"id{k}", "")).strip() for k in range(1, 6))
        if int(t) == 58:
            frfs.append(UffFrf(int(s["rsp_node"]), int(s["rsp_dir"]), int(s["ref_node"]), int(s["ref_dir"]),
                               np.asarray(s["x"], dtype=float), np.asarray(s["data"]),
                               _NAMES.get(int(s.get("ordinate_spec_data_type", 0)), "unknown"),
                               _NAMES.get(int(s.get("orddenom_spec_data_type", 0)), "unknown"), ids))
        elif int(t) == 55 and int(s.get("analysis_type", 0)) == 2:
            shape = np.column_stack([np.asarray(s[r], dtype=float) for r in ("r1", "r2", "r3")])
            modes.append(UffMode(int(s["mode_n"]), float(s["freq"]), float(s.get("modal_damp_vis", 0.0)),
                                 np.asarray(s["node_nums"], dtype=int), shape, ids))
    return frfs, modes


__all__ = ["UffFrf", "UffMode", "frf_set", "mode_sets", "write", "read", "FORM_TYPES", "DATA_TYPES"]
