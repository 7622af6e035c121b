"""Lagrangians that read a group state (issue 28): a gravity-gradient potential on SO(3).

``l(R, Omega) = 1/2 Omega . I Omega - k/2 gamma . I gamma`` with ``gamma = R^T e3`` (the
nadir seen from the body; k = 3 n^2 for a circular orbit of rate n, the orbit frame taken as
inertial). Its reduced Euler-Lagrange equations are Euler's with the gravity-gradient torque
``k gamma x I gamma`` — derived here by the mechanics module from l alone and checked
against that closed form; solved with multipliers that satisfy the discrete Euler-Lagrange
equations; and simulated freely, conserving the energy and the angular momentum about the
spatial e3 (the potential's symmetry).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

import ocgroupoid as og

K = 0.8
INERTIA = [1.0, 2.0, 3.0]


def gravity_gradient(control: bool = True) -> og.Problem:
    pb = og.Problem(og.LieGroupFactor(og.SO3, state="R", velocity="Omega"), name="gg")
    I = pb.parameter("inertia", 3, INERTIA)
    k = pb.parameter("k", 1, K)
    Om, R = pb.velocity("Omega"), pb.node_state("R")
    gamma = R.T @ ca.DM([0, 0, 1])
    u = pb.mechanics(0.5 * ca.dot(Om, I * Om) - 0.5 * k * ca.dot(gamma, I * gamma),
                     actuated="Omega", input_matrix=ca.diag(I))
    pb.minimize(0.5 * ca.sumsqr(u))
    pb.initial(R=np.eye(3), Omega=[0, 0, 0])
    pb.final(R=og.so3.from_axis_angle([1, 0, 0], 1.0), Omega=[0, 0, 0])
    pb.horizon(3.0)
    return pb


def test_the_derived_equations_are_euler_with_the_gravity_gradient_torque() -> None:
    pb = gravity_gradient()
    mech = pb.dynamics
    I = np.array(INERTIA)
    rng = np.random.default_rng(3)
    EL = ca.Function("EL", [pb.s, pb.y, pb.dy, pb.P], [mech.EL])
    for _ in range(5):
        s = pb.groupoid.factors[0].sample_state(rng)
        R = pb.groupoid.factors[0].matrix(s)
        w, dw = rng.normal(size=3), rng.normal(size=3)
        gamma = R.T @ [0, 0, 1]
        closed = I * dw + np.cross(w, I * w) - K * np.cross(gamma, I * gamma)
        got = np.array(EL(s, w, dw, pb.parameter_values())).ravel()
        assert np.allclose(got, closed, atol=1e-12), (got, closed)


def test_a_slew_with_the_potential_satisfies_the_discrete_equations() -> None:
    for scheme in ("order2", "order4"):
        sol = og.solve(gravity_gradient(), N=64, scheme=scheme)
        assert sol.success, sol.hint
        assert sol.diagnostics["euler_lagrange_residual_max"] <= 1e-10


def test_free_motion_conserves_energy_and_the_axial_momentum() -> None:
    """Free motion in the potential (no control): the energy 1/2 Omega.I Omega + V(R) and
    e3 . R I Omega are conserved; the variational integrator keeps both bounded at O(h^2)
    (shrinking four-fold when h halves), RK4 to its own accuracy."""
    pb = gravity_gradient()
    start = {"R": og.so3.from_axis_angle([1, 1, 0], 0.7), "Omega": [0.3, -0.2, 0.5]}
    drift = []
    I = np.array(INERTIA)
    for h in (0.02, 0.01):
        sim = og.simulate(pb, h=h, steps=int(round(20 / h)), initial=start)
        for traj in (sim.variational, sim.rk4):
            R = np.array([pb.groupoid.factors[0].matrix(s) for s in traj.states])
            L3 = np.einsum("kij,kj->ki", R, I * traj.velocities)[:, 2]
            assert np.max(np.abs(L3 - L3[0])) <= 1e-3 * (h / 0.01) ** 2
            assert np.max(np.abs(traj.energy - traj.energy[0])) <= 1e-3 * (h / 0.01) ** 2
        drift.append(np.max(np.abs(sim.variational.energy - sim.variational.energy[0])))
    assert drift[0] / drift[1] >= 3.0, drift
