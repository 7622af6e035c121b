"""One NLP from a problem and a method: its graph, layout, bounds and shared Functions.

The scheme (:mod:`ocgroupoid.nlp.schemes`) lays out its variables and stage Functions; the
transcription adds the final conditions shared by every scheme — the chart coordinates of
each prescribed final state (3 equations for a rotation, 2 for a point of S^2, one per
prescribed component of R^n) and the user's final conditions — assembles the derivatives
(:mod:`ocgroupoid.nlp.assembly`). Initial states enter through p
(:mod:`ocgroupoid.nlp.layout`). No solver is built here: the backends take the NLP
(:mod:`ocgroupoid.nlp.backends`), and the transcription ties the two
(:mod:`ocgroupoid.nlp.transcription`).

Three computations that both the Python path and exported C need are CasADi Functions built
here once: the geodesic guesses as graphs of p (:attr:`Transcription.guess_function`), the
NLP point of a guess (:attr:`NonlinearProgram.point_function`) and the read-out of a
solution (:attr:`readout_function`). The packing of p is :class:`~ocgroupoid.nlp.parameters.
ParameterValues`.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from ..errors import BoundaryError, ConfigError
from ..model.boundary_values import prescribe
from ..model.consistency import check_order
from ..model.problem import Boundary, Problem
from ..model.values import check_horizon
from .assembly import Block, Derivatives, Kind, assemble
from .boundary import FinalConditions
from .buffered import Buffered
from .layout import Layout, Masks
from .method import Discretization, Method
from .parameters import ParameterValues
from .schemes import make_scheme
from .shared import shared_blocks

#: outputs of the read-out Function, in the order exported C reads them (enum ocg_output)
READOUT_OUTPUTS = ("x_solution", "t", "states", "node_states", "velocity_t", "velocities",
                   "control_t", "controls", "multiplier_t", "multipliers",
                   "final_multipliers", "control_breaks", "control_coefficients", "steps")
C_READOUT_OUTPUTS = READOUT_OUTPUTS[:13]


@dataclass
class Guess:
    """Velocities on the N intervals (N x dim y); the scheme turns them into a point. A warm
    start carries a whole NLP point ``x`` of the same structure (a previous solution), and
    its multipliers ``lam_g``, ``lam_x``: IPOPT then starts from the primal-dual point
    (:attr:`~ocgroupoid.nlp.backends.ipopt.IpoptBackend.warm_solver`)."""

    label: str
    xi: np.ndarray
    x: np.ndarray | None = None
    lam_g: np.ndarray | None = None
    lam_x: np.ndarray | None = None
    #: the horizon the velocities were made for (a coarser grid's solved T): a free horizon
    #: starts there rather than at the problem's guess, so the path keeps its length
    T: float | None = None
    #: a warm start carried from a coarser grid: the same start without its multipliers,
    #: solved instead if the warm start fails (:mod:`~ocgroupoid.solve.multipliers`); IPOPT
    #: starts such a guess with larger bound pushes than a solution's own multipliers
    #: (:data:`~ocgroupoid.nlp.backends.ipopt.CARRIED_IPOPT`)
    primal: Guess | None = None


def casadi_name(name: str) -> str:
    """A valid CasADi Function name made from any problem name (a file's stem such as
    ``my-slew`` or ``2 slews``): runs of other characters than ASCII letters and digits become
    one ``_``, and a name that does not start with a letter gets ``p_`` in front
    (``my_slew``, ``p_2_slews``). The problem keeps its own name for display."""
    text = re.sub(r"[^A-Za-z0-9]+", "_", name[:64]).strip("_")
    return text if text[:1].isalpha() else f"p_{text}".rstrip("_")


class NonlinearProgram:
    """The NLP of (problem, method), for any parameters p: no solver (module docstring)."""

    def __init__(self, problem: Problem, method: Method,
                 derivatives: Derivatives | None = None) -> None:
        t0 = time.perf_counter()
        if problem.cost is None:
            raise ConfigError(f"problem {problem.name!r} has no cost; call minimize()")
        check_order(problem)
        disc = Discretization.of(method)
        self.problem, self.disc, self.N = problem, disc, disc.N
        self.scheme = make_scheme(disc.scheme, problem, disc.N, disc.retraction, disc.rule,
                                  disc.bound_points)
        self.masks = Masks.of(problem.groupoid, problem.end_velocities, problem.start, problem.end)
        if disc.steps == "adaptive" and not self.scheme.adaptive_steps:
            raise ConfigError(
                f"adaptive steps need a scheme whose stages are intervals; {disc.scheme} for "
                f"order-{problem.order} problems has node stages: choose scheme order4 "
                "(or order6)")
        self.layout = Layout(problem, self.masks, self.scheme.n_stage, disc.N, disc.phases)
        self.scheme.index(self.layout)
        self.nx, self.np = self.layout.nx, self.layout.np
        self.values = ParameterValues(problem, self.masks, self.layout)
        self.final_check = FinalConditions(problem, self.masks, self.layout, self.scheme.stages)
        self.pack(T=problem.T or 1.0)  # over-determined final conditions raise here
        self.blocks = self.scheme.blocks() + shared_blocks(problem, self.masks, self.layout,
                                                           self.scheme, disc.N)
        t1 = time.perf_counter()
        x, p = ca.MX.sym("x", self.nx), ca.MX.sym("p", self.np)
        #: the stages' derivative Functions (:class:`~ocgroupoid.nlp.assembly.Derivatives`),
        #: which another assembly of the same blocks (fatrop's stage form) calls as well
        self.derivatives = derivatives if derivatives is not None else Derivatives()
        #: the graphs f and g and their assembled derivatives (``nlp_grad_f``, ``nlp_jac_g``,
        #: ``nlp_hess_l``), which every backend takes
        self.functions = assemble(self.blocks, x, p, derivatives=self.derivatives)
        t2 = time.perf_counter()
        self.ng = int(self.functions["g"].numel())
        self.nlp = {"x": x, "p": p, "f": self.functions["f"], "g": self.functions["g"]}
        #: the name of the solver Function (and of its exported C code): safe for CasADi
        self.function_name = f"{casadi_name(problem.name)}_N{self.N}"
        self.bounds_function = self._bounds_function()
        self.f_fun = ca.Function("f", [x, p], [self.nlp["f"]])
        self.g_fun = ca.Function("g", [x, p], [self.nlp["g"]])
        #: where the build time went: stage graphs and layout, derivative assembly
        self.build_phases = {"stages": t1 - t0, "assembly": t2 - t1}

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
        gauss = self.scheme.held_rows(b.points)
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
        shown = ca.Function("shown", [s], [G.as_matrix(s)])
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

    @cached_property
    def _point(self) -> Buffered:
        """:attr:`point_function` on numpy arrays, without CasADi's conversions (so3 at N = 4:
        24 against 74 us, in every solve from a guess)."""
        return Buffered(self.point_function)

    def point(self, guess: Guess, p: np.ndarray) -> np.ndarray:
        """NLP point of a guess (:attr:`point_function`)."""
        xi = np.asarray(guess.xi, dtype=float)
        dg = self.problem.groupoid.algebra_dim
        if xi.shape != (self.N, dg):
            raise ConfigError(f"guess {guess.label!r} has shape {xi.shape}, "
                              f"expected {(self.N, dg)}")
        # XI (dim y x N) column by column, as CasADi stores it, is xi row by row
        return self._point(XI=xi, p=p)["x"]

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
