"""Structure of the NLP: no idle variables, full-rank constraint Jacobian (LICQ)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import ocgroupoid as og
from ocgroupoid.systems.rigid_body import rigid_body

from .test_api_general import minimum_acceleration, rolling_problem


def rolling() -> og.Problem:
    return rolling_problem(xy=[1.0, 0.5], R=og.so3.from_rotvec([-0.5, 1.0, 0.3]))


def free_end_velocity() -> og.Problem:
    return rigid_body(OmegaT=[0.0, None, None])


@pytest.mark.parametrize("factory", [rigid_body, free_end_velocity, minimum_acceleration,
                                     rolling])
@pytest.mark.parametrize("scheme", og.nlp.SCHEME_NAMES)
def test_every_variable_is_used_and_licq_holds(factory, scheme: str) -> None:
    problem = factory()
    solver = og.compile_problem(problem, N=16, scheme=scheme)
    tr = solver.transcription
    sol = solver.solve(multistart=factory is rolling)
    if scheme in og.nlp.schemes.BASELINES:  # solved, but a quaternion drifts off SO(3)
        failures = sol.diagnostics["verdict"]["failures"]
        assert sol.status == "Solve_Succeeded" and all(
            "off its manifold" in f or "off SO(3)" in f for f in failures), failures
    else:
        assert sol.success, sol.status
    J = np.array(ca.DM(tr.solver.get_function("nlp_jac_g")(sol.x, sol.p)[1]))
    H = np.array(ca.DM(tr.solver.get_function("nlp_hess_l")(sol.x, sol.p, 1.0,
                                                             np.ones(tr.ng))))
    used = (np.abs(J).sum(axis=0) > 0) | (np.abs(H).sum(axis=0) > 0) | (np.abs(H).sum(axis=1) > 0)
    assert used.all(), np.flatnonzero(~used)
    assert np.linalg.matrix_rank(J, tol=1e-9) == tr.ng
