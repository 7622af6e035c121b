"""Property tests over every group and retraction (seed 000, Appendix D)."""

from __future__ import annotations

from dataclasses import dataclass
from math import factorial

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, strategies as st
from scipy.linalg import expm

from ocgroupoid.errors import ConfigError, SingularityError
from ocgroupoid.lie import SE2, SE3, SO3, MatrixGroup, Rn, retraction, se2, se3, so3

from .strategies import in_ball, twists, vectors


@dataclass(frozen=True)
class Case:
    """A retraction on a group, with the rotation radius of the algebra ball on which tau is
    a diffeomorphism we sample from, and the largest rotation angle tau_inv accepts."""

    group: MatrixGroup
    name: str
    radius: float
    angle_limit: float

    @property
    def id(self) -> str:
        return f"{self.group.name}-{self.name}"

    def algebra(self, shrink: float = 1.0) -> st.SearchStrategy[np.ndarray]:
        return twists(self.group.dim, self.group.turning, shrink * self.radius)


CASES = [Case(SO3, "cayley", 8.0, np.pi - 1e-3), Case(SO3, "exp", np.pi - 1e-3, np.pi - 1e-3),
         Case(SO3, "first_order", 0.99, np.pi / 2 - 1e-3),
         Case(SE3, "cayley", 8.0, np.pi - 1e-3), Case(SE3, "exp", np.pi - 1e-3, np.pi - 1e-3),
         Case(SE2, "cayley", 8.0, np.pi - 1e-3), Case(SE2, "exp", np.pi - 1e-3, np.pi - 1e-3)]
every_retraction = pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
MATRIX_GROUPS = [SO3, SE3, SE2]
every_matrix_group = pytest.mark.parametrize("G", MATRIX_GROUPS, ids=lambda G: G.name)


def fd_right(G: MatrixGroup, tau, a: np.ndarray, b: np.ndarray, eps: float = 1e-6
             ) -> np.ndarray:
    """vee(dg g^{-1}) of tau along b by central differences."""
    dg = (tau(a + eps * b) - tau(a - eps * b)) / (2 * eps)
    return G.vee(dg @ G.inverse(tau(a)))


def rotation_size(G: MatrixGroup) -> int:
    """How many stored numbers hold the rotation (the quaternion): all but the position."""
    return G.form.size - (G.dim - len(range(G.dim)[G.turning]))


# ------------------------------------------------------------------ retractions


@every_retraction
@given(data=st.data())
def test_tau_tau_inv_bijective(case: Case, data: st.DataObject) -> None:
    G, ret = case.group, retraction(case.name, case.group)
    g = G.exp(data.draw(twists(G.dim, G.turning, case.angle_limit)))
    assert np.allclose(ret.tau(ret.tau_inv(g)), g, atol=1e-11, rtol=0)
    a = data.draw(case.algebra())
    assert np.allclose(ret.tau_inv(ret.tau(a)), a, atol=1e-9 * max(1, np.linalg.norm(a)),
                       rtol=0)


@every_retraction
@given(data=st.data())
def test_tau_lands_in_group(case: Case, data: st.DataObject) -> None:
    G, ret = case.group, retraction(case.name, case.group)
    a = data.draw(case.algebra())
    g = ret.tau(a)
    assert G.distance_from_group(g) <= 1e-12
    assert abs(np.linalg.det(g) - 1) <= 1e-12  # = det R
    assert np.allclose(ret.tau(a) @ ret.tau(-a), G.identity(), atol=1e-12)


@every_retraction
@given(data=st.data())
def test_dtau_matches_finite_differences(case: Case, data: st.DataObject) -> None:
    G, ret = case.group, retraction(case.name, case.group)
    a = data.draw(case.algebra(0.9))
    b = data.draw(vectors(G.dim, 1.0))
    fd = fd_right(G, ret.tau, a, b)
    assert np.allclose(ret.dtau(a) @ b, fd, atol=1e-6, rtol=1e-6), (a, b)


@every_retraction
@given(data=st.data())
def test_dtau_left_matches_finite_differences(case: Case, data: st.DataObject) -> None:
    G, ret = case.group, retraction(case.name, case.group)
    a = data.draw(case.algebra(0.9))
    b = data.draw(vectors(G.dim, 1.0))
    eps = 1e-6
    dg = (ret.tau(a + eps * b) - ret.tau(a - eps * b)) / (2 * eps)
    assert np.allclose(G.vee(G.inverse(ret.tau(a)) @ dg), ret.dtau_left(a) @ b, atol=1e-6,
                       rtol=1e-6)


@every_retraction
@given(data=st.data())
def test_dtau_inv_inverts_dtau(case: Case, data: st.DataObject) -> None:
    G, ret = case.group, retraction(case.name, case.group)
    a = data.draw(case.algebra(0.9))
    assert np.allclose(ret.dtau(a) @ ret.dtau_inv(a), np.eye(G.dim), atol=1e-10)
    assert np.allclose(ret.dtau_inv_left(a) @ ret.dtau_left(a), np.eye(G.dim), atol=1e-10)


@every_retraction
@given(data=st.data())
def test_tau_state_is_tau(case: Case, data: st.DataObject) -> None:
    """The stored form of tau(a) is tau(a), with a unit quaternion; tau_inv_state inverts it
    for either sign of the quaternion."""
    G, ret = case.group, retraction(case.name, case.group)
    a = data.draw(case.algebra(0.9))
    s = ret.tau_state(a)
    assert abs(np.linalg.norm(s[:rotation_size(G)]) - 1) <= 1e-14
    assert np.allclose(G.form.matrix(s), ret.tau(a), atol=1e-13)
    flipped = s.copy()
    flipped[:rotation_size(G)] *= -1
    for t in (s, flipped):
        assert np.allclose(ret.tau_inv_state(t), a, atol=1e-9 * max(1, np.linalg.norm(a)))


@every_retraction
def test_symbolic_and_numeric_agree(case: Case) -> None:
    G, ret = case.group, retraction(case.name, case.group)
    a = ca.SX.sym("a", G.dim)
    s = ca.SX.sym("s", G.form.size)
    f = ca.Function("f", [a, s], [ret.tau(a), ret.dtau(a), ret.dtau_inv(a), ret.tau_state(a),
                                  ret.tau_inv_state(s)])
    rng = np.random.default_rng(1)
    for v in (0.3 * rng.normal(size=G.dim), np.zeros(G.dim), 1e-7 * rng.normal(size=G.dim)):
        sv = ret.tau_state(v)
        out = f(v, sv)
        ref = (ret.tau(v), ret.dtau(v), ret.dtau_inv(v), sv, ret.tau_inv_state(sv))
        for o, r in zip(out, ref):
            assert np.allclose(np.array(o).reshape(np.shape(r)), r, atol=1e-14)


@every_retraction
def test_derivatives_are_finite_at_zero(case: Case) -> None:
    """The Taylor branches keep values, Jacobians and second derivatives NaN-free at a = 0
    (jaxlie's safe trick): IPOPT differentiates every graph twice."""
    G, ret = case.group, retraction(case.name, case.group)
    a, s = ca.SX.sym("a", G.dim), ca.SX.sym("s", G.form.size)
    outs = [ca.vec(ret.tau(a)), ca.vec(ret.dtau(a)), ca.vec(ret.dtau_inv(a)),
            ret.tau_state(a), ret.tau_inv_state(G.form.exp(a)), G.form.log(G.form.exp(a))]
    graphs = [ca.jacobian(o, a) for o in outs]
    graphs += [ca.jacobian(ca.vec(J), a) for J in graphs]
    F = ca.Function("F", [a, s], outs + graphs)
    for out in F(np.zeros(G.dim), G.form.exp(np.zeros(G.dim))):
        assert np.all(np.isfinite(np.array(out)))


@every_retraction
def test_step_norm_is_the_rotation_angle(case: Case) -> None:
    """One norm per row: |a| on SO(3), |omega| on SE(n) (what step_limit refers to)."""
    G, ret = case.group, retraction(case.name, case.group)
    a = np.random.default_rng(2).normal(size=(5, G.dim))
    assert np.allclose(ret.step_norm(a), np.linalg.norm(a[:, : 1 if G is SE2 else 3], axis=1))


def test_cayley_singular_at_pi_says_what_to_do() -> None:
    R = so3.from_axis_angle([0, 1, 1], np.pi)
    for G, g in ((SO3, R), (SE3, se3.from_spec({"rotation": R, "position": [1, 2, 3]})),
                 (SE2, se2.from_spec({"angle": np.pi, "position": [1, 2]}))):
        with pytest.raises(SingularityError, match="rotation of pi in one step; increase N"):
            retraction("cayley", G).tau_inv(g)


def test_first_order_singular_at_half_turn() -> None:
    ret = retraction("first_order", SO3)
    with pytest.raises(SingularityError, match="increase N"):
        ret.tau_inv(so3.from_axis_angle([1, 0, 0], 2.0))
    with pytest.raises(SingularityError, match="increase N"):
        ret.tau(np.array([1.2, 0, 0]))


def test_unknown_retraction_is_named() -> None:
    with pytest.raises(ConfigError, match="unknown retraction 'cayly'.*cayley, exp, first_order"):
        retraction("cayly", SO3)


@pytest.mark.parametrize("G", [SE3, SE2], ids=lambda G: G.name)
def test_first_order_is_so3_only(G: MatrixGroup) -> None:
    with pytest.raises(ConfigError, match=f"on {G.name} choose cayley or exp"):
        retraction("first_order", G)


# ------------------------------------------------------------------ the groups


@every_matrix_group
@given(data=st.data())
def test_exp_log_bijective(G: MatrixGroup, data: st.DataObject) -> None:
    w = data.draw(twists(G.dim, G.turning, 20.0))
    g = G.exp(w)
    assert G.distance_from_group(g) <= 1e-12
    assert np.allclose(G.exp(G.log(g)), g, atol=1e-11)
    if np.linalg.norm(w[G.turning]) < np.pi - 1e-6:
        assert np.allclose(G.log(g), w, atol=1e-9)
    assert np.allclose(expm(G.hat(w)), g, atol=1e-9)


def test_log_at_pi() -> None:
    for axis in ([1, 0, 0], [0, 1, 1], [1, -2, 3]):
        R = so3.from_axis_angle(axis, np.pi)
        assert np.allclose(so3.exp(so3.log(R)), R, atol=1e-12)
        assert np.isclose(np.linalg.norm(so3.log(R)), np.pi)
        g = se3.from_spec({"rotation": R, "position": [0.3, -1.0, 2.0]})
        assert np.allclose(se3.exp(se3.log(g)), g, atol=1e-12)
    g = se2.from_spec({"angle": np.pi, "position": [0.3, -1.0]})
    assert np.allclose(se2.exp(se2.log(g)), g, atol=1e-12)


@every_matrix_group
@given(data=st.data())
def test_hat_vee_and_bracket(G: MatrixGroup, data: st.DataObject) -> None:
    x, y = data.draw(vectors(G.dim)), data.draw(vectors(G.dim))
    assert np.allclose(G.vee(G.hat(x)), x)
    bracket = G.hat(x) @ G.hat(y) - G.hat(y) @ G.hat(x)
    assert np.allclose(G.vee(bracket), G.ad(x) @ y, atol=1e-9)


def test_so3_hat_is_the_cross_product() -> None:
    x, y = np.array([0.3, -1.0, 2.0]), np.array([1.5, 0.2, -0.7])
    assert np.allclose(so3.hat(x) @ y, np.cross(x, y))


@every_matrix_group
@given(data=st.data())
def test_adjoint(G: MatrixGroup, data: st.DataObject) -> None:
    """g hat(x) g^{-1} = hat(Ad_g x), Ad_g ad_x Ad_g^{-1} = ad_{Ad_g x} and
    Ad_{exp(x)} = exp(ad_x)."""
    w = data.draw(twists(G.dim, G.turning, 3.0))
    x = data.draw(vectors(G.dim, 3.0))
    g, A = G.exp(w), G.Ad(G.exp(w))
    assert np.allclose(g @ G.hat(x) @ G.inverse(g), G.hat(A @ x), atol=1e-9)
    assert np.allclose(A @ G.ad(x) @ np.linalg.inv(A), G.ad(A @ x), atol=1e-8)
    assert np.allclose(A, expm(G.ad(w)), atol=1e-9)


@every_matrix_group
@given(data=st.data())
def test_dexp_is_the_series_of_ad(G: MatrixGroup, data: st.DataObject) -> None:
    """The left Jacobian is ``sum_k ad_x^k/(k+1)!`` (independently of Barfoot's Q)."""
    x = data.draw(twists(G.dim, G.turning, 3.0))
    ad = G.ad(x)
    series = sum(np.linalg.matrix_power(ad, k) / factorial(k + 1) for k in range(40))
    assert np.allclose(G.dexp(x), series, atol=1e-9)
    assert np.allclose(G.dexp(x) @ G.dexp_inv(x), np.eye(G.dim), atol=1e-9)


@every_matrix_group
@given(data=st.data())
def test_cayley_is_its_definition(G: MatrixGroup, data: st.DataObject) -> None:
    """``cay(x) = (I - X/2)^{-1} (I + X/2)`` and ``hat(dcay_inv(x) y) = (I - X/2) hat(y)
    (I + X/2)`` (the trivialised derivative derived by hand, independently of Kobilarov &
    Marsden's printed formula)."""
    x, y = data.draw(twists(G.dim, G.turning, 5.0)), data.draw(vectors(G.dim, 3.0))
    X, n = G.hat(x), G.identity().shape[0]
    assert np.allclose(G.cay(x), np.linalg.solve(np.eye(n) - X / 2, np.eye(n) + X / 2),
                       atol=1e-10)
    assert np.allclose(G.hat(G.dcay_inv(x) @ y), (np.eye(n) - X / 2) @ G.hat(y)
                       @ (np.eye(n) + X / 2), atol=1e-9)


@given(x=vectors(3, 4.0), y=vectors(3, 4.0))
def test_se2_is_se3_restricted_to_the_plane(x: np.ndarray, y: np.ndarray) -> None:
    """SE(2) formulas = SE(3) ones on (omega_z, v_x, v_y): every map, both Jacobians."""
    embed = [2, 3, 4]

    def lift(v: np.ndarray) -> np.ndarray:
        out = np.zeros(6)
        out[embed] = v
        return out

    plane = np.ix_([0, 1, 3], [0, 1, 3])
    for f2, f3 in ((se2.exp, se3.exp), (se2.cay, se3.cay)):
        assert np.allclose(f2(x), f3(lift(x))[plane], atol=1e-12)
    for f2, f3 in ((se2.dexp, se3.dexp), (se2.dexp_inv, se3.dexp_inv), (se2.dcay, se3.dcay),
                   (se2.dcay_inv, se3.dcay_inv), (se2.ad, se3.ad)):
        assert np.allclose(f2(x) @ y, (f3(lift(x)) @ lift(y))[embed], atol=1e-9)


@every_matrix_group
@given(a=vectors(6, 3.0), b=vectors(6, 3.0), c=vectors(6, 1.0))
def test_form_is_the_group(G: MatrixGroup, a: np.ndarray, b: np.ndarray, c: np.ndarray
                           ) -> None:
    """The stored form composes, inverts, exponentiates and moves as the matrices do."""
    F = G.form
    a, b, c = a[:G.dim], b[:G.dim], c[:G.dim]
    sa, sb = F.exp(a), F.exp(b)
    assert np.allclose(F.matrix(F.compose(sa, sb)), G.exp(a) @ G.exp(b), atol=1e-12)
    assert np.allclose(F.matrix(F.inverse(sa)), G.inverse(G.exp(a)), atol=1e-12)
    assert np.allclose(F.matrix(F.exp(F.log(sa))), G.exp(a), atol=1e-11)
    assert np.allclose(F.of_matrix(F.matrix(sa)), F.normalise(sa), atol=1e-12)
    assert np.allclose(F.shown(sa), G.exp(a).ravel(), atol=1e-12)
    t = 1e-6
    body = (F.compose(sa, F.exp(t * c)) - F.compose(sa, F.exp(-t * c))) / (2 * t)
    spatial = (F.compose(F.exp(t * c), sa) - F.compose(F.exp(-t * c), sa)) / (2 * t)
    assert np.allclose(F.body_rate(sa, c), body, atol=1e-8)
    assert np.allclose(F.spatial_rate(sa, c), spatial, atol=1e-8)
    assert np.allclose(F.chart(F.between(sa, sa, "right")), 0, atol=1e-14)
    assert np.allclose(F.chart(F.between(sa, sa, "left")), 0, atol=1e-14)


@every_matrix_group
def test_normalise_chooses_the_sign_and_flags_zero(G: MatrixGroup) -> None:
    F = G.form
    s = F.exp(np.linspace(0.3, 1.2, G.dim))
    rot = rotation_size(G)
    scaled = s.copy()
    scaled[:rot] *= -2.5
    assert np.allclose(F.normalise(scaled), s, atol=1e-15)
    zero = s.copy()
    zero[:rot] = 0
    assert float(F.invalid(ca.DM(zero))) == 1.0 and float(F.invalid(ca.DM(s))) == 0.0


# ------------------------------------------------------------------ constructors


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


def test_pose_constructors_agree() -> None:
    R, p = so3.from_axis_angle([1, 2, 3], 1.5), [1.0, 0.5, -0.3]
    g = se3.from_spec({"rotation": {"axis_angle": {"axis": [1, 2, 3], "angle": 1.5}},
                       "position": p})
    assert np.allclose(g[:3, :3], R) and np.allclose(g[:3, 3], p)
    assert np.allclose(se3.from_spec(g), g) and np.allclose(se3.from_spec(g.tolist()), g)
    stored = SE3.form.parse(g)
    assert np.allclose(se3.from_spec(stored), g) and np.allclose(SE3.form.parse(stored), stored)
    assert np.allclose(se3.from_spec({"position": p})[:3, :3], np.eye(3))
    assert np.allclose(se3.from_spec("identity"), np.eye(4))
    with pytest.raises(ConfigError, match="did you mean 'position'"):
        se3.from_spec({"positon": p})
    with pytest.raises(ConfigError, match="last row"):
        se3.from_spec(np.diag([1.0, 1.0, 1.0, 2.0]))
    with pytest.raises(ConfigError, match="a pose is identity"):
        se3.from_spec([1.0, 2.0])
    h = se2.from_spec({"angle": 2.0, "position": [1.0, -1.0]})
    assert np.allclose(SE2.form.parse(h), [np.cos(1.0), np.sin(1.0), 1.0, -1.0])
    assert np.allclose(se2.from_spec(SE2.form.parse(h)), h)
    with pytest.raises(ConfigError, match="not a planar pose"):
        se2.from_spec(np.diag([1.0, -1.0, 1.0]))
    with pytest.raises(ConfigError, match="did you mean 'angle'"):
        se2.from_spec({"angel": 1.0})


# ------------------------------------------------------------------ R^n and every group


@given(vectors(4, 5.0), vectors(4, 5.0))
def test_rn_group_laws(a: np.ndarray, b: np.ndarray) -> None:
    G = Rn(4)
    ret = retraction("cayley", G)
    assert np.allclose(G.compose(a, G.inverse(a)), G.identity())
    assert np.allclose(ret.tau(ret.tau_inv(b)), b)
    assert np.allclose(ret.dtau(a) @ ret.dtau_inv(a), np.eye(4))


GROUPS = [SO3, SE3, SE2, Rn(4)]
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


@given(in_ball(np.pi - 1e-3, 1))
def test_in_ball_of_one_dimension(a: np.ndarray) -> None:
    assert a.shape == (1,) and abs(a[0]) < np.pi
