"""Ball rolling without slipping on a rotating plate (seed 001, §6.2; PROBLEMS.md §3).

The ball's centre (x, y) moves in the plane, its attitude R in SO(3) turns with the spatial
angular velocity w, ``dR/dt = hat(w) R``. The controls are the velocities v = (dx/dt, dy/dt),
the cost is ``1/2 int |v|^2 dt``, and the non-integrable (vakonomic) rolling constraints are

    dy/dt + r w_x = Omega_p x,    dx/dt - r w_y = -Omega_p y,    w_z = c.

Discrete problem. The groupoid is ``R^2 x R^2 x SO(3) => R^2``: the pair groupoid of the plane
times SO(3) over a point, built as ``Groupoid(Pair(2), LieGroupFactor(side="left"))``. An
element ``(x_k, y_k, x_{k+1}, y_{k+1}, g_{k+1})`` carries the node state ``(x_k, y_k, R_k)`` to
``(x_{k+1}, y_{k+1}, g_{k+1} R_k)``: the spatial (left) convention ``R_{k+1} = g_{k+1} R_k``,
so the attitude reached is ``g_N ... g_1 R_0``. On interval k the discrete Lagrangian and
constraints are the seed's (001, eq. 8)

    L_d = h l(v_k),   phi_d = h psi((x_k + x_{k+1})/2, (y_k + y_{k+1})/2, v_k, w_k),
    v_k = ((x_{k+1} - x_k)/h, (y_{k+1} - y_k)/h),   w_k = tau^{-1}(g_{k+1})/h,

and the retraction tau is the discretisation rule (``discretization.retraction``):
``first_order`` is the seed's read-out ``w = vee(skew(g))/h`` (eq. 8, from exp(h xi) ~ I + h
xi), ``cayley`` (default) and ``exp`` the exact retraction rules ``w = cay^{-1}(g)/h``,
``log(g)/h``. The rows of psi are written as the seed's ``phi^a/h``, so the IPOPT multipliers
of the constraint rows (``Solution.multipliers["Phi"]``, one row per interval) are the seed's
``lambda_k``. The read-out ``vee(skew(g))`` is ``sin(angle)`` times the axis, ``h w (1 -
h^2 |w|^2/6 + ...)``: an odd retraction exact to third order, so, despite its name, the
seed's rule converges at second order like Cayley (measured in tests/test_plate_ball.py and
scripts/bench_plate_ball.py).

Local minima. Rolling turns the ball about horizontal axes only (with c = 0); the vertical
part of the target attitude comes from the holonomy of the path, so the optimal paths bend
and there are several local minima. The best path of the PROBLEMS.md instance makes a small
loop. With ``Omega_p = 0`` the problem is symmetric under reflecting the path in the
perpendicular bisector of its end points and running it backwards (``p(t) -> p_0 + p_T -
M p(T - t)``, M the reflection in the line through the end points; the attitude is
conjugated by the reflection, which keeps the end attitudes of that instance): the best
path, with its loop early, has a mirror image, with its loop late, of exactly equal cost.
The model's multi-start guesses (:func:`bends`) are such loops, to the right and to the
left of the chord, early and late, and arcs to either side, each with the angular velocity
that rolls along it; the two right loops are mirror images of each other and lead IPOPT to
the two mirror minima (see ``Solution.minima``).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
from pydantic import BaseModel, Field

from ..groupoid import Groupoid, LieGroupFactor, Pair
from ..lie import so3
from ..model.problem import GuessContext, Problem
from ..model.values import Number, PositiveNumber, Rotation, Strict, Vector2, Vector2Free
from .registry import ModelSpec, register

TARGET_XY = (1.0, 0.5)
TARGET_R = so3.from_rotvec([-0.5, 1.0, 0.3])
LOOP, ARC = 0.25, 0.5  # radius of the guesses' loops, height of their arcs (x chord length)


def plate_ball(r: float = 1.0, Omega_p: float = 0.0, c: float = 0.0, T: float = 1.0,
               xy0: Any = (0.0, 0.0), R0: Any = np.eye(3), xyT: Any = TARGET_XY,
               RT: Any = TARGET_R, name: str = "plate_ball") -> Problem:
    """The plate-ball problem of PROBLEMS.md §3, or any instance of it.

    Defaults: r = 1, Omega_p = 0, c = 0, T = 1, from (0, 0), R = I to (1, 0.5),
    R = exp(hat(-0.5, 1, 0.3)). None leaves a final value (or one component of xyT) free.
    """
    G = Groupoid(Pair(2, state="xy", velocity="v"),
                 LieGroupFactor(state="R", velocity="w", side="left"))
    pb = Problem(G, name=name, order=1)
    rad = pb.parameter("r", 1, r, "ball radius")
    Om = pb.parameter("Omega_p", 1, Omega_p, "angular velocity of the plate")
    spin = pb.parameter("c", 1, c, "spin of the ball about the vertical")
    xy, v, w = pb.state("xy"), pb.velocity("v"), pb.velocity("w")
    pb.minimize(0.5 * ca.sumsqr(v))
    pb.subject_to(ca.vertcat(v[1] + rad * w[0] - Om * xy[0],  # seed phi^1 / h
                             v[0] - rad * w[1] + Om * xy[1],  # seed phi^2 / h
                             spin - w[2]),  # seed phi^3 / h
                  name="rolling")
    pb.report_controls(v, ["dx", "dy"])
    pb.describe("xy", "position of the ball's centre", "m", components=["x", "y"])
    pb.describe("R", "attitude of the ball", "rad",
                components=["about x", "about y", "about z"])
    pb.describe("v", "velocity of the centre", "m/s", components=["dx/dt", "dy/dt"])
    pb.describe("w", "angular velocity of the ball (spatial)", "rad/s",
                components=["w_x", "w_y", "w_z"])
    pb.describe("u", "velocity of the centre (the controls)", "m/s",
                components=["dx/dt", "dy/dt"])
    pb.describe("rolling", "rolling constraints", ["m/s", "m/s", "m²/s"],  # cost / row
                components=["λ1: dy/dt + r w_x = Ω_p x", "λ2: dx/dt - r w_y = -Ω_p y",
                            "λ3: w_z = c"])
    pb.initial(xy=xy0, R=R0)
    pb.final(xy=xyT, R=RT)
    pb.horizon(T)
    pb.guesses(bends)
    return pb


def rolling_velocity(xy: np.ndarray, v: np.ndarray, r: float, Omega_p: float, c: float
                     ) -> np.ndarray:
    """The angular velocities (n x 3) that roll along velocities v at positions xy (n x 2):
    the rolling constraints solved for w."""
    return np.column_stack([(Omega_p * xy[:, 0] - v[:, 1]) / r,
                            (v[:, 0] + Omega_p * xy[:, 1]) / r, np.full(len(v), c)])


def bends(problem: Problem, ctx: GuessContext) -> list[tuple[str, np.ndarray]]:
    """Multi-start guesses: paths bending right and left (see the module docstring).

    Each path is the chord between the end points plus an offset, in units of the chord
    length d (the ball radius when the ends coincide): a loop of radius LOOP run through in
    the first or the second half of the horizon, or an arc ARC sin(pi t/T) high. v are the
    difference quotients of the path and w rolls along it at the interval midpoints, so every
    guess satisfies the discrete rolling constraints and the final position exactly, whatever
    the rule; IPOPT corrects the attitude.
    """
    N, T = ctx.N, ctx.T
    P = {name: float(v[0]) for name, v in ctx.params.items()}
    start = ctx.initial["xy"]
    end = ctx.final.get("xy", np.full(2, np.nan))
    end = np.where(np.isnan(end), start, end)
    chord = end - start
    dist = float(np.linalg.norm(chord))
    along = chord / dist if dist > 1e-9 else np.array([1.0, 0.0])
    left = np.array([-along[1], along[0]])
    scale = dist if dist > 1e-9 else P["r"]
    t = np.linspace(0.0, 1.0, N + 1)[:, None]
    offsets = []
    for side, name in ((-1, "right"), (1, "left")):
        for t1, when in ((0.0, "early"), (0.5, "late")):
            turn = 2 * np.pi * np.clip((t - t1) / 0.5, 0.0, 1.0)
            offsets.append((f"loop {name}, {when}",
                            LOOP * (-np.sin(turn) * along + side * (1 - np.cos(turn)) * left)))
    for side, name in ((1, "left"), (-1, "right")):
        offsets.append((f"arc {name}", side * ARC * np.sin(np.pi * t) * left))
    out = []
    for label, offset in offsets:
        path = start + t * chord + scale * offset
        v = np.diff(path, axis=0) / (T / N)
        w = rolling_velocity((path[1:] + path[:-1]) / 2, v, P["r"], P["Omega_p"], P["c"])
        out.append((label, np.hstack([v, w])))
    return out


class Parameters(Strict):
    """The ``parameters`` section of a plate_ball problem file."""

    r: PositiveNumber = Field(1.0, description="ball radius (> 0)")
    Omega_p: Number = Field(0.0, description="angular velocity of the plate about the vertical")
    c: Number = Field(0.0, description="spin of the ball about the vertical, w_z = c")


class Initial(Strict):
    """The ``initial`` section: where the ball starts."""

    xy: Vector2 = Field(description="initial position of the ball's centre")
    R: Rotation = Field(description="initial attitude")


class Final(Strict):
    """The ``final`` section: where the ball must end (left out: free)."""

    xy: Vector2Free | None = Field(None, description="final position (null components: free)")
    R: Rotation | None = Field(None, description="final attitude (left out: free)")


def _build(params: BaseModel, initial: BaseModel, final: BaseModel, T: float,
           name: str) -> Problem:
    p: Any = params  # validated by Parameters, Initial and Final
    i: Any = initial
    f: Any = final
    return plate_ball(p.r, p.Omega_p, p.c, T, i.xy, i.R, f.xy, f.R, name)


register(ModelSpec("plate_ball", "ball rolling on a rotating plate, R^2 x R^2 x SO(3) => R^2, "
                   "cost 1/2 int |v|^2", Parameters, Initial, Final, _build))
