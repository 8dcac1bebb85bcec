"""The output folders of the commands that write files (the API's defaults and the command line's)."""

#: ``simulate``, ``run``, ``frf``, ``animate``, ``scaling``.
DEFAULT_OUT = "springchain-out"
#: ``bench``.
DEFAULT_BENCH_OUT = "springchain-bench"
#: ``sweep``.
DEFAULT_SWEEP_OUT = "springchain-sweep"
