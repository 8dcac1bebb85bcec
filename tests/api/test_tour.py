"""docs/tour.ipynb, executed by a real Jupyter kernel (nbclient + ipykernel), with checks on what it shows."""

from __future__ import annotations

import base64
import re
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

TOUR = Path(__file__).resolve().parents[2] / "docs" / "tour.ipynb"


@pytest.fixture(scope="module")
def executed(tmp_path_factory):
    """The tour run top to bottom in a fresh kernel, in an empty folder; cells by their tag."""
    folder = tmp_path_factory.mktemp("tour")
    nb = nbformat.read(TOUR, as_version=4)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code"), "commit the tour without outputs"
    nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(folder)}}).execute()  # raises on any error
    cells = {c.metadata["tags"][0]: c for c in nb.cells if c.cell_type == "code"}
    return cells, folder


def _data(cell, mime: str) -> str:
    for out in cell.outputs:
        if out.get("output_type") in ("execute_result", "display_data") and mime in out.get("data", {}):
            return out["data"][mime]
    raise AssertionError(f"no {mime} output in cell {cell.metadata['tags']}: {cell.outputs}")


def test_tour_runs_and_every_result_displays(executed):
    cells, folder = executed
    assert not [o for c in cells.values() for o in c.outputs if o.get("output_type") == "error"]
    stderr = [line for c in cells.values() for o in c.outputs if o.get("name") == "stderr"
              for line in o["text"].splitlines()]
    assert all(line.startswith("springchain: ") for line in stderr), stderr  # progress only, no warnings
    assert "Scene('seed'" in _data(cells["load"], "text/plain")
    latex = _data(cells["modes"], "text/latex")
    assert latex.lstrip().startswith("\\begin{align*}") and "\\omega^2" in latex and "\\mathbf{K}" in latex
    assert "[0, k/m, 5*k/(3*m)]" in _data(cells["omega2"], "text/plain")
    changed = _data(cells["change"], "text/plain")
    assert re.search(r"0\.\s+,\s+4\.\s+,\s+6\.6666666", changed), changed
    page = _data(cells["simulate"], "text/html")
    assert "<table" in page and "max |x − x_exact|" in page
    png = re.search(r'data:image/png;base64,([A-Za-z0-9+/=]+)', page).group(1)
    assert base64.b64decode(png).startswith(b"\x89PNG")
    assert "x_modal" in _data(cells["xarray"], "text/plain") and "mass" in _data(cells["xarray"], "text/plain")
    error = float(_data(cells["error"], "text/plain"))
    assert 1e-3 < error < 1.0  # Verlet's phase error at k = 4, dt = 0.1 over 30 s: visible, bounded
    assert "ω_n [rad/s]" in _data(cells["frf"], "text/html")
    gif = re.search(r'data:image/gif;base64,([A-Za-z0-9+/=]+)', _data(cells["animate"], "text/html")).group(1)
    assert base64.b64decode(gif).startswith(b"GIF89a")
    assert (folder / "springchain-out" / "seed-mode2.gif").exists()
    assert "ω² mean" in _data(cells["sweep"], "text/html")
    assert "omega2" in _data(cells["pandas"], "text/html")
