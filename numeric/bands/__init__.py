"""Periodic chains, numeric side: the bands of a unit cell at the scene's values, accurate at any contrast.

:mod:`.factor` (the Bloch factor X(q), D = X Xᴴ, by a subtraction-free elimination on the cell's elements) and
:mod:`.jacobi` (one-sided Jacobi SVD) give ω²_j(q), eigenvectors and group velocities (:mod:`.spectrum`, branches
by continuity); :mod:`.edges` band edges and gaps, :mod:`.decay` Im q in the gaps, :mod:`.dos` the density of
states, :mod:`.finite` the finite chain's modes by band, :mod:`.damped` damped bands, :mod:`.plots` the figure.
The cell comes from the generated module through :meth:`springchain.numeric.system.System.band_cell`.
"""
