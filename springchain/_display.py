"""What a notebook shows for springchain's results: ``_repr_html_`` and ``_repr_png_`` bodies.

Figures are made without pyplot (:mod:`springchain.numeric.plots.figures`) and embedded as PNG; tables are
built by :mod:`springchain.numeric.plots.html`. Nothing here writes files or touches the user's backend.
"""

from __future__ import annotations

from .numeric.plots import html


def simulation_png(sim) -> bytes:
    """The positions figure of a Simulation."""
    return html.figure_png(sim.plot())


def simulation_table(sim) -> str:
    s = sim.summary
    conservative = s.get("energy_conserved", True)
    rows = []
    for name, rec in s.get("methods", {}).items():
        rows.append([name, f"{rec['seconds'] * 1e3:.3g}", html.number(rec.get("max_position_difference")),
                     html.number(rec.get("max_velocity_difference")), html.number(rec.get("energy_drift"))])
    energy = "max |E(t) − E(0)| [J]" + ("" if conservative else " (not conserved: damping/forcing)")
    caption = (f"{sim.scene.name}: {len(sim.t)} samples of {sim.scene.n} masses, dt = {s.get('dt', 0):g} s, "
               f"t_end = {s.get('t_end', 0):g} s (module: {s.get('module', '?')})")
    return html.table(["method", "ms", "max |x − x_exact| [m]", "max |v − v_exact| [m/s]", energy], rows, caption)


def simulation_html(sim, png: bytes | None = None) -> str:
    png = simulation_png(sim) if png is None else png
    return simulation_table(sim) + "<br/>" + html.image(png, "image/png", f"{sim.scene.name}: positions")


def simulation_bundle(sim) -> dict:
    """HTML and PNG from one drawing of the figure (IPython asks for every format it can show)."""
    png = simulation_png(sim)
    return {"text/html": simulation_html(sim, png), "image/png": png, "text/plain": repr(sim)}


def frf_png(h) -> bytes:
    return html.figure_png(h.plot())


def frf_bundle(h) -> dict:
    """HTML and PNG from one drawing of the Bode figure."""
    png = frf_png(h)
    return {"text/html": frf_html(h, png), "image/png": png, "text/plain": repr(h)}


def frf_html(h, png: bytes | None = None) -> str:
    rows = []
    for r in h.resonances:
        if not r.participates:
            continue
        peak = "∞ (undamped)" if r.undamped else (html.number(r.peak_magnitude) if r.peak_omega is not None else "–")
        rows.append([html.number(r.omega_n, 8), html.number(r.zeta), html.number(r.omega_d, 8),
                     html.number(r.peak_omega, 8), peak])
    table = html.table(["ω_n [rad/s]", "ζ", "ω_d [rad/s]", "peak at ω [rad/s]", "peak |H| [m/N]"], rows,
                       f"{h.scene.name}: receptance X_{h.output} / F_{h.input}, {len(h.omega)} frequencies "
                       f"{h.omega[0]:.4g} … {h.omega[-1]:.4g} rad/s")
    notes = "".join(f"<br/><i>note: {html.escape(n)}</i>" for n in h.notes)
    png = frf_png(h) if png is None else png
    return table + notes + "<br/>" + html.image(png, "image/png", f"{h.scene.name}: Bode figure")


def animation_html(a) -> str:
    from pathlib import Path

    data = Path(a.path).read_bytes()
    return (html.image(data, "image/gif", a.describe())
            + f"<br/><small>{html.escape(a.describe())} — {html.escape(a.path)}</small>")


def sweep_html(r) -> str:
    s = r.summary
    w2 = s["omega2"]
    modes = s["modes"]
    picked = list(range(modes)) if modes <= 20 else list(range(10)) + list(range(modes - 10, modes))
    q = w2["quantiles"]
    pr = s.get("participation_ratio", {}).get("mean")
    rows = []
    for j in picked:
        rows.append([j, html.number(w2["mean"][j]), html.number(w2["std"][j]),
                     *(html.number(q[k][j]) for k in sorted(q, key=float)), html.number(None if pr is None else pr[j])])
    run = r.run
    caption = (f"sweep of {s['scene']}: {s['samples']} samples × {modes} modes"
               + (" (10 lowest and 10 highest shown)" if modes > 20 else "")
               + f"; {run['computed']} batches computed, {run['skipped']} already done, {run['seconds']:.3g} s, "
               f"{run.get('scheduler', '')}; {r.out}")
    quant = [f"ω² q{float(k) * 100:g}%" for k in sorted(q, key=float)]
    return html.table(["mode", "ω² mean", "ω² std", *quant, "participation ratio (mean)"], rows, caption)


__all__ = ["simulation_html", "simulation_png", "simulation_bundle", "frf_html", "frf_png", "frf_bundle",
           "animation_html", "sweep_html"]
