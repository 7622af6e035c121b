"""Per-step time of closed-loop MPC: our converged loop and RTI step against a rockit loop.

The converged loop runs twice: in Python and in exported C (:func:`in_c`: ``DIR/mpc``, the
same loop on the same generated arithmetic; its step time is the shift, the warm re-solve,
the read-out and the bound check), and so does the RTI loop (C: ``DIR/mpc --rti``, the
projected Hessian as Python's; its step is the shift, the prediction, the linearisation and
the projection, HPIPM's QP, the step, the read-out and the bound check). The floor of a C RTI
step: its QP alone (the driver's ``qp`` timing).

One run each, on the same machine in the same process: so3_rest_to_rest at N = 16, 32, 64
and the free flyer at N = 32, |u_i| <= 0.45, a receding horizon for N samples with the
inertia x 1.05 in the plant and velocity kicks of 1e-4 after each sample
(:func:`ocgroupoid.mpc`).

The rockit loop (:func:`rockit_loop`) solves the same problem: the rigid body with its
attitude as a unit quaternion and its body rates (the free flyer: with its position and body
velocity), the same Euler (Newton-Euler) equations, the same cost 1/2 int |u|^2 dt, the same
bounds, the same target, N and T; multiple shooting with one RK4 step per interval (rockit's
``MultipleShooting(N, M=1, intg="rk")``), IPOPT with ``expand`` and our tolerance (1e-10).
The terminal attitude is imposed as the vector part of ``q_target^* q(T)``: 3 rows, as
the four components of a unit quaternion are not independent (with four rows the Jacobian
is nearly rank deficient: only RK4's error moves the norm of q(T)); the cold solve starts
from the quaternion interpolated to the target (an earlier version, with four rows and the
identity as guess, failed its cold solve in 3 of the 4 cases). A warm step then gets the
measured state and the last solution shifted by one interval (its last point repeated) and
re-solves: a primal warm start, as rockit passes no multipliers. It runs two ways, each
with the same plant and kicks:

* ``function``: through ``ocp.to_function`` with the initial state and the initial guesses
  of the states and controls as inputs — rockit's way to repeat solves
  (``examples/repeated_solve.py``; its ``mpc_example.py`` notes that ``sol.sample``,
  ``set_value`` and ``solve`` cost more than the optimisation). The timed step is the call.
* ``examples``: as its MPC examples do (``examples/motion_planning_MPC.py``): ``set_value``
  of the initial state, ``set_initial`` of every state and the control, ``solve()``, then
  ``sol.sample``; all of it timed.

The plant is the same model with the same mismatch, integrated by RK4 with
:data:`SUBSTEPS` substeps per sample. IPOPT runs with ``error_on_fail``: a step that does not
converge raises and counts as failed (the last plan goes on).

Writes results/bench_mpc.json (with the statuses of our steps) and bench_mpc.png, prints a
table (median, p99 and max of the warm steps, ms; failed steps; our mean iterations; rockit's
are not reported through ``to_function``). ``--quick``: so3 at N = 16 only.
"""

from __future__ import annotations

import time
from collections import Counter
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
from rich.console import Console
from rich.table import Table

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.bench.record import write_summary
from ocgroupoid.bench.script import arguments
from ocgroupoid.export import export_c
from ocgroupoid.mpc.report import percentiles

BOUND = 0.45
CASES = {"so3": ("problems/so3_rest_to_rest.yaml", [f"bounds={{u: [-{BOUND}, {BOUND}]}}"]),
         "free_flyer": ("problems/free_flyer.yaml", [f"bounds={{u: [-{BOUND}, {BOUND}]}}"])}
NOISE, MISMATCH = 1e-4, 1.05
ROOT = Path(__file__).resolve().parents[1]
#: RK4 substeps per sample of the rockit loop's plant
SUBSTEPS = 8


def quat_mul(a: Any, b: Any) -> Any:
    """Hamilton product of quaternions (w, x, y, z)."""
    return ca.vertcat(a[0] * b[0] - ca.dot(a[1:], b[1:]),
                      a[0] * b[1:] + b[0] * a[1:] + ca.cross(a[1:], b[1:]))


def rotate(q: Any, v: Any) -> Any:
    """R(q) v."""
    return quat_mul(quat_mul(q, ca.vertcat(0, v)), ca.vertcat(q[0], -q[1:]))[1:]


def rigid_body(name: str, q: Any, w: Any, rest: list[Any], u: Any, P: dict[str, Any]
               ) -> list[Any]:
    """The time derivatives of ``[q, w, *rest]`` (so3: rest empty; the free flyer: position
    and body velocity) under the control u with the parameters P."""
    dq = 0.5 * quat_mul(q, ca.vertcat(0, w))
    if name == "so3":
        I = P["inertia"]
        return [dq, ca.cross(I * w, w) / I + u]
    J, m = P["J"], P["m"][0]
    pos, v = rest
    return [dq, (u[:3] - ca.cross(w, J * w)) / J, rotate(q, v), u[3:] / m - ca.cross(w, v)]


def rockit_loop(problem: og.Problem, name: str, N: int, steps: int, key: str
                ) -> dict[str, Any]:
    """The warm steps of a rockit MPC loop of the same problem (module docstring), run twice:
    through ``ocp.to_function`` (``"function"``) and as rockit's MPC examples do
    (``"examples"``); the seconds of each step and the failed steps."""
    from rockit import MultipleShooting, Ocp

    tr = og.compile_problem(problem, N).transcription
    p = tr.pack()
    T = tr.horizon_of(p)
    P = {k: ca.DM(tr.part(p, "P")[s]) for k, s in problem.parameter_slices.items()}
    target = np.asarray(tr.part(p, "end"), dtype=float)
    ocp = Ocp(T=T)
    q, w = ocp.state(4), ocp.state(3)
    rest = [] if name == "so3" else [ocp.state(3), ocp.state(3)]
    u = ocp.control(3 if name == "so3" else 6)
    parts = [q, w, *rest]
    for part, der in zip(parts, rigid_body(name, q, w, rest, u, P)):
        ocp.set_der(part, der)
    x = ca.vertcat(*parts)
    x0 = ocp.parameter(x.numel())
    ocp.subject_to(ocp.at_t0(x) == x0)
    q_goal = ca.DM(target[:4])
    ocp.subject_to(quat_mul(ca.vertcat(q_goal[0], -q_goal[1:]), ocp.at_tf(q))[1:] == 0)
    ocp.subject_to(ocp.at_tf(w) == 0)
    if rest:
        ocp.subject_to(ocp.at_tf(rest[0]) == ca.DM(target[4:7]))
        ocp.subject_to(ocp.at_tf(rest[1]) == 0)
    ocp.subject_to(-BOUND <= (u <= BOUND))
    ocp.add_objective(ocp.integral(ca.sumsqr(u)) / 2)
    ocp.method(MultipleShooting(N=N, M=1, intg="rk"))
    ocp.solver("ipopt", {"expand": True, "print_time": False, "ipopt.print_level": 0,
                         "ipopt.sb": "yes", "ipopt.tol": 1e-10, "error_on_fail": True})
    state = np.zeros(x.numel())
    state[0] = 1.0
    ocp.set_value(x0, state)
    s = np.linspace(0.0, 1.0, N + 1)  # the cold guess: the quaternion interpolated
    guess = np.outer(1 - s, state[:4]) + np.outer(s, target[:4])
    ocp.set_initial(q, (guess / np.linalg.norm(guess, axis=1, keepdims=True)).T)
    if rest:
        ocp.set_initial(rest[0], np.outer(target[4:7], s))
    sol = ocp.solve()
    X, U = ocp.sample(x, grid="control")[1], ocp.sample(u, grid="control-")[1]
    solve = ocp.to_function("rockit_step", [ocp.value(x0), X, U], [X, U],
                            ["x0", "x_init", "u_init"], ["x", "u"])
    plant = _plant(name, {k: v * (MISMATCH if k == key else 1.0) for k, v in P.items()},
                   x.numel(), u.numel(), T / N)
    _, xs = sol.sample(x, grid="control")
    _, us = sol.sample(u, grid="control")  # its last sample repeats the last interval's
    xs, us = xs.T, us[:-1].T
    out: dict[str, Any] = {}
    for how in ("function", "examples"):
        rng = np.random.default_rng(0)  # the same kicks for both
        state = np.array(sol.sample(x, grid="control")[1][0]).ravel()
        xs_k, us_k = xs.copy(), us.copy()
        seconds, failed = [], 0
        for _ in range(steps - 1):
            state = np.array(plant(state, us_k[:, 0])).ravel()
            state[4:7] += rng.normal(0, NOISE, 3)
            if rest:
                state[10:13] += rng.normal(0, NOISE, 3)
            x_init = np.hstack([xs_k[:, 1:], xs_k[:, -1:]])
            u_init = np.hstack([us_k[:, 1:], us_k[:, -1:]])
            t0 = time.perf_counter()
            try:
                if how == "function":
                    r = solve(state, x_init, u_init)
                    xs_k, us_k = np.array(r[0]), np.array(r[1])
                else:
                    ocp.set_value(x0, state)
                    k = 0
                    for part in parts:  # rockit sets a trajectory one variable at a time
                        ocp.set_initial(part, x_init[k:k + part.numel()])
                        k += part.numel()
                    ocp.set_initial(u, u_init)
                    s_k = ocp.solve()
                    xs_k = np.array(s_k.sample(x, grid="control")[1]).T
                    us_k = np.array(s_k.sample(u, grid="control")[1])[:-1].T
            except RuntimeError:  # IPOPT did not converge (error_on_fail): the plan goes on
                failed += 1
                xs_k, us_k = x_init, u_init
            seconds.append(time.perf_counter() - t0)
        out[how] = {"step": percentiles(seconds), "failed_steps": failed}
    return out


def _plant(name: str, P: dict[str, Any], nx: int, nu: int, h: float) -> ca.Function:
    """``(x, u) -> x``: one sample of the rockit model with the parameters P, RK4 with
    :data:`SUBSTEPS` substeps."""
    x, u = ca.SX.sym("x", nx), ca.SX.sym("u", nu)
    q, w = x[:4], x[4:7]
    rest = [] if name == "so3" else [x[7:10], x[10:13]]
    f = ca.Function("f", [x, u], [ca.vertcat(*rigid_body(name, q, w, rest, u, P))])
    dt, z = h / SUBSTEPS, x
    for _ in range(SUBSTEPS):
        k1 = f(z, u)
        k2 = f(z + dt / 2 * k1, u)
        k3 = f(z + dt / 2 * k2, u)
        k4 = f(z + dt * k3, u)
        z = z + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return ca.Function("plant", [x, u], [z])


def ours(problem: og.Problem, N: int, rti: bool, key: str) -> dict[str, Any]:
    """Our loop's warm steps: the step, the feedback alone, the failed steps, the statuses."""
    r = og.mpc(problem, N, N, rti=rti, noise=NOISE, mismatch={key: MISMATCH})
    t = r.timing()
    return {"step": t["step"], "feedback": t["feedback"], "failed_steps": r.failed_steps,
            "iterations_mean": r.summary()["iterations_mean"],
            "statuses": dict(Counter(s.status for s in r.warm))}


def in_c(problem: og.Problem, N: int, key: str) -> dict[str, Any]:
    """The loop in exported C (``DIR/mpc``, built with the Makefile's -O2): the warm steps'
    times of the converged loop (``c``: the same loop as :func:`ours`; its kicks from C's
    own generator) and of the real-time iterations (``c_rti``: ``--rti``), and the QP of each
    RTI feedback alone (``qp_floor``)."""
    import json
    import subprocess
    import tempfile

    out: dict[str, Any] = {}
    with tempfile.TemporaryDirectory(prefix="bench-mpc-") as tmp:
        done = export_c(problem, Path(tmp) / "c", N=N, build=True, mpc=True)
        assert done.mpc is not None
        for name, extra in (("c", []), ("c_rti", ["--rti"])):
            r = subprocess.run([str(done.mpc), "--steps", str(N), "--noise", str(NOISE),
                                "--mismatch", f"{key}={MISMATCH}", *extra],
                               capture_output=True, text=True, timeout=600)
            s = json.loads(r.stdout)["summary"]
            out[name] = {"step": s["timing"]["step"], "feedback": s["timing"]["feedback"],
                         "failed_steps": s["failed_steps"]}
            if name == "c":  # C's RTI does not count HPIPM's iterations
                out[name]["iterations_mean"] = s["iterations_mean"]
    out["qp_floor"] = {"step": s["timing"]["qp"], "failed_steps": s["failed_steps"]}
    return out


def main() -> None:
    args = arguments(__doc__.splitlines()[0], ROOT / "results")
    runs = [("so3", 16)] if args.quick else [("so3", 16), ("so3", 32), ("so3", 64),
                                             ("free_flyer", 32)]
    rows = []
    for name, N in runs:
        path, sets = CASES[name]
        pb = files.build(files.load(ROOT / path, [f"horizon.N={N}", *sets]))
        key = "inertia" if name == "so3" else "J"
        Console(stderr=True).print(f"{name} N={N} ...")
        row = {"problem": name, "N": N,
               "converged": ours(pb, N, False, key), **in_c(pb, N, key),
               "rti": ours(pb, N, True, key),
               "rockit": rockit_loop(pb, name, N, N, key)}
        rows.append(row)
    table = Table(title="MPC per-step time, ms: median / p99 / max of the warm steps; "
                  "failed steps (mean iterations)")
    for col in ("problem", "N", "converged (IPOPT warm)", "converged in C (DIR/mpc)",
                "RTI step (HPIPM)", "RTI feedback", "RTI in C (DIR/mpc --rti)",
                "its QP in C (floor)",
                "rockit to_function (IPOPT warm)", "rockit set_initial + solve"):
        table.add_column(col)

    def cell(r: dict[str, Any], sub: str = "step") -> str:
        s = r[sub]
        it = f" ({r['iterations_mean']:.1f} it)" if "iterations_mean" in r else ""
        return " / ".join(f"{s[k] * 1e3:.2f}" for k in ("median", "p99", "max")) + \
            f"; {r['failed_steps']} failed{it}"

    for r in rows:
        table.add_row(r["problem"], str(r["N"]), cell(r["converged"]), cell(r["c"]), cell(r["rti"]),
                      cell(r["rti"], "feedback"), cell(r["c_rti"]),
                      cell(r["qp_floor"]), cell(r["rockit"]["function"]),
                      cell(r["rockit"]["examples"]))
    Console().print(table)
    args.out.mkdir(parents=True, exist_ok=True)
    write_summary(args.out / "bench_mpc.json", {"rows": rows})
    chart(rows, args.out / "bench_mpc.png")

def chart(rows: list[dict[str, Any]], path: Path) -> None:
    """Median ms per step of every loop, one group of bars per problem and N (log scale)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(10, 4))
    labels = [f"{r['problem']} N={r['N']}" for r in rows]
    bars = {"converged step": lambda r: r["converged"]["step"],
            "converged in C": lambda r: r["c"]["step"],
            "RTI step": lambda r: r["rti"]["step"], "RTI feedback": lambda r: r["rti"]["feedback"],
            "RTI in C": lambda r: r["c_rti"]["step"],
            "its QP in C": lambda r: r["qp_floor"]["step"],
            "rockit to_function": lambda r: r["rockit"]["function"]["step"],
            "rockit set_initial + solve": lambda r: r["rockit"]["examples"]["step"]}
    for i, (label, get) in enumerate(bars.items()):
        ax.bar(np.arange(len(rows)) + 0.1 * i, [get(r).get("median", np.nan) * 1e3
                                                for r in rows], 0.1, label=label)
    ax.set_xticks(np.arange(len(rows)) + 0.35, labels)
    ax.set(ylabel="median ms per step", yscale="log", title="MPC step time")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
