"""Figures: trajectories, energies, mode shapes, structural plots, animation and the HTML report."""
