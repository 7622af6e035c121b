"""``solver.backend: ipopt``: IPOPT on the whole sparse KKT system (MUMPS), through
``casadi.nlpsol``, with the stage-wise assembled derivatives in its cache.

Instances of the one NLP, all but the first built on first use: the plain solver (free of
Python: the exported C solver calls it), one with an iteration callback
(:mod:`~ocgroupoid.nlp.watch`: progress, Ctrl-C and the deadline), one started from a
primal-dual point (IPOPT's ``warm_start_init_point``) and that one with the callback (a
warm start someone listens to: a polish after fatrop, a sweep's neighbour), and the two
started from multipliers carried from a coarser grid (:data:`CARRIED_IPOPT`).
"""

from __future__ import annotations

import time
from functools import cached_property
from typing import Any

import casadi as ca

from ...errors import ConfigError
from ..buffered import Buffered
from ..jit import compiled
from ..options import MAX_SECONDS, SolverOptions
from ..watch import Watch
from .base import Backend, Graph, Run, Start

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
    # MUMPS's workspace: its estimate and 100 % more, not IPOPT's 1000 % more. The larger
    # one is allocated afresh at every factorisation and its page faults were 15-20 % of the
    # KKT solves' wall time at N = 256 (scripts/bench_setting.py, 2026-12-02, order4+jit: the
    # quadrotor 486 -> 410 ms, quadrotor_min_time 1462 -> 1273 ms, the reaction wheels 628 ->
    # 529 ms; rk4_quat+jit on the quadrotor 279 -> 224 ms); smaller KKT systems unchanged,
    # the same iterations and costs. MUMPS asks for more when it needs it and IPOPT grows
    # the workspace then (no file did with order4 or rk4_quat, even at 20 %; the Dubins car
    # with order6 at N = 256 does, at 1000 % too: its pivots are delayed, see
    # docs/benchmarks/performance.md on mumps_permuting_scaling)
    "mumps_mem_percent": 100,
    # second-order corrections of a rejected trial step: 10, not IPOPT's 4. From the
    # cart-pole's first guess order6's filter rejected 10 steps in a row (5 halvings each,
    # 28-37 iterations); with more corrections its fourth step is accepted whole: 30, 28,
    # 29 -> 19, 20, 25 iterations at N = 16, 32, 64, the same minima (2026-12-02). No other
    # problem file changes (order4 and order6, N = 16, 64, 256, from the first guess; the
    # cart-pole's four starts at N = 64; rk4_quat on the cart-pole)
    "max_soc": 10,
    # a rank-deficient constraint Jacobian is regularised by 1e-6 mu^(1/4), not IPOPT's
    # 1e-8 mu^(1/4). The plate-ball's first guess (a straight roll) is a singular point of
    # its endpoint map: one direction of the final orientation is reached only through the
    # Lie bracket of the rolling fields, so the linearised constraints lose rank there. At
    # 1e-8 the first step solved a nearly singular KKT system (|d| ~ 1e5, iterative refinement
    # failing) and its direction was decided by rounding: order4 at N = 64 took 88 iterations
    # (64 of them restoring feasibility), or 35 with the Runge-Kutta matrix one ulp off; now
    # 27 whatever the rounding, the same minima. From the first guess only the plate-ball
    # changes at N = 16...128 (every file, order2/4/6) and quadrotor_min_time's order6 at
    # N = 256 (71 -> 49 iterations), 2026-12-02: docs/benchmarks/performance.md
    "jacobian_regularization_value": 1e-6,
    "print_level": 0,
    "sb": "yes",
}

#: IPOPT options of a primal-dual warm start (:attr:`IpoptBackend.warm_solver`)
WARM_IPOPT: dict[str, Any] = {
    "ipopt.warm_start_init_point": "yes", "ipopt.warm_start_bound_push": 1e-9,
    "ipopt.warm_start_slack_bound_push": 1e-9, "ipopt.warm_start_mult_bound_push": 1e-9,
    "ipopt.mu_init": 1e-6}

#: IPOPT options of a start whose multipliers were carried from a coarser grid
#: (:mod:`~ocgroupoid.solve.multipliers`, :attr:`Start.carried`): :data:`WARM_IPOPT` with the
#: bound pushes at 1e-5. Such a point is not near the fine grid's solution as a polish's or a
#: controller's is: its controls, made from interpolated velocities, cross their bounds where
#: the coarse ones switched (``quadrotor_min_time`` from N = 16 to 32: 221 rows violated by
#: more than 1e-3, up to 24.7), and slacks pushed 1e-9 inside their bounds cut IPOPT's first
#: steps to alpha 4e-6. Measured with IPOPT from N/2 to N = 16...256 on five bounded files
#: (2026-12-04, pushes 1e-9 / 1e-5 / cold): ``quadrotor_min_time`` 41 / 26 / 23 iterations at
#: N = 16, 37 / 24 / 27 at 32, 19 / 15 / 35 at 128; the cart-pole 26 / 14 / 20 at 64;
#: ``dubins_car`` 24 / 10 / 17 at 32; fewer or as many with 1e-5 in all 25 cases. A polish
#: after fatrop wants the small pushes (``quadrotor_min_time`` at N = 256: 7 iterations, 16
#: with 1e-5), a controller's re-solve either (so3 and the free flyer: the same).
CARRIED_IPOPT: dict[str, Any] = {
    **WARM_IPOPT, "ipopt.warm_start_bound_push": 1e-5,
    "ipopt.warm_start_slack_bound_push": 1e-5, "ipopt.warm_start_mult_bound_push": 1e-5}


def ipopt_options(options: SolverOptions) -> dict[str, Any]:
    """IPOPT's options of each run: :data:`DEFAULT_IPOPT` overridden by the solve's
    (:attr:`SolverOptions.run_ipopt`)."""
    return {**DEFAULT_IPOPT, **options.run_ipopt}


def nlpsol_options(ipopt: dict[str, Any] | None, fns: dict[str, ca.Function]) -> dict[str, Any]:
    """Options of ``casadi.nlpsol``: IPOPT's (defaults overridden by ``ipopt``) and the
    assembled derivative functions in its cache, so that it derives none itself."""
    opts: dict[str, Any] = {f"ipopt.{k}": v for k, v in {**DEFAULT_IPOPT, **(ipopt or {})}.items()}
    opts.update({"print_time": False, "calc_lam_p": False, "show_eval_warnings": False,
                 "cache": {k: fns[k] for k in ("nlp_grad_f", "nlp_jac_g", "nlp_hess_l")}})
    return opts


def evaluated(nlp: Graph) -> dict[str, ca.Function]:
    """The Functions IPOPT evaluates (:data:`~ocgroupoid.nlp.jit.NLP_FUNCTIONS`): the
    assembled derivatives, and f and g as Functions of their own, to be compiled with them."""
    x, p = nlp.nlp["x"], nlp.nlp["p"]
    return {**nlp.functions,
            "nlp_f": ca.Function("nlp_f", [x, p], [nlp.nlp["f"]], ["x", "p"], ["f"]),
            "nlp_g": ca.Function("nlp_g", [x, p], [nlp.nlp["g"]], ["x", "p"], ["g"])}


class IpoptBackend(Backend):
    """IPOPT for one NLP (module docstring); ``jit`` compiles its Functions, unless they are
    given as ``compiled_functions`` (:func:`evaluated`, compiled beside fatrop's)."""

    name = "ipopt"

    def __init__(self, nlp: Graph, options: SolverOptions, jit: bool = False,
                 compiled_functions: dict[str, ca.Function] | None = None) -> None:
        self.nx, self.ng, self.np = nlp.nx, nlp.ng, nlp.np
        self.function_name, self.nlp, self.bounds = \
            nlp.function_name, nlp.nlp, nlp.bounds_function
        self.options = nlpsol_options(options.run_ipopt, nlp.functions)
        t0 = time.perf_counter()
        if compiled_functions is not None:
            self.options["cache"] = compiled_functions
        elif jit:
            (self.options["cache"],), self.jit_compiled, _ = compiled(evaluated(nlp))
        #: the compilation of jit (or the load from its cache)
        self.jit_seconds = time.perf_counter() - t0
        t0 = time.perf_counter()
        self._calls: dict[int, Buffered] = {}
        try:
            #: the plain IPOPT instance (no Python inside: the exported C solver's)
            self.solver = ca.nlpsol(self.function_name, "ipopt", self.nlp, self.options)
        except RuntimeError as err:
            raise ConfigError(f"IPOPT rejected the options {options.run_ipopt}: {err}") \
                from None
        #: the time nlpsol took to set IPOPT up
        self.setup_seconds = time.perf_counter() - t0

    @cached_property
    def watch(self) -> Watch:
        """The iteration callback of the watched instances (:mod:`~ocgroupoid.nlp.watch`),
        armed per solve."""
        return Watch(self.nx, self.ng, self.np)

    def _instance(self, *extra: dict[str, Any]) -> ca.Function:
        """Another IPOPT instance of the NLP: :attr:`options` with ``extra`` over them."""
        options = dict(self.options)
        for more in extra:
            options.update(more)
        return ca.nlpsol(self.function_name, "ipopt", self.nlp, options)

    @cached_property
    def watched_solver(self) -> ca.Function:
        """:attr:`solver` with the iteration callback (:attr:`watch`), built on first use (the
        plain :attr:`solver` stays free of Python, for the C export)."""
        return self._instance({"iteration_callback": self.watch})

    @cached_property
    def warm_solver(self) -> ca.Function:
        """:attr:`solver` started from a given primal-dual point (IPOPT's
        ``warm_start_init_point``, its bound pushes small and mu_init low, so that a point
        near the solution stays near it), built on first use."""
        return self._instance(WARM_IPOPT)

    @cached_property
    def watched_warm_solver(self) -> ca.Function:
        """:attr:`warm_solver` with the iteration callback (:attr:`watch`), built on first
        use."""
        return self._instance(WARM_IPOPT, {"iteration_callback": self.watch})

    @cached_property
    def carried_solver(self) -> ca.Function:
        """:attr:`solver` started from multipliers carried from a coarser grid
        (:data:`CARRIED_IPOPT`), built on first use."""
        return self._instance(CARRIED_IPOPT)

    @cached_property
    def watched_carried_solver(self) -> ca.Function:
        """:attr:`carried_solver` with the iteration callback (:attr:`watch`), built on first
        use."""
        return self._instance(CARRIED_IPOPT, {"iteration_callback": self.watch})

    def run(self, start: Start) -> Run:
        """IPOPT from ``start``: warm (:attr:`warm_solver`, or :attr:`carried_solver` for
        multipliers carried from a coarser grid) when it carries multipliers, and watched
        (:attr:`watched_solver`, :attr:`watched_warm_solver`,
        :attr:`watched_carried_solver`) when someone listens. Its deadline is IPOPT's own
        ``max_wall_time`` and the listener's (which stops IPOPT by returning True), warm or
        cold."""
        watched = start.listener is not None  # (a solver built on first use: before t0)
        if not start.warm:
            solver = self.watched_solver if watched else self.solver
        elif start.carried:
            solver = self.watched_carried_solver if watched else self.carried_solver
        else:
            solver = self.watched_warm_solver if watched else self.warm_solver
        call = self._call(solver)
        t0 = time.perf_counter()
        bounds = self._call(self.bounds)(p=start.p)
        duals = {"lam_g0": start.lam_g0, "lam_x0": start.lam_x0} if start.warm else {}
        if start.listener is not None:
            self.watch.start(start.listener, bounds["lbg"], bounds["ubg"])
        r = call(x0=start.x0, p=start.p, **bounds, **duals)
        seconds = time.perf_counter() - t0
        stats = call.stats()
        status = str(stats["return_status"])
        iterations = 0 if status == "Not_Enough_Degrees_Of_Freedom" else int(stats["iter_count"])
        return Run(r["x"], float(r["f"][0]), r["lam_g"], r["lam_x"], status,
                   bool(stats["success"]), iterations, seconds)

    def _call(self, fn: ca.Function) -> Buffered:
        """The buffered calls of ``fn`` (:mod:`~ocgroupoid.nlp.buffered`), made once."""
        if id(fn) not in self._calls:  # each holds its Function: the ids stay distinct
            self._calls[id(fn)] = Buffered(fn)
        return self._calls[id(fn)]

    def graph(self, x0: ca.MX, p: ca.MX, lam_g0: ca.MX | None = None,
              lam_x0: ca.MX | None = None) -> dict[str, Any]:
        """The solve from x0 as a graph, with the bounds of p; with multipliers, IPOPT's
        primal-dual warm start (:attr:`warm_solver`)."""
        lbg, ubg, lbx, ubx = self.bounds(p)
        duals: dict[str, ca.MX] = {}
        if lam_g0 is not None and lam_x0 is not None:
            duals = {"lam_g0": lam_g0, "lam_x0": lam_x0}
        solver = self.warm_solver if duals else self.solver
        r = solver(x0=x0, p=p, lbg=lbg, ubg=ubg, lbx=lbx, ubx=ubx, **duals)
        return {k: r[k] for k in ("x", "f", "g", "lam_g", "lam_x")}
