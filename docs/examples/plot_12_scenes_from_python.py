"""
Scenes from Python, and data out
================================

Scenes can be changed and built in Python — each change returns a new, validated scene, checked
exactly as a scene file — and results go out as NumPy arrays, NPZ files, or, with the ``data``
extra, xarray and pandas objects.
"""

import numpy as np

import springchain as sc

scene = sc.load("seed")
stiff = scene.with_parameters(k=4.0, m=2.0)          # a new Scene; `scene` is unchanged
moved = stiff.with_initial(x=[0.1, 0.0, 0.0], v=np.zeros(3))
print(sc.modes(stiff).omega2_values)                  # k/m = 2 and 5k/(3m) = 10/3 now

# %%
# A bad value is refused with the one-line message a scene file would get:
try:
    scene.with_parameters(m=-1.0)
except sc.SceneError as exc:
    print("SceneError:", exc)

# %%
# A scene from a dict with the TOML structure; a force may be a table given as an array (t, f):
two = sc.scene_from_dict({
    "name": "two", "parameters": {"m": 1.0, "k": 4.0},
    "masses": {"a": "m", "b": "m"},
    "springs": [{"between": ["wall", "a"], "k": "k"}, {"between": ["a", "b"], "k": "k"}],
    "forces": [{"on": "b", "table": np.column_stack([[0.0, 0.5, 1.0], [0.0, 1.0, 0.0]])}],
    "simulation": {"dt": 0.01, "steps": 300},
})
run = sc.simulate(two, progress=False)
fig = run.plot()

# %%
# Data out: an xarray Dataset (dims ``time`` and ``mass``, units attached), a long pandas table,
# and the modes as a DataFrame.
ds = run.to_xarray()
print(ds)
print(run.to_dataframe().head())
print(sc.modes(stiff).to_dataframe()[["omega2", "omega2_value", "omega"]])
