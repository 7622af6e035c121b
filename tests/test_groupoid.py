"""Groupoid axioms and the discrete structure of every factor, with the factors' own samples."""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, strategies as st

from ocgroupoid.errors import ConfigError
from ocgroupoid.groupoid import Groupoid, LieGroupFactor, Pair, SphereAction
from ocgroupoid.groupoid.base import BoundaryMask
from ocgroupoid.lie import RETRACTION_NAMES, SE2, SE3, SO3, retraction, se3, so3

from .strategies import in_ball, vectors


def same(a, b) -> bool:
    if a is None or b is None:
        return a is None and b is None
    if isinstance(a, tuple):
        return all(same(x, y) for x, y in zip(a, b))
    return np.allclose(a, b, atol=1e-10)


GROUP_FACTORS = [LieGroupFactor(G, side=side) for G in (SO3, SE3, SE2)
                 for side in ("right", "left")]
FACTORS = [*GROUP_FACTORS, Pair(2), SphereAction()]


def factor_id(f) -> str:
    return f"{type(f).__name__}-{f.group.name}-{f.side}"


def defined(name: str, f) -> bool:
    """Whether the retraction ``name`` exists on the factor's group (first_order: SO(3))."""
    try:
        retraction(name, f.group)
    except ConfigError:
        return False
    return True


every_factor = pytest.mark.parametrize("f", FACTORS, ids=factor_id)
every_group_factor = pytest.mark.parametrize("f", GROUP_FACTORS, ids=factor_id)
every_factor_and_retraction = pytest.mark.parametrize(
    "f, name", [(f, n) for f in FACTORS for n in RETRACTION_NAMES if defined(n, f)],
    ids=lambda v: v if isinstance(v, str) else factor_id(v))
seeds = st.integers(0, 2**32 - 1)


@every_factor
@given(seed=seeds)
def test_multiplication_is_associative_and_respects_source_target(f, seed: int) -> None:
    rng = np.random.default_rng(seed)
    g = f.sample_element(rng)
    k = f.sample_element(rng, source=f.target(g))
    m = f.sample_element(rng, source=f.target(k))
    gk = f.multiply(g, k)
    assert same(f.source(gk), f.source(g)) and same(f.target(gk), f.target(k))
    assert same(f.multiply(gk, m), f.multiply(g, f.multiply(k, m)))


@every_factor
@given(seed=seeds)
def test_identity_and_inverse(f, seed: int) -> None:
    g = f.sample_element(np.random.default_rng(seed))
    assert same(f.multiply(f.identity(f.source(g)), g), g)
    assert same(f.multiply(g, f.identity(f.target(g))), g)
    assert same(f.multiply(g, f.inverse(g)), f.identity(f.source(g)))
    assert same(f.multiply(f.inverse(g), g), f.identity(f.target(g)))


@pytest.mark.parametrize("f", [Pair(3), SphereAction()], ids=["pair", "action"])
@given(seed=seeds, a=in_ball(2.0))
def test_step_is_the_target_of_the_element(f, seed: int, a: np.ndarray) -> None:
    """Over a base: s_{k+1} = step(s_k, tau(a)) is the target of the element it generates."""
    ret = retraction("cayley", f.group)
    s = f.sample_state(np.random.default_rng(seed))
    assert np.allclose(np.asarray(f.step(s, ret, a)).ravel(),
                       f.target(f.element(s, ret.tau(a))))


@pytest.mark.parametrize("G", [SO3, SE3, SE2], ids=lambda G: G.name)
def test_spatial_convention_is_left_multiplication(G) -> None:
    """Spatial factor: g_{k+1} = w_k g_k (dg/dt = hat(xi) g); body: g_{k+1} = g_k w_k."""
    ret = retraction("cayley", G)
    a = np.array([0.2, -0.4, 0.1, 0.7, -0.3, 1.1])[:G.dim]
    s = G.exp(np.array([0.5, 0.3, -1.0, 0.2, 0.9, -0.4])[:G.dim])
    left, right = LieGroupFactor(G, side="left"), LieGroupFactor(G, side="right")
    g, w = G.matrix(s), G.matrix(ret.tau(a))
    assert np.allclose(left.matrix(np.asarray(left.step(s, ret, a))), w @ g)
    assert np.allclose(right.matrix(np.asarray(right.step(s, ret, a))), g @ w)


@every_factor
@given(seed=seeds)
def test_variation_is_the_derivative_of_the_moved_state(f, seed: int) -> None:
    """variation(s, eta) = d/dt of the state under w_{k-1} -> w_{k-1} exp(t eta) (right) or
    exp(t eta) w_{k-1} (left), written with the factor's group."""
    G, ret = f.group, retraction("exp", f.group)
    rng = np.random.default_rng(seed)
    a, eta = 0.5 * rng.normal(size=f.algebra_dim), rng.normal(size=f.algebra_dim)
    s, t = f.sample_state(rng), 1e-6

    def moved(sign: float) -> np.ndarray:
        w, dw = G.exp(a), G.exp(sign * t * eta)
        w = G.compose(w, dw) if f.side == "right" else G.compose(dw, w)
        return np.asarray(f.step(s, ret, ret.tau_inv(w)), dtype=float).ravel()

    fd = (moved(1.0) - moved(-1.0)) / (2 * t)
    base = np.asarray(f.step(s, ret, a), dtype=float).ravel()
    assert np.allclose(fd, np.asarray(f.variation(base, eta), dtype=float).ravel(), atol=1e-7)


@every_factor
@given(seed=seeds)
def test_rplus_inverts_rminus(f, seed: int) -> None:
    """rplus(b, rminus(a, b)) = a, and |rminus(a, b)| is the distance (symmetric)."""
    rng = np.random.default_rng(seed)
    a, b = f.sample_state(rng), f.sample_state(rng)
    v = np.asarray(f.rminus(a, b), dtype=float).ravel()
    back = np.asarray(f.rplus(b, v), dtype=float).ravel()
    assert f.terminal_error(back, a, np.ones(f.state_dim, bool)) <= 1e-9
    d_ab = f.terminal_error(a, b, np.ones(f.state_dim, bool))
    assert d_ab == pytest.approx(np.linalg.norm(v), abs=1e-12)
    assert d_ab == pytest.approx(f.terminal_error(b, a, np.ones(f.state_dim, bool)), abs=1e-9)


@every_group_factor
@given(seed=seeds)
def test_distances_of_states_are_each_state_s(f, seed: int) -> None:
    """The distances from the group of many node states (drifted off it), measured in one
    mapped call and one stack, are those of each state alone."""
    rng = np.random.default_rng(seed)
    states = np.array([f.sample_state(rng) for _ in range(6)])
    states += 1e-4 * np.arange(6)[:, None] * rng.standard_normal(states.shape)
    each = [f.distance(s) for s in states]
    assert np.allclose(f.distances(states), each, rtol=1e-13, atol=1e-16)
    assert each[0] <= 1e-12


@every_factor
@given(seed=seeds, angle=st.sampled_from([0.0, 1e-9, 1.0, np.pi - 1e-6, np.pi - 1e-12, np.pi]))
def test_terminal_error_is_the_formula_on_numbers(f, seed: int, angle: float) -> None:
    """The compiled rminus of terminal_error (one Function call) gives what the formula
    evaluated on numbers gives, at random pairs and at a half-turn and near it."""
    rng = np.random.default_rng(seed)
    a = f.sample_state(rng)
    v = rng.standard_normal(f.algebra_dim)
    b = np.asarray(f.rplus(a, angle * v / np.linalg.norm(v)), dtype=float).ravel()
    mask = np.ones(f.state_dim, bool)
    for s, goal in ((b, a), (a, b), (f.sample_state(rng), a)):
        formula = float(np.linalg.norm(np.asarray(f.rminus(s, goal), dtype=float).ravel()))
        assert f.terminal_error(s, goal, mask) == pytest.approx(formula, rel=1e-12, abs=1e-12)


@every_factor
@given(seed=seeds)
def test_chart_has_no_root_but_the_target(f, seed: int) -> None:
    """The chart vanishes at the target and grows with the distance from it: |chart| is at
    least half the distance, also at the farthest point along any geodesic (a rotation of pi,
    the antipode on S^2), which the skew part of R_T^T R alone would take for a root."""
    rng = np.random.default_rng(seed)
    goal, s = f.sample_state(rng), f.sample_state(rng)
    packed = np.asarray(f.pack_target(goal), dtype=float).ravel()
    mask = np.ones(f.state_dim, bool)
    assert np.allclose(np.asarray(f.chart(f.state_of_target(packed), packed), dtype=float), 0,
                       atol=1e-14)
    v = np.asarray(f.rminus(s, goal), dtype=float).ravel()
    far = np.asarray(f.rplus(goal, np.pi * v / np.linalg.norm(v)), dtype=float).ravel()
    for point in (s, far):
        with np.errstate(divide="ignore", invalid="ignore"):
            c = np.asarray(f.chart(point, packed), dtype=float).ravel()
        dist = f.terminal_error(point, goal, mask)
        assert not np.all(np.isfinite(c)) or np.linalg.norm(c) >= 0.5 * dist - 1e-12, (c, dist)


@functools.lru_cache(maxsize=None)
def guess_and_step(f, name: str, N: int) -> tuple[list[str], ca.Function, ca.Function]:
    """The labels of a factor's guesses, their graph of (start, end, V0, VN, T) and its step
    as a Function of (s, a), built once per factor and retraction."""
    ret = retraction(name, f.group)
    start, end = (ca.MX.sym(n, f.target_size) for n in ("start", "end"))
    V0, VN, Ts = ca.MX.sym("V0", f.algebra_dim), ca.MX.sym("VN", f.algebra_dim), ca.MX.sym("T")
    flags = np.ones(f.algebra_dim, bool)
    alts = f.guesses(ret, start, end, V0, VN, Ts, N, BoundaryMask(np.ones(f.state_dim, bool),
                                                                 flags, flags))
    s, a = ca.SX.sym("s", f.state_size), ca.SX.sym("a", f.algebra_dim)
    return ([label for label, _ in alts],
            ca.Function("g", [start, end, V0, VN, Ts], [xi for _, xi in alts]),
            ca.Function("step", [s, a], [f.step(s, ret, a)]))


@every_factor_and_retraction
@given(seed=seeds)
def test_every_geodesic_guess_lands_on_the_target(f, name: str, seed: int) -> None:
    """Each alternative of a factor's guesses, stepped N times from the start, reaches the
    prescribed end (a free end: rest); the preferred one turns the least (the sum of the
    steps' rotation angles, ``Retraction.step_norm``)."""
    rng = np.random.default_rng(seed)
    ret, N, T = retraction(name, f.group), 12, 2.0
    s0, sT = f.sample_state(rng), f.sample_state(rng)
    labels, fun, step = guess_and_step(f, name, N)
    outs = fun(f.pack_target(s0), f.pack_target(sT), np.zeros(f.algebra_dim),
               np.zeros(f.algebra_dim), T)
    outs = outs if isinstance(outs, (list, tuple)) else [outs]
    lengths = []
    for label, xi in zip(labels, outs):
        xi, s = np.array(xi), np.asarray(s0, dtype=float)
        for k in range(N):
            s = np.array(step(s, T / N * xi[:, k])).ravel()
        assert f.terminal_error(s, sT, np.ones(f.state_dim, bool)) <= 1e-9, label
        lengths.append(np.sum(ret.step_norm(T / N * xi.T)))
    assert lengths[0] <= min(lengths) + 1e-12


def test_product_layout_and_names() -> None:
    G = Groupoid(SphereAction(), Pair(2, "theta", "dtheta"))
    assert (G.state_size, G.algebra_dim, G.base_size) == (5, 5, 5)
    assert G.by_velocity("dtheta")[0] == 1
    with pytest.raises(ConfigError, match="distinct"):
        Groupoid(Pair(2), Pair(3))
    with pytest.raises(ConfigError, match="no velocity called 'w'"):
        G.by_velocity("w")


@every_factor
@given(seed=seeds, a=vectors(6, 1.0))
def test_symbolic_step_matches_numeric(f, seed: int, a: np.ndarray) -> None:
    ret = retraction("cayley", f.group)
    a = a[:f.algebra_dim]
    s = f.sample_state(np.random.default_rng(seed))
    ss, aa = ca.SX.sym("s", f.state_size), ca.SX.sym("a", f.algebra_dim)
    F = ca.Function("F", [ss, aa], [f.step(ss, ret, aa)])
    assert np.allclose(np.array(F(s, a)).ravel(), np.asarray(f.step(s, ret, a)).ravel())


@every_factor_and_retraction
@given(seed=seeds)
def test_coordinate_rate_moves_the_state_with_the_velocity(f, name: str, seed: int) -> None:
    """With dTheta/dt = coordinate_rate(Theta, y), s(t) = step(s_k, tau(Theta(t))) moves at
    ds/dt = state_rate(s, y) (the reconstruction equation); velocity_of_rate inverts it."""
    rng = np.random.default_rng(seed)
    ret = retraction(name, f.group)
    s0, y = f.sample_state(rng), rng.normal(size=f.algebra_dim)
    theta = rng.normal(size=f.algebra_dim)
    theta *= 0.8 * rng.uniform() / np.linalg.norm(theta)  # inside every retraction's domain
    rate = np.asarray(f.coordinate_rate(ret, theta, y), dtype=float).ravel()
    assert np.allclose(np.asarray(f.velocity_of_rate(ret, theta, rate), dtype=float).ravel(), y,
                       atol=1e-10)
    t = 1e-6
    moved = [np.asarray(f.step(s0, ret, theta + sign * t * rate), dtype=float).ravel()
             for sign in (1.0, -1.0)]
    s = np.asarray(f.step(s0, ret, theta), dtype=float).ravel()
    assert np.allclose((moved[0] - moved[1]) / (2 * t),
                       np.asarray(f.state_rate(s, y), dtype=float).ravel(), atol=1e-7)


@every_factor
@given(seed=seeds)
def test_magnus_step_has_local_order_five(f, seed: int) -> None:
    """step(s, exp(magnus(y(g1 h), y(g2 h), h))) against the reconstruction equation
    ds/dt = state_rate(s, y(t)) integrated by DOP853, for a smooth velocity: the error falls
    by 2^5 when h halves (exact on R^n)."""
    from scipy.integrate import solve_ivp

    rng = np.random.default_rng(seed)
    c = rng.normal(size=(3, f.algebra_dim))
    y = lambda t: c[0] + c[1] * t + c[2] * t * t  # noqa: E731
    s0, ret = f.sample_state(rng), retraction("exp", f.group)
    g = np.array([0.5 - np.sqrt(3) / 6, 0.5 + np.sqrt(3) / 6])
    errors = []
    for h in (0.05, 0.025):  # asymptotic for every seed; at 0.2 some show ratio 16-21
        exact = solve_ivp(lambda t, s: np.asarray(f.state_rate(s, y(t)), dtype=float).ravel(),
                          (0.0, h), s0, method="DOP853", rtol=1e-13, atol=1e-14).y[:, -1]
        W = np.asarray(f.magnus(y(g[0] * h), y(g[1] * h), h), dtype=float).ravel()
        step = np.asarray(f.step(s0, ret, W), dtype=float).ravel()
        errors.append(f.terminal_error(step, exact, np.ones(f.state_dim, bool)))
    assert errors[1] <= 1e-12 or errors[0] / errors[1] >= 2**4.5, errors


@every_factor
@pytest.mark.parametrize("seed", range(6))
def test_magnus6_step_has_local_order_seven(f, seed: int) -> None:
    """step(s, exp(magnus6(y(g1 h), y(g2 h), y(g3 h), h))) against the reconstruction
    equation integrated by DOP853, for a quadratic velocity (order4's): the slope of log error
    against log h over h = 0.4 ... 0.05 is 7 (6.6-7.4 on these data; magnus's is 4.8-5.3;
    exact on R^n). Fixed data and a fit over seven steps, not pairs of random ones: from one
    h to the next the leading error term can nearly cancel (SE(2): ratios 716, 30, 93 for one
    velocity), which no threshold on a ratio survives."""
    from scipy.integrate import solve_ivp

    rng = np.random.default_rng(seed)
    c = rng.normal(size=(3, f.algebra_dim))
    y = lambda t: c[0] + c[1] * t + c[2] * t * t  # noqa: E731
    s0, ret = f.sample_state(rng), retraction("exp", f.group)
    g = 0.5 + np.array([-1.0, 0.0, 1.0]) * np.sqrt(15) / 10
    hs = 0.4 * 2.0 ** -np.arange(0.0, 3.01, 0.5)
    errors = []
    for h in hs:
        exact = solve_ivp(lambda t, s: np.asarray(f.state_rate(s, y(t)), dtype=float).ravel(),
                          (0.0, h), s0, method="DOP853", rtol=3e-14, atol=1e-16).y[:, -1]
        W = np.asarray(f.magnus6(*(y(gi * h) for gi in g), h), dtype=float).ravel()
        step = np.asarray(f.step(s0, ret, W), dtype=float).ravel()
        errors.append(f.terminal_error(step, exact, np.ones(f.state_dim, bool)))
    if max(errors) <= 1e-14:
        return
    slope = np.polyfit(np.log2(hs), np.log2(errors), 1)[0]
    assert slope >= 6.3, (slope, errors)


@every_group_factor
@given(seed=seeds)
def test_stored_state_round_trips(f, seed: int) -> None:
    """A state parsed from its matrix is itself; the packed target of any multiple of it
    (sign free) is it; users see its matrix row-major; a zero quaternion is invalid."""
    s = f.sample_state(np.random.default_rng(seed))
    M = f.matrix(s)
    assert f.distance(s) <= 1e-12
    assert np.allclose(f.parse_state(M), s, atol=1e-12)
    assert np.allclose(np.asarray(f.as_matrix(s)).reshape(f.matrix_shape), M, atol=1e-15)
    rot = f.state_size - (f.algebra_dim - len(range(f.algebra_dim)[f.group.angular]))
    scaled = s.copy()
    scaled[:rot] *= -3.0
    assert np.allclose(np.asarray(f.pack_target(scaled)).ravel(), s, atol=1e-15)
    scaled[:rot] = 0
    assert float(f.invalid(ca.DM(scaled))) == 1.0 and float(f.invalid(ca.DM(s))) == 0.0


def test_group_factor_words_and_sizes() -> None:
    """What messages and parameter files say of each group's states."""
    words = [(f.manifold, f.value_kind, f.state_size, f.state_dim, f.matrix_shape)
             for f in GROUP_FACTORS[::2]]
    assert words == [("SO(3)", "rotation", 4, 3, (3, 3)), ("SE(3)", "pose", 7, 6, (4, 4)),
                     ("SE(2)", "pose", 4, 3, (3, 3))]
    with pytest.raises(ConfigError, match="use Pair for R\\^n"):
        LieGroupFactor(Pair(2).group)


def test_pose_values_in_every_form() -> None:
    """SE(3) states from a 4 x 4 matrix, 7 numbers, identity, or rotation and position."""
    f = LieGroupFactor(SE3, state="g", velocity="xi")
    R = so3.from_axis_angle([1, 2, 3], 1.5)
    g = se3.from_spec({"rotation": R, "position": [1.0, 0.5, -0.3]})
    s = f.parse_state({"rotation": {"axis_angle": {"axis": [1, 2, 3], "angle": 1.5}},
                       "position": [1.0, 0.5, -0.3]})
    for value in (g, g.tolist(), s, -np.concatenate([s[:4], -s[4:]])):
        assert np.allclose(f.parse_state(value), s, atol=1e-12)
    assert np.allclose(f.parse_state("identity"), [1, 0, 0, 0, 0, 0, 0])
    with pytest.raises(ConfigError, match="a pose is"):
        f.parse_state([1.0, 0.0, 0.0])
