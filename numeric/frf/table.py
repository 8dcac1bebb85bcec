"""The resonance table of a receptance: which modes H sees, and the true local maxima of |H|.

Three questions, each answered on an accurate route, never by a threshold on a float64 value alone:

1. **Is there any transfer?** Input and output on pieces no spring or dashpot joins have
   ``H ≡ 0`` (:func:`connected`; Rayleigh damping couples where springs do, modal damping within
   a piece).
2. **Does H see an undamped mode?** (ζ = 0 exactly: no dampers, or a mode they do not touch.) H
   has a pole at ω_j with the residue ``R = Σ φ_out φ_in`` over the undamped subspace at ω_j (a
   repeated ω sums its modes; the sum does not depend on the basis). ``R = 0`` — a node at the
   input or the output — leaves |H| finite at ω_j (:func:`sees`). A float64 residue below
   :data:`NODE_SUSPECT` of the subspace's projector's largest diagonal entry is settled in mpmath
   (scenes of at most :data:`SETTLE_MAX` masses) at doubling precision: a true residue settles
   however small it is (1e-68 of the scale beside a mass ratio of 1e34), the noise around an exact
   node keeps falling (:func:`_mp_sees`). Larger scenes judge by the float64 residue against
   :data:`NODE_FLOAT` (said in a note); scenes past :data:`SHAPES_MAX` masses are not checked.
3. **Where are the peaks?** Every interior local maximum of |H| on the (resonance-refined) grid
   is bracketed by its two neighbours and maximised by a bounded Brent search on the certified
   route's float64 solve (each trial one solve), its value then certified (:func:`local_maxima`);
   brackets holding an undamped ω_j (|H| = ∞) are skipped. Each maximum is attributed to the
   nearest damped resonance (in log ω); a resonance keeps the nearest of its maxima. A
   resonance without one says so (masked by a neighbouring mode, or damped out); maxima not
   attributed are listed apart. A lightly damped mode near another may have its peak shifted
   far from ω_d, or none at all: the table says which, never a point that is not a maximum.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: A float64 residue below this fraction of the subspace's largest component² is settled in mpmath.
NODE_SUSPECT = 1e-4
#: Largest scene whose suspected nodes are settled in mpmath (a few ``eigsy`` at rising precision).
SETTLE_MAX = 60
#: Without mpmath (scenes past :data:`SETTLE_MAX`): a residue below this fraction is a node (a true
#: residue of 5e-10 of the scale occurs on a 30-mass chain at a stiffness contrast of 1e8).
NODE_FLOAT = 1e-12
#: A residue below this fraction of the scale is no resonance float64 can show (|H| would pass 1e308 only
#: within that fraction of ω_n, which no float64 frequency resolves): reported as a node. A true residue of
#: 1e-330 arises on six masses with a mass contrast of 1e33 (the coupling falls by the contrast per mass).
VISIBLE = 1e-300
#: Digits at which a residue is compared with :data:`VISIBLE` (its noise then far below it).
VISIBLE_DPS = 360
#: Largest scene whose mode shapes are computed to check nodes (spring-factor SVD, O(N³)).
SHAPES_MAX = 400
#: Two ω within this relative distance are one repeated frequency (their residues add; the accurate
#: spectrum gives a symmetry's repeated ω equal to ~1e-15, and two modes 6e-9 apart are two poles).
REPEATED = 1e-12
#: Below this ζ (> 0) a peak is narrower than float64 resolves in ω (relative width 2ζ): not located.
NARROW_ZETA = 1e-12
#: A grid maximum counts when it beats both neighbours by more than this (relative; the certified
#: values are good to 1e-11, so rounding cannot make one).
SIGNIFICANT = 1e-9
#: A found maximum is checked with certified values these fractions of its bracket to each side.
VERIFY = (1e-3, 1e-6, 1e-9)
#: A grid maximum's bracket is narrowed until both its ends are at least this fraction of the top.
RESOLVED = 0.5
#: Certified values per narrowing step, and the most steps (each divides the bracket by ~8).
ZOOM_POINTS, ZOOM_STEPS = 18, 14
#: A peak is attributed to the resonance nearest it only within this factor of its ω_d.
ATTRIBUTE_FACTOR = 2.0
#: A peak farther than this many ζ from ω_d (relative) is reported as shifted.
SHIFT_ZETAS = 3.0


@dataclass(frozen=True)
class Resonance:
    """One mode's resonance: undamped ω_n, ratio ζ (NaN: not computed), damped ω_d; the local
    maximum of |H| attributed to it (None: none near it)."""

    omega_n: float
    zeta: float
    omega_d: float
    peak_omega: float | None = None
    peak_magnitude: float | None = None
    #: False for an undamped mode with a node at the input or the output (|H| finite at ω_n).
    participates: bool = True
    #: Modes sharing this (ω_n, ζ) (a repeated frequency: one resonance).
    multiplicity: int = 1

    @property
    def undamped(self) -> bool:
        """ζ = 0: a pole of H on the real ω axis (|H| = ∞ at ω_n when it participates)."""
        return self.zeta == 0

    @property
    def narrow(self) -> bool:
        """0 < ζ < :data:`NARROW_ZETA`: a peak narrower than float64 resolves in ω."""
        return 0 < self.zeta < NARROW_ZETA

    @property
    def singular(self) -> bool:
        """The grid keeps its distance from ω_n (undamped or narrow, and seen by H)."""
        return self.participates and (self.undamped or self.narrow)

    @property
    def searched(self) -> bool:
        """A resonance that a local maximum of |H| may be attributed to."""
        return self.participates and not self.undamped and not self.narrow and self.omega_d > 0

    @property
    def shift(self) -> float | None:
        """Relative distance of the peak from ω_d."""
        return None if self.peak_omega is None else self.peak_omega / self.omega_d - 1

    @property
    def shifted(self) -> bool:
        """The peak is farther from ω_d than :data:`SHIFT_ZETAS` ζ (neighbouring modes move it)."""
        s = self.shift
        return s is not None and not math.isnan(self.zeta) and abs(s) > max(SHIFT_ZETAS * self.zeta, 1e-3)

    def as_json(self) -> dict:
        return {"omega_n": self.omega_n, "zeta": None if np.isnan(self.zeta) else self.zeta, "omega_d": self.omega_d,
                "peak_omega": self.peak_omega, "peak_magnitude": self.peak_magnitude,
                "multiplicity": self.multiplicity}


# -- 1. transfer --------------------------------------------------------------------------------------
def connected(el, input: int, output: int) -> bool:
    """Whether a chain of springs and dashpots (nonzero) joins the input and output masses."""
    if input == output:
        return True
    from ..modes.spectrum import spring_components

    ends = [np.asarray(el.spring_ends, dtype=np.intp).reshape(-1, 2)[np.asarray(el.stiffness) != 0],
            np.asarray(el.damper_ends, dtype=np.intp).reshape(-1, 2)[np.asarray(el.damping) != 0]]
    _, labels = spring_components(el.n, np.concatenate(ends))
    return bool(labels[input] == labels[output])


# -- 2. nodes -----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Seen:
    """Which undamped modes H sees: ``flags`` per asked ω, and how nodes were judged (``how``:
    "mpmath", "float64" or "unchecked")."""

    flags: list
    how: str


def sees(el, omega: list[float], input: int, output: int) -> Seen:
    """For each undamped (or narrow) ω_j of ``omega``: whether H(in → out) has a pole there.

    Parameters
    ----------
    el : numeric.modes.elements.Elements
    omega : list of float
        Elastic ω_j asked (each once per mode: a repeated ω appears as often as its multiplicity).
    """
    if not omega:
        return Seen([], "mpmath")
    if el.n > SHAPES_MAX:
        return Seen([True] * len(omega), "unchecked")
    from ..modes.elements import modal_damping
    from ..modes.spectrum import spectrum

    spec = spectrum(el.masses, el.spring_ends, el.stiffness)
    w, Phi = spec.omega, spec.shapes
    G = modal_damping(el, w, Phi) if el.damped else None
    clusters = []  # the asked ω grouped by repeated frequency: [representative, multiplicity]
    for wt in sorted(omega):
        if clusters and wt - clusters[-1][0] <= REPEATED * wt:
            clusters[-1][1] += 1
        else:
            clusters.append([wt, 1])
    rep = lambda wt: next(c[0] for c in reversed(clusters) if c[0] <= wt)  # noqa: E731
    flags, how = {}, "mpmath" if el.n <= SETTLE_MAX else "float64"
    for wt, count in clusters:
        group = np.flatnonzero(np.abs(w - wt) <= REPEATED * wt)
        if group.size == 0:
            group = np.array([int(np.argmin(np.abs(w - wt)))])
        basis = Phi[:, group]
        if G is not None and count < group.size:  # the undamped part of a repeated ω: G's null directions
            g = G[np.ix_(group, group)]
            _, vec = np.linalg.eigh(0.5 * (g + g.T))
            basis = basis @ vec[:, :count]
        residue = float(np.sum(basis[output] * basis[input]))
        scale = float(np.max(np.sum(basis**2, axis=1)))  # the projector's largest diagonal: basis-free
        seen = abs(residue) > NODE_SUSPECT * scale
        if not seen and how == "mpmath" and count == group.size:
            seen = _mp_sees(el, group, input, output)
        elif not seen:
            seen = abs(residue) > NODE_FLOAT * scale
        flags[wt] = seen
    return Seen([flags[rep(wt)] for wt in omega], how)


def _mp_sees(el, group: np.ndarray, input: int, output: int) -> bool:
    """The residue of the modes ``group`` (positions in ascending ω) settled in mpmath at d, 2d, 4d, …
    digits (d = 30 beyond the decades of the springs and masses): a true residue, however small,
    settles (two successive values agree to 1e-6); rounding noise around an exact node falls with
    the digits — a fall by more than 10^(p/2) from p to 2p digits, to below 10^-p, means a node (a
    true residue below ~10^-(1.5 d) of the scale would be taken for one); a residue below
    :data:`VISIBLE` of the scale (settled, or at :data:`VISIBLE_DPS` digits or more) is reported as a
    node too: no float64 frequency shows its resonance. Unsettled at
    :data:`frf_dense.MP_MAX_DPS` digits: seen (|H| = ∞ is then the claim)."""
    import mpmath

    from .dense import MP_MAX_DPS, mp_modes

    def decades(v):
        v = np.abs(np.asarray(v, dtype=float))
        v = v[v > 0]
        return math.log10(float(v.max() / v.min())) if v.size else 0.0

    def ratio(dps):
        with mpmath.workdps(dps):
            lam, shapes = mp_modes(el, mpmath)
            # the repeated frequency as this precision resolves it (two modes 1e-12 apart are two poles)
            centre = lam[int(group[0])]
            tol = mpmath.mpf(10) ** (-(dps // 2)) * abs(centre)
            near = [j for j in range(el.n) if abs(lam[j] - centre) <= tol]
            residue = mpmath.fsum(shapes[j][output] * shapes[j][input] for j in near)
            scale = max(mpmath.fsum(shapes[j][i] ** 2 for j in near) for i in range(el.n))
            return abs(residue) / scale

    dps = int(min(MP_MAX_DPS, 30 + math.ceil(decades(el.stiffness) + decades(el.masses))))
    a = ratio(dps)
    while dps < MP_MAX_DPS:
        prev, dps = dps, min(2 * dps, MP_MAX_DPS)
        b = ratio(dps)
        if b != 0 and abs(a - b) <= 1e-6 * b:  # settled: a true residue (below VISIBLE: none float64 shows)
            return bool(b >= VISIBLE)
        if b == 0 or (b < a * mpmath.mpf(10) ** (-(prev // 2)) and b < mpmath.mpf(10) ** (-(dps // 2))):
            return False  # noise falling with the digits: an exact node
        if dps >= VISIBLE_DPS and b < VISIBLE * mpmath.mpf(10) ** -30:  # settled or not, far below VISIBLE
            return False
        a = b
    return True


# -- 3. peaks -----------------------------------------------------------------------------------------
def local_maxima(solve, omega: np.ndarray, H: np.ndarray, poles: list[float]) -> list[tuple[float, complex]]:
    """The interior local maxima of |H| found from the grid, each refined by a bounded search.

    Parameters
    ----------
    solve : callable
        ``solve(w, certify)`` → H at the frequencies ``w`` (ndarray, shape (W,)); ``certify=False``
        for the search's trials.
    omega, H : ndarray, shape (W,)
        The grid and its certified H.
    poles : list of float
        ω_j where |H| = ∞ (a bracket holding one is skipped).

    Returns
    -------
    list of (ω, H)
        Ascending ω; H certified.
    """
    m = np.abs(np.asarray(H))
    if m.shape[0] < 3:
        return []
    poles = np.asarray(sorted(poles), dtype=float)
    out = []
    rise = np.flatnonzero(m[1:-1] > m[:-2] * (1 + SIGNIFICANT)) + 1
    for k in rise.tolist():
        j = k  # a flat top of equal values: bracket it whole
        while j + 1 < m.shape[0] and m[j + 1] == m[k]:
            j += 1
        if j + 1 >= m.shape[0] or not m[k] > m[j + 1] * (1 + SIGNIFICANT):
            continue
        a, b = float(omega[k - 1]), float(omega[j + 1])
        if poles.size and np.any((poles >= a) & (poles <= b)):
            continue
        a, b, best = _zoom(solve, a, b, (float(omega[k]), complex(H[k])))
        w, value = _maximise(solve, a, b, abs(best[1]), certify=False)
        if w is None or not _verified(solve, a, b, w, value):  # float64 trials misled the search
            w, value = _maximise(solve, a, b, abs(best[1]), certify=True)
        out.append((w, value) if w is not None and abs(value) > abs(best[1]) else best)  # else the best sample
    return out


def _zoom(solve, a: float, b: float, best: tuple[float, complex]) -> tuple[float, float, tuple[float, complex]]:
    """Narrow the bracket (a, b) of a grid maximum ``best = (ω, H)`` until the peak is resolved in it:
    certified values at :data:`ZOOM_POINTS` points across the bracket, then the bracket of their
    largest, until that largest no longer grows (by 1e-6) and both its neighbours are at least
    :data:`RESOLVED` of it — a peak far narrower than the grid spacing (ζ = 1e-9 between points 1e-4
    apart) is a needle no bounded search finds. At most :data:`ZOOM_STEPS` times. Returns the
    bracket and the best point sampled."""
    w, top = best[0], abs(best[1])
    for _ in range(ZOOM_STEPS):
        if b - a <= 64 * np.spacing(w):
            break
        inner = np.geomspace(a, b, ZOOM_POINTS)[1:-1] if a > 0 else np.linspace(a, b, ZOOM_POINTS)[1:-1]
        pts = np.union1d(np.union1d(inner, [w]), [a, b])
        H = solve(pts, True)
        h = np.abs(H)
        k = int(np.argmax(h[1:-1])) + 1
        if not h[k] >= top:
            break
        grew = h[k] > top * (1 + 1e-6)
        a, b, w, top = float(pts[k - 1]), float(pts[k + 1]), float(pts[k]), float(h[k])
        best = (w, complex(H[k]))
        if not grew and min(h[k - 1], h[k + 1]) >= RESOLVED * top:
            break
    return a, b, best


def _maximise(solve, a: float, b: float, top: float, certify: bool) -> tuple[float | None, complex]:
    """Brent's bounded search for the maximum of |H| on (a, b), in the bracket's own coordinate (its
    tolerance relative to b − a, not to ω); the value at the result certified. (None, 0) when the
    search ends on the bracket's edge."""
    from scipy.optimize import minimize_scalar

    def f(u):
        h = abs(solve(np.array([a + u * (b - a)]), certify)[0]) / top
        return -h if np.isfinite(h) else 0.0  # a trial float64 cannot evaluate counts as low
    sol = minimize_scalar(f, bounds=(0.0, 1.0), method="bounded", options={"xatol": 1e-12})
    w = a + float(sol.x) * (b - a)
    if not a < w < b:
        return None, 0j
    return w, complex(solve(np.array([w]), True)[0])


def _verified(solve, a: float, b: float, w: float, value: complex) -> bool:
    """The certified |H| at ``w ± h (b − a)`` for each h of :data:`VERIFY` (down to a few ulps of w) is
    below ``|value|``: a local maximum at every scale the bracket resolves."""
    h = np.array([v * (b - a) for v in VERIFY if v * (b - a) > 4 * np.spacing(w)])
    if not h.size:
        return True
    side = np.abs(solve(np.concatenate([np.maximum(w - h, a), np.minimum(w + h, b)]), True))
    return bool(np.all(side <= abs(value)))


def attribute(resonances: list[Resonance], peaks: list[tuple[float, float]]) -> tuple[list[Resonance], list]:
    """Each peak to the resonance nearest it in log ω, when that one is searched and within a factor
    :data:`ATTRIBUTE_FACTOR`; a resonance keeps its nearest peak.

    Returns the resonances (with ``peak_omega`` / ``peak_magnitude`` set or None) and the peaks not
    attributed, ascending.
    """
    marks = [j for j, r in enumerate(resonances) if r.omega_d > 0]
    best: dict[int, tuple[float, float, float]] = {}
    extra = []
    for w, h in peaks:
        dist = [abs(math.log(w / resonances[j].omega_d)) for j in marks]
        j = marks[int(np.argmin(dist))] if marks else -1
        d = min(dist, default=math.inf)
        if j < 0 or not resonances[j].searched or d > math.log(ATTRIBUTE_FACTOR):  # not a mode's own peak
            extra.append((w, h))
            continue
        if j in best:
            keep, drop = ((d, w, h), best[j]) if d < best[j][0] else (best[j], (d, w, h))
            best[j] = keep
            extra.append(drop[1:])
        else:
            best[j] = (d, w, h)
    out = []
    for j, r in enumerate(resonances):
        if r.searched:
            w, h = (best[j][1], best[j][2]) if j in best else (None, None)
            r = Resonance(r.omega_n, r.zeta, r.omega_d, w, h, r.participates, r.multiplicity)
        out.append(r)
    return out, sorted(extra)


__all__ = ["Resonance", "Seen", "connected", "sees", "local_maxima", "attribute", "NARROW_ZETA"]
