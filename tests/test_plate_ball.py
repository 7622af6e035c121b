"""plate_ball: non-integrable rolling constraints on R^2 x R^2 x SO(3) => R^2 (issue 4).

Both instances of PROBLEMS.md §3 (Omega_p = 0 and 1) under both rules (the exact Cayley
retraction and the seed's first-order read-out, seed 001 eq. 8) are solved with multi-start
at N = 32 ... 256, and continued to N = 512 from the N = 256 solution for the orders.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from typer.testing import CliRunner

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.cli import app
from ocgroupoid.nlp import Kind
from ocgroupoid.solve import distinct_minima, interpolate
from ocgroupoid.solve.guesses import model_guesses
from ocgroupoid.systems.plate_ball import plate_ball

from .lie_oracles import vee_skew

NS = [32, 64, 128, 256]
FINE = 512
RULES = ["cayley", "first_order"]
OMEGAS = [0.0, 1.0]
ROOT = Path(__file__).resolve().parent.parent
E = [og.SO3.hat(e) for e in np.eye(3)]  # the seed's basis E_1, E_2, E_3 of so(3)


def observed_orders(values: list[float]) -> np.ndarray:
    v = np.asarray(values)
    return np.log2(v[:-1] / v[1:])


@pytest.fixture(scope="module")
def runs() -> dict[tuple[float, str], dict[int, og.Solution]]:
    """Multi-start solutions at N = 32..256 and the N = 512 continuation, per instance/rule."""
    out = {}
    for Om in OMEGAS:
        pb = plate_ball(Omega_p=Om)
        for rule in RULES:
            solvers = {N: og.compile_problem(pb, N=N, retraction=rule) for N in [*NS, FINE]}
            sols = {N: solvers[N].solve(multistart=True) for N in NS}
            coarse = sols[NS[-1]]
            start = interpolate(solvers[NS[-1]].transcription, coarse.x, coarse.p, FINE)
            sols[FINE] = solvers[FINE].solve(guess=start)
            out[(Om, rule)] = sols
    return out


CASES = [(Om, rule, N) for Om in OMEGAS for rule in RULES for N in NS]


@pytest.mark.parametrize("Om, rule, N", CASES)
def test_solves_with_tiny_residuals(runs, Om: float, rule: str, N: int) -> None:
    sol = runs[(Om, rule)][N]
    d = sol.diagnostics
    assert sol.success and sol.status == "Solve_Succeeded"
    assert len(d["euler_lagrange_residual_per_node"]) == N - 1
    assert max(d["euler_lagrange_residual_per_node"]) <= 1e-8
    assert d["final_residual"]["xy"] <= 1e-9 and d["final_residual"]["R"] <= 1e-9
    assert d["manifold_distance"]["R"] <= 1e-12


def mirror(xy: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Node positions and attitudes of the mirror image ``p(t) -> p_0 + p_T - M p(T - t)``
    (M the reflection in the line through the end points) of a path from R_0 = I."""
    p0, pT = xy[0], xy[-1]
    d = (pT - p0) / np.linalg.norm(pT - p0)
    S = 2 * np.outer(d, d) - np.eye(2)
    e = np.append(d, 0.0)
    S_perp = np.eye(3) - 2 * np.outer(e, e)  # reflection in the vertical plane normal to d
    xy_m = p0 + pT - (p0 + (xy[::-1] - p0) @ S.T)
    R_m = S_perp @ R[::-1] @ R[-1].T @ S_perp
    return xy_m, R_m


def same_path(a: og.Solution, b: og.Solution, mirrored: bool) -> float:
    """Largest distance between the positions of a and b (or b's mirror) at a's nodes."""
    xy_b = mirror(b.states["xy"], b.states["R"])[0] if mirrored else b.states["xy"]
    on_a = np.column_stack([np.interp(a.t, b.t, xy_b[:, j]) for j in range(2)])
    return float(np.max(np.linalg.norm(a.states["xy"] - on_a, axis=1)))


@pytest.mark.parametrize("Om, rule", [(Om, rule) for Om in OMEGAS for rule in RULES])
def test_every_grid_lands_in_the_same_minimum(runs, Om: float, rule: str) -> None:
    """Cost and orders compare like with like: every N in the best minimum's branch (with
    Omega_p = 0 up to the mirror symmetry), the fine grid continued from N = 256."""
    sols = runs[(Om, rule)]
    for N in NS:
        dist = min(same_path(sols[N], sols[FINE], m) for m in ((False, True) if Om == 0 else
                                                                 (False,)))
        assert dist <= 0.05, (N, dist)
    assert sols[FINE].success and sols[FINE].iterations <= 10


@pytest.mark.parametrize("rule", RULES)
def test_right_loops_find_the_two_mirror_minima(rule: str) -> None:
    """Omega_p = 0: the model's loops to the right, early and late (mirror images of each
    other), lead to the best path and to its mirror image, of equal cost, at every N."""
    for N in NS:
        tr = og.compile_problem(plate_ball(), N=N, retraction=rule).transcription
        p = tr.pack()
        guesses = {g.label: g for g in model_guesses(tr, p, tr.guesses(p)[0])}
        ends = []
        for label in ("loop right, early", "loop right, late"):
            r = tr.solve(guesses[label], p)
            assert r.success and r.iterations <= 60, (N, label, r.iterations)
            s = tr.unpack(r.x, p)["s"]
            ends.append((r, s[:, :2], np.array([og.SO3.matrix(q) for q in s[:, 2:]])))
        (a, xy_a, R_a), (b, xy_b, R_b) = ends
        assert b.cost == pytest.approx(a.cost, rel=1e-9)  # IPOPT tol 1e-10
        assert np.max(np.abs(xy_a - xy_b)) > 0.1  # two paths
        xy_m, R_m = mirror(xy_a, R_a)
        assert np.max(np.abs(xy_m - xy_b)) <= 1e-6 and np.max(np.abs(R_m - R_b)) <= 1e-6
        assert len(distinct_minima([a, b])) == 2


@pytest.mark.parametrize("rule", RULES)
def test_multistart_reports_both_mirror_images(runs, rule: str) -> None:
    for N in NS:
        sol = runs[(0.0, rule)][N]
        costs = [m["cost"] for m in sol.minima]
        assert len(costs) >= 2 and costs[1] == pytest.approx(costs[0], rel=1e-9), (N, costs)
    for N in NS:  # the rotating plate has no such symmetry: no second minimum of equal cost
        costs = [m["cost"] for m in runs[(1.0, rule)][N].minima]
        assert all(c > 10 * costs[0] for c in costs[1:]), (N, costs)


@pytest.mark.parametrize("rule", RULES)
def test_rotating_plate_breaks_the_mirror_symmetry(rule: str) -> None:
    """Omega_p = 1: the mirror-image starts (right loops, early and late) that lead to two
    minima of equal cost on the fixed plate do not here: they meet one minimum, or two of
    clearly different cost."""
    for N in (32, 64):
        tr = og.compile_problem(plate_ball(Omega_p=1.0), N=N, retraction=rule).transcription
        p = tr.pack()
        guesses = {g.label: g for g in model_guesses(tr, p, tr.guesses(p)[0])}
        a, b = (tr.solve(guesses[label], p) for label in ("loop right, early",
                                                           "loop right, late"))
        assert a.success and b.success, (N, a.status, b.status)
        assert len(distinct_minima([a, b])) == 1 or \
            abs(a.cost - b.cost) > 1e-3 * min(a.cost, b.cost), (N, a.cost, b.cost)


def cay(a: np.ndarray) -> np.ndarray:
    """Cayley map (I - hat(a)/2)^{-1} (I + hat(a)/2), written out independently."""
    A = og.SO3.hat(a)
    return np.linalg.solve(np.eye(3) - A / 2, np.eye(3) + A / 2)


@pytest.mark.parametrize("Om", OMEGAS)
def test_spatial_convention_R_next_is_g_R(runs, Om: float) -> None:
    """R_{k+1} = g_{k+1} R_k with g = cay(h w) (Cayley) or skew(g) = hat(h w) (seed's rule);
    the body convention R_k g would not reproduce the trajectory."""
    sol = runs[(Om, "cayley")][64]
    R, w, h = sol.states["R"], sol.velocities["w"], sol.T / sol.N
    g = np.array([cay(h * wk) for wk in w])
    assert np.max(np.abs(R[1:] - g @ R[:-1])) <= 1e-12
    assert np.max(np.abs(R[1:] - R[:-1] @ g)) >= 1e-3
    sol = runs[(Om, "first_order")][64]
    R, w = sol.states["R"], sol.velocities["w"]
    g = R[1:] @ np.transpose(R[:-1], (0, 2, 1))
    assert np.max(np.abs(np.array([vee_skew(gk) for gk in g]) - h * w)) <= 1e-12


def replay_matrix(sol: og.Solution) -> tuple[float, float]:
    """Integrate the reported (dx/dt, dy/dt), linearly interpolated, with w from the rolling
    constraints and dR/dt = hat(w) R for the 3 x 3 matrix R (SciPy DOP853, not the library's
    replay); return the final position and attitude errors against the target."""
    r, Om, c = (sol.parameters[k][0] for k in ("r", "Omega_p", "c"))
    t_u, U = sol.controls_t, sol.controls
    target_xy, target_R = sol.states["xy"][-1], sol.states["R"][-1]

    def rhs(t: float, z: np.ndarray) -> np.ndarray:
        v = np.array([np.interp(t, t_u, U[:, 0]), np.interp(t, t_u, U[:, 1])])
        x, y = z[:2]
        w = np.array([(Om * x - v[1]) / r, (v[0] + Om * y) / r, c])
        return np.concatenate([v, (og.SO3.hat(w) @ z[2:].reshape(3, 3)).ravel()])

    z = np.concatenate([sol.states["xy"][0], sol.states["R"][0].ravel()])
    for a, b in zip(t_u[:-1], t_u[1:]):
        z = solve_ivp(rhs, (a, b), z, method="DOP853", rtol=1e-12, atol=1e-12).y[:, -1]
    RT = z[2:].reshape(3, 3)
    return (float(np.linalg.norm(z[:2] - target_xy)),
            float(np.linalg.norm(og.SO3.log(og.SO3.of_matrix(target_R.T @ RT)))))


@pytest.mark.parametrize("Om", OMEGAS)
def test_replay_in_matrix_form_lands_on_the_target(runs, Om: float) -> None:
    sol = runs[(Om, "cayley")][128]
    e_xy, e_R = replay_matrix(sol)
    rep = sol.diagnostics["replay"]["terminal_error"]
    assert e_xy == pytest.approx(rep["xy"], rel=1e-6) and e_R == pytest.approx(rep["R"], rel=1e-6)
    assert max(e_xy, e_R) <= 2e-3


@pytest.mark.parametrize("Om", OMEGAS)
def test_cayley_is_second_order(runs, Om: float) -> None:
    """Replay error and cost fall at order >= 1.8. The replay orders are taken on
    N = 64 ... 512: from N = 32 to 64 the fixed-plate instance is still pre-asymptotic
    (order 1.77, reported by scripts/bench_plate_ball.py)."""
    sols = runs[(Om, "cayley")]
    err = [sols[N].diagnostics["replay"]["max_terminal_error"] for N in [*NS, FINE]]
    assert np.all(observed_orders(err[1:]) >= 1.8), err
    assert sols[128].diagnostics["replay"]["max_terminal_error"] <= 2e-3
    J = [sols[N].cost for N in [*NS, FINE]]
    assert np.all(observed_orders(list(np.abs(np.diff(J)))) >= 1.8), J


@pytest.mark.parametrize("Om", OMEGAS)
def test_seeds_first_order_rule_is_second_order(runs, Om: float) -> None:
    """The seed's read-out w = vee(skew(g))/h is sin(h|w|)/h times the axis: an odd
    retraction exact to third order, so the rule converges at second order (pinned)."""
    sols = runs[(Om, "first_order")]
    err = [sols[N].diagnostics["replay"]["max_terminal_error"] for N in [*NS, FINE]]
    J = [sols[N].cost for N in [*NS, FINE]]
    for orders in (observed_orders(err), observed_orders(list(np.abs(np.diff(J))))):
        assert np.all((orders >= 1.8) & (orders <= 2.3)), (orders, err, J)
    # both rules converge to the same continuous optimum (Richardson extrapolation)
    limits = [sols[FINE].cost + (sols[FINE].cost - sols[NS[-1]].cost) / 3 for sols in
              (sols, runs[(Om, "cayley")])]
    assert limits[0] == pytest.approx(limits[1], abs=1e-6)


def seed_equations(sol: og.Solution, rule: str) -> np.ndarray:
    """The seed's eight discrete equations (001 §6.2) at the interior nodes with IPOPT's
    multipliers as lambda_k, derived for the spatial convention R_{k+1} = g_{k+1} R_k (the
    printed ones have the body convention, the lambda_1/lambda_2 roles in the y equation
    swapped and the sign of the lambda_3 terms flipped). Intervals k-1 and k meet at node k.

    x, y:  (q_{k+1} - 2 q_k + q_{k-1})/h^2 + (lam_k - lam_{k-1})/h +- Omega (lam_{k-1} + lam_k)/2
    R (first_order, phi^a = ... + alpha_a tr(g E_a)/2, alpha = (-r, r, 1)):
        sum_a alpha_a (lam^a_{k-1} tr(E_i g_{k-1} E_a) - lam^a_k tr(g_k E_i E_a)) = 0
    R (cayley, phi = h psi(tau^{-1}(g)/h), B = dpsi/dw = diag(r, -r, -1)):
        dcay^{-1}(h w_{k-1})^T B lam_{k-1} - dcay^{-1}(-h w_k)^T B lam_k = 0
    constraints: the rolling constraints on every interval.
    """
    r, Om, c = (sol.parameters[k][0] for k in ("r", "Omega_p", "c"))
    h = sol.T / sol.N
    x, y = sol.states["xy"].T
    R = sol.states["R"]
    g = R[1:] @ np.transpose(R[:-1], (0, 2, 1))
    lam = np.asarray(sol.multipliers["Phi"])
    l1, l2, l3 = lam.T
    ex = (x[2:] - 2 * x[1:-1] + x[:-2]) / h**2 + (l2[1:] - l2[:-1]) / h \
        + Om * (l1[:-1] + l1[1:]) / 2
    ey = (y[2:] - 2 * y[1:-1] + y[:-2]) / h**2 + (l1[1:] - l1[:-1]) / h \
        - Om * (l2[:-1] + l2[1:]) / 2
    if rule == "first_order":
        alpha = np.array([-r, r, 1.0])
        eR = np.array([[sum(alpha[a] * (lam[k - 1, a] * np.trace(E[i] @ g[k - 1] @ E[a])
                                        - lam[k, a] * np.trace(g[k] @ E[i] @ E[a]))
                            for a in range(3)) for i in range(3)] for k in range(1, sol.N)])
        w = np.array([vee_skew(gk) for gk in g]) / h  # seed eq. 8
    else:
        w = np.array([og.SO3.vee(2 * (gk - np.eye(3)) @ np.linalg.inv(gk + np.eye(3)))
                      for gk in g]) / h  # cay^{-1}(g)/h

        def dcay_inv(a: np.ndarray) -> np.ndarray:  # seed 000, eq. 64
            return np.eye(3) - og.SO3.hat(a) / 2 + np.outer(a, a) / 4

        B = np.diag([r, -r, -1.0])
        eR = np.array([dcay_inv(h * w[k - 1]).T @ B @ lam[k - 1]
                       - dcay_inv(-h * w[k]).T @ B @ lam[k] for k in range(1, sol.N)])
    v = np.diff(sol.states["xy"], axis=0) / h
    mid = (sol.states["xy"][1:] + sol.states["xy"][:-1]) / 2
    phi = np.column_stack([v[:, 1] + r * w[:, 0] - Om * mid[:, 0],
                           v[:, 0] - r * w[:, 1] + Om * mid[:, 1], c - w[:, 2]])
    return np.concatenate([ex, ey, eR.ravel(), phi.ravel()])


@pytest.mark.parametrize("Om, rule", [(Om, rule) for Om in OMEGAS for rule in RULES])
def test_multipliers_are_the_seeds_lambda(runs, Om: float, rule: str) -> None:
    """multipliers["Phi"] (one row per interval) satisfy the seed's eight equations."""
    for N in (32, 256):
        sol = runs[(Om, rule)][N]
        assert sol.multipliers["Phi"].shape == (N, 3)
        assert sol.multipliers["names"] == ["rolling"] * 3
        assert np.allclose(sol.multipliers["t"], (np.arange(N) + 0.5) * sol.T / N)
        assert np.max(np.abs(seed_equations(sol, rule))) <= 1e-8
    # the equations are not satisfied by other multipliers
    sol = runs[(Om, rule)][32]
    sol.multipliers["Phi"] = sol.multipliers["Phi"] * 1.01
    try:
        assert np.max(np.abs(seed_equations(sol, rule))) >= 1e-4
    finally:
        sol.multipliers["Phi"] = sol.multipliers["Phi"] / 1.01


def test_model_guesses_roll_and_reach_the_final_position() -> None:
    """Every bend guess satisfies the discrete rolling constraints and the final position
    exactly (only the attitude is left to IPOPT), for any parameters."""
    pb = plate_ball(r=0.7, Omega_p=0.8, c=0.2, xyT=(-0.4, 1.3))
    tr = og.compile_problem(pb, N=16).transcription
    p = tr.pack()
    guesses = [(g.label, g.xi) for g in model_guesses(tr, p, tr.guesses(p)[0])]
    assert [label for label, _ in guesses] == ["loop right, early", "loop right, late",
                                               "loop left, early", "loop left, late",
                                               "arc left", "arc right"]
    for _, xi in guesses:
        g = np.array(tr.g_fun(tr.point(og.Guess("", xi), p), p)).ravel()
        assert np.max(np.abs(g[tr.rows(Kind.PATH).ravel()])) <= 1e-12
        assert np.max(np.abs(g[tr.rows(Kind.FINAL).ravel()][:2])) <= 1e-12


def test_exp_retraction_solves_too() -> None:
    sol = og.solve(plate_ball(Omega_p=1.0), N=64, retraction="exp", multistart=True)
    assert sol.success and sol.diagnostics["euler_lagrange_residual_max"] <= 1e-8
    assert sol.cost == pytest.approx(3.0883, abs=2e-3)  # the Cayley/first-order limit


def test_problem_files_hold_both_instances_and_every_key_can_be_set() -> None:
    fixed = files.load(ROOT / "problems" / "plate_ball.yaml")
    rotating = files.load(ROOT / "problems" / "plate_ball_rotating.yaml")
    assert fixed.parameters.Omega_p == 0.0 and rotating.parameters.Omega_p == 1.0
    assert fixed.file.discretization.retraction == "cayley"
    sets = ["parameters.r=1.5", "parameters.Omega_p=0.5", "parameters.c=0.1",
            "initial.xy=[0.1, -0.2]", "initial.R={rotvec: [0, 0, 0.2]}",
            "final.xy=[1.2, null]", "final.R={axis_angle: {axis: [0, 1, 0], angle: 1.0}}",
            "discretization.retraction=first_order", "horizon.N=24"]
    cfg = files.load(ROOT / "problems" / "plate_ball.yaml", sets)
    pb = files.build(cfg)
    assert cfg.file.discretization.retraction == "first_order"
    assert pb.parameter_values().tolist() == [1.5, 0.5, 0.1]
    assert pb.start.states["xy"] == [0.1, -0.2] and pb.end.states["xy"] == [1.2, None]
    assert np.allclose(pb.start.states["R"], og.SO3.of_matrix(og.so3.from_rotvec([0, 0, 0.2])))
    r = CliRunner().invoke(app, ["solve", str(ROOT / "problems" / "plate_ball.yaml"), *(
        a for s in sets for a in ("--set", s))])
    assert r.exit_code == 0, r.output
    text = " ".join(r.output.split())
    assert "Solve_Succeeded" in text and "first_order" in text
    bad = CliRunner().invoke(app, ["check", str(ROOT / "problems" / "plate_ball.yaml"),
                                   "--set", "parameters.r=-1"])
    assert bad.exit_code == 2 and "parameters.r" in bad.output and "> 0" in bad.output
