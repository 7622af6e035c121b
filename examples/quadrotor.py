"""A quadrotor on SE(3) in a few lines: thrust along body z, three body torques, gravity.

Only the reduced Lagrangian (with the gravity potential, which reads the pose) and the force
the controls exert are written; the forced Newton-Euler equations are derived. Four controls
for six velocities: the two lateral equations become constraints (underactuation).
Run: python examples/quadrotor.py
"""

import casadi as ca
import numpy as np

import ocgroupoid as og

pb = og.Problem(og.LieGroupFactor(og.SE3, state="g", velocity="xi"), name="quadrotor")
m, J, grav = pb.parameter("m", 1, 1.0), pb.parameter("J", 3, [0.05, 0.05, 0.09]), 9.81
f, tau = pb.control("f"), pb.control("tau", 3)       # thrust along body z, body torques
w, v = pb.velocity("xi")[:3], pb.velocity("xi")[3:]  # body twist (omega, v)
height = pb.node_state("g")[2, 3]                     # the pose as a 4x4 matrix
pb.mechanics(0.5 * ca.dot(w, J * w) + 0.5 * m * ca.dot(v, v) - m * grav * height,
             force=ca.vertcat(tau, 0, 0, f))          # thrust f e3 on v, tau on omega
pb.minimize((f - m * grav) ** 2 + ca.sumsqr(tau))
pb.bound(f, 0, 20.0, name="f")
pb.bound(tau, -0.5, 0.5, name="tau")
pb.initial(g=np.eye(4), xi=np.zeros(6))
pb.final(g={"rotation": {"rotvec": [0, 0, np.pi / 2]}, "position": [2, 1, 1]}, xi=np.zeros(6))
pb.horizon(4.0)
sol = og.solve(pb, N=64, scheme="order4", multistart=True)
print(f"cost {sol.cost:.6f}, verified: {sol.success}, controls {sol.control_names}")
