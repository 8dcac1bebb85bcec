"""springchain: mass–spring chains from a scene file to equations, closed-form normal modes,
generated NumPy code and trustworthy simulations.

The public API (each name loads what it needs on first use, so ``import springchain`` is cheap)::

    import springchain as sc
    scene = sc.load("seed")            # a path or a bundled scene's name
    s4 = scene.with_parameters(k=4.0).with_initial(x=[0.1, 0, 0])  # new validated scenes
    sc.scene_from_dict({"name": "two", "parameters": {...}, ...})  # the TOML schema as a dict
    m = sc.modes(scene)                # equations and modes; m.to_json(), m._repr_latex_()
    run = sc.simulate(scene)           # run.t (S,), run.x["modal"] (S, N), run.plot(), run.save(path)
    sc.plan(scene, tol=1e-6)           # the cheapest method and step for a tolerance
    sc.bench(scene, quick=True)        # work-precision benchmark
    sc.generate(["seed"], out="generated")  # `springchain derive`: write modules (check=True: compare)
    sc.scaling(max_n=10_000)           # exact set-up vs Verlet step for long chains (files in springchain-out)
    sc.sweep("chain100k", disorder=["mass=uniform(0.5, 1.5)"], samples=100)  # ensembles on Dask
    h = sc.frf("building", input="floor3", output="floor3")  # h.omega, h.magnitude, h.phase, h.plot()
    sc.animate("seed", mode=2, out="springchain-out")          # a GIF of mode 2 oscillating
    sc.rayleigh_coefficients("building", zeta=(0.05, 0.05), modes=(1, 3))  # .alpha, .beta, closed forms
    sc.response_spectrum("quake-record", zeta=[0.02, 0.05])   # SD, PSV, PSA (exact); a CSV path or bundled record
    sc.rsa("building_quake", spectrum="quake-record")         # SRSS and CQC peaks
    b = sc.bands("diatomic")           # periodic chains: b.omega2 (q x branch), b.gaps, b.plot(), b.save(dir)
    sc.sensitivities("seed", parameters="k,m")              # d omega^2/dp, d phi/dp (Nelson), ranking
    sc.mac("building", "measured.csv")                      # MAC matrix and optimal pairing
    sc.update("building", "measured.csv", parameters="k")   # least-squares model updating
    sc.reconstruct("spectra.csv", total_mass=3.0)           # a chain from its two spectra
    sc.random_response("building", "spec.csv", on="floor3")    # RMS by the exact modal integral; .plot()
    sc.state_space("building", inputs="floor3", outputs=["floor3:a"], form="control")  # SciPy / python-control
    sc.frf_form("building_quake", "transmissibility", output="floor3", hz=True, db=True)  # mobility, ... too
    sc.write_frf_uff(h, "h.uff"); frfs, modes = sc.read_uff("measured.uff")  # UFF 58 (binary) and 55

Subpackages: :mod:`springchain.derive` (SymPy), :mod:`springchain.numeric` (NumPy/SciPy),
:mod:`springchain.generated` (generated modules of the bundled scenes).
"""

from __future__ import annotations

__version__ = "0.3.0"

#: Public names and the module that defines each (imported on first use).
_LAZY = {
    "load": "._api", "modes": "._api", "simulate": "._api", "plan": "._api", "bench": "._api",
    "generate": "._api", "scaling": "._api",
    "method_names": "._api", "Modes": "._api", "parse_expression": "._api", "Simulation": "._api",
    "SceneError": ".derive.errors", "RunRefused": ".numeric.errors", "Scene": ".derive.scene",
    "bundled_scenes": "._scenes", "sweep": "._sweep", "SweepResult": "._sweep",
    "frf": "._frf", "FrequencyResponse": "._frf", "animate": "._animate", "Animation": "._animate",
    "scene_from_dict": ".derive.scene",
    "rayleigh_coefficients": "._structural", "response_spectrum": "._structural", "rsa": "._structural",
    "SpectrumResult": "._structural", "RSA": "._structural",
    "bands": "._bands", "Bands": "._bands",
    "sensitivities": "._sensitivity", "Sensitivities": "._sensitivity", "mac": "._mac", "MAC": "._mac",
    "update": "._updating", "Update": "._updating", "reconstruct": "._updating", "Reconstruction": "._updating",
    "random_response": "._random", "RandomVibration": "._random",
    "state_space": "._interop", "AccuracyWarning": "._interop",
    "frf_form": "._frf_forms", "FrfForm": "._frf_forms",
    "read_uff": "._uff", "write_frf_uff": "._uff", "write_modes_uff": "._uff",
}

__all__ = ["__version__", *_LAZY]


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(_LAZY[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'springchain' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
