"""Exact solutions: the modal solution of dense scenes and chains, linear loads by augmentation, the sine
transform of uniform chains, absolute coordinates, equilibria and modal energies, special closed forms."""
