"""Extended-precision references for the accurate-route tests, built from a scene's TOML text.

Nothing here calls springchain: a scene is read with ``tomllib`` (the tests write numbers, parameter
names and the few expression shapes listed in :func:`accuracy_scene_text`), every parameter becomes an exact
binary fraction, and K, C, M are assembled element by element in mpmath (never summed in float64).
Each reference is computed at ``dps`` and ``2·dps`` digits and the two must agree.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from fractions import Fraction

import mpmath
import numpy as np


def mpf(v) -> mpmath.mpf:
    """The exact value of a float (a binary fraction) at the current precision."""
    f = Fraction(float(v))
    return mpmath.mpf(f.numerator) / f.denominator


# -- scene text ----------------------------------------------------------------------------------------
def accuracy_scene_text(name: str, masses: list[float], springs: list[tuple], dampers: list[tuple] = (), *,
               gravity: float | None = None, force: tuple | None = None, ground: tuple | None = None,
               rayleigh: tuple | None = None, modal: float | None = None, x0=None, v0=None,
               dt: float = 0.1, steps: int = 10) -> str:
    """TOML of a ``[masses]`` scene with numeric parameters.

    springs, dampers : list of (end, end, value); an end is a mass index or -1 (a wall).
    gravity : g;  force : (mass, F1, F0, W) for ``F1 + F0*cos(W*t)``;  ground : (A0, A, W) for
    ``A0 + A*sin(W*t)``;  rayleigh : (alpha, beta);  modal : one ratio for every mode.
    """
    p = {f"m{i}": v for i, v in enumerate(masses)}
    p.update({f"k{j}": s[2] for j, s in enumerate(springs)})
    p.update({f"c{j}": d[2] for j, d in enumerate(dampers)})
    if gravity is not None:
        p["g"] = gravity
    if force is not None:
        p.update(F1=force[1], F0=force[2], W=force[3])
    if ground is not None:
        p.update(A0=ground[0], A=ground[1], Wg=ground[2])
    if rayleigh is not None:
        p.update(alpha=rayleigh[0], beta=rayleigh[1])
    end = lambda e: "wall" if e < 0 else f"x{e}"  # noqa: E731
    lines = [f'name = "{name}"', 'description = "accuracy test"', "", "[parameters]"]
    lines += [f"{k} = {float(v)!r}" for k, v in p.items()]
    lines += ["", "[masses]"] + [f'x{i} = "m{i}"' for i in range(len(masses))]
    for j, (a, b, _) in enumerate(springs):
        lines += ["", "[[springs]]", f'between = ["{end(a)}", "{end(b)}"]', f'k = "k{j}"']
    for j, (a, b, _) in enumerate(dampers):
        lines += ["", "[[dampers]]", f'between = ["{end(a)}", "{end(b)}"]', f'c = "c{j}"']
    if force is not None:
        lines += ["", "[[forces]]", f'on = "x{force[0]}"', 'f = "F1 + F0*cos(W*t)"']
    if ground is not None:
        lines += ["", "[ground]", 'acceleration = "A0 + A*sin(Wg*t)"']
    if rayleigh is not None:
        lines += ["", "[damping]", 'rayleigh = ["alpha", "beta"]']
    if modal is not None:
        lines += ["", "[damping]", f"modal = {float(modal)!r}"]
    if gravity is not None:
        lines += ["", "[gravity]", 'g = "g"']
    n = len(masses)
    x0 = [0.0] * n if x0 is None else x0
    v0 = [0.0] * n if v0 is None else v0
    lines += ["", "[initial]", f"x = [{', '.join(repr(float(v)) for v in x0)}]",
              f"v = [{', '.join(repr(float(v)) for v in v0)}]",
              "", "[simulation]", f"dt = {float(dt)!r}", f"steps = {int(steps)}"]
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class Scene:
    """What the references need, read back from the TOML text (values as floats; exact when used)."""

    names: list
    masses: list
    springs: list  # (a, b, k), -1 = wall
    dampers: list  # (a, b, c)
    params: dict
    data: dict

    @property
    def n(self) -> int:
        return len(self.masses)


def read(text: str) -> Scene:
    data = tomllib.loads(text)
    p = data["parameters"]
    names = list(data["masses"])
    idx = lambda e: -1 if e == "wall" else names.index(e)  # noqa: E731
    masses = [float(p[v]) for v in data["masses"].values()]
    springs = [(idx(s["between"][0]), idx(s["between"][1]), float(p[s["k"]])) for s in data.get("springs", [])]
    dampers = [(idx(s["between"][0]), idx(s["between"][1]), float(p[s["c"]])) for s in data.get("dampers", [])]
    return Scene(names, masses, springs, dampers, p, data)


def _stamp(n: int, elements: list) -> mpmath.matrix:
    A = mpmath.zeros(n, n)
    for a, b, v in elements:
        for i, si in ((a, 1), (b, -1)):
            for j, sj in ((a, 1), (b, -1)):
                if i >= 0 and j >= 0:
                    A[i, j] += si * sj * mpf(v)
    return A


def _damping(sc: Scene) -> mpmath.matrix:
    """C at the current precision: dashpots, Rayleigh α M + β K, modal M Φ diag(2ζω) Φᵀ M."""
    n = sc.n
    C = _stamp(n, sc.dampers)
    damping = sc.data.get("damping", {})
    if "rayleigh" in damping:
        alpha, beta = (mpf(sc.params[k]) for k in damping["rayleigh"])
        K = _stamp(n, sc.springs)
        for i in range(n):
            for j in range(n):
                C[i, j] += beta * K[i, j] + (alpha * mpf(sc.masses[i]) if i == j else 0)
    if "modal" in damping:
        zeta = mpf(damping["modal"])
        r = [1 / mpmath.sqrt(mpf(m)) for m in sc.masses]
        K = _stamp(n, sc.springs)
        D = mpmath.matrix(n, n)
        for i in range(n):
            for j in range(n):
                D[i, j] = K[i, j] * r[i] * r[j]
        w2, E = mpmath.eigsy(D)
        for j in range(n):
            g = 2 * zeta * mpmath.sqrt(max(w2[j], 0))
            mphi = [E[i, j] / r[i] for i in range(n)]  # M φ with φ = M^-1/2 e
            for a in range(n):
                for b in range(n):
                    C[a, b] += g * mphi[a] * mphi[b]
    return C


def _twice(fn, dps: int, rel: float = 1e-25):
    a, b = np.asarray(fn(dps)), np.asarray(fn(2 * dps))
    scale = np.max(np.abs(b)) if np.size(b) else 0.0
    # both are rounded to float64 at the end: a value next to a rounding boundary may differ by an ulp
    ok = np.abs(a - b) <= rel * max(scale, 1e-300) + 2 * np.finfo(float).eps * np.abs(b)
    assert np.all(ok), "reference did not settle"
    return b


def _settled(fn, dps: int, rel: float, floor: float, top: int = 1000):
    """``fn(d)`` at doubling precision until two successive results agree element by element to
    ``rel`` relative (or ``floor`` absolute: values that are noise at every precision, an exact 0):
    a small value computed beside large ones (ζ = 1e-38 next to |λ| = 3e11) needs more digits than
    its neighbours, so one fixed doubling is not enough."""
    a = np.asarray(fn(dps))
    while True:
        dps *= 2
        b = np.asarray(fn(dps))
        if a.shape == b.shape and np.all(np.abs(a - b) <= rel * np.abs(b) + floor + 2 * np.finfo(float).eps * np.abs(b)):
            return b
        assert dps <= top, "reference did not settle"
        a = b


# -- references ---------------------------------------------------------------------------------------
def receptance(sc: Scene, omega, i: int, o: int, dps: int = 60) -> np.ndarray:
    """H(iω) = X_o / F_i by Gaussian elimination on Z = K − ω²M + iωC assembled exactly."""
    def at(d):
        with mpmath.workdps(d):
            K, C = _stamp(sc.n, sc.springs), _damping(sc)
            out = []
            for w in np.asarray(omega, dtype=float).tolist():
                W = mpf(w)
                Z = mpmath.matrix(sc.n, sc.n)
                for a in range(sc.n):
                    for b in range(sc.n):
                        Z[a, b] = K[a, b] + 1j * W * C[a, b] - (W * W * mpf(sc.masses[a]) if a == b else 0)
                F = mpmath.matrix(sc.n, 1)
                F[i] = 1
                out.append(complex(mpmath.lu_solve(Z, F)[o]))
            return np.array(out)
    return _twice(at, dps)


def trajectory(sc: Scene, x0, v0, times, *, const=None, harmonics=(), dps: int = 50) -> np.ndarray:
    """x(t) (S, N) of ``M x'' + C x' + K x = const + Σ (Fc cos Ωt + Fs sin Ωt)``: ``z' = A z`` with A
    assembled exactly (oscillator states for the harmonics, a constant state), solved through A's
    eigen-decomposition in mpmath."""
    n = sc.n
    const = np.zeros(n) if const is None else np.asarray(const, dtype=float)

    def at(d):
        with mpmath.workdps(d):
            h = len(harmonics)
            size = 2 * n + 2 * h + 1
            K, C = _stamp(n, sc.springs), _damping(sc)
            A = mpmath.zeros(size, size)
            for i in range(n):
                mi = mpf(sc.masses[i])
                A[i, n + i] = 1
                for j in range(n):
                    A[n + i, j] = -K[i, j] / mi
                    A[n + i, n + j] = -C[i, j] / mi
                A[n + i, size - 1] = mpf(const[i]) / mi
            for j, (Om, Fc, Fs) in enumerate(harmonics):
                ci, si = 2 * n + 2 * j, 2 * n + 2 * j + 1
                for i in range(n):
                    A[n + i, ci] = mpf(Fc[i]) / mpf(sc.masses[i])
                    A[n + i, si] = mpf(Fs[i]) / mpf(sc.masses[i])
                A[ci, si] = -mpf(Om)
                A[si, ci] = mpf(Om)
            z0 = mpmath.matrix([mpf(v) for v in x0] + [mpf(v) for v in v0] + [1 - (k % 2) for k in range(2 * h)] + [1])
            # z(t) = V exp(Λt) V⁻¹ z0: A's eigenvalues are simple for these scenes (no rigid piece, no exact
            # resonance), and unlike a Taylor or Padé exp(A t) nothing of size exp(‖A‖t) ever cancels
            lam, V = mpmath.eig(A)
            c = mpmath.lu_solve(V, z0)
            out = []
            for t in np.asarray(times).tolist():
                T = mpf(t)
                e = [c[j] * mpmath.exp(lam[j] * T) for j in range(size)]
                out.append([float(mpmath.re(mpmath.fsum(V[i, j] * e[j] for j in range(size)))) for i in range(n)])
            return np.array(out)
    return _twice(at, dps, 1e-20)


def modal_trajectory(masses, springs, x0, v0, times, dps: int = 50) -> np.ndarray:
    """x(t) (S, N) of an undamped scene from mpmath's eigen-decomposition of D (assembled exactly)."""
    n = len(masses)

    def at(d):
        with mpmath.workdps(d):
            r = [1 / mpmath.sqrt(mpf(m)) for m in masses]
            K = _stamp(n, springs)
            D = mpmath.matrix(n, n)
            for i in range(n):
                for j in range(n):
                    D[i, j] = K[i, j] * r[i] * r[j]
            w2, E = mpmath.eigsy(D)
            y0 = [mpf(x0[i]) / r[i] for i in range(n)]
            p0 = [mpf(v0[i]) / r[i] for i in range(n)]
            q0 = [mpmath.fsum(E[i, j] * y0[i] for i in range(n)) for j in range(n)]
            p = [mpmath.fsum(E[i, j] * p0[i] for i in range(n)) for j in range(n)]
            w = [mpmath.sqrt(max(v, 0)) for v in w2]
            out = []
            for t in np.asarray(times).tolist():
                T = mpf(t)
                q = [q0[j] * mpmath.cos(w[j] * T) + p[j] * (mpmath.sin(w[j] * T) / w[j] if w[j] else T) for j in range(n)]
                out.append([float(r[i] * mpmath.fsum(E[i, j] * q[j] for j in range(n))) for i in range(n)])
            return np.array(out)
    return _twice(at, dps, 1e-20)


def damping_ratios(sc: Scene, dps: int = 60) -> np.ndarray:
    """ζ of the oscillatory eigenvalues of ``[[0, I], [−M⁻¹K, −M⁻¹C]]`` (exact), ascending |λ|."""
    n = sc.n

    def at(d):
        with mpmath.workdps(d):
            K, C = _stamp(n, sc.springs), _damping(sc)
            A = mpmath.zeros(2 * n, 2 * n)
            for i in range(n):
                A[i, n + i] = 1
                for j in range(n):
                    A[n + i, j] = -K[i, j] / mpf(sc.masses[i])
                    A[n + i, n + j] = -C[i, j] / mpf(sc.masses[i])
            lam = mpmath.eig(A, left=False, right=False)
            tiny = mpmath.mpf(10) ** (-d // 2) * max(abs(v) for v in lam)
            osc = sorted((v for v in lam if mpmath.im(v) > tiny), key=abs)
            return np.array([float(-mpmath.re(v) / abs(v)) for v in osc])
    # absolute floor 1e-100, far below the product's ZETA_FLOOR (1e-72) that the tests compare with
    return _settled(at, dps, 1e-20, 1e-100)
