"""The chunks of a sweep on the cluster: a bounded number in flight, each released once stored.

At most :data:`IN_FLIGHT` chunks per task slot are submitted at a time; a finished chunk's
outcomes are handed to the caller one by one and its future is dropped before the next chunk
is submitted, so neither the client nor a worker holds the results of finished chunks (the
worker's memory stays flat over a long sweep). A chunk whose task died (its worker was
killed, and Dask's retries are spent) yields WORKER_LOST records, which ``--resume`` solves
again.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Generator, Sequence

from . import record
from .task import Outcome, Task, solve_chunk

if TYPE_CHECKING:
    from distributed import Client

#: chunks submitted per task slot (worker thread) at a time: one running, one queued
IN_FLIGHT = 2


def outcomes(client: Client, tasks: Sequence[Task], slots: int
             ) -> Generator[list[Outcome], None, None]:
    """Run ``tasks`` on ``client`` (``slots`` task slots) and yield each chunk's outcomes as
    it finishes. Unfinished chunks are cancelled when the caller stops (an interrupt, a write
    error), so the cluster is free for the resumed run."""
    from distributed import as_completed

    queue = list(reversed(tasks))
    running: dict = {}  # future -> its task

    def submit() -> Any:
        task = queue.pop()
        future = client.submit(solve_chunk, task, pure=False)
        running[future] = task
        return future

    done = as_completed([submit() for _ in range(min(len(queue), IN_FLIGHT * max(slots, 1)))])
    try:
        for future in done:
            task = running.pop(future)
            try:
                results = future.result()
            except Exception as err:  # noqa: BLE001  (the task's error, recorded per point)
                results = [Outcome(record.failed(p, record.WORKER_LOST, record.describe(err)),
                                   None) for p in task.points]
            future.release()
            del future
            if queue:
                done.add(submit())
            yield results
    finally:
        client.cancel(list(running))
