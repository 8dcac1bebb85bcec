"""HTML for notebooks: small tables and embedded images (what ``_repr_html_`` returns).

Rendering only: each function returns a string (or PNG bytes); nothing is displayed or written.
Figures come from :mod:`numeric.plots.figures` (made without pyplot) and are embedded as base64 PNG.
"""

from __future__ import annotations

import base64
import html
import io
import math

#: Resolution of figures embedded in a notebook.
DPI = 80


def escape(text: object) -> str:
    return html.escape(str(text), quote=True)


def number(value, digits: int = 4) -> str:
    """A float in a table cell (``–`` for None, the word for NaN/∞)."""
    if value is None:
        return "–"
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("∞" if value > 0 else "−∞")
    if isinstance(value, int):
        return str(value)
    return f"{value:.{digits}g}"


def table(headers: list[str], rows: list[list], caption: str | None = None, bold_row: int | None = None) -> str:
    """An HTML table; cells are escaped text, ``bold_row`` (an index into rows) highlighted."""
    out = ['<table style="border-collapse:collapse;font-size:90%">']
    if caption:
        out.append(f'<caption style="text-align:left;font-weight:bold">{escape(caption)}</caption>')
    out.append("<thead><tr>" + "".join(f'<th style="text-align:right;padding:2px 8px">{escape(h)}</th>'
                                       for h in headers) + "</tr></thead><tbody>")
    for j, row in enumerate(rows):
        style = ' style="font-weight:bold"' if j == bold_row else ""
        out.append(f"<tr{style}>" + "".join(f'<td style="text-align:right;padding:2px 8px">{escape(c)}</td>'
                                            for c in row) + "</tr>")
    out.append("</tbody></table>")
    return "".join(out)


def figure_png(fig, dpi: int = DPI) -> bytes:
    """A matplotlib Figure as PNG bytes (its own Agg canvas: no pyplot, no backend switch), laid out
    once (:func:`numeric.plots.figures.lay_out`: the figure is for this picture only)."""
    from .figures import lay_out

    lay_out(fig, dpi)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def image(data: bytes, mime: str, alt: str) -> str:
    """An ``<img>`` with the image embedded (base64)."""
    b64 = base64.b64encode(data).decode("ascii")
    return f'<img src="data:{mime};base64,{b64}" alt="{escape(alt)}"/>'


def plan_table(plan) -> str:
    """A :class:`numeric.plan.planner.Plan` as the table ``springchain plan`` prints, the recommendation in bold."""
    ranked = sorted(plan.candidates, key=lambda c: c.predicted_seconds)
    rows = []
    for c in ranked:
        setting = f"{c.dt:.6g}" if c.dt is not None else (f"rtol {c.rtol:.2g}" if c.rtol is not None else "–")
        rows.append([c.name, setting, "–" if c.steps is None else c.steps, f"{c.predicted_error:.3e}",
                     f"{c.predicted_seconds:.3e}", c.model])
    for c in plan.unreachable:
        rows.append([c.name, "cannot reach", "–", f"{c.predicted_error:.2e}", "–", c.model or "floor"])
    best = next((j for j, c in enumerate(ranked) if c is plan.recommended), None)
    caption = (f"plan: largest position error ≤ {plan.tol:g} over t = 0 … {plan.t_end:g}; "
               f"recommended: {plan.recommended.name}")
    return table(["method", "dt / rtol", "steps", "predicted error", "predicted s", "model"], rows, caption, best)


__all__ = ["table", "image", "figure_png", "plan_table", "escape", "number"]
