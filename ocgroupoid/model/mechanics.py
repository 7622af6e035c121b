"""The Euler-Lagrange operator of a reduced Lagrangian on a Lie algebroid, derived by CasADi.

For a Lagrangian l(q, g, y) on the algebroid of a (product) groupoid, with anchor
``dq/dt = rho(q, y)`` and bracket ``[y, .] = ad_y``, the controlled Euler-Lagrange(-Poincare)
equations read (seed 000, §3.3.1, the operator EL(L) of Remark 6)

    EL_a = d/dt (dl/dy^a) - rho^i_a dl/dq^i + C^g_{ab} y^b dl/dy^g - <dl/dg, g e_a> = F_a,

where ``C^g_{ab} y^b mu_g = -(ad_y^T mu)_a``. For SO(3) and ``l = 1/2 Omega . I Omega`` this
is Euler's ``I dOmega/dt + Omega x I Omega = F``; nothing here is typed in per model.

The last term is the trivialised derivative of l along the group state g of a Lie group
factor (over a point): the symmetry a potential breaks. Varying ``g -> g exp(t eta)`` (body
factors; ``exp(t eta) g`` for spatial ones) in the reduced Hamilton principle
``delta int l(g, xi) dt = 0`` with ``delta xi = d eta/dt + ad_xi eta`` gives the forced
Euler-Poincare equations ``d/dt dl/dxi - ad*_xi dl/dxi = g^{-1} dl/dg + F``: gravity
``m gravity p_3`` on SE(3), a gravity-gradient torque on SO(3). Lagrangians that do not
read g are unchanged.

Actuated directions carry the generalised force ``F_a``. Two forms:

* ``F = B u`` with a square input matrix ``B(q, g)``: the controls are recovered from the
  actuated equations, ``u = B^{-1} EL_actuated``, the unactuated ones give the second-order
  constraints ``Phi^A = EL_A = 0`` (eq. 21), and the cost becomes the second-order
  Lagrangian ``Ltilde(q, y, dy) = C(q, y, u(q, y, dy))`` (eq. 19).
* ``F = F(q, g, y, u)``, any expression of the state and of controls declared as variables
  of their own (:meth:`~ocgroupoid.model.problem.Problem.control`), with as many or fewer
  controls than actuated velocities (thrust along a body axis, torques): every equation
  becomes a constraint ``Phi = EL - F(u) = 0`` and the cost ``C(q, g, y, u)`` reads the
  controls directly; the schemes carry u where they impose Phi.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import casadi as ca
import numpy as np

from ..errors import ConfigError, DimensionError
from ..groupoid.product import Groupoid


def anchor(groupoid: Groupoid, q: ca.SX, y: ca.SX) -> ca.SX:
    """rho(q, y): the base velocity dq/dt, factor by factor."""
    parts = [f.anchor(q[bs], y[vs]) for f, bs, vs in
             zip(groupoid.factors, groupoid.base_layout.slices, groupoid.velocity_layout.slices)]
    return ca.vertcat(*parts) if parts else ca.SX.zeros(0, 1)


def ad_matrix(groupoid: Groupoid, y: ca.SX) -> ca.SX:
    """Block-diagonal matrix of ad_y over the factors' algebras."""
    return ca.diagcat(*[ca.SX(f.ad(y[vs])) for f, vs in
                        zip(groupoid.factors, groupoid.velocity_layout.slices)])


def group_variations(groupoid: Groupoid, s: ca.SX) -> ca.SX:
    """``ds/deta``: the change of the stored node states under ``g -> g exp(t eta)`` (body
    factors; ``exp(t eta) g`` spatial), one column per velocity component (zero for factors
    with a base: their dependence enters through the anchor)."""
    V = ca.SX.zeros(groupoid.state_size, groupoid.algebra_dim)
    for f, ss, vs in zip(groupoid.factors, groupoid.state_layout.slices,
                         groupoid.velocity_layout.slices):
        if f.base_size:
            continue
        for a in range(f.algebra_dim):
            eta = ca.SX.zeros(f.algebra_dim)
            eta[a] = 1.0
            V[ss, vs.start + a] = f.variation(s[ss], eta)
    return V


def on_base(groupoid: Groupoid, expr: ca.SX, q: ca.SX, s: ca.SX) -> ca.SX:
    """``expr`` with the node states of the factors that have a base (R^n, S^2: their node
    state is their base point) replaced by the base coordinates q, so that a Lagrangian may
    name them either way."""
    old, new = [], []
    for f, ss, bs in zip(groupoid.factors, groupoid.state_layout.slices,
                         groupoid.base_layout.slices):
        if f.base_size:
            old.append(s[ss])
            new.append(q[bs])
    return ca.substitute(expr, ca.vertcat(*old), ca.vertcat(*new)) if old else expr


def euler_lagrange(groupoid: Groupoid, l: ca.SX, q: ca.SX, y: ca.SX, dy: ca.SX,
                   s: ca.SX | None = None) -> ca.SX:
    """EL(l)(q, g, y, dy) of the module docstring, as a column of length dim(y); ``s`` the
    node-state symbols the Lagrangian may read (group factors' g)."""
    if l.shape != (1, 1):
        raise DimensionError(f"a Lagrangian is a scalar expression, got shape {l.shape}")
    if s is not None:
        l = on_base(groupoid, l, q, s)
    mu = ca.gradient(l, y)
    qdot = anchor(groupoid, q, y)
    dmu = ca.mtimes(ca.jacobian(mu, y), dy)
    if q.numel() > 0:
        dmu += ca.mtimes(ca.jacobian(mu, q), qdot)
        dmu -= ca.mtimes(ca.jacobian(qdot, y).T, ca.gradient(l, q))
    if s is not None and ca.depends_on(l, s):
        # d mu/dt along g' = g y, and the trivialised derivative of l along g
        V = group_variations(groupoid, s)
        dmu += ca.mtimes(ca.jacobian(mu, s), ca.mtimes(V, y))
        dmu -= ca.mtimes(V.T, ca.gradient(l, s))
    return ca.simplify(dmu - ca.mtimes(ad_matrix(groupoid, y).T, mu))


@dataclass(frozen=True)
class Mechanics:
    """The split controlled Euler-Lagrange system of a Lagrangian.

    ``u`` are the controls: recovered from the actuated equations (``B u = EL_actuated``),
    or the declared control symbols when a ``force`` is given; ``phi`` the equations left
    as constraints (the unactuated ones, or every ``EL - F(u)``), ``EL`` the full operator.
    The mass matrix ``dEL/ddy`` and ``EL|_{dy=0}`` give the forward dynamics of replays.
    """

    lagrangian: ca.SX
    EL: ca.SX
    actuated: tuple[int, ...]
    unactuated: tuple[int, ...]
    input_matrix: ca.SX | None
    u: ca.SX
    phi: ca.SX
    #: the generalised force on the actuated velocities as an expression of the state and
    #: the declared controls (None: ``input_matrix @ u``)
    force: ca.SX | None = None

    def generalised_force(self, u: ca.SX, n: int) -> ca.SX:
        """F on all n velocities for the controls u (zero on the unactuated ones)."""
        F = ca.SX.zeros(n)
        if self.force is not None:
            F[list(self.actuated)] = ca.substitute(self.force, self.u, u)
        else:
            assert self.input_matrix is not None  # split() sets one of the two
            F[list(self.actuated)] = ca.mtimes(self.input_matrix, u)
        return F


def split(groupoid: Groupoid, l: ca.SX, q: ca.SX, y: ca.SX, dy: ca.SX,
          actuated: Sequence[int], input_matrix: ca.SX | None, s: ca.SX | None = None,
          force: ca.SX | None = None, controls: ca.SX | None = None) -> Mechanics:
    """Split EL(l) into controls and constraints (the two forms of the module docstring)."""
    n = y.numel()
    act = tuple(sorted(set(int(i) for i in actuated)))
    if not act or act[0] < 0 or act[-1] >= n:
        raise ConfigError(f"actuated indices must lie in 0..{n - 1}, got {list(actuated)}")
    unact = tuple(i for i in range(n) if i not in act)
    EL = euler_lagrange(groupoid, l, q, y, dy, s)
    if force is not None:
        assert controls is not None
        if force.numel() != len(act):
            raise DimensionError(
                f"the force has {force.numel()} components but {len(act)} velocity components "
                "are actuated: give one generalised force per actuated component (0 where a "
                "control does not push)")
        F = ca.SX.zeros(n)
        F[list(act)] = ca.vec(force)
        return Mechanics(l, EL, act, unact, None, controls, EL - F, ca.vec(force))
    B = ca.SX.eye(len(act)) if input_matrix is None else ca.SX(input_matrix)
    if B.shape != (len(act), len(act)):
        raise DimensionError(
            f"input matrix must be {len(act)} x {len(act)} (one column per control), "
            f"got {B.shape}; with fewer controls than actuated velocities, or a force that is "
            "not B u, declare the controls with pb.control(...) and pass force=...")
    u = ca.solve(B, EL[list(act)])
    phi = EL[list(unact)] if unact else ca.SX.zeros(0, 1)
    return Mechanics(l, EL, act, unact, B, u, phi)


def control_rank(force: ca.SX, controls: ca.SX, args: ca.SX, samples: np.ndarray) -> int:
    """The smallest rank of ``dF/du`` over sample points of ``args`` (rows of samples): the
    controls are independent where it equals their number."""
    J = ca.Function("dF_du", [args, controls], [ca.jacobian(force, controls)])
    ranks = []
    for z in samples:
        u = np.random.default_rng(1).normal(size=controls.numel())
        ranks.append(int(np.linalg.matrix_rank(np.array(J(z, u)), tol=1e-9)))
    return min(ranks)


def least_squares_controls(force: ca.SX, controls: ca.SX, target: ca.SX, start: ca.SX,
                           affine: bool) -> ca.SX:
    """The controls u that bring ``force(u)`` closest to ``target`` (the actuated part of
    the EL operator), as an expression: one Gauss-Newton step from ``start`` (exact for a
    force affine in u), else three damped ones. Exact wherever the constraints hold, so the
    read-out samples it where a scheme carries no control variable (ends of order4's
    intervals) and the guesses start from it."""
    u = start
    for _ in range(1 if affine else 3):
        F = ca.substitute(force, controls, u)
        J = ca.substitute(ca.jacobian(force, controls), controls, u)
        JtJ = ca.mtimes(J.T, J)
        damping = 0.0 if affine else 1e-9 * (1 + ca.trace(JtJ))
        u = u - ca.solve(JtJ + damping * ca.SX.eye(controls.numel()),
                         ca.mtimes(J.T, F - target))
    return u
