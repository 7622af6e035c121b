"""The Dubins car of problems/dubins_car.yaml, written in Python: the shortest path from the
origin to (4, 4) heading north, with unit speed, no sideslip and |omega| <= 1.

A kinematic problem: the velocities are the controls, so it is first order (order=1); the
speed and the no-sideslip condition are equality constraints, the turn rate a bound.
Run: python examples/dubins_car.py
"""

import numpy as np

import ocgroupoid as og

pb = og.Problem(og.LieGroupFactor(og.SE2, state="g", velocity="xi"), name="dubins_car", order=1)
xi = pb.velocity("xi")                                # (turn rate, forward, sideways)
pb.subject_to(xi[1] - 1, name="speed")                # unit forward speed
pb.subject_to(xi[2], name="no_sideslip")              # no velocity across the car
pb.bound(xi[0], -1, 1, name="turn_rate")              # turning radius 1
pb.initial(g={"angle": 0.0, "position": [0.0, 0.0]})
pb.final(g={"angle": np.pi / 2, "position": [4.0, 4.0]})
pb.horizon(8.0, free=True, T_min=1.0, T_max=30.0)     # T a decision variable (8: its guess)
pb.minimize_time()
sol = og.solve(pb, N=64, scheme="order4", multistart=True)
print(f"length {sol.T:.6f} (Dubins: LSL, 5.813446), verified: {sol.success}")
