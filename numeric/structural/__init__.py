"""Structural dynamics: response spectra of records, response-spectrum analysis (SRSS, CQC), modal
quantities (participation, effective masses), storey quantities and the single-oscillator peak."""
