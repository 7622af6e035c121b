"""A quadrotor on SE(3): total thrust along the body z axis, three body torques, gravity.

The pose g = (R, p) moves with the body twist xi = (omega, v), ``dR/dt = R hat(omega)``,
``dp/dt = R v`` (SE(3) over a point, body convention). The reduced Lagrangian reads the
pose through gravity,

    l(g, omega, v) = 1/2 omega . J omega + 1/2 m |v|^2 - m gravity p_3,

and the controls are variables of their own: the thrust f (along body z: the generalised
force ``f e_3`` on v) and the body torques tau (on omega). Fewer controls (4) than velocities
(6): the quadrotor is underactuated, and the two lateral equations of motion are constraints.
The mechanics module derives the forced Newton-Euler equations (Lee, Leok & McClamroch 2010)

    J domega/dt + omega x J omega = tau,   m (dv/dt + omega x v) + m gravity R^T e_3 = f e_3,

from the seeds' reduced variational principle: nothing here is typed in but l and the force.
Bounds ``0 <= f <= f_max``, ``|tau_i| <= tau_max``; the running cost
``(f - m gravity)^2 + |tau|^2`` (thrust beyond hovering, and torque), weighted by the
objective's effort against the time.
"""

from __future__ import annotations

from typing import Any, Sequence

import casadi as ca
import numpy as np
from pydantic import BaseModel, Field

from ..groupoid import LieGroupFactor
from ..lie import se3
from ..lie.se3 import SE3
from ..model.problem import GuessContext, Problem
from ..model.values import Positive3, PositiveNumber, Strict
from .registry import ModelSpec, register
from .rigid_body_se3 import Final, Initial  # the same pose and twist as the free flyer

MASS = 1.0
INERTIA = (0.05, 0.05, 0.09)
GRAVITY = 9.81
F_MAX = 20.0
TAU_MAX = 0.5
HORIZON = 4.0
#: from rest at the origin to rest 2 m ahead, 1 m left and 1 m up, turned to face left
TARGET = se3.from_spec({"rotation": {"axis_angle": {"axis": [0.0, 0.0, 1.0],
                                                   "angle": float(np.pi / 2)}},
                        "position": [2.0, 1.0, 1.0]})
REST = (0.0,) * 6


def quadrotor(m: float = MASS, J: Sequence[float] = INERTIA, gravity: float = GRAVITY,
              f_max: float = F_MAX, tau_max: float = TAU_MAX, T: float = HORIZON,
              g0: Any = np.eye(4), xi0: Any = REST, gT: Any = TARGET, xiT: Any = REST,
              name: str = "quadrotor") -> Problem:
    """The point-to-point flight of the module docstring, or any instance of it (None, also
    per component of a twist, leaves a value free)."""
    pb = Problem(LieGroupFactor(SE3, state="g", velocity="xi", side="right"), name=name)
    mass = pb.parameter("m", 1, m, "mass")
    inertia = pb.parameter("J", 3, J, "principal moments of inertia")
    grav = pb.parameter("gravity", 1, gravity, "gravitational acceleration")
    fmax = pb.parameter("f_max", 1, f_max, "largest thrust")
    taumax = pb.parameter("tau_max", 1, tau_max, "largest body torque about each axis")
    axes = ("body x", "body y", "body z")
    f = pb.control("f", unit="N", meaning="thrust along body z")
    tau = pb.control("tau", 3, unit="N m", meaning="body torques",
                     components=[f"torque τ{i} about {a}" for i, a in zip("123", axes)])
    xi, pose = pb.velocity("xi"), pb.node_state("g")
    omega, v = xi[:3], xi[3:]
    height = pose[2, 3]
    l = 0.5 * ca.dot(omega, inertia * omega) + 0.5 * mass * ca.dot(v, v) \
        - mass * grav * height
    pb.mechanics(l, actuated="xi", force=ca.vertcat(tau, 0, 0, f))
    pb.minimize((f - mass * grav) ** 2 + ca.sumsqr(tau))
    pb.bound(f, 0, fmax, name="f")
    pb.bound(tau, -taumax, taumax, name="tau")
    pb.describe("g", "pose", ["rad"] * 3 + ["m"] * 3,
                components=[*(f"about {a}" for a in axes), "x", "y", "z"])
    pb.describe("xi", "body twist", ["rad/s"] * 3 + ["m/s"] * 3,
                components=[*(f"ω{i} about {a}" for i, a in zip("123", axes)),
                            *(f"v{i} along {a}" for i, a in zip("123", axes))])
    pb.describe("Phi", "equations of motion",
                components=[*(f"λ{i} of the torque equation about {a}"
                              for i, a in zip("123", axes)),
                            *(f"λ{i} of the force equation along {a}"
                              for i, a in zip("456", axes))],
                group=["rotation"] * 3 + ["translation"] * 3)
    pb.initial(g=g0, xi=xi0)
    pb.final(g=gT, xi=xiT)
    pb.horizon(T)
    pb.guesses(yaw_excursions)
    return pb


def yaw_excursions(problem: Problem, ctx: GuessContext) -> list[tuple[str, np.ndarray]]:
    """The geodesic guess with a yaw excursion of +-90 and 180 degrees out and back, ``psi(t)
    = A sin^2(pi t/T)``: starts from which IPOPT reaches minima that bank the other way
    (roll where the geodesic pitches, with a heading changed on the way) — cheaper when the
    inertia about one body axis is much smaller."""
    t = (np.arange(ctx.N) + 0.5) / ctx.N
    rate = np.pi / ctx.T * np.sin(2 * np.pi * t)  # d/dt sin^2(pi t/T), per unit amplitude
    out = []
    for amplitude, word in ((np.pi / 2, "+90"), (-np.pi / 2, "-90"), (np.pi, "180")):
        xi = ctx.base.copy()
        xi[:, 2] += amplitude * rate
        out.append((f"yaw excursion {word} deg", xi))
    return out


class Parameters(Strict):
    m: PositiveNumber = Field(MASS, description="mass (> 0)")
    J: Positive3 = Field(list(INERTIA), description="principal moments of inertia")
    gravity: PositiveNumber = Field(GRAVITY, description="gravitational acceleration (> 0)")
    f_max: PositiveNumber = Field(F_MAX, description="largest thrust (> 0)")
    tau_max: PositiveNumber = Field(TAU_MAX, description="largest body torque about each "
                                    "axis (> 0)")


def _build(params: BaseModel, initial: BaseModel, final: BaseModel, T: float,
           name: str) -> Problem:
    p: Any = params  # validated by Parameters, Initial and Final
    i: Any = initial
    f: Any = final
    return quadrotor(p.m, p.J, p.gravity, p.f_max, p.tau_max, T, i.g, i.xi, f.g, f.xi, name)


register(ModelSpec("quadrotor", "quadrotor on SE(3): thrust along body z, body torques, "
                   "gravity; cost int (f - m g)^2 + |tau|^2", Parameters, Initial, Final,
                   _build))
