"""Frequency response: the dense and chain receptance routes (certified, extended precision where float64
fails) and the resonance table (peaks, nodes, half-power widths)."""
