"""A coarse grid's multipliers carried onto a finer grid (ocgroupoid.solve.multipliers): they
converge to the finer grid's own as the grids are refined, block by block, with the bounds'
scaled by the ratio of the steps; they carry only between grids of one scheme and to IPOPT;
the warm start they give is what continuation and accuracy on demand run, and a failed warm
start is solved again without them."""

from __future__ import annotations

import pickle
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.nlp.assembly import Kind
from ocgroupoid.nlp.transcription import RawResult, Transcription
from ocgroupoid.solve.multipliers import carried, onto
from ocgroupoid.solve.rows import Rows

QMT = Path(__file__).resolve().parent.parent / "problems" / "quadrotor_min_time.yaml"


def compiled(N: int, *sets: str) -> og.CompiledProblem:
    """quadrotor_min_time on N intervals: bounds, a free horizon, final conditions."""
    cfg = files.load(QMT, [f"horizon.N={N}", *sets])
    return og.compile_problem(files.build(cfg), files.method(cfg), files.options(cfg))


@pytest.fixture(scope="module")
def solved() -> dict[int, tuple[Transcription, og.Solution]]:
    out = {}
    for N in (16, 32, 64):
        c = compiled(N)
        sol = c.solve(multistart=False)
        assert sol.success, sol.status
        out[N] = (c.transcription, sol)
    return out


def errors(solved: dict[int, tuple[Transcription, og.Solution]], N: int,
           bound_scale: float = 1.0) -> dict[str, float]:
    """Per block of the grid 2N: |carried from N - its own| / |its own|, the bounds' carried
    multipliers times ``bound_scale``."""
    (tc, sc), (tf, sf) = solved[N], solved[2 * N]
    duals = carried(Rows.of(tc), sc.lam_g, sc.lam_x, Rows.of(tf))
    assert duals is not None
    lam_g, lam_x = duals
    assert lam_g.shape == sf.lam_g.shape and lam_x.shape == sf.lam_x.shape
    assert np.allclose(lam_x, sf.lam_x, rtol=0.0, atol=1e-9)  # the free horizon's bounds
    out = {}
    for b in tf.blocks:
        rows = b.g_rows
        if rows.size:
            scale = bound_scale if b.kind is Kind.INEQUALITY else 1.0
            out[b.name] = float(np.linalg.norm(scale * lam_g[rows] - sf.lam_g[rows])
                                / np.linalg.norm(sf.lam_g[rows]))
    return out


def test_carried_multipliers_converge_to_the_finer_grids_own(solved) -> None:
    """Every block's carried multipliers approach the finer grid's own under refinement
    (measured: 0.03-0.23 from N = 16 to 32, 0.01-0.10 from 32 to 64); the bounds' only with
    their scaling by the steps' ratio: unscaled they are off by their own size."""
    coarse, fine = errors(solved, 16), errors(solved, 32)
    assert set(fine) == {"recon", "interval", "interval_bounds", "final"}
    for name in fine:
        assert fine[name] < coarse[name], (name, coarse[name], fine[name])
        assert fine[name] < 0.15, (name, fine[name])
    unscaled = errors(solved, 32, bound_scale=2.0)  # undo the scaling by 32/64
    assert unscaled["interval_bounds"] > 0.5


def test_a_switching_control_is_carried_point_by_point() -> None:
    """The cart-pole's force switches between its bounds, which hold at four points of every
    interval; an interval's end and the next one's start share a time but not their
    multipliers across a switch. Carried point by point, the warm start from N = 64 takes
    about the cold start's iterations (measured 15 against 18; with all four points
    interpolated at once 36, with the pushes of a polish 19)."""
    cart_pole = QMT.parent / "cart_pole.yaml"

    def at(N: int) -> og.CompiledProblem:
        cfg = files.load(cart_pole, [f"horizon.N={N}", "solver.backend=ipopt"])
        return og.compile_problem(files.build(cfg), files.method(cfg), files.options(cfg))

    coarse, fine = at(64), at(128)
    first = coarse.solve(multistart=False)
    tc, tf = coarse.transcription, fine.transcription
    assert next(b for b in tf.blocks if b.kind is Kind.INEQUALITY).points == 4
    warm_start = onto(tc, first, tf, tf.pack())
    assert warm_start.primal is not None
    cold = fine.solve(multistart=False, guess=warm_start.primal)
    warm = fine.solve(multistart=False, guess=warm_start)
    assert cold.success and warm.success
    assert warm.cost == pytest.approx(cold.cost, rel=1e-9)
    assert warm.iterations <= cold.iterations + 5, (warm.iterations, cold.iterations)


def test_carried_multipliers_start_ipopt_with_larger_bound_pushes(solved) -> None:
    """The interpolated point's controls cross their bounds where the coarse ones switched
    (N = 16 to 32: up to 24.7 outside), so IPOPT's carried warm start pushes the slacks 1e-5
    inside them, not a polish's 1e-9, and takes fewer iterations than the cold start from
    the same point (measured 24 against 27; with the pushes at 1e-9, 37)."""
    (tc, sc), (tf, _) = solved[16], solved[32]
    p = tf.pack()
    start = onto(tc, sc, tf, p)
    assert start.primal is not None
    x0, _ = tf.start_point(start, p)
    g = np.asarray(tf.g_fun(x0, p)).ravel()
    lbg, ubg, _, _ = (np.asarray(b).ravel() for b in tf.bounds_function(p))
    assert np.max(np.maximum(lbg - g, g - ubg)) > 1.0  # the bounds crossed
    ipopt = tf.backends[-1]
    for name in ("warm_solver", "carried_solver"):
        vars(ipopt).pop(name, None)
    cold, warm = tf.solve(start.primal, p), tf.solve(start, p)
    assert "carried_solver" in vars(ipopt) and "warm_solver" not in vars(ipopt)
    assert cold.success and warm.success
    assert warm.cost == pytest.approx(cold.cost, rel=1e-9)
    assert warm.iterations < cold.iterations, (warm.iterations, cold.iterations)


def test_multipliers_carry_between_grids_of_one_scheme_to_ipopt_only(solved) -> None:
    tc, sc = solved[16]
    order2 = compiled(32, "discretization.scheme=order2").transcription
    assert carried(Rows.of(tc), sc.lam_g, sc.lam_x, Rows.of(order2)) is None
    p = solved[32][0].pack()
    warm = onto(tc, sc, solved[32][0], p)
    assert warm.x is not None and warm.lam_g is not None and warm.primal is not None
    assert warm.label == "interpolated from N=16, with its multipliers"
    assert warm.primal.x is None and warm.T == pytest.approx(sc.T)
    fatrop = compiled(32, "solver.backend=fatrop").transcription
    start = onto(tc, sc, fatrop, fatrop.pack())
    assert start.x is None and start.lam_g is None and start.primal is None


def test_continuation_starts_the_finer_grid_warm_and_lands_on_its_minimum(solved) -> None:
    """The continuation's last grid starts from the coarse point and multipliers and ends at
    the minimum a direct solve of that grid finds."""
    sol = compiled(64).solve(multistart=False, continuation=[32])
    assert sol.success
    assert sol.discretization["start"] == "interpolated from N=32, with its multipliers"
    assert sol.cost == pytest.approx(solved[64][1].cost, rel=1e-9)
    assert "continuation" not in sol.diagnostics  # nothing failed


def test_a_solution_given_as_the_guess_of_another_grid_brings_its_multipliers(solved) -> None:
    """``solve(guess=solution)`` on a finer grid starts from the solution's multipliers too
    (the Solution keeps its NLP's rows), lands on the minimum the direct solve finds, and
    takes fewer iterations than from the same velocities alone (measured N = 16 to 32: 24
    against 27; 128 to 512: 18 against 413). A solution read from its file carries no rows:
    the solve takes them from its own grid of the file's N (the same problem, scheme,
    retraction and rule) and starts exactly as from the solution itself; from a file of
    another method, or with a multiplier it could not read (null), from its velocities
    alone."""
    sc = solved[16][1]
    assert sc.rows is not None and sc.rows.N == 16 and sc.rows.ng == sc.lam_g.size
    fine = compiled(32)
    warm = fine.solve(multistart=False, guess=sc)
    assert warm.discretization["start"] == "interpolated from a solution (order4, N=16), " \
        "with its multipliers"
    read = og.Solution.from_json(sc.to_json())
    assert read.rows is None
    again = fine.solve(multistart=False, guess=read)
    assert again.discretization["start"] == warm.discretization["start"]
    assert again.iterations == warm.iterations and again.cost == pytest.approx(warm.cost,
                                                                               rel=1e-12)
    other = replace(read, discretization={**read.discretization, "rule": "trapezoidal"})
    cold = fine.solve(multistart=False, guess=other)
    assert cold.discretization["start"] == "interpolated from a solution (order4, N=16)"
    damaged = replace(read, lam_g=np.where(np.arange(read.lam_g.size) == 3, np.nan, read.lam_g))
    assert fine._rows_of(damaged) is None and fine._rows_of(read) is not None  # (a null)
    assert warm.success and cold.success
    assert warm.cost == pytest.approx(solved[32][1].cost, rel=1e-9)
    assert cold.cost == pytest.approx(warm.cost, rel=1e-9)
    assert warm.iterations < cold.iterations, (warm.iterations, cold.iterations)
    kept = pickle.loads(pickle.dumps(sc))  # a sweep's worker sends its solutions back
    assert kept.rows is not None and carried(kept.rows, kept.lam_g, kept.lam_x,
                                             Rows.of(solved[32][0])) is not None


def test_a_solution_of_another_problem_as_the_guess_is_a_clear_error(solved) -> None:
    """The quadrotor's solution has no cart-pole velocities: one line that says so, no
    KeyError."""
    cfg = files.load(QMT.parent / "cart_pole.yaml", ["horizon.N=16", "solver.backend=ipopt"])
    cart_pole = og.compile_problem(files.build(cfg), files.method(cfg), files.options(cfg))
    with pytest.raises(og.ConfigError, match=r"has no velocities \['dx', 'dtheta'\]"):
        cart_pole.solve(multistart=False, guess=solved[16][1])


def test_a_failed_warm_start_is_solved_again_without_the_multipliers(monkeypatch) -> None:
    """The warm start is made to fail: the grid is solved again from the interpolated
    velocities alone, to the minimum, and the note says so."""
    real = Transcription.solve
    tried: list[str] = []

    def failing(self, guess, *args, **kwargs):  # type: ignore[no-untyped-def]
        r = real(self, guess, *args, **kwargs)
        tried.append(guess.label)
        if guess.lam_g is not None:
            return RawResult(guess.label, r.x, r.p, r.lam_g, r.cost, "Maximum_Iterations_Exceeded",
                             False, 3000, r.solve_seconds, r.lam_x)
        return r

    monkeypatch.setattr(Transcription, "solve", failing)
    sol = compiled(32).solve(multistart=False, continuation=[16])
    assert tried[-2:] == ["interpolated from N=16, with its multipliers",
                          "interpolated from N=16"]
    assert sol.success and sol.discretization["start"] == "interpolated from N=16"
    notes = sol.diagnostics["continuation"]
    assert any("ended Maximum_Iterations_Exceeded; solved again without the multipliers "
               "(Solve_Succeeded)" in n for n in notes), notes


def test_accuracy_on_demand_warm_starts_each_grid_from_the_last(monkeypatch) -> None:
    """Accuracy on demand starts every grid after the first from the last one's point and
    multipliers, and meets its target."""
    from ocgroupoid.solve import accuracy

    starts: list[str] = []

    def recorded(*args, **kwargs):  # type: ignore[no-untyped-def]
        guess = onto(*args, **kwargs)
        starts.append(guess.label)
        return guess

    monkeypatch.setattr(accuracy, "onto", recorded)
    cfg = files.load(QMT, ["horizon.N=16"])
    sol = og.solve_to_accuracy(files.build(cfg), accuracy=1e-4, N_min=16, N_max=128,
                               method=files.method(cfg), options=files.options(cfg),
                               multistart=False)
    assert sol.success and sol.error_estimate is not None and sol.error_estimate <= 1e-4
    assert starts and all(s.endswith("with its multipliers") for s in starts), starts
