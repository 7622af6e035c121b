"""Shared fixtures and hypothesis settings."""

from __future__ import annotations

import os
from typing import Any, Iterator

import pytest
from hypothesis import HealthCheck, settings

settings.register_profile(
    "default", deadline=None, max_examples=60,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile("ci", deadline=None, max_examples=60, derandomize=True,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


@pytest.fixture(scope="module")
def client() -> Iterator[Any]:
    """For the sweep tests: a LocalCluster as `sweep` makes one (processes, one thread
    each), two workers."""
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as c:
        yield c


def pytest_itemcollected(item: pytest.Item) -> None:
    """Under ``--dist loadgroup`` (pyproject's addopts): the tests that share a module- or
    class-scoped fixture (one of its parameters) form one group and run on one worker, so
    its set-up (a C build, a reference solve) is paid once rather than once per worker.
    (Marked as each item is collected: xdist reads the marks in its own
    ``pytest_collection_modifyitems``.)"""
    info = getattr(item, "_fixtureinfo", None)
    if info is None:
        return
    callspec = getattr(item, "callspec", None)
    keys = []
    for name in info.names_closure:
        defs = info.name2fixturedefs.get(name)
        if not defs or defs[-1].scope not in ("module", "class"):
            continue
        index = callspec.indices.get(name) if callspec is not None else None
        if index is not None and any(name in _argnames(m) for m in
                                     item.iter_markers("parametrize")):
            index = f"{item.originalname}:{index}"  # the test's own list (indirect=True)
        keys.append(name if index is None else f"{name}={index}")  # no "]": xdist
    if keys:
        module = item.nodeid.split("::")[0]
        item.add_marker(pytest.mark.xdist_group(f"{module}:{','.join(sorted(keys))}"))


def _argnames(mark: pytest.Mark) -> list[str]:
    """The names a ``parametrize`` mark sets: "a, b" or ("a", "b")."""
    names = mark.args[0] if mark.args else mark.kwargs.get("argnames", ())
    return [n.strip() for n in names.split(",")] if isinstance(names, str) else list(names)
