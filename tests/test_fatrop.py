"""solver.backend fatrop (issue 18): the stage form of every scheme is the same NLP in
fatrop's order, and fatrop reaches IPOPT's cost on the problem files."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from rich.console import Console

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.cli.summary import summary
from ocgroupoid.errors import ConfigError
from ocgroupoid.nlp.assembly import Block, Kind
from ocgroupoid.nlp.backends import Backend, Run, Start, in_turn
from ocgroupoid.nlp.schemes.base import stage_function
from ocgroupoid.nlp.stageform import NotStaged, StageForm, stage_form
from ocgroupoid.solve import compile_problem
from ocgroupoid.solve.compiled import RESCUE_ITERATIONS
from ocgroupoid.systems.heavy_top import heavy_top

ROOT = Path(__file__).resolve().parent.parent
PROBLEMS = sorted((ROOT / "problems").glob("*.yaml"))
#: the canonical problems: fatrop itself must solve them (no IPOPT fallback)
CANONICAL = ("so3_rest_to_rest", "plate_ball", "plate_ball_rotating", "heavy_top_rotors")
TOL = 1e-8  # the tolerance on the cost


def transcription(name: str, scheme: str, N: int | None = None, backend: str = "ipopt",
                  jit: bool = False, tol: float | None = None) -> og.Transcription:
    cfg = files.load(ROOT / "problems" / f"{name}.yaml", [f"discretization.scheme={scheme}"])
    f, d = cfg.file, cfg.file.discretization
    ipopt = {**f.solver.ipopt, **({"tol": tol} if tol else {})}
    return compile_problem(files.build(cfg), N or f.horizon.N, d.retraction, d.rule, ipopt,
                           d.scheme, d.steps, jit, backend).transcription


def stage_of_z(sf: StageForm) -> np.ndarray:
    sizes = [nx + nu for nx, nu in zip(sf.nx, sf.nu)]
    return np.repeat(np.arange(len(sizes)), sizes)


# ------------------------------------------------------------------ the stage form


STAGED = [("so3_rest_to_rest", "order2"), ("so3_rest_to_rest", "order4"),
          ("so3_rest_to_rest", "rk4_quat"), ("plate_ball", "order2"), ("plate_ball", "order4"),
          ("so3_minimum_time", "order2"), ("so3_minimum_time", "order4"),
          ("heavy_top_rotors", "order4"), ("reaction_wheels", "order2"),
          ("free_flyer", "order4"), ("cart_pole", "order4")]


@pytest.mark.parametrize("name,scheme", STAGED, ids=[f"{n}-{s}" for n, s in STAGED])
def test_stage_form_is_the_same_nlp_in_stage_order(name: str, scheme: str) -> None:
    """At a random point: the same cost, the original rows permuted, copies satisfied, each
    scaled by its factor at that point (IPOPT's gradient-based scaling: no row's gradient
    above the file's ``nlp_scaling_max_gradient``, the gap rows unscaled); every row reads
    one stage (a gap row also x_{k+1}, once, with coefficient +1) and the Hessian of the
    Lagrangian is the scaled one, block diagonal by stage (fatrop drops what lies outside)."""
    tr = transcription(name, scheme, N=8, backend="fatrop")
    sf = tr.fatrop.form
    rng = np.random.default_rng(0)
    p = tr.pack()
    x = tr.point(tr.guesses(p)[0], p) + 0.01 * rng.standard_normal(tr.nx)
    z = sf.z_of(x)
    q = tr.fatrop.arguments(x, p)["p"]
    s, s_f = q[p.size:-1], q[-1]
    assert np.all(s[sf.gap_rows] == 1.0) and np.all((0 < s) & (s <= 1)) and 0 < s_f <= 1
    nlp = tr.fatrop.solver
    f_z = float(nlp.get_function("nlp_f")(z, q))
    g_z = np.array(nlp.get_function("nlp_g")(z, q)).ravel()
    assert f_z == pytest.approx(s_f * float(tr.f_fun(x, p)), rel=1e-13)
    np.testing.assert_allclose(sf.rows_x(g_z / s), np.array(tr.g_fun(x, p)).ravel(), rtol=0,
                               atol=1e-13)
    assert np.all(g_z[sf.rank[sf.n_rows:]] == 0.0)  # the copies hold their variables
    assert sum(sf.nx) + sum(sf.nu) == sf.nz and sum(sf.ng) + sum(sf.nx[1:]) == g_z.size
    ipopt = files.load(ROOT / "problems" / f"{name}.yaml").file.solver.ipopt
    max_gradient = float(ipopt.get("nlp_scaling_max_gradient", 100.0))
    assert name != "cart_pole" or np.any(s < 1)  # its file scales at 10
    scaled_jac = np.abs(np.array(ca.DM(nlp.get_function("nlp_jac_g")(z, q)[1])))
    assert np.all(scaled_jac[~sf.gap_rows].max(axis=1, initial=0.0)
                  <= max_gradient * (1 + 1e-12))
    # rows in fatrop's order: per stage k, nx[k+1] gap rows, then ng[k] stage rows
    stage = stage_of_z(sf)
    first = np.cumsum([0] + [nx + nu for nx, nu in zip(sf.nx, sf.nu)])
    _, jac = nlp.get_function("nlp_jac_g")(z, q)
    jac = ca.DM(jac)
    rows, cols = (np.array(v) for v in jac.sparsity().get_triplet())
    values = np.array(jac.nonzeros())
    r = 0
    for k in range(sf.K + 1):
        for i in range(sf.nx[k + 1] if k < sf.K else 0):  # gap rows into x_{k+1}
            here = rows == r + i
            ahead = cols[here][stage[cols[here]] == k + 1]
            assert ahead.tolist() == [first[k + 1] + i]
            assert values[here][stage[cols[here]] == k + 1].tolist() == [1.0]
            assert set(stage[cols[here]]) <= {k, k + 1}
        r += sf.nx[k + 1] if k < sf.K else 0
        for i in range(sf.ng[k]):
            assert set(stage[cols[rows == r + i]]) <= {k}
        r += sf.ng[k]
    lam = rng.standard_normal(g_z.size)
    hess_l = nlp.get_function("nlp_hess_l")
    grad_l, hess = hess_l(z, q, 1.0, lam)
    hr, hc = ca.DM(hess).sparsity().get_triplet()
    assert np.array_equal(stage[np.array(hr)], stage[np.array(hc)])
    # the scaled Lagrangian s_f f + lam^T (s g): its gradient from the scaled f and g, its
    # Hessian the derivative of that gradient (central differences)
    grad_f = np.array(nlp.get_function("nlp_grad_f")(z, q)).ravel()
    np.testing.assert_allclose(np.array(grad_l).ravel(), grad_f + jac.full().T @ lam,
                               rtol=1e-10, atol=1e-10)
    d, eps = rng.standard_normal(z.size), 1e-6
    fd = (np.array(hess_l(z + eps * d, q, 1.0, lam)[0]).ravel()
          - np.array(hess_l(z - eps * d, q, 1.0, lam)[0]).ravel()) / (2 * eps)
    np.testing.assert_allclose(ca.DM(hess).full() @ d, fd, rtol=0,
                               atol=1e-6 * max(1.0, float(np.max(np.abs(fd)))))


def test_a_block_reading_a_later_stage_is_refused() -> None:
    """Two gap rows chained backwards (interval 0 reads the state interval 1 defines): not a
    chain of stages, and the message says which block."""
    step = stage_function("step", [1, 1], lambda s, s1: (ca.SX(1, 1), s1 - 2 * s))
    # variables: a (free), b = 2 a ... but column 0 reads c, which column 1 defines
    idx = np.array([[2, 0], [1, 2]])
    blocks = [Block("recon", step, idx, 0, Kind.RECONSTRUCTION, next=slice(1, 2))]
    with pytest.raises(NotStaged, match="recon"):
        stage_form(blocks, 3)


def test_unknown_backend_is_refused_with_the_choices() -> None:
    with pytest.raises(ConfigError, match="ipopt, fatrop"):
        transcription("so3_rest_to_rest", "order2", N=8, backend="mumps")
    with pytest.raises(ConfigError, match="backend"):
        files.load(ROOT / "problems" / "so3_rest_to_rest.yaml", ["solver.backend=snopt"])


# ------------------------------------------------------------------ fatrop against IPOPT


def bound_violation(tr: og.Transcription, x: np.ndarray, p: np.ndarray) -> float:
    g = np.array(tr.g_fun(x, p)).ravel()
    lbg, ubg, lbx, ubx = (np.array(v).ravel() for v in tr.bounds_function(p))
    return float(max(np.max(np.maximum(lbg - g, 0.0), initial=0.0),
                     np.max(np.maximum(g - ubg, 0.0), initial=0.0),
                     np.max(np.maximum(lbx - x, 0.0), initial=0.0),
                     np.max(np.maximum(x - ubx, 0.0), initial=0.0)))


CASES = [(path.stem, scheme) for path in PROBLEMS for scheme in ("order2", "order4")]


@pytest.mark.parametrize("name,scheme", CASES, ids=[f"{n}-{s}" for n, s in CASES])
def test_fatrop_reaches_ipopts_cost(name: str, scheme: str) -> None:
    """Every problem file, both schemes, its own N, from the first geodesic guess: where
    fatrop converges, IPOPT's cost to 1e-8 relative with the bounds held as tightly as
    IPOPT holds them; where it does not, IPOPT's result from the same start (the fallback).
    On the canonical problems fatrop itself converges. Both solve to tol 1e-12: at the
    files' 1e-10, IPOPT's cost of reaction_wheels (order4) is 4e-8 above the optimum
    (0.0435338592 against 0.0435338575 at 1e-12 and 1e-13), fatrop's 1e-8."""
    ipopt = transcription(name, scheme, tol=1e-12)
    fatrop = transcription(name, scheme, backend="fatrop", tol=1e-12)
    p = ipopt.pack()
    guess = ipopt.guesses(p)[0]
    a, b = ipopt.solve(guess, p), fatrop.solve(guess, p)
    assert a.success, a.status
    assert b.success, b.status
    if name in CANONICAL:
        assert b.backend == "fatrop", b.status
    assert abs(b.cost - a.cost) <= TOL * abs(a.cost), (a.cost, b.cost, b.backend)
    assert bound_violation(fatrop, b.x, p) <= 1e-12
    same_point = np.max(np.abs(b.x - a.x)) <= 1e-6 * max(1.0, float(np.max(np.abs(a.x))))
    if b.backend == "fatrop" and same_point:  # the multipliers map back to the original rows
        scale = max(1.0, float(np.max(np.abs(a.lam_g))))
        assert np.max(np.abs(b.lam_g - a.lam_g)) <= 1e-5 * scale
        scale = max(1.0, float(np.max(np.abs(a.lam_x))))
        assert np.max(np.abs(b.lam_x - a.lam_x)) <= 1e-5 * scale


def test_solution_json_names_the_backend(tmp_path: Path) -> None:
    sol = og.solve(files.build(files.load(ROOT / "problems" / "plate_ball.yaml")), N=16,
                   backend="fatrop")
    assert sol.success and sol.backend == "fatrop"
    again = og.Solution.from_json(sol.to_json(tmp_path / "s.json"))
    assert again.backend == "fatrop"


def test_jit_compiled_fatrop_equals_the_virtual_machine(tmp_path: Path, monkeypatch) -> None:
    """solver.jit with fatrop: the compiled Functions give the same solve to 1e-10."""
    import shutil
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler")
    monkeypatch.setenv("OCGROUPOID_JIT_CACHE", str(tmp_path))
    vm = transcription("plate_ball", "order2", N=16, backend="fatrop")
    jit = transcription("plate_ball", "order2", N=16, backend="fatrop", jit=True)
    assert jit.jit_compiled
    p = vm.pack()
    guess = vm.guesses(p)[0]
    a, b = vm.solve(guess, p), jit.solve(guess, p)
    assert a.success and b.success and a.iterations == b.iterations
    assert abs(a.cost - b.cost) <= 1e-10 * abs(a.cost)
    np.testing.assert_allclose(b.x, a.x, rtol=0, atol=1e-10)


def test_jit_compiles_ipopts_functions_beside_fatrops(tmp_path: Path, monkeypatch) -> None:
    """solver.jit with fatrop compiles IPOPT's Functions too (its polish and fallback), into
    fatrop's library: one library, the stages' derivatives made once for both assemblies,
    and IPOPT's Functions (their Hessian from the stage Lagrangian's) equal to the virtual
    machine's, so that IPOPT's run from the same start is the same run."""
    import shutil
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler")
    monkeypatch.setenv("OCGROUPOID_JIT_CACHE", str(tmp_path))
    vm = transcription("quadrotor_min_time", "order4", N=8, backend="fatrop")
    jit = transcription("quadrotor_min_time", "order4", N=8, backend="fatrop", jit=True)
    assert jit.jit_compiled and len(list(tmp_path.glob("ocg_jit_*.so"))) == 1
    staged = jit.fatrop.form.blocks[0]
    original = next(b for b in jit.blocks if b.fun is staged.fun)
    assert jit.derivatives.of(staged) is jit.derivatives.of(original)
    ours, theirs = vm.backends[-1].options["cache"], jit.backends[-1].options["cache"]
    assert all(theirs[k].name() == k for k in theirs)  # nlpsol's cache goes by name
    called = {fn.instruction_MX(i).which_function().name() for fn in theirs.values()
              for i in range(fn.n_instructions()) if fn.instruction_MX(i).is_call()}
    assert called == {f"s1_{k}" for k in theirs}  # each calls its code in the library
    rng = np.random.default_rng(3)
    x, p = rng.standard_normal(vm.nx), vm.pack()
    lam_g = rng.standard_normal(vm.ng)
    for name, args in (("nlp_grad_f", (x, p)), ("nlp_jac_g", (x, p)),
                       ("nlp_hess_l", (x, p, 0.7, lam_g))):
        for a, b in zip(ours[name].call(list(args)), theirs[name].call(list(args))):
            a, b = ca.DM(a).full(), ca.DM(b).full()
            np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(a).max()))
    guess = vm.guesses(p)[0]
    x0, p = vm.start_point(guess, p)
    a, b = vm.backends[-1].run(Start(x0, p)), jit.backends[-1].run(Start(x0, p))
    assert a.success and b.success and a.iterations == b.iterations
    assert abs(a.f - b.f) <= 1e-10 * abs(a.f)


def test_fatrop_reads_the_ipopt_options_it_shares() -> None:
    """tol and max_iter pass through, constr_mult_init_max (zero initial multipliers, our
    default) becomes fatrop's lam_max, acceptable_tol its tol_acceptable (else its
    acceptable stop's own, 1e-5) and perturb_dec_fact its kappa_wmin, and IPOPT-only
    options stay with IPOPT; with zero initial multipliers fatrop needs no more iterations
    than IPOPT on the so3 slew."""
    cfg = files.load(ROOT / "problems" / "so3_rest_to_rest.yaml")
    pb = files.build(cfg)
    tr = compile_problem(pb, 32, ipopt={"tol": 1e-9, "max_iter": 77, "linear_solver": "mumps",
                                        "acceptable_tol": 1e-7, "perturb_dec_fact": 0.1},
                         backend="fatrop").transcription
    opts = tr.fatrop.options["fatrop"]
    assert (opts["tol"], opts["max_iter"], opts["lam_max"]) == (1e-9, 77, 0.0)
    assert (opts["tol_acceptable"], opts["acceptable_iter"]) == (1e-7, 20)
    assert opts["kappa_wmin"] == 0.1 and "perturb_dec_fact" not in opts
    assert "linear_solver" not in opts
    plain = compile_problem(pb, 32, backend="fatrop").transcription.fatrop.options["fatrop"]
    assert plain["tol_acceptable"] == 1e-5 and "kappa_wmin" not in plain
    ipopt = transcription("so3_rest_to_rest", "order2", N=32)
    p = tr.pack()
    guess = tr.guesses(p)[0]
    assert tr.solve(guess, p).iterations <= ipopt.solve(guess, p).iterations


@pytest.mark.parametrize("ipopt, message", [
    ({"nlp_scaling_method": "equilibration-based"}, "gradient-based or none"),
    ({"nlp_scaling_max_gradient": 0.0}, "nlp_scaling_max_gradient"),
    ({"nlp_scaling_max_gradient": "10"}, "nlp_scaling_max_gradient"),
    ({"nlp_scaling_min_value": -1.0}, "nlp_scaling_min_value"),
])
def test_fatrop_refuses_a_scaling_it_is_not_given(ipopt: dict, message: str) -> None:
    """fatrop is given IPOPT's gradient-based scaling or none: another method is a
    ConfigError saying so, not a silently unscaled solve; a value out of range is refused
    (by IPOPT, its fallback) with the option's name."""
    pb = files.build(files.load(ROOT / "problems" / "so3_rest_to_rest.yaml"))
    with pytest.raises(ConfigError, match=message):
        compile_problem(pb, 8, ipopt=ipopt, backend="fatrop")


def test_fatrop_without_scaling_is_given_unit_scales() -> None:
    """``nlp_scaling_method: none``: the cart-pole's rows, which its file scales at 10, reach
    fatrop unscaled (every factor 1)."""
    cfg = files.load(ROOT / "problems" / "cart_pole.yaml")
    scales = {}
    for method in ("gradient-based", "none"):
        tr = compile_problem(files.build(cfg), 16, ipopt={**cfg.file.solver.ipopt,
                                                          "nlp_scaling_method": method},
                             backend="fatrop").transcription
        p = tr.pack()
        q = tr.fatrop.arguments(tr.point(tr.guesses(p)[0], p), p)["p"]
        assert q.size == p.size + tr.fatrop.form.order.size + 1
        scales[method] = q[p.size:]
    assert np.any(scales["gradient-based"] < 1) and np.all(scales["none"] == 1.0)


# ------------------------------------------------------------------ the rescue in the turn

class Scripted(Backend):
    """A backend that returns a given status (and counts its runs)."""

    def __init__(self, name: str, status: str, success: bool) -> None:
        self.name, self.status, self.success, self.runs = name, status, success, 0  # type: ignore[misc]

    def run(self, start: Start) -> Run:
        self.runs += 1
        return Run(start.x0, 1.0, np.zeros(1), np.zeros(1), self.status, self.success, 3, 0.5)


@pytest.mark.parametrize("first_status, rescued, expected, runs, earlier", [
    ("Fatrop_Failed", True, "fatrop through order2", (1, 1, 0),
     [("fatrop", "Fatrop_Failed", 3), ("order2", "Solve_Succeeded", 7)]),
    ("Fatrop_Failed", False, "ipopt after order2 rescue after fatrop", (1, 1, 1),
     [("fatrop", "Fatrop_Failed", 3), ("order2", "Solve_Succeeded", 7),
      ("order2 rescue", "Fatrop_Failed", 4)]),
    ("Solve_Succeeded", True, "fatrop", (1, 0, 0), []),
    ("Maximum_WallTime_Exceeded", True, "fatrop", (1, 0, 0), []),
])
def test_the_rescue_runs_between_fatrops_failure_and_ipopt(
        first_status: str, rescued: bool, expected: str, runs: tuple, earlier: list) -> None:
    """``in_turn``'s rescue: after the first backend failed of itself, before the next; its
    run is the answer when it succeeded; not after a success or a run out of time. The
    seconds count every run, and the answer names the runs before it (the rescue's own
    included) with their status and iterations."""
    fatrop = Scripted("fatrop", first_status, first_status == "Solve_Succeeded")
    ipopt = Scripted("ipopt", "Solve_Succeeded", True)
    calls = []

    def rescue(start: Start, failed: Run) -> tuple[Run, str]:
        assert failed.status == first_status
        calls.append(start)
        run = Run(start.x0, 2.0, np.zeros(1), np.zeros(1),
                  "Solve_Succeeded" if rescued else "Fatrop_Failed", rescued, 4, 0.25,
                  earlier=(("order2", "Solve_Succeeded", 7),))
        return run, "fatrop through order2" if rescued else "order2 rescue"

    run, label = in_turn([fatrop, ipopt], Start(np.zeros(1), np.zeros(0)), lambda x, p: 0.0,
                         rescue)
    assert label == expected
    assert (fatrop.runs, len(calls), ipopt.runs) == runs
    assert run.seconds == pytest.approx(0.5 * (fatrop.runs + ipopt.runs) + 0.25 * len(calls))
    assert list(run.earlier) == earlier


class Recording(Scripted):
    """A scripted backend that keeps the starts it was given."""

    def __init__(self, name: str, status: str, success: bool) -> None:
        super().__init__(name, status, success)
        self.starts: list[Start] = []

    def run(self, start: Start) -> Run:
        self.starts.append(start)
        run = super().run(start)
        return replace(run, x=start.x0 + 1.0, lam_g=np.full(1, 2.0), lam_x=np.full(1, 3.0))


@pytest.mark.parametrize("status, label, warm", [
    ("Solved_To_Acceptable_Level", "ipopt polish after fatrop", True),
    ("Fatrop_Failed", "ipopt after fatrop", False),
])
def test_a_stop_at_an_acceptable_point_is_polished_from_that_point(
        status: str, label: str, warm: bool) -> None:
    """fatrop near a solution but not at the tolerance (its acceptable stop): IPOPT starts
    from fatrop's point and multipliers (a warm start), not from the start, and no rescue
    runs; after a failure of another kind IPOPT starts from the start, after the rescue."""
    fatrop = Recording("fatrop", status, False)
    ipopt = Recording("ipopt", "Solve_Succeeded", True)
    rescued: list[Run] = []

    def rescue(start: Start, failed: Run) -> None:
        rescued.append(failed)  # and gives up: the next backend runs

    run, name = in_turn([fatrop, ipopt], Start(np.zeros(1), np.zeros(0)), lambda x, p: 0.0,
                        rescue)
    assert name == label and run.success
    given = ipopt.starts[0]
    if warm:
        assert given.warm and (given.x0[0], given.lam_g0[0], given.lam_x0[0]) == (1, 2, 3)
    else:
        assert not given.warm and given.x0[0] == 0.0
    assert len(rescued) == (0 if warm else 1)
    assert run.earlier == (("fatrop", status, 3),)


def test_fatrop_crawling_near_a_solution_is_polished_by_ipopt() -> None:
    """quadrotor_min_time from the long way round, N = 8: fatrop reaches the solution's
    neighbourhood and then regularises in every iteration, its error stuck near 4e-9 (it ran
    500 iterations, then IPOPT solved the start again in 21). It now stops at an acceptable
    point and IPOPT finishes from it in a few iterations, at the cost IPOPT reaches from the
    start: after 37 of fatrop's (its error below 1e-5 for 20 in a row; 67 with its own
    1e-6 and 50 in a row)."""
    path = Path(__file__).resolve().parent.parent / "problems" / "quadrotor_min_time.yaml"
    cfg = files.load(path, ["horizon.N=8"])
    f, d = cfg.file, cfg.file.discretization
    solver = compile_problem(files.build(cfg), 8, d.retraction, d.rule, f.solver.ipopt,
                             d.scheme, d.steps, False, "fatrop")
    tr = solver.transcription
    p = tr.pack()
    far = next(g for g in solver.guesses(tr, p, True) if g.label == "long way round")
    r = tr.solve(far, p)
    assert r.success and r.backend == "ipopt polish after fatrop", (r.backend, r.status)
    (who, status, crawled), = r.earlier
    assert (who, status) == ("fatrop", "Solved_To_Acceptable_Level") and crawled <= 40
    assert r.iterations <= 5
    cold = tr.backends[-1].run(Start(tr.point(far, p), p))
    assert cold.success and r.cost == pytest.approx(cold.f, rel=1e-9)
    sol = solver.solve(guess=far)  # the solution tells both runs, and its table says so
    assert sol.diagnostics["runs"] == [
        {"backend": "fatrop", "status": "Solved_To_Acceptable_Level", "iterations": crawled},
        {"backend": "ipopt polish", "status": "Solve_Succeeded", "iterations": sol.iterations}]
    console = Console(width=300, record=True)
    console.print(summary(sol))
    assert f"│ {sol.iterations} (after fatrop {crawled}: Solved_To_Acceptable_Level)" in \
        console.export_text()


def test_the_first_start_fatrop_fails_on_is_rescued_through_order2() -> None:
    """The heavy top from the great circle the long way round, N=96: fatrop fails (11
    iterations), and before IPOPT's fallback fatrop solves order2 from the same start and
    order4 from its solution: verified, in the minimum another start finds directly (the
    natural start finds a higher one), labelled by who solved it."""
    solver = og.compile_problem(heavy_top(), N=96, scheme="order4", backend="fatrop")
    tr = solver.transcription
    p = tr.pack()
    far = next(g for g in solver.guesses(tr, p, True) if g.label == "great circle, long way")
    failure = tr.fatrop.run(Start(tr.point(far, p), p))
    assert not failure.success  # the premise
    sol = solver.solve(guess=far)
    assert sol.success and sol.backend == "fatrop through order2"
    spun = next(g for g in solver.guesses(tr, p, True)
                if g.label == "great circle, rotor 1 spun +")
    best = solver.solve(guess=spun)  # the multi-start's best minimum
    assert best.success and best.backend == "fatrop"
    assert sol.cost == pytest.approx(best.cost, rel=1e-8)
    assert sol.solve_seconds == sol.ipopt_seconds_total  # one start, every run counted
    rescue = sol.diagnostics["rescue"]
    assert rescue["rescued"] and rescue["scheme"] == "order2" and rescue["backend"] == "fatrop"
    assert rescue["failed"] == "Fatrop_Failed"
    tried, cheap, last = rescue["iterations"]  # fatrop's failure, order2, order4
    assert tried == failure.iterations and 0 < cheap <= RESCUE_ITERATIONS
    assert last == sol.iterations
    assert rescue["message"].startswith("fatrop failed from the start 'great circle, long way' "
                                        f"(Fatrop_Failed after {tried} iterations); solved "
                                        f"order2 on the same grid first in {cheap} iterations")
    assert "rescue" not in best.diagnostics


def test_fatrop_out_of_iterations_is_left_to_ipopt() -> None:
    """A fatrop run that reached its iteration limit crawled near a solution: the rescue
    is not tried (it would crawl again), IPOPT's fallback finishes; a breakdown is tried."""
    solver = og.compile_problem(heavy_top(), N=8, scheme="order4", backend="fatrop")
    tr = solver.transcription
    p = tr.pack()
    start = Start(tr.point(solver.guesses(tr, p, False)[0], p), p)
    rescue = solver._through(tr, "order2", (None, None, None, None))

    def failed(status: str) -> Run:
        return Run(start.x0, 1.0, np.zeros(tr.ng), np.zeros(tr.nx), status, False, 500, 1.0)

    assert rescue(start, failed("Maximum_Iterations_Exceeded")) is None
    run, label = rescue(start, failed("Fatrop_Failed"))
    assert run.success and label == "fatrop through order2" and run.x.size == tr.nx
