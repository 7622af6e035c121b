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
from ocgroupoid.lie import SE2, SE3, SO3, LieGroup, Rn, retraction, se2, se3, so3

from .lie_oracles import ORACLES, first_order_tau, vee_skew
from .strategies import in_ball, twists, vectors


@dataclass(frozen=True)
class Case:
    """A retraction on a group, with the rotation radius of the algebra ball on which tau is
    a diffeomorphism we sample from, and the largest rotation angle tau_inv accepts."""

    group: LieGroup
    name: str
    radius: float
    angle_limit: float

    @property
    def id(self) -> str:
        return f"{self.group.name}-{self.name}"

    def algebra(self, shrink: float = 1.0) -> st.SearchStrategy[np.ndarray]:
        return twists(self.group.dim, self.group.angular, shrink * self.radius)


CASES = [Case(SO3, "cayley", 8.0, np.pi - 1e-3), Case(SO3, "exp", np.pi - 1e-3, np.pi - 1e-3),
         Case(SO3, "first_order", 0.99, np.pi / 2 - 1e-3),
         Case(SE3, "cayley", 8.0, np.pi - 1e-3), Case(SE3, "exp", np.pi - 1e-3, np.pi - 1e-3),
         Case(SE2, "cayley", 8.0, np.pi - 1e-3), Case(SE2, "exp", np.pi - 1e-3, np.pi - 1e-3),
         Case(Rn(4), "cayley", 8.0, 8.0)]
every_retraction = pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
MATRIX_GROUPS = [SO3, SE3, SE2]
every_matrix_group = pytest.mark.parametrize("G", MATRIX_GROUPS, ids=lambda G: G.name)
GROUPS = [*MATRIX_GROUPS, Rn(4)]
every_group = pytest.mark.parametrize("G", GROUPS, ids=lambda G: G.name)


def tau_matrix(G: LieGroup, tau):
    """The map a -> the group matrix of tau(a)."""
    return lambda a: np.asarray(G.matrix(tau(a)))


def fd_right(G: LieGroup, tau, a: np.ndarray, b: np.ndarray, eps: float = 1e-6
             ) -> np.ndarray:
    """vee(dg g^{-1}) of tau along b by central differences (on the group matrices)."""
    M = tau_matrix(G, tau)
    dg = (M(a + eps * b) - M(a - eps * b)) / (2 * eps)
    return G.vee(dg @ np.linalg.inv(M(a)))


def rotation_size(G: LieGroup) -> int:
    """How many parameters hold the rotation (the quaternion): all but the position."""
    return 0 if isinstance(G, Rn) else G.size - (G.dim - len(range(G.dim)[G.angular]))


# ------------------------------------------------------------------ retractions


@every_retraction
@given(data=st.data())
def test_tau_tau_inv_bijective(case: Case, data: st.DataObject) -> None:
    G, ret = case.group, retraction(case.name, case.group)
    g = G.exp(data.draw(twists(G.dim, G.angular, case.angle_limit)))
    assert np.allclose(G.matrix(ret.tau(ret.tau_inv(g))), G.matrix(g), atol=1e-11, rtol=0)
    a = data.draw(case.algebra())
    assert np.allclose(ret.tau_inv(ret.tau(a)), a, atol=1e-9 * max(1, np.linalg.norm(a)),
                       rtol=0)


@every_group
@given(seed=st.integers(0, 2**32 - 1))
def test_distance_from_group_of_a_stack_is_each_matrix_s(G, seed: int) -> None:
    """A stack of matrices, some pushed off the group, measured at once as one by one."""
    rng = np.random.default_rng(seed)
    Ms = [np.asarray(G.matrix(G.sample(rng)), dtype=float) for _ in range(5)]
    Ms = [M + (1e-3 * i) * rng.standard_normal(M.shape) for i, M in enumerate(Ms)]
    each = [float(G.distance_from_group(M)) for M in Ms]
    stacked = np.asarray(G.distance_from_group(np.stack(Ms)), dtype=float)
    assert stacked.shape == (5,) and np.allclose(stacked, each, rtol=1e-14, atol=0)
    assert each[0] <= 1e-12 and (isinstance(G, Rn) or all(e > 0 for e in each[1:]))


@every_retraction
@given(data=st.data())
def test_tau_lands_in_group(case: Case, data: st.DataObject) -> None:
    """tau(a) has unit rotation parameters, tau(a) tau(-a) = e, and its matrix is in G."""
    G, ret = case.group, retraction(case.name, case.group)
    a = data.draw(case.algebra())
    s, g = ret.tau(a), np.asarray(G.matrix(ret.tau(a)))
    assert abs(np.linalg.norm(s[:rotation_size(G)]) - 1) <= 1e-14 or rotation_size(G) == 0
    assert G.distance_from_group(g) <= 1e-12
    assert abs(np.linalg.det(g) - 1) <= 1e-12  # = det R
    assert np.allclose(G.compose(ret.tau(a), ret.tau(-a)), G.identity(), atol=1e-12)


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
    eps, M = 1e-6, tau_matrix(G, ret.tau)
    dg = (M(a + eps * b) - M(a - eps * b)) / (2 * eps)
    assert np.allclose(G.vee(np.linalg.inv(M(a)) @ dg), ret.dtau_left(a) @ b, atol=1e-6,
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
def test_tau_inv_takes_either_sign(case: Case, data: st.DataObject) -> None:
    """tau_inv inverts tau for either sign of the quaternion."""
    G, ret = case.group, retraction(case.name, case.group)
    a = data.draw(case.algebra(0.9))
    flipped = np.array(ret.tau(a))
    flipped[:rotation_size(G)] *= -1
    assert np.allclose(ret.tau_inv(flipped), a, atol=1e-9 * max(1, np.linalg.norm(a)))


@every_retraction
@given(data=st.data())
def test_tau_is_its_matrix_formula(case: Case, data: st.DataObject) -> None:
    """The matrix of tau(a) is the oracle's: cay, exp (and expm of hat), the first-order
    rule's ``c I + hat(a) + a a^T/(1 + c)``; tau_inv of it is the oracle's inverse."""
    G, ret = case.group, retraction(case.name, case.group)
    a = data.draw(case.algebra(0.9))
    oracle = ORACLES[G.name]
    if case.name == "first_order":
        matrix, inverse = first_order_tau, vee_skew
    else:
        matrix, inverse = (oracle.cay, oracle.cay_inv) if case.name == "cayley" else \
            (oracle.exp, oracle.log)
    g = matrix(a)
    assert np.allclose(G.matrix(ret.tau(a)), g, atol=1e-12)
    assert np.allclose(ret.tau_inv(G.of_matrix(g)), inverse(g), atol=1e-9)


@every_retraction
def test_symbolic_and_numeric_agree(case: Case) -> None:
    G, ret = case.group, retraction(case.name, case.group)
    a = ca.SX.sym("a", G.dim)
    s = ca.SX.sym("s", G.size)
    f = ca.Function("f", [a, s], [ret.tau(a), ret.dtau(a), ret.dtau_inv(a), ret.tau_inv(s)])
    rng = np.random.default_rng(1)
    for v in (0.3 * rng.normal(size=G.dim), np.zeros(G.dim), 1e-7 * rng.normal(size=G.dim)):
        sv = ret.tau(v)
        out = f(v, sv)
        ref = (sv, ret.dtau(v), ret.dtau_inv(v), ret.tau_inv(sv))
        for o, r in zip(out, ref):
            assert np.allclose(np.array(o).reshape(np.shape(r)), r, atol=1e-14)


@every_retraction
def test_derivatives_are_finite_at_zero(case: Case) -> None:
    """The Taylor branches keep values, Jacobians and second derivatives NaN-free at a = 0
    (jaxlie's safe trick): IPOPT differentiates every graph twice."""
    G, ret = case.group, retraction(case.name, case.group)
    a, s = ca.SX.sym("a", G.dim), ca.SX.sym("s", G.size)
    outs = [ca.SX(ca.vec(o)) for o in (ret.tau(a), ret.dtau(a), ret.dtau_inv(a),
                                       ret.tau_inv(G.exp(a)), G.log(G.exp(a)),
                                       G.matrix(ret.tau(a)))]
    graphs = [ca.jacobian(o, a) for o in outs]
    graphs += [ca.jacobian(ca.vec(J), a) for J in graphs]
    F = ca.Function("F", [a, s], outs + graphs)
    for out in F(np.zeros(G.dim), G.exp(np.zeros(G.dim))):
        assert np.all(np.isfinite(np.array(out)))


@every_retraction
def test_step_norm_is_the_rotation_angle(case: Case) -> None:
    """One norm per row: |a| on SO(3) and R^n, |omega| on SE(n) (what step_limit refers to)."""
    G, ret = case.group, retraction(case.name, case.group)
    a = np.random.default_rng(2).normal(size=(5, G.dim))
    angular = {"SE2": 1, "SE3": 3}.get(G.name, G.dim)
    assert np.allclose(ret.step_norm(a), np.linalg.norm(a[:, :angular], axis=1))


def test_cayley_singular_at_pi_says_what_to_do() -> None:
    R = so3.from_axis_angle([0, 1, 1], np.pi)
    for G, g in ((SO3, R), (SE3, se3.from_spec({"rotation": R, "position": [1, 2, 3]})),
                 (SE2, se2.from_spec({"angle": np.pi, "position": [1, 2]}))):
        with pytest.raises(SingularityError, match="rotation of pi in one step; increase N"):
            retraction("cayley", G).tau_inv(G.of_matrix(g))


def test_first_order_singular_at_half_turn() -> None:
    ret = retraction("first_order", SO3)
    with pytest.raises(SingularityError, match="increase N"):
        ret.tau_inv(SO3.of_matrix(so3.from_axis_angle([1, 0, 0], 2.0)))
    with pytest.raises(SingularityError, match="increase N"):
        ret.tau(np.array([1.2, 0, 0]))


def test_unknown_retraction_is_named() -> None:
    with pytest.raises(ConfigError, match="unknown retraction 'cayly'.*cayley, exp, first_order"):
        retraction("cayly", SO3)


@pytest.mark.parametrize("G", [SE3, SE2], ids=lambda G: G.name)
def test_first_order_is_so3_only(G: LieGroup) -> None:
    with pytest.raises(ConfigError, match=f"on {G.name} choose cayley or exp"):
        retraction("first_order", G)


# ------------------------------------------------------------------ the groups


@every_group
@given(data=st.data())
def test_exp_log_bijective(G: LieGroup, data: st.DataObject) -> None:
    w = data.draw(twists(G.dim, G.angular, 20.0))
    s = G.exp(w)
    g = np.asarray(G.matrix(s))
    assert G.distance_from_group(g) <= 1e-12
    assert np.allclose(G.matrix(G.exp(G.log(s))), g, atol=1e-11)
    if isinstance(G, Rn) or np.linalg.norm(w[G.angular]) < np.pi - 1e-6:
        assert np.allclose(G.log(s), w, atol=1e-9)
    assert np.allclose(expm(G.hat(w)), g, atol=1e-9)


@every_group
@given(data=st.data())
def test_maps_are_their_matrix_formulas(G: LieGroup, data: st.DataObject) -> None:
    """exp, log, cay, cay_inv and Ad on parameters are the oracles' on matrices."""
    oracle = ORACLES[G.name]
    x = data.draw(twists(G.dim, G.angular, np.pi - 1e-3))
    for f, f_matrix in ((G.exp, oracle.exp), (G.cay, oracle.cay)):
        s = f(x)
        assert np.allclose(G.matrix(s), f_matrix(x), atol=1e-12)
    g = oracle.exp(x)
    assert np.allclose(G.log(G.of_matrix(g)), oracle.log(g), atol=1e-9)
    assert np.allclose(G.cay_inv(G.of_matrix(g)), oracle.cay_inv(g), atol=1e-9)
    assert np.allclose(G.Ad(G.exp(x)), oracle.Ad(g), atol=1e-12)


def test_log_at_pi() -> None:
    for axis in ([1, 0, 0], [0, 1, 1], [1, -2, 3]):
        R = so3.from_axis_angle(axis, np.pi)
        q = SO3.of_matrix(R)
        assert np.allclose(SO3.matrix(SO3.exp(SO3.log(q))), R, atol=1e-12)
        assert np.isclose(np.linalg.norm(SO3.log(q)), np.pi)
        g = se3.from_spec({"rotation": R, "position": [0.3, -1.0, 2.0]})
        assert np.allclose(SE3.matrix(SE3.exp(SE3.log(SE3.of_matrix(g)))), g, atol=1e-12)
    g = se2.from_spec({"angle": np.pi, "position": [0.3, -1.0]})
    assert np.allclose(SE2.matrix(SE2.exp(SE2.log(SE2.of_matrix(g)))), g, atol=1e-12)


@every_group
@given(data=st.data())
def test_hat_vee_and_bracket(G: LieGroup, data: st.DataObject) -> None:
    x, y = data.draw(vectors(G.dim)), data.draw(vectors(G.dim))
    assert np.allclose(G.vee(G.hat(x)), x)
    bracket = G.hat(x) @ G.hat(y) - G.hat(y) @ G.hat(x)
    assert np.allclose(G.vee(bracket), G.ad(x) @ y, atol=1e-9)


def test_so3_hat_is_the_cross_product() -> None:
    x, y = np.array([0.3, -1.0, 2.0]), np.array([1.5, 0.2, -0.7])
    assert np.allclose(SO3.hat(x) @ y, np.cross(x, y))


@every_group
@given(data=st.data())
def test_adjoint(G: LieGroup, data: st.DataObject) -> None:
    """g hat(x) g^{-1} = hat(Ad_g x), Ad_g ad_x Ad_g^{-1} = ad_{Ad_g x} and
    Ad_{exp(x)} = exp(ad_x)."""
    w = data.draw(twists(G.dim, G.angular, 3.0))
    x = data.draw(vectors(G.dim, 3.0))
    g, A = np.asarray(G.matrix(G.exp(w))), G.Ad(G.exp(w))
    assert np.allclose(g @ G.hat(x) @ np.linalg.inv(g), G.hat(A @ x), atol=1e-9)
    assert np.allclose(A @ G.ad(x) @ np.linalg.inv(A), G.ad(A @ x), atol=1e-8)
    assert np.allclose(A, expm(G.ad(w)), atol=1e-9)


@every_group
@given(data=st.data())
def test_dexp_is_the_series_of_ad(G: LieGroup, data: st.DataObject) -> None:
    """The left Jacobian is ``sum_k ad_x^k/(k+1)!`` (independently of Barfoot's Q)."""
    x = data.draw(twists(G.dim, G.angular, 3.0))
    ad = G.ad(x)
    series = sum(np.linalg.matrix_power(ad, k) / factorial(k + 1) for k in range(40))
    assert np.allclose(G.dexp(x), series, atol=1e-9)
    assert np.allclose(G.dexp(x) @ G.dexp_inv(x), np.eye(G.dim), atol=1e-9)


@every_group
@given(data=st.data())
def test_cayley_is_its_definition(G: LieGroup, data: st.DataObject) -> None:
    """``cay(x) = (I - X/2)^{-1} (I + X/2)`` and ``hat(dcay_inv(x) y) = (I - X/2) hat(y)
    (I + X/2)`` (the trivialised derivative derived by hand, independently of Kobilarov &
    Marsden's printed formula)."""
    x, y = data.draw(twists(G.dim, G.angular, 5.0)), data.draw(vectors(G.dim, 3.0))
    X = G.hat(x)
    n = X.shape[0]
    assert np.allclose(G.matrix(G.cay(x)), np.linalg.solve(np.eye(n) - X / 2, np.eye(n) + X / 2),
                       atol=1e-10)
    assert np.allclose(G.hat(G.dcay_inv(x) @ y), (np.eye(n) - X / 2) @ G.hat(y)
                       @ (np.eye(n) + X / 2), atol=1e-9)
    assert np.allclose(G.dcay(x) @ G.dcay_inv(x), np.eye(G.dim), atol=1e-9)


@given(x=vectors(3, 4.0), y=vectors(3, 4.0))
def test_se2_is_se3_restricted_to_the_plane(x: np.ndarray, y: np.ndarray) -> None:
    """SE(2) formulas = SE(3) ones on (omega_z, v_x, v_y): every map, both Jacobians."""
    embed = [2, 3, 4]

    def lift(v: np.ndarray) -> np.ndarray:
        out = np.zeros(6)
        out[embed] = v
        return out

    plane = np.ix_([0, 1, 3], [0, 1, 3])
    for f in ("exp", "cay"):
        assert np.allclose(SE2.matrix(getattr(SE2, f)(x)),
                           np.asarray(SE3.matrix(getattr(SE3, f)(lift(x))))[plane], atol=1e-12)
    for f in ("dexp", "dexp_inv", "dcay", "dcay_inv", "ad"):
        assert np.allclose(getattr(SE2, f)(x) @ y, (getattr(SE3, f)(lift(x)) @ lift(y))[embed],
                           atol=1e-9)


@every_group
@given(a=vectors(6, 3.0), b=vectors(6, 3.0), c=vectors(6, 1.0))
def test_parameters_are_the_group(G: LieGroup, a: np.ndarray, b: np.ndarray, c: np.ndarray
                                  ) -> None:
    """The parameters compose, invert, exponentiate and move as the matrices do."""
    a, b, c = (np.resize(v, G.dim) for v in (a, b, c))
    sa, sb = G.exp(a), G.exp(b)
    ga, gb = np.asarray(G.matrix(sa)), np.asarray(G.matrix(sb))
    assert np.allclose(G.matrix(G.compose(sa, sb)), ga @ gb, atol=1e-12)
    assert np.allclose(G.matrix(G.inverse(sa)), np.linalg.inv(ga), atol=1e-12)
    assert np.allclose(G.matrix(G.exp(G.log(sa))), ga, atol=1e-11)
    assert np.allclose(G.of_matrix(ga), G.normalise(sa), atol=1e-12)
    assert np.allclose(G.as_matrix(sa), ga.ravel() if G.matrix_shape == ga.shape else sa,
                       atol=1e-12)
    t = 1e-6
    body = (G.compose(sa, G.exp(t * c)) - G.compose(sa, G.exp(-t * c))) / (2 * t)
    spatial = (G.compose(G.exp(t * c), sa) - G.compose(G.exp(-t * c), sa)) / (2 * t)
    assert np.allclose(G.body_rate(sa, c), body, atol=1e-8)
    assert np.allclose(G.spatial_rate(sa, c), spatial, atol=1e-8)
    assert np.allclose(G.chart(G.between(sa, sa, "right")), 0, atol=1e-14)
    assert np.allclose(G.chart(G.between(sa, sa, "left")), 0, atol=1e-14)


@every_group
@given(a=vectors(6, 3.0))
def test_paths_land_on_delta(G: LieGroup, a: np.ndarray) -> None:
    """Every path of N steps from the identity, translated on either side, ends at delta."""
    delta, N = G.exp(np.resize(a, G.dim)), 5
    for side in ("right", "left"):
        for label, steps in G.paths(delta, N, side):
            s = G.identity()
            for k in range(N):
                s = G.translate(s, steps[k % len(steps)], side)
            assert np.allclose(G.matrix(np.asarray(ca.DM(s)).ravel()), G.matrix(delta),
                               atol=1e-9), label


@every_matrix_group
def test_normalise_chooses_the_sign_and_flags_zero(G: LieGroup) -> None:
    s = G.exp(np.linspace(0.3, 1.2, G.dim))
    rot = rotation_size(G)
    scaled = s.copy()
    scaled[:rot] *= -2.5
    assert np.allclose(G.normalise(scaled), s, atol=1e-15)
    zero = s.copy()
    zero[:rot] = 0
    assert float(G.invalid(ca.DM(zero))) == 1.0 and float(G.invalid(ca.DM(s))) == 0.0


# ------------------------------------------------------------------ constructors


def test_rotation_constructors_agree() -> None:
    R = so3.from_axis_angle([1, 2, 3], 2.5)
    assert np.allclose(so3.from_rotvec(np.array([1, 2, 3]) / np.sqrt(14) * 2.5), R)
    assert np.allclose(so3.from_quaternion(SO3.of_matrix(R)), R)
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
    stored = SE3.parse(g)
    assert np.allclose(se3.from_spec(stored), g) and np.allclose(SE3.parse(stored), stored)
    assert np.allclose(se3.from_spec({"position": p})[:3, :3], np.eye(3))
    assert np.allclose(se3.from_spec("identity"), np.eye(4))
    with pytest.raises(ConfigError, match="did you mean 'position'"):
        se3.from_spec({"positon": p})
    with pytest.raises(ConfigError, match="last row"):
        se3.from_spec(np.diag([1.0, 1.0, 1.0, 2.0]))
    with pytest.raises(ConfigError, match="a pose is identity"):
        se3.from_spec([1.0, 2.0])
    h = se2.from_spec({"angle": 2.0, "position": [1.0, -1.0]})
    assert np.allclose(SE2.parse(h), [np.cos(1.0), np.sin(1.0), 1.0, -1.0])
    assert np.allclose(se2.from_spec(SE2.parse(h)), h)
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


@every_group
@given(seed=st.integers(0, 2**32 - 1))
def test_deduced_operations(G, seed: int) -> None:
    """between, rplus and rminus, written once on the primitives (manif's deduced section):
    a between(a, b) = b and rplus(b, rminus(a, b)) = a on either side; samples lie on the
    group."""
    rng = np.random.default_rng(seed)
    a, b = G.sample(rng), G.sample(rng)
    assert G.distance_from_group(G.matrix(a)) <= 1e-12
    for side in ("right", "left"):
        assert np.allclose(G.translate(a, G.between(a, b, side), side), b, atol=1e-12)
        assert np.allclose(G.matrix(G.rplus(b, G.rminus(a, b, side), side)), G.matrix(a),
                           atol=1e-9)
        assert np.allclose(G.rminus(a, a, side), 0, atol=1e-12)


@given(in_ball(np.pi - 1e-3, 1))
def test_in_ball_of_one_dimension(a: np.ndarray) -> None:
    assert a.shape == (1,) and abs(a[0]) < np.pi
