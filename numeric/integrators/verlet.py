"""Velocity Verlet, exactly the reference scheme (one force evaluation per step)."""

from __future__ import annotations

from .base import Integrator, Problem, State


class VelocityVerlet(Integrator):
    """``x ← x + v h + a h²/2;  a' = a(x);  v ← v + (a + a') h/2``.

    Second order, symplectic and time-reversible for conservative forces; the
    acceleration is kept in the state so each step evaluates it once.
    """

    name = "verlet"
    order = 2
    symplectic = True
    evals_per_step = 1.0

    def step(self, problem: Problem, state: State, h: float) -> State:
        x = state.x + h * state.v + (0.5 * h * h) * state.a
        a_new = problem.acceleration(x)
        v = state.v + (0.5 * h) * (state.a + a_new)
        return State(x, v, a_new, state.i + 1)
