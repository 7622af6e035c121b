"""Per-step time of closed-loop MPC: our converged loop and RTI step against a rockit loop.

One run each, on the same machine in the same process: so3_rest_to_rest at N = 16, 32, 64
and the free flyer at N = 32, a receding horizon for N samples with inertia x 1.05 and
velocity kicks of 1e-4 after each sample (:func:`ocgroupoid.mpc`). The rockit loop solves the
same rest-to-rest problem (unit quaternion and body rates; multiple shooting with RK4, as
rockit's defaults; |u| bounded as ours) with IPOPT, warm-started from the last solution
shifted by one interval (``set_initial``; rockit passes no multipliers, so IPOPT's
``warm_start_init_point`` only slowed it: measured 30-40 iterations, ~1 s a step), with
``expand`` (SX evaluation), as rockit's MPC examples do;
its plant is its own model. Writes results/bench_mpc.json and bench_mpc.png, prints a table
(median, p99 and max of the warm steps, ms). ``--quick``: so3 at N = 16 only.
"""

from __future__ import annotations

import time
from typing import Any

import casadi as ca
import numpy as np
from _bench import arguments, machine, save
from rich.console import Console
from rich.table import Table

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.mpc.report import percentiles

BOUND = 0.45
CASES = {"so3": ("problems/so3_rest_to_rest.yaml", [f"bounds={{u: [-{BOUND}, {BOUND}]}}"]),
         "free_flyer": ("problems/free_flyer.yaml", [f"bounds={{u: [-{BOUND}, {BOUND}]}}"])}


def quat_mul(a: Any, b: Any) -> Any:
    """Hamilton product of quaternions (w, x, y, z)."""
    return ca.vertcat(a[0] * b[0] - ca.dot(a[1:], b[1:]),
                      a[0] * b[1:] + b[0] * a[1:] + ca.cross(a[1:], b[1:]))


def rotate(q: Any, v: Any) -> Any:
    """R(q) v."""
    return quat_mul(quat_mul(q, ca.vertcat(0, v)), ca.vertcat(q[0], -q[1:]))[1:]


def rockit_loop(problem: og.Problem, name: str, N: int, steps: int) -> list[float]:
    """The seconds of each warm re-solve of a rockit MPC loop (module docstring)."""
    from rockit import MultipleShooting, Ocp

    tr = og.compile(problem, N).transcription
    p = tr.pack()
    T = tr.horizon_of(p)
    P = {k: tr.part(p, "P")[s] for k, s in problem.parameter_slices.items()}
    target = tr.part(p, "end")
    ocp = Ocp(T=T)
    q, w = ocp.state(4), ocp.state(3)
    u = ocp.control(3 if name == "so3" else 6)
    if name == "so3":
        I = ca.DM(P["inertia"])
        ocp.set_der(w, (ca.cross(I * w, w)) / I + u)
        parts = [q, w]
        goal = ca.vertcat(target[:4], 0, 0, 0)
    else:
        J, m = ca.DM(P["J"]), float(P["m"][0])
        pos, v = ocp.state(3), ocp.state(3)
        ocp.set_der(w, (u[:3] - ca.cross(w, J * w)) / J)
        ocp.set_der(v, u[3:] / m - ca.cross(w, v))
        ocp.set_der(pos, rotate(q, v))
        parts = [q, w, pos, v]
        goal = ca.vertcat(target[:4], 0, 0, 0, target[4:7], 0, 0, 0)
    ocp.set_der(q, 0.5 * quat_mul(q, ca.vertcat(0, w)))
    x = ca.vertcat(*parts)
    x0 = ocp.parameter(x.numel())
    ocp.subject_to(ocp.at_t0(x) == x0)
    ocp.subject_to(ocp.at_tf(x) == goal)
    ocp.subject_to(-BOUND <= (u <= BOUND))
    ocp.add_objective(ocp.integral(ca.sumsqr(u)) / 2)
    ocp.method(MultipleShooting(N=N, M=1, intg="rk"))
    ocp.solver("ipopt", {"expand": True, "print_time": False, "ipopt.print_level": 0,
                         "ipopt.sb": "yes", "ipopt.tol": 1e-10})
    state = np.array(ca.vertcat(1, 0, 0, 0, 0, 0, 0, *([] if name == "so3" else [0] * 6))).ravel()
    ocp.set_value(x0, state)
    ocp.set_initial(q, ca.DM([1, 0, 0, 0]))  # a unit quaternion: rockit's zero guess is singular
    try:
        sol = ocp.solve()
    except RuntimeError:  # the cold solve failed: no loop to time (reported as count 0)
        return []
    sim = ocp._method.discrete_system(ocp)
    rng = np.random.default_rng(0)
    seconds = []
    for _ in range(steps - 1):
        _, xs = sol.sample(x, grid="control")
        _, us = sol.sample(u, grid="control")
        state = np.array(sim(x0=state, u=us[0], T=T / N)["xf"]).ravel()
        state[4:7] += rng.normal(0, 1e-4, 3)
        t0 = time.perf_counter()
        ocp.set_value(x0, state)
        shifted, k = np.vstack([xs[1:], xs[-1:]]).T, 0
        for part in parts:  # rockit sets a trajectory one variable at a time
            ocp.set_initial(part, shifted[k:k + part.numel()])
            k += part.numel()
        ocp.set_initial(u, np.vstack([us[1:-1], us[-2:-1]]).T)
        try:
            sol = ocp.solve()
        except RuntimeError:  # a failed warm solve: the last plan goes on (as in our loop)
            pass
        seconds.append(time.perf_counter() - t0)
    return seconds


def ours(problem: og.Problem, N: int, rti: bool, key: str) -> dict[str, Any]:
    """Our loop's warm steps: the step, and the feedback alone."""
    r = og.mpc(problem, N, N, rti=rti, noise=1e-4, mismatch={key: 1.05})
    t = r.timing()
    return {"step": t["step"], "feedback": t["feedback"], "failed_steps": r.failed_steps,
            "iterations_mean": r.summary()["iterations_mean"]}


def main() -> None:
    args = arguments(__doc__.splitlines()[0])
    runs = [("so3", 16)] if args.quick else [("so3", 16), ("so3", 32), ("so3", 64),
                                             ("free_flyer", 32)]
    rows = []
    for name, N in runs:
        path, sets = CASES[name]
        pb = files.build(files.load(path, [f"horizon.N={N}", *sets]))
        key = "inertia" if name == "so3" else "J"
        Console(stderr=True).print(f"{name} N={N} ...")
        row = {"problem": name, "N": N,
               "converged": ours(pb, N, False, key), "rti": ours(pb, N, True, key),
               "rockit": {"step": percentiles(rockit_loop(pb, name, N, N))}}
        rows.append(row)
    table = Table(title="MPC per-step time, ms (median / p99 / max of the warm steps)")
    for col in ("problem", "N", "converged (IPOPT warm)", "RTI step (HPIPM)",
                "RTI feedback", "rockit (IPOPT warm)"):
        table.add_column(col)
    fmt = lambda s: " / ".join(f"{s[k] * 1e3:.2f}" for k in ("median", "p99", "max")) \
        if s["count"] else "cold solve failed"  # noqa: E731
    for r in rows:
        table.add_row(r["problem"], str(r["N"]), fmt(r["converged"]["step"]),
                      fmt(r["rti"]["step"]), fmt(r["rti"]["feedback"]), fmt(r["rockit"]["step"]))
    Console().print(table)
    save(args.out, "bench_mpc", {"machine": machine(), "rows": rows})
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4))
    labels = [f"{r['problem']} N={r['N']}" for r in rows]
    for i, (k, sub) in enumerate((("converged", "step"), ("rti", "step"), ("rti", "feedback"),
                                  ("rockit", "step"))):
        ax.bar(np.arange(len(rows)) + 0.2 * i, [r[k][sub].get("median", np.nan) * 1e3
                                                for r in rows], 0.2,
               label=f"{k} {sub}")
    ax.set_xticks(np.arange(len(rows)) + 0.3, labels)
    ax.set(ylabel="median ms per step", yscale="log", title="MPC step time")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out / "bench_mpc.png", dpi=110)


if __name__ == "__main__":
    main()
