"""Checking a discrete solution without trusting the solver: the replay of its controls through
the continuous problem (:mod:`~ocgroupoid.verify.replay`), the verdict built on it
(:mod:`~ocgroupoid.verify.verdict`), the discrete Euler-Lagrange residuals with the solver's
multipliers and the manifold and boundary checks (:mod:`~ocgroupoid.verify.diagnostics`), the
rank test of the conditions at the solution (:mod:`~ocgroupoid.verify.dependencies`),
Richardson estimates (:mod:`~ocgroupoid.verify.richardson`) and the verification as one
CasADi graph for the exported C (:mod:`~ocgroupoid.verify.graph`)."""
