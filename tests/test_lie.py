"""Property tests over every group and retraction (seed 000, Appendix D)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, strategies as st

from ocgroupoid.errors import ConfigError, SingularityError
from ocgroupoid.lie import SO3, Rn, retraction, so3

from .strategies import in_ball, vectors

# name -> radius of the algebra ball on which tau is a diffeomorphism we sample from
RETRACTIONS = {"cayley": 8.0, "exp": np.pi - 1e-3, "first_order": 0.99}
every_retraction = pytest.mark.parametrize("name", list(RETRACTIONS))


def fd_right(tau, a: np.ndarray, b: np.ndarray, eps: float = 1e-6) -> np.ndarray:
    """vee(dR R^T) of tau along b by central differences."""
    dR = (tau(a + eps * b) - tau(a - eps * b)) / (2 * eps)
    return so3.vee(dR @ tau(a).T)


@every_retraction
@given(data=st.data())
def test_tau_tau_inv_bijective(name: str, data: st.DataObject) -> None:
    ret = retraction(name, SO3)
    angle_limit = {"cayley": np.pi - 1e-3, "exp": np.pi - 1e-3, "first_order": np.pi / 2 - 1e-3}
    g = so3.exp(data.draw(in_ball(angle_limit[name])))
    assert np.allclose(ret.tau(ret.tau_inv(g)), g, atol=1e-12, rtol=0)
    a = data.draw(in_ball(RETRACTIONS[name]))
    assert np.allclose(ret.tau_inv(ret.tau(a)), a, atol=1e-9 * max(1, np.linalg.norm(a)), rtol=0)


@every_retraction
@given(data=st.data())
def test_tau_lands_in_group(name: str, data: st.DataObject) -> None:
    ret = retraction(name, SO3)
    a = data.draw(in_ball(RETRACTIONS[name]))
    R = ret.tau(a)
    assert np.linalg.norm(R.T @ R - np.eye(3)) <= 1e-12
    assert abs(np.linalg.det(R) - 1) <= 1e-12
    assert np.allclose(ret.tau(a) @ ret.tau(-a), np.eye(3), atol=1e-12)


@every_retraction
@given(data=st.data())
def test_dtau_matches_finite_differences(name: str, data: st.DataObject) -> None:
    ret = retraction(name, SO3)
    a = data.draw(in_ball(0.9 * RETRACTIONS[name]))
    b = data.draw(vectors(3, 1.0))
    fd = fd_right(ret.tau, a, b)
    assert np.allclose(ret.dtau(a) @ b, fd, atol=1e-6, rtol=1e-6), (a, b)


@every_retraction
@given(data=st.data())
def test_dtau_left_matches_finite_differences(name: str, data: st.DataObject) -> None:
    ret = retraction(name, SO3)
    a = data.draw(in_ball(0.9 * RETRACTIONS[name]))
    b = data.draw(vectors(3, 1.0))
    eps = 1e-6
    dR = (ret.tau(a + eps * b) - ret.tau(a - eps * b)) / (2 * eps)
    assert np.allclose(so3.vee(ret.tau(a).T @ dR), ret.dtau_left(a) @ b, atol=1e-6, rtol=1e-6)


@every_retraction
@given(data=st.data())
def test_dtau_inv_inverts_dtau(name: str, data: st.DataObject) -> None:
    ret = retraction(name, SO3)
    a = data.draw(in_ball(0.9 * RETRACTIONS[name]))
    assert np.allclose(ret.dtau(a) @ ret.dtau_inv(a), np.eye(3), atol=1e-10)
    assert np.allclose(ret.dtau_inv_left(a) @ ret.dtau_left(a), np.eye(3), atol=1e-10)


@every_retraction
@given(data=st.data())
def test_tau_quaternion_is_tau(name: str, data: st.DataObject) -> None:
    ret = retraction(name, SO3)
    a = data.draw(in_ball(0.9 * RETRACTIONS[name]))
    q = ret.tau_quat(a)
    assert abs(np.linalg.norm(q) - 1) <= 1e-14
    assert np.allclose(so3.quat_to_matrix(q), ret.tau(a), atol=1e-13)


@every_retraction
def test_symbolic_and_numeric_agree(name: str) -> None:
    ret = retraction(name, SO3)
    a = ca.SX.sym("a", 3)
    f = ca.Function("f", [a], [ret.tau(a), ret.dtau(a), ret.dtau_inv(a), ret.tau_quat(a)])
    for v in (np.array([0.3, -0.2, 0.5]), np.zeros(3), np.array([1e-7, 0, 2e-7])):
        out = f(v)
        ref = (ret.tau(v), ret.dtau(v), ret.dtau_inv(v), ret.tau_quat(v))
        for o, r in zip(out, ref):
            assert np.allclose(np.array(o).reshape(np.shape(r)), r, atol=1e-14)


@every_retraction
def test_derivatives_are_finite_at_zero(name: str) -> None:
    """The Taylor branches keep value and Jacobian NaN-free at a = 0 (jaxlie's safe trick)."""
    ret = retraction(name, SO3)
    a = ca.SX.sym("a", 3)
    J = ca.Function("J", [a], [ca.jacobian(ca.vec(ret.dtau(a)), a),
                               ca.jacobian(ca.vec(ret.dtau_inv(a)), a)])
    for out in J(np.zeros(3)):
        assert np.all(np.isfinite(np.array(out)))


def test_cayley_singular_at_pi_says_what_to_do() -> None:
    R = so3.from_axis_angle([0, 1, 1], np.pi)
    with pytest.raises(SingularityError, match="rotation of pi in one step; increase N"):
        retraction("cayley", SO3).tau_inv(R)


def test_first_order_singular_at_half_turn() -> None:
    ret = retraction("first_order", SO3)
    with pytest.raises(SingularityError, match="increase N"):
        ret.tau_inv(so3.from_axis_angle([1, 0, 0], 2.0))
    with pytest.raises(SingularityError, match="increase N"):
        ret.tau(np.array([1.2, 0, 0]))


def test_unknown_retraction_is_named() -> None:
    with pytest.raises(ConfigError, match="unknown retraction 'cayly'.*cayley, exp, first_order"):
        retraction("cayly", SO3)


@given(vectors(3, 20.0))
def test_exp_log_bijective(w: np.ndarray) -> None:
    angle = np.linalg.norm(w)
    R = so3.exp(w)
    assert np.linalg.norm(R.T @ R - np.eye(3)) <= 1e-12
    assert np.allclose(so3.exp(so3.log(R)), R, atol=1e-12)
    if angle < np.pi - 1e-6:
        assert np.allclose(so3.log(R), w, atol=1e-10)


def test_log_at_pi() -> None:
    for axis in ([1, 0, 0], [0, 1, 1], [1, -2, 3]):
        R = so3.from_axis_angle(axis, np.pi)
        assert np.allclose(so3.exp(so3.log(R)), R, atol=1e-12)
        assert np.isclose(np.linalg.norm(so3.log(R)), np.pi)


@given(vectors(), vectors())
def test_hat_vee_and_bracket(x: np.ndarray, y: np.ndarray) -> None:
    assert np.allclose(so3.vee(so3.hat(x)), x)
    assert np.allclose(so3.hat(x) @ y, np.cross(x, y))
    bracket = so3.hat(x) @ so3.hat(y) - so3.hat(y) @ so3.hat(x)
    assert np.allclose(so3.vee(bracket), so3.ad(x) @ y, atol=1e-9)


@given(vectors(3, 3.0), vectors())
def test_adjoint(w: np.ndarray, x: np.ndarray) -> None:
    R = so3.exp(w)
    assert np.allclose(R @ so3.hat(x) @ R.T, so3.hat(so3.Ad(R) @ x), atol=1e-9)


@given(vectors(3, 3.0), vectors(3, 3.0))
def test_quaternion_product_is_rotation_product(a: np.ndarray, b: np.ndarray) -> None:
    p, q = so3.to_quaternion(so3.exp(a)), so3.to_quaternion(so3.exp(b))
    assert np.allclose(so3.quat_to_matrix(so3.quat_multiply(p, q)), so3.exp(a) @ so3.exp(b),
                       atol=1e-12)
    assert np.allclose(so3.quat_to_matrix(p), so3.exp(a), atol=1e-12)


def test_rotation_constructors_agree() -> None:
    R = so3.from_axis_angle([1, 2, 3], 2.5)
    assert np.allclose(so3.from_rotvec(np.array([1, 2, 3]) / np.sqrt(14) * 2.5), R)
    assert np.allclose(so3.from_quaternion(so3.to_quaternion(R)), R)
    assert np.allclose(so3.from_matrix(R), R)
    with pytest.raises(ConfigError, match="not a rotation"):
        so3.from_matrix(np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(ConfigError, match="axis is zero"):
        so3.from_axis_angle([0, 0, 0], 1.0)
    with pytest.raises(ConfigError, match="zero quaternion"):
        so3.from_quaternion([0, 0, 0, 0])


@given(vectors(4, 5.0), vectors(4, 5.0))
def test_rn_group_laws(a: np.ndarray, b: np.ndarray) -> None:
    G = Rn(4)
    ret = retraction("cayley", G)
    assert np.allclose(G.compose(a, G.inverse(a)), G.identity())
    assert np.allclose(ret.tau(ret.tau_inv(b)), b)
    assert np.allclose(ret.dtau(a) @ ret.dtau_inv(a), np.eye(4))


GROUPS = [SO3, Rn(4)]
every_group = pytest.mark.parametrize("G", GROUPS, ids=lambda G: G.name)


@every_group
@given(seed=st.integers(0, 2**32 - 1))
def test_deduced_operations(G, seed: int) -> None:
    """between, rplus and rminus, written once on the primitives (manif's deduced section):
    a between(a, b) = b and rplus(b, rminus(a, b)) = a; samples lie on the group."""
    rng = np.random.default_rng(seed)
    a, b = G.sample(rng), G.sample(rng)
    assert G.distance_from_group(a) <= 1e-12
    assert np.allclose(G.compose(a, G.between(a, b)), b, atol=1e-12)
    assert np.allclose(G.rplus(b, G.rminus(a, b)), a, atol=1e-9)
    assert np.allclose(G.rminus(a, a), 0, atol=1e-12)
