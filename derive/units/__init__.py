"""Physical units in scenes (the optional extra ``springchain[units]``, pint).

Scene values may carry units — ``m = "10 t"``, ``k = "4 MN/m"``, ``c = "2 kN*s/m"``,
``g = "9.81 m/s^2"``, a CSV header ``t [s], a [g]`` — converted to SI once at load (the scene
holds SI floats: nothing changes at run time), each checked against what its key means
(:mod:`.dimension`), and every expression that involves a quantity with a unit checked for
dimensional consistency (:mod:`.check`). Without pint, plain numbers work as before and a unit
says in one line what to install. Output units (``--units``) are :mod:`.output`.

Modules: :mod:`.dimension` (dimensions, the meaning of each key), :mod:`.check` (an expression's
dimension), :mod:`.registry` (pint: safe parsing, SI factors), :mod:`.scope` (one scene's units
while it loads), :mod:`.tables` (CSV headers), :mod:`.output` (results in the user's units).
"""

from __future__ import annotations

from .dimension import Dimension, meaning
from .registry import EXTRA, UnitProblem, parse_unit, split_quantity
from .scope import SceneUnits
from .tables import HeaderProblem, header_factors

__all__ = ["Dimension", "meaning", "EXTRA", "UnitProblem", "parse_unit", "split_quantity", "SceneUnits",
           "HeaderProblem", "header_factors"]
