"""Heavy top with two internal rotors (seed 000, §3.3.5; PROBLEMS.md §2).

The configuration lives on the action groupoid ``S^2 x SO(3) => S^2`` (Gamma, the upward
vertical seen from the body; composable when ``Gamma_{k+1} = W_k^T Gamma_k``) times the pair
groupoid of the rotor angles theta on R^2. The model states only the reduced Lagrangian

    l = 1/2 (gamma_1 O_1^2 + gamma_2 O_2^2 + Ibar_3 O_3^2 + J_1 dth_1^2 + J_2 dth_2^2)
        + J_1 O_1 dth_1 + J_2 O_2 dth_2 - mgl Gamma_3,      gamma_i = Ibar_i + J_i,

that the rotors are actuated, the parameters and the boundary conditions. The mechanics
module derives the rest: the rotor torques ``u_i = J_i (dO_i/dt + ddth_i)`` and the top
equations ``dPi/dt = Pi x Omega + mgl Gamma x e3`` with ``Pi = dl/dOmega``, which carry no
control and become the constraints Phi^A (their IPOPT multipliers are the seed's lambda^k).

The Casimir ``Pi . Gamma`` is conserved for every control and declared so: with Gamma(T),
Omega_1,2(T) and dtheta(T) prescribed it fixes Omega_3(T), so that one is left free, and a
problem file that prescribes it too is rejected before IPOPT runs (:mod:`ocgroupoid.nlp.boundary`).

Two discretisations of the top equations: the seed's midpoint rule (the default), and
:func:`lie_poisson`, the discrete top of the groupoid lecture (seed 004) written for the
spatial momentum, which conserves a discrete Casimir exactly. Multi-start adds
:func:`rotor_guesses`: the cheap minima spin a rotor up and back down.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Sequence

import casadi as ca
import numpy as np
from pydantic import BaseModel, Field

from ..errors import ConfigError
from ..groupoid import Groupoid, Pair, SphereAction
from ..model.mechanics import anchor
from ..model.problem import GuessContext, Problem
from ..model.values import (
    Number,
    Positive2,
    Positive3,
    Strict,
    UnitVector3,
    Vector2Free,
    Vector3Free,
)
from ..nlp.schemes import Node
from .registry import ModelSpec, register

if TYPE_CHECKING:
    from ..nlp.transcription import Transcription

IBAR = (1.1, 1.2, 0.6)
ROTOR = (0.1, 0.1)
MGL = 1.0
GAMMA0 = (0.0, float(np.sin(0.4)), float(np.cos(0.4)))
UPRIGHT = (0.0, 0.0, 1.0)


def heavy_top(Ibar: Sequence[float] = IBAR, J: Sequence[float] = ROTOR, mgl: float = MGL,
              T: float = 3.0, Gamma0: Any = GAMMA0, Omega0: Any = (0.0, 0.0, 5.0),
              theta0: Any = (0.0, 0.0), dtheta0: Any = (0.0, 0.0), GammaT: Any = UPRIGHT,
              OmegaT: Any = (0.0, 0.0, None), dthetaT: Any = (0.0, 0.0), thetaT: Any = None,
              name: str = "heavy_top_rotors") -> Problem:
    """The PROBLEMS.md instance (the defaults), or any other; None leaves a value free."""
    G = Groupoid(SphereAction("Gamma", "Omega"), Pair(2, "theta", "dtheta"))
    pb = Problem(G, name=name)
    Ib = pb.parameter("Ibar", 3, Ibar, "top inertias including the rotors' transverse ones")
    Jr = pb.parameter("J", 2, J, "axial inertias of the rotors")
    m = pb.parameter("mgl", 1, mgl, "mass x gravity x distance of the centre of mass")
    Gamma, Omega, dtheta = pb.state("Gamma"), pb.velocity("Omega"), pb.velocity("dtheta")
    gamma = Ib[:2] + Jr
    l = (0.5 * (ca.dot(gamma, Omega[:2] ** 2) + Ib[2] * Omega[2] ** 2 + ca.dot(Jr, dtheta ** 2))
         + ca.dot(Jr * Omega[:2], dtheta) - m * Gamma[2])
    u = pb.mechanics(l, actuated="dtheta", control_names=["u1", "u2"])
    pb.minimize(0.5 * ca.sumsqr(u))
    pb.conserved("Pi.Gamma", ca.dot(ca.gradient(l, Omega), Gamma))
    axes = [f"body axis {i}" for i in (1, 2, 3)]
    pb.describe("Gamma", "upward vertical in the body frame", "1",
                components=[f"Γ{i} along {a}" for i, a in zip("123", axes)])
    pb.describe("theta", "rotor angles", "rad", components=["rotor 1", "rotor 2"])
    pb.describe("Omega", "body angular velocity", "rad/s",
                components=[f"Ω{i} about {a}" for i, a in zip("123", axes)])
    pb.describe("dtheta", "rotor rates relative to the body", "rad/s",
                components=["rotor 1", "rotor 2"])
    pb.describe("u", "rotor torques", "N m", components=["u1 on rotor 1", "u2 on rotor 2"])
    pb.describe("Phi", "the top's equations dΠ/dt = Π × Ω + mgl Γ × e3", "N m",
                components=[f"λ{i} about {a}" for i, a in zip("123", axes)])
    pb.rule("lie_poisson", lie_poisson)
    pb.guesses(rotor_guesses)
    pb.initial(Gamma=Gamma0, Omega=Omega0, theta=theta0, dtheta=dtheta0)
    pb.final(Gamma=GammaT, Omega=OmegaT, theta=thetaT, dtheta=dthetaT)
    pb.horizon(T)
    return pb


# ------------------------------------------------------------------ the Lie-Poisson rule


def _sphere(pb: Problem) -> int:
    """Index of the factor whose states live on S^2 (the action groupoid S^2 x SO(3))."""
    for i, f in enumerate(pb.groupoid.factors):
        if f.manifold == "S^2":
            return i
    raise ConfigError("the lie_poisson rule needs a SphereAction factor (S^2 x SO(3))")


def momentum(pb: Problem) -> tuple[ca.SX, ca.SX]:
    """Body momentum ``M = dl/dOmega`` and the torque ``tau = (drho/dOmega)^T dl/dq``
    (``mgl Gamma x e3`` here), from the problem's Lagrangian."""
    if pb.dynamics is None:
        raise ConfigError("the lie_poisson rule derives the top equations from mechanics()")
    i = _sphere(pb)
    Omega = pb.y[pb.groupoid.velocity_layout.slices[i]]
    l = pb.dynamics.lagrangian
    M = ca.gradient(l, Omega)
    if ca.depends_on(M, pb.q):
        raise ConfigError("the lie_poisson rule needs a momentum dl/dOmega independent of q")
    rho = anchor(pb.groupoid, pb.q, pb.y)
    return M, ca.mtimes(ca.jacobian(rho, Omega).T, ca.gradient(l, pb.q))


def lie_poisson(node: Node) -> ca.SX:
    """Discrete top equations at node k in Lie-Poisson form (seed 004, discrete heavy top):

        (V_k M_k - W_{k-1}^T V_{k-1} M_{k-1}) / h - tau(q_k) = 0,

    ``M_j = dl/dOmega(xi_j)`` the body momentum of interval j, ``W_j = tau(h Omega_j)`` its
    step (``Gamma_{j+1} = W_j^T Gamma_j``) and ``V_j = tau(h Omega_j / 2)`` its half step.
    In the frame of node k, ``V_k M_k`` is the spatial momentum of interval k at its midpoint
    and ``W_{k-1}^T V_{k-1} M_{k-1}`` that of interval k-1: the equation is the centred
    difference of ``d(R Pi)/dt = R tau`` (second order), and the seed's
    ``Pi_{k+1} = W_k^T Pi_k + h^2 mgl Gamma_{k+1} x e`` with the momenta at the midpoints.
    As ``tau . Gamma = 0``, its dot product with Gamma_k reads ``C_k = C_{k-1}`` for
    ``C_j = (V_j M_j) . Gamma_j`` (:func:`discrete_casimir`): the Casimir is conserved
    exactly, whatever the controls. The other constraints, if any, use the midpoint rule.
    """
    pb = node.problem
    i = _sphere(pb)
    mech = pb.dynamics
    vs = pb.groupoid.velocity_layout.slices[i]
    if mech is None or list(mech.unactuated) != list(range(vs.start, vs.stop)):
        raise ConfigError("the lie_poisson rule replaces the top equations: the unactuated "
                          "velocities must be exactly the SO(3) velocity of the S^2 factor")
    M, torque = momentum(pb)
    ret, h = node.retractions[i], node.h
    Mp, Mn = (ca.substitute(M, pb.y, xi) for xi in (node.xi_prev, node.xi_next))
    Op, On = node.xi_prev[vs], node.xi_next[vs]
    matrix = ret.group.matrix  # W = matrix(tau(h xi))
    spatial = ca.mtimes(matrix(ret.tau(h * On / 2)), Mn) - \
        ca.mtimes(matrix(ret.tau(h * Op)).T, ca.mtimes(matrix(ret.tau(h * Op / 2)), Mp))
    others = [node.substitute(c) for n, c in pb.constraints if n != "Phi"]
    return ca.vertcat(spatial / h - node.substitute(torque), *others)


def discrete_casimir(tr: "Transcription", x: np.ndarray, p: np.ndarray) -> np.ndarray:
    """``C_j = (V_j M_j) . Gamma_j`` for the intervals j = -1..N (ghosts at both ends,
    ``xi_{-1} = 2 V_0 - xi_0``, ``Gamma_{-1} = W_{-1} Gamma_0``, ``xi_N = 2 V_N - xi_{N-1}``):
    constant under the Lie-Poisson rule, to rounding."""
    pb = tr.problem
    i = _sphere(pb)
    vs, ss = pb.groupoid.velocity_layout.slices[i], pb.groupoid.state_layout.slices[i]
    ret = tr.scheme.retractions[i]
    d = tr.unpack(x, p)
    h = d["T"] / tr.N
    xi = np.vstack([2 * d["V0"] - d["xi"][0], d["xi"], 2 * d["VN"] - d["xi"][-1]])
    matrix = ret.group.matrix  # W = matrix(tau(h xi))
    W_ghost = matrix(ret.tau(h * xi[0, vs]))
    Gamma = np.vstack([W_ghost @ d["s"][0, ss], d["s"][:, ss]])
    M = ca.Function("M", [pb.y, pb.P], [momentum(pb)[0]])
    return np.array([float(np.dot(matrix(ret.tau(h * xi[j, vs] / 2))
                                  @ M(xi[j], d["P"]).full().ravel(), Gamma[j]))
                     for j in range(tr.N + 2)])


# ------------------------------------------------------------------ multi-start guesses


def rotor_guesses(problem: Problem, ctx: GuessContext) -> list[tuple[str, np.ndarray]]:
    """Gamma along the short great circle, one rotor spun up and back down:
    ``dtheta_i = +-A_i sin(pi t/T)``, with ``A_i = |Pi| / J_i`` the rate at which rotor i
    alone would carry the top's angular momentum (its largest value on the great circle).

    The natural guess (rotors at rest) leads IPOPT to a costly minimum; these four lead to
    the cheapest one we know, at every N (tests/test_heavy_top.py).
    """
    k, rotors = problem.groupoid.by_velocity("dtheta")
    rs = problem.groupoid.velocity_layout.slices[k]
    base = ctx.base
    P = np.concatenate([ctx.params[name] for name in problem.params])
    V0 = np.nan_to_num(np.concatenate([ctx.initial[f.velocity]
                                       for f in problem.groupoid.factors]))
    size = ca.Function("Pi", [problem.y, problem.P], [ca.norm_2(momentum(problem)[0])])
    Pi = max(float(size(y, P)) for y in [V0, *base])
    J = ctx.params["J"]
    t = (np.arange(ctx.N) + 0.5) / ctx.N
    out = []
    for r in range(rotors.algebra_dim):
        for sign, word in ((1.0, "+"), (-1.0, "-")):
            xi = base.copy()
            xi[:, rs.start + r] = sign * Pi / J[r] * np.sin(np.pi * t)
            out.append((f"great circle, rotor {r + 1} spun {word}", xi))
    return out


# ------------------------------------------------------------------ problem files


class Parameters(Strict):
    Ibar: Positive3 = Field(list(IBAR), description="top inertias (with the rotors' "
                            "transverse inertias), gamma_i = Ibar_i + J_i")
    J: Positive2 = Field(list(ROTOR), description="axial inertias of the two rotors")
    mgl: Number = Field(MGL, description="mass x gravity x distance of the centre of mass")


class Initial(Strict):
    Gamma: UnitVector3 = Field(description="initial upward vertical in the body frame")
    Omega: Vector3Free | None = Field(None, description="initial body angular velocity")
    theta: Vector2Free | None = Field(None, description="initial rotor angles")
    dtheta: Vector2Free | None = Field(None, description="initial rotor rates")


class Final(Strict):
    Gamma: UnitVector3 | None = Field(None, description="final vertical (two conditions)")
    Omega: Vector3Free | None = Field(
        None, description="final body angular velocity; leave Omega3 null: the Casimir fixes it")
    theta: Vector2Free | None = Field(None, description="final rotor angles (free if left out)")
    dtheta: Vector2Free | None = Field(None, description="final rotor rates")


def _build(params: BaseModel, initial: BaseModel, final: BaseModel, T: float,
           name: str) -> Problem:
    P, a, b = params, initial, final
    return heavy_top(P.Ibar, P.J, P.mgl, T, a.Gamma, a.Omega, a.theta,  # type: ignore[attr-defined]
                     a.dtheta, b.Gamma, b.Omega, b.dtheta, b.theta, name)  # type: ignore[attr-defined]


register(ModelSpec("heavy_top", "heavy top with two actuated rotors on S^2 x SO(3) x R^2, "
                   "cost 1/2 int |u|^2", Parameters, Initial, Final, _build))
