"""Many problems at once: sweeps and batches of one problem file on Dask (issue 17).

``sweep`` solves a problem file at every point of a grid and/or random samples of
``--set`` overrides, one NLP per structure, on a Dask cluster; ``plot_sweep`` draws the
cost and status of a sweep's folder against the swept keys. Dask, pandas and pyarrow are
imported when a sweep runs, not with ``ocgroupoid``.
"""

from .plot import plot_sweep
from .run import sweep

__all__ = ["sweep", "plot_sweep"]
