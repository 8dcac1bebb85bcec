"""Results as pandas and xarray objects (the optional extra ``springchain[data]``).

pandas and xarray are imported only here, on first use; without them each method raises an
``ImportError`` whose one line names the extra to install.
"""

from __future__ import annotations

import importlib

import numpy as np

EXTRA = 'pip install "springchain[data]"'
#: Units of each recorded quantity (NPZ key prefix).
#: (pint-readable: ``ds.pint.quantify()`` of pint-xarray reads the ``units`` attributes.)
UNITS = {"x": "m", "v": "m/s", "aabs": "m/s^2", "xabs": "m", "drift": "m", "spring_force": "N", "base_shear": "N",
         "modal_energy": "J"}
LONG_NAMES = {"x": "displacement from the springs' rest configuration", "v": "velocity",
              "aabs": "absolute acceleration (relative acceleration + ground acceleration)",
              "xabs": "absolute displacement (relative displacement + ground displacement)",
              "drift": "spring stretch (storey drift)", "spring_force": "spring force",
              "base_shear": "base shear (sum of the forces of the springs to the wall)",
              "modal_energy": "energy of each linear normal mode (ascending omega)"}
#: The second dimension of each recorded quantity (absent: one value per time).
SECOND_DIM = {"x": "mass", "v": "mass", "aabs": "mass", "xabs": "mass", "drift": "spring", "spring_force": "spring",
              "modal_energy": "mode"}


#: The extra that installs each optional module other than the data extra's.
EXTRAS = {"control": 'pip install "springchain[control]"', "pyuff": 'pip install "springchain[uff]"',
          "pint": 'pip install "springchain[units]"'}


def require(module: str, what: str):
    """Import an optional dependency, or fail in one line naming the extra that provides it."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise ImportError(f"{what} needs {module}, which springchain installs only on request: "
                          f"{EXTRAS.get(module, EXTRA)}") from None


def _mass_coords(scene) -> list:
    """Mass names (``[chain]`` scenes: the 0-based indices)."""
    return list(scene.mass_names) if scene.chain is None else list(range(scene.n))


def _series(sim) -> list[tuple[str, str, np.ndarray]]:
    """(quantity, method, array (S, N)) of every recorded array of a Simulation."""
    out = [(q, m, arr) for q, d in (("x", sim.x), ("v", sim.v)) for m, arr in d.items()]
    for key, arr in sim.extra.items():
        q = next((name for name in sorted(UNITS, key=len, reverse=True) if key.startswith(name + "_")), None)
        q, m = (q, key[len(q) + 1:]) if q else key.partition("_")[::2]
        out.append((q, m, arr))
    return out


def _dims(q: str, arr) -> tuple[str, ...]:
    """Dimensions of a recorded array: (time, mass), (time, spring), (time, mode) or (time,)."""
    return ("time",) if np.ndim(arr) == 1 else ("time", SECOND_DIM.get(q, "mass"))


def simulation_xarray(sim):
    """:meth:`springchain.Simulation.to_xarray`: a Dataset with dims (time, mass), one variable per
    quantity and method (``x_modal``, ``v_verlet``, ...), attributes scene, dt, units."""
    xr = require("xarray", "Simulation.to_xarray()")
    coords = {"time": ("time", np.asarray(sim.t), {"units": "s", "long_name": "time t = i·dt"}),
              "mass": ("mass", _mass_coords(sim.scene), {"long_name": "mass (coordinate order)"})}
    data = {f"{q}_{m}": (_dims(q, arr), np.asarray(arr),
                         {"units": UNITS.get(q, ""), "long_name": LONG_NAMES.get(q, q), "method": m, "quantity": q})
            for q, m, arr in _series(sim)}
    s = sim.summary
    attrs = {"scene": sim.scene.name, "scene_file": str(sim.scene.file), "dt": float(s.get("dt", np.nan)),
             "steps": int(s.get("steps", 0)), "methods": ", ".join(sim.methods),
             "units": "time: s; x: m; v: m/s; aabs: m/s^2; xabs: m; drift: m; spring_force: N; base_shear: N; "
                      "modal_energy: J",
             "parameters": ", ".join(f"{k} = {v:g}" for k, v in sorted(sim.scene.parameters.items()))}
    return xr.Dataset(data, coords=coords, attrs=attrs)


def simulation_dataframe(sim):
    """:meth:`springchain.Simulation.to_dataframe`: long form, one row per (method, quantity, time, mass)
    with columns ``method, quantity, time, mass, value, unit``."""
    pd = require("pandas", "Simulation.to_dataframe()")
    t = np.asarray(sim.t)
    masses = np.asarray(_mass_coords(sim.scene), dtype=object)
    frames = []
    for q, m, arr in _series(sim):
        arr = np.asarray(arr)
        arr = arr[:, None] if arr.ndim == 1 else arr
        s, n = arr.shape
        frames.append(pd.DataFrame({"method": m, "quantity": q, "time": np.repeat(t, n),
                                    "mass": np.tile(masses[:n], s), "value": arr.reshape(-1),
                                    "unit": UNITS.get(q, "")}))
    return pd.concat(frames, ignore_index=True)


def frf_dataframe(h):
    """:meth:`springchain.FrequencyResponse.to_dataframe`: one row per frequency, columns
    ``omega`` [rad/s], ``H`` (complex, m/N), ``magnitude`` [m/N], ``phase_deg``."""
    pd = require("pandas", "FrequencyResponse.to_dataframe()")
    df = pd.DataFrame({"omega": np.asarray(h.omega), "H": np.asarray(h.H), "magnitude": h.magnitude,
                       "phase_deg": h.phase})
    df.attrs.update({"scene": h.scene.name, "input": h.input, "output": h.output,
                     "units": {"omega": "rad/s", "H": "m/N", "magnitude": "m/N", "phase_deg": "deg"}})
    return df


def modes_dataframe(m):
    """:meth:`springchain.Modes.to_dataframe`: one row per listed mode (as ``modes --json``): ``omega2``
    (text), ``omega2_value``, ``omega`` [rad/s], ``multiplicity``, ``shape`` (text) and, where
    listed, one column ``shape_<mass>`` per mass."""
    pd = require("pandas", "Modes.to_dataframe()")
    data = m.to_json()
    masses = data["masses"] or [str(i) for i in range(m.scene.n)]
    rows = []
    for j, rec in enumerate(data["modes"]):
        w2 = float(rec["omega2_value"])
        row = {"mode": rec.get("j", j), "omega2": rec["omega2"], "omega2_value": w2,
               "omega": float(np.sqrt(max(w2, 0.0))), "multiplicity": rec["multiplicity"],
               "shape": None if rec["shape"] is None else (rec["shape"] if isinstance(rec["shape"], str)
                                                          else "(" + ", ".join(rec["shape"]) + ")")}
        for key in ("damping_ratio", "omega_damped"):
            if key in rec:
                row[key] = rec[key]
        for name, value in zip(masses, rec.get("shape_value") or ()):
            row[f"shape_{name}"] = value
        rows.append(row)
    df = pd.DataFrame(rows)
    df.attrs.update({"scene": data["scene"], "parameters": data["parameters"],
                     "units": {"omega2_value": "rad^2/s^2", "omega": "rad/s"}})
    return df


def sweep_pandas(result, columns=None):
    """:meth:`springchain.SweepResult.to_pandas`: the rows of ``sweep.parquet`` (sample order); list
    columns (``omega2``, ...) hold one array per sample."""
    require("pandas", "SweepResult.to_pandas()")
    return result.table(columns).to_pandas()


__all__ = ["simulation_xarray", "simulation_dataframe", "frf_dataframe", "modes_dataframe", "sweep_pandas",
           "require", "EXTRA"]
