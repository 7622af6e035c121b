"""solver.fatrop: fatrop's own options by fatrop's names, checked against fatrop's list
when they are given, over our defaults and the IPOPT options fatrop shares, on every way
fatrop runs (its own C interface, with jit or without; CasADi's nlpsol where the interface is
unavailable); and the cart-pole's, which
stops fatrop's crawl with order6 (its stage-wise factorisation calls the KKT system
indefinite once the barrier parameter falls below 1e-8)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.errors import ConfigError
from ocgroupoid.nlp.backends.fatrop import ACCEPTABLE_STOP
from ocgroupoid.solve import compile_problem

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.parametrize("fatrop, message", [
    ({"tol_acceptible": 1e-4}, "fatrop has no option tol_acceptible"),
    ({"acceptable_iter": 5.5}, "acceptable_iter is an integer, got 5.5"),
    ({"acceptable_iter": True}, "acceptable_iter is an integer, got True"),
    ({"tol_acceptable": "small"}, "tol_acceptable is a number, got 'small'"),
    ({"tol_acceptable": [1e-4]}, "fatrop options are a dict"),
    ({1: 2}, "fatrop options are a dict"),
])
def test_a_bad_option_is_refused_when_it_is_given(fatrop: dict, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        og.SolverOptions(backend="fatrop", fatrop=fatrop)


def test_a_files_bad_option_is_refused_where_it_is_written(tmp_path: Path) -> None:
    """When the file is read (before anything is built), at its line or its --set."""
    with pytest.raises(ConfigError, match=r"\(--set solver.fatrop.kappa_w_min\): "
                                          r"solver.fatrop.kappa_w_min: fatrop has no option"):
        files.load(ROOT / "problems" / "so3_rest_to_rest.yaml", ["solver.fatrop.kappa_w_min=0.1"])
    text = (ROOT / "problems" / "cart_pole.yaml").read_text()
    line = text[:text.index("  fatrop: {")].count("\n") + 1
    path = tmp_path / "cart_pole.yaml"
    path.write_text(text.replace("acceptable_iter: 5}", "acceptable_iter: 5.5}"))
    with pytest.raises(ConfigError, match=rf"cart_pole.yaml:{line}.*acceptable_iter is an "
                                          r"integer, got 5.5"):
        files.load(path)


def fatrop_run(jit: bool, fatrop: dict) -> og.Transcription:
    cfg = files.load(ROOT / "problems" / "so3_rest_to_rest.yaml", ["horizon.N=8"])
    problem, method, options = files.build_all(cfg)
    options = og.SolverOptions(backend="fatrop", ipopt=options.ipopt, fatrop=fatrop, jit=jit)
    return compile_problem(problem, method, options).transcription


@pytest.mark.parametrize("way", ["jit", "casadi", "nlpsol"])
def test_the_options_reach_fatrop_over_ours_and_ipopts(way: str, tmp_path: Path,
                                                       monkeypatch) -> None:
    """fatrop's options over ours (the acceptable stop) and the IPOPT ones it shares
    (max_iter): fatrop stops where they say, through its own interface (the Functions
    compiled, or evaluated by CasADi) and through CasADi's nlpsol, and a run it stops is
    still polished to IPOPT's minimum."""
    if way != "nlpsol" and shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler")
    monkeypatch.setenv("OCGROUPOID_JIT_CACHE", str(tmp_path))
    jit = way == "jit"
    free = fatrop_run(jit, {})
    tr = fatrop_run(jit, {"max_iter": 2, "acceptable_iter": 3})
    if way == "nlpsol":  # as where the driver does not compile
        free.fatrop.direct = tr.fatrop.direct = None
    assert (tr.fatrop.direct is not None) == (way != "nlpsol")
    opts = tr.fatrop.options["fatrop"]
    assert (opts["max_iter"], opts["acceptable_iter"]) == (2, 3)
    assert opts["tol_acceptable"] == ACCEPTABLE_STOP["tol_acceptable"]
    assert tr.fatrop.max_iter == 2  # its deadline counts the iterations it may take
    p = tr.pack()
    guess = tr.guesses(p)[0]
    x0, p = tr.start_point(guess, p)
    run = tr.fatrop._solve_here((x0, p))
    # (fatrop stops once its count passes max_iter: 3 for 2)
    assert (run.status, run.iterations) == ("Maximum_Iterations_Exceeded", 3)
    unlimited = free.fatrop._solve_here((x0, p))
    assert unlimited.success and unlimited.iterations > 3
    r = tr.solve(guess, p)
    assert r.success and r.earlier[0][:2] == ("fatrop", "Maximum_Iterations_Exceeded")
    assert r.cost == pytest.approx(unlimited.f, rel=1e-9)


def test_the_cart_poles_order6_stops_crawling_at_ipopts_minimum() -> None:
    """The cart-pole's order6 at N = 16 from the first guess: with the file's acceptable stop
    (5 within 1e-4) fatrop stops after at most 30 iterations (73 with ours) and IPOPT's
    polish reaches the minimum IPOPT reaches alone."""
    cfg = files.load(ROOT / "problems" / "cart_pole.yaml",
                     ["horizon.N=16", "discretization.scheme=order6", "solver.multistart=false"])
    problem, method, options = files.build_all(cfg)
    assert options.fatrop == {"tol_acceptable": 1e-4, "acceptable_iter": 5}
    solver = compile_problem(problem, method, options)
    tr = solver.transcription
    p = tr.pack()
    guess = tr.guesses(p)[0]
    r = tr.solve(guess, p)
    (who, status, crawled), = r.earlier
    assert (who, status) == ("fatrop", "Solved_To_Acceptable_Level") and crawled <= 30
    assert r.success and r.backend == "ipopt polish after fatrop" and r.iterations <= 6
    alone = compile_problem(problem, method, og.SolverOptions(ipopt=options.ipopt))
    a = alone.transcription.solve(guess, p)
    assert a.success and r.cost == pytest.approx(a.cost, rel=1e-9)
