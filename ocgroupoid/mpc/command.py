"""``ocgroupoid mpc FILE``: a problem file in closed loop (registered in :mod:`ocgroupoid.cli`).

Writes ``OUT/mpc.json`` (:mod:`~ocgroupoid.mpc.report`) and ``OUT/mpc.png``
(:mod:`~ocgroupoid.mpc.figure`). Exit codes: 0 every step solved, 1 some step failed (the
files are written), 2 bad input (one line, no traceback), 130 interrupted.
"""

from __future__ import annotations

import math
from pathlib import Path

import typer

from ..console import fail, out
from ..errors import ConfigError


def parse_mismatch(items: list[str]) -> dict[str, float]:
    """``KEY=FACTOR`` items as a dict (the keys are checked against the problem later)."""
    result = {}
    for item in items:
        key, sep, value = item.partition("=")
        try:
            factor = float(value)
        except ValueError:
            factor = math.nan
        if not sep or not key.strip() or not math.isfinite(factor) or factor <= 0:
            raise ConfigError(f"--mismatch {item!r}: write KEY=FACTOR with a factor > 0, e.g. "
                              "--mismatch inertia=1.05 (the plant's inertia 5 % larger)")
        result[key.strip()] = factor
    return result


def mpc_command(
    file: Path = typer.Argument(..., help="problem file (YAML)"),
    steps: int = typer.Option(..., "--steps", help="number of samples to run (>= 1)"),
    rti: bool = typer.Option(False, "--rti", help="one real-time iteration (SQP step, HPIPM "
                             "QP) per sample instead of converged re-solves"),
    noise: float = typer.Option(0.0, "--noise", help="standard deviation of the velocity "
                                "kicks after each sample (process noise)"),
    mismatch: list[str] = typer.Option([], "--mismatch", help="KEY=FACTOR: the plant's "
                                       "parameter KEY scaled (e.g. inertia=1.05); repeatable"),
    shrinking: bool = typer.Option(False, "--shrinking", help="fixed final time (the horizon "
                                   "shrinks) instead of a receding horizon"),
    min_horizon: int = typer.Option(1, "--min-horizon", help="with --shrinking: the shortest "
                                    "horizon solved, in samples; the last plan is held after"),
    hessian: str = typer.Option("projected", "--hessian", help="with --rti: the QP's Hessian, "
                                "projected (each stage block made positive definite) or exact"),
    seed: int = typer.Option(0, "--seed", help="seed of the noise"),
    out_dir: Path = typer.Option(Path("mpc"), "--out", help="folder for mpc.json and mpc.png"),
    set_: list[str] = typer.Option([], "--set", help="Override any key: KEY=VALUE, the value "
                                   "read as YAML (e.g. bounds={u: [-0.4, 0.4]})"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="print only errors"),
) -> None:
    """Run a problem file in closed loop against a simulated plant (model predictive control);
    write OUT/mpc.json (per-step times, iterations, status, tracking error, bound
    violations) and OUT/mpc.png."""
    from .. import files
    from ..errors import OcgError, SolverError
    from ..solve.outputs import check_folder
    from .loop import mpc

    try:
        if not math.isfinite(noise) or noise < 0:
            raise ConfigError(f"--noise {noise}: give a standard deviation >= 0, e.g. 0.001")
        if steps < 1:
            raise ConfigError(f"--steps {steps}: give a number of samples >= 1")
        factors = parse_mismatch(mismatch)
        check_folder(out_dir, "--out")
        cfg = files.load(file, set_)
        N = files.fixed_grid(cfg, "mpc")
        f, d = cfg.file, cfg.file.discretization
        result = mpc(files.build(cfg), N, steps, rti=rti, noise=noise, mismatch=factors,
                     seed=seed, horizon="shrinking" if shrinking else "receding",
                     min_horizon=min_horizon, hessian=hessian,
                     retraction=d.retraction, rule=d.rule, scheme=d.scheme,
                     ipopt=f.solver.ipopt, backend=f.solver.backend, fatrop=f.solver.fatrop,
                     progress=not quiet)
        out_dir.mkdir(parents=True, exist_ok=True)
        result.to_json(out_dir / "mpc.json")
        result.plot(out_dir / "mpc.png")
    except SolverError as e:
        fail(str(e), 1)
        return
    except OcgError as e:
        fail(str(e))
        return
    s = result.summary()
    if not quiet:
        step = s["timing"]["step"]
        out.print(f"{result.problem}: {s['steps']} steps ({result.settings['mode']}, "
                  f"{result.settings['horizon']}), {s['failed_steps']} failed; step time "
                  f"median {step.get('median', 0) * 1e3:.2f} ms, max "
                  f"{step.get('max', 0) * 1e3:.2f} ms; terminal error "
                  + ", ".join(f"{k} {v:.2e}" for k, v in s["terminal_error"].items())
                  + f"; largest bound violation {s['bound_violation_max']:.1e}; written to "
                  f"{out_dir}/mpc.json and mpc.png")
    if s["failed_steps"]:
        raise typer.Exit(1)
