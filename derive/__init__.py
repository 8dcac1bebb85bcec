"""springchain's symbolic side: scene files, the Lagrangian derivation, closed-form modes and code
generation. The only package of springchain that imports SymPy (lazily: loading a scene does not)."""
