"""The static equilibrium of springs that form a tree with the ground: statically determinate, spring by spring.

When the springs close no loop (every wall one node: a chain or a tree hung from one wall, free pieces), the
tension of each spring at equilibrium is fixed by the loads alone: ``t_s = ±Σ F_i`` over the masses beyond
it (the side away from the wall; for a free piece, away from its lowest-numbered mass), whatever the laws.
The loading path of :mod:`derive.equilibrium` (the loads and pre-stress applied gradually from rest)
then splits into one scalar path per spring,

    V_s'(d_s) = V_s'(0) + λ (t_s − V_s'(0)),   λ: 0 → 1,

followed from d_s = 0 in mpmath (predictor ``Δd = Δλ (t_s − V'(0)) / V''(d)``, Newton correctors that must
contract, the step halved otherwise) inside the spring's domain, with V''(d_s) > 0 along it (K = Σ V'' b bᵀ
of a tree is positive definite exactly when every V'' is). The positions are sums of extensions from the
wall (or from a free piece's root, then its centre of mass put back at 0), in mpmath: an extension of 1e-10
on a displacement of 1e13 — below float64's resolution of x — is as accurate as any other.
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath

#: Digits of the scalar paths; the result is polished by Newton at twice as many, and twice again, until two
#: precisions agree to AGREE in every extension and every V''(d) (near a pole, V'' rests on the few digits of
#: the distance to it), up to MAX_DPS.
DPS = 50
MAX_DPS = 1600
AGREE = mpmath.mpf(10) ** -20
FLOOR = mpmath.mpf(10) ** -30
MAX_POLISH = 40
#: Load steps per spring before giving up; the smallest step relative to the load reached (or, first, of
#: the full load); the contraction each Newton step must show.
MAX_STEPS = 4000
MIN_STEP = mpmath.mpf(10) ** -12
FIRST_STEP = mpmath.mpf(10) ** -40
CONTRACTION = mpmath.mpf(3) / 4
#: Extensions beyond this are taken as running off (past float64's range of the positions; and mpmath's
#: exp of an argument with an exponent beyond 2^63 bits would abort in GMP).
HUGE = mpmath.mpf(10) ** 300


@dataclass(frozen=True)
class Tree:
    """The load path of springs that form a forest with the ground.

    Attributes
    ----------
    beyond : list of (list of int, int)
        Per spring, the masses beyond it and the sign of its tension in their load (``t_s = sign·Σ F_i``).
    parent : list of (int, int, int)
        Per mass, ``(spring, neighbour, sign)``: x = x_neighbour + sign·d_spring, in placement order
        (the roots of free pieces first with x = 0); mass indices in ``order``.
    order : list of int
        Masses in placement order.
    roots : list of list of int
        The masses of each free piece (their centre of mass is put back at 0).
    """

    beyond: list
    parent: dict
    order: list
    roots: list


def tree(n: int, ends: list[tuple[int, int]]) -> Tree | None:
    """The load path of ``ends`` (−1 a wall), or None when the springs close a loop (two walls on a piece, a
    ring, parallel springs): their tensions then depend on the laws, not on the loads alone."""
    ground = n
    nodes = [(ground if a < 0 else a, ground if b < 0 else b) for a, b in ends]
    adjacency: list[list[tuple[int, int]]] = [[] for _ in range(n + 1)]
    for s, (a, b) in enumerate(nodes):
        adjacency[a].append((b, s))
        adjacency[b].append((a, s))
    seen: set[int] = set()
    parent: dict[int, tuple[int, int, int]] = {}
    order: list[int] = []
    beyond: list = [None] * len(ends)
    free: list[list[int]] = []
    starts = [ground] + list(range(n))
    for root in starts:  # depth-first from the ground, then from each free piece's lowest mass
        if root in seen:
            continue
        seen.add(root)
        stack, visit = [root], []
        while stack:
            u = stack.pop()
            visit.append(u)
            for w, s in adjacency[u]:
                if s in parent.get(u, (None,))[:1]:
                    continue
                if w in seen:
                    return None  # a second way to reach w: a loop
                seen.add(w)
                sign = 1 if nodes[s][1] == w else -1  # x_w = x_u + sign·d_s (d = x_b − x_a)
                parent[w] = (s, u, sign)
                stack.append(w)
        masses = [u for u in visit if u != ground]
        order += masses
        if root != ground:
            free.append(masses)
        below = {u: ([u] if u != ground else []) for u in visit}
        for u in reversed(visit):  # children before parents
            if u in parent and u != root:
                s, up, sign = parent[u]
                beyond[s] = (below[u], sign)
                below[up] = below[up] + below[u]
    if any(b is None for b in beyond):
        return None
    return Tree(beyond, parent, order, free)


def _newton(V1, V2, d, target, lo, hi, scale):
    """Newton on V'(d) = target from d; the root, or None unless each step (or else each residual) contracts,
    d stays inside (lo, hi)
    and the residual ends below 10^(12 − digits) of ``scale`` (the forces at play: a step that is small
    next to a huge d says nothing where V' is exponential there)."""
    last, last_f = None, None
    unit = mpmath.mpf(10) ** -mpmath.mp.dps
    for _ in range(60):
        try:
            f, k = V1(d) - target, V2(d)
        except (ZeroDivisionError, ValueError, OverflowError):
            return None
        if not (_real(f) and _real(k)) or k == 0:
            return None
        # the residual's floor: the forces to 10^(12 - digits), or the rounding of d itself (near a pole, or
        # a stiff spring at a large extension) through V''
        floor = unit * max(10 ** 12 * scale, 10 ** 3 * abs(k) * abs(d))
        step = f / k
        size = abs(step)
        if last is not None and size > CONTRACTION * last and abs(f) > CONTRACTION * last_f:
            return d if abs(f) <= floor or abs(f) <= 100 * _noise(V1, d) else None
        d = d - step
        if not lo < d < hi or abs(d) > HUGE:
            return None
        last, last_f = size, abs(f)
        if size <= mpmath.mpf(10) ** (6 - mpmath.mp.dps) * max(abs(d), mpmath.mpf(10) ** -300):
            try:
                f = V1(d) - target
            except (ZeroDivisionError, ValueError, OverflowError):
                return None
            if abs(f) <= floor or abs(f) <= 100 * _noise(V1, d):
                return d
    return None


def _noise(V1, d):
    """How far V'(d) as evaluated is from its value: the difference to an evaluation 20 digits finer (a
    tension written as a difference, a·(1 − exp(−b d)) at d = 1e-19, loses a·10^-digits to cancellation)."""
    try:
        coarse = V1(d)
        with mpmath.workdps(mpmath.mp.dps + 20):
            fine = V1(d)
    except (ZeroDivisionError, ValueError, OverflowError):
        return mpmath.mpf(0)
    return abs(coarse - fine) if _real(coarse) and _real(fine) else mpmath.mpf(0)


def _real(v) -> bool:
    return not isinstance(v, mpmath.mpc) and bool(mpmath.isfinite(v))


@dataclass(frozen=True)
class Ended:
    """A spring's path ended short of its tension: the fraction ``reached`` of it, at extension ``d``."""

    spring: int
    reached: float
    d: object
    stiffness: object


def extension(V1, V2, tension, lo: float, hi: float) -> tuple[object, int] | Ended:
    """The extension at which the spring's tension V'(d) reaches ``tension`` along its path from d = 0
    (mpmath at the current precision): ``(d, steps)``, or :class:`Ended` (``spring`` left −1)."""
    f0 = V1(mpmath.mpf(0))
    if tension == f0:
        return mpmath.mpf(0), 0
    lo, hi = mpmath.mpf(lo), mpmath.mpf(hi)
    d, lam, h, steps = mpmath.mpf(0), mpmath.mpf(0), mpmath.mpf(1), 0
    direction = 1 if tension > f0 else -1
    scale = max(abs(tension), abs(f0))
    for _ in range(MAX_STEPS):
        if lam >= 1:
            return d, steps
        k = V2(d)
        if not (_real(k) and k > 0):
            return Ended(-1, float(lam), d, k)
        target = min(mpmath.mpf(1), lam + h)
        pred = d + (target - lam) * (tension - f0) / k
        inside = lo < pred < hi and abs(pred) <= HUGE
        nxt = _newton(V1, V2, pred, f0 + target * (tension - f0), lo, hi, scale) if inside else None
        if nxt is not None and not ((nxt - d) * direction >= 0 and _real(V2(nxt)) and V2(nxt) > 0):
            nxt = None  # the stable branch moves with the load and keeps V'' > 0: not another root
        if nxt is None:
            h /= 2
            if h < MIN_STEP * lam or h < FIRST_STEP:
                return Ended(-1, float(lam), d, k)
            continue
        d, lam, steps = nxt, target, steps + 1
        h = min(mpmath.mpf(1), 2 * h)
    return Ended(-1, float(lam), d, V2(d))


def solve_tree(t: Tree, n: int, laws, values, loads, masses, bounds) -> tuple[list, list, int, int] | Ended:
    """Extensions and positions of the equilibrium on the loading path, in mpmath.

    Parameters
    ----------
    t : Tree
    n : int
    laws : list of (V', V'') callables of (d, *parameter values) in mpmath, per spring
    values : callable
        ``values(dps)``: the parameter values at ``dps`` digits.
    loads, masses : callable
        ``loads(dps)``, ``masses(dps)``: the constant force on each mass and the masses (for the free pieces'
        centres of mass), at ``dps`` digits.
    bounds : list of (float, float)
        Each spring's domain around d = 0.

    Returns
    -------
    (x, d, steps, digits)
        Positions and extensions (mpf), load steps (the largest over the springs), digits they agree to;
    Ended
        the first spring whose path ends short of its tension (the smallest fraction reached); ``spring``
        −2 when the extensions do not settle within MAX_DPS digits.
    """
    with mpmath.workdps(DPS):
        ext, worst, steps = [], None, 0
        vals, load = values(DPS), loads(DPS)
        for s, ((mass_set, sign), (F, S), (lo, hi)) in enumerate(zip(t.beyond, laws, bounds)):
            tension = sign * mpmath.fsum(load[i] for i in mass_set)
            found = extension(lambda d, F=F: F(d, *vals), lambda d, S=S: S(d, *vals), tension, lo, hi)
            if isinstance(found, Ended):
                if worst is None or found.reached < worst.reached:
                    worst = Ended(s, found.reached, found.d, found.stiffness)
                continue
            ext.append(found[0])
            steps = max(steps, found[1])
        if worst is not None:
            return worst
        stiff = [S(d, *vals) for (_, S), d in zip(laws, ext)]
    dps = DPS
    while True:  # polish each extension by Newton at twice the digits until two precisions agree
        if dps >= MAX_DPS:
            return Ended(-2, 1.0, None, None)
        dps *= 2
        with mpmath.workdps(dps):
            vals, load = values(dps), loads(dps)
            new_ext, new_stiff = [], []
            for (mass_set, sign), (F, S), d in zip(t.beyond, laws, ext):
                tension = sign * mpmath.fsum(load[i] for i in mass_set)
                d = mpmath.mpf(d)
                for _ in range(MAX_POLISH):
                    step = (F(d, *vals) - tension) / S(d, *vals)
                    d -= step
                    if abs(step) <= mpmath.mpf(10) ** (10 - dps) * max(abs(d), mpmath.mpf(10) ** -300):
                        break
                new_ext.append(d)
                new_stiff.append(S(d, *vals))
            # relative agreement, or absolute below 1e-30 of the largest of its kind (a spring that carries no
            # load sits at d = 0 up to the rounding of its V'(0), which differs from one precision to the next)
            agree = all(abs(a - b) <= AGREE * abs(b) + FLOOR * top
                        for old_, new_ in ((ext, new_ext), (stiff, new_stiff))
                        for top in [max([abs(v) for v in new_] + [mpmath.mpf(0)])]
                        for a, b in zip(old_, new_))
            ext, stiff = new_ext, new_stiff
            if agree:
                break
    with mpmath.workdps(dps):
        mass = masses(dps)
        x = [mpmath.mpf(0)] * n
        for i in t.order:  # placement: each mass from its parent (roots of free pieces at 0)
            if i in t.parent:
                s, up, sign = t.parent[i]
                x[i] = (x[up] if up < n else 0) + sign * ext[s]
        for piece in t.roots:
            centre = mpmath.fsum(mass[i] * x[i] for i in piece) / mpmath.fsum(mass[i] for i in piece)
            for i in piece:
                x[i] -= centre
    return x, ext, steps, dps


__all__ = ["Tree", "Ended", "tree", "extension", "solve_tree"]
