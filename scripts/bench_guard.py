"""fatrop guarded in the caller's process against fatrop in its helper process (issue 26).

Every fatrop solve used to run in a helper process, since fatrop 1.1.8 has no time limit
and loops without a bound on some singular KKT systems; through its own C interface on
Linux it now runs in the caller's process, guarded by the driver
(:mod:`~ocgroupoid.nlp.backends.fatrop_ocp`'s ``Guard``). Per problem file and N, the
file's problem with ``order6@fatrop+jit`` solved as a caller solves it
(:meth:`~ocgroupoid.nlp.transcription.Transcription.solve`, from the first geodesic guess),
in rounds: one guarded solve, then one through the helper, :data:`ROUNDS` times; the
median of each, in milliseconds, and their ratio. The same iterations and cost both ways
(checked).

Writes ``bench_guard.json`` and ``bench_guard.png`` (both medians against N, one panel per
file).
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ocgroupoid import files  # noqa: E402
from ocgroupoid.bench.record import write_summary  # noqa: E402
from ocgroupoid.bench.script import arguments, steps  # noqa: E402
from ocgroupoid.solve import compile_problem  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
PROBLEMS = ROOT / "problems"
FILES = ("so3_rest_to_rest", "custom_rigid_body", "free_flyer", "so3_minimum_time",
         "quadrotor", "cart_pole")
NS = (4, 8, 16, 64)
ROUNDS = 61
QUICK = (("so3_rest_to_rest",), (4,), 3)


def rows_of(name: str, N: int, rounds: int) -> dict[str, Any]:
    """The guarded and the helper's solves of one file at N, in rounds."""
    cfg = files.load(PROBLEMS / f"{name}.yaml", [f"horizon.N={N}",
                                                  "discretization.scheme=order6",
                                                  "solver.backend=fatrop", "solver.jit=true"])
    solver = compile_problem(files.build(cfg), files.method(cfg), files.options(cfg))
    tr = solver.transcription
    fatrop = tr.fatrop
    if fatrop is None or fatrop.direct is None:
        raise SystemExit("fatrop's own interface is not available here")
    guarded = fatrop.guarded
    p = tr.pack()
    guess = tr.guesses(p)[0]
    times: dict[bool, list[float]] = {True: [], False: []}
    results = {}
    for where in (False, True):  # the helper forks at its first call: not timed
        fatrop.guarded = where and guarded
        results[where] = tr.solve(guess, p)
    for _ in range(rounds):
        for where in (True, False):
            fatrop.guarded = where and guarded
            t0 = time.perf_counter()
            r = tr.solve(guess, p)
            times[where].append(time.perf_counter() - t0)
            if (r.iterations, r.cost) != (results[where].iterations, results[where].cost):
                raise SystemExit(f"{name} N={N}: a solve differs from the first")
    fatrop.guarded = guarded
    same = (results[True].iterations, results[True].cost) == (results[False].iterations,
                                                          results[False].cost)
    inside, helper = (statistics.median(times[w]) * 1e3 for w in (True, False))
    return {"problem": name, "N": N, "guarded": guarded, "iterations": results[True].iterations,
            "backend": results[True].backend, "same": same, "guarded_ms": inside,
            "helper_ms": helper, "ratio": helper / inside}


def chart(rows: list[dict[str, Any]], path: Path) -> None:
    """Median solve against N, guarded and through the helper, one panel per file."""
    names = list(dict.fromkeys(r["problem"] for r in rows))
    fig, axes = plt.subplots(1, len(names), figsize=(3.2 * len(names), 3.2), squeeze=False)
    for ax, name in zip(axes[0], names):
        mine = [r for r in rows if r["problem"] == name]
        Ns = [r["N"] for r in mine]
        ax.loglog(Ns, [r["guarded_ms"] for r in mine], "o-", label="guarded, this process")
        ax.loglog(Ns, [r["helper_ms"] for r in mine], "s--", label="helper process")
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("N")
        ax.set_xticks(Ns, [str(N) for N in Ns])
        ax.xaxis.set_minor_locator(plt.NullLocator())
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].set_ylabel("median solve (ms)")
    axes[0][0].legend(fontsize=8)
    fig.suptitle("fatrop, order6+jit: in the caller's process against its helper", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> None:
    args = arguments(__doc__.splitlines()[0], ROOT / "results")
    names, Ns, rounds = QUICK if args.quick else (FILES, NS, ROUNDS)
    rows = []
    with steps(len(names) * len(Ns)) as step:
        for name in names:
            for N in Ns:
                step(f"{name} N={N}")
                rows.append(rows_of(name, N, rounds))
    args.out.mkdir(parents=True, exist_ok=True)
    write_summary(args.out / "bench_guard.json", {"rounds": rounds, "rows": rows})
    chart(rows, args.out / "bench_guard.png")
    for r in rows:
        print(f"{r['problem']:>18} N={r['N']:<4} {r['iterations']:>3} it  guarded "
              f"{r['guarded_ms']:7.2f} ms  helper {r['helper_ms']:7.2f} ms  "
              f"{r['ratio']:.2f}x{'' if r['same'] else '  (differ!)'}")


if __name__ == "__main__":
    main()
