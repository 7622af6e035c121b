"""The Dask client a sweep runs on: the caller's, a scheduler's address, or a LocalCluster.

A LocalCluster has one worker process per core with one thread each (``processes=True``),
so that IPOPT and MUMPS never share a core; Dask's nannies also set ``OMP_NUM_THREADS=1``
and the BLAS equivalents in each worker. An address (``tcp://HOST:PORT``) connects to an
existing cluster; both run the same tasks. What this module opens, it closes; a client the
caller passes in stays open. A LocalCluster's workers run without Dask's statistical profiler
(:data:`LOCAL_CONFIG`); start the workers of a cluster at ``--scheduler`` with
``DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED=False`` for the same flat memory.
"""

from __future__ import annotations

import logging
import os
from contextlib import contextmanager
from typing import TYPE_CHECKING, Iterator

from ..errors import ConfigError

if TYPE_CHECKING:
    from distributed import Client


#: Dask settings of a LocalCluster: no statistical profiler in the workers (it samples the
#: stack of the running task every 10 ms and keeps an hour of those samples: 40 kB of worker
#: memory a point of a sweep, measured over 1600 so3 points; 2 kB without it)
LOCAL_CONFIG = {"distributed.worker.profile.enabled": False}


def cores() -> int:
    """Cores this process may use (its CPU affinity where the OS tells it)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


@contextmanager
def connect(client: Client | None = None, scheduler: str | None = None,
            workers: int | None = None, timeout: float = 10.0) -> Iterator[Client]:
    """Yield a client with at least one worker; close what was opened here.

    ``scheduler``: the address of a running scheduler, which must answer (and have a
    worker) within ``timeout`` seconds. Otherwise a LocalCluster of ``workers`` processes
    (default: one per core).
    """
    if client is not None:
        if scheduler is not None or workers is not None:
            raise ConfigError("give a client, or a scheduler address or a worker count, "
                              "not both")
        yield client
        return
    if scheduler is not None:
        if workers is not None:
            raise ConfigError("--workers sizes a local cluster; a cluster at --scheduler "
                              "has its own workers (start more with `dask worker ADDRESS`)")
        with _remote(scheduler, timeout) as remote:
            yield remote
        return
    if workers is not None and workers < 1:
        raise ConfigError(f"--workers must be >= 1, got {workers}")
    import dask
    from distributed import Client, LocalCluster

    with dask.config.set(LOCAL_CONFIG), \
            LocalCluster(n_workers=workers or cores(), threads_per_worker=1, processes=True,
                         dashboard_address=None, silence_logs=logging.ERROR) as cluster, \
            Client(cluster) as local:
        yield local


@contextmanager
def _remote(address: str, timeout: float) -> Iterator[Client]:
    from distributed import Client

    try:
        remote = Client(address, timeout=timeout)
    except Exception as err:  # noqa: BLE001  (any failure means: no usable scheduler there)
        raise ConfigError(f"--scheduler {address}: no scheduler answered within {timeout:g} s "
                          f"({type(err).__name__}: {err}); start one with `dask scheduler`, "
                          "check the address (tcp://HOST:PORT), or leave --scheduler out "
                          "to run on this machine") from None
    try:
        try:
            remote.wait_for_workers(1, timeout=timeout)
        except TimeoutError:
            raise ConfigError(f"--scheduler {address}: the scheduler has no worker after "
                              f"{timeout:g} s; start one with `dask worker {address}`") from None
        yield remote
    finally:
        remote.close()
