"""Fully actuated rigid body on SO(3) (seed 000, §3.3.4; PROBLEMS.md §1).

Only the reduced Lagrangian ``l(Omega) = 1/2 Omega . I Omega`` is stated; Euler's equations
``I dOmega/dt + Omega x I Omega = I u`` come out of the mechanics module. The control u is
the torque divided by the inertia (an angular acceleration), the cost ``1/2 int |u|^2 dt``.
"""

from __future__ import annotations

from typing import Any, Sequence

import casadi as ca
import numpy as np
from pydantic import BaseModel, Field

from ..groupoid import LieGroupFactor
from ..lie import so3
from ..model.problem import Problem
from ..model.values import Positive3, Rotation, Strict, Vector3Free
from .registry import ModelSpec, register

INERTIA = (1.0, 2.0, 3.0)
TARGET = so3.from_rotvec(2.5 * np.array([1.0, 2.0, 3.0]) / np.sqrt(14.0))
REST = (0.0, 0.0, 0.0)


def rigid_body(inertia: Sequence[float] = INERTIA, T: float = 5.0, R0: Any = np.eye(3),
               Omega0: Any = REST, RT: Any = TARGET, OmegaT: Any = REST,
               name: str = "so3_rest_to_rest") -> Problem:
    """The rest-to-rest slew of PROBLEMS.md, or any instance of it.

    Defaults: I = diag(1, 2, 3), T = 5, R(0) = I, R(T) = exp(2.5 hat(n)), n = (1,2,3)/sqrt 14,
    at rest at both ends. None (also per component of a velocity) leaves a value free.
    """
    pb = Problem(LieGroupFactor(state="R", velocity="Omega", side="right"), name=name)
    I = pb.parameter("inertia", 3, inertia, "principal moments of inertia")
    Omega = pb.velocity("Omega")
    u = pb.mechanics(0.5 * ca.dot(Omega, I * Omega), actuated="Omega",
                     input_matrix=ca.diag(I), control_names=["u1", "u2", "u3"])
    pb.minimize(0.5 * ca.sumsqr(u))
    axes = [f"body axis {i}" for i in (1, 2, 3)]
    pb.describe("R", "attitude", "rad", components=[f"about {a}" for a in axes])
    pb.describe("Omega", "body angular velocity", "rad/s",
                components=[f"Ω{i} about {a}" for i, a in zip("123", axes)])
    pb.describe("u", "angular acceleration u = torque / inertia", "rad/s²",
                components=[f"u{i} about {a}" for i, a in zip("123", axes)])
    pb.initial(R=R0, Omega=Omega0)
    pb.final(R=RT, Omega=OmegaT)
    pb.horizon(T)
    return pb


class Parameters(Strict):
    inertia: Positive3 = Field(list(INERTIA), description="principal moments of inertia")


class Initial(Strict):
    R: Rotation = Field(description="initial attitude")
    Omega: Vector3Free | None = Field(None, description="initial body angular velocity")


class Final(Strict):
    R: Rotation | None = Field(None, description="final attitude (left out: free)")
    Omega: Vector3Free | None = Field(None, description="final body angular velocity")


def _build(params: BaseModel, initial: BaseModel, final: BaseModel, T: float,
           name: str) -> Problem:
    return rigid_body(params.inertia, T, initial.R, initial.Omega, final.R,  # type: ignore[attr-defined]
                      final.Omega, name)  # type: ignore[attr-defined]


register(ModelSpec("rigid_body", "fully actuated rigid body on SO(3), cost 1/2 int |u|^2",
                   Parameters, Initial, Final, _build))
