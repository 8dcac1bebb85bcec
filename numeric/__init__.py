"""springchain's numeric side (NumPy/SciPy/matplotlib only, never SymPy): the exact modal solution,
integrators, trajectories, plots and benchmarks, all driven by the generated modules."""
