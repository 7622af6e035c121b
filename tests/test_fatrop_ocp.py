"""fatrop through its own C interface (issue 26: fatrop's build linear in N): the stage form's
Functions (compiled with ``jit``, else evaluated by CasADi) drive fatrop directly, with block
maps computed in linear time, and the solve is CasADi's fatrop solve, the same to the last
bit."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from ocgroupoid import files
from ocgroupoid.errors import ConfigError
from ocgroupoid.nlp.backends.fatrop_ocp import FatropOcp, block_maps
from ocgroupoid.solve import compile_problem

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"

pytestmark = pytest.mark.skipif(not any(shutil.which(c) for c in ("cc", "gcc", "clang")),
                                reason="no C compiler on PATH")


@pytest.fixture(scope="module", autouse=True)
def own_cache(tmp_path_factory: pytest.TempPathFactory) -> Iterator[None]:
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("OCGROUPOID_JIT_CACHE", str(tmp_path_factory.mktemp("jit")))
        yield


def fatrop(name: str, N: int, scheme: str | None = None, jit: bool = True) -> tuple:
    overrides = [f"horizon.N={N}"] + ([f"discretization.scheme={scheme}"] if scheme else [])
    cfg = files.load(PROBLEMS / f"{name}.yaml", overrides)
    f, d = cfg.file, cfg.file.discretization
    tr = compile_problem(files.build(cfg), N, d.retraction, d.rule, f.solver.ipopt, d.scheme,
                         d.steps, jit, "fatrop").transcription
    return tr, tr.fatrop


# every kind of stage form: states only (so3), bounds on controls and rows (the cart-pole),
# a free horizon carried as state copies (so3_minimum_time), a first-order problem
# (plate_ball), controls as lines (the quadrotor), order2's nodes
CASES = [("so3_rest_to_rest", "order6"), ("cart_pole", "order4"),
         ("so3_minimum_time", "order4"), ("plate_ball", "order2"), ("quadrotor", "order6"),
         ("heavy_top_rotors", "order2")]


@pytest.mark.parametrize("name,scheme", CASES, ids=[f"{n}-{s}" for n, s in CASES])
def test_the_block_maps_put_every_nonzero_in_its_stage_block(name: str, scheme: str) -> None:
    """Random values in the Jacobian's and the Hessian's patterns, scattered by the maps into
    the dense stage blocks and read back from them by the blocks' layout (column-major over
    (x_k, u_k)), give the same matrices: the gap rows' blocks negated, their +1 on x_{k+1}
    alone outside the blocks; the Hessian block diagonal."""
    _, fb = fatrop(name, 5, scheme, jit=False)
    sf = fb.form
    jac = fb.options["cache"]["nlp_jac_g"].sparsity_out(1)
    hess = fb.options["cache"]["nlp_hess_l"].sparsity_out(1)
    m = block_maps(sf, jac, hess)
    rng = np.random.default_rng(0)
    a = rng.standard_normal(jac.nnz())
    rows, cols = (np.asarray(v) for v in jac.get_triplet())
    a[m.a_kind == 2] = 1.0
    AB, CD = np.zeros(m.ab_off[-1]), np.zeros(m.cd_off[-1])
    AB[m.a_index[m.a_kind == 0]] = -a[m.a_kind == 0]
    CD[m.a_index[m.a_kind == 1]] = a[m.a_kind == 1]
    dense = np.zeros((sf.order.size, sf.nz))
    dense[rows, cols] = a
    back = np.zeros_like(dense)
    for k in range(sf.K + 1):
        n = sf.nx[k] + sf.nu[k]
        c = slice(m.col[k], m.col[k] + n)
        if k < sf.K:
            nxt = sf.nx[k + 1]
            back[m.row_ab[k]:m.row_ab[k] + nxt, c] = \
                -AB[m.ab_off[k]:m.ab_off[k + 1]].reshape(n, nxt).T
            back[m.row_ab[k]:m.row_ab[k] + nxt,
                 m.col[k + 1]:m.col[k + 1] + nxt] += np.eye(nxt)
        back[m.row_cd[k]:m.row_cd[k] + sf.ng[k], c] = \
            CD[m.cd_off[k]:m.cd_off[k + 1]].reshape(n, sf.ng[k]).T
    np.testing.assert_array_equal(back, dense)
    assert np.all(m.h_index >= 0)  # block diagonal
    h = rng.standard_normal(hess.nnz())
    RSQ = np.zeros(m.rsq_off[-1])
    RSQ[m.h_index] = h
    dense_h = np.zeros((sf.nz, sf.nz))
    dense_h[tuple(np.asarray(v) for v in hess.get_triplet())] = h
    for k in range(sf.K + 1):
        n = sf.nx[k] + sf.nu[k]
        c = slice(m.col[k], m.col[k] + n)
        block = RSQ[m.rsq_off[k]:m.rsq_off[k + 1]].reshape(n, n).T
        np.testing.assert_array_equal(block, dense_h[c, c])
        dense_h[c, c] = 0.0
    assert not dense_h.any()


@pytest.mark.parametrize("jit", [True, False], ids=["jit", "casadi"])
@pytest.mark.parametrize("name,scheme", CASES, ids=[f"{n}-{s}" for n, s in CASES])
def test_the_own_interface_solves_as_casadis_fatrop(name: str, scheme: str, jit: bool) -> None:
    """From each start (the first guesses and a perturbed one, there and back, one solver
    object reused): the same iterations, status, point, cost and multipliers as CasADi's
    fatrop nlpsol on the same Functions, compiled (jit) or evaluated by CasADi."""
    tr, fb = fatrop(name, 8, scheme, jit)
    assert fb.direct is not None
    p = tr.pack()
    starts = [tr.point(g, p) for g in tr.guesses(p)[:2]]
    starts.append(starts[0] + 1e-3 * np.random.default_rng(1).standard_normal(starts[0].size))
    starts += starts[::-1]
    own = [fb._solve_here((x0, p)) for x0 in starts]
    direct, fb.direct = fb.direct, None
    try:
        casadi = [fb._solve_here((x0, p)) for x0 in starts]
    finally:
        fb.direct = direct
    for a, b in zip(own, casadi):
        assert (a.iterations, a.status, a.success) == (b.iterations, b.status, b.success)
        for x, y in ((a.x, b.x), (a.lam_g, b.lam_g), (a.lam_x, b.lam_x), (a.f, b.f)):
            np.testing.assert_allclose(x, y, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("name,scheme", [("cart_pole", "order6"), ("so3_rest_to_rest", "order4")])
def test_a_solve_reports_its_evaluations_as_casadi_counts_them(name: str, scheme: str) -> None:
    """The driver's count of each Function's evaluations during fatrop's call is the count
    CasADi's fatrop nlpsol keeps of the same solve (``n_call_*``), and their seconds are
    positive and within the call's."""
    tr, fb = fatrop(name, 8, scheme)
    p = tr.pack()
    a = fb.arguments(tr.point(tr.guesses(p)[0], p), p)
    iterations = fb.direct.solve(a["x0"], a["p"], a["lbg"], a["ubg"], a["lbx"], a["ubx"])[1]
    times = fb.direct.times
    fb.solver(**a)
    stats = fb.solver.stats()
    assert iterations == stats["iter_count"]
    assert times.calls == {name: stats[f"n_call_{name}"] for name in times.calls}
    assert all(v > 0 for v in times.evaluations.values())
    assert sum(times.evaluations.values()) < times.solve


def test_a_reused_solver_reads_each_solves_bounds() -> None:
    """fatrop's solver is kept while the split of rows and bounds into equalities and
    inequalities stays; with other bounds of the same split, and with a split changed (a
    bounded row made an equality), each solve equals a solve by a new solver."""
    tr, fb = fatrop("cart_pole", 8, "order4")
    p = tr.pack()
    a = fb.arguments(tr.point(tr.guesses(p)[0], p), p)

    def tightened(v: np.ndarray, c: float) -> np.ndarray:
        v = np.array(v, dtype=float)
        v[np.isfinite(v)] *= c
        return v

    fixed_lb, fixed_ub = np.array(a["lbg"], dtype=float), np.array(a["ubg"], dtype=float)
    bounded = np.flatnonzero(np.isfinite(fixed_lb) & np.isfinite(fixed_ub) & (fixed_lb < fixed_ub))
    j = int(bounded[bounded.size // 2])
    fixed_lb[j] = fixed_ub[j] = (fixed_lb[j] + fixed_ub[j]) / 2
    cases = [(a["lbg"], a["ubg"], a["lbx"], a["ubx"]),
             tuple(tightened(a[k], 0.8) for k in ("lbg", "ubg", "lbx", "ubx")),
             (fixed_lb, fixed_ub, a["lbx"], a["ubx"])]
    reused = [fb.direct.solve(a["x0"], a["p"], *bounds) for bounds in cases]
    for bounds, (out, iterations, flag, value, stopped) in zip(cases, reused):
        fresh = FatropOcp(fb.form, fb.options["cache"], fb.direct.library,
                          fb.options["fatrop"]).solve(a["x0"], a["p"], *bounds)
        assert (iterations, flag, value, stopped) == fresh[1:]
        for key in out:
            np.testing.assert_array_equal(out[key], fresh[0][key])
    assert reused[1][0]["f"] != reused[0][0]["f"]  # the tightened bounds bind
    assert reused[2][3] == 0 and reused[2][0]["g"][j] == pytest.approx(fixed_lb[j], abs=1e-8)


def test_a_solves_result_is_its_own_and_its_inputs_are_checked() -> None:
    """The driver's arrays are allocated once and reused: a solve's result is not changed by
    the next solve, and an input of the wrong length is refused (not read past its end)."""
    tr, fb = fatrop("cart_pole", 8, "order4")
    p = tr.pack()
    a = fb.arguments(tr.point(tr.guesses(p)[0], p), p)
    first = fb.direct.solve(a["x0"], a["p"], a["lbg"], a["ubg"], a["lbx"], a["ubx"])[0]
    kept = {k: v.copy() for k, v in first.items()}
    tight = [np.where(np.isfinite(a[k]), 0.8 * np.asarray(a[k]), a[k])
             for k in ("lbg", "ubg", "lbx", "ubx")]
    second = fb.direct.solve(a["x0"], a["p"], *tight)[0]
    assert second["f"] != first["f"]  # the tightened bounds bind: other numbers were written
    for key in first:
        np.testing.assert_array_equal(first[key], kept[key])
    with pytest.raises(ValueError, match=f"expects {np.size(a['x0'])} numbers, got 3"):
        fb.direct.solve(np.zeros(3), a["p"], a["lbg"], a["ubg"], a["lbx"], a["ubx"])


@pytest.mark.parametrize("jit", [True, False], ids=["jit", "casadi"])
def test_no_nlpsol_is_built(jit: bool) -> None:
    """The N² of CasADi's fatrop interface is in building its nlpsol: with jit or without,
    neither the build nor a solve builds one."""
    tr, fb = fatrop("so3_rest_to_rest", 16, jit=jit)
    p = tr.pack()
    assert tr.solve(tr.guesses(p)[0], p).success
    assert fb.direct is not None and (fb.direct.library is not None) == jit
    assert "solver" not in vars(fb) and "_whole" not in vars(fb)


def test_an_option_fatrop_does_not_have_is_refused() -> None:
    _, fb = fatrop("so3_rest_to_rest", 4)
    with pytest.raises(ConfigError, match="no_such_option"):
        FatropOcp(fb.form, fb.options["cache"], fb.direct.library, {"no_such_option": 1})



@pytest.mark.parametrize("jit", [True, False], ids=["jit", "casadi"])
def test_where_the_driver_does_not_compile_fatrop_runs_through_nlpsol(
        jit: bool, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """With the driver's compilation failing, fatrop runs through CasADi's nlpsol, with jit
    or without, and the compilation is tried once, not again at every build."""
    from ocgroupoid.nlp.backends import fatrop_ocp
    tries = []

    def no_headers(*args: object) -> None:
        tries.append(args)
        raise ConfigError("fatrop/ocp/OCPCInterface.h: No such file or directory")

    monkeypatch.setenv("OCGROUPOID_JIT_CACHE", str(tmp_path))
    monkeypatch.setattr(fatrop_ocp, "build", no_headers)
    fatrop_ocp._driver.cache_clear()
    try:
        with pytest.raises(fatrop_ocp.Unavailable, match="No such file"):
            fatrop_ocp.driver()
        for _ in range(2):
            tr, fb = fatrop("so3_rest_to_rest", 4, jit=jit)
            p = tr.pack()
            assert fb.direct is None and tr.solve(tr.guesses(p)[0], p).success
        assert len(tries) == 1
    finally:
        fatrop_ocp._driver.cache_clear()
