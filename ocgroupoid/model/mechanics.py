"""The Euler-Lagrange operator of a reduced Lagrangian on a Lie algebroid, derived by CasADi.

For a Lagrangian l(q, y) on the algebroid of a (product) groupoid, with anchor
``dq/dt = rho(q, y)`` and bracket ``[y, .] = ad_y``, the controlled Euler-Lagrange(-Poincare)
equations read (seed 000, §3.3.1, the operator EL(L) of Remark 6)

    EL_a = d/dt (dl/dy^a) - rho^i_a dl/dq^i + C^g_{ab} y^b dl/dy^g = F_a,

where ``C^g_{ab} y^b mu_g = -(ad_y^T mu)_a``. For SO(3) and ``l = 1/2 Omega . I Omega`` this
is Euler's ``I dOmega/dt + Omega x I Omega = F``; nothing here is typed in per model.

Actuated directions carry the control force ``F_a = B u``; the unactuated ones give the
second-order constraints ``Phi^A = EL_A = 0`` (eq. 21), and the cost becomes the
second-order Lagrangian ``Ltilde(q, y, dy) = C(q, y, u(q, y, dy))`` (eq. 19).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import casadi as ca

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


def euler_lagrange(groupoid: Groupoid, l: ca.SX, q: ca.SX, y: ca.SX, dy: ca.SX) -> ca.SX:
    """EL(l)(q, y, dy) of the module docstring, as a column of length dim(y)."""
    if l.shape != (1, 1):
        raise DimensionError(f"a Lagrangian is a scalar expression, got shape {l.shape}")
    mu = ca.gradient(l, y)
    qdot = anchor(groupoid, q, y)
    dmu = ca.mtimes(ca.jacobian(mu, y), dy)
    if q.numel() > 0:
        dmu += ca.mtimes(ca.jacobian(mu, q), qdot)
        dmu -= ca.mtimes(ca.jacobian(qdot, y).T, ca.gradient(l, q))
    return ca.simplify(dmu - ca.mtimes(ad_matrix(groupoid, y).T, mu))


@dataclass(frozen=True)
class Mechanics:
    """The split controlled Euler-Lagrange system of a Lagrangian.

    ``u`` are the controls recovered from the actuated equations (``B u = EL_actuated``),
    ``phi`` the unactuated equations (constraints), ``EL`` the full operator. The mass matrix
    ``dEL/ddy`` and ``EL|_{dy=0}`` give the forward dynamics used by replays.
    """

    lagrangian: ca.SX
    EL: ca.SX
    actuated: tuple[int, ...]
    unactuated: tuple[int, ...]
    input_matrix: ca.SX
    u: ca.SX
    phi: ca.SX


def split(groupoid: Groupoid, l: ca.SX, q: ca.SX, y: ca.SX, dy: ca.SX,
          actuated: Sequence[int], input_matrix: ca.SX | None) -> Mechanics:
    """Split EL(l) into controls ``u = B^{-1} EL_a`` and constraints ``Phi = EL_A``."""
    n = y.numel()
    act = tuple(sorted(set(int(i) for i in actuated)))
    if not act or act[0] < 0 or act[-1] >= n:
        raise ConfigError(f"actuated indices must lie in 0..{n - 1}, got {list(actuated)}")
    unact = tuple(i for i in range(n) if i not in act)
    B = ca.SX.eye(len(act)) if input_matrix is None else ca.SX(input_matrix)
    if B.shape != (len(act), len(act)):
        raise DimensionError(
            f"input matrix must be {len(act)} x {len(act)} (one column per control), "
            f"got {B.shape}"
        )
    EL = euler_lagrange(groupoid, l, q, y, dy)
    u = ca.solve(B, EL[list(act)])
    phi = EL[list(unact)] if unact else ca.SX.zeros(0, 1)
    return Mechanics(l, EL, act, unact, B, u, phi)
