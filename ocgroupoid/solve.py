"""Solving: IPOPT from good guesses, multi-start over local minima, coarse-to-fine continuation.

Optimal-control problems on SO(3) have several local minima (a slew may turn the short or
the long way round). ``multistart`` solves from every geodesic guess (each group factor both
ways round), the model's own guesses and a few deterministic perturbations, keeps the best
feasible result and lists the distinct minima met. ``continuation`` solves on coarse grids
first and interpolates each solution onto the next grid as its initial guess.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import Any, Callable, Iterable, Sequence

import numpy as np

from .diagnostics import diagnose, node_controls, node_velocities
from .discretize import DEFAULT_RULE, Discretization
from .errors import ConfigError
from .groupoid.pair import Pair
from .problem import Problem
from .solution import Solution
from .transcribe import Guess, RawResult, Transcription

Progress = Callable[[str], None]

HINTS = {
    "Infeasible_Problem_Detected": "the constraints and boundary conditions look incompatible: "
    "check the final values (are they reachable?) and the prescribed components; "
    "`ocgroupoid check` lists them",
    "Not_Enough_Degrees_Of_Freedom": "more equality constraints than variables: free a "
    "boundary value or drop a constraint (`ocgroupoid check` names the redundant ones)",
    "Maximum_Iterations_Exceeded": "try multistart, continuation from a coarser N, a longer "
    "horizon, or a larger solver.max_iter",
    "Invalid_Number_Detected": "a stage evaluated to NaN/Inf: with first_order a step turned "
    "by pi/2 or more; increase N or use the cayley retraction",
    "Diverging_Iterates": "the iterates left every physical scale (|x| > 1e8): start from "
    "another guess (multistart, continuation) or raise solver.ipopt.diverging_iterates_tol if "
    "your variables are that large",
    "Restoration_Failed": "IPOPT lost feasibility: try multistart or continuation",
    "Search_Direction_Becomes_Too_Small": "the problem may be degenerate: check for redundant "
    "boundary conditions",
    "Error_In_Step_Computation": "the KKT matrix is singular: check for redundant boundary "
    "conditions or constraints",
}


def _noop(_: str) -> None:
    return None


def factor_guesses(tr: Transcription, p: np.ndarray) -> list[list[tuple[str, np.ndarray]]]:
    """Per factor, labelled velocity alternatives (N x dim), the preferred one first."""
    G, T, N = tr.problem.groupoid, tr.horizon_of(p), tr.N
    start, end = p[tr.p_layout["start"]], p[tr.p_layout["end"]]
    V0, VN = p[tr.p_layout["V0"]], p[tr.p_layout["VN"]]
    out = []
    for f, r, ts, vs, m_end, m0, mN in zip(
            G.factors, tr.stages.retractions, G.target_layout.slices, G.velocity_layout.slices,
            tr.masks.end_state, tr.masks.start_velocity_by(G), tr.masks.end_velocity_by(G)):
        s0 = f.state_of_target(start[ts])
        sT = f.state_of_target(end[ts]) if m_end.all() else None
        if isinstance(f, Pair):
            goal = np.where(m_end, f.state_of_target(end[ts]), s0 + T * np.where(m0, V0[vs], 0))
            v0 = np.where(m0, V0[vs], (goal - s0) / T)
            vT = np.where(mN, VN[vs], (goal - s0) / T)
            alts = [("cubic", f.hermite(s0, v0, goal, vT, T, N))]
        else:
            alts = f.geodesics(s0, sT, T, N, r)
        out.append(alts)
    return out


def geodesic_guesses(tr: Transcription, p: np.ndarray) -> list[Guess]:
    """The all-preferred guess, then one guess per alternative of each factor."""
    per = factor_guesses(tr, p)
    first = [alts[0] for alts in per]
    label = " + ".join(name for name, _ in first)
    guesses = [Guess(label, np.hstack([xi for _, xi in first]))]
    for i, alts in enumerate(per):
        for name, xi in alts[1:]:
            parts = [a[0][1] if j != i else xi for j, a in enumerate(per)]
            guesses.append(Guess(name, np.hstack(parts)))
    return guesses


def perturbed_guesses(base: Guess, T: float, count: int, seed: int = 0) -> list[Guess]:
    """Deterministic perturbations ``xi + A sin(pi t/T) d`` of a guess (fixed seed)."""
    rng = np.random.default_rng(seed)
    N, n = base.xi.shape
    t = (np.arange(N) + 0.5) / N
    scale = max(float(np.sqrt(np.mean(base.xi**2))), 1.0 / T)
    out = []
    for i in range(count):
        d = rng.normal(size=n)
        d /= np.linalg.norm(d)
        out.append(Guess(f"perturbed {i + 1}",
                         base.xi + 2.0 * scale * np.sin(np.pi * t)[:, None] * d[None, :]))
    return out


def interpolate(coarse: Transcription, x: np.ndarray, p: np.ndarray, N: int) -> Guess:
    """A guess on N intervals from a solution on a coarser grid (linear in time)."""
    d = coarse.unpack(x, p)
    T = d["T"]
    t_c = (np.arange(coarse.N) + 0.5) * T / coarse.N
    t_f = (np.arange(N) + 0.5) * T / N
    xi = np.column_stack([np.interp(t_f, t_c, d["xi"][:, j]) for j in range(d["xi"].shape[1])])
    return Guess(f"interpolated from N={coarse.N}", xi)


@dataclass
class Minimum:
    """A distinct local minimum met by multi-start."""

    cost: float
    label: str
    status: str
    iterations: int


def distinct_minima(results: Iterable[RawResult], rtol: float = 1e-6, xtol: float = 1e-4
                    ) -> list[Minimum]:
    """Successful results grouped into local minima, cheapest first.

    Two results are one minimum when their costs agree to ``rtol`` and their NLP points
    to ``xtol`` (max-norm, relative to max(1, |x|)): minima of equal cost on different
    trajectories (mirror images, e.g. the plate-ball's) stay apart.
    """
    found: list[tuple[Minimum, np.ndarray]] = []
    for r in sorted((r for r in results if r.success), key=lambda r: r.cost):
        if not any(abs(r.cost - m.cost) <= rtol * max(1.0, abs(m.cost))
                   and np.max(np.abs(r.x - x)) <= xtol * max(1.0, float(np.max(np.abs(x))))
                   for m, x in found):
            found.append((Minimum(r.cost, r.label, r.status, r.iterations), r.x))
    return [m for m, _ in found]


class Solver:
    """A compiled problem: build once, solve for any parameters, boundary values and T.

    >>> solver = compile(problem, N=64)                    # doctest: +SKIP
    >>> sol = solver.solve(params={"inertia": [2, 1, 1]})  # doctest: +SKIP
    """

    def __init__(self, problem: Problem, N: int, retraction: str = "cayley",
                 rule: str = DEFAULT_RULE, ipopt: dict[str, Any] | None = None) -> None:
        self.problem = problem
        self.ipopt = dict(ipopt or {})
        self.disc = Discretization(N, retraction, rule)
        self.transcription = Transcription(problem, self.disc, self.ipopt)
        self._coarse: dict[int, Transcription] = {}

    def _at(self, N: int) -> Transcription:
        if N == self.disc.N:
            return self.transcription
        if N not in self._coarse:
            disc = Discretization(N, self.disc.retraction, self.disc.rule)
            self._coarse[N] = Transcription(self.problem, disc, self.ipopt)
        return self._coarse[N]

    def guesses(self, tr: Transcription, p: np.ndarray, multistart: bool | int) -> list[Guess]:
        geo = geodesic_guesses(tr, p)
        if not multistart:
            return geo[:1]
        extra = []
        if self.problem.guess_hook is not None:
            extra = [Guess(lbl, xi) for lbl, xi in self.problem.guess_hook(self.problem, tr, p)]
        count = 3 if multistart is True else int(multistart)
        return geo + extra + perturbed_guesses(geo[0], tr.horizon_of(p), count)

    def solve(self, params: dict[str, Any] | None = None, initial: dict[str, Any] | None = None,
              final: dict[str, Any] | None = None, T: float | None = None,
              multistart: bool | int = False, continuation: Sequence[int] | None = None,
              guess: Guess | None = None, replay: bool = True, progress: Progress = _noop
              ) -> Solution:
        """Solve with IPOPT and return a diagnosed Solution (``success`` may be False).

        ``multistart``: True (3 perturbations) or the number of perturbed starts, on top of
        the geodesic and model guesses. ``continuation``: coarser N solved first, in order.
        """
        levels = sorted(set(int(n) for n in (continuation or [])))
        if any(n >= self.disc.N for n in levels):
            raise ConfigError(f"continuation grids must be coarser than N={self.disc.N}: {levels}")
        results: list[RawResult] = []
        seeds: list[Guess] | None = [guess] if guess is not None else None
        prev: tuple[Transcription, RawResult] | None = None
        for n in [*levels, self.disc.N]:
            tr = self._at(n)
            p = tr.pack(params, initial, final, T)
            if prev is not None:
                starts = [interpolate(prev[0], prev[1].x, prev[1].p, n)]
            else:
                starts = seeds or self.guesses(tr, p, multistart)
            level: list[RawResult] = []
            for i, g in enumerate(starts):
                progress(f"N={n}: start {i + 1}/{len(starts)} ({g.label})")
                level.append(tr.solve(g, p))
            if prev is None:
                results = level
            best = min(level, key=lambda r: (not r.success, r.cost))
            prev = (tr, best)
        assert prev is not None
        tr, best = prev
        progress("diagnostics")
        return make_solution(tr, best, distinct_minima(results), replay)


def compile(problem: Problem, N: int = 64, retraction: str = "cayley", rule: str = DEFAULT_RULE,
            ipopt: dict[str, Any] | None = None) -> Solver:
    """Build the NLP of ``problem`` on N intervals once; see :class:`Solver`."""
    return Solver(problem, N, retraction, rule, ipopt)


def solve(problem: Problem, N: int = 64, retraction: str = "cayley", rule: str = DEFAULT_RULE,
          ipopt: dict[str, Any] | None = None, **kwargs: Any) -> Solution:
    """Build and solve in one call; ``kwargs`` go to :meth:`Solver.solve`."""
    return compile(problem, N, retraction, rule, ipopt).solve(**kwargs)


def hint_for(tr: Transcription, r: RawResult) -> str:
    """What went wrong and what to try, from IPOPT's status and the last iterate."""
    if r.success:
        return ""
    parts = [HINTS.get(r.status, "try multistart or continuation")]
    d = tr.unpack(r.x, r.p)
    G = tr.problem.groupoid
    for f, vs in zip(G.factors, G.velocity_layout.slices):
        if isinstance(f, Pair):
            continue
        step = float(np.max(np.linalg.norm(d["xi"][:, vs], axis=1))) * d["T"] / tr.N
        limit = np.pi / 2 if tr.disc.retraction == "first_order" else np.pi
        if step > 0.5 * limit:
            parts.append(f"{f.velocity} turns {step:.3g} rad in one step ({tr.disc.retraction} "
                         f"is singular at {limit:.2f}); increase N")
    return "; ".join(parts)


def make_solution(tr: Transcription, r: RawResult, minima: Sequence[Minimum],
                  replay: bool = True) -> Solution:
    """Assemble a Solution (trajectory, controls, multipliers, diagnostics) from a result."""
    pb, G = tr.problem, tr.problem.groupoid
    t0 = time.perf_counter()
    g_nlp = np.array(tr.g_fun(r.x, r.p)).ravel()
    recon_nlp = float(np.max(np.abs(g_nlp[tr.rows("recon").ravel()])))
    r = replace(r, x=tr.reconstruct(r.x, r.p))
    d = tr.unpack(r.x, r.p)
    T, N = d["T"], tr.N
    states = {f.state: np.array([f.format_state(row[ss]) for row in d["s"]])
              for f, ss in zip(G.factors, G.state_layout.slices)}
    vel = node_velocities(tr, r.x, r.p)
    velocities = {f.velocity: vel[:, vs] for f, vs in zip(G.factors, G.velocity_layout.slices)}
    vt = np.linspace(0, T, N + 1) if pb.order == 2 else (np.arange(N) + 0.5) * T / N
    t_u, u = node_controls(tr, r.x, r.p)
    rows = tr.phi_rows()
    mult: dict[str, Any] = {"t": vt if pb.order == 2 else (np.arange(N) + 0.5) * T / N,
                            "names": [n for n, c in pb.constraints for _ in range(c.numel())]}
    if rows.size:
        mult["Phi"] = r.lam_g[rows].T
    final_rows = tr.rows("final")
    if final_rows.size:
        mult["final"] = r.lam_g[final_rows.ravel()]
    diagnostics = diagnose(tr, r.x, r.p, r.lam_g, replay=replay, solved=r.success)
    diagnostics["reconstruction_residual_nlp"] = recon_nlp
    diagnostics["seconds"] = time.perf_counter() - t0
    params = {name: d["P"][sl].tolist() for name, sl in pb.parameter_slices.items()}
    return Solution(
        problem=pb.name, success=r.success, status=r.status, N=N, T=T, cost=r.cost,
        iterations=r.iterations, solve_seconds=r.solve_seconds,
        build_seconds=tr.build_seconds,
        discretization={"retraction": tr.disc.retraction, "rule": tr.disc.rule,
                        "order": pb.order, "start": r.label},
        parameters=params, t=np.linspace(0, T, N + 1), states=states, velocity_t=vt,
        velocities=velocities, controls_t=t_u, controls=u,
        control_names=[n for n, _ in pb.controls], multipliers=mult, diagnostics=diagnostics,
        minima=[m.__dict__ for m in minima], hint=hint_for(tr, r), x=r.x, p=r.p,
    )
