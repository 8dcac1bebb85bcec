"""Periodic chains, symbolic side: the unit cell of a scene (``[cell]`` tables and ``[chain]`` scenes whose
expressions repeat in ``i``), its Bloch matrix D(q), characteristic polynomial, closed-form branches and the
band section of generated modules.

:mod:`.cell` (the ``[cell]`` table: parsed and expanded into masses and springs by the scene loader) imports no
SymPy; the other modules do, and are imported only by the derivation.
"""
