"""The blocks every scheme shares, added to the scheme's own: the terminal cost, the time
weight, the steps of adaptive phases (summing to T), the chart coordinates of every
prescribed final state (3 equations for a rotation, 2 for a point of S^2, one per prescribed
component of R^n) and the user's final conditions."""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..model.problem import Problem
from .assembly import Block, Kind
from .layout import Layout, Masks
from .method import STEP_RANGE
from .schemes.base import Scheme, columns, stage_function


def shared_blocks(pb: Problem, masks: Masks, lay: Layout, sch: Scheme, N: int) -> list[Block]:
    """The shared blocks of ``pb`` on N intervals laid out by the scheme ``sch`` (module
    docstring)."""
    G = pb.groupoid
    dg, nt = G.algebra_dim, G.target_size
    npar = pb.P.numel()
    out = []
    zN, stored = sch.final_state()
    nz = len(zN)
    if pb.terminal is not None:
        y = pb.y if pb.end_velocities else ca.SX.zeros(dg)
        phi = ca.substitute(pb.terminal, ca.vertcat(pb.y, pb.s, pb.q),
                            ca.vertcat(y, pb.s, G.base(pb.s)))
        terminal = ca.Function("terminal", [pb.s, pb.y, pb.P], [phi])
        out.append(Block("terminal", stage_function(
            "terminal", [nz, dg, npar], lambda z, v, par: (terminal(stored(z), v, par),
                                                           ca.SX(0, 1))),
            columns(zN, sch.end_velocity, lay.P, ncols=1), npar, Kind.COST))
    if lay.phases:
        lo, hi = STEP_RANGE
        n = ca.DM(lay.phases)
        M = len(lay.phases)
        mesh = stage_function("mesh", [M, 1], lambda t, T: (ca.SX(1, 1), ca.vertcat(
            ca.dot(n, t) / N - T, t - lo * T, hi * T - t)))
        out.append(Block("mesh", mesh, columns(lay.phase_steps, lay.T, ncols=1), 0,
                         Kind.MESH, ["sum of the steps - T"] +
                         [f"phase {i} step >= {lo} T/N" for i in range(M)] +
                         [f"phase {i} step <= {hi} T/N" for i in range(M)], [""],
                         bounds=(ca.SX(ca.DM.zeros(2 * M + 1)),
                                 ca.SX(ca.vertcat(0, ca.DM.inf(2 * M))))))
    if pb.weights["time"] > 0:
        w = pb.weights["time"]
        out.append(Block("time", stage_function("time", [1], lambda T: (w * T, ca.SX(0, 1))),
                         columns(lay.T, ncols=1), 0 if pb.T_free else 1, Kind.COST))
    rows = np.concatenate(masks.end_state)
    if rows.any():
        keep = np.flatnonzero(rows).tolist()
        chart = sch.stages.chart
        labels = [f"final.{f.state} " + (f"component {j}" if f.componentwise
                                         else f"(chart coordinate {j + 1})")
                  for f, m in zip(G.factors, masks.end_state)
                  for j in np.flatnonzero(m)]
        out.append(Block("final", stage_function(
            "final", [nz, nt], lambda z, tg: (ca.SX(1, 1), chart(stored(z), tg)[keep])),
            columns(zN, lay.end, ncols=1), nt, Kind.FINAL, labels, [""]))
    if pb.final_conditions:
        ends = sch.stages.final_conditions
        labels = [f"final condition {n!r}" for n, c in pb.final_conditions
                  for _ in range(c.numel())]
        out.append(Block("final_conditions", stage_function(
            "final_conditions", [nz, dg, npar],
            lambda z, v, par: (ca.SX(1, 1), ends(stored(z), v, par))),
            columns(zN, sch.end_velocity, lay.P, ncols=1), npar,
            Kind.FINAL_CONDITION, labels, [""]))
    return out

