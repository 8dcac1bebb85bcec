"""Eigenproblems and their accurate routes: the spring-factor SVD spectrum of dense scenes, bisection on
the bidiagonal factor of chains, LAPACK bidiagonal kernels, damped modes, element assembly and bounds."""
