"""so3_rest_to_rest against rockit's RK4 multiple shooting, side by side in one run (issue 26).

Both solve ``problems/so3_rest_to_rest.yaml`` (the rigid body's rest-to-rest slew, cost
``1/2 int |u|^2``) on N = 4 ... 256 intervals:

* **ours**: our fastest configuration, ``order6`` with fatrop and compiled evaluation
  (``order6@fatrop+jit``), from the first geodesic guess; its time is the wall time of one
  solve of the built NLP (:func:`~ocgroupoid.bench.timing.timed_solve`: the median of repeated
  solves from the same cold start, each from its guess's start point to the answer read back,
  fatrop's guard, or its helper's round trip, included; the build not timed);
* **rockit**: the same problem written as a rockit user writes it — unit quaternion and body
  rates as states (the model of ``bench_mpc.py``), ``MultipleShooting(N=N, M=1,
  intg="rk")`` (one RK4 step per interval, piecewise-constant controls), IPOPT with
  ``expand`` and the file's ``tol``, the quaternion interpolated as the start; its time is
  the wall time of ``ocp.solve()`` (median, same repeats), and IPOPT's own ``t_wall_total``
  is kept beside it.

Landing accuracy is measured the same way for both, by an integrator that is neither's: each
plan's controls (our control polynomial; rockit's constants) drive the same model through
scipy's DOP853 at rtol 1e-13, and the landing error is the larger of the final attitude's
angle from the target and the final rate's norm. The time at equal landing accuracy at each
decade from 1e-5 to 1e-9 is read from both lines as the project's work-precision bench reads
it (:func:`~ocgroupoid.bench.equal_accuracy.time_at`: log-log interpolation between grids);
the aim is rockit's time / ours >= 5 at every level.

Writes ``bench_rockit.json`` and ``bench_rockit.png`` (time against landing error).
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path
from typing import Any

import casadi as ca
import matplotlib
import numpy as np
from scipy.integrate import solve_ivp
from scipy.interpolate import PPoly

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from bench_mpc import quat_mul, rigid_body  # noqa: E402  (scripts/: the same quaternion model)

from ocgroupoid import files  # noqa: E402
from ocgroupoid.bench.equal_accuracy import time_at  # noqa: E402
from ocgroupoid.bench.methods import parse_methods  # noqa: E402
from ocgroupoid.bench.record import write_summary  # noqa: E402
from ocgroupoid.bench.script import arguments, steps  # noqa: E402
from ocgroupoid.bench.timing import MAX_REPEATS, MIN_SECONDS, Setting, timed_solve  # noqa: E402
from ocgroupoid.solve import compile_problem  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
FILE = ROOT / "problems" / "so3_rest_to_rest.yaml"
NS = (4, 8, 16, 32, 64, 128, 256)  # order6 lands within 1e-7 from N = 8
OURS = "order6@fatrop+jit"
LEVELS = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9)
AIM = 5.0


def landing_error(control: Any, T: float, P: dict[str, Any], q_goal: np.ndarray) -> float:
    """The plan's controls ``control(t)`` driven through DOP853 from rest at the identity
    (the dynamics of :func:`bench_mpc.rigid_body`): the larger of the final attitude's angle
    from ``q_goal`` and the final rate's norm."""
    z, v = ca.SX.sym("z", 7), ca.SX.sym("u", 3)
    f = ca.Function("f", [z, v], [ca.vertcat(*rigid_body("so3", z[:4], z[4:], [], v, P))])

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        return np.array(f(y, np.asarray(control(t)).ravel())).ravel()

    z0 = np.array([1.0, 0, 0, 0, 0, 0, 0])
    end = solve_ivp(rhs, (0.0, T), z0, method="DOP853", rtol=1e-13, atol=1e-14).y[:, -1]
    rel = np.array(quat_mul(inverse(q_goal), ca.DM(end[:4] / np.linalg.norm(end[:4])))).ravel()
    angle = 2.0 * np.arctan2(np.linalg.norm(rel[1:]), abs(rel[0]))
    return float(max(angle, np.linalg.norm(end[4:])))


def inverse(q: np.ndarray) -> ca.DM:
    """The inverse of a unit quaternion (w, x, y, z)."""
    return ca.DM(np.concatenate([[q[0]], -q[1:]]))


def ours(problem: Any, setting: Setting, N: int, T: float, P: dict[str, Any],
         q_goal: np.ndarray) -> dict[str, Any]:
    """Our fastest configuration on N intervals: median solve time, iterations, landing."""
    timed = timed_solve(problem, parse_methods(OURS, ())[0], N, setting, 3)
    sol = timed.solution
    pp = PPoly(np.asarray(sol.control_ppoly["c"]), np.asarray(sol.control_ppoly["x"]))
    return {"N": N, "seconds": timed.median, "iterations": sol.iterations,
            "success": sol.success, "cost": sol.cost,
            "landing_error": landing_error(pp, T, P, q_goal)}


def rockit(N: int, T: float, P: dict[str, Any], q_goal: np.ndarray, tol: float
           ) -> dict[str, Any]:
    """The rockit transcription on N intervals (module docstring): median wall time of
    ``ocp.solve()``, IPOPT's own time and iterations, landing."""
    from rockit import MultipleShooting, Ocp

    ocp = Ocp(T=T)
    q, w = ocp.state(4), ocp.state(3)
    u = ocp.control(3)
    for part, der in zip((q, w), rigid_body("so3", q, w, [], u, P)):
        ocp.set_der(part, der)
    ocp.subject_to(ocp.at_t0(q) == ca.DM([1, 0, 0, 0]))
    ocp.subject_to(ocp.at_t0(w) == 0)
    ocp.subject_to(quat_mul(inverse(q_goal), ocp.at_tf(q))[1:] == 0)
    ocp.subject_to(ocp.at_tf(w) == 0)
    ocp.add_objective(ocp.integral(ca.sumsqr(u)) / 2)
    ocp.method(MultipleShooting(N=N, M=1, intg="rk"))
    ocp.solver("ipopt", {"expand": True, "print_time": False, "record_time": True,
                         "ipopt.print_level": 0,
                         "ipopt.sb": "yes", "ipopt.tol": tol})
    s = np.linspace(0.0, 1.0, N + 1)
    guess = np.outer(1 - s, [1.0, 0, 0, 0]) + np.outer(s, q_goal)
    guess /= np.linalg.norm(guess, axis=1, keepdims=True)

    def cold() -> None:
        ocp.set_initial(q, guess.T)
        ocp.set_initial(w, np.zeros((3, N + 1)))
        ocp.set_initial(u, np.zeros((3, N)))

    cold()
    ocp.solve()  # the first solve builds the solver: not timed
    seconds, ipopt_seconds = [], []
    while len(seconds) < 3 or (sum(seconds) < MIN_SECONDS and len(seconds) < MAX_REPEATS):
        cold()
        t0 = time.perf_counter()
        sol = ocp.solve()
        seconds.append(time.perf_counter() - t0)
        stats = sol.stats
        ipopt_seconds.append(stats["t_wall_total"])
    ts, us = sol.sample(u, grid="control")
    U = np.atleast_2d(us)[:-1]

    def control(t: float) -> np.ndarray:
        return U[min(int(t / (T / N)), N - 1)]

    return {"N": N, "seconds": statistics.median(seconds),
            "ipopt_seconds": statistics.median(ipopt_seconds),
            "iterations": stats["iter_count"], "success": stats["success"],
            "cost": float(sol.value(ocp.objective)),
            "landing_error": landing_error(control, T, P, q_goal)}


def ratios(lines: dict[str, list[dict[str, Any]]]) -> list[dict[str, Any]]:
    """rockit's time over ours at each level of :data:`LEVELS` both lines reach."""
    out = []
    for level in LEVELS:
        a = time_at(lines["ours"], "landing_error", level)
        b = time_at(lines["rockit"], "landing_error", level)
        b_ipopt = time_at([{**r, "seconds": r["ipopt_seconds"]} for r in lines["rockit"]],
                          "landing_error", level)
        out.append({"level": level, "ours_seconds": a and a[0], "rockit_seconds": b and b[0],
                    "ours_upper_bound": bool(a and a[1]),
                    "ratio": (b[0] / a[0]) if a and b and not b[1] else None,
                    "ratio_ipopt_only": (b_ipopt[0] / a[0]) if a and b_ipopt and not b_ipopt[1]
                    else None})
    return out


def chart(lines: dict[str, list[dict[str, Any]]], path: Path) -> None:
    """Time against landing error, both lines, N marked."""
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for name, style in (("ours", "o-"), ("rockit", "s-")):
        rows = lines[name]
        label = OURS if name == "ours" else "rockit RK4 multiple shooting (IPOPT)"
        ax.loglog([r["landing_error"] for r in rows], [r["seconds"] for r in rows], style,
                  label=label)
        for r in rows:
            ax.annotate(f"N={r['N']}", (r["landing_error"], r["seconds"]), fontsize=7,
                        textcoords="offset points", xytext=(4, 2))
    for level in LEVELS:
        ax.axvline(level, color="0.85", lw=0.8, zorder=0)
    ax.invert_xaxis()
    ax.set_xlabel("landing error (DOP853 replay of the plan's controls)")
    ax.set_ylabel("solve time (s)")
    ax.set_title("so3_rest_to_rest: ours against rockit, one run")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def main() -> None:
    args = arguments(__doc__.splitlines()[0], ROOT / "results")
    Ns = (8, 16, 32) if args.quick else NS
    cfg = files.load(FILE)
    problem = files.build(cfg)
    f = cfg.file
    setting = Setting.of(f)
    tr = compile_problem(problem, 8).transcription  # the instance's numbers, as bench_mpc
    p = tr.pack()
    T = tr.horizon_of(p)
    P = {k: ca.DM(tr.part(p, "P")[sl]) for k, sl in problem.parameter_slices.items()}
    q_goal = np.asarray(tr.part(p, "end"), dtype=float)[:4]  # SO(3)'s target: a quaternion
    lines: dict[str, list[dict[str, Any]]] = {"ours": [], "rockit": []}
    with steps(2 * len(Ns)) as step:
        for N in Ns:
            step(f"ours N={N}")
            lines["ours"].append(ours(problem, setting, N, T, P, q_goal))
            step(f"rockit N={N}")
            lines["rockit"].append(rockit(N, T, P, q_goal, float(setting.ipopt.get("tol", 1e-8))))
    table = ratios(lines)
    for name, rows in lines.items():
        for r in rows:
            print(f"{name:7s} N={r['N']:4d}  {1e3 * r['seconds']:9.2f} ms  "
                  f"it={r['iterations']:3d}  landing={r['landing_error']:.2e}  "
                  f"cost={r['cost']:.12f}")
    for r in table:
        ratio = "-" if r["ratio"] is None else f"{r['ratio']:.1f}x"
        only = "-" if r["ratio_ipopt_only"] is None else f"{r['ratio_ipopt_only']:.1f}x"
        print(f"landing {r['level']:.0e}: rockit/ours {ratio} (IPOPT time alone: {only})")
    args.out.mkdir(parents=True, exist_ok=True)
    write_summary(args.out / "bench_rockit.json", {"ours_method": OURS, "lines": lines,
                                                   "equal_landing": table, "aim": AIM})
    chart(lines, args.out / "bench_rockit.png")


if __name__ == "__main__":
    main()
