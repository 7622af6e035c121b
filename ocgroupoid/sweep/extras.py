"""The optional dependencies of sweeps (the ``sweep`` extra), checked before a sweep starts.

``pip install -e .`` installs ocgroupoid without Dask, pandas and pyarrow; a sweep (and the
figure of a sweep's folder) then stops at once with one line naming the extra to install,
instead of failing half-way with an ImportError.
"""

from __future__ import annotations

import importlib.util

from ..errors import DependencyError

#: the modules of the ``sweep`` extra (pyproject.toml) and the distributions that hold them
MODULES = {"distributed": "dask[distributed]", "pandas": "pandas", "pyarrow": "pyarrow"}
INSTALL = 'pip install -e ".[sweep]"'


def _missing(module: str) -> bool:
    try:
        return importlib.util.find_spec(module) is None
    except (ImportError, ValueError):  # a parent package is missing, or the module is blocked
        return True


def require(what: str = "ocgroupoid sweep") -> None:
    """DependencyError naming the extra when a module of it is not installed."""
    missing = [dist for module, dist in MODULES.items() if _missing(module)]
    if missing:
        raise DependencyError(f"{what} needs the sweep extra ({', '.join(missing)} not "
                              f"installed): run {INSTALL} in the source folder (or pip "
                              "install \"ocgroupoid[sweep]\")")
