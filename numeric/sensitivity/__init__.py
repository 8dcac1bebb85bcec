"""Sensitivities of modes to parameters (∂ω²/∂p, ∂φ/∂p) and the modal assurance criterion.

* :mod:`.compute` — the route for each kind of scene, :func:`.compute.compute`;
* :mod:`.derivatives` — eigenvalue derivatives, degenerate perturbation theory, Nelson's method;
* :mod:`.refine`, :mod:`.chain` — modes refined to double-double from the elements;
* :mod:`.solvers` — the float64 correctors (modal, tridiagonal deleted-row);
* :mod:`.double_double` — error-free arithmetic on arrays, residuals from the elements;
* :mod:`.mac` — the modal assurance criterion and optimal pairing.
"""
