"""Results cached on a model: the reports ask for one result (damped modes, participation, a
Rayleigh fit) several times, and a model is built once per scene."""

from __future__ import annotations


def cached_on(model, slot: str, key, compute):
    """``compute()`` once per ``key`` in the model's cache ``slot`` (an attribute of the model)."""
    cache = model.__dict__.setdefault(slot, {})
    if key not in cache:
        cache[key] = compute()
    return cache[key]
