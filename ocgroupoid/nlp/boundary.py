"""Over-determined boundary conditions, found before IPOPT runs.

The final conditions of a problem are equations on the final node ``(s_N, y_N)``:

* the chart coordinates of every prescribed final state (``state_dim`` equations: 2 for a
  point of S^2, 3 for a rotation, one per prescribed component of R^n),
* every prescribed final velocity component,
* the user's final conditions (:meth:`Problem.final_condition`), and, implicitly,
* every conserved quantity (:meth:`Problem.conserved`) whose initial value the initial
  conditions fix: ``C(q_N, y_N) = C(q_0, y_0)`` holds whatever the controls do.

When the Jacobian of these equations with respect to the final node (states moved along the
admissible variations ``eta``, velocities freely) has dependent rows, LICQ fails at every
feasible point and the conditions are either redundant or contradictory: the problem is
over-determined. Example (PROBLEMS.md §2): with ``Gamma(T)``, ``Omega_1,2(T)`` and
``dtheta(T)`` prescribed, the Casimir ``Pi . Gamma`` fixes ``Omega_3(T)``; prescribing it too
is one condition too many. The test runs at the prescribed final values with the free
components drawn at random (a dependency that holds there holds generically) and names the
dependent condition and the conditions it depends on.

A quantity declared conserved is checked first: ``dC/dt = dC/dq rho(q, y) + dC/dy dy`` must
vanish wherever the constraints ``Phi(q, y, dy) = 0`` hold, i.e. be a combination
``mu(q, y) . Phi``, at random node states reached from the initial ones.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..errors import BoundaryError, ConfigError
from ..lie.retraction import Retraction
from ..model.mechanics import anchor
from ..model.problem import Problem
from .layout import Layout, Masks
from .stages import Stages

RANK_TOL = 1e-8  # singular values below RANK_TOL * (largest, at least 1) count as zero
SAMPLES = 4  # random states at which a declared conservation law is checked


@dataclass(frozen=True)
class Row:
    """One final equation: its label, the condition it belongs to, whether the user wrote it
    (conserved quantities are implied, never blamed) and how to remove it."""

    label: str
    group: str
    written: bool
    fix: str


class FinalConditions:
    """The final equations of a transcription and their rank test (module docstring)."""

    def __init__(self, problem: Problem, masks: Masks, layout: Layout, stages: Stages,
                 seed: int = 0) -> None:
        pb, G, m = problem, problem.groupoid, masks
        self.problem, self.masks, self.layout, self.stages = problem, masks, layout, stages
        self.seed = seed
        self.laws_checked = False  # declared conservation laws: a property of the model
        #: the last p whose final conditions passed: a solve again with the same values
        #: (a repeat, a warm start) skips the rank test, 1 of a so3 solve's 10 ms at N = 8
        self.passed: bytes | None = None
        ds, dg, nt = G.state_size, G.algebra_dim, G.target_size
        s, v = ca.SX.sym("s", ds), ca.SX.sym("v", dg)
        target = ca.SX.sym("target", nt)
        self.base = ca.Function("base", [s], [G.base(s)])
        self.rates = {name: _conservation(pb, C) for name, C in pb.invariants}
        q = G.base(s)
        y = v if pb.end_velocities else ca.SX.zeros(dg)
        at_node = (ca.vertcat(pb.q, pb.s, pb.y), ca.vertcat(q, s, y))
        rows: list[ca.SX] = []
        self.rows: list[Row] = []
        for name, C in pb.invariants:
            if self._fixed_initially(C):
                rows.append(ca.substitute(C, *at_node))
                self.rows += [Row(f"conserved quantity {name!r}", name, False, "")] * C.numel()
        chart = stages.chart(s, target)
        k = 0
        for f, mask in zip(G.factors, m.end_state):
            for j in np.flatnonzero(mask):
                rows.append(chart[k + int(j)])
                if f.componentwise:
                    label, fix = f"final.{f.state}[{j}]", f"leave final.{f.state}[{j}] free (null)"
                else:
                    label, fix = f"final.{f.state}", f"leave final.{f.state} free"
                self.rows.append(Row(label, f"final.{f.state}", True, fix))
            k += f.state_dim
        if pb.end_velocities:
            for f, vs in zip(G.factors, G.velocity_layout.slices):
                for j in np.flatnonzero(m.end_velocity[vs]):
                    label = f"final.{f.velocity}[{j}]"
                    rows.append(v[vs.start + int(j)])
                    self.rows.append(Row(label, f"final.{f.velocity}", True,
                                         f"leave {label} free (null)"))
        for name, g in pb.final_conditions:
            rows.append(ca.substitute(g, *at_node))
            self.rows += [Row(f"final condition {name!r}", name, True,
                              f"drop final condition {name!r}")] * g.numel()
        eta = ca.SX.sym("eta", dg)
        moved = ca.vertcat(*[f.variation(s[ss], eta[vs]) for f, ss, vs in
                             zip(G.factors, G.state_layout.slices, G.velocity_layout.slices)])
        R = ca.vertcat(*rows) if rows else ca.SX(0, 1)
        J = ca.horzcat(ca.mtimes(ca.jacobian(R, s), ca.jacobian(moved, eta)),
                       ca.jacobian(R, v))
        self.jacobian = ca.Function("final_jacobian", [s, v, target, pb.P], [J])
        self.velocity_columns = set(range(dg, 2 * dg))
        self.state_columns = [(f, set(range(vs.start, vs.stop))) for f, vs in
                              zip(G.factors, G.velocity_layout.slices)]

    def _fixed_initially(self, C: ca.SX) -> bool:
        """Whether every q and y component C depends on is prescribed at t = 0."""
        pb, G, m = self.problem, self.problem.groupoid, self.masks
        given_q = [np.ones(f.base_size, bool) if not f.componentwise else mask
                   for f, mask in zip(G.factors, m.start_state)]
        given_y = m.start_velocity if pb.end_velocities else np.zeros(G.algebra_dim, bool)
        given = np.concatenate([*given_q, given_y])
        used = np.array(ca.which_depends(C, ca.vertcat(pb.q, pb.y), 1, False), dtype=bool)
        return bool(np.all(given[used]))

    def node(self, p: np.ndarray, rng: np.random.Generator, prescribed: bool
             ) -> tuple[np.ndarray, np.ndarray]:
        """A node ``(s, y)`` on the manifolds: random (states reached from the initial ones by
        random steps), with the prescribed final values of p where ``prescribed``."""
        G, m, lay = self.problem.groupoid, self.masks, self.layout.p_slices
        start, end = p[lay["start"]], p[lay["end"]]
        parts = []
        for f, r, ts, mask in zip(G.factors, self.stages.retractions, G.target_layout.slices,
                                  m.end_state):
            s0 = np.asarray(f.state_of_target(start[ts]), dtype=float)
            s = np.asarray(f.step(s0, r, _inside(r, rng.normal(size=f.algebra_dim))),
                           dtype=float).ravel()
            if prescribed and mask.any():
                goal = np.asarray(f.state_of_target(end[ts]), dtype=float)
                s = np.where(mask, goal, s) if f.componentwise else goal
            parts.append(s)
        VN = p[lay["VN"]]
        v = rng.normal(size=VN.size)
        if prescribed:
            v = np.where(m.end_velocity, VN, v)
        return np.concatenate(parts), v

    def check(self, p: np.ndarray) -> None:
        """Raise ConfigError for a false conservation law (tested at the first p only: the
        law holds for every instance or for none), BoundaryError naming the first dependent
        final condition (tested at every p but the last that passed: it depends on the prescribed
        values)."""
        if not self.laws_checked:
            rng = np.random.default_rng(self.seed)
            for name, C in self.problem.invariants:
                self._check_conserved(name, C, p, rng)
            self.laws_checked = True
        key = np.asarray(p, dtype=float).tobytes()
        if not self.rows or key == self.passed:
            return
        s, v = self.node(p, np.random.default_rng(self.seed + 1), prescribed=True)
        lay = self.layout.p_slices
        J = np.array(self.jacobian(s, v, p[lay["end"]], p[lay["P"]]))
        scale = max(1.0, float(np.max(np.abs(J))))
        kept: list[int] = []
        for i, row in enumerate(self.rows):
            if _rank(J[[*kept, i]], scale) > len(kept):
                kept.append(i)
            elif row.written:
                raise BoundaryError(self._message(i, J, kept, scale))
        self.passed = key

    def _check_conserved(self, name: str, C: ca.SX, p: np.ndarray,
                         rng: np.random.Generator) -> None:
        """``dC/dt = c0 + c . dy`` must equal ``mu . (A dy + b)``, the constraints linearised
        in dy, for some mu: tested by least squares at random nodes."""
        P = p[self.layout.p_slices["P"]]
        for _ in range(SAMPLES):
            s, y = self.node(p, rng, prescribed=False)
            q = np.array(self.base(s)).ravel()
            c, c0, A, b = (np.array(M) for M in self.rates[name](q, s, y, P))
            lhs, rhs = np.hstack([A, b]), np.hstack([c, c0])
            mu = np.linalg.lstsq(lhs.T, rhs.T, rcond=None)[0] if lhs.size else \
                np.zeros((0, rhs.shape[0]))
            miss = float(np.max(np.abs(rhs - mu.T @ lhs)))
            if miss > RANK_TOL * max(1.0, float(np.max(np.abs(rhs)))):
                raise ConfigError(
                    f"conserved quantity {name!r} is not conserved by the dynamics: its rate "
                    f"is no combination of the constraints (off by {miss:.3g} at q = "
                    f"{np.round(q, 3).tolist()}, y = {np.round(y, 3).tolist()}); declare "
                    "only quantities that stay constant for every control, such as a Casimir"
                )

    def _message(self, i: int, J: np.ndarray, kept: list[int], scale: float) -> str:
        row = self.rows[i]
        group = [k for k, r in enumerate(self.rows) if r.group == row.group and r.written]
        own = _rank(J[group], scale)
        if own < len(group):
            return self._too_many(row, group, own, J, scale)
        alpha = np.linalg.lstsq(J[kept].T, J[i], rcond=None)[0] if kept else np.zeros(0)
        big = np.abs(alpha) > RANK_TOL * max(1.0, float(np.abs(alpha).max(initial=0.0)))
        names = list(dict.fromkeys(self.rows[kept[k]].label for k in np.flatnonzero(big)))
        why = " (conserved for every control: its final value is its initial value, which " \
              "the initial conditions fix)" if any(n.startswith("conserved") for n in names) \
            else ""
        return (f"over-determined final conditions: {row.label} is already fixed by "
                f"{' and '.join(names) or 'nothing a solution could change'}{why}; "
                f"prescribing it too makes it redundant or contradictory (LICQ fails): "
                f"{row.fix}")

    def _too_many(self, row: Row, group: list[int], rank: int, J: np.ndarray,
                  scale: float) -> str:
        """A condition with more equations than independent ones (Gamma componentwise)."""
        cols = set(np.flatnonzero(np.max(np.abs(J[group]), axis=0) > RANK_TOL * scale).tolist())
        states = [f for f, c in self.state_columns if c & cols]
        text = (f"over-determined final conditions: {row.label} imposes {len(group)} "
                f"equations, of which only {rank} are independent")
        if len(states) == 1 and not cols & self.velocity_columns:
            f = states[0]
            text += (f": {f.state}(T) on {f.manifold} is {_count(f.state_dim)} conditions, "
                     f"not {_count(len(group))}; prescribe final.{f.state} instead (imposed in "
                     f"{f.state_dim} chart coordinates)")
        return text + f", or {row.fix}"


def _conservation(pb: "Problem", C: ca.SX) -> ca.Function:
    """``(c, c0, A, b)``: ``dC/dt = c0 + c z`` and the constraints ``Phi = b + A z`` in the
    unknowns ``z = (dy, u)`` (u: controls declared as variables), at a node ``(q, s, y)``."""
    phi = ca.vertcat(*[c for _, c in pb.constraints]) if pb.constraints else ca.SX(0, 1)
    rate = ca.mtimes(ca.jacobian(C, pb.y), pb.dy)
    if pb.q.numel():
        rate += ca.mtimes(ca.jacobian(C, pb.q), anchor(pb.groupoid, pb.q, pb.y))
    z = ca.vertcat(pb.dy, pb.U)
    zero = ca.DM.zeros(z.numel())
    return ca.Function("conservation", [pb.q, pb.s, pb.y, pb.P],
                       [ca.jacobian(rate, z), ca.substitute(rate, z, zero),
                        ca.jacobian(phi, z), ca.substitute(phi, z, zero)])


def _rank(M: np.ndarray, scale: float) -> int:
    if M.size == 0:
        return 0
    return int(np.sum(np.linalg.svd(M, compute_uv=False) > RANK_TOL * scale))


def _count(n: int) -> str:
    return {1: "one", 2: "two", 3: "three", 4: "four"}.get(n, str(n))


def _inside(ret: Retraction, a: np.ndarray) -> np.ndarray:
    """The random step ``a`` shrunk into the retraction's domain: a turn of at most half its
    :attr:`~ocgroupoid.lie.retraction.Retraction.step_limit` (the first-order rule is
    undefined from |a| = 1, Cayley singular at pi)."""
    n, most = float(ret.step_norm(a)), 0.5 * ret.step_limit
    return a * (most / n) if n > most else a
