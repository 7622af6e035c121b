"""order4 draws bounded recovered controls as lines (:mod:`ocgroupoid.nlp.control_lines`).

When every bound of a problem bounds a recovered control, order4 makes those controls
variables, linear on each interval and equal to the recovered ones at the Gauss points; the
bounds then hold at the interval's ends, and so on the whole interval. Tested: when it
applies, that the bound holds everywhere on the solved plan (the recovered cubic, bounded at
four points, overshot between them), that the scheme keeps its fourth order, that it reaches
the recovered formulation's limit, and that the solution is verified.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ocgroupoid import files
from ocgroupoid.nlp.control_lines import TIE, ControlLines
from ocgroupoid.nlp.stages import Stages
from ocgroupoid.solve import CompiledProblem, compile_problem

PROBLEMS = Path(__file__).resolve().parent.parent / "problems"


def compiled(name: str, *overrides: str) -> CompiledProblem:
    """A problem file compiled with order4, one start."""
    cfg = files.load(PROBLEMS / f"{name}.yaml", ["discretization.scheme=order4",
                                                 "solver.multistart=false", *overrides])
    return compile_problem(files.build(cfg), files.method(cfg), files.options(cfg))


def test_only_bounded_controls_are_drawn_as_lines() -> None:
    """so3_minimum_time bounds its three recovered controls and nothing else: lines, their
    bounds at the ends, one tie row per control at each Gauss point. The reaction wheels
    also bound a wheel rate (the motion, at four points): recovered controls as before. An
    unbounded problem keeps them too."""
    tr = compiled("so3_minimum_time", "horizon.N=8").transcription
    scheme = tr.scheme
    assert isinstance(scheme.stages, ControlLines)
    assert scheme.stages.n_u == 3
    np.testing.assert_array_equal(scheme.bound_times, [0.0, 1.0])
    path = next(b for b in tr.blocks if b.name == "interval")
    assert [r for r in path.rows if TIE in r] == [f"u{i} {TIE} (Gauss point {j})"
                                                  for j in (1, 2) for i in (1, 2, 3)]
    for name in ("reaction_wheels", "so3_rest_to_rest"):
        stages = compiled(name, "horizon.N=8").transcription.scheme.stages
        assert type(stages) is Stages, name


def test_the_bound_holds_on_the_whole_interval() -> None:
    """The reported control of so3_minimum_time, sampled densely, stays within |u| <= 0.5
    (to the solver's bound relaxation): a line within its bounds at both ends is within them
    between. The recovered cubic, bounded at the ends and the Gauss points, overshot by
    1.8e-3 at N = 64."""
    sol = compiled("so3_minimum_time", "horizon.N=16").solve()
    assert sol.success, sol.hint
    t = np.linspace(0.0, sol.T, 4001)
    assert np.abs(sol.control(t)).max() <= 0.5 * (1 + 1e-8)
    assert np.abs(sol.controls).max() > 0.5 * (1 - 1e-6)  # the bounds are active


def test_lines_keep_order_four() -> None:
    """A smooth slew with a bound that stays inactive (|u| <= 10) is drawn with lines; its
    cost converges at order 4 to the recovered formulation's limit (measured against N =
    128: orders 3.94 and 3.99 from N = 8 to 32; against N = 256, 3.95, 3.99 and 4.00 from N = 8
    to 64, and the two limits agree to 2e-11)."""
    name = "so3_rest_to_rest"
    costs = {}
    for N in (8, 16, 32, 128):
        solver = compiled(name, f"horizon.N={N}", "bounds.u=[-10.0, 10.0]")
        assert isinstance(solver.transcription.scheme.stages, ControlLines)
        costs[N] = solver.solve(replay=False).cost
    errors = np.array([abs(costs[N] - costs[128]) for N in (8, 16, 32)])
    orders = np.log2(errors[:-1] / errors[1:])
    assert orders.min() > 3.7, orders
    recovered = compiled(name, "horizon.N=128").solve(replay=False).cost
    assert abs(costs[128] - recovered) < 1e-9 * recovered
