"""Parameter studies: the sweep driver (local or Dask), realisations of random parameters, their
distributions and summaries."""
