"""How the shooting baselines carry an attitude: unit quaternions, rotation matrices or ZYX
Euler angles, each integrated as a plain vector (no projection back onto SO(3)).

A :class:`Coordinates` maps the factor's stored state (a unit quaternion for SO(3) factors) to
its own coordinates ``z`` (:meth:`of_stored`), back (:meth:`stored`, what boundary
conditions, read-outs and replays see), and gives ``dz/dt`` for the velocity y
(:meth:`rate`). Factors that are not SO(3) keep their stored form in every baseline.

* quaternion: ``dq/dt = q (0, Omega) / 2`` (body) or ``(0, omega) q / 2`` (spatial): what a
  rockit or Opti user writes. Nothing keeps |q| = 1; the final chart reads the direction of q.
* matrix: ``dR/dt = R hat(Omega)`` (body) or ``hat(omega) R`` (spatial), nine numbers; read
  back through Shepperd's quaternion of R.
* euler: ``R = Rz(psi) Ry(theta) Rx(phi)``; body rates ``Omega`` give
  ``dphi = Omega1 + tan(theta) (Omega2 sin(phi) + Omega3 cos(phi))``,
  ``dtheta = Omega2 cos(phi) - Omega3 sin(phi)``,
  ``dpsi = (Omega2 sin(phi) + Omega3 cos(phi)) / cos(theta)``: singular at a pitch of
  +-90 degrees (gimbal lock).
"""

from __future__ import annotations

from typing import Any, ClassVar

import casadi as ca

from ...groupoid.base import Factor
from ...lie import SO3

COORDINATES = ("quaternion", "matrix", "euler")


class Coordinates:
    """The factor's stored form itself (every non-SO(3) factor, and quaternions)."""

    name: ClassVar[str] = "quaternion"

    def __init__(self, factor: Factor) -> None:
        self.factor = factor

    @property
    def size(self) -> int:
        return self.factor.state_size

    def of_stored(self, s: Any) -> Any:
        return s

    def stored(self, z: Any) -> Any:
        return z

    def rate(self, z: Any, y: Any) -> Any:
        return self.factor.state_rate(z, y)

    def body_rate(self, z: Any, y: Any) -> Any:
        """The body angular velocity of an SO(3) factor: y itself (body side) or
        ``R^T omega`` (spatial side)."""
        if self.factor.side == "right":
            return y
        return ca.mtimes(SO3.matrix(self.stored(z)).T, y)


class Matrix(Coordinates):
    """Nine entries of R, column by column."""

    name = "matrix"
    size = 9

    def of_stored(self, s: Any) -> Any:
        return ca.vec(SO3.matrix(s))

    def stored(self, z: Any) -> Any:
        return quaternion_of_matrix(ca.reshape(z, 3, 3))

    def rate(self, z: Any, y: Any) -> Any:
        R = ca.reshape(z, 3, 3)
        return ca.vec(ca.mtimes(R, SO3.hat(y)) if self.factor.side == "right"
                      else ca.mtimes(SO3.hat(y), R))


class Euler(Coordinates):
    """Roll, pitch, yaw ``(phi, theta, psi)`` of ``R = Rz(psi) Ry(theta) Rx(phi)``."""

    name = "euler"
    size = 3

    def of_stored(self, s: Any) -> Any:
        w, x, y, z = s[0], s[1], s[2], s[3]
        sin_pitch = ca.fmin(ca.fmax(2 * (w * y - z * x), -1.0), 1.0)
        return ca.vertcat(ca.atan2(2 * (w * x + y * z), 1 - 2 * (x**2 + y**2)),
                          ca.asin(sin_pitch),
                          ca.atan2(2 * (w * z + x * y), 1 - 2 * (y**2 + z**2)))

    def stored(self, z: Any) -> Any:
        half = z / 2
        qx = ca.vertcat(ca.cos(half[0]), ca.sin(half[0]), 0, 0)
        qy = ca.vertcat(ca.cos(half[1]), 0, ca.sin(half[1]), 0)
        qz = ca.vertcat(ca.cos(half[2]), 0, 0, ca.sin(half[2]))
        return SO3.compose(qz, SO3.compose(qy, qx))

    def rate(self, z: Any, y: Any) -> Any:
        W = self.body_rate(z, y)
        phi, theta = z[0], z[1]
        turn = W[1] * ca.sin(phi) + W[2] * ca.cos(phi)
        return ca.vertcat(W[0] + ca.tan(theta) * turn, W[1] * ca.cos(phi) - W[2] * ca.sin(phi),
                          turn / ca.cos(theta))


def coordinates(name: str, factor: Factor) -> Coordinates:
    """The coordinates called ``name`` for ``factor``: SO(3) factors get them, every other
    factor keeps its stored form."""
    is_so3 = getattr(factor, "group", None) is SO3 and factor.state_size == 4
    cls = {"matrix": Matrix, "euler": Euler}.get(name, Coordinates) if is_so3 else Coordinates
    return cls(factor)


def quaternion_of_matrix(R: Any) -> Any:
    """Shepperd's unit quaternion (w >= 0) of a (nearly) orthogonal matrix, as a graph: of the
    four candidate formulas the one with the largest square root. The square roots' arguments
    are floored so that the branches not taken stay finite (their derivatives too)."""
    t = R[0, 0] + R[1, 1] + R[2, 2]
    diag = [t, R[0, 0] - R[1, 1] - R[2, 2], R[1, 1] - R[0, 0] - R[2, 2],
            R[2, 2] - R[0, 0] - R[1, 1]]
    r = [0.5 * ca.sqrt(ca.fmax(1 + d, 1e-12)) for d in diag]
    a = [(R[2, 1] - R[1, 2]), (R[0, 2] - R[2, 0]), (R[1, 0] - R[0, 1])]  # 4 w (x, y, z)
    b = [(R[0, 1] + R[1, 0]), (R[0, 2] + R[2, 0]), (R[1, 2] + R[2, 1])]  # 4 (xy, xz, yz)
    cands = [ca.vertcat(r[0], a[0] / (4 * r[0]), a[1] / (4 * r[0]), a[2] / (4 * r[0])),
             ca.vertcat(a[0] / (4 * r[1]), r[1], b[0] / (4 * r[1]), b[1] / (4 * r[1])),
             ca.vertcat(a[1] / (4 * r[2]), b[0] / (4 * r[2]), r[2], b[2] / (4 * r[2])),
             ca.vertcat(a[2] / (4 * r[3]), b[1] / (4 * r[3]), b[2] / (4 * r[3]), r[3])]
    q = cands[3]
    for i in (2, 1, 0):
        best = ca.logic_and(ca.logic_and(diag[i] >= diag[(i + 1) % 4],
                                         diag[i] >= diag[(i + 2) % 4]),
                            diag[i] >= diag[(i + 3) % 4])
        q = ca.if_else(best, cands[i], q)
    return SO3.normalise(q)
