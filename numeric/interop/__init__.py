"""Hand-offs to other tools: state-space models (:mod:`.state_space`) for SciPy and python-control,
FRF forms (:mod:`.frf_forms`), and Universal File Format files (:mod:`.uff`, pyuff).

NumPy/SciPy only at import time; python-control and pyuff are imported where they are used.
"""
