"""``solver.backend: fatrop``: the NLP in stage form, solved by fatrop's Riccati recursion.

IPOPT factorises the KKT system of the whole NLP as one sparse matrix (MUMPS). fatrop, an
interior-point method of the same family that CasADi ships, factorises it stage by stage, in
time linear in N with small dense blocks. It needs the NLP in stage form
(:mod:`~ocgroupoid.nlp.stageform`), which every scheme's blocks give. The derivatives are the
same stage-wise assembly IPOPT gets (:func:`~ocgroupoid.nlp.assembly.assemble`), with the
rows permuted into stage order and in the signatures fatrop asks for (the Hessian whole, not
its upper triangle, with the gradient of the Lagrangian, both summed from the stages).

The Functions (compiled with ``jit``, else evaluated by CasADi) drive fatrop through its own
C interface (:mod:`~ocgroupoid.nlp.backends.fatrop_ocp`), the same solve to the last bit as
CasADi's fatrop ``nlpsol``, whose build grows as N² (so3 at N = 1024: 2.4-3.3 s, against 0.34 s);
the exported C solver runs the same driver (:attr:`FatropBackend.exported`), and CasADi's
``nlpsol`` runs where the driver does not compile.

fatrop reads the IPOPT options it shares (:data:`SHARED_OPTIONS`, :data:`RENAMED_OPTIONS`)
over its own (:data:`DEFAULT_FATROP`: no watchdog, more second-order corrections). It has no
scaling of its own: it is given the NLP scaled as IPOPT scales it (:func:`row_scales`,
:func:`_scales`), its rows and cost multiplied by factors computed at the start and passed
as parameters, and its solution is mapped back (:meth:`FatropBackend.unscaled`). It has no
dual warm start (a warm start gives it the primal point), no iteration callback (the driver
makes one: it asks the listener at each iteration's Hessian and stops fatrop by lowering its
``max_iter``), no time limit, and it loops without bound on some singular KKT systems. Every
solve is therefore guarded: it is left at its deadline, after repeated NaN evaluations, on
Ctrl-C, or once it runs longer than its iterations can take (:data:`STUCK_SECONDS`). Through
the own interface on Linux the guard is the driver's (``fatrop_guard.c``: a jump back out of
fatrop, from its callbacks or from a timer signal), and the solve runs in this process;
elsewhere it runs in a helper process (:mod:`~ocgroupoid.nlp.isolated`), which is killed.
The helper's way there and back was about half of a small solve (so3 at N = 4: 1.33 ms
against 0.65 ms in this process).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np

from ...errors import ConfigError
from .. import isolated
from ..assembly import Derivatives, assemble
from ..buffered import Buffered
from ..isolated import Isolated, Stopped
from ..jit import compiled
from ..options import SolverOptions
from ..stageform import NotStaged, StageForm, stage_form
from ..watch import Listener
from .base import ACCEPTABLE, INTERRUPTED, LISTENER_STOP, TIMED_OUT, Backend, Graph, Run, Start
from .fatrop_ocp import (
    FATROP_MAX_ITER,
    BlockMaps,
    FatropOcp,
    Guard,
    Unavailable,
    block_maps,
    option_kinds,
)
from .ipopt import ipopt_options

#: IPOPT options fatrop also has; the others do not apply to it
SHARED_OPTIONS = ("tol", "max_iter", "mu_init", "bound_push", "bound_frac", "constr_viol_tol",
                  "acceptable_iter")
#: fatrop's own options where its defaults fail (measured with ``scripts/bench_fatrop.py``:
#: every problem file, its scheme and order2, N = 16 to 256). From a start nearly feasible but
#: far from the optimum (the cart-pole's geodesic guess: infeasibility 8e-3, cost 0.06 against
#: 49.6) the Newton step is long and the constraints' curvature along it raises the
#: infeasibility, so that the filter accepts only steps of alpha ~ 5e-3 (IPOPT as well).
#: fatrop's watchdog, woken after 10 such steps, fails, and so does the restoration phase it
#: then enters ("locally infeasible": the cart-pole at N >= 32, order2 at N >= 128); given
#: more trial steps its watchdog runs away instead (heavy_top_rotors order4, N = 32: dual
#: infeasibility 1e17, then an endless inertia correction). Without the watchdog and with up
#: to 20 second-order corrections (fatrop's default 4; each must cut the infeasibility by
#: kappa_soc = 0.99) the full step is corrected back onto the constraints and accepted: the
#: cart-pole order4 at N = 32, 64, 128, 256 converges in 25, 32, 30, 40 iterations (IPOPT 27,
#: 56, 67, 59; without the watchdog alone 77, 127, 243, 490; since fatrop gets IPOPT's scaling
#: of the file's rows, 17, 21, 24, 33). Every other run takes at most
#: one iteration more than before or fewer (heavy_top_rotors order2 at N = 32 to 256: 21-22,
#: were 23-28), except heavy_top_rotors order2 at N = 16 (28, was 23; IPOPT 22)
DEFAULT_FATROP: dict[str, Any] = {"watchdog_shortened_iter_trigger": 0, "max_soc": 20}
#: the longest a fatrop run may take before it counts as stuck: :data:`STUCK_FLOOR` seconds
#: and :data:`STUCK_SECONDS` per variable and iteration up to ``max_iter``. Measured on every
#: problem file (order4, fatrop, jit, from the first guess): 1.2-4.1 us per variable and
#: iteration at N = 64 and 256, so 10 times the most; 1.6-9 us at N = 8, where the call's
#: fixed cost of about a millisecond weighs, and which the floor covers. fatrop has no time
#: limit and prints nothing below print_level 5 (whose output, through CasADi's Python hook,
#: costs 0.3-0.7 ms a solve), and on a singular KKT system its inertia correction loops
#: without printing or returning (heavy_top_rotors, order4, N = 8, "great circle, long way":
#: 41 iterations in 15 ms, then nothing until the deadline, 600 s by default): past this
#: limit the run has failed, and IPOPT solves the start with the time left
STUCK_FLOOR, STUCK_SECONDS = 5.0, 40e-6
#: fatrop's stop at an acceptable point: its error below ``tol_acceptable`` for
#: ``acceptable_iter`` iterations in a row. Near some solutions with active bounds fatrop
#: calls its KKT system indefinite and regularises it in every iteration, and its last steps
#: converge linearly, or not at all (quadrotor_min_time, N = 256: 500 iterations, 38 s, the
#: dual infeasibility stuck at 1e-7); IPOPT finishes from the point it reached, with its
#: multipliers, in a few iterations (:func:`~ocgroupoid.nlp.backends.policy.in_turn`). With
#: fatrop's own tolerance (1e-6) and 50 iterations in a row it crawled 123 iterations there
#: before IPOPT's 6 (11.4 s in all, one run); from the multi-start's "long way round" 158 + 5
#: at N = 64 (1.21 s), 99 + 4 at N = 128 (1.29 s), 81 + 4 at N = 256 (2.42 s). With 1e-5 and
#: 20 it stops after 51 + 7 (5.9 s), 44 + 7 (0.46 s), 59 + 4 (0.88 s), 43 + 6 (2.12 s), the
#: same costs. A run that converges stays fatrop's: of the 120 runs of
#: scripts/bench_fatrop.py (every problem file, N = 16 to 256, 4-63 iterations) one other
#: changed, so3_minimum_time order2 at N = 64, 35 iterations to 33 + 2 (10 iterations in a
#: row stopped two converging runs: quadrotor_min_time order4 at N = 64 after 31 of 32)
ACCEPTABLE_STOP: dict[str, Any] = {"tol_acceptable": 1e-5, "acceptable_iter": 20}
#: IPOPT options fatrop has under another name: constr_mult_init_max 0 (our default: start from
#: zero multipliers, not least-squares ones) is fatrop's lam_max 0 (measured on so3, N = 256:
#: 7 -> 4 iterations, as IPOPT's; the other problem files unchanged); acceptable_tol is
#: fatrop's tol_acceptable (:data:`ACCEPTABLE_STOP`); perturb_dec_fact (how fast the
#: Hessian's regularisation falls back, 1/3 by default) is fatrop's kappa_wmin
RENAMED_OPTIONS = {"constr_mult_init_max": "lam_max", "acceptable_tol": "tol_acceptable",
                   "perturb_dec_fact": "kappa_wmin"}
#: what a failed fatrop solve reports where IPOPT has no name for the reason
FAILED = "Fatrop_Failed"
#: fatrop's return flags (``stats()["fatrop"]["return_flag"]``, its ``IpSolverReturnFlag``)
#: by IPOPT's name for the same outcome; CasADi counts only flag 0 as success, so a stop at
#: an acceptable point (flag 2: the error below ``tol_acceptable`` for ``acceptable_iter``
#: iterations, not below ``tol``) is not one, as IPOPT's is not for the verdict
#: (:mod:`~ocgroupoid.verify.verdict`), and IPOPT finishes from its point (:data:`ACCEPTABLE_STOP`)
STATUS = {0: "Solve_Succeeded", 1: "Maximum_Iterations_Exceeded", 2: ACCEPTABLE,
          3: "Infeasible_Problem_Detected"}
#: what one solve returns, in the original variables and rows (:meth:`FatropBackend.unscaled`)
UNSCALED = ("x", "f", "g", "lam_g", "lam_x")
#: fatrop relaxes every inequality bound by this factor, as IPOPT's default
#: ``bound_relax_factor`` (``lb - eps max(1, |lb|)``), and has no option to turn it off: the
#: bounds it is given are tightened by as much, so that they hold at the solution to
#: O(eps^2) as with IPOPT's ``bound_relax_factor: 0`` (measured: violations 5e-8 -> 1e-15)
BOUND_RELAX = 1e-8


def tightened(bounds: ca.Function, sf: StageForm) -> ca.Function:
    """``fatrop_bounds(p, s) -> (lbg, ubg, lbx, ubx)``: the bounds of ``bounds(p) -> (lbg, ubg,
    lbx, ubx)`` in stage form (:class:`StageForm`), the rows multiplied by their scales ``s``
    (:func:`_scales`), then every inequality bound moved inwards by fatrop's relaxation
    (:data:`BOUND_RELAX`, in the scaled units fatrop relaxes in); equalities (lb = ub) and
    infinite bounds as they are, and bounds closer than the two moves meet at their
    midpoint."""
    # built as whole-vector MX operations and then expanded: the same SX graph (bit-identical
    # bounds, as fast a call) built in 40 ms at N = 1024 where the SX expressions took 67 ms
    p, s = ca.MX.sym("p", bounds.size1_in(0)), ca.MX.sym("s", sf.order.size)
    lbg, ubg, lbx, ubx = bounds(p)
    staged = [s * sf.rows_z(lbg), s * sf.rows_z(ubg), *sf.bounds_z(lbx, ubx)]
    out = []
    for lb, ub in zip(*[iter(staged)] * 2):
        lo = lb + BOUND_RELAX * ca.fmax(1.0, ca.fabs(lb))
        up = ub - BOUND_RELAX * ca.fmax(1.0, ca.fabs(ub))
        finite_lo, finite_up = lb > -np.inf, ub < np.inf
        cross = finite_lo * finite_up * (lo > up)
        mid = (lb + ub) / 2
        moved = lb < ub
        out.append(ca.if_else(moved * finite_lo, ca.if_else(cross, mid, lo), lb))
        out.append(ca.if_else(moved * finite_up, ca.if_else(cross, mid, up), ub))
    return ca.Function("fatrop_bounds", [p, s], out, ["p", "s"],
                       ["lbg", "ubg", "lbx", "ubx"]).expand()


def row_scales(options: dict[str, Any]) -> tuple[float, float] | None:
    """IPOPT's gradient-based scaling as fatrop gets it: ``(max_gradient, min_value)`` from the
    shared options (``nlp_scaling_max_gradient``, default 100; ``nlp_scaling_min_value``,
    default 1e-8), or None for ``nlp_scaling_method: none``. IPOPT's other methods and its
    target gradients (``nlp_scaling_obj_target_gradient``, ``..._constr_target_gradient``) are
    IPOPT's alone: ConfigError for another method. (IPOPT, built beside fatrop as its
    fallback, refuses values out of range.)"""
    method = options.get("nlp_scaling_method", "gradient-based")
    if method == "none":
        return None
    if method != "gradient-based":
        raise ConfigError(f"solver.backend fatrop is given IPOPT's gradient-based scaling or "
                          f"none, not nlp_scaling_method {method!r}; set it to gradient-based "
                          f"or none, or use solver.backend: ipopt")
    return (float(options.get("nlp_scaling_max_gradient", 100.0)),
            float(options.get("nlp_scaling_min_value", 1e-8)))


def _scales(functions: dict[str, ca.Function], sf: StageForm, np_: int,
            scaling: tuple[float, float] | None) -> ca.Function:
    """``scales(x, p) -> (s, s_f)``: IPOPT's gradient-based scaling at the start (its
    implementation paper, Wächter & Biegler 2006, sec. 3.8): each row, and the objective,
    multiplied by ``max(min_value, min(1, max_gradient / |gradient|_inf))``, so that no
    gradient at the start exceeds ``max_gradient``; ones without scaling. The gap rows keep
    scale 1: fatrop reads ``x_{k+1}`` in them with coefficient 1. The gradients are those of
    fatrop's own (compiled, where ``jit``) Functions at scale 1."""
    z, p = ca.MX.sym("z", sf.nz), ca.MX.sym("p", np_)
    n_rows, gap = sf.order.size, sf.gap_rows
    if scaling is None:
        return ca.Function("fatrop_scales", [z, p], [ca.DM.ones(n_rows), 1.0],
                           ["x", "p"], ["s", "s_f"])
    max_gradient, min_value = scaling
    unit = ca.vertcat(p, ca.DM.ones(n_rows + 1))
    _, jac = functions["nlp_jac_g"](z, unit)
    f_grad = functions["nlp_grad_f"](z, unit)
    # |J_ij| gathered into columns: column k holds each row's k-th nonzero (or a zero past
    # the last), so that the rows' maxima are a few vector operations, not one per row
    rows, _ = jac.sparsity().get_triplet()
    nnz = len(rows)
    by_row: list[list[int]] = [[] for _ in range(n_rows)]
    for k, r in enumerate(rows):
        if not gap[r]:
            by_row[r].append(k)
    padded = ca.vertcat(ca.fabs(jac.nz[:]), 0.0)
    largest: ca.MX = ca.MX.zeros(n_rows)
    for k in range(max(map(len, by_row), default=0)):
        largest = ca.fmax(largest, padded[[ks[k] if k < len(ks) else nnz for ks in by_row]])

    def scale(g: ca.MX) -> ca.MX:
        return ca.fmax(min_value, ca.fmin(1.0, max_gradient / g))

    return ca.Function("fatrop_scales", [z, p], [scale(largest), scale(ca.mmax(ca.fabs(f_grad)))],
                       ["x", "p"], ["s", "s_f"])


def _rows_scaled(jac: ca.MX, s: ca.MX) -> ca.MX:
    """``diag(s) jac`` as one product per nonzero, in jac's sparsity (a sparse matrix product
    with the diagonal made the Jacobian's evaluation 1.6 times slower)."""
    rows, _ = jac.sparsity().get_triplet()
    return ca.sparsity_cast(jac.nz[:] * s[rows], jac.sparsity())


def _functions(sf: StageForm, np_: int, derivatives: Derivatives
               ) -> tuple[dict[str, Any], dict[str, ca.Function]]:
    """The NLP dict and the five Functions fatrop evaluates, in stage-form order, over the
    parameters ``q = [p; s; s_f]``: the rows multiplied by ``s`` and the objective by ``s_f``
    (:func:`_scales` gives them at a start); the stages' derivatives are the NLP's own
    (``derivatives``)."""
    z, p = ca.MX.sym("z", sf.nz), ca.MX.sym("p", np_)
    s, s_f = ca.MX.sym("s", sf.order.size), ca.MX.sym("s_f")
    q = ca.vertcat(p, s, s_f)
    fns = assemble(sf.blocks, z, p, whole=True, derivatives=derivatives)
    order = sf.order.tolist()
    g = fns["g"][order]
    _, jac = fns["nlp_jac_g"](z, p)
    jac = jac[order, :]
    _, grad_f = fns["nlp_grad_f"](z, p)
    lam_f, lam = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", sf.order.size)
    # the Lagrangian of the scaled NLP is the original's with scaled multipliers
    grad_l, hess = fns["nlp_hess_l"](z, p, s_f * lam_f, (s * lam)[sf.rank.tolist()])
    functions = {
        "nlp_f": ca.Function("nlp_f", [z, q], [s_f * fns["f"]], ["x", "p"], ["f"]),
        "nlp_g": ca.Function("nlp_g", [z, q], [s * g], ["x", "p"], ["g"]),
        "nlp_grad_f": ca.Function("nlp_grad_f", [z, q], [s_f * grad_f], ["x", "p"],
                                  ["grad_f_x"]),
        "nlp_jac_g": ca.Function("nlp_jac_g", [z, q], [s * g, _rows_scaled(jac, s)],
                                 ["x", "p"], ["g", "jac_g_x"]),
        "nlp_hess_l": ca.Function("nlp_hess_l", [z, q, lam_f, lam], [grad_l, hess],
                                  ["x", "p", "lam_f", "lam_g"],
                                  ["grad_gamma_x", "hess_gamma_x_x"]),
    }
    return {"x": z, "p": q, "f": s_f * fns["f"], "g": s * g}, functions


@dataclass(frozen=True)
class Exported:
    """fatrop as the exported C solver runs it (:mod:`ocgroupoid.export.fatrop`): its driver
    (``fatrop_ocp.c``) on the stage form ``form`` with the five ``functions`` (graphs: the C
    code generator writes them) and fatrop's ``options`` (their ``kinds``, as
    :func:`~.fatrop_ocp.option_kinds` gives them); ``arguments(x0, p) -> (z0, q, lbg, ubg,
    lbz, ubz)`` its inputs from an original point (:meth:`FatropBackend.arguments`) and
    ``unscaled(z, f, g, lam_g, lam_x, q) -> (x, f, g, lam_g, lam_x)`` its solution in the
    original variables and rows (:meth:`FatropBackend.unscaled`); ``maps`` where the
    Jacobian's and the Hessian's nonzeros go in the stage blocks."""

    form: StageForm
    functions: dict[str, ca.Function]
    arguments: ca.Function
    unscaled: ca.Function
    maps: BlockMaps
    options: dict[str, Any]
    kinds: dict[str, int]


#: the solver's inputs (:meth:`FatropBackend.arguments`), as nlpsol names them
ARGUMENTS = ("x0", "p", "lbg", "ubg", "lbx", "ubx")


class FatropBackend(Backend):
    """The fatrop instance of a block NLP over ``w = [x; p]``, solved in the original
    variables: points, bounds and multipliers are mapped in and out (:class:`StageForm`);
    ``jit`` compiles its Functions, and ``beside`` into the same library (IPOPT's:
    :attr:`compiled_beside`)."""

    name = "fatrop"

    def __init__(self, nlp: Graph, options: SolverOptions, jit: bool = False,
                 beside: dict[str, ca.Function] | None = None) -> None:
        t0 = time.perf_counter()
        name, ipopt = nlp.function_name, ipopt_options(options)
        try:
            self.form = stage_form(nlp.blocks, nlp.nx)
        except NotStaged as err:
            raise ConfigError(f"solver.backend fatrop needs the NLP as a chain of stages, and "
                              f"this one is not ({err}); use solver.backend: ipopt") from None
        graph, functions = _functions(self.form, nlp.np, nlp.derivatives)
        #: the five Functions as graphs (before jit compiles them), for the exported solver
        self.functions = functions
        self._scaling = row_scales(ipopt)
        #: the bounds fatrop is given, in stage form (:func:`tightened`)
        self.bounds = tightened(nlp.bounds_function, self.form)
        # fatrop's options: ours, the IPOPT options it shares, then the solve's own
        fatrop = {"print_level": 0, **DEFAULT_FATROP, **ACCEPTABLE_STOP,
                  **{k: v for k, v in ipopt.items() if k in SHARED_OPTIONS},
                  **{RENAMED_OPTIONS[k]: v for k, v in ipopt.items() if k in RENAMED_OPTIONS},
                  **options.fatrop}
        try:
            option_kinds(fatrop)
        except ConfigError as err:
            raise ConfigError(f"fatrop's options (solver.fatrop and the IPOPT options fatrop "
                              f"shares, {', '.join(SHARED_OPTIONS)}): {err}") from None
        self.max_iter = int(fatrop.get("max_iter", FATROP_MAX_ITER))
        #: the seconds after which a run counts as stuck (:data:`STUCK_SECONDS`)
        self.stuck_after = STUCK_FLOOR + STUCK_SECONDS * self.max_iter * nlp.nx
        self.jit_compiled = False
        #: ``beside`` compiled with fatrop's Functions (with jit and beside), else None
        self.compiled_beside: dict[str, ca.Function] | None = None
        library = None
        if jit:
            (functions, *others), self.jit_compiled, library = compiled(
                functions, *([beside] if beside is not None else []))
            self.compiled_beside = others[0] if others else None
        #: the rows' and the objective's scales at a start (:func:`_scales`)
        self.scales = _scales(functions, self.form, nlp.np, self._scaling)
        sf = self.form
        self.options: dict[str, Any]
        self.options = {"structure_detection": "manual", "N": sf.K, "nx": sf.nx, "nu": sf.nu,
                        "ng": sf.ng, "cache": functions, "print_time": False, "fatrop": fatrop}
        #: the NLP in stage form, as nlpsol is given it
        self.nlp = graph
        self._name = name
        #: fatrop driven through its own C interface (:mod:`.fatrop_ocp`: a build linear in
        #: N); where it is unavailable, CasADi's nlpsol (:attr:`solver`), built here
        self.direct: FatropOcp | None
        try:
            self.direct = FatropOcp(sf, functions, library, self.options["fatrop"])
        except (NotStaged, Unavailable):
            self.direct = None
        if self.direct is None:
            _ = self._whole
        #: whether fatrop runs in this process, guarded (:mod:`.fatrop_ocp`'s ``Guard``: its
        #: own interface, where it is guardable), else in :attr:`_isolated`
        self.guarded = self.direct is not None and self.direct.guardable
        #: the non-finite evaluations of the last run
        self.nans = 0
        self._isolated = Isolated(self._solve_here)
        #: the time the build took (stage form, Functions, jit, nlpsol or the driver's maps)
        self.build_seconds = time.perf_counter() - t0

    @cached_property
    def solver(self) -> ca.Function:
        """CasADi's fatrop nlpsol on the stage form (its build grows as N²: built only where
        fatrop's own interface is unavailable)."""
        try:
            return ca.nlpsol(self._name, "fatrop", self.nlp, self.options)
        except RuntimeError as err:
            raise ConfigError(f"fatrop rejected the NLP or its options: {err}; use "
                              "solver.backend: ipopt") from None

    @cached_property
    def _whole(self) -> Buffered:
        """One solve through :attr:`solver` as one call (:meth:`_solve_graph`: the scales,
        the bounds, fatrop and the way back in a single Function; its stats are fatrop's):
        0.1-0.6 ms a solve less than the steps called one by one from Python (so3,
        N = 16...128, in pairs)."""
        x0, p = ca.MX.sym("x0", self.form.z_slot.size), ca.MX.sym("p", self.bounds.size1_in(0))
        return Buffered(ca.Function(f"{self._name}_whole", [x0, p],
                                    list(self._solve_graph(self.solver, x0, p).values()),
                                    ["x0", "p"], list(UNSCALED)))

    @cached_property
    def _arguments(self) -> Buffered:
        """:meth:`arguments` of numbers as one call (so3, N = 4: 34 against 53 us in steps),
        built at the first solve."""
        x0, p = ca.MX.sym("x0", self.form.z_slot.size), ca.MX.sym("p", self.bounds.size1_in(0))
        return Buffered(ca.Function(f"{self._name}_arguments", [x0, p], list(
            self.arguments(x0, p).values()), ["x0", "p"], [f"{a}_out" for a in ARGUMENTS]))

    def arguments(self, x0: Any, p: Any, scales: ca.Function | None = None) -> dict[str, Any]:
        """The solver's inputs in stage form, for an original point x0 and parameters p (numbers,
        or graphs; every copy starts at its variable): its parameters are ``[p; s; s_f]``, with
        the scales at x0 (:func:`_scales`: :attr:`scales`, or ``scales`` of graphs)."""
        if not isinstance(p, ca.MX):
            return dict(zip(ARGUMENTS, self._arguments(x0=x0, p=p).values()))
        z0 = self.form.z_of(x0)
        s, s_f = (scales or self.scales)(z0, p)
        lbg, ubg, lbz, ubz = self.bounds(p, s)
        return dict(zip(ARGUMENTS, (z0, ca.vertcat(p, s, s_f), lbg, ubg, lbz, ubz)))

    def _solve_graph(self, solver: ca.Function, x0: ca.MX, p: ca.MX) -> dict[str, ca.MX]:
        """``solver`` (fatrop on the stage form) from the original point x0 with parameters p,
        as a graph in the original variables and rows (:meth:`arguments`, :meth:`unscaled`)."""
        arguments = self.arguments(x0, p)
        return self.unscaled(solver(**arguments), arguments["p"])

    def unscaled(self, r: dict[str, Any], q: Any) -> dict[str, Any]:
        """fatrop's result ``r`` on the scaled NLP with parameters ``q`` (:meth:`arguments`) as
        the original NLP's, in the original variables and rows: ``x, f, g, lam_g, lam_x``.
        The scaled Lagrangian ``s_f f + (s lam')^T g + lam_x'^T x`` is ``s_f`` times the
        original's, so ``lam = s lam' / s_f`` and ``lam_x = lam_x' / s_f``."""
        sf, n = self.form, self.form.order.size
        s, s_f = q[-n - 1:-1], q[-1]
        return {"x": sf.x_of(r["x"]), "f": r["f"] / s_f, "g": sf.rows_x(r["g"] / s),
                "lam_g": sf.rows_x(s * r["lam_g"] / s_f), "lam_x": sf.x_of(r["lam_x"] / s_f)}

    def run(self, start: Start) -> Run:
        """Run fatrop from the primal point of ``start`` (its multipliers are not for fatrop;
        its listener hears fatrop's iterations where fatrop runs guarded in this process),
        guarded in this process (:attr:`guarded`) or else in the helper
        process, until its deadline (status :data:`TIMED_OUT`), stopped after repeated NaN
        evaluations or past :attr:`stuck_after` (:data:`FAILED`, with a note) or once
        ``start.stop()`` is true or on Ctrl-C (:data:`INTERRUPTED`). Its seconds are the
        caller's wait (through the helper: the way there and back with the solve)."""
        x0, p = start.x0, start.p
        seconds = start.deadline - time.monotonic()
        stuck = self.stuck_after < seconds  # the run is cut before the deadline
        limit = max(0.0, min(seconds, self.stuck_after))
        t0 = time.perf_counter()
        answer: Run | Stopped | None = None
        if self.guarded:
            try:
                answer = self._solve_here((x0, p), Guard(limit, start.stop, isolated.NAN_LIMIT,
                                                          isolated.POLL), start.listener)
            except Unavailable:
                self.guarded = False
        if answer is None:
            answer = self._isolated.call((x0, p), limit, start.stop)
            self.nans = self._isolated.nans
        if isinstance(answer, Stopped):
            status, note = {
                "time": (FAILED, f"fatrop stopped after {self.stuck_after:.3g} s, longer than "
                                 f"{self.max_iter} of its iterations take here: stuck in a "
                                 "loop (an inertia correction that never ends?)") if stuck
                else (TIMED_OUT, f"fatrop stopped at the time limit ({seconds:.3g} s)"),
                "nan": (FAILED, f"fatrop stopped after {self.nans} NaN evaluations"),
                "stop": (INTERRUPTED, "fatrop stopped by an interrupt"),
            }.get(answer.reason, (FAILED, f"fatrop's process died ({answer.detail})"))
            nx = np.size(x0)
            return Run(np.asarray(x0, dtype=float), float("nan"),
                                np.zeros(self.form.n_rows), np.zeros(nx), status, False,
                                0, time.perf_counter() - t0, note)
        return replace(answer, seconds=time.perf_counter() - t0)

    def _solve_here(self, request: tuple[np.ndarray, np.ndarray], guard: Guard | None = None,
                    listener: Listener | None = None) -> Run | Stopped:
        """The solve itself, in this process: guarded by ``guard`` (:attr:`guarded`), or run
        by the helper process (:meth:`run` times it as the caller waits for it). With its own
        interface, ``listener`` hears each iteration (the objective unscaled) and may stop it
        (status :data:`~ocgroupoid.nlp.backends.base.LISTENER_STOP`, after the iteration
        under way: :meth:`~.fatrop_ocp.FatropOcp.solve`)."""
        x0, p = request
        if self.direct is not None:
            a = self.arguments(x0, p)
            heard = None
            if listener is not None:
                s_f, listen = float(np.asarray(a["p"]).ravel()[-1]), listener

                def heard(k: int, objective: float, infeasibility: float) -> bool:
                    return listen(k, objective / s_f, infeasibility)

            solved = self.direct.solve(a["x0"], a["p"], a["lbg"], a["ubg"], a["lbx"], a["ubx"],
                                       guard, heard)
            self.nans = self.direct.nans
            if isinstance(solved, Stopped):
                return solved
            r, iterations, flag, value, stopped = solved
            u = self.unscaled(r, a["p"])
            # asked to stop and not converged: the listener's stop, whatever fatrop then said
            # (its iteration limit, or an acceptable point IPOPT would otherwise polish)
            status = LISTENER_STOP if stopped and value != 0 else STATUS.get(flag, FAILED)
            return Run(u["x"], float(u["f"][0]), u["lam_g"], u["lam_x"], status, value == 0,
                       iterations, 0.0)
        r = self._whole(x0=x0, p=p)
        stats = self._whole.stats()
        success, iterations = bool(stats["success"]), int(stats["iter_count"])
        status = STATUS.get(int(stats["fatrop"]["return_flag"]), FAILED)
        return Run(r["x"], float(r["f"][0]), r["lam_g"], r["lam_x"], status, success,
                   iterations, 0.0)

    @cached_property
    def exported(self) -> Exported:
        """What the exported C solver runs (:class:`Exported`): fatrop's own interface, as
        here, without the stop at an acceptable point (:data:`ACCEPTABLE_STOP`: it has no
        IPOPT to finish from it), on the Functions as graphs. Built on first use."""
        sf, functions = self.form, self.functions
        options = {**self.options["fatrop"], "acceptable_iter": self.max_iter + 1}
        np_ = self.bounds.size1_in(0)
        x0, p = ca.MX.sym("x0", sf.z_slot.size), ca.MX.sym("p", np_)
        a = self.arguments(x0, p, _scales(functions, sf, np_, self._scaling))
        arguments = ca.Function("fatrop_in", [x0, p], list(a.values()), ["x0", "p"],
                                ["z0", "q", "lbg", "ubg", "lbz", "ubz"])
        n, nq = sf.order.size, arguments.nnz_out(1)
        r = {"x": ca.MX.sym("z", sf.nz), "f": ca.MX.sym("f"), "g": ca.MX.sym("g", n),
             "lam_g": ca.MX.sym("lam_g", n), "lam_x": ca.MX.sym("lam_x", sf.nz)}
        q = ca.MX.sym("q", nq)
        back = self.unscaled(r, q)
        unscaled = ca.Function("fatrop_out", [*r.values(), q], [back[k] for k in UNSCALED],
                               ["z", "f_z", "g_z", "lam_g_z", "lam_x_z", "q"], list(UNSCALED))
        maps = block_maps(sf, functions["nlp_jac_g"].sparsity_out(1),
                          functions["nlp_hess_l"].sparsity_out(1))
        return Exported(sf, functions, arguments, unscaled, maps, options, option_kinds(options))
