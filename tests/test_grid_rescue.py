"""A final grid whose every start failed, and its scheme's rescue too, is rescued through a
grid a quarter as fine: that grid from the same start, then the final one from its solution
with its multipliers carried (``CompiledProblem._grid_rescue``)."""

from __future__ import annotations

import pytest
from rich.console import Console

import ocgroupoid as og
from ocgroupoid.cli.summary import summary
from ocgroupoid.solve.compiled import GRID_RESCUE_MIN, MAX_ITER
from ocgroupoid.systems.heavy_top import heavy_top


def _far(solver: og.CompiledProblem) -> og.Guess:
    tr = solver.transcription
    return next(g for g in solver.guesses(tr, tr.pack(), True)
                if g.label == "great circle, long way")


def test_a_failed_fine_grid_is_rescued_through_a_quarter_of_it() -> None:
    """The heavy top from the great circle the long way round, order4 on N = 128, IPOPT held to
    31 iterations: order4 fails, and so does its order2 rescue (it needs 47); N = 32 solves
    from the same start (28) and N = 128 from its solution (4). Verified, at the minimum that
    solving N = 32 and then N = 128 from its solution reaches without the limit; the rescue
    told in the diagnostics and the table, its time counted. Held to 20, N = 32 fails too and
    the hint says what was tried."""
    solver = og.compile_problem(heavy_top(), N=128, scheme="order4", ipopt={"max_iter": 31})
    sol = solver.solve(guess=_far(solver), multistart=False)
    coarse_solver = og.compile_problem(heavy_top(), N=32, scheme="order4")
    coarse = coarse_solver.solve(guess=_far(coarse_solver), multistart=False)
    fine = og.compile_problem(heavy_top(), N=128, scheme="order4").solve(guess=coarse,
                                                                         multistart=False)
    assert coarse.success and fine.success
    assert sol.success and sol.cost == pytest.approx(fine.cost, rel=1e-9)
    rescue = sol.diagnostics["rescue"]
    assert rescue["rescued"] and rescue["grid"] == 32 and rescue["scheme"] == "order2"
    assert rescue["failed"] == MAX_ITER and len(rescue["iterations"]) == 3
    assert rescue["iterations"][0] == 31 and sol.iterations == rescue["iterations"][-1] < 31
    assert sol.discretization["start"] == "great circle, long way, through N=32"
    assert sol.ipopt_seconds_total > sol.solve_seconds + rescue["seconds"] / 2
    console = Console(width=400, record=True)
    console.print(summary(sol))
    table = console.export_text()
    assert "a rescue through order2 and N=32" in table and "│ rescued " in table
    assert "then solved N=32 first, then N=128 from its solution: N=32 Solve_Succeeded" in table

    held = og.compile_problem(heavy_top(), N=128, scheme="order4", ipopt={"max_iter": 20})
    hopeless = held.solve(guess=_far(held), multistart=False)
    assert not hopeless.success and not hopeless.diagnostics["rescue"]["rescued"]
    assert "then tried N=32 first" in hopeless.hint


def test_no_grid_rescue_below_its_coarsest_grid() -> None:
    """On N = 32 a quarter would be 8 intervals, fewer than GRID_RESCUE_MIN: the failed solve
    is rescued through order2 alone, as before."""
    assert 32 // 4 < GRID_RESCUE_MIN <= 128 // 4
    solver = og.compile_problem(heavy_top(), N=32, scheme="order4", ipopt={"max_iter": 5})
    sol = solver.solve(guess=_far(solver), multistart=False)
    assert not sol.success and "grid" not in sol.diagnostics["rescue"]
