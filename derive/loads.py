"""Loads a scene brings: external forces (expressions or tables) and ground motion.

* ``[[forces]]`` entries: ``on`` names a mass (``[masses]`` scenes) or a 0-based index
  (``[chain]`` scenes), and either ``f = "EXPR of t"`` or ``table = "FILE.csv"``;
* ``[ground]``: ``acceleration = "EXPR of t"`` or ``table = "FILE.csv"``.

A table is a CSV file with a header line (``t,f`` for forces, ``t,a`` for ground motion)
and rows of two finite numbers, times strictly increasing. It is resolved relative to the
scene file and must lie in the scene's folder or below (the scene is untrusted: it cannot
make springchain read other files), linearly interpolated and zero outside its time range. Tables are data: they are
read here into arrays, never pasted into generated source (the generated module takes them
as arguments). Every problem raises :class:`~derive.errors.SceneError` naming the file, the
key, the bad value and what is accepted. SymPy is not imported here.
"""

from __future__ import annotations

import math
import os
import stat
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import SceneError, show
from .expr import Expr
from .scene_loader import did_you_mean

FORCE_KEYS = ("on", "f", "table")
GROUND_KEYS = ("acceleration", "table")
#: Largest table file read, and most rows.
MAX_TABLE_BYTES = 64 * 2**20
MAX_TABLE_ROWS = 10**6
#: Largest |value| in a table (products with masses stay finite).
MAX_TABLE_VALUE = 1e150


@dataclass(frozen=True)
class Table:
    """A validated two-column table, linearly interpolated and zero outside ``[t[0], t[-1]]``.

    Attributes
    ----------
    file : str
        The CSV file as resolved (relative to the scene file).
    t : ndarray, shape (R,)
        Strictly increasing finite times, R >= 2.
    y : ndarray, shape (R,)
        Finite values.
    """

    file: str
    t: np.ndarray = field(repr=False)
    y: np.ndarray = field(repr=False)


@dataclass(frozen=True)
class Force:
    """An external force ``f(t, parameters)`` on mass ``on``; ``key`` names its scene entry."""

    on: int
    f: Expr
    key: str


@dataclass(frozen=True)
class TableForce:
    """A tabulated external force (newtons) on mass ``on``, the same kind of entry as :class:`Force`."""

    on: int
    table: Table
    key: str


@dataclass(frozen=True)
class Ground:
    """Ground (support) acceleration a_g(t): an expression of t and parameters, or a table."""

    acceleration: Expr | None
    table: Table | None
    key: str = "ground"


def _read_text(scene_file: str, value: str, bad) -> tuple[Path, str]:
    """The table file ``value`` (relative to ``scene_file``'s folder, never outside it) as text, after
    checking it is a regular, readable, bounded UTF-8 file; ``bad(value, why)`` makes the error."""
    base = Path(scene_file).parent if scene_file else Path(".")
    path = base / value
    try:  # the scene is untrusted: it may name files in its own folder (or below), nothing else
        inside = not os.path.isabs(value) and path.resolve().is_relative_to(base.resolve())
    except (OSError, RuntimeError):
        inside = False
    if not inside:
        raise bad(value, "outside the scene file's folder (absolute, '..' or a link out of it); "
                         "tables are read from the scene's folder or below")
    try:
        mode = os.stat(path).st_mode
    except OSError as exc:
        raise bad(value, f"cannot read the file ({exc.strerror or exc}; names are relative to the scene "
                         "file's folder)") from None
    if not stat.S_ISREG(mode):
        raise bad(value, "not a regular file (a folder, FIFO or device)")
    try:
        with open(path, "rb") as fh:
            raw = fh.read(MAX_TABLE_BYTES + 1)
    except OSError as exc:
        raise bad(value, f"cannot read the file ({exc.strerror or exc})") from None
    if len(raw) > MAX_TABLE_BYTES:
        raise bad(value, f"larger than {MAX_TABLE_BYTES // 2**20} MiB")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise bad(value, f"byte {exc.start} is not UTF-8") from None
    if text.startswith("\ufeff"):
        text = text[1:]
    return path, text


def read_table(scene_file: str, key: str, value, column: str) -> Table:
    """Read and check the CSV ``value`` (relative to ``scene_file``) with header ``t,<column>``.

    Raises
    ------
    SceneError
        Naming ``scene_file``, ``key``, the bad value and the accepted form.
    """
    form = (f"a CSV file with a header line 't,{column}' (units optional: 't [s], {column} [UNIT]') and rows of two "
            "numbers, times strictly increasing")

    def bad(what, why: str) -> SceneError:
        return SceneError(scene_file, key, f"{show(what)}: {why}; accepted: {form}")

    if not isinstance(value, str):  # from Python (scene_from_dict): arrays, not a file
        return table_from_arrays(scene_file, key, value, column)
    if not value or "\x00" in value:
        raise bad(value, "not a file name")
    path, text = _read_text(scene_file, value, bad)
    lines = [ln.strip() for ln in text.splitlines()]
    lines = [ln for ln in lines if ln and not ln.startswith("#")]
    if not lines:
        raise bad(value, "empty")
    from .units import HeaderProblem, header_factors

    try:  # "t,a", or with units "t [s], a [g]" (converted to SI below)
        factors = header_factors(lines[0], ("t", column))
    except HeaderProblem as exc:
        raise bad(value, str(exc)) from None
    rows = lines[1:]
    if len(rows) < 2:
        raise bad(value, f"{len(rows)} data rows (at least 2 needed)")
    if len(rows) > MAX_TABLE_ROWS:
        raise bad(value, f"more than {MAX_TABLE_ROWS} rows")
    data = np.empty((len(rows), 2))
    for r, line in enumerate(rows):
        cells = line.split(",")
        if len(cells) != 2:
            raise bad(value, f"row {r + 1} {line[:40]!r} has {len(cells)} columns, not 2")
        for c, cell in enumerate(cells):
            try:
                number = float(cell)
            except ValueError:
                raise bad(value, f"row {r + 1} {line[:40]!r}: {cell.strip()[:20]!r} is not a number") from None
            if not math.isfinite(number) or abs(number) > MAX_TABLE_VALUE:
                raise bad(value, f"row {r + 1} {line[:40]!r}: {cell.strip()[:20]!r} is not a finite number "
                                 f"of size at most {MAX_TABLE_VALUE:g}")
            data[r, c] = number
    if factors != (1.0, 1.0):  # the header's units, to SI once
        data *= np.asarray(factors)[None, :]
        if not np.all(np.abs(data) <= MAX_TABLE_VALUE):
            raise bad(value, f"values beyond {MAX_TABLE_VALUE:g} in SI units")
    _check_times(data, lambda why: bad(value, why))
    return Table(str(path), data[:, 0].copy(), data[:, 1].copy())


def _check_times(data: np.ndarray, bad) -> None:
    dt = np.diff(data[:, 0])
    if not np.all(dt > 0):
        r = int(np.argmax(~(dt > 0))) + 2
        raise bad(f"times not strictly increasing at row {r} (t = {data[r - 1, 0]:g} after {data[r - 2, 0]:g})")


def table_from_arrays(scene_file: str, key: str, value, column: str) -> Table:
    """A table given as data from Python: an array of shape (R, 2) (columns t and ``column``) or a
    dict ``{"t": ..., column: ...}``; the checks of a CSV table (finite, at least 2 rows, times
    strictly increasing)."""
    form = (f"a CSV file name, an array of shape (R, 2) (columns t, {column}) or a dict "
            f"{{'t': [...], '{column}': [...]}}, R >= 2, finite, times strictly increasing")

    def bad(why: str) -> SceneError:
        return SceneError(scene_file, key, f"{show(value)}: {why}; accepted: {form}")

    if isinstance(value, dict) and sorted(map(str, value)) != sorted(["t", column]):
        raise bad(f"keys {sorted(map(str, value))}")
    try:
        if isinstance(value, dict):
            t, y = (np.asarray(value[c]) for c in ("t", column))
            raw = np.stack([t, y], axis=1) if t.ndim == 1 and t.shape == y.shape else None
        else:
            raw = np.asarray(value)
    except (ValueError, TypeError):
        raw = None
    if raw is None or raw.dtype.kind not in "iuf" or raw.ndim != 2 or raw.shape[1] != 2:
        what = "not numbers in two columns" if raw is None or raw.dtype.kind not in "iuf" else f"shape {raw.shape}"
        raise bad(what)
    data = raw.astype(float)
    if data.shape[0] < 2:
        raise bad(f"{data.shape[0]} rows (at least 2 needed)")
    if data.shape[0] > MAX_TABLE_ROWS:
        raise bad(f"more than {MAX_TABLE_ROWS} rows")
    off = ~np.isfinite(data) | (np.abs(data) > MAX_TABLE_VALUE)
    if off.any():
        r = int(np.argmax(off.any(axis=1)))
        raise bad(f"row {r + 1}: {data[r].tolist()} is not two finite numbers of size at most {MAX_TABLE_VALUE:g}")
    _check_times(data, bad)
    return Table("<array>", data[:, 0].copy(), data[:, 1].copy())


def parse_forces(ld, entries: list[dict], *, chain_n: int | None, index: dict[str, int],
                 pnames: frozenset[str], env: dict, times: np.ndarray):
    """``[[forces]]`` entries as (expression forces, tabulated forces).

    ``ld`` is the scene loader (:class:`derive.scene_loader.Loader`); ``chain_n`` is the chain
    length for ``[chain]`` scenes (``on`` is then an index), else None.
    """
    forces, tables = [], []
    for j, f in enumerate(entries):
        key = f"forces[{j}]"
        ld.keys(f, FORCE_KEYS, key, required=("on",), what="a [[forces]] entry")
        if ("f" in f) == ("table" in f):
            raise ld.bad(key, sorted(k for k in f if k in ("f", "table")),
                         "give exactly one of f and table",
                         'f = "EXPR of t" or table = "FILE.csv" (header t,f)')
        on = f["on"]
        if chain_n is None:
            if not isinstance(on, str) or on not in index:
                raise ld.bad(f"{key}.on", on, f"not a mass{did_you_mean(on, index)}",
                             ", ".join(repr(m) for m in index))
            at = index[on]
        else:
            if isinstance(on, bool) or not isinstance(on, int) or not 0 <= on < chain_n:
                raise ld.bad(f"{key}.on", on, "not a mass index of the chain",
                             f"a whole number 0 ... {chain_n - 1} (the 0-based mass index)")
            at = on
        if "f" in f:
            expr = ld.expression(f"{key}.f", f["f"], pnames | {"t"}, env={**env, "t": times})
            forces.append(Force(at, expr, key))
        else:
            tables.append(TableForce(at, read_table(ld.file, f"{key}.table", f["table"], "f"), key))
    return tuple(forces), tuple(tables)


def parse_ground(ld, pnames: frozenset[str], env: dict, times: np.ndarray) -> Ground | None:
    """The ``[ground]`` table, or None without one."""
    if "ground" not in ld.data:
        return None
    g = ld.table("ground", example=' with acceleration = "EXPR of t" or table = "FILE.csv"')
    ld.keys(g, GROUND_KEYS, "ground", what="[ground]")
    if ("acceleration" in g) == ("table" in g):
        raise ld.bad("ground", sorted(g), "give exactly one of acceleration and table",
                     'acceleration = "EXPR of t" or table = "FILE.csv" (header t,a)')
    if "acceleration" in g:
        expr = ld.expression("ground.acceleration", g["acceleration"], pnames | {"t"}, env={**env, "t": times})
        return Ground(expr, None)
    return Ground(None, read_table(ld.file, "ground.table", g["table"], "a"))


__all__ = ["Table", "Force", "TableForce", "Ground", "read_table", "table_from_arrays", "parse_forces", "parse_ground",
           "FORCE_KEYS", "GROUND_KEYS"]
