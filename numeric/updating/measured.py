"""Measured modes from a CSV file: natural frequencies, optionally their standard deviations and mode
shapes at sensor masses.

Format (one row per measured mode, any order; ``#`` starts a comment line)::

    omega,omega_std,floor1,floor3
    12.41,0.012,0.52,1.0
    31.02,0.031,1.0,-0.63

* ``omega`` (rad/s) or ``frequency`` (Hz) — required, finite and > 0;
* ``omega_std`` / ``frequency_std`` — optional standard deviations (> 0) in the same unit; without them
  the fit weighs frequencies by their relative error and estimates one noise level from the residual;
* ``shape_std`` — optional standard deviation of each shape value once the shape is scaled to 1 in
  magnitude at its largest sensor (needed with ``omega_std`` when shapes are given);
* every other column is a sensor: a mass name (an index 0 … n−1 for ``[chain]`` scenes), its value the
  measured mode shape there (any scale and sign; all sensor columns filled, or the shape left out of a
  row by leaving all of them empty).

The file is untrusted data: it is read as text with the :mod:`csv` module, every cell parsed by
``float`` after a check that it is a plain decimal number; anything else is refused in one line naming
the file, the row, the column and what is accepted.
"""

from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import RunRefused

#: Largest measured file read (bytes).
MAX_BYTES = 8 * 2**20
#: Plain decimal numbers (no nan, inf, hex, underscores).
NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")
#: Column names that are not sensors.
RESERVED = ("omega", "omega_std", "frequency", "frequency_std", "shape_std")
ACCEPTED = ("a CSV file with a header row: omega (rad/s) or frequency (Hz), optionally omega_std / frequency_std, "
            "and one column per sensor mass holding the measured shape")


@dataclass(frozen=True)
class Measured:
    """Measured modes.

    Attributes
    ----------
    file : str
    omega : ndarray, shape (R,)
        Natural frequencies [rad/s] in the file's row order.
    omega_std : ndarray, shape (R,) or None
        Their standard deviations [rad/s].
    sensors : tuple of str
        Sensor column names (masses), in file order.
    shapes : ndarray, shape (D, R) or None
        Measured shapes at the sensors (columns = modes); NaN for a row whose shape was left out.
    """

    file: str
    omega: np.ndarray = field(repr=False)
    omega_std: np.ndarray | None = field(default=None, repr=False)
    sensors: tuple[str, ...] = ()
    shapes: np.ndarray | None = field(default=None, repr=False)
    #: Standard deviation of the normalised shape values of each row, shape (R,), or None.
    shape_std: np.ndarray | None = field(default=None, repr=False)

    def first(self, rows: int) -> "Measured":
        """The first ``rows`` measured modes."""
        cut = lambda a: None if a is None else (a[..., :rows])  # noqa: E731
        return Measured(self.file, self.omega[:rows], cut(self.omega_std), self.sensors, cut(self.shapes),
                        cut(self.shape_std))

    @property
    def rows(self) -> int:
        return int(self.omega.shape[0])

    def with_shapes(self) -> np.ndarray:
        """Indices of the rows that carry a shape, shape (R',)."""
        if self.shapes is None:
            return np.zeros(0, dtype=np.intp)
        return np.flatnonzero(np.all(np.isfinite(self.shapes), axis=0))


def _refuse(file: str, where: str, why: str) -> RunRefused:
    return RunRefused(f"{file}: {where}: {why}; accepted: {ACCEPTED}", "measured")


def read_text(path: Path, file: str) -> str:
    """The file's text (UTF-8, at most :data:`MAX_BYTES`), refused in one line otherwise."""
    try:
        if not path.is_file():
            raise _refuse(file, "file", "not a regular file")
        with open(path, "rb") as fh:
            raw = fh.read(MAX_BYTES + 1)
    except OSError as exc:
        raise _refuse(file, "file", f"cannot be read ({exc.strerror or exc})") from None
    if len(raw) > MAX_BYTES:
        raise _refuse(file, "file", f"larger than {MAX_BYTES // 2**20} MiB")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise _refuse(file, "file", f"byte {exc.start} is not UTF-8") from None


def rows_of(text: str, file: str) -> tuple[list[str], list[tuple[int, list[str]]]]:
    """Header and data rows (with their line numbers) of a CSV text; comment and blank lines skipped."""
    lines = [(i + 1, ln) for i, ln in enumerate(text.splitlines()) if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise _refuse(file, "file", "empty (no header row)")
    reader = list(csv.reader(io.StringIO("\n".join(ln for _, ln in lines))))
    header = [h.strip() for h in reader[0]]
    return header, [(num, [c.strip() for c in row]) for (num, _), row in zip(lines[1:], reader[1:])]


def number(cell: str, file: str, line: int, column: str, positive: bool = False) -> float:
    """A cell as a finite float (refused in one line otherwise)."""
    if not NUMBER.match(cell):
        raise _refuse(file, f"line {line}, column {column!r}", f"{cell[:40]!r} is not a number")
    value = float(cell)
    if not np.isfinite(value):
        raise _refuse(file, f"line {line}, column {column!r}", f"{cell[:40]!r} is not finite")
    if positive and not value > 0:
        raise _refuse(file, f"line {line}, column {column!r}", f"{cell[:40]!r} is not > 0")
    return value


def read_measured(path: str | Path) -> Measured:
    """Read and check a measured-modes CSV file (see the module docstring).

    Raises
    ------
    RunRefused
        One line naming the file, line and column (missing columns, not-a-number cells, NaN or inf,
        non-positive frequencies, ragged rows, duplicate columns, no rows).
    """
    file = str(path)
    header, rows = rows_of(read_text(Path(path), file), file)
    if len(set(header)) != len(header):
        dup = next(h for h in header if header.count(h) > 1)
        raise _refuse(file, "header", f"column {dup!r} appears twice")
    if any(not h for h in header):
        raise _refuse(file, "header", "an empty column name")
    hz = "frequency" in header
    if ("omega" in header) == hz:
        raise _refuse(file, "header", "needs exactly one of the columns 'omega' (rad/s) or 'frequency' (Hz); "
                                      f"found {', '.join(header)!r}")
    col = "frequency" if hz else "omega"
    std = col + "_std"
    other = ("omega" if hz else "frequency") + "_std"
    if other in header:
        raise _refuse(file, "header", f"{other!r} with {col!r}: a standard deviation in the other unit")
    if not rows:
        raise _refuse(file, "file", "no data rows")
    sensors = tuple(h for h in header if h not in RESERVED)
    scale = 2 * np.pi if hz else 1.0
    omega, sd, shapes, ssd = [], [], [], []
    for line, row in rows:
        if len(row) != len(header):
            raise _refuse(file, f"line {line}", f"{len(row)} cells for {len(header)} columns")
        cells = dict(zip(header, row))
        omega.append(scale * number(cells[col], file, line, col, positive=True))
        if std in cells:
            sd.append(scale * number(cells[std], file, line, std, positive=True))
        if "shape_std" in cells:
            ssd.append(number(cells["shape_std"], file, line, "shape_std", positive=True) if cells["shape_std"]
                       else np.nan)
        values = [cells[s] for s in sensors]
        if sensors and all(v == "" for v in values):
            shapes.append([np.nan] * len(sensors))
        else:
            shape = [number(v, file, line, s) for v, s in zip(values, sensors)]
            if sensors and not any(shape):
                raise _refuse(file, f"line {line}", "a measured shape that is zero at every sensor")
            shapes.append(shape)
    return Measured(file, np.array(omega), np.array(sd) if std in header else None, sensors,
                    np.array(shapes, dtype=float).T if sensors else None,
                    np.array(ssd) if "shape_std" in header else None)


__all__ = ["Measured", "read_measured", "read_text", "rows_of", "number", "NUMBER", "RESERVED"]
