"""The variational integrator: the discrete controlled Euler-Lagrange equations stepped forward.

At node k the discrete controlled Euler-Lagrange equations of a second-order problem with
mechanics (the ``order2`` node stage, :class:`~ocgroupoid.nlp.schemes.NodeMidpoint`, seed 000
eq. 27-29) read

    u(q_k, xi_{k-1/2}, xi_{k-1,k}) = u_k   (actuated),      Phi_d = 0   (unactuated):

dim(y) equations for the unknown xi_k, solved by Newton (a CasADi ``rootfinder`` started from
xi_{k-1}); then ``s_{k+1} = step(s_k, tau(h xi_k))``. The first node uses the ghost
``xi_{-1} = 2 V_0 - xi_0``, so that the node velocities ``y_k = (xi_{k-1} + xi_k)/2`` start
at V_0. One step is a CasADi Function run by ``Function.mapaccum`` in chunks of
:data:`CHUNK` steps (:func:`accumulate`, shared with the RK4 comparison of
:mod:`~ocgroupoid.simulation.simulate`); a failed Newton solve is reported after its chunk.
"""

from __future__ import annotations

from typing import Any, Callable, Iterator

import casadi as ca
import numpy as np

from ..errors import ConfigError, SolverError
from ..model.problem import Problem
from ..nlp.schemes import NodeMidpoint

#: steps per compiled call: failures and progress are checked between calls
CHUNK = 10_000
#: a node equation left above this (max norm) after Newton is a failed step
RESIDUAL_TOL = 1e-8
#: Newton's options: from the start xi_{k-1}, O(h) from the root, it reaches rounding in
#: about 4 iterations; a step criterion above rounding (CasADi's default 1e-12) would stop it
#: early and let the invariants drift by ~1e-14 per step
NEWTON = {"abstol": 1e-14, "abstolStep": 1e-16, "max_iter": 10, "line_search": False,
          "error_on_fail": False}

Advance = Callable[[int], None]


def _quiet(steps: int) -> None:
    """A progress callback that shows nothing."""


def check_mechanics(problem: Problem) -> None:
    """Refuse a problem whose discrete Euler-Lagrange equations cannot be stepped forward."""
    if problem.order != 2 or problem.dynamics is None:
        what = "a first-order problem" if problem.order != 2 else "a problem without mechanics()"
        raise ConfigError(f"{problem.name} is {what}: a forward simulation steps the discrete "
                          "Euler-Lagrange equations of a second-order problem with mechanics() "
                          "(Problem(..., order=2) and pb.mechanics(lagrangian, actuated=...))")
    if problem.cost is None:
        raise ConfigError(f"{problem.name} has no cost: the simulation reuses the order2 node "
                          "stage, which carries one; call minimize(...) (any running cost: it "
                          "does not enter the simulation)")


class DiscreteFlow:
    """Step the discrete Euler-Lagrange equations of a second-order problem forward in time
    (module docstring), with the node stage of ``scheme`` (its step is ``h = T/N``)."""

    def __init__(self, scheme: NodeMidpoint) -> None:
        pb = scheme.problem
        check_mechanics(pb)
        if not isinstance(scheme, NodeMidpoint):
            raise ConfigError(f"a discrete flow steps the order2 node rule, not {scheme.name}")
        G = pb.groupoid
        dg, ds, nu = G.algebra_dim, G.state_size, len(pb.controls)
        s, xp, xn, T = ca.SX.sym("s", ds), ca.SX.sym("xp", dg), ca.SX.sym("xn", dg), ca.SX.sym("T")
        u = ca.SX.sym("u", nu)
        if scheme.stages.n_u:  # controls of their own: the node equations EL - F(u) = 0
            res = scheme.node(s, xp, xn, u, T, pb.P)[1]
        else:  # recovered controls: u_k(xi) = u, and the unactuated equations
            _, phi, u_expr, _ = scheme.node(s, xp, xn, ca.SX(0, 1), T, pb.P)
            res = ca.vertcat(u_expr - u, phi)
        if res.numel() != dg:
            raise ConfigError(f"the node equations of {pb.name} are {res.numel()} (controls "
                              f"{nu}, constraints {phi.numel()}) for {dg} velocities: a "
                              "simulation needs exactly as many equations as velocities; drop "
                              "constraints that are not the unactuated equations")
        args = [xn, s, xp, T, u, pb.P]
        #: ``residual(xi_k, s_k, xi_{k-1}, T, u_k, P)``: the node equations
        self.residual = ca.Function("node_eq", args, [res])
        self.solve_node = ca.rootfinder("node_solve", "newton", self.residual, NEWTON)
        #: the same at node 0, with the ghost ``xi_{-1} = 2 V_0 - xi_0`` (xi_prev = V_0)
        self.ghost_residual = ca.Function("node0_eq", args,
                                          [ca.substitute(res, xp, 2 * xp - xn)])
        self.solve_first = ca.rootfinder("node0_solve", "newton", self.ghost_residual, NEWTON)
        self.step, self.N, self.problem = scheme.stages.step, scheme.N, pb
        self.one_step = self._one_step(ds, dg, nu)
        self._maps: dict[int, ca.Function] = {}

    def _one_step(self, ds: int, dg: int, nu: int) -> ca.Function:
        """``([s_k; xi_{k-1}], u_k, T, P) -> ([s_{k+1}; xi_k], |residual|_inf)``."""
        s, xp = ca.MX.sym("s", ds), ca.MX.sym("xi_prev", dg)
        u, T, P = ca.MX.sym("u", nu), ca.MX.sym("T"), ca.MX.sym("P", self.problem.P.numel())
        xi = self.solve_node(xp, s, xp, T, u, P)
        r = ca.norm_inf(self.residual(xi, s, xp, T, u, P))
        return ca.Function("flow_step", [ca.vertcat(s, xp), u, T, P],
                           [ca.vertcat(self.step(s, T / self.N * xi), xi), r])

    def run(self, s0: np.ndarray, V0: np.ndarray, controls: np.ndarray, T: float,
            params: np.ndarray, advance: Advance = _quiet) -> tuple[np.ndarray, np.ndarray]:
        """States ``s_0..s_n`` (n+1 x ds) and velocities ``xi_0..xi_{n-1}`` (n x dy) from
        s0, V0 and the node controls ``u_0..u_{n-1}`` (n rows). ``T`` is the horizon the step
        is derived from (``h = T/N`` of the scheme); ``advance(m)`` hears every m steps done.
        """
        ds = s0.size
        V0 = np.asarray(V0, dtype=float)
        xi0 = np.array(self.solve_first(V0, s0, V0, T, controls[0], params)).ravel()
        r0 = float(ca.norm_inf(self.ghost_residual(xi0, s0, V0, T, controls[0], params)))
        self._check(0, r0, T)
        z = np.concatenate([np.array(self.step(s0, T / self.N * xi0)).ravel(), xi0])
        out = [z[:, None]]
        advance(1)
        for k, Z, (r,) in accumulate(self._maps, self.one_step, z, [controls[1:].T],
                                     [T, params], advance, first=1):
            r = r.ravel()
            bad = np.flatnonzero(~(r <= RESIDUAL_TOL))
            if bad.size:
                self._check(k + int(bad[0]), float(r[bad[0]]), T)
            out.append(Z)
        Z = np.hstack(out)
        return np.vstack([s0, Z[:ds].T]), Z[ds:].T

    def _check(self, k: int, residual: float, T: float) -> None:
        """A SolverError naming node k when its equations were not solved."""
        if residual <= RESIDUAL_TOL:
            return
        h = T / self.N
        raise SolverError(
            f"{self.problem.name}: Newton did not solve the discrete Euler-Lagrange equations "
            f"at node {k} (t = {k * h:.6g}): residual {residual:.3g} > {RESIDUAL_TOL:g}. The "
            f"step h = {h:.6g} is too large for this motion: decrease h (e.g. h/2) and take "
            "more steps")


def accumulate(cache: dict[int, ca.Function], step: ca.Function, z0: np.ndarray,
               per_step: list[np.ndarray], fixed: list[Any], advance: Advance,
               first: int = 0) -> Iterator[tuple[int, np.ndarray, list[np.ndarray]]]:
    """Run ``z_{k+1}, *out_k = step(z_k, *per_step[:, k], *fixed)`` over the columns of
    ``per_step``, :data:`CHUNK` steps per call of ``step.mapaccum`` (built once per chunk
    length, kept in ``cache``). Yields, per chunk, the index of its first step (counted from
    ``first``), the states reached (columns) and the other outputs of ``step`` (columns)."""
    n = per_step[0].shape[1]
    z = z0
    for start in range(0, n, CHUNK):
        m = min(CHUNK, n - start)
        if m not in cache:
            cache[m] = step.mapaccum(m)
        out = cache[m](z, *[c[:, start:start + m] for c in per_step], *fixed)
        Z, *rest = (np.array(a) for a in (out if isinstance(out, (list, tuple)) else [out]))
        z = Z[:, -1]
        advance(m)
        yield first + start, Z, rest
