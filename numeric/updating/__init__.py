"""Model updating and inverse problems.

* :mod:`.measured` — measured modes from CSV (frequencies, standard deviations, shapes at sensors);
* :mod:`.frf_peaks` — a measured FRF reduced to modes (peaks, then one mode plus the others' tails fitted);
* :mod:`.residuals` — pairing with the model's modes, weighted residuals and their Jacobian;
* :mod:`.fit` — least squares in log p, standard errors, correlations, identifiability;
* :mod:`.figure` — the before/after figure;
* :mod:`.reconstruct` — a fixed–free chain from its two spectra (Lanczos in extended precision).
"""
