"""fatrop against IPOPT on every problem file (issue 26): does fatrop converge by itself?

Per problem file, scheme (the file's own, and order2 where the file has another) and N = 16
to 256: fatrop's status, iterations and wall time, whether the solve would fall back to
IPOPT (fatrop failed), IPOPT's status, iterations and time, and the relative difference of
the two costs. Both backends run from the same start (the first geodesic guess) on the one
NLP, with the file's solver options. Then the build of each backend (its ``casadi.nlpsol``
and, for fatrop, the stage form and its Functions) on ``so3_rest_to_rest`` at N = 256, 512
and 1024, on CasADi's virtual machine and with jit, the whole build a solve waits for (the
transcription with each backend) and the export of the C solver: fatrop's must grow linearly
in N, as IPOPT's, and stay within 3 times IPOPT's.

Writes ``bench_fatrop.json`` and ``bench_fatrop.png`` (iterations of both against N, one
panel per file and scheme; build times against N).
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from ocgroupoid import files
from ocgroupoid.bench.record import write_summary
from ocgroupoid.bench.script import arguments, steps
from ocgroupoid.export.codegen import export_c
from ocgroupoid.nlp.backends import FatropBackend, IpoptBackend, Start
from ocgroupoid.nlp.backends.base import ACCEPTABLE
from ocgroupoid.nlp.method import Method
from ocgroupoid.nlp.options import SolverOptions
from ocgroupoid.nlp.program import NonlinearProgram
from ocgroupoid.nlp.transcription import Transcription
from ocgroupoid.solve import compile_problem

ROOT = Path(__file__).resolve().parent.parent
PROBLEMS = ROOT / "problems"
NS = (16, 32, 64, 128, 256)
BUILD_NS = (256, 512, 1024)
SECONDS = 120.0  # the deadline of one run


def schemes(path: Path) -> list[str]:
    """The file's own scheme, then order2 when it is another."""
    own = files.load(path).file.discretization.scheme
    return [own] if own == "order2" else [own, "order2"]


def transcription(path: Path, scheme: str, N: int, backend: str = "fatrop") -> Any:
    """The file's NLP at N with ``scheme``, built with the file's method and solver options
    (its ``solver.ipopt`` and ``solver.fatrop`` among them) on CasADi's virtual machine."""
    cfg = files.load(path, [f"horizon.N={N}", f"discretization.scheme={scheme}"])
    return compile_problem(files.build(cfg), files.method(cfg), files.options(cfg),
                           backend=backend, jit=False).transcription


def measure(path: Path, scheme: str, N: int) -> dict[str, Any]:
    """Both backends of one NLP from the first geodesic guess; where fatrop stopped at an
    acceptable point, IPOPT's polish from it too (what a solve runs: a polish, not a
    fallback)."""
    tr = transcription(path, scheme, N)
    p = tr.pack()
    start = Start(tr.point(tr.guesses(p)[0], p), p, deadline=time.monotonic() + SECONDS)
    row: dict[str, Any] = {"problem": path.stem, "scheme": scheme, "N": N}
    for backend in tr.backends:
        if backend.name == "fatrop":
            start = Start(start.x0, p, deadline=time.monotonic() + SECONDS)
        run = backend.run(start)
        row.update({f"{backend.name}_status": run.status, f"{backend.name}_success": run.success,
                    f"{backend.name}_iterations": run.iterations,
                    f"{backend.name}_seconds": run.seconds, f"{backend.name}_cost": run.f})
        if backend.name == "fatrop" and run.status == ACCEPTABLE:
            polish = tr.backends[-1].run(Start(run.x, p, run.lam_g, run.lam_x))
            row.update({"polish_success": polish.success,
                        "polish_iterations": polish.iterations,
                        "polish_seconds": polish.seconds, "fatrop_cost": polish.f})
    row["polished"] = row["fatrop_status"] == ACCEPTABLE and row["polish_success"]
    row["fallback"] = not (row["fatrop_success"] or row["polished"])
    row["cost_difference"] = abs(row["fatrop_cost"] - row["ipopt_cost"]) / \
        max(abs(row["ipopt_cost"]), 1e-300)
    return row


def build_times(N: int) -> dict[str, Any]:
    """The construction of each backend on the one NLP of so3_rest_to_rest (seconds): on
    CasADi's virtual machine, and with jit from a warm cache (the library compiled by an
    untimed build before; the best of three), where fatrop runs through its own C interface
    (``fatrop_ocp``) instead of CasADi's nlpsol. Then the whole build a solve waits for, the
    :class:`~ocgroupoid.nlp.transcription.Transcription` with each backend (the stage graphs
    and the NLP's assembly, which IPOPT's backend gets built and fatrop's repeats in stage
    form; fatrop's has IPOPT's beside it, its fallback), the best of three each way; and the
    export of the C solver with each backend (``export_c`` without building the C), the best
    of two."""
    cfg = files.load(PROBLEMS / "so3_rest_to_rest.yaml", [f"horizon.N={N}"])
    d = cfg.file.discretization
    nlp = NonlinearProgram(files.build(cfg), Method(N, scheme=d.scheme,
                                                    retraction=d.retraction, rule=d.rule))
    options = SolverOptions(ipopt=dict(cfg.file.solver.ipopt))
    row: dict[str, Any] = {"N": N}
    for cls in (IpoptBackend, FatropBackend):
        t0 = time.perf_counter()
        cls(nlp, options)  # type: ignore[arg-type]  # NonlinearProgram is a Graph
        row[f"{cls.name}_build_seconds"] = time.perf_counter() - t0
        cls(nlp, options, jit=True)  # type: ignore[arg-type]
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            cls(nlp, options, jit=True)  # type: ignore[arg-type]
            times.append(time.perf_counter() - t0)
        row[f"{cls.name}_jit_build_seconds"] = min(times)
    row["ratio"] = row["fatrop_build_seconds"] / row["ipopt_build_seconds"]
    row["jit_ratio"] = row["fatrop_jit_build_seconds"] / row["ipopt_jit_build_seconds"]
    problem, method = files.build(cfg), files.method(cfg)
    for backend in ("ipopt", "fatrop"):  # the whole build a solve waits for
        for jit, key in ((False, "whole"), (True, "whole_jit")):
            options = replace(files.options(cfg), backend=backend, jit=jit)
            Transcription(problem, method, options)  # with jit: the library compiled
            times = []
            for _ in range(3):
                t0 = time.perf_counter()
                Transcription(problem, method, options)
                times.append(time.perf_counter() - t0)
            row[f"{backend}_{key}_seconds"] = min(times)
    with tempfile.TemporaryDirectory() as tmp:  # the export of the C solver (no C build)
        for backend in ("ipopt", "fatrop"):
            options = replace(files.options(cfg), backend=backend, jit=False)
            times = []
            for k in range(2):
                t0 = time.perf_counter()
                export_c(problem, Path(tmp) / f"{backend}{k}", method=method, options=options,
                         mpc=False)
                times.append(time.perf_counter() - t0)
            row[f"{backend}_export_seconds"] = min(times)
    for key in ("whole", "whole_jit", "export"):
        row[f"{key}_ratio"] = row[f"fatrop_{key}_seconds"] / row[f"ipopt_{key}_seconds"]
    return row


def chart(rows: list[dict[str, Any]], builds: list[dict[str, Any]], out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    keys = sorted({(r["problem"], r["scheme"]) for r in rows})
    cols = 4
    n = len(keys) + 1
    fig, axes = plt.subplots(-(-n // cols), cols, figsize=(14, 3 * -(-n // cols)),
                             squeeze=False)
    for ax, (name, scheme) in zip(axes.ravel(), keys):
        sel = sorted((r for r in rows if (r["problem"], r["scheme"]) == (name, scheme)),
                     key=lambda r: r["N"])
        for backend, mark in (("ipopt", "o-"), ("fatrop", "s--")):
            ax.semilogx([r["N"] for r in sel], [r[f"{backend}_iterations"] for r in sel], mark,
                        label=backend, ms=4)
        failed = [r for r in sel if r["fallback"]]
        ax.semilogx([r["N"] for r in failed], [r["fatrop_iterations"] for r in failed], "rx",
                    ms=8, label="fatrop failed")
        ax.set_title(f"{name} ({scheme})", fontsize=9)
        ax.set_xlabel("N")
        ax.set_ylabel("iterations")
        ax.legend(fontsize=6)
    ax = axes.ravel()[len(keys)]
    for key, mark, label in (("ipopt", "o-", "ipopt"), ("fatrop", "s--", "fatrop (nlpsol)"),
                             ("ipopt_jit", "o:", "ipopt, jit"),
                             ("fatrop_jit", "s-", "fatrop, jit (own interface)")):
        ax.loglog([b["N"] for b in builds], [b[f"{key}_build_seconds"] for b in builds],
                  mark, label=label)
    ax.set_title("build (so3_rest_to_rest)", fontsize=9)
    ax.set_xlabel("N")
    ax.set_ylabel("seconds")
    ax.legend(fontsize=6)
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    fig.tight_layout()
    fig.savefig(out / "bench_fatrop.png", dpi=90)
    plt.close(fig)


def main() -> None:
    args = arguments(__doc__.splitlines()[0], ROOT / "results")
    paths = [PROBLEMS / "so3_rest_to_rest.yaml"] if args.quick else \
        sorted(PROBLEMS.glob("*.yaml"))
    Ns, build_Ns = ((16,), (64, 128)) if args.quick else (NS, BUILD_NS)
    args.out.mkdir(parents=True, exist_ok=True)
    cases = [(path, scheme, N) for path in paths for scheme in schemes(path) for N in Ns]
    rows: list[dict[str, Any]] = []
    builds: list[dict[str, Any]] = []
    summary = args.out / "bench_fatrop.json"
    with steps(len(cases) + len(build_Ns)) as step:
        for path, scheme, N in cases:
            step(f"{path.stem} {scheme} N={N}")
            try:
                rows.append(measure(path, scheme, N))
            except Exception as e:  # a configuration that does not build is recorded
                rows.append({"problem": path.stem, "scheme": scheme, "N": N,
                             "error": f"{type(e).__name__}: {e}"})
            write_summary(summary, {"rows": rows})
        for N in build_Ns:
            step(f"build N={N}")
            builds.append(build_times(N))
    done = [r for r in rows if "error" not in r]
    write_summary(summary, {"rows": rows, "builds": builds,
                            "fallbacks": sum(r["fallback"] for r in done),
                            "polished": sum(r["polished"] for r in done)})
    chart(done, builds, args.out)
    print(f"{'problem':20s} {'scheme':7s} {'N':>4s}  {'fatrop':22s} {'it':>4s} {'s':>6s}  "
          f"{'ipopt':22s} {'it':>4s} {'s':>6s}  fallback  cost diff")
    for r in rows:
        if "error" in r:
            print(f"{r['problem']:20s} {r['scheme']:7s} {r['N']:4d}  {r['error'][:90]}")
            continue
        print(f"{r['problem']:20s} {r['scheme']:7s} {r['N']:4d}  {r['fatrop_status'][:22]:22s} "
              f"{r['fatrop_iterations']:4d} {r['fatrop_seconds']:6.2f}  "
              f"{r['ipopt_status'][:22]:22s} {r['ipopt_iterations']:4d} "
              f"{r['ipopt_seconds']:6.2f}  {'YES' if r['fallback'] else 'no':8s}  "
              f"{r['cost_difference']:.1e}"
              + (f"  polished by IPOPT in {r['polish_iterations']}" if r["polished"] else ""))
    print(f"fallbacks: {sum(r['fallback'] for r in done)} of {len(done)}; polished by IPOPT "
          f"from fatrop's acceptable point: {sum(r['polished'] for r in done)}")
    for b in builds:
        print(f"build N={b['N']:5d}: ipopt {b['ipopt_build_seconds']:6.2f} s, fatrop "
              f"{b['fatrop_build_seconds']:6.2f} s ({b['ratio']:.1f}x); with jit (warm): "
              f"ipopt {b['ipopt_jit_build_seconds']:6.2f} s, fatrop "
              f"{b['fatrop_jit_build_seconds']:6.2f} s ({b['jit_ratio']:.1f}x)")
        print(f"  whole build N={b['N']:5d}: ipopt {b['ipopt_whole_seconds']:6.2f} s, fatrop "
              f"{b['fatrop_whole_seconds']:6.2f} s ({b['whole_ratio']:.1f}x); with jit (warm): "
              f"ipopt {b['ipopt_whole_jit_seconds']:6.2f} s, fatrop "
              f"{b['fatrop_whole_jit_seconds']:6.2f} s ({b['whole_jit_ratio']:.1f}x)")
        print(f"  export N={b['N']:5d}: ipopt {b['ipopt_export_seconds']:6.2f} s, fatrop "
              f"{b['fatrop_export_seconds']:6.2f} s ({b['export_ratio']:.1f}x)")


if __name__ == "__main__":
    main()
