"""Choosing a method: the planner, its pilot runs and the error models it predicts with."""
