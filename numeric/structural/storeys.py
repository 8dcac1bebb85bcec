"""What an engineer reads off a trajectory of a shear building: drifts, spring forces, base shear.

From positions (any method): the drift ``x_b − x_a`` of each spring and its tension, ``k d + k3 d³``,
or ``V'(d)`` for a spring potential (the generated cancellation-free tension, not the linearisation
at x_eq); one pass over the spring list (vectorised over frames and springs, no loop over masses).
A drift that is a small difference of large displacements carries float64's rounding of them,
``ε·(|x_a| + |x_b|)``: a chain hung from a 1e-6 N/m spring sags by ~1e8 m while its 1e6 N/m springs
stretch by ~1e-5 m, so their force from positions is 5.8e-4 off. :func:`rounding` bounds that error;
where it exceeds :data:`FORCE_ROUNDING` of the largest force the run says so in a note.

**The exact method's forces without that cancellation** (:func:`exact_series`, linear ``[masses]``
scenes whose springs form a tree with the ground: a chain or a building hung from one wall, free
pieces): the tension of every spring follows from the loads beyond it (the load path, statically
determinate), so

    t_s(t) = t_s,eq + Σ_j T_sj y_j(t),   t_eq = P·(F0 − M a),   T_sj = ω_j² (P·M φ_j),

with ``P`` (S × N) the load path (``±1`` on the masses beyond spring s, the side away from the
wall), F0 the constant loads (M a the free pieces' uniform acceleration), φ_j, ω_j the modes of the
accurate spectrum and y_j = q_j − q_eq,j the exact solution's own modal coordinates
(``K φ_j = ω_j² M φ_j``: a mode's spring forces balance its inertia forces beyond each spring). No
term is a difference of displacements: each is good to float64 of the force scale. Drifts are
``t_s / k_s``. Other topologies (loops: a chain between two walls, rings) keep the positions' route
and its note.
"""

from __future__ import annotations

import numpy as np

from ..system import System

#: Float64 rounding of spring forces formed from positions, relative to the run's largest spring force,
#: above which a note says so.
FORCE_ROUNDING = 1e-10
_EPS = float(np.finfo(float).eps)


def _ends_values(system: System, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    ends = system.spring_ends
    xa = np.where(ends[:, 0] >= 0, x[:, np.maximum(ends[:, 0], 0)], 0.0)
    xb = np.where(ends[:, 1] >= 0, x[:, np.maximum(ends[:, 1], 0)], 0.0)
    return xa, xb


def base_sign(system: System) -> np.ndarray:
    """+1 for a spring whose first end is a wall, −1 for its second end, 0 otherwise, shape (S,): the base
    shear is ``force @ base_sign`` (the wall springs' force on the ground, positive in +x)."""
    ends = system.spring_ends
    return np.where(ends[:, 0] < 0, 1.0, 0.0) - np.where(ends[:, 1] < 0, 1.0, 0.0)


def _tensions(system: System, drift: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Tension of every spring (S, springs) at the frames x: V'(d) for potentials, else k d + k3 d³."""
    if system.potential:
        return system.spring_tensions(x)
    force = drift * system.stiffness[None, :]
    if system.cubic_stiffness is not None:
        force = force + system.cubic_stiffness[None, :] * drift**3
    return force


def spring_series(system: System, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Drifts, spring forces and base shear of a trajectory, from its positions.

    Parameters
    ----------
    system : System
    x : ndarray, shape (S, N)
        Positions (relative to the ground).

    Returns
    -------
    drift : ndarray, shape (S, springs)
        ``x_b − x_a`` of each spring ``between = [a, b]`` (a wall is 0): the inter-storey drift.
    force : ndarray, shape (S, springs)
        Spring tension ``k·d + k3·d³`` (``V'(d)`` for a potential) with d the drift (the storey shear
        of a shear building) [N].
    base_shear : ndarray, shape (S,)
        Force of the wall springs on the ground, positive in +x [N].
    """
    x = np.asarray(x, dtype=float)
    xa, xb = _ends_values(system, x)
    drift = xb - xa
    force = _tensions(system, drift, x)
    return drift, force, force @ base_sign(system)


def rounding(system: System, x: np.ndarray, force: np.ndarray) -> float:
    """Bound on the float64 rounding of the forces :func:`spring_series` forms from positions x (S, N),
    relative to the largest |force| (0 when every force is 0): ``ε·|k_t|·(|x_a| + |x_b|)`` per spring and
    frame, with ``k_t`` the tangent stiffness (``k + 3 k3 d²``; a potential's V''(d))."""
    x = np.asarray(x, dtype=float)
    top = float(np.max(np.abs(force), initial=0.0))
    if not top > 0 or not np.isfinite(top):
        return 0.0
    xa, xb = _ends_values(system, x)
    if system.potential:
        with np.errstate(all="ignore"):
            k = np.abs(system.spring_stiffnesses(x))
    else:
        k = np.abs(system.stiffness)[None, :]
        if system.cubic_stiffness is not None:
            k = k + 3.0 * np.abs(system.cubic_stiffness)[None, :] * (xb - xa) ** 2
    with np.errstate(all="ignore"):
        err = float(np.max(2.0 * _EPS * k * (np.abs(xa) + np.abs(xb)), initial=0.0))
    return err / top


def load_path(n: int, ends: np.ndarray) -> np.ndarray | None:
    """The load path ``P`` (S, N) of springs that form a forest with the ground (every wall one node):
    ``t_s = (P f)_s`` is spring s's tension when the loads f balance the springs (``K x = f``). Row s is
    +1 on the masses beyond s on its second end's side, −1 on its first end's (the side away from the
    ground; for a free piece, away from its lowest-numbered mass). None where the springs close a loop
    (two walls on one piece, a ring, parallel springs): the tensions are then not fixed by the loads.
    """
    ends = np.asarray(ends, dtype=np.intp).reshape(-1, 2)
    ground = n
    nodes = np.where(ends < 0, ground, ends)
    parent = list(range(n + 1))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b in nodes.tolist():  # union-find over springs: a spring joining one component closes a loop
        ra, rb = find(a), find(b)
        if ra == rb:
            return None
        parent[ra] = rb
    adjacency: list[list[tuple[int, int]]] = [[] for _ in range(n + 1)]
    for s, (a, b) in enumerate(nodes.tolist()):
        adjacency[a].append((b, s))
        adjacency[b].append((a, s))
    P = np.zeros((ends.shape[0], n))
    roots = {find(i): None for i in range(n + 1)}
    roots[find(ground)] = ground
    for i in range(n):  # the root of each free piece: its lowest-numbered mass
        if roots[find(i)] is None:
            roots[find(i)] = i
    for root in roots.values():  # depth-first from each root: a spring's far side is its child's subtree
        order, stack, seen, via = [], [root], {root}, {}
        while stack:
            u = stack.pop()
            order.append(u)
            for w, s in adjacency[u]:
                if w not in seen:
                    seen.add(w)
                    via[w] = s
                    stack.append(w)
        below: dict[int, list[int]] = {u: ([u] if u != ground else []) for u in order}
        for u in reversed(order):  # children before parents
            if u in via:
                s = via[u]
                sign = 1.0 if nodes[s, 1] == u else -1.0
                P[s, below[u]] = sign
                parent_node = nodes[s, 0] if nodes[s, 1] == u else nodes[s, 1]
                below[parent_node] = below[parent_node] + below[u]
    return P


def series(system: System, x: np.ndarray, exact: tuple | None = None) -> tuple:
    """Drifts, spring forces, base shear of a run's positions x (S, N), and the bound on their float64
    rounding relative to the largest force (:func:`rounding`; 0 on the exact route).

    ``exact = (x0, v0, t)`` for the exact method's run: where the positions' rounding bound exceeds
    :data:`FORCE_ROUNDING`, its forces come from the load path instead (:func:`exact_series`) where that
    applies (elsewhere the positions' route is taken: the same numbers as every other method's)."""
    drift, force, base = spring_series(system, x)
    bound = rounding(system, x, force)
    if exact is not None and bound > FORCE_ROUNDING:
        found = exact_series(system, *exact, x=x)
        if found is not None and found[3] < bound:
            return found
    return drift, force, base, bound


def rounding_note(method: str, bound: float) -> str | None:
    """The note of a run whose spring forces from positions may be off by more than :data:`FORCE_ROUNDING`."""
    if not bound > FORCE_ROUNDING:
        return None
    return (f"{method}: spring forces (and drifts) from positions may be off by up to {bound:.1e} of the largest "
            "spring force: float64 rounding of x_b - x_a, a small difference of large displacements (the exact "
            "method forms them by the load path where the springs form a tree with the ground)")


def exact_series(system: System, x0: np.ndarray, v0: np.ndarray, t: np.ndarray, x: np.ndarray | None = None):
    """Drifts, spring forces and base shear of the exact solution from ``(x0, v0)`` at times t (S,), by the
    load path (module docstring); None where it does not apply (a ``[chain]``, no exact solution, or
    springs that close a loop), then the positions' route is the one there is. ``x`` (S, N), the run's
    positions, gives the drift of a spring of stiffness 0 (whose tension says nothing of it).

    Returns
    -------
    (drift, force, base_shear, bound) : ndarrays, shapes (S, springs), (S, springs), (S,), and float
        ``bound``: the rounding the initial state's modal coordinates carry into the forces, relative to the
        largest force, ``ε·Σ_j |T_j| (|φ_j|ᵀM|x0| + |φ_j|ᵀ|F0|/ω_j² + |φ_j|ᵀM|v0|/ω_j)`` (float64 projections of
        x0, v0 and the loads on the modes; ~ε for a scene released at rest, large for a huge x0 whose
        drifts are small).
    """
    if system.chain or system.no_exact_solution or not system.linear:
        return None
    P = load_path(system.n, system.spring_ends)
    if P is None:
        return None
    t = np.asarray(t, dtype=float)
    m = system.masses
    if system.springs_only:
        from ..exact.modal import ModalSolution, cos_tsinc

        spec = system.spectrum
        sol = ModalSolution.from_initial(spec, np.asarray(x0, dtype=float), np.asarray(v0, dtype=float))
        cs = cos_tsinc(t, spec.omega)
        n = spec.omega.shape[0]
        y = (sol.q0[:, None] * cs[:n] + sol.p0[:, None] * cs[n:]).T  # mass-weighted: x = M^-1/2 E q
        shapes, omega, loads = spec.shapes, spec.omega, np.zeros(system.n)
    else:
        from ..exact.linear import AugmentedLinear

        aug = AugmentedLinear.from_system(system)
        Z, _ = aug.states_grid(np.asarray(x0, dtype=float), np.asarray(v0, dtype=float), t)
        y = aug.modal_coordinates(Z)
        shapes, omega, loads = aug.shapes, aug.omega, aug.static_load
    modal = (P @ (m[:, None] * shapes)) * (omega * omega)[None, :]  # (S, N): tensions per unit y_j
    force = (P @ loads)[None, :] + y @ modal.T
    elastic = omega > 0
    w = np.where(elastic, omega, 1.0)
    a = np.abs(shapes).T
    proj = a @ (m * np.abs(x0)) + (a @ (m * np.abs(v0))) / w + (a @ np.abs(loads)) / (w * w)
    err = 4.0 * _EPS * float(np.max(np.abs(modal[:, elastic]) @ proj[elastic], initial=0.0))
    top = float(np.max(np.abs(force), initial=0.0))
    bound = err / top if top > 0 else 0.0
    k = system.stiffness
    with np.errstate(all="ignore"):
        drift = force / np.where(k != 0, k, 1.0)[None, :]
    if np.any(k == 0) and x is not None:
        xa, xb = _ends_values(system, np.asarray(x, dtype=float))
        drift = np.where(k[None, :] != 0, drift, xb - xa)
    return drift, force, force @ base_sign(system), bound


__all__ = ["series", "spring_series", "exact_series", "rounding", "rounding_note", "load_path", "base_sign",
           "FORCE_ROUNDING"]
