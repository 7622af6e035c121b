"""Free-flying rigid body on SE(3): body torque and body force, rest to rest.

The pose g = (R, p) moves with the body twist xi = (omega, v), ``dR/dt = R hat(omega)``,
``dp/dt = R v`` (SE(3) over a point, body convention). Only the reduced Lagrangian

    l(omega, v) = 1/2 omega . J omega + 1/2 m |v|^2

is stated; the mechanics module derives the Newton-Euler equations in the body frame,
``J domega/dt + omega x J omega = tau`` and ``m (dv/dt + omega x v) = f``, with the body
torque tau and force f as the six controls (input matrix I). The cost is
``1/2 int (|tau|^2 + |f|^2) dt``.

In the world frame the force is ``R f = m d^2p/dt^2``, and ``|R f| = |f|``: the translation
decouples from the rotation. The optimal path of the centre of mass is the straight line
with the cubic profile of a double integrator, whose cost is ``6 m^2 |d|^2 / T^3`` for a
rest-to-rest displacement d; the rotation is the torque-optimal slew of a rigid body.
"""

from __future__ import annotations

from typing import Any, Sequence

import casadi as ca
import numpy as np
from pydantic import BaseModel, Field

from ..groupoid import LieGroupFactor
from ..lie import se3
from ..lie.se3 import SE3
from ..model.problem import Problem
from ..model.values import Pose, Positive3, PositiveNumber, Strict, Vector6Free
from .registry import ModelSpec, register

INERTIA = (1.0, 2.0, 3.0)
MASS = 2.0
TARGET = se3.from_spec({"rotation": {"axis_angle": {"axis": [1.0, 2.0, 3.0], "angle": 1.5}},
                        "position": [1.0, 0.5, -0.3]})
REST = (0.0,) * 6
CONTROLS = ["tau1", "tau2", "tau3", "f1", "f2", "f3"]


def free_flyer(J: Sequence[float] = INERTIA, m: float = MASS, T: float = 5.0,
               g0: Any = np.eye(4), xi0: Any = REST, gT: Any = TARGET, xiT: Any = REST,
               name: str = "free_flyer") -> Problem:
    """The rest-to-rest manoeuvre of the module docstring, or any instance of it.

    Defaults: J = diag(1, 2, 3), m = 2, T = 5, from the identity to the rotation of 1.5 rad
    about (1, 2, 3)/sqrt 14 and the position (1, 0.5, -0.3), at rest at both ends. None
    (also per component of a twist) leaves a value free.
    """
    pb = Problem(LieGroupFactor(SE3, state="g", velocity="xi", side="right"), name=name)
    inertia = pb.parameter("J", 3, J, "principal moments of inertia")
    mass = pb.parameter("m", 1, m, "mass")
    xi = pb.velocity("xi")
    omega, v = xi[:3], xi[3:]
    l = 0.5 * ca.dot(omega, inertia * omega) + 0.5 * mass * ca.dot(v, v)
    wrench = pb.mechanics(l, actuated="xi", control_names=CONTROLS)
    pb.minimize(0.5 * ca.sumsqr(wrench))
    axes = ("body x", "body y", "body z")
    pb.describe("g", "pose", ["rad"] * 3 + ["m"] * 3,
                components=[*(f"about {a}" for a in axes), "x", "y", "z"])
    pb.describe("xi", "body twist", ["rad/s"] * 3 + ["m/s"] * 3,
                components=[*(f"ω{i} about {a}" for i, a in zip("123", axes)),
                            *(f"v{i} along {a}" for i, a in zip("123", axes))])
    pb.describe("u", "body wrench", ["N m"] * 3 + ["N"] * 3,
                components=[*(f"torque τ{i} about {a}" for i, a in zip("123", axes)),
                            *(f"force f{i} along {a}" for i, a in zip("123", axes))])
    pb.initial(g=g0, xi=xi0)
    pb.final(g=gT, xi=xiT)
    pb.horizon(T)
    return pb


class Parameters(Strict):
    J: Positive3 = Field(list(INERTIA), description="principal moments of inertia")
    m: PositiveNumber = Field(MASS, description="mass (> 0)")


class Initial(Strict):
    g: Pose = Field(description="initial pose")
    xi: Vector6Free | None = Field(None, description="initial body twist (omega, v)")


class Final(Strict):
    g: Pose | None = Field(None, description="final pose (left out: free)")
    xi: Vector6Free | None = Field(None, description="final body twist (omega, v)")


def _build(params: BaseModel, initial: BaseModel, final: BaseModel, T: float,
           name: str) -> Problem:
    p: Any = params  # validated by Parameters, Initial and Final
    i: Any = initial
    f: Any = final
    return free_flyer(p.J, p.m, T, i.g, i.xi, f.g, f.xi, name)


register(ModelSpec("rigid_body_se3", "free-flying rigid body on SE(3), body torque and force, "
                   "cost 1/2 int |tau|^2 + |f|^2", Parameters, Initial, Final, _build))
