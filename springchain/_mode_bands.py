"""``modes`` of a finite periodic chain named by band: each mode's band j and wavenumber q, or a gap mode
(edge or defect) with its localisation length — the route of ``springchain bands`` (:mod:`numeric.bands.finite`)
on the scene's own chain, added to the ``modes`` report.

Cost, and what is skipped:

* ``[masses]`` scenes have no unit cell: nothing is done (no period search, no module);
* a ``[chain]`` is periodic when its generated module has the band section (the period is found once, when the
  module is derived: a non-uniform chain's ``modes`` loads that module anyway, a uniform chain is periodic);
  ``[cell]`` scenes always are;
* the labels need the chain's full accurate spectrum (the spring-factor SVD, dense), so chains of more than
  :data:`MAX_MASSES` masses are not named (a note says where: ``springchain bands`` names up to 1200).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .derive.scene import Scene

#: Longest chain whose modes ``modes`` names by band (its dense spectrum: ~0.05 s at 200 masses).
MAX_MASSES = 200
#: The JSON fields each listed mode gains.
FIELDS = ("band", "q", "kind", "localisation_length", "bloch_weight")


@dataclass(frozen=True)
class ModeBands:
    """The modes of a periodic scene's finite chain named by band, ascending in ω².

    Attributes
    ----------
    p : int
        Masses per cell.
    labels : list of numeric.bands.finite.FiniteMode or None
        One per mode (None past :data:`MAX_MASSES` masses).
    note : str
    """

    p: int
    labels: list | None = field(repr=False)
    note: str = ""

    def records(self, records: list[dict], n: int, listed_each_end: int) -> list[dict]:
        """``records`` (the report's listed modes, ascending: all ``n``, or ``listed_each_end`` at each end) with the
        :data:`FIELDS` of their mode added (in place; returned)."""
        if self.labels is None:
            return records
        if len(records) == n:
            positions = range(n)
        elif len(records) == 2 * listed_each_end:
            positions = list(range(listed_each_end)) + list(range(n - listed_each_end, n))
        else:  # pragma: no cover - the reports list every mode or both ends
            return records
        for rec, pos in zip(records, positions):
            rec.update({k: v for k, v in self.labels[pos].as_json().items() if k in FIELDS})
        return records

    def text_lines(self, shown_each_end: int) -> list[str]:
        """The text report's section: every mode (up to ``2 * shown_each_end``, else both ends), its ω², then its
        band and q or its gap kind and localisation length."""
        if self.labels is None:
            return ["", f"note: {self.note}"] if self.note else []
        n = len(self.labels)
        shown = range(n) if n <= 2 * shown_each_end else \
            list(range(shown_each_end)) + list(range(n - shown_each_end, n))
        out = ["", f"Modes named by band (unit cell of {self.p} mass{'es' if self.p > 1 else ''}; its bands: "
                   "`springchain bands SCENE`): band j and q [rad per cell], or a gap mode decaying over its "
                   "localisation length [cells]:"]
        for pos in shown:
            m = self.labels[pos]
            head = f"    {pos:>4}  ω² = {m.omega2:<20.10g}"
            if m.kind == "band":
                out.append(f"{head} band {m.band}, q = {m.q:.10g}")
            else:
                length = m.localisation
                out.append(f"{head} {m.kind} mode in a gap, localisation length "
                           + ("infinite" if length is None else f"{length:.6g} cells"))
            if pos == shown_each_end - 1 and n > 2 * shown_each_end:
                out.append(f"    ... ({n - 2 * shown_each_end} more)")
        hidden = [g for g in self.gap_modes() if g["position"] not in shown]
        for g in hidden:
            length = g["localisation_length"]
            out.append(f"    {g['position']:>4}  ω² = {g['omega2']:<20.10g} {g['kind']} mode in a gap, localisation "
                       "length " + ("infinite" if length is None else f"{length:.6g} cells") + "  (among those not listed)")
        return out

    def gap_modes(self) -> list[dict]:
        """Every gap mode: ``position`` (in ascending ω²), ``omega2``, ``kind``, ``localisation_length`` (cells)."""
        return [{"position": k, "omega2": m.omega2, "kind": m.kind, "localisation_length": m.localisation}
                for k, m in enumerate(self.labels or ()) if m.kind != "band"]


def mode_bands(scene: Scene, uniform_chain: bool = False) -> ModeBands | None:
    """The band names of a periodic scene's modes; None for a scene without a unit cell.

    Parameters
    ----------
    scene : Scene
    uniform_chain : bool
        The scene is a uniform ``[chain]`` (periodic with one mass per cell: its module is loaded only to name
        its modes, past no size).
    """
    if scene.cell is None and scene.chain is None:
        return None
    too_long = scene.n > MAX_MASSES
    if too_long and (scene.cell is not None or uniform_chain):
        return ModeBands(0, None, _long(scene))
    from ._modules import system_of

    system, _ = system_of(scene)
    if not system.periodic:
        return None
    cell = system.band_cell()
    if too_long:
        return ModeBands(cell.p, None, _long(scene))
    from .numeric.bands.finite import label
    from .numeric.progress import phase

    ends = scene.chain.left if scene.chain is not None else scene.cell.left
    with phase(f"modes of {scene.name!r}: named by band"):
        spectrum = system.spectrum
        labels = label(cell, spectrum.omega2, spectrum.vectors, str(ends) == "ring")
    return ModeBands(cell.p, labels)


def _long(scene: Scene) -> str:
    from ._bands import FINITE_MAX

    return (f"modes are named by band up to {MAX_MASSES} masses ({scene.n} here): `springchain bands SCENE` "
            f"names every mode of chains up to {FINITE_MAX}")


__all__ = ["ModeBands", "mode_bands", "MAX_MASSES", "FIELDS"]
