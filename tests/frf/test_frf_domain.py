"""The frequency response over the domain the loader accepts (issue 31): |H|, phase and the resonance table.

Every reference is built here from the values the test draws or writes by hand — never from
springchain: ``M``, ``K``, ``C`` assembled element by element in mpmath from the exact binary
values (springs and dashpots by their ends, Rayleigh ``αM + βK``, modal ``M Φ diag(2ζω) Φᵀ M``
from ``mpmath.eigsy``), then ``(K − ω²M + iωC) X = F`` solved by ``mpmath.lu_solve`` at 50 digits
beyond the decades the values span, and again at twice that (the two must agree).

The properties: |H| within :data:`MAG_REL` (relative) and the phase within :data:`PHASE_ABS`
(radians) of the reference at grid points near every resonance and elsewhere; every listed
peak a local maximum of the reference |H|; every mode said to have a node at the input or output
one where the reference |H| stays finite at ω_j; every "|H| = ∞" a pole of the reference; ``H ≡ 0``
said exactly when the reference is 0 — or a one-line refusal naming the float64 limit. Scenes are
drawn by hypothesis (2–6 masses; chains, rings, walls, free pieces, extra springs; dashpots,
Rayleigh, modal damping; values over up to the whole 1e-150 … 1e150 range); the slow variant
draws more.
"""

from __future__ import annotations

import math
import os
import warnings
from dataclasses import dataclass
from fractions import Fraction

import mpmath
import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import springchain as sc
from helpers import SLOW_BUDGET

#: |H| relative to the reference.
MAG_REL = 1e-10
#: Phase of H against the reference [rad].
PHASE_ABS = 1e-10
EXAMPLES = int(os.environ.get("SPRINGCHAIN_FRF_DOMAIN_EXAMPLES", "14"))


# -- the reference ---------------------------------------------------------------------------------------
def _mpf(v) -> mpmath.mpf:
    f = Fraction(float(v))
    return mpmath.mpf(f.numerator) / f.denominator


@dataclass(frozen=True)
class Case:
    """A ``[masses]`` scene as plain numbers: springs and dampers ``(a, b, value)``, -1 a wall."""

    masses: tuple
    springs: tuple
    dampers: tuple = ()
    rayleigh: tuple | None = None
    modal: tuple | None = None  # one ratio per mode (ascending ω), or one ratio for all
    #: A ``[chain]`` scene instead: (left, right, m0, m1, k0, k1) — masses and springs alternate between
    #: two values (exactly: ``m0*(1 - i % 2) + m1*(i % 2)``); ``masses``/``springs`` are then its elements.
    chain: tuple | None = None

    @classmethod
    def of_chain(cls, n: int, left: str, right: str, m0: float, m1: float, k0: float, k1: float,
                 dampers: tuple = (), rayleigh: tuple | None = None) -> "Case":
        """A chain's elements by hand: spring k(j) joins j and j+1, k(-1) the left wall, k(n-1) the right
        wall or (a ring) masses n-1 and 0."""
        m = lambda j: m1 if j % 2 else m0  # noqa: E731
        k = lambda j: k1 if j % 2 else k0  # noqa: E731
        springs = [(j, j + 1, k(j)) for j in range(n - 1)]
        springs += [(-1, 0, k(-1))] if left == "wall" else []
        springs += [(n - 1, -1, k(n - 1))] if right == "wall" else []
        springs += [(n - 1, 0, k(n - 1))] if left == "ring" else []
        return cls(tuple(m(j) for j in range(n)), tuple(springs), tuple(dampers), rayleigh, None,
                   (left, right, m0, m1, k0, k1))

    @property
    def n(self) -> int:
        return len(self.masses)

    def name(self, j: int) -> str:
        return str(j) if self.chain else f"x{j}"

    def values(self) -> list[float]:
        out = list(self.masses) + [s[2] for s in self.springs] + [d[2] for d in self.dampers]
        return [abs(v) for v in out if v != 0]

    def text(self, name: str = "dom") -> str:
        """The scene's TOML: every value a parameter written with repr (exact)."""
        if self.chain:
            return self._chain_text(name)
        p = {f"m{i}": v for i, v in enumerate(self.masses)}
        p.update({f"k{j}": s[2] for j, s in enumerate(self.springs)})
        p.update({f"c{j}": d[2] for j, d in enumerate(self.dampers)})
        end = lambda e: "wall" if e < 0 else f"x{e}"  # noqa: E731
        lines = [f'name = "{name}"', "[parameters]"] + [f"{k} = {float(v)!r}" for k, v in p.items()]
        lines += ["[masses]"] + [f'x{i} = "m{i}"' for i in range(self.n)]
        for j, (a, b, _) in enumerate(self.springs):
            lines += ["[[springs]]", f'between = ["{end(a)}", "{end(b)}"]', f'k = "k{j}"']
        for j, (a, b, _) in enumerate(self.dampers):
            lines += ["[[dampers]]", f'between = ["{end(a)}", "{end(b)}"]', f'c = "c{j}"']
        if self.rayleigh is not None:
            lines += ["[damping]", f"rayleigh = [{float(self.rayleigh[0])!r}, {float(self.rayleigh[1])!r}]"]
        if self.modal is not None:
            z = self.modal[0] if len(self.modal) == 1 else "[" + ", ".join(repr(float(v)) for v in self.modal) + "]"
            lines += ["[damping]", f"modal = {z}"]
        zeros = ", ".join(["0.0"] * self.n)
        lines += ["[initial]", f"x = [{zeros}]", f"v = [{zeros}]", "[simulation]", "dt = 0.1", "steps = 10"]
        return "\n".join(lines) + "\n"


    def _chain_text(self, name: str) -> str:
        left, right, m0, m1, k0, k1 = self.chain
        p = {"m0": m0, "m1": m1, "k0": k0, "k1": k1}
        p.update({f"c{j}": d[2] for j, d in enumerate(self.dampers)})
        lines = [f'name = "{name}"', "[parameters]"] + [f"{k} = {float(v)!r}" for k, v in p.items()]
        lines += ["[chain]", f"n = {self.n}", 'mass = "m0*(1 - i % 2) + m1*(i % 2)"',
                  'k = "k0*(1 - i % 2) + k1*(i % 2)"', f'left = "{left}"', f'right = "{right}"']
        for j, (a, b, _) in enumerate(self.dampers):
            lines += ["[[dampers]]", f'between = [{a}, {b if b >= 0 else chr(34) + "wall" + chr(34)}]', f'c = "c{j}"']
        if self.rayleigh is not None:
            lines += ["[damping]", f"rayleigh = [{float(self.rayleigh[0])!r}, {float(self.rayleigh[1])!r}]"]
        return "\n".join(lines) + "\n"


def _digits(case: Case, omega: float = 1.0) -> int:
    v = case.values() + [omega * omega * m for m in case.masses] + [omega]
    v = [x for x in v if 0 < x < math.inf]
    return 50 + math.ceil(math.log10(max(v)) - math.log10(min(v)))


def _stamp(n: int, elements, scale=1) -> mpmath.matrix:
    A = mpmath.zeros(n, n)
    for a, b, v in elements:
        for i, si in ((a, 1), (b, -1)):
            for j, sj in ((a, 1), (b, -1)):
                if i >= 0 and j >= 0 and a != b:
                    A[i, j] += si * sj * _mpf(v) * scale
    return A


_MODES: dict = {}


def _modes(case: Case):
    """ω² ascending and M-orthonormal shapes (lists) at the current precision (once per case and precision)."""
    key = (case, mpmath.mp.dps)
    if key not in _MODES:
        if len(_MODES) > 32:
            _MODES.clear()
        _MODES[key] = _modes_at(case)
    return _MODES[key]


def _modes_at(case: Case):
    n = case.n
    r = [1 / mpmath.sqrt(_mpf(m)) for m in case.masses]
    K = _stamp(n, case.springs)
    D = mpmath.matrix(n, n)
    for i in range(n):
        for j in range(n):
            D[i, j] = K[i, j] * r[i] * r[j]
    lam, E = mpmath.eigsy(D)
    order = sorted(range(n), key=lambda j: lam[j])
    return [lam[j] for j in order], [[E[i, j] * r[i] for i in range(n)] for j in order]


def _free_pieces(case: Case) -> int:
    """Pieces joined by springs that no spring ties to a wall (each has one rigid mode)."""
    parent = list(range(case.n))

    def root(x):
        while parent[x] != x:
            x = parent[x]
        return x
    for a, b, _ in case.springs:
        if a >= 0 and b >= 0:
            parent[root(a)] = root(b)
    walled = {root(a if a >= 0 else b) for a, b, _ in case.springs if min(a, b) < 0}
    return len({root(x) for x in range(case.n)} - walled)


def _damping(case: Case) -> mpmath.matrix:
    n = case.n
    C = _stamp(n, case.dampers)
    if case.rayleigh is not None:
        a, b = (_mpf(v) for v in case.rayleigh)
        K = _stamp(n, case.springs)
        for i in range(n):
            for j in range(n):
                C[i, j] += b * K[i, j] + (a * _mpf(case.masses[i]) if i == j else 0)
    if case.modal is not None:
        lam, shapes = _modes(case)
        zeta = [case.modal[0]] * n if len(case.modal) == 1 else list(case.modal)
        rigid = _free_pieces(case)
        for j in range(rigid, n):  # rigid modes (one per free piece, the lowest) have ω = 0: no damping
            g = 2 * _mpf(zeta[j]) * mpmath.sqrt(max(lam[j], 0))
            mphi = [_mpf(case.masses[i]) * shapes[j][i] for i in range(n)]
            for a in range(n):
                for b in range(n):
                    C[a, b] += g * mphi[a] * mphi[b]
    return C


def reference(case: Case, omega, i: int, o: int, digits: int | None = None) -> np.ndarray:
    """H(iω) = X_o / F_i of ``(K − ω²M + iωC) X = e_i`` at ``d`` and ``2d`` digits (must agree)."""
    omega = [float(w) for w in np.atleast_1d(omega)]
    out = []
    for w in omega:
        d = digits or _digits(case, w)
        with mpmath.workdps(d):
            a = _solve(case, _mpf(w), i, o)
        while True:  # doubling until two precisions agree (modal damping's shapes may need more digits)
            d *= 2
            with mpmath.workdps(d):
                b = _solve(case, _mpf(w), i, o)
            if abs(a - b) <= mpmath.mpf(10) ** (-30) * abs(b) or (a == 0 and b == 0):
                break
            assert d < 4000, "reference did not settle"
            a = b
        out.append(complex(b))
    return np.array(out)


_MATRICES: dict = {}


def _matrices(case: Case):
    """K and C (dicts of nonzero entries) at the current precision, computed once per case and precision."""
    key = (case, mpmath.mp.dps)
    if key not in _MATRICES:
        if len(_MATRICES) > 64:
            _MATRICES.clear()
        K, C = _stamp(case.n, case.springs), _damping(case)
        _MATRICES[key] = tuple({(a, b): A[a, b] for a in range(case.n) for b in range(case.n) if A[a, b] != 0}
                               for A in (K, C))
    return _MATRICES[key]


def _solve(case: Case, w, i: int, o: int):
    """X_o of Z X = e_i by Gaussian elimination with partial pivoting on Z's nonzero entries only (a
    chain's Z is tridiagonal, a ring's has two corners: O(n) fill)."""
    n = case.n
    K, C = _matrices(case)
    rows = [dict() for _ in range(n)]
    for (a, b), v in K.items():
        rows[a][b] = rows[a].get(b, 0) + v
    for (a, b), v in C.items():
        rows[a][b] = rows[a].get(b, 0) + 1j * w * v
    for a in range(n):
        rows[a][a] = rows[a].get(a, 0) - w * w * _mpf(case.masses[a])
    rhs = [mpmath.mpc(0)] * n
    rhs[i] = mpmath.mpc(1)
    order = list(range(n))  # rows not yet used as pivots
    pivots = []
    for col in range(n):
        cand = [r for r in order if rows[r].get(col, 0) != 0]
        p = max(cand, key=lambda r: abs(rows[r][col]))
        order.remove(p)
        pivots.append((col, p))
        for r in cand:
            if r == p:
                continue
            f = rows[r][col] / rows[p][col]
            for c, v in rows[p].items():
                rows[r][c] = rows[r].get(c, 0) - f * v
            del rows[r][col]
            rhs[r] -= f * rhs[p]
    x = [mpmath.mpc(0)] * n
    for col, p in reversed(pivots):
        acc = rhs[p] - mpmath.fsum(v * x[c] for c, v in rows[p].items() if c != col)
        x[col] = acc / rows[p][col]
    return x[o]


# -- the checks -----------------------------------------------------------------------------------------
def _connected(case: Case, i: int, o: int) -> bool:
    parent = list(range(case.n))

    def root(x):
        while parent[x] != x:
            x = parent[x]
        return x
    for a, b, _ in list(case.springs) + list(case.dampers):
        if a >= 0 and b >= 0:
            parent[root(a)] = root(b)
    return root(i) == root(o)


def _errors(H: np.ndarray, ref: np.ndarray, angle: np.ndarray | None = None) -> tuple[float, float]:
    """Worst |H| relative error and worst phase error [rad] (points where the reference is nonzero).

    A reference below the smallest normal float64 (a subnormal: digits lost) must be printed as 0 (the
    response says so in a note); its phase is still checked, from ``angle`` (the response's arg H)."""
    nz = ref != 0
    normal = np.abs(ref) >= np.finfo(float).tiny
    assert np.all(H[nz & ~normal] == 0), "|H| below the float64 range must be printed as 0"
    mag = np.abs(np.abs(H[normal]) / np.abs(ref[normal]) - 1)
    arg = np.angle(H) if angle is None else angle
    ph = np.abs(np.angle(np.exp(1j * (arg[nz] - np.angle(ref[nz])))))
    return float(np.max(mag, initial=0.0)), float(np.max(ph, initial=0.0))


def _picked(r, count: int = 10) -> np.ndarray:
    """Grid indices: spread over the range, and on both sides of every resonance and peak."""
    w = r.omega
    idx = set(np.linspace(0, w.shape[0] - 1, count).round().astype(int).tolist())
    for res in r.resonances:
        for target in (res.omega_d, res.peak_omega):
            if target:
                k = int(np.searchsorted(w, target))
                idx.update(j for j in (k - 1, k, k + 1) if 0 <= j < w.shape[0])
    return np.array(sorted(idx))


def _frf(tmp_path, case: Case, i: int, o: int, **kw):
    """``springchain.frf`` on the case's TOML, any warning an error (none may leak to the user)."""
    path = tmp_path / "dom.toml"
    path.write_text(case.text())
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return sc.frf(path, input=case.name(i), output=case.name(o), transfer=False, **kw)


def check_case(tmp_path, case: Case, i: int, o: int, points: int = 60) -> dict:
    """Run frf on ``case`` and check every number and claim against the reference; return the errors."""
    try:
        r = _frf(tmp_path, case, i, o, points=points)
    except sc.RunRefused as exc:  # allowed only as one line naming the float64 limit
        msg = str(exc)
        assert "\n" not in msg and ("float64" in msg or "digits" in msg), msg
        return {"refused": msg}
    text = r.to_text()
    if not _connected(case, i, o):
        assert not r.connected and np.all(r.H == 0) and not r.resonances
        assert "no transfer" in text and "∞" not in text and "peak" not in text
        assert np.all(reference(case, r.omega[::max(1, r.omega.shape[0] // 3)], i, o) == 0)
        return {"mag": 0.0, "phase": 0.0}
    assert r.connected and "no transfer" not in text
    idx = _picked(r)
    ref = reference(case, r.omega[idx], i, o)
    mag, ph = _errors(r.H[idx], ref, np.radians(r.phase[idx]))
    stated = _stated_bound(r)
    assert mag <= max(MAG_REL, stated) and ph <= max(PHASE_ABS, stated), (
        mag, ph, r.omega[idx][np.argmax(np.abs(np.abs(r.H[idx]) / np.abs(ref) - 1))])
    if stated > MAG_REL:  # the float64 limit said: each listed peak's |H| within the bound said, no more
        for w, h in [(res.peak_omega, res.peak_magnitude) for res in r.resonances if res.peak_omega] + r.extra_peaks:
            assert abs(h / abs(reference(case, [w], i, o)[0]) - 1) <= stated
        return {"mag": mag, "phase": ph, "stated": stated}
    _check_peaks(case, r, i, o)
    _check_poles_and_nodes(case, r, i, o)
    return {"mag": mag, "phase": ph}


def _stated_bound(r) -> float:
    """The relative error the response says its values near resonances may have (its note naming the
    float64 limit of a long chain's sweep past the extended-precision budget), or 0."""
    import re

    for note in r.notes:
        hit = re.match(r"H near resonances is certified to (\S+) relative only", note)
        if hit:
            return float(hit.group(1))
    return 0.0


def _check_peaks(case: Case, r, i: int, o: int) -> None:
    """Every listed peak is a local maximum of the reference |H| — no higher value at ω (1 ± δ) for δ
    from 1e-6 to 1e-2 of the peak's ζ (within the values' 1e-11) — and its value is right."""
    listed = [(res.peak_omega, res.peak_magnitude, res.zeta) for res in r.resonances if res.peak_omega is not None]
    zmin = min((res.zeta for res in r.resonances if res.zeta > 0 and not math.isnan(res.zeta)), default=1e-3)
    listed += [(w, h, zmin) for w, h in r.extra_peaks]
    marks = sorted([w for w, _, _ in listed] + [res.omega_d for res in r.resonances])
    for wp, hp, zeta in listed:
        scale = zeta if zeta > 0 and not math.isnan(zeta) else 1e-3
        gap = min((abs(w / wp - 1) for w in marks if w != wp), default=1.0)  # stay clear of other peaks
        deltas = [f * scale for f in (1e-6, 1e-4, 1e-2) if f * scale < gap / 2 and f * scale > 1e-14]
        ws = [wp] + [wp * (1 + s * d) for d in deltas for s in (-1, 1)]
        at = np.abs(reference(case, ws, i, o))
        assert abs(hp / at[0] - 1) <= MAG_REL
        assert np.all(at[1:] <= at[0] * (1 + 1e-11)), ("not a local maximum", wp, deltas, at)


def _residue(case: Case, w: float, i: int, o: int, dps: int):
    """``|Σ φ_o φ_i| / max_p Σ φ_p²`` over the modes at ω = w (a repeated ω: all of them; both sums do not
    depend on the basis chosen inside it), at ``dps`` digits."""
    with mpmath.workdps(dps):
        lam, shapes = _modes(case)
        wj = _mpf(w) ** 2
        j = min(range(case.n), key=lambda q: abs(lam[q] - wj))
        tol = mpmath.mpf(10) ** (-dps // 2) * abs(lam[j])
        group = [q for q in range(case.n) if abs(lam[q] - lam[j]) <= tol]
        residue = mpmath.fsum(shapes[q][o] * shapes[q][i] for q in group)
        return abs(residue) / max(mpmath.fsum(shapes[q][p] ** 2 for q in group) for p in range(case.n))


def _check_poles_and_nodes(case: Case, r, i: int, o: int) -> None:
    """Each undamped mode said to have a node at the input or output has the residue ``Σ φ_o φ_i`` (over
    its repeated ω) exactly 0 or below 1e-300 of the scale (no float64 frequency shows it), each said to
    give |H| = ∞ a nonzero one above that: the reference's own modes at
    d, 2d, 4d digits — a true residue is the same at the last two, an exact zero's noise falls by
    more than 10^d from 2d to 4d digits, to below 10^-2d."""
    claims = [(res.omega_n, res.participates) for res in r.resonances if res.undamped]
    for w, sees in claims:
        d = max(_digits(case) + 20, 120)  # 4d digits resolve residues far below 1e-300 of the scale
        got = [_residue(case, w, i, o, d * f) for f in (1, 2, 4)]
        settled = got[2] != 0 and abs(got[2] - got[1]) <= 1e-6 * got[2]
        zero = got[2] == 0 or (not settled and got[2] < got[1] * mpmath.mpf(10) ** (-d)
                               and got[2] < mpmath.mpf(10) ** (-2 * d))
        # a residue below 1e-300 of the scale is a resonance no float64 frequency shows: said as a node
        invisible = got[2] < mpmath.mpf("1e-300")
        assert settled or zero or invisible, ("reference residue unsettled", w, [mpmath.nstr(g, 5) for g in got])
        if sees:
            assert settled and not invisible, ("|H| = ∞ said, but a node", w, [mpmath.nstr(g, 5) for g in got])
        else:
            assert zero or invisible, ("a node said, but |H| = ∞", w, [mpmath.nstr(g, 5) for g in got])


# -- regressions: the findings -------------------------------------------------------------------
def _two(contrast: float) -> Case:
    """Two unit masses on a wall spring 1/√c and a link spring √c, a dashpot at the far mass."""
    s = math.sqrt(contrast)
    return Case((1.0, 1.0), ((-1, 0, 1 / s), (0, 1, s)), ((1, -1, 0.1),))


@pytest.mark.parametrize("contrast", [1e24, 1e30, 1e36, 1e60, 1e100, 1e200, 1e300])
def test_contrast_past_1e36_is_accurate(tmp_path, contrast):
    """Was "matrix is numerically singular" (mpmath's pivot test at 30 digits) from 1e36 up."""
    case = _two(contrast)
    for i, o in ((0, 1), (1, 1)):
        r = _frf(tmp_path, case, i, o, points=80)
        ref = reference(case, r.omega, i, o)
        mag, ph = _errors(r.H, ref, np.radians(r.phase))
        assert mag <= MAG_REL and ph <= PHASE_ABS, (mag, ph)


def test_node_at_the_output_of_a_damped_scene_is_no_resonance(tmp_path):
    """Three equal masses between two walls, a dashpot on the middle one: the antisymmetric mode
    (ω = √2) is undamped with a node at the middle mass. H(x1 → x1) is finite there; the table said
    "|H| = ∞". H(x0 → x2) sees it: |H| = ∞ is true there."""
    case = Case((1.0, 1.0, 1.0), ((-1, 0, 1.0), (0, 1, 1.0), (1, 2, 1.0), (2, -1, 1.0)), ((1, -1, 0.1),))
    r = _frf(tmp_path, case, 1, 1)
    node = [res for res in r.resonances if abs(res.omega_n - math.sqrt(2)) < 1e-9]
    assert len(node) == 1 and not node[0].participates
    assert "∞" not in r.to_text() and "node at the input or output" in r.to_text()
    _check_poles_and_nodes(case, r, 1, 1)
    r = _frf(tmp_path, case, 0, 2)
    assert [res.participates for res in r.resonances if res.undamped] == [True]
    _check_poles_and_nodes(case, r, 0, 2)
    check_case(tmp_path, case, 0, 1)


@pytest.mark.parametrize("damping", ["none", "dashpots", "rayleigh", "half"])
def test_unconnected_input_and_output_have_no_transfer(tmp_path, damping):
    """Two masses on their own wall springs: H ≡ 0. Was infinite resonances (or "peak |H| = 0") and a
    Bode figure with an empty log panel and a matplotlib warning."""
    dampers = {"dashpots": ((0, -1, 0.1), (1, -1, 0.1)), "half": ((0, -1, 0.1),)}.get(damping, ())
    case = Case((1.0, 2.0), ((-1, 0, 1.0), (1, -1, 3.0)), dampers, (0.01, 0.01) if damping == "rayleigh" else None)
    r = _frf(tmp_path, case, 0, 1)
    assert not r.connected and np.all(r.H == 0) and r.resonances == []
    text = r.to_text()
    assert "no transfer: input x0 and output x1 are not connected" in text
    assert "∞" not in text and "peak" not in text
    data = r.to_json()
    assert data["connected"] is False and data["resonances"] == [] and max(data["magnitude"]) == 0.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = r.plot()
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert any("H ≡ 0" in t for t in texts)
    import matplotlib.pyplot as plt

    plt.close(fig)
    assert np.all(reference(case, r.omega[::50], 0, 1) == 0)


def test_bode_of_zero_response_writes_without_warnings(tmp_path):
    case = Case((1.0, 1.0, 1.0), ((-1, 0, 1.0), (1, 2, 2.0)), ((2, -1, 0.3),))
    r = _frf(tmp_path, case, 0, 2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        path = r.save(tmp_path / "fig")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def _storeys(n: int, damping: str) -> Case:
    """A shear building: floors 1e4 kg, storeys 4e6 N/m; Rayleigh 5 % at modes 1 and 3 (α, β by hand from
    the undamped ω of the uniform chain, ω_j = 2√(k/m) sin((2j−1)π/(2(2n+1)))), or a base dashpot."""
    m, k = 1e4, 4e6
    springs = ((-1, 0, k),) + tuple((j, j + 1, k) for j in range(n - 1))
    if damping == "rayleigh":
        w1, w3 = (2 * math.sqrt(k / m) * math.sin((2 * j - 1) * math.pi / (2 * (2 * n + 1))) for j in (1, 3))
        alpha, beta = 2 * 0.05 * w1 * w3 / (w1 + w3), 2 * 0.05 / (w1 + w3)
        return Case((m,) * n, springs, (), (alpha, beta))
    return Case((m,) * n, springs, ((0, -1, 2e4),))


def _true_maxima(case: Case, lo: float, hi: float, i: int, o: int, count: int = 1500) -> list[float]:
    """Local maxima of the reference |H| on a log grid (fine: refined where found)."""
    w = np.geomspace(lo, hi, count)
    h = np.abs(reference(case, w, i, o, digits=40))
    k = np.flatnonzero((h[1:-1] > h[:-2]) & (h[1:-1] > h[2:])) + 1
    return w[k].tolist()


@pytest.mark.parametrize("io", [(0, 4), (1, 3), (0, 0), (4, 0)])
@pytest.mark.parametrize("damping", ["rayleigh", "base"])
def test_five_storey_peaks_are_the_local_maxima(tmp_path, io, damping):
    """Every listed peak (to a mode, or between modes) is a local maximum of the reference |H|, and every
    local maximum of the reference in range is listed (within the reference grid's spacing). Was: a far
    transfer's mode-5 "exact peak" that was no maximum (the true one 12.6 % away), one peak listed for
    two modes."""
    case = _storeys(5, damping)
    i, o = io
    r = _frf(tmp_path, case, i, o)
    listed = sorted([res.peak_omega for res in r.resonances if res.peak_omega is not None]
                    + [w for w, _ in r.extra_peaks])
    assert len(set(listed)) == len(listed)  # no peak listed twice
    _check_peaks(case, r, i, o)
    true = _true_maxima(case, r.omega[0], r.omega[-1], i, o)
    assert len(true) == len(listed), (true, listed)
    spacing = (r.omega[-1] / r.omega[0]) ** (1 / 1499) - 1
    for a, b in zip(true, listed):
        assert abs(b / a - 1) <= 1.5 * spacing
    for res in r.resonances:  # a peak is attributed to the nearest mode; a shifted one says so
        if res.peak_omega is not None and abs(res.shift) > max(3 * res.zeta, 1e-3):
            assert "% from ω_d" in r.to_text()


def test_damped_chain_zeta_is_that_of_modes(tmp_path):
    """A damped [chain] printed "ζ not computed" while `modes` computed it."""
    base = ('name = "dch"\n[parameters]\nm = 1.0\nk = 1.0\nc = 0.1\na = 0.01\nb = 0.01\n[chain]\nn = 5\nmass = "m"\n'
            'k = "k"\nleft = "wall"\nright = "free"\n')
    for extra in ('[[dampers]]\nbetween = [0, "wall"]\nc = "c"\n', '[damping]\nrayleigh = ["a", "b"]\n'):
        path = tmp_path / "dch.toml"
        path.write_text(base + extra)
        r = sc.frf(path, input=0, output=4)
        assert "not computed" not in r.to_text()
        modes = [m["damping_ratio"] for m in sc.modes(path).to_json()["modes"]]
        got = [res.zeta for res in r.resonances]
        assert len(got) == 5 and np.allclose(got, modes, rtol=1e-14, atol=0)
        # against the reference: the chain as a [masses] case, its peaks local maxima
        springs = ((-1, 0, 1.0),) + tuple((j, j + 1, 1.0) for j in range(4))
        case = Case((1.0,) * 5, springs, ((0, -1, 0.1),) if "dampers" in extra else (),
                    None if "dampers" in extra else (0.01, 0.01))
        idx = _picked(r)
        mag, ph = _errors(r.H[idx], reference(case, r.omega[idx], 0, 4), np.radians(r.phase[idx]))
        assert mag <= MAG_REL and ph <= PHASE_ABS
        _check_peaks(case, r, 0, 4)


# -- the domain ------------------------------------------------------------------------------------------
@st.composite
def cases(draw):
    """A [masses] scene of 2–6 masses over the accepted value range, with input and output masses."""
    n = draw(st.integers(2, 6))
    spread = draw(st.sampled_from([1.0, 6.0, 20.0, 75.0, 150.0]))
    centre = draw(st.floats(-150 + spread, 150 - spread)) if spread < 150 else 0.0
    val = lambda: float(f"{10.0 ** (centre + draw(st.floats(-spread, spread))):.6g}")  # noqa: E731
    masses = tuple(val() for _ in range(n))
    links = [(j, j + 1) for j in range(n - 1) if draw(st.floats(0, 1)) < 0.85]
    if n > 2 and draw(st.booleans()):
        links.append((0, n - 1))  # a ring
    if n > 2 and draw(st.booleans()):
        a, b = draw(st.sampled_from([(a, b) for a in range(n) for b in range(a + 2, n)]))
        links.append((a, b))
    walls = draw(st.lists(st.integers(0, n - 1), min_size=0, max_size=2))
    springs = tuple((a, b, val()) for a, b in links) + tuple((-1, a, val()) for a in walls)
    if not springs:
        springs = ((-1, 0, val()),)
    kind = draw(st.sampled_from(["none", "dashpots", "dashpots", "rayleigh", "modal", "modal_list", "both"]))
    dampers, rayleigh, modal = (), None, None
    if kind in ("dashpots", "both"):
        count = draw(st.integers(1, 2))
        dampers = tuple((draw(st.integers(0, n - 1)), draw(st.sampled_from([-1] + list(range(n)))), val())
                        for _ in range(count))
        dampers = tuple(d for d in dampers if d[0] != d[1]) or ((0, -1, val()),)
    if kind in ("rayleigh", "both"):
        alpha = draw(st.sampled_from([0.0, 1e-3, 0.05])) * 10 ** draw(st.floats(-3, 3))
        beta = draw(st.sampled_from([1e-3, 0.05])) * 10 ** draw(st.floats(-3, 3))
        w = math.sqrt(max(s[2] for s in springs) / min(masses))  # a β that damps the stiffest modes lightly
        rayleigh = (float(f"{alpha * math.sqrt(min(s[2] for s in springs) / max(masses)):.6g}"),
                    float(f"{beta / w:.6g}"))
    if kind == "modal":
        modal = (draw(st.sampled_from([1e-4, 0.01, 0.05, 0.3])),)
    if kind == "modal_list":
        modal = tuple(draw(st.sampled_from([0.0, 1e-3, 0.02, 0.2])) for _ in range(n))
        if not any(modal):
            modal = (0.02,) * n
    i, o = draw(st.integers(0, n - 1)), draw(st.integers(0, n - 1))
    return Case(masses, springs, dampers, rayleigh, modal), i, o


@st.composite
def chain_cases(draw, long: bool = False):
    """A [chain] of 3–8 masses (``long``: or 30, past the dense route) with two alternating masses and
    springs over the accepted range, walls, free ends or a ring, dashpots or Rayleigh damping."""
    n = draw(st.sampled_from([3, 4, 5, 6, 8] + [30] * long))
    spread = draw(st.sampled_from([1.0, 6.0, 30.0, 75.0]))
    centre = draw(st.floats(-150 + spread, 150 - spread))
    val = lambda: float(f"{10.0 ** (centre + draw(st.floats(-spread, spread))):.6g}")  # noqa: E731
    ends = draw(st.sampled_from([("free", "free"), ("wall", "free"), ("free", "wall"), ("wall", "wall"),
                                 ("ring", "ring")]))
    m0, m1, k0, k1 = val(), val(), val(), val()
    kind = draw(st.sampled_from(["none", "dashpots", "rayleigh"]))
    dampers, rayleigh = (), None
    if kind == "dashpots":
        picks = draw(st.lists(st.integers(0, n - 1), min_size=1, max_size=2, unique=True))
        beside = lambda j: (j + 1) % n if ends[0] == "ring" else (j + 1 if j + 1 < n else j - 1)  # noqa: E731
        dampers = tuple((j, draw(st.sampled_from([-1, beside(j)])), val()) for j in picks)
    if kind == "rayleigh":
        w_lo, w_hi = math.sqrt(min(k0, k1) / max(m0, m1)), math.sqrt(max(k0, k1) / min(m0, m1))
        rayleigh = (float(f"{0.02 * w_lo * 10 ** draw(st.floats(-2, 1)):.6g}"),
                    float(f"{0.02 / w_hi * 10 ** draw(st.floats(-2, 1)):.6g}"))
    i, o = draw(st.integers(0, n - 1)), draw(st.integers(0, n - 1))
    return Case.of_chain(n, *ends, m0, m1, k0, k1, dampers, rayleigh), i, o


_FOUND = [  # failures the generator found in the frf's own code, kept as examples
    # peak search misled by float64 trials (a mass contrast of 1e68): a "peak" that was no maximum
    (Case((1.00023, 1.98747e+68, 1.00023, 1.00023, 0.316301), ((0, 1, 7.45003e-60), (1, 2, 2.77032e-16),
          (2, 3, 0.0478025), (3, 4, 1.00023), (0, 4, 1.00023)), ((0, -1, 1.00023),)), 1, 0),
    # OverflowError: the mpmath digit count from max/min of terms overflowing float64
    (Case((9.87143e-74, 1.25893, 1.0, 1.0, 1.0), ((0, 1, 54138.8), (1, 2, 6.32339e+145), (2, 3, 9.34231e-69),
          (3, 4, 6.14428e+113), (0, 4, 7.93194e-47)), ((0, 2, 4.53897e+143),), (8.61443e-38, 1.54386e-113)), 0, 0),
    # a true residue 1.6e-68 of the scale (mass ratio 1e34) called a node
    (Case((2.64881e-09, 3.33544e-43), ((0, 1, 2.64881e-29),)), 0, 0),
    # mpmath residue exactly 0 at the first precision, noise after: "|H| = ∞" claimed for a node
    (Case((5.93497e+33, 1.0, 1.0, 1.0, 0.0794328), ((0, 1, 8.88601e-69), (2, 3, 172.057), (0, 4, 1.0),
          (-1, 1, 1e-150))), 3, 2),
    # ζ = 8e-12: the grid refined at 1e-4, the listed "peak" on the flank
    (Case((1.59804e-43, 5.05344e-43, 9.26971e-48, 1.76187e-48, 5.68892e-39, 5.05344e-43),
          ((0, 1, 5.05345e-43), (2, 3, 8.74446e-42), (3, 4, 5.05344e-43), (4, 5, 9.47286e-43), (0, 5, 4.9346e-48),
           (2, 4, 5.05344e-43)), ((0, -1, 5.05344e-43),)), 0, 0),
    # modal damping at 1e150 masses: sqrt of a negative ω² noise made derive's G complex (a traceback)
    (Case((1e+150, 0.00031239, 1e+150), ((0, 1, 7.23195e+42), (1, 2, 3.55223e+112), (0, 2, 8.06626e-42),
          (0, 2, 6.56135e+31), (-1, 2, 2.2446), (-1, 1, 2.69085e-12)), modal=(0.05,)), 2, 2),
    # chains: light modes (λ ~ 1e-11 beside 1) "rigid" in chain_damped, the sweep 2.4e-8 off at a peak
    (Case.of_chain(8, "wall", "free", 4.1251e+62, 1.30853e+41, 2.35359e-52, 1.30853e+41, ((4, -1, 1.30853e+41),)), 0, 0),
    # float64 trials 99.8 % off: the search ended on the bracket's edge, the grid point was listed
    (Case.of_chain(6, "wall", "wall", 3.04125e+58, 3.04125e+58, 0.373395, 1.09146e-67, (), (1.33351e-65, 5.70784e+27)),
     4, 2),
    # a needle peak (ζ ~ 1e-9) between grid points 1e-4 apart
    (Case.of_chain(5, "free", "wall", 4.29482e-122, 9.82889e-112, 2.08205e-115, 1.25741e-137,
                   ((4, -1, 1.19241e-125), (2, -1, 1.04299e-107))), 1, 0),
    # the zoom's best point dropped for the grid point
    (Case.of_chain(5, "free", "free", 6.43994e+30, 6.43994e+30, 1.46763e+58, 8.1811e+29, ((4, -1, 3.325e+41),)), 1, 3),
    # a dashpot between masses 2 and 0 of an open chain: refused by the dynamic-stiffness route
    (Case.of_chain(3, "free", "free", 3.66517e-115, 2.16919e-94, 1.28604e-91, 1.15903e-114,
                   ((2, 0, 7.5335e-100), (1, -1, 4.83339e-141))), 2, 1),
]
#: Found on 30-mass chains (the slow run): two modes 6e-9 apart grouped as one repeated ω (their residues
#: cancel: "a node" said at two poles); a real residue of 5e-10 of the scale judged a node in float64.
_FOUND_LONG = [
    (Case.of_chain(30, "free", "free", 1.0, 1.0, 1.52756e-05, 2493.5), 0, 0),
    (Case.of_chain(30, "free", "free", 2493.5, 1.0, 2493.5, 2493.5), 0, 0),
    # a light end mass (1e-33, 1e-60) on five unit masses: the coupling of its mode to mass 0 is 1e-330 of the
    # scale (a resonance no float64 ω shows, now a node); the reference's own digits did not reach it
    (Case((1.0, 1.0, 1.0, 1.0, 1.0, 1e-33), tuple((j, j + 1, 1.0) for j in range(5))), 0, 0),
    (Case((1.0, 1.0, 1.0, 1.0, 1.0, 1e-60), tuple((j, j + 1, 1.0) for j in range(5))), 0, 0),
    # a sub-chain's dynamic stiffness exactly 0 in float64 at a trial frequency: ZeroDivisionError in the
    # compiled sweep; and (ζ ~ 1e-18, past the mpmath budget) peaks 37 % off the stated-limit note covers
    (Case.of_chain(30, "wall", "free", 166.228, 8.51689e-57, 8.51689e-57, 2.06036e-102, ((6, 7, 4.96494e-74),)),
     27, 16),
    (Case.of_chain(30, "wall", "free", 166.228, 8.51689e-57, 8.51689e-57, 2.06036e-102, ((6, 7, 4.96494e-74),)),
     16, 16),
]


def _with_examples(found):
    def wrap(test):
        for case in found:
            test = example(drawn=case)(test)
        return test
    return wrap


@settings(max_examples=EXAMPLES)
@_with_examples(_FOUND)
@given(drawn=st.one_of(cases(), chain_cases()))
def test_frf_over_the_accepted_domain(tmp_path_factory, drawn):
    case, i, o = drawn
    check_case(tmp_path_factory.mktemp("dom"), case, i, o)


@pytest.mark.slow
@settings(max_examples=int(400 * SLOW_BUDGET))
@_with_examples(_FOUND + _FOUND_LONG)
@given(drawn=st.one_of(cases(), chain_cases(long=True)))
def test_frf_over_the_accepted_domain_exhaustive(tmp_path_factory, drawn):
    case, i, o = drawn
    check_case(tmp_path_factory.mktemp("dom"), case, i, o, points=120)
