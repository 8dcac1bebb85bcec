"""Scene text builders and 50+-digit mpmath references for the mode-accuracy tests.

The reference solves ``K φ = ω² M φ`` for the scene's parameter values (as exact
binary rationals) with ``mpmath.eigsy`` on ``D = M^-1/2 K M^-1/2`` at 60 digits,
re-solved at 120 digits and required to agree: independent of springchain's code.
"""

from __future__ import annotations

from fractions import Fraction

import mpmath
import numpy as np

from helpers import scene_toml


def modes_scene_text(name: str, masses: list[tuple[str, float]], stiff: list[tuple[str, float]],
               mass_of: list[str], springs: list[tuple[str, str, str]], x0=None, v0=None,
               dt: float = 0.01, steps: int = 10) -> str:
    """TOML of a scene: mass parameters, stiffness parameters, masses and springs.

    Parameters
    ----------
    name : str
    masses, stiff : list of (parameter name, value)
    mass_of : list of str
        Mass expression (a parameter name) of each mass ``x0, x1, ...``.
    springs : list of (end, end, stiffness parameter); an end is ``"wall"`` or a mass name.
    x0, v0 : list of float, optional
        Initial state (default: all 0.1, at rest).
    dt, steps : the ``[simulation]`` values.
    """
    n = len(mass_of)
    return scene_toml(name, dict(masses + stiff), description="accuracy test",
                      masses={f"x{i}": m for i, m in enumerate(mass_of)},
                      springs=[{"between": [a, b], "k": k} for a, b, k in springs],
                      initial={"x": [float(c) for c in ([0.1] * n if x0 is None else x0)],
                               "v": [float(c) for c in ([0.0] * n if v0 is None else v0)]},
                      simulation={"dt": float(dt), "steps": int(steps)})


def _mp(v):
    """An exact mpmath value of a float or a Fraction (exact products like 3*m stay exact)."""
    f = v if isinstance(v, Fraction) else Fraction(float(v))
    return mpmath.mpf(f.numerator) / f.denominator


def reference(masses: list[float], springs: list[tuple[int, int, float]], dps: int = 60):
    """ω² ascending and physical shapes (columns) at ``dps`` digits, checked at ``2*dps``.

    Parameters
    ----------
    masses : list of float
    springs : list of (int, int, float)
        Ends as mass indices (-1 = wall) and stiffness.

    Returns
    -------
    w2 : list of mpf
    shapes : mpmath matrix, physical shapes ``M^-1/2 e`` (M-orthonormal) as columns
    """
    out = []
    for d in (dps, 2 * dps):
        with mpmath.workdps(d):
            n = len(masses)
            r = [1 / mpmath.sqrt(_mp(m)) for m in masses]
            D = mpmath.zeros(n, n)
            for a, b, k in springs:
                for i, si in ((a, 1), (b, -1)):
                    for j, sj in ((a, 1), (b, -1)):
                        if i >= 0 and j >= 0:
                            D[i, j] += si * sj * _mp(k) * r[i] * r[j]
            w, E = mpmath.eigsy(D)
            order = sorted(range(n), key=lambda j: w[j])
            S = mpmath.matrix(n, n)
            for c, j in enumerate(order):
                for i in range(n):
                    S[i, c] = E[i, j] * r[i]
            out.append(([w[j] for j in order], S))
    (w1, S1), (w2, _) = out
    with mpmath.workdps(dps):
        top = max(abs(x) for x in w2) if w2 else 0
        for a, b in zip(w1, w2):  # the lower precision is converged wherever it is above its noise
            if abs(b) > top * mpmath.mpf(10) ** (8 - dps):
                assert abs(a - b) <= abs(b) * mpmath.mpf(10) ** (-30), "reference not converged"
    return w1, S1


def rel_err(values, ref, n_rigid: int) -> float:
    """Worst relative error of ``values`` against the reference ω² (rigid: must be exactly 0)."""
    values = np.asarray(values, dtype=float)
    assert values.shape == (len(ref),)
    worst = 0.0
    for j, (v, r) in enumerate(zip(sorted(values), ref)):
        if j < n_rigid:
            assert v == 0.0, f"rigid mode {j} is {v}, not exactly 0"
            continue
        worst = max(worst, float(abs(mpmath.mpf(float(v)) - r) / abs(r)))
    return worst


def shape_err(shapes, masses, ref_w2, ref_shapes, n_rigid: int) -> float:
    """Worst ``angle × relgap / 1e-13`` ratio is what callers bound; here: max over elastic modes
    of ``sin∠(φ, φ_ref)`` in the mass inner product times the relative gap to the nearest other ω²."""
    with mpmath.workdps(50):
        return _shape_err(np.asarray(shapes, dtype=float), masses, ref_w2, ref_shapes, n_rigid)


def _shape_err(shapes, masses, ref_w2, ref_shapes, n_rigid: int) -> float:
    n = len(masses)
    worst = 0.0
    sq = [mpmath.sqrt(_mp(m)) for m in masses]
    for j in range(n_rigid, n):
        gaps = [abs(ref_w2[j] - ref_w2[i]) / abs(ref_w2[j]) for i in range(n) if i != j]
        gap = min(gaps) if gaps else mpmath.mpf(1)
        if gap == 0:
            continue
        e_ref = [sq[i] * ref_shapes[i, j] for i in range(n)]
        nref = mpmath.sqrt(sum(x * x for x in e_ref))
        # the column of ``shapes`` closest to this reference (order may differ among equal values)
        best = None
        for c in range(shapes.shape[1]):
            e = [sq[i] * mpmath.mpf(float(shapes[i, c])) for i in range(n)]
            ne = mpmath.sqrt(sum(x * x for x in e))
            if ne == 0:
                continue
            cos = abs(sum(a * b for a, b in zip(e, e_ref))) / (ne * nref)
            sin = mpmath.sqrt(max(1 - cos * cos, 0))
            best = sin if best is None else min(best, sin)
        worst = max(worst, float(best * min(gap, 1)))
    return worst
