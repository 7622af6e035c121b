"""fatrop hears a listener through its own C interface (``fatrop_ocp.c``: asked at each
iteration's Hessian, it stops fatrop by lowering ``max_iter``): the iterations, the unscaled
objective and the infeasibility reach it, a stop keeps the last iterate and ends the turn, the
next solve has its ``max_iter`` back, and a further start of a multi-start is stopped by the
iterations of its budget, in turn and on workers, as IPOPT's are."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

import ocgroupoid as og
from ocgroupoid.nlp.backends import LISTENER_STOP, FatropBackend, Start
from ocgroupoid.nlp.transcription import Transcription
from ocgroupoid.solve import compiled, parallel
from ocgroupoid.systems.rigid_body import rigid_body

pytestmark = pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None,
                                reason="fatrop's own interface needs a C compiler")


def _fatrop(N: int = 16) -> tuple[Transcription, FatropBackend]:
    tr = og.compile_problem(rigid_body(), N=N, backend="fatrop"
                            ).transcription
    fatrop = tr.backends[0]
    assert isinstance(fatrop, FatropBackend)
    if not fatrop.guarded:
        pytest.skip("fatrop runs in its helper process here: no listener")
    return tr, fatrop


def test_fatrop_tells_its_listener_every_iteration() -> None:
    """k = 0, 1, ... once each; at k = 0 the objective of the start itself (unscaled), the
    infeasibility of a start off the constraints falling to the tolerance's order by the
    last."""
    tr, fatrop = _fatrop()
    x0, p = tr.start_point(tr.guesses(tr.pack())[0], tr.pack())
    x0 = x0 + 0.05 * np.random.default_rng(0).standard_normal(x0.size)
    heard: list[tuple[int, float, float]] = []
    run = fatrop.run(Start(x0, p, listener=lambda k, f, inf: heard.append((k, f, inf)) or False))
    assert run.success and run.iterations > 3
    assert [k for k, _, _ in heard] == list(range(run.iterations))
    assert heard[0][1] == pytest.approx(float(tr.f_fun(x0, p)), rel=1e-12, abs=1e-12)
    assert heard[0][2] > 1e-3 and 0.0 <= heard[-1][2] < 1e-6
    assert heard[-1][1] == pytest.approx(run.f, rel=1e-3)


def test_a_listeners_stop_keeps_the_iterate_and_the_next_solve_its_max_iter() -> None:
    """Stopped at k = 1: fatrop ends that iteration (2 done), keeps its iterate, says
    LISTENER_STOP; the next solve from the same start runs to the minimum as before."""
    tr, fatrop = _fatrop()
    x0, p = tr.start_point(tr.guesses(tr.pack())[0], tr.pack())
    free = fatrop.run(Start(x0, p))
    stopped = fatrop.run(Start(x0, p, listener=lambda k, f, inf: k >= 1))
    assert (stopped.status, stopped.iterations, stopped.success) == (LISTENER_STOP, 2, False)
    assert np.max(np.abs(stopped.x - x0)) > 1e-3
    again = fatrop.run(Start(x0, p))
    assert again.success and again.iterations == free.iterations > 2
    assert again.f == pytest.approx(free.f, rel=1e-10)


def test_a_listeners_stop_ends_the_turn() -> None:
    """A fatrop run its listener stopped is not handed to IPOPT (the same listener would stop
    it): the solve reports the stop, one run."""
    tr, _ = _fatrop()
    r = tr.solve(tr.guesses(tr.pack())[0], tr.pack(), lambda k, f, inf: k >= 1)
    assert r.status == LISTENER_STOP and r.iterations == 2 and r.backend == "fatrop"


@pytest.mark.parametrize("workers", [1, 2])
def test_fatrops_further_starts_are_stopped_by_their_iterations(monkeypatch, tmp_path,
                                                                workers: int) -> None:
    """A budget of 3 iterations and seconds without end: every further start fatrop solves
    stops after its budget's iterations (one more: it ends the iteration under way), reported
    as spent, in turn and in parallel; the first start runs to its minimum."""
    monkeypatch.setattr(compiled, "START_BUDGET", parallel.Rule(least=3, times=0, pace=1e9,
                                                                least_seconds=1e9))
    solve = Transcription.solve
    record = tmp_path / "starts"

    def spy(self, guess, *args, **kwargs):
        r = solve(self, guess, *args, **kwargs)
        with open(record, "a") as out:  # from the workers too
            out.write(f"{guess.label}\t{r.status}\t{r.iterations}\n")
        return r

    monkeypatch.setattr(Transcription, "solve", spy)
    try:
        sol = og.compile_problem(rigid_body(), N=16, workers=workers,
                                 backend="fatrop").solve(multistart=3)
    finally:
        parallel.close()  # the workers hold the spy: not for the next test
    rows = [line.split("\t") for line in record.read_text().splitlines()]
    first, *further = rows
    assert first[0] == "geodesic" and first[1] == "Solve_Succeeded"
    assert len(further) == 4
    assert {(status, int(iterations)) for _, status, iterations in further} == \
        {(LISTENER_STOP, 4)}
    ms = sol.diagnostics["multistart"]
    assert ms["workers"] == workers
    assert sorted(ms["budget_spent"]) == sorted(label for label, _, _ in further)
    assert sol.success and sol.discretization["start"] == "geodesic"
