"""Many problems at once: sweeps and batches of one problem file on Dask (issue 17)."""
