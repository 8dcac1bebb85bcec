"""Model updating from measured modes (:mod:`.fit`, :mod:`.measured`) and a chain rebuilt from its two
spectra (:mod:`.reconstruct`)."""
