"""The closed loop: ``og.mpc(problem, N, ...)``.

At each sample time ``t_i = i h`` (h = T/N unless given) the plant (:mod:`~ocgroupoid.mpc.plant`)
runs one sample under the control polynomial of the current plan (its span [0, h]); the
measured state becomes the NLP's initial state — a parameter change, no rebuild — and the
feedback law (:mod:`~ocgroupoid.mpc.controller`) computes the next plan from the last one
moved by one sample (:mod:`~ocgroupoid.mpc.shift`), prepared before the measurement; when
the solver fails, the last plan goes on (its next sample is applied) and the failure is
counted. The
horizon either recedes (its length T fixed, the terminal condition kept: the target is always
T ahead) or shrinks (the final time fixed: the horizon is ``T - t_i``, N intervals over it;
at most N samples). The first plan, the open-loop plan, is solved cold at the nominal initial
state; the tracking error is measured against it.

A shrinking horizon stops re-solving once less than ``min_horizon`` samples are left: the
last plan, solved over ``min_horizon`` samples, is applied to the end (status ``hold``).
With the final time fixed and the terminal state prescribed, the last horizons leave no room:
the plans of a rest-to-rest problem brake at their control bounds near the end, so a kick
there asks for more than the bounds allow, and a horizon of one sample squeezes all N
intervals into it. The hold keeps the problem and the final time and costs at most the
effect of the last ``min_horizon - 1`` kicks, which no bounded control could remove in the
time left. A penalty on the terminal rows instead would change the problem the loop solves
and trade the final error against the bounds through a weight. Measured (N = 32, inertia
x 1.05, kicks of 1e-3): the quadrotor's one infeasible step, the last, goes with
``min_horizon = 2``; on the free flyer (|u| <= 0.45) and the reaction wheels the problem is
infeasible from much earlier (from sample 23 and 14 on: the bounds are active over the
whole rest of the plan), and those steps keep the last plan and count as failed — what they
need is an exact (L1) penalty on the terminal rows with slack variables, so that a feasible
problem keeps its solution. The default :data:`MIN_HORIZON` = 1 re-solves at every sample.

The loop is the one the exported C runs (:mod:`ocgroupoid.export.mpc`, both horizons,
converged and RTI): fixed sizes (one NLP, N intervals, for every sample of both horizons),
the preparation apart from the feedback, the measurement entering only two slices of p and
the horizon one entry.
"""

from __future__ import annotations

import time
from typing import Any, Callable

import numpy as np
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from ..errors import ConfigError, SolverError
from ..model.problem import Problem
from ..nlp.assembly import Kind
from ..nlp.loop import MIN_HORIZON, check_fixed_horizon
from ..nlp.method import DEFAULT_RETRACTION, Method
from ..nlp.options import DEFAULT_BACKEND, SolverOptions
from ..nlp.schemes import DEFAULT_RULE, DEFAULT_SCHEME
from ..nlp.transcription import Transcription
from ..solve.compiled import CompiledProblem
from ..solve.readout import control_ppoly
from ..verify.replay import terminal_errors
from .controller import Converged, Outcome, RealTime
from .plant import Plant, mismatched
from .report import HOLD, MpcResult, Step
from .rti import HESSIANS, Iterate
from .shift import Shift
from .state import distance, plan_at, with_state

HORIZONS = ("receding", "shrinking")
#: control samples per sample interval in the recorded trajectory (the figure)
CONTROL_SAMPLES = 8


def _check(steps: int, N: int, horizon: str, sample: float | None,
           min_horizon: int) -> None:
    if horizon not in HORIZONS:
        raise ConfigError(f"horizon must be {' or '.join(HORIZONS)}, got {horizon!r}")
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise ConfigError(f"steps must be an integer >= 1, got {steps!r}")
    if horizon == "shrinking" and steps > N:
        raise ConfigError(f"a shrinking horizon ends at the final time after N = {N} samples; "
                          f"got steps = {steps}: ask for at most {N}, or a receding horizon")
    if isinstance(min_horizon, bool) or not isinstance(min_horizon, int) or min_horizon < 1:
        raise ConfigError(f"min_horizon must be a number of samples >= 1, got {min_horizon!r}")
    if sample is not None and not (np.isfinite(sample) and sample > 0):
        raise ConfigError(f"sample must be a time > 0, got {sample!r}")


def _bound_violation(tr: Transcription, x: np.ndarray, p: np.ndarray, rows: np.ndarray) -> float:
    """The largest violation of the NLP's bounds at their points (0 without bounds)."""
    if not rows.size:
        return 0.0
    g = np.array(tr.g_fun(x, p)).ravel()[rows]
    lbg, ubg = (np.array(v).ravel()[rows] for v in tr.bounds_function(p)[:2])
    return float(np.max(np.maximum(0.0, np.maximum(lbg - g, g - ubg))))


def _controls_on(ppoly: dict[str, np.ndarray], t: np.ndarray) -> np.ndarray:
    """The control polynomial at the times t (one row each)."""
    breaks, C = ppoly["x"], ppoly["c"]
    j = np.clip(np.searchsorted(breaks, t, side="right") - 1, 0, breaks.size - 2)
    tau = t - breaks[j]
    out = np.zeros((t.size, C.shape[2]))
    for i in range(C.shape[0]):
        out = out * tau[:, None] + C[i, j, :]
    return out


def mpc(problem: Problem, N: int = 32, steps: int | None = None, *, rti: bool = False,
        horizon: str = "receding", noise: float = 0.0, mismatch: dict[str, float] | None = None,
        seed: int = 0, sample: float | None = None, qp: str = "hpipm",
        hessian: str = HESSIANS[0], min_horizon: int = MIN_HORIZON,
        retraction: str = DEFAULT_RETRACTION, rule: str = DEFAULT_RULE,
        scheme: str = DEFAULT_SCHEME,
        ipopt: dict[str, Any] | None = None, backend: str = DEFAULT_BACKEND,
        fatrop: dict[str, Any] | None = None,
        progress: bool | Callable[[int, int], None] = False) -> MpcResult:
    """Run ``problem`` in closed loop for ``steps`` samples (module docstring).

    ``steps``: default N (shrinking) or 2N (receding). ``rti``: one real-time iteration per
    sample (:mod:`~ocgroupoid.mpc.rti`, QP solver ``qp``, QP Hessian ``hessian``) instead of
    converged re-solves. ``min_horizon``: the shortest horizon a shrinking loop solves, in
    samples (module docstring).
    ``noise``: the standard deviation of the velocity kicks after each sample; ``mismatch``:
    the plant's parameters scaled (``{"inertia": 1.05}``); ``seed``: the noise's generator.
    ``sample``: the sampling time (default T/N). ``progress``: a rich progress bar (True) or
    a callback ``(done, total)``. ``ipopt``, ``backend``, ``fatrop``: the solver options of
    every solve (:class:`~ocgroupoid.nlp.options.SolverOptions`). Raises
    :class:`~ocgroupoid.errors.SolverError` when the open-loop plan does not solve.
    """
    K = steps if steps is not None else (N if horizon == "shrinking" else 2 * N)
    _check(K, N, horizon, sample, min_horizon)
    check_fixed_horizon(problem)
    mismatch = dict(mismatch or {})
    solver = CompiledProblem(problem, Method(N, scheme=scheme, retraction=retraction, rule=rule),
                    SolverOptions(backend=backend, ipopt=dict(ipopt or {}),
                                  fatrop=dict(fatrop or {})))
    tr = solver.transcription
    p = tr.pack()
    T = tr.horizon_of(p)
    h = float(sample) if sample is not None else T / N
    if horizon == "shrinking" and K * h > T * (1 + 1e-12):
        raise ConfigError(f"a shrinking horizon ends at T = {T:g}: {K} samples of {h:g} pass it")
    plant = Plant(tr, mismatched(tr, p, mismatch), noise, seed)
    shift = Shift(tr)
    law = RealTime(tr, qp, hessian) if rti else Converged(tr)
    G = tr.problem.groupoid
    ns = G.state_size
    z = np.concatenate([np.concatenate([f.state_of_target(tr.part(p, "start")[ts])
                                        for f, ts in zip(G.factors, G.target_layout.slices)]),
                        tr.part(p, "V0")])
    ineq = tr.rows(Kind.INEQUALITY).ravel()
    t0 = time.perf_counter()
    first = tr.solve(tr.guesses(p)[0], p)
    if not first.success:
        raise SolverError(f"the open-loop plan of {problem.name!r} did not solve "
                          f"({first.status}); solve the problem file alone first (ocgroupoid "
                          "solve), e.g. with multistart or another N")
    it = Iterate(first.x, first.lam_g, first.lam_x)
    out = tr.readout(it.x, p, it.lam_g)
    ppoly = control_ppoly(out)
    first_seconds = time.perf_counter() - t0
    plan = {k: out[k] for k in ("t", "node_states", "velocity_t", "velocities", "control_t",
                                "controls")}
    violation = _bound_violation(tr, it.x, p, ineq)
    records = [Step(0.0, first.status, True, first.iterations, first_seconds, 0.0,
                    first_seconds, distance(tr, z, z), violation,
                    _controls_on(ppoly, np.zeros(1))[0].tolist())]
    Z, ts, U = [z], [0.0], [_controls_on(ppoly, np.linspace(0, h, CONTROL_SAMPLES + 1))]
    T_now, offset = T, 0.0  # offset: how far into the plan being applied (failed steps)
    with _bar(progress, K) as advance:
        advance(1)
        for i in range(1, K + 1):
            # preparation: the next problem, the last plan moved by one sample
            T_next = T_now - h if horizon == "shrinking" else T_now
            solving = i < K and (horizon == "receding" or T_next > (min_horizon - 1e-9) * h)
            tp = time.perf_counter()
            if solving:
                p_next = p.copy()
                p_next[tr.layout.p_slices["T"]] = T_next
                guess = shift(it, shift.sigma(h, T_now, T_next))
                law.prepare(guess, with_state(tr, p_next, *plan_at(tr, out, offset + h)))
            prepare_seconds = time.perf_counter() - tp
            # the plant runs one sample under the current plan
            z = plant.advance(z, ppoly, offset, offset + h)
            Z.append(z)
            ts.append(i * h)
            if i == K:
                break
            # feedback: the measured state in, the next plan out
            tf = time.perf_counter()
            if solving:
                p = with_state(tr, p_next, z[:ns], z[ns:])
                done = law.feedback(p)
            else:
                done = Outcome(it, True, HOLD, 0, 0.0)
            if solving and done.success:  # the new plan
                it, offset = done.iterate, 0.0
                out = tr.readout(it.x, p, it.lam_g)
                ppoly = control_ppoly(out)
                violation = _bound_violation(tr, it.x, p, ineq)
            else:  # the last plan goes on (a failed step starts the next from its shift)
                it, offset = (guess if solving else it), offset + h
            feedback_seconds = time.perf_counter() - tf
            U.append(_controls_on(ppoly, offset + np.linspace(0, h, CONTROL_SAMPLES + 1)))
            reference = np.concatenate(plan_at(tr, plan, i * h))
            records.append(Step(i * h, done.status, done.success, done.iterations,
                                prepare_seconds + feedback_seconds, prepare_seconds,
                                feedback_seconds, distance(tr, z, reference), violation,
                                _controls_on(ppoly, np.full(1, offset))[0].tolist()))
            T_now = T_next
            advance(1)
    end = np.concatenate(plan_at(tr, plan, K * h))
    sample_t = np.concatenate([i * h + np.linspace(0, h, CONTROL_SAMPLES + 1)
                               for i in range(len(U))])
    settings = {"N": N, "steps": K, "sample": h, "T": T, "horizon": horizon,
                "mode": "rti" if rti else "converged", "qp": qp if rti else None,
                "hessian": hessian if rti else None, "min_horizon": min_horizon,
                "backend": backend, "noise": noise, "mismatch": mismatch, "seed": seed,
                "scheme": scheme, "retraction": tr.scheme.retraction}  # the one it steps with
    return MpcResult(problem.name, settings, records, np.array(ts), np.array(Z), sample_t,
                     np.vstack(U), plan, terminal_errors(tr, z[:ns], z[ns:], p),
                     distance(tr, z, end),
                     [n for n, _ in problem.controls], problem.labels(tr.part(p, "P"))["bounds"])


class _bar:
    """A rich progress bar on stderr (``progress`` True), a callback, or nothing."""

    def __init__(self, progress: bool | Callable[[int, int], None], total: int) -> None:
        self.progress, self.total, self.done = progress, total, 0
        self.bar: Progress | None = None

    def __enter__(self) -> Callable[[int], None]:
        if self.progress is True:
            self.bar = Progress(TextColumn("MPC"), BarColumn(), MofNCompleteColumn(),
                                TimeElapsedColumn(), console=Console(stderr=True),
                                transient=True)
            self.bar.start()
            self.task = self.bar.add_task("mpc", total=self.total)
        return self.advance

    def advance(self, n: int) -> None:
        self.done += n
        if self.bar is not None:
            self.bar.update(self.task, completed=self.done)
        elif callable(self.progress):
            self.progress(self.done, self.total)

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.stop()
