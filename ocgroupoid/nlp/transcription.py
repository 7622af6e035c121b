"""One NLP from a problem and a discretisation.

The scheme (:mod:`ocgroupoid.nlp.schemes`) lays out its variables and stage Functions; the
transcription adds the final conditions shared by every scheme — the chart coordinates of
each prescribed final state (3 equations for a rotation, 2 for a point of S^2, one per
prescribed component of R^n) and the user's final conditions — assembles the derivatives
(:mod:`ocgroupoid.nlp.assembly`) and sets IPOPT up. Initial states enter through p
(:mod:`ocgroupoid.nlp.layout`).

Three computations that both the Python path and exported C need are CasADi Functions built
here once: the geodesic guesses as graphs of p (:attr:`Transcription.guess_function`), the
NLP point of a guess (:attr:`point_function`) and the read-out of a solution
(:attr:`readout_function`). The packing of p is :class:`~ocgroupoid.nlp.parameters.
ParameterValues`.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Callable

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from ..errors import BoundaryError, ConfigError
from ..lie.retraction import RETRACTION_NAMES
from ..model.boundary_values import prescribe
from ..model.consistency import check_order
from ..model.problem import Boundary, Problem
from ..model.values import check_horizon
from .assembly import Block, Kind, assemble
from .boundary import FinalConditions
from .fatrop import INTERRUPTED, TIMED_OUT, FatropNLP
from .jit import compiled
from .layout import Layout, Masks
from .parameters import ParameterValues
from .schemes import DEFAULT_RULE, DEFAULT_SCHEME, SCHEME_NAMES, make_scheme
from .schemes.order2 import columns, stage_function
from .schemes.order4 import GAUSS2
from .watch import Listener, Watch

#: the wall time one solve may take (seconds, ``solver.max_seconds``): IPOPT's
#: ``max_wall_time`` for each of its runs, and the deadline of a fatrop run
#: (:mod:`~ocgroupoid.nlp.isolated`); :class:`~ocgroupoid.solve.Solver` holds every start of
#: one solve to it together
MAX_SECONDS = 600.0

DEFAULT_IPOPT: dict[str, Any] = {
    "tol": 1e-10,
    "max_wall_time": MAX_SECONDS,
    "constr_mult_init_max": 0.0,  # start from zero multipliers: saves a factorisation
    "max_iter": 500,
    # a start that wanders off (|x| > 1e8: no physical velocity or state) stops at once as
    # Diverging_Iterates; left to run, MUMPS grows its workspace each iteration and one bad
    # start of a multi-start took minutes (heavy top, N=256, "long way" guess)
    "diverging_iterates_tol": 1e8,
    # bounds hold exactly at the solution (IPOPT relaxes them by 1e-8 by default); equality
    # constraints are never relaxed, so problems without bounds are unaffected
    "bound_relax_factor": 0.0,
    "print_level": 0,
    "sb": "yes",
}

#: outputs of the read-out Function, in the order exported C reads them (enum ocg_output)
READOUT_OUTPUTS = ("x_solution", "t", "states", "node_states", "velocity_t", "velocities",
                   "control_t", "controls", "multiplier_t", "multipliers",
                   "final_multipliers", "control_breaks", "control_coefficients", "steps")
C_READOUT_OUTPUTS = READOUT_OUTPUTS[:13]


def nlpsol_options(ipopt: dict[str, Any] | None, fns: dict[str, ca.Function]) -> dict[str, Any]:
    """Options of ``casadi.nlpsol``: IPOPT's (defaults overridden by ``ipopt``) and the
    assembled derivative functions in its cache, so that it derives none itself."""
    opts: dict[str, Any] = {f"ipopt.{k}": v for k, v in {**DEFAULT_IPOPT, **(ipopt or {})}.items()}
    opts.update({"print_time": False, "calc_lam_p": False, "show_eval_warnings": False,
                 "cache": {k: fns[k] for k in ("nlp_grad_f", "nlp_jac_g", "nlp_hess_l")}})
    return opts


#: IPOPT options of a primal-dual warm start (Transcription.warm_solver)
WARM_IPOPT: dict[str, Any] = {
    "ipopt.warm_start_init_point": "yes", "ipopt.warm_start_bound_push": 1e-9,
    "ipopt.warm_start_slack_bound_push": 1e-9, "ipopt.warm_start_mult_bound_push": 1e-9,
    "ipopt.mu_init": 1e-6}

#: the NLP solvers: IPOPT on the whole sparse KKT system (MUMPS), or fatrop on the stage form
#: (:mod:`~ocgroupoid.nlp.fatrop`)
BACKENDS = ("ipopt", "fatrop")
DEFAULT_BACKEND = "ipopt"

STEPS = ("uniform", "adaptive")
MAX_BOUND_POINTS = 16
#: adaptive steps stay within [STEP_RANGE[0], STEP_RANGE[1]] times the uniform step T/N
STEP_RANGE = (0.1, 10.0)


@dataclass(frozen=True)
class Discretization:
    """N intervals, a scheme, a retraction for the group factors, a rule for the constraints,
    and the steps: uniform h = T/N, or adaptive: ``phases`` (interval counts summing to N),
    uniform within each phase, the phases' durations free (seed 001, §6.3: time as a variable
    of the discrete problem). The solver chooses the phases so that phase boundaries — nodes
    — fall on the switches of the controls (:mod:`ocgroupoid.solve.mesh`)."""

    N: int
    retraction: str = "cayley"
    rule: str = DEFAULT_RULE
    scheme: str = DEFAULT_SCHEME
    steps: str = "uniform"
    phases: tuple[int, ...] = ()
    #: bounds imposed at this many more points inside every interval (uniformly spaced),
    #: beyond the scheme's own; order4 only
    bound_points: int = 0
    #: adaptive steps: per phase, per bound row, the side held throughout the phase (+1 upper,
    #: -1 lower, 0 none): a bang-bang arc as an equality, so that the phases' durations are
    #: the switching times (:mod:`ocgroupoid.solve.mesh`)
    active: tuple[tuple[int, ...], ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.N, int) or isinstance(self.N, bool) or self.N < 2:
            raise ConfigError(f"N must be an integer >= 2, got {self.N!r}")
        if self.retraction not in RETRACTION_NAMES:
            raise ConfigError(
                f"unknown retraction {self.retraction!r}; choose one of "
                f"{', '.join(RETRACTION_NAMES)}"
            )
        if self.scheme not in SCHEME_NAMES:
            raise ConfigError(f"unknown scheme {self.scheme!r}; choose one of "
                              f"{', '.join(SCHEME_NAMES)}")
        if self.steps not in STEPS:
            raise ConfigError(f"steps are {' or '.join(STEPS)}, got {self.steps!r}")
        if isinstance(self.bound_points, bool) or not isinstance(self.bound_points, int) or \
                not 0 <= self.bound_points <= MAX_BOUND_POINTS:
            raise ConfigError(f"bound_points is an integer in 0..{MAX_BOUND_POINTS} (more points "
                              f"per interval where the bounds hold), got {self.bound_points!r}")
        if self.active and len(self.active) != len(self.phases):
            raise ConfigError(f"active sides are given for {len(self.active)} phases, the "
                              f"grid has {len(self.phases)}")
        if self.phases and (sum(self.phases) != self.N or min(self.phases) < 1):
            raise ConfigError(f"phases {self.phases} must be positive interval counts summing "
                              f"to N = {self.N}")


@dataclass
class Guess:
    """Velocities on the N intervals (N x dim y); the scheme turns them into a point. A warm
    start carries a whole NLP point ``x`` of the same structure (a previous solution), and
    its multipliers ``lam_g``, ``lam_x``: IPOPT then starts from the primal-dual point
    (:attr:`Transcription.warm_solver`)."""

    label: str
    xi: np.ndarray
    x: np.ndarray | None = None
    lam_g: np.ndarray | None = None
    lam_x: np.ndarray | None = None
    #: the horizon the velocities were made for (a coarser grid's solved T): a free horizon
    #: starts there rather than at the problem's guess, so the path keeps its length
    T: float | None = None


@dataclass
class RawResult:
    """What IPOPT returned for one start, before diagnostics."""

    label: str
    x: np.ndarray
    p: np.ndarray
    lam_g: np.ndarray
    cost: float
    status: str
    success: bool
    iterations: int
    solve_seconds: float
    lam_x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: which solver produced it: ``ipopt``, ``fatrop``, or ``ipopt after fatrop`` (fatrop
    #: failed and IPOPT solved from the same start; solve_seconds counts both)
    backend: str = "ipopt"


def _never() -> bool:
    return False


def casadi_name(name: str) -> str:
    """A valid CasADi Function name made from any problem name (a file's stem such as
    ``my-slew`` or ``2 slews``): runs of other characters than ASCII letters and digits become
    one ``_``, and a name that does not start with a letter gets ``p_`` in front
    (``my_slew``, ``p_2_slews``). The problem keeps its own name for display."""
    text = re.sub(r"[^A-Za-z0-9]+", "_", name[:64]).strip("_")
    return text if text[:1].isalpha() else f"p_{text}".rstrip("_")


class Transcription:
    """The compiled NLP of (problem, discretisation); solve it for any parameters p."""

    def __init__(self, problem: Problem, disc: Discretization,
                 ipopt: dict[str, Any] | None = None, jit: bool = False,
                 backend: str = DEFAULT_BACKEND) -> None:
        t0 = time.perf_counter()
        if backend not in BACKENDS:
            raise ConfigError(f"unknown solver backend {backend!r}; choose one of "
                              f"{', '.join(BACKENDS)}")
        if problem.cost is None:
            raise ConfigError(f"problem {problem.name!r} has no cost; call minimize()")
        check_order(problem)
        self.problem, self.disc, self.N = problem, disc, disc.N
        self.scheme = make_scheme(disc.scheme, problem, disc.N, disc.retraction, disc.rule,
                                  disc.bound_points)
        self.masks = Masks.of(problem.groupoid, problem.end_velocities, problem.start, problem.end)
        if disc.steps == "adaptive" and not self.scheme.adaptive_steps:
            raise ConfigError(
                f"adaptive steps need a scheme whose stages are intervals; {disc.scheme} for "
                f"order-{problem.order} problems has node stages: choose scheme order4")
        self.layout = Layout(problem, self.masks, self.scheme.n_stage, disc.N, disc.phases)
        self.scheme.index(self.layout)
        self.nx, self.np = self.layout.nx, self.layout.np
        self.values = ParameterValues(problem, self.masks, self.layout)
        self.final_check = FinalConditions(problem, self.masks, self.layout, self.scheme.stages)
        self.pack(T=problem.T or 1.0)  # over-determined final conditions raise here
        self.blocks = self.scheme.blocks() + self._final_blocks()
        t1 = time.perf_counter()
        x, p = ca.MX.sym("x", self.nx), ca.MX.sym("p", self.np)
        fns = assemble(self.blocks, x, p)
        t2 = time.perf_counter()
        self.ng = int(fns["g"].numel())
        self.nlp = {"x": x, "p": p, "f": fns["f"], "g": fns["g"]}
        #: the name of the IPOPT Function (and of its exported C code): safe for CasADi
        self.function_name = f"{casadi_name(problem.name)}_N{self.N}"
        self._options = nlpsol_options(ipopt, fns)
        #: compiled evaluation (:mod:`~ocgroupoid.nlp.jit`): whether on, and whether this
        #: build compiled its library (False: loaded from the cache)
        self.jit, self.jit_compiled = jit, False
        self.backend = backend
        if jit and backend == "ipopt":
            fns["nlp_f"] = ca.Function("nlp_f", [x, p], [fns["f"]], ["x", "p"], ["f"])
            fns["nlp_g"] = ca.Function("nlp_g", [x, p], [fns["g"]], ["x", "p"], ["g"])
            self._options["cache"], self.jit_compiled = compiled(fns)
        t_jit = time.perf_counter()
        self._watch: Watch | None = None
        try:
            self.solver = ca.nlpsol(self.function_name, "ipopt", self.nlp, self._options)
        except RuntimeError as err:
            raise ConfigError(f"IPOPT rejected the options {ipopt}: {err}") from None
        t3 = time.perf_counter()
        #: the time limit of one run of the backend (IPOPT's ``max_wall_time``)
        self.max_seconds = float({**DEFAULT_IPOPT, **(ipopt or {})}["max_wall_time"])
        self.bounds_function = self._bounds_function()
        #: the fatrop instance of the same NLP (solver.backend: fatrop), else None
        self.fatrop = FatropNLP(self.function_name, self.blocks, self.nx, self.np,
                                self.bounds_function, {**DEFAULT_IPOPT, **(ipopt or {})}, jit) \
            if backend == "fatrop" else None
        if self.fatrop is not None:  # compiled evaluation is the backend's
            self.jit_compiled = self.fatrop.jit_compiled
        t4 = time.perf_counter()
        self.f_fun = ca.Function("f", [x, p], [fns["f"]])
        self.g_fun = ca.Function("g", [x, p], [fns["g"]])
        self.build_seconds = time.perf_counter() - t0
        #: where the build time went: stage graphs and layout, derivative assembly, IPOPT setup
        self.build_phases = {"stages": t1 - t0, "assembly": t2 - t1, "jit": t_jit - t2,
                             "nlpsol": t3 - t_jit, "fatrop": t4 - t3}

    def _final_blocks(self) -> list[Block]:
        pb, G, N, lay, sch = self.problem, self.problem.groupoid, self.N, self.layout, self.scheme
        dg, nt = G.algebra_dim, G.target_size
        npar = pb.P.numel()
        out = []
        zN, stored = sch.final_state()
        nz = len(zN)
        if pb.terminal is not None:
            y = pb.y if pb.end_velocities else ca.SX.zeros(dg)
            phi = ca.substitute(pb.terminal, ca.vertcat(pb.y, pb.s, pb.q),
                                ca.vertcat(y, pb.s, G.base(pb.s)))
            terminal = ca.Function("terminal", [pb.s, pb.y, pb.P], [phi])
            out.append(Block("terminal", stage_function(
                "terminal", [nz, dg, npar], lambda z, v, par: (terminal(stored(z), v, par),
                                                               ca.SX(0, 1))),
                columns(zN, sch.end_velocity, lay.P, ncols=1), npar, Kind.COST))
        if lay.phases:
            lo, hi = STEP_RANGE
            n = ca.DM(lay.phases)
            M = len(lay.phases)
            mesh = stage_function("mesh", [M, 1], lambda t, T: (ca.SX(1, 1), ca.vertcat(
                ca.dot(n, t) / N - T, t - lo * T, hi * T - t)))
            out.append(Block("mesh", mesh, columns(lay.phase_steps, lay.T, ncols=1), 0,
                             Kind.MESH, ["sum of the steps - T"] +
                             [f"phase {i} step >= {lo} T/N" for i in range(M)] +
                             [f"phase {i} step <= {hi} T/N" for i in range(M)], [""],
                             bounds=(ca.SX(ca.DM.zeros(2 * M + 1)),
                                     ca.SX(ca.vertcat(0, ca.DM.inf(2 * M))))))
        if pb.weights["time"] > 0:
            w = pb.weights["time"]
            out.append(Block("time", stage_function("time", [1], lambda T: (w * T, ca.SX(0, 1))),
                             columns(lay.T, ncols=1), 0 if pb.T_free else 1, Kind.COST))
        rows = np.concatenate(self.masks.end_state)
        if rows.any():
            keep = np.flatnonzero(rows).tolist()
            chart = sch.stages.chart
            labels = [f"final.{f.state} " + (f"component {j}" if f.componentwise
                                             else f"(chart coordinate {j + 1})")
                      for f, m in zip(G.factors, self.masks.end_state)
                      for j in np.flatnonzero(m)]
            out.append(Block("final", stage_function(
                "final", [nz, nt], lambda z, tg: (ca.SX(1, 1), chart(stored(z), tg)[keep])),
                columns(zN, lay.end, ncols=1), nt, Kind.FINAL, labels, [""]))
        if self.problem.final_conditions:
            ends = sch.stages.final_conditions
            labels = [f"final condition {n!r}" for n, c in self.problem.final_conditions
                      for _ in range(c.numel())]
            out.append(Block("final_conditions", stage_function(
                "final_conditions", [nz, dg, npar],
                lambda z, v, par: (ca.SX(1, 1), ends(stored(z), v, par))),
                columns(zN, sch.end_velocity, lay.P, ncols=1), npar,
                Kind.FINAL_CONDITION, labels, [""]))
        return out

    def _bounds_function(self) -> ca.Function:
        """``bounds(p) -> (lbg, ubg, lbx, ubx)``: zero for equality rows, the problem's bounds
        (expressions of its parameters) for inequality rows; the horizon's bounds when free.
        IPOPT reads them at every solve: changing a bound never rebuilds the NLP."""
        pb = self.problem
        p = ca.SX.sym("p", self.np)
        P = p[self.layout.p_slices["P"]]
        lo, hi = [], []
        for b in self.blocks:
            if b.bounds is None:
                lo.append(ca.SX.zeros(b.m * b.ncols))
                hi.append(ca.SX.zeros(b.m * b.ncols))
            else:
                low, up = (ca.substitute(v, pb.P, P) for v in b.bounds)
                if b.kind is Kind.INEQUALITY and self.disc.active:
                    low, up = self._held(b, low, up)
                    lo.append(low)
                    hi.append(up)
                    continue
                lo.append(ca.repmat(low, b.ncols, 1))
                hi.append(ca.repmat(up, b.ncols, 1))
        lbx, ubx = ca.DM.ones(self.nx) * -np.inf, ca.DM.ones(self.nx) * np.inf
        if pb.T_free:
            lbx[int(self.layout.T[0])], ubx[int(self.layout.T[0])] = pb.T_bounds
        return ca.Function("bounds", [p], [ca.vertcat(*lo), ca.vertcat(*hi), lbx, ubx], ["p"],
                           ["lbg", "ubg", "lbx", "ubx"])

    def _held(self, b: Block, low: ca.SX, up: ca.SX) -> tuple[ca.SX, ca.SX]:
        """The sides of an inequality block column by column (interval by interval), with
        the rows a phase holds at one side turned into equalities there
        (:attr:`Discretization.active`)."""
        per_phase = np.repeat(np.arange(len(self.disc.phases)), self.disc.phases)
        # held at the first Gauss point of each interval, bounded at the others: one equality
        # per interval (more would over-determine the interval's unknowns where a problem has
        # conditions that its conservation laws already imply); the optimum holds the rest
        times = np.asarray(getattr(self.scheme, "bound_times", np.zeros(b.points)))
        gauss = np.isclose(times, GAUSS2[0])
        lo_cols, hi_cols = [], []
        for c in range(b.ncols):
            side = np.concatenate([np.asarray(self.disc.active[per_phase[c]]) * int(g)
                                   for g in gauss])
            lo_cols += [up[i] if side[i] > 0 else low[i] for i in range(low.numel())]
            hi_cols += [low[i] if side[i] < 0 else up[i] for i in range(up.numel())]
        return ca.vertcat(*lo_cols), ca.vertcat(*hi_cols)

    # -- constraint rows ----------------------------------------------------------------

    def rows(self, kind: Kind) -> np.ndarray:
        """Global constraint rows of every block of ``kind``, in block order: shaped
        (rows per column, columns) — for the path constraints, one column per time."""
        parts = [b.g_rows for b in self.blocks if b.kind is kind]
        return np.hstack(parts) if parts else np.zeros((0, 0), dtype=np.int64)

    def path_times(self) -> np.ndarray:
        """Times of the path-constraint columns, as fractions of T."""
        parts = [b.times for b in self.blocks if b.kind is Kind.PATH]
        return np.concatenate(parts) if parts else np.zeros(0)

    def row_labels(self) -> list[str]:
        """A readable name for every constraint row, e.g. ``final.R (chart coordinate 2)``."""
        return [label for b in self.blocks for label in b.labels()]

    # -- parameters ---------------------------------------------------------------------

    def pack(self, params: dict[str, Any] | None = None, initial: dict[str, Any] | None = None,
             final: dict[str, Any] | None = None, T: float | None = None) -> np.ndarray:
        """The parameter vector p: problem defaults overridden by the arguments.

        Overrides may change values but not which components are prescribed (that is the
        NLP's structure: change it on the Problem and build again).
        """
        pb, G = self.problem, self.problem.groupoid
        start = Boundary(dict(pb.start.states), dict(pb.start.velocities))
        end = Boundary(dict(pb.end.states), dict(pb.end.velocities))
        for bc, upd, label in ((start, initial, "initial"), (end, final, "final")):
            prescribe(bc, upd or {}, label, G, pb.end_velocities)
        if Masks.of(G, pb.end_velocities, start, end) != self.masks:
            raise BoundaryError(
                "the overrides change which boundary components are prescribed; that changes "
                "the NLP: set them on the Problem and build a new Transcription"
            )
        if T is None and pb.T is None:
            raise ConfigError("no horizon: give T or call problem.horizon(T)")
        values = np.zeros(self.values.size)
        P = pb.parameter_values(params)
        for b in self.values.blocks:
            end_name, _, name = b.key.partition(".")
            side = {"initial": start, "final": end}.get(end_name)
            given: ArrayLike | None
            if side is None:
                given = check_horizon(pb.T if T is None else T) if b.key == "T" else \
                    P[pb.parameter_slices[b.key]]
            else:
                given = side.states.get(name, side.velocities.get(name))
            if given is not None:
                values[b.values] = [0.0 if c is None else c for c in np.atleast_1d(
                    np.asarray(given, dtype=object))]
        p = self.values.pack(values)
        self.final_check.check(p)
        return p

    def part(self, p: np.ndarray, key: str) -> np.ndarray:
        """One part of p: ``P`` (physical parameters), ``start``/``end`` (packed targets),
        ``V0``/``VN`` (end velocities) or ``T``."""
        return np.asarray(p)[self.layout.p_slices[key]]

    def horizon_of(self, p: np.ndarray) -> float:
        """The horizon of the instance p (for a free horizon: its initial guess)."""
        return float(self.part(p, "T")[0])

    def horizon(self, x: np.ndarray, p: np.ndarray) -> float:
        """The horizon of a point (solved, when it is free)."""
        w = np.concatenate([np.asarray(x, dtype=float).ravel(), p])
        return float(w[self.layout.T][0])

    # -- the shared Functions -----------------------------------------------------------

    @cached_property
    def guess_labels(self) -> list[str]:
        """Labels of the geodesic guesses: the all-preferred one first, then one per
        alternative of each factor (the others kept preferred)."""
        return self._guesses(ca.MX.sym("p", self.np))[0]

    @cached_property
    def guess_function(self) -> ca.Function:
        """``guesses(p) -> (XI_1, ..., XI_m)``: the geodesic guesses of every factor as interval
        velocities (dim y x N), as graphs of p."""
        p = ca.MX.sym("p", self.np)
        labels, outs = self._guesses(p)
        return ca.Function("guesses", [p], outs, ["p"], [f"guess{i}" for i in range(len(outs))])

    def _guesses(self, p: ca.MX) -> tuple[list[str], list[ca.MX]]:
        G, N, lay = self.problem.groupoid, self.N, self.layout.p_slices
        T = p[lay["T"].start]
        start, end, V0, VN = (p[lay[k]] for k in ("start", "end", "V0", "VN"))
        per = [f.guesses(r, start[ts], end[ts], V0[vs], VN[vs], T, N, self.masks.factor(G, i))
               for i, (f, r, ts, vs) in enumerate(zip(
                   G.factors, self.scheme.retractions, G.target_layout.slices,
                   G.velocity_layout.slices))]
        first = [alts[0] for alts in per]
        labels = [" + ".join(name for name, _ in first)]
        outs = [ca.vertcat(*[xi for _, xi in first])]
        for i, alts in enumerate(per):
            for name, xi in alts[1:]:
                labels.append(name)
                outs.append(ca.vertcat(*[a[0][1] if j != i else xi for j, a in enumerate(per)]))
        return labels, outs

    @cached_property
    def point_function(self) -> ca.Function:
        """``point(XI, p) -> x``: the NLP point of interval velocities XI (dim y x N)."""
        XI = ca.MX.sym("XI", self.problem.groupoid.algebra_dim, self.N)
        p = ca.MX.sym("p", self.np)
        x = ca.MX.zeros(self.nx)  # free initial components start at zero
        T_guess = p[int(self.layout.T_guess[0] - self.nx)]
        for i in {*self.layout.T.tolist(), *self.layout.phase_steps.tolist()}:
            if i < self.nx:  # a free horizon at its guess, adaptive steps uniform
                x[int(i)] = T_guess
        w = ca.vertcat(x, p)
        pick = lambda idx: self.layout.gather(w, idx)  # noqa: E731
        grid = [(idx, pick(idx)) for idx in (self.layout.T, self.layout.phase_steps)]
        x0 = self.layout.compose(self.scheme.point(XI, pick) + grid)
        return ca.Function("point", [XI, p], [x0], ["XI", "p"], ["x"])

    @cached_property
    def readout_function(self) -> ca.Function:
        """``readout(x, p, lam_g)``: what a solution reports (:data:`READOUT_OUTPUTS`), each a
        (width x count) matrix with one column per time."""
        G = self.problem.groupoid
        x, p, lam = ca.MX.sym("x", self.nx), ca.MX.sym("p", self.np), ca.MX.sym("lam_g", self.ng)
        w = ca.vertcat(x, p)
        pick = lambda idx: self.layout.gather(w, idx)  # noqa: E731
        r = self.scheme.readout(pick)
        x_rec = self.layout.compose([(np.arange(self.nx), x), *self.scheme.reconstructed(r)])
        T = pick(self.layout.T)
        steps = pick(self.layout.steps[None, :]) / self.N  # 1 x N step sizes
        nodes = ca.vertcat(0, ca.cumsum(steps.T))  # node times, a column
        s = ca.SX.sym("s", G.state_size)
        shown = ca.Function("shown", [s], [G.shown(s)])
        path, final = self.rows(Kind.PATH), self.rows(Kind.FINAL)
        lam_path = ca.reshape(lam[path.ravel(order="F").tolist()], *path.shape) if path.size \
            else ca.MX(0, 1)
        lam_final = lam[final.ravel().tolist()] if final.size else ca.MX(0, 1)
        def times(frac: np.ndarray) -> ca.MX:
            """Times of fractions of the horizon on this grid: T frac for uniform steps; with
            adaptive steps, interval k = floor(frac N) at its own fraction."""
            frac = np.asarray(frac, dtype=float)
            if not self.layout.phases:
                return T * ca.DM(frac).T
            u = frac * self.N
            k = np.minimum(np.floor(u), self.N - 1).astype(int).tolist()
            if not k:
                return ca.MX(1, 0)
            return (nodes[k] + ca.DM(u - k) * ca.vec(steps)[k]).T

        outs = [x_rec, times(np.arange(self.N + 1) / self.N),
                shown.map(self.N + 1)(r.states), r.states, times(r.velocity_t), r.velocities,
                times(r.control_t), r.controls, times(self.path_times()), lam_path, lam_final,
                times(r.control_breaks), r.control_coefficients, r.steps]
        return ca.Function("readout", [x, p, lam], [ca.densify(o) for o in outs],
                           ["x", "p", "lam_g"], list(READOUT_OUTPUTS))

    # -- numeric evaluation -------------------------------------------------------------

    def guesses(self, p: np.ndarray) -> list[Guess]:
        """The geodesic guesses (see :attr:`guess_labels`) of the instance p."""
        outs = self.guess_function(p)
        outs = outs if isinstance(outs, (list, tuple)) else [outs]
        return [Guess(label, np.array(xi).T) for label, xi in zip(self.guess_labels, outs)]

    def point(self, guess: Guess, p: np.ndarray) -> np.ndarray:
        """NLP point of a guess (:attr:`point_function`)."""
        xi = np.asarray(guess.xi, dtype=float)
        dg = self.problem.groupoid.algebra_dim
        if xi.shape != (self.N, dg):
            raise ConfigError(f"guess {guess.label!r} has shape {xi.shape}, "
                              f"expected {(self.N, dg)}")
        return np.array(self.point_function(xi.T, p)).ravel()

    def readout(self, x: np.ndarray, p: np.ndarray, lam_g: np.ndarray | None = None
                ) -> dict[str, np.ndarray]:
        """The read-out of a point, one row per time (``x_solution``: a flat vector)."""
        lam = np.zeros(self.ng) if lam_g is None else lam_g
        outs = self.readout_function(x, p, lam)
        res = {k: np.array(v).T for k, v in zip(READOUT_OUTPUTS, outs)}
        res["x_solution"] = res["x_solution"].ravel()
        for k in ("t", "velocity_t", "control_t", "multiplier_t", "control_breaks"):
            res[k] = res[k].ravel()
        res["final_multipliers"] = res["final_multipliers"].ravel()
        return res

    def unpack(self, x: np.ndarray, p: np.ndarray) -> dict[str, np.ndarray]:
        """The scheme's variables of an NLP point, by name (e.g. ``xi``, ``s``, ``T``)."""
        return self.scheme.unpack(np.concatenate([np.asarray(x, dtype=float).ravel(), p]))

    # -- solving ------------------------------------------------------------------------

    @cached_property
    def watched_solver(self) -> ca.Function:
        """:attr:`solver` with an iteration callback (:mod:`~ocgroupoid.nlp.watch`), built on
        first use (the plain :attr:`solver` stays free of Python, for the C export)."""
        self._watch = Watch(self.nx, self.ng, self.np)
        return ca.nlpsol(self.function_name, "ipopt", self.nlp,
                         {**self._options, "iteration_callback": self._watch})

    @cached_property
    def warm_solver(self) -> ca.Function:
        """:attr:`solver` started from a given primal-dual point (IPOPT's
        ``warm_start_init_point``, its bound pushes small and mu_init low, so that a point
        near the solution stays near it), built on first use."""
        return ca.nlpsol(self.function_name, "ipopt", self.nlp, {**self._options, **WARM_IPOPT})

    def solve(self, guess: Guess, p: np.ndarray | None = None,
              listener: Listener | None = None, deadline: float | None = None,
              stop: Callable[[], bool] | None = None) -> RawResult:
        """Run the backend from ``guess`` with parameters ``p`` (default: the problem's).
        With IPOPT, ``listener(iteration, objective, infeasibility)`` hears every iteration
        and stops IPOPT by returning True (status ``User_Requested_Stop``), and a guess with
        multipliers is a primal-dual warm start (:attr:`warm_solver`; no listener). fatrop
        has neither: it starts from the guess's primal point, in a helper process that is
        stopped at ``deadline`` (``time.monotonic()``; default: :attr:`max_seconds` from now),
        after repeated NaN evaluations, or once ``stop()`` is true; when it fails (its Riccati
        recursion needs every stage's reduced Hessian positive definite, and regularises until
        it is: slow or stuck on some nonconvex problems) IPOPT solves from the same start
        with the time left. A run that used up the time has status
        ``Maximum_WallTime_Exceeded``."""
        p = self.pack() if p is None else np.asarray(p, dtype=float)
        if guess.T is not None and self.problem.T_free and guess.x is None:
            p = p.copy()
            p[self.layout.p_slices["T"]] = guess.T
        x0 = guess.x if guess.x is not None and guess.x.size == self.nx else self.point(guess, p)
        if deadline is None:
            deadline = time.monotonic() + self.max_seconds
        first = None
        if self.fatrop is not None:
            first = self.fatrop.solve(x0, p, deadline - time.monotonic(), stop or _never)
            if first.success or first.status in (TIMED_OUT, INTERRUPTED):
                cost = first.f if first.success else float(self.f_fun(first.x, p))
                return RawResult(guess.label, first.x, p, first.lam_g, cost, first.status,
                                 first.success, first.iterations, first.seconds, first.lam_x,
                                 "fatrop")
        lbg, ubg, lbx, ubx = self.bounds_function(p)
        warm = self._warm(guess)
        solver = self.solver
        duals: dict[str, np.ndarray] = {}
        if warm and guess.lam_g is not None and guess.lam_x is not None:  # (as _warm checked)
            solver, duals = self.warm_solver, {"lam_g0": guess.lam_g, "lam_x0": guess.lam_x}
        elif listener is not None:
            solver = self.watched_solver
            assert self._watch is not None
            self._watch.start(listener, np.array(lbg).ravel(), np.array(ubg).ravel())
        t0 = time.perf_counter()
        r = solver(x0=x0, p=p, lbg=lbg, ubg=ubg, lbx=lbx, ubx=ubx, **duals)
        seconds = time.perf_counter() - t0
        stats = solver.stats()
        status = str(stats["return_status"])
        iterations = 0 if status == "Not_Enough_Degrees_Of_Freedom" else int(stats["iter_count"])
        return RawResult(guess.label, np.array(r["x"]).ravel(), p, np.array(r["lam_g"]).ravel(),
                         float(r["f"]), status, bool(stats["success"]), iterations,
                         seconds + (first.seconds if first else 0.0),
                         np.array(r["lam_x"]).ravel(),
                         "ipopt after fatrop" if first else "ipopt")

    def solve_graph(self, x0: ca.MX, p: ca.MX, lam_g0: ca.MX | None = None,
                    lam_x0: ca.MX | None = None) -> dict[str, ca.MX]:
        """A solve from x0 as a graph (``x, f, g, lam_g, lam_x``) with the bounds of
        :attr:`bounds_function`: the backend's nlpsol inside, for the exported C solver.
        With multipliers, IPOPT's primal-dual warm start (:attr:`warm_solver`); fatrop has
        none and starts from x0."""
        if self.fatrop is not None:
            return self.fatrop.graph(x0, p)
        lbg, ubg, lbx, ubx = self.bounds_function(p)
        duals: dict[str, ca.MX] = {}
        if lam_g0 is not None and lam_x0 is not None:
            duals = {"lam_g0": lam_g0, "lam_x0": lam_x0}
        solver = self.warm_solver if duals else self.solver
        r = solver(x0=x0, p=p, lbg=lbg, ubg=ubg, lbx=lbx, ubx=ubx, **duals)
        return {k: r[k] for k in ("x", "f", "g", "lam_g", "lam_x")}

    def _warm(self, guess: Guess) -> bool:
        """Whether ``guess`` is a primal-dual point of this NLP (sizes match)."""
        return (guess.x is not None and guess.x.size == self.nx and guess.lam_g is not None
                and guess.lam_g.size == self.ng and guess.lam_x is not None
                and guess.lam_x.size == self.nx)
