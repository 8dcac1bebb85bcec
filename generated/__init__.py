"""Generated NumPy modules, one per bundled scene. Never edit by hand: `springchain derive`."""
