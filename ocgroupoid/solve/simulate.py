"""Forward simulation with the discrete equations: the variational integrator itself.

At node k the discrete controlled Euler-Lagrange equations of a second-order problem with
mechanics read ``u(q_k, xi_{k-1/2}, xi_{k-1,k}) = u_k`` (actuated) and ``Phi_d = 0``
(unactuated): dim(y) equations for the unknown xi_k, solved by Newton (CasADi rootfinder);
then ``s_{k+1} = step(s_k, tau(h xi_k))``. With zero control this is the implicit-midpoint
Lie-group integrator of the free system: states stay on the group to rounding and quadratic
first integrals (energy, |I Omega|^2 of the rigid body) are conserved.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..errors import ConfigError, SolverError
from ..nlp.schemes import NodeMidpoint


class DiscreteFlow:
    """Step the discrete dynamics of a second-order problem forward in time."""

    def __init__(self, scheme: NodeMidpoint) -> None:
        pb = scheme.problem
        if pb.order != 2 or pb.dynamics is None:
            raise ConfigError("a discrete flow needs a second-order problem with mechanics()")
        if not isinstance(scheme, NodeMidpoint):
            raise ConfigError(f"a discrete flow steps the order2 node rule, not {scheme.name}")
        G = pb.groupoid
        dg, ds = G.algebra_dim, G.state_size
        s, xp, xn, T = ca.SX.sym("s", ds), ca.SX.sym("xp", dg), ca.SX.sym("xn", dg), ca.SX.sym("T")
        u = ca.SX.sym("u", len(pb.controls))
        _, phi, u_expr, _ = scheme.node(s, xp, xn, T, pb.P)
        res = ca.vertcat(u_expr - u, phi)
        fun = ca.Function("node_eq", [xn, s, xp, T, u, pb.P], [res])
        self.solve_node = ca.rootfinder("flow", "newton", fun, {"abstol": 1e-14})
        ghost = ca.Function("first", [xn, s, xp, T, u, pb.P],
                            [ca.substitute(res, xp, 2 * xp - xn)])
        self.solve_first = ca.rootfinder("flow0", "newton", ghost, {"abstol": 1e-14})
        self.step, self.N = scheme.stages.step, scheme.N

    def run(self, s0: np.ndarray, V0: np.ndarray, controls: np.ndarray, T: float,
            params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """States (N+1 x ds) and velocities (N x dy) from s0, V0 and node controls u_0..u_{N-1}.

        ``T`` is the horizon the step is derived from (h = T/N of the stages).
        """
        N = controls.shape[0]
        xi = np.zeros((N, V0.size))
        s = np.zeros((N + 1, s0.size))
        s[0] = s0
        prev = np.asarray(V0, dtype=float)
        for k in range(N):
            try:
                if k == 0:
                    xk = self.solve_first(prev, s[0], prev, T, controls[0], params)
                else:
                    xk = self.solve_node(prev, s[k], prev, T, controls[k], params)
            except RuntimeError as err:
                raise SolverError(f"Newton failed at step {k}: {err}; reduce the step") from None
            prev = np.array(xk).ravel()
            xi[k] = prev
            s[k + 1] = np.array(self.step(s[k], T / self.N * prev)).ravel()
        return s, xi
