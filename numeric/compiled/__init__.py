"""Small ``[masses]`` scenes at compiled speed: whole runs in numba loops over the generated
module's straight-line ``scalar_force`` (:mod:`.loops`, compiled and cached on disk by
:mod:`.cache`), chosen inside the step kind (:mod:`numeric.run.step`) with the NumPy driver as the
fallback; and SciPy's DOP853 compiled (:func:`.run.dop853`), the honest peer of the benchmarks.
"""
