"""One NLP from a problem and a discretisation.

Decision variables (per interval k = 0..N-1) are the velocities ``xi_k`` and the next node
state ``s_{k+1}``, then any free boundary components; the NLP parameters are

    p = [physical parameters | initial states | V_0 | final targets | V_N | T].

Constraints: the reconstruction ``s_{k+1} = step(s_k, tau(h xi_k))`` (per factor, e.g.
``R_{k+1} = R_k w_k``), the discrete constraints ``Phi_d`` at every node (the seeds' lambda^k
are their multipliers), and the final conditions in the factors' charts (3 equations for a
rotation, 2 for a point of S^2, one per prescribed component of R^n). Initial states enter
through p. The objective is the discrete action sum of :mod:`ocgroupoid.discretize`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from .assembly import Block, assemble
from .boundary import FinalConditions
from .discretize import Discretization, Stages
from .errors import BoundaryError, ConfigError
from .groupoid.product import Groupoid
from .problem import Boundary, Problem, check_horizon

DEFAULT_IPOPT: dict[str, Any] = {
    "tol": 1e-10,
    "constr_mult_init_max": 0.0,  # start from zero multipliers: saves a factorisation
    "max_iter": 500,
    # a start that wanders off (|x| > 1e8: no physical velocity or state) stops at once as
    # Diverging_Iterates; left to run, MUMPS grows its workspace each iteration and one bad
    # start of a multi-start took minutes (heavy top, N=256, "long way" guess)
    "diverging_iterates_tol": 1e8,
    "print_level": 0,
    "sb": "yes",
}


def nlpsol_options(ipopt: dict[str, Any] | None, fns: dict[str, ca.Function]) -> dict[str, Any]:
    """Options of ``casadi.nlpsol``: IPOPT's (defaults overridden by ``ipopt``) and the
    assembled derivative functions in its cache, so that it derives none itself."""
    opts: dict[str, Any] = {f"ipopt.{k}": v for k, v in {**DEFAULT_IPOPT, **(ipopt or {})}.items()}
    opts.update({"print_time": False, "calc_lam_p": False, "show_eval_warnings": False,
                 "cache": {k: fns[k] for k in ("nlp_grad_f", "nlp_jac_g", "nlp_hess_l")}})
    return opts


@dataclass(frozen=True)
class Masks:
    """Which boundary components are prescribed (True) — structural, fixed at build time."""

    start_state: tuple[np.ndarray, ...]  # per factor, one flag per state component
    end_state: tuple[np.ndarray, ...]  # per factor, one flag per chart row
    start_velocity: np.ndarray
    end_velocity: np.ndarray

    @staticmethod
    def of(groupoid: Groupoid, order: int, start_bc: Boundary, end_bc: Boundary) -> "Masks":
        G = groupoid
        start, end = [], []
        for f in G.factors:
            v0 = start_bc.states.get(f.state)
            if not f.componentwise:
                if v0 is None:
                    raise BoundaryError(
                        f"initial.{f.state} is required: the initial {f.state} of "
                        f"{type(f).__name__} cannot be left free"
                    )
                start.append(np.ones(f.state_size, dtype=bool))
            else:
                start.append(np.array([c is not None for c in (v0 or [None] * f.state_size)]))
            vT = end_bc.states.get(f.state)
            if f.componentwise:
                end.append(np.array([c is not None for c in (vT or [None] * f.state_dim)]))
            else:
                end.append(np.full(f.state_dim, vT is not None))

        def vel(b: dict[str, Any]) -> np.ndarray:
            out = np.zeros(G.algebra_dim, dtype=bool)
            if order == 1:
                return out
            for f, vs in zip(G.factors, G.velocity_layout.slices):
                v = b.get(f.velocity)
                if v is not None:
                    out[vs] = [c is not None for c in v]
            return out

        return Masks(tuple(start), tuple(end), vel(start_bc.velocities),
                     vel(end_bc.velocities))

    def start_velocity_by(self, G: Groupoid) -> list[np.ndarray]:
        """Initial-velocity flags split per factor."""
        return [self.start_velocity[vs] for vs in G.velocity_layout.slices]

    def end_velocity_by(self, G: Groupoid) -> list[np.ndarray]:
        """Final-velocity flags split per factor."""
        return [self.end_velocity[vs] for vs in G.velocity_layout.slices]

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Masks):
            return NotImplemented
        same = lambda a, b: all(np.array_equal(x, y) for x, y in zip(a, b))  # noqa: E731
        return (same(self.start_state, other.start_state)
                and same(self.end_state, other.end_state)
                and same((self.start_velocity, self.end_velocity),
                         (other.start_velocity, other.end_velocity)))


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


@dataclass
class Guess:
    """Velocities on the N intervals (N x dim y); states follow by forward composition."""

    label: str
    xi: np.ndarray
    extra: dict[str, Any] = field(default_factory=dict)


class Transcription:
    """The compiled NLP of (problem, discretisation); solve it for any parameters p."""

    def __init__(self, problem: Problem, disc: Discretization,
                 ipopt: dict[str, Any] | None = None) -> None:
        t0 = time.perf_counter()
        self.problem, self.disc = problem, disc
        self.N = disc.N
        self.stages = Stages(problem, disc)
        self.masks = Masks.of(problem.groupoid, problem.order, problem.start, problem.end)
        self._index()
        self.final_check = FinalConditions(self)
        self.pack(T=problem.T or 1.0)  # over-determined final conditions raise here
        self.blocks = self._blocks()
        t1 = time.perf_counter()
        x, p = ca.MX.sym("x", self.nx), ca.MX.sym("p", self.np)
        fns = assemble(self.blocks, x, p)
        t2 = time.perf_counter()
        self.ng = int(fns["g"].numel())
        self.nlp = {"x": x, "p": p, "f": fns["f"], "g": fns["g"]}
        try:
            self.solver = ca.nlpsol(f"{problem.name}_N{self.N}", "ipopt", self.nlp,
                                    nlpsol_options(ipopt, fns))
        except RuntimeError as err:
            raise ConfigError(f"IPOPT rejected the options {ipopt}: {err}") from None
        t3 = time.perf_counter()
        self.f_fun = ca.Function("f", [x, p], [fns["f"]])
        self.g_fun = ca.Function("g", [x, p], [fns["g"]])
        self.build_seconds = time.perf_counter() - t0
        #: where the build time went: stage graphs and layout, derivative assembly, IPOPT setup
        self.build_phases = {"stages": t1 - t0, "assembly": t2 - t1, "nlpsol": t3 - t2}

    # -- layout -------------------------------------------------------------------------

    def _index(self) -> None:
        G, N = self.problem.groupoid, self.N
        ds, dg, nt = G.state_size, G.algebra_dim, G.target_size
        per = dg + ds
        self.iw_xi = (np.arange(N)[None, :] * per + np.arange(dg)[:, None])
        s_next = np.arange(N)[None, :] * per + dg + np.arange(ds)[:, None]
        nx = N * per
        free_start = [~m for m in self.masks.start_state]
        n_free0 = int(sum(m.sum() for m in free_start))
        x_free0 = nx + np.arange(n_free0)
        nx += n_free0
        # end velocities exist in second-order problems only (their ghosts enter the nodes)
        free_V0 = ~self.masks.start_velocity if self.problem.order == 2 else np.zeros(dg, bool)
        free_VN = ~self.masks.end_velocity if self.problem.order == 2 else np.zeros(dg, bool)
        x_V0 = nx + np.arange(int(free_V0.sum()))
        nx += x_V0.size
        x_VN = nx + np.arange(int(free_VN.sum()))
        nx += x_VN.size
        self.nx = nx
        npar = self.problem.P.numel()
        self.p_layout = {"P": slice(0, npar), "start": slice(npar, npar + nt),
                         "V0": slice(npar + nt, npar + nt + dg),
                         "end": slice(npar + nt + dg, npar + 2 * nt + dg),
                         "VN": slice(npar + 2 * nt + dg, npar + 2 * nt + 2 * dg),
                         "T": slice(npar + 2 * nt + 2 * dg, npar + 2 * nt + 2 * dg + 1)}
        self.np = self.p_layout["T"].stop
        pw = {k: nx + np.arange(s.start, s.stop) for k, s in self.p_layout.items()}
        s0 = np.zeros(ds, dtype=np.int64)
        k = 0
        for f, ss, ts, m in zip(G.factors, G.state_layout.slices, G.target_layout.slices,
                                self.masks.start_state):
            for j in range(f.state_size):
                if m[j]:
                    s0[ss.start + j] = pw["start"][ts.start + j]
                else:
                    s0[ss.start + j] = x_free0[k]
                    k += 1
        self.iw_s = np.hstack([s0[:, None], s_next])
        self.iw_V0 = pw["V0"].copy()
        self.iw_V0[free_V0] = x_V0
        self.iw_VN = pw["VN"].copy()
        self.iw_VN[free_VN] = x_VN
        self.iw_T, self.iw_P, self.iw_end = pw["T"], pw["P"], pw["end"]

    def _columns(self, *parts: np.ndarray, ncols: int) -> np.ndarray:
        """Stack index rows; 1-D parts (T, P) are repeated for every column."""
        rows = [np.tile(p[:, None], (1, ncols)) if p.ndim == 1 else p for p in parts]
        return np.vstack(rows).astype(np.int64)

    def _blocks(self) -> list[Block]:
        st, N, G = self.stages, self.N, self.problem.groupoid
        ds, dg, nt = G.state_size, G.algebra_dim, G.target_size
        npar = self.problem.P.numel()
        S, XI, T, P = self.iw_s, self.iw_xi, self.iw_T, self.iw_P
        zero = ca.SX(1, 1)

        def fun(name: str, sizes: list[int], body: Any) -> ca.Function:
            z = ca.SX.sym("z", sum(sizes))
            parts = ca.vertsplit(z, np.cumsum([0, *sizes]).tolist())
            f, g = body(*parts)
            return ca.Function(name, [z], [f, g])

        recon = fun("recon", [ds, dg, ds, 1],
                    lambda s, xi, s1, t: (zero, st.recon(s, xi, s1, t)))
        blocks = [Block("recon", recon, self._columns(S[:, :N], XI, S[:, 1:], T, ncols=N), 1)]
        if self.problem.order == 2:
            def node(weight: float, ghost: str) -> Any:
                def body(s: ca.SX, a: ca.SX, b: ca.SX, t: ca.SX, par: ca.SX) -> Any:
                    xp, xn = {"prev": (2 * a - b, b), "next": (a, 2 * b - a), "": (a, b)}[ghost]
                    L, phi, _ = st.node(s, xp, xn, t, par)
                    return weight * L, phi
                return body

            sizes = [ds, dg, dg, 1, npar]
            blocks += [
                Block("node0", fun("node0", sizes, node(0.5, "prev")),
                      self._columns(S[:, 0], self.iw_V0, XI[:, 0], T, P, ncols=1), 1 + npar),
                Block("node", fun("node", sizes, node(1.0, "")),
                      self._columns(S[:, 1:N], XI[:, :N - 1], XI[:, 1:], T, P, ncols=N - 1),
                      1 + npar),
                Block("nodeN", fun("nodeN", sizes, node(0.5, "next")),
                      self._columns(S[:, N], XI[:, N - 1], self.iw_VN, T, P, ncols=1),
                      1 + npar),
            ]
        else:
            def interval(s: ca.SX, xi: ca.SX, t: ca.SX, par: ca.SX) -> Any:
                L, phi, _ = st.node(s, xi, t, par)
                return L, phi

            blocks.append(Block("interval", fun("interval", [ds, dg, 1, npar], interval),
                                self._columns(S[:, :N], XI, T, P, ncols=N), 1 + npar))
        rows = np.concatenate(self.masks.end_state)
        if rows.any():
            chart = fun("final", [ds, nt], lambda s, tg: (zero, st.chart(s, tg)[np.flatnonzero(rows).tolist()]))
            blocks.append(Block("final", chart, self._columns(S[:, N], self.iw_end, ncols=1), nt))
        if self.problem.final_conditions:
            ends = fun("final_conditions", [ds, dg, npar],
                       lambda s, v, par: (zero, st.final_conditions(s, v, par)))
            blocks.append(Block("final_conditions", ends,
                                self._columns(S[:, N], self.iw_VN, P, ncols=1), npar))
        return blocks

    def rows(self, name: str) -> np.ndarray:
        """Global constraint rows of a block, shaped (rows per column, columns)."""
        for b in self.blocks:
            if b.name == name:
                return b.g_offset + np.arange(b.m * b.ncols).reshape(b.ncols, b.m).T
        return np.zeros((0, 0), dtype=np.int64)

    def phi_rows(self) -> np.ndarray:
        """Rows of Phi_d: (n_phi, N+1) at the nodes (order 2) or (n_phi, N) per interval."""
        if self.problem.order == 1:
            return self.rows("interval")
        return np.hstack([self.rows("node0"), self.rows("node"), self.rows("nodeN")])

    def row_labels(self) -> list[str]:
        """A readable name for every constraint row, e.g. ``final R (chart 2)``."""
        G, labels = self.problem.groupoid, [""] * self.ng
        comps = [f"{f.state}[{j}]" for f in G.factors for j in range(f.state_size)]
        names = [n for n, c in self.problem.constraints for _ in range(c.numel())] or ["Phi"]
        ends = [n for n, c in self.problem.final_conditions for _ in range(c.numel())]
        node_of = {"node0": lambda c: 0, "node": lambda c: c + 1,
                   "nodeN": lambda c: self.N, "interval": lambda c: c}
        for b in self.blocks:
            rows = self.rows(b.name)
            for c in range(b.ncols):
                for r in range(b.m):
                    if b.name == "recon":
                        text = f"reconstruction k={c} {comps[r]}"
                    elif b.name == "final":
                        text = self._final_label(r)
                    elif b.name == "final_conditions":
                        text = f"final condition {ends[r]!r}"
                    else:
                        name = names[r] if r < len(names) else f"Phi[{r}]"
                        text = f"{name} at {'node' if b.name != 'interval' else 'interval'} " \
                               f"{node_of[b.name](c)}"
                    labels[rows[r, c]] = text
        return labels

    def _final_label(self, r: int) -> str:
        G = self.problem.groupoid
        k = 0
        for f, mask in zip(G.factors, self.masks.end_state):
            for j in np.flatnonzero(mask):
                if k == r:
                    return f"final.{f.state} " + (f"component {j}" if f.componentwise
                                                  else f"(chart coordinate {j + 1})")
                k += 1
        return f"final condition {r}"

    # -- parameters and points ----------------------------------------------------------

    def pack(self, params: dict[str, Any] | None = None, initial: dict[str, Any] | None = None,
             final: dict[str, Any] | None = None, T: float | None = None) -> np.ndarray:
        """The parameter vector p: problem defaults overridden by the arguments.

        Overrides may change values but not which components are prescribed (that is the
        NLP's structure: change it on the Problem and build again).
        """
        pb, G = self.problem, self.problem.groupoid
        p = np.zeros(self.np)
        p[self.p_layout["P"]] = pb.parameter_values(params)
        start = Boundary(dict(pb.start.states), dict(pb.start.velocities))
        end = Boundary(dict(pb.end.states), dict(pb.end.velocities))
        for bc, upd, label in ((start, initial, "initial"), (end, final, "final")):
            for name, value in (upd or {}).items():
                if name in G.state_names:
                    bc.states[name] = pb.check_state(name, value, label)
                elif name in G.velocity_names and pb.order == 2:
                    bc.velocities[name] = pb.check_velocity(name, value, label)
                else:
                    raise ConfigError(f"{label}.{name}: unknown state or velocity")
        if Masks.of(G, pb.order, start, end) != self.masks:
            raise BoundaryError(
                "the overrides change which boundary components are prescribed; that changes "
                "the NLP: set them on the Problem and build a new Transcription"
            )
        for f, ts in zip(G.factors, G.target_layout.slices):
            for bc, key in ((start, "start"), (end, "end")):
                v = bc.states.get(f.state)
                if v is not None:
                    vec = [0.0 if c is None else c for c in v] if f.componentwise else v
                    p[self.p_layout[key]][ts] = f.pack_target(vec)
        for f, vs in zip(G.factors, G.velocity_layout.slices):
            for bc, key in ((start, "V0"), (end, "VN")):
                v = bc.velocities.get(f.velocity)
                if v is not None:
                    p[self.p_layout[key]][vs] = [0.0 if c is None else c for c in v]
        if T is None and pb.T is None:
            raise ConfigError("no horizon: give T or call problem.horizon(T)")
        p[self.p_layout["T"]] = check_horizon(pb.T if T is None else T)
        self.final_check.check(p)
        return p

    def horizon_of(self, p: np.ndarray) -> float:
        return float(p[self.p_layout["T"]][0])

    def point(self, guess: Guess, p: np.ndarray) -> np.ndarray:
        """NLP point of a guess: velocities as given, states by forward composition."""
        xi = np.asarray(guess.xi, dtype=float)
        G = self.problem.groupoid
        if xi.shape != (self.N, G.algebra_dim):
            raise ConfigError(f"guess {guess.label!r} has shape {xi.shape}, "
                              f"expected {(self.N, G.algebra_dim)}")
        w = np.concatenate([np.zeros(self.nx), p])
        s0 = w[self.iw_s[:, 0]]
        T = self.horizon_of(p)
        states = np.array(self.stages.step.mapaccum(self.N)(s0, xi.T, T))
        w[self.iw_xi] = xi.T
        w[self.iw_s[:, 1:]] = states
        for iw, k in ((self.iw_V0, 0), (self.iw_VN, self.N - 1)):
            free = iw < self.nx
            w[iw[free]] = xi[k, free]
        return w[: self.nx]

    def reconstruct(self, x: np.ndarray, p: np.ndarray) -> np.ndarray:
        """The point with every state recomputed from s_0 and the velocities by the exact
        reconstruction (e.g. ``R_{k+1} = R_k tau(h xi_k)``): on the manifold to rounding,
        whatever tolerance the solver stopped at."""
        w = np.concatenate([np.asarray(x, dtype=float).ravel(), p])
        xi = w[self.iw_xi]
        w[self.iw_s[:, 1:]] = np.array(
            self.stages.step.mapaccum(self.N)(w[self.iw_s[:, 0]], xi, self.horizon_of(p)))
        return w[: self.nx]

    def unpack(self, x: np.ndarray, p: np.ndarray) -> dict[str, np.ndarray]:
        """Numeric xi (N x dy), s (N+1 x ds), V0, VN, T, P of an NLP point."""
        w = np.concatenate([np.asarray(x, dtype=float).ravel(), p])
        return {"xi": w[self.iw_xi].T, "s": w[self.iw_s].T, "V0": w[self.iw_V0],
                "VN": w[self.iw_VN], "T": w[self.iw_T][0], "P": w[self.iw_P]}

    # -- solving ------------------------------------------------------------------------

    def solve(self, guess: Guess, p: np.ndarray | None = None) -> RawResult:
        """Run IPOPT from ``guess`` with parameters ``p`` (default: the problem's)."""
        p = self.pack() if p is None else np.asarray(p, dtype=float)
        x0 = self.point(guess, p)
        t0 = time.perf_counter()
        r = self.solver(x0=x0, p=p, lbg=0, ubg=0)
        seconds = time.perf_counter() - t0
        stats = self.solver.stats()
        status = str(stats["return_status"])
        iterations = 0 if status == "Not_Enough_Degrees_Of_Freedom" else int(stats["iter_count"])
        return RawResult(guess.label, np.array(r["x"]).ravel(), p, np.array(r["lam_g"]).ravel(),
                         float(r["f"]), status, bool(stats["success"]), iterations, seconds)

