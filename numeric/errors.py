"""Errors the numeric side raises for requests it refuses (the command prints one line, exits 2)."""


class RunRefused(ValueError):
    """A run that would be wrong or impossible, e.g. a step beyond Verlet's stability limit."""
