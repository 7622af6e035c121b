"""Groupoid axioms and the discrete structure of every factor."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, strategies as st

from ocgroupoid.errors import ConfigError
from ocgroupoid.groupoid import Groupoid, LieGroupFactor, Pair, SphereAction
from ocgroupoid.lie import SO3, retraction, so3

from .strategies import in_ball, vectors


def unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v)
    return v / n if n > 1e-6 else np.array([0.0, 0.0, 1.0])


def sample_element(f, data):
    """A random element of the factor groupoid and its source."""
    if isinstance(f, LieGroupFactor):
        return so3.exp(data.draw(in_ball(3.0)))
    if isinstance(f, Pair):
        return (data.draw(vectors(f.state_size)), data.draw(vectors(f.state_size)))
    return (unit(data.draw(vectors(3))), so3.exp(data.draw(in_ball(3.0))))


def next_element(f, g, data):
    """A random element composable with g (its source is g's target)."""
    if isinstance(f, LieGroupFactor):
        return so3.exp(data.draw(in_ball(3.0)))
    if isinstance(f, Pair):
        return (f.target(g), data.draw(vectors(f.state_size)))
    return (f.target(g), so3.exp(data.draw(in_ball(3.0))))


def same(a, b) -> bool:
    if a is None or b is None:
        return a is None and b is None
    if isinstance(a, tuple):
        return all(same(x, y) for x, y in zip(a, b))
    return np.allclose(a, b, atol=1e-10)


FACTORS = [LieGroupFactor(), LieGroupFactor(side="left"), Pair(2), SphereAction()]
every_factor = pytest.mark.parametrize("f", FACTORS, ids=lambda f: f"{type(f).__name__}-{f.side}")


@every_factor
@given(data=st.data())
def test_multiplication_is_associative_and_respects_source_target(f, data) -> None:
    g = sample_element(f, data)
    k = next_element(f, g, data)
    m = next_element(f, k, data)
    gk = f.multiply(g, k)
    assert same(f.source(gk), f.source(g)) and same(f.target(gk), f.target(k))
    assert same(f.multiply(gk, m), f.multiply(g, f.multiply(k, m)))


@every_factor
@given(data=st.data())
def test_identity_and_inverse(f, data) -> None:
    g = sample_element(f, data)
    assert same(f.multiply(f.identity(f.source(g)), g), g)
    assert same(f.multiply(g, f.identity(f.target(g))), g)
    assert same(f.multiply(g, f.inverse(g)), f.identity(f.source(g)))
    assert same(f.multiply(f.inverse(g), g), f.identity(f.target(g)))


@pytest.mark.parametrize("f", [Pair(3), SphereAction()], ids=["pair", "action"])
@given(data=st.data())
def test_step_is_the_target_of_the_element(f, data) -> None:
    """s_{k+1} = step(s_k, tau(a)) is the target of the element the velocity generates."""
    ret = retraction("cayley", f.group)
    s = unit(data.draw(vectors(3))) if isinstance(f, SphereAction) else data.draw(vectors(3))
    a = data.draw(in_ball(2.0))
    w = ret.tau(a)
    assert np.allclose(np.asarray(f.step(s, ret, a)).ravel(), f.target(f.element(s, w)))


def test_spatial_convention_is_left_multiplication() -> None:
    """Spatial factor: R_{k+1} = w_k R_k (dR/dt = hat(w) R); body: R_{k+1} = R_k w_k."""
    ret = retraction("cayley", SO3)
    a = np.array([0.2, -0.4, 0.1])
    R = so3.from_rotvec([0.5, 0.3, -1.0])
    q = so3.to_quaternion(R)
    left, right = LieGroupFactor(side="left"), LieGroupFactor(side="right")
    assert np.allclose(left.matrix(np.asarray(left.step(q, ret, a))), ret.tau(a) @ R)
    assert np.allclose(right.matrix(np.asarray(right.step(q, ret, a))), R @ ret.tau(a))


@every_factor
def test_variation_is_the_derivative_of_the_moved_state(f) -> None:
    """variation(s, eta) = d/dt of the state under w_{k-1} -> w_{k-1} exp(t eta) (right) or
    exp(t eta) w_{k-1} (left)."""
    ret = retraction("exp", f.group)
    rng = np.random.default_rng(3)
    a, eta = 0.5 * rng.normal(size=f.algebra_dim), rng.normal(size=f.algebra_dim)
    s = so3.to_quaternion(so3.exp(rng.normal(size=3))) if isinstance(f, LieGroupFactor) else \
        unit(rng.normal(size=3)) if isinstance(f, SphereAction) else rng.normal(size=2)
    if isinstance(f, Pair):
        a, eta = a[:2], eta[:2]
    t = 1e-6

    def moved(sign: float) -> np.ndarray:
        if isinstance(f, Pair):
            return np.asarray(f.step(s, ret, a + sign * t * eta))
        w = so3.exp(a)
        w = w @ so3.exp(sign * t * eta) if f.side == "right" else so3.exp(sign * t * eta) @ w
        return np.asarray(f.step(s, ret, so3.log(w)))

    fd = (moved(1.0) - moved(-1.0)) / (2 * t)
    base = np.asarray(f.step(s, ret, a))
    assert np.allclose(fd, np.asarray(f.variation(base, eta)).ravel(), atol=1e-7)


@every_factor
def test_chart_has_a_single_root(f) -> None:
    """Zero at the target; the antipode / rotation of pi is not a root (a pole)."""
    target_value = so3.from_rotvec([0.3, -1.0, 0.5]) if isinstance(f, LieGroupFactor) else \
        unit(np.array([0.3, -1.0, 0.5])) if isinstance(f, SphereAction) else np.array([1.0, 2.0])
    packed = f.pack_target(target_value)
    s = f.state_of_target(packed)
    assert np.allclose(np.asarray(f.chart(s, packed), dtype=float), 0.0, atol=1e-14)
    if isinstance(f, Pair):
        return
    if isinstance(f, LieGroupFactor):
        flipped = f.parse_state(so3.from_axis_angle([1, 1, 0], np.pi) @ target_value)
    else:
        flipped = -s + np.array([0.0, 1e-9, 0.0])
        flipped /= np.linalg.norm(flipped)
    with np.errstate(divide="ignore", invalid="ignore"):
        c = np.asarray(f.chart(flipped, packed), dtype=float)
    assert not np.all(np.abs(c) < 1e3), c


def test_product_layout_and_names() -> None:
    G = Groupoid(SphereAction(), Pair(2, "theta", "dtheta"))
    assert (G.state_size, G.algebra_dim, G.base_size) == (5, 5, 5)
    assert G.by_velocity("dtheta")[0] == 1
    with pytest.raises(ConfigError, match="distinct"):
        Groupoid(Pair(2), Pair(3))
    with pytest.raises(ConfigError, match="no velocity called 'w'"):
        G.by_velocity("w")


def test_symbolic_step_matches_numeric() -> None:
    f = SphereAction()
    ret = retraction("cayley", SO3)
    s, a = ca.SX.sym("s", 3), ca.SX.sym("a", 3)
    F = ca.Function("F", [s, a], [f.step(s, ret, a)])
    g, v = unit(np.array([0.1, 0.2, 0.9])), np.array([0.3, -0.1, 0.2])
    assert np.allclose(np.array(F(g, v)).ravel(), ret.tau(v).T @ g)
