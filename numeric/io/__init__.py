"""Files out: atomic writes, NPZ, chunked trajectories, strict JSON and array records."""
