"""Replay: the plan driven through the continuous problem, and everything measured along it.

What is driven, and through what:

* second-order problems with mechanics: the controls through ``M(q, g, y) dy/dt = F(u) -
  c(q, g, y)`` (the controlled Euler-Lagrange(-Poincare) equations; a force of controls of
  their own, thrust along body z, as declared); second-order problems whose controls are the
  accelerations: ``dy/dt = u``;
* first-order problems whose controls are velocity components that the constraints
  ``psi(q, y) = 0`` complete: the controls through that kinematics;
* every other first-order problem: the plan's velocities themselves, through the
  reconstruction ``g' = g y`` (``s' = state_rate(s, y)``), with the constraints ``psi``
  checked along the integrated path (a no-slip or no-sideslip condition between the points
  where the scheme imposes it).

The input is the piecewise polynomial the scheme implies (``Solution.control_ppoly``; the
velocities' for the last case: a constant or a line per interval through the velocity
samples). Along the replay, on a dense grid (at least :data:`DENSE` samples per piece), the
bounds are evaluated (the largest violation of each is the one a Solution reports), the
constraints (last case) too, and the running cost is integrated (the cost recomputed from the
plan). The integrator is RK4 compiled by CasADi and mapped over the pieces, its substeps
doubled until its own error is negligible (:meth:`Replay.run`). With the transcription's
``jit`` its RK4 substep and its sample of the bounds are machine code as the NLP's Functions
are (:func:`~ocgroupoid.nlp.jit.library`; the graphs of the exported verdict keep CasADi's
own).
"""

from __future__ import annotations

import weakref
from typing import Any

import casadi as ca
import numpy as np

from ..nlp.dynamics import Dynamics, rk4
from ..nlp.jit import library
from ..nlp.transcription import Transcription

#: RK4 substeps per piece: the first pair compared, and the most ever taken
SUBSTEPS = (4, 256)
#: at least this many samples of the bounds and constraints per piece (their extremes then
#: refined by the parabola through the three samples around each)
DENSE = 32
REL_TOL, ABS_TOL = 1e-3, 1e-12  # the replay's own error, against what it reports


def terminal_errors(tr: Transcription, s: np.ndarray, y: np.ndarray | None, p: np.ndarray
                    ) -> dict[str, float]:
    """Errors of a final state (and velocity) against the prescribed targets: each factor's
    :meth:`~ocgroupoid.groupoid.base.Factor.terminal_error` (an angle for rotations and
    directions, a norm over the prescribed components on R^n); velocities: the norm over
    the prescribed components."""
    G, m = tr.problem.groupoid, tr.masks
    target = tr.part(p, "end")
    out: dict[str, float] = {}
    for f, ss, ts, mask in zip(G.factors, G.state_layout.slices, G.target_layout.slices,
                               m.end_state):
        if mask.any():
            out[f.state] = f.terminal_error(s[ss], f.state_of_target(target[ts]), mask)
    if y is not None and tr.problem.end_velocities:
        VT = tr.part(p, "VN")
        for f, vs in zip(G.factors, G.velocity_layout.slices):
            mask = m.end_velocity[vs]
            if mask.any():
                out[f.velocity] = float(np.linalg.norm((y[vs] - VT[vs])[mask]))
    return out


def velocity_ppoly(out: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The velocities a first-order plan implies as a PPoly: on each interval the polynomial
    through its velocity samples (one: a constant, the midpoint rule's; two: a line, the
    Gauss stages')."""
    t, tv, V = out["t"], out["velocity_t"], out["velocities"]
    pieces = t.size - 1
    k = max(1, tv.size // pieces)
    C = np.zeros((k, pieces, V.shape[1]))
    for j in range(pieces):
        ts, vs = tv[j * k:(j + 1) * k] - t[j], V[j * k:(j + 1) * k]
        C[:, j, :] = np.linalg.solve(np.vander(ts, k), vs) if k > 1 else vs
    return {"x": t, "c": C}


class Replay:
    """The continuous problem driven by the plan (module docstring)."""

    def __init__(self, tr: Transcription) -> None:
        #: the transcription, not kept alive by its replay (kept per transcription,
        #: :func:`~ocgroupoid.verify.diagnostics.replay_of`)
        self.tr = weakref.proxy(tr)
        pb, G = tr.problem, tr.problem.groupoid
        stages = tr.scheme.stages
        dynamics = Dynamics(pb, stages)
        self.reason = dynamics.reason
        #: what drives the replay: "controls" (dynamics or kinematics), "velocities" (a
        #: first-order plan's velocities through the reconstruction) or "" (nothing can)
        self.input = "controls" if dynamics.rhs is not None else \
            "velocities" if pb.order == 1 else ""
        s, y = ca.SX.sym("s", G.state_size), ca.SX.sym("y", G.algebra_dim)
        #: ``rhs(z, v, P) -> dz/dt`` and ``(L, H, psi)(z, v, P)``: the running cost, the bounds'
        #: expressions and (velocity input) the constraints along the replay
        self.rhs: ca.Function | None = None
        self.along: ca.Function | None = None
        quantities = [stages.running_cost(), stages.inequalities]
        psi = stages.constraints if self.input == "velocities" else ca.SX(0, 1)
        if self.input == "controls":
            assert dynamics.rhs is not None
            self.rhs = dynamics.rhs
            u = dynamics.u
            if dynamics.second:
                z = ca.vertcat(s, y)
                assert dynamics.acceleration is not None
                dy = dynamics.acceleration(s, y, u, pb.P)
                vals = stages.at(quantities, s, y, dy, u)
            else:
                z = s
                assert dynamics.velocity is not None
                vals = stages.at(quantities, s, dynamics.velocity(s, u, pb.P))
            self.along = ca.Function("along", [z, u, pb.P], [*vals, psi])
        elif self.input == "velocities":
            self.rhs = ca.Function("rhs", [s, y, pb.P], [G.state_rate(s, y)])
            vals = stages.at([*quantities, psi], s, y)
            self.along = ca.Function("along", [s, y, pb.P], vals)
            self.reason = ""
        bounds = stages.inequality_bounds()
        self.sides = ca.Function("sides", [pb.P], list(bounds) if bounds else
                                 [ca.SX(0, 1), ca.SX(0, 1)])
        self.names = stages.inequality_names
        #: whether :meth:`run` evaluates compiled substeps and samples (the transcription's jit)
        self.compiled = bool(tr.jit)
        self._cache: dict[tuple[int | str | bool, ...], ca.Function] = {}
        self._kernels: dict[tuple[int, int, bool], tuple[ca.Function, ca.Function]] = {}

    def run(self, out: dict[str, np.ndarray], ppoly: dict[str, np.ndarray], p: np.ndarray
            ) -> dict[str, Any]:
        """Integrate from the read-out's initial state, piece by piece of the input polynomial;
        return what was measured (module docstring).

        RK4 with M substeps per piece, compiled and mapped over the pieces, M doubled until
        two successive results agree (their difference, /15, estimates the error of the
        finer one, which is then Richardson-extrapolated) to 1e-3 of the terminal error or
        :data:`ABS_TOL`: the replay's own error is never what it reports. The doublings
        integrate only (:meth:`_path`) below :data:`DENSE` substeps; the bounds and
        constraints, if any, are sampled once along the last M (:meth:`_pieces`), on the
        same substeps from DENSE on, where the doublings take them along."""
        if self.rhs is None:
            return {"available": False, "reason": self.reason}
        tr = self.tr
        if self.input == "velocities":
            ppoly = velocity_ppoly(out)
        breaks, C = np.asarray(ppoly["x"], dtype=float), np.asarray(ppoly["c"], dtype=float)
        k, n, m = C.shape  # (k, pieces, m), highest power first
        P = tr.part(p, "P")
        ns = tr.problem.groupoid.state_size
        second = tr.problem.end_velocities and self.input == "controls"
        z0 = np.concatenate([out["node_states"][0], out["velocities"][0]]) if second else \
            out["node_states"][0].copy()
        z0 = np.concatenate([z0, [0.0]])  # the running cost, integrated alongside
        coeffs = C.transpose(0, 2, 1).reshape(k * m, n)  # column j: piece j, m fastest
        args = (z0, coeffs, np.diff(breaks)[None, :], np.repeat(P[:, None], n, axis=1))
        assert self.along is not None  # set with rhs
        sampled = bool(self.along.numel_out(1) or self.along.numel_out(2))  # bounds, psi

        def integrate(M: int) -> tuple[np.ndarray, list[np.ndarray] | None]:
            """The state after every piece with M substeps, and the samples (H, psi) where
            they ride along on the same substeps (M >= DENSE; else None)."""
            if sampled and M >= DENSE:
                zs, *samples = (np.asarray(v) for v in
                                self._pieces(k, m, M, n, self.compiled)(*args))
                return zs[:, -1], samples
            return np.asarray(self._path(k, m, M, n, self.compiled)(*args))[:, -1], None

        M = SUBSTEPS[0]
        previous, _ = integrate(M)
        while True:
            M *= 2
            raw, samples = integrate(M)
            # Richardson pairs two plain RK4 results, never an extrapolated one
            estimate = float(np.max(np.abs(raw[:-1] - previous[:-1]))) / 15.0
            z = raw + (raw - previous) / 15.0
            if not np.all(np.isfinite(z)):
                return {"available": False, "reason": "the replayed state diverged (not finite)"}
            errors = terminal_errors(tr, z[:ns], z[ns:-1] if second else None, p)
            worst = max(errors.values()) if errors else 0.0
            if estimate <= max(REL_TOL * worst, ABS_TOL) or M >= SUBSTEPS[1]:
                break
            previous = raw
        H = psi = np.zeros((0, 0))
        if sampled and samples is None:  # the last M below DENSE: sampled apart
            _, H, psi = (np.asarray(v) for v in self._pieces(k, m, M, n, self.compiled)(*args))
        elif samples is not None:
            H, psi = samples
        report = {"available": True, "input": self.input, "terminal_error": errors,
                  "max_terminal_error": worst, "integration_error": estimate, "substeps": M,
                  "final_state": z[:-1].tolist(), "running_cost": float(z[-1])}
        self._samples = max(M, DENSE) + 1
        report.update(self._violations(H, P))
        if psi.size:
            report["constraint_residual_max"] = float(np.max(psi))
        return report

    def _violations(self, H: np.ndarray, P: np.ndarray) -> dict[str, Any]:
        """The largest violation of every bound along the replay (H: the bounds' expressions
        at the samples of every piece, :meth:`_pieces`), each extreme refined by a parabola."""
        if not H.size:
            return {}
        lo, hi = (np.array(v).ravel() for v in self.sides(P))
        n = H.shape[1] // self._samples
        S = H.reshape(H.shape[0], n, self._samples)
        over = extreme(S) - hi
        under = lo + extreme(-S)
        worst = np.maximum(0.0, np.maximum(np.nan_to_num(over, nan=np.inf, neginf=0.0),
                                           np.nan_to_num(under, nan=np.inf, neginf=0.0)))
        per: dict[str, float] = {}
        for name, v in zip(self.names, worst):
            per[name] = max(per.get(name, 0.0), float(v))
        return {"bound_violation": per, "bound_violation_max": float(np.max(worst)),
                "bound_samples": DENSE}

    def _pieces(self, k: int, m: int, M: int, n: int, compiled: bool = False) -> ca.Function:
        """``(z0, coefficients (k m x n), steps (1 x n), P) -> (z, H, psi)``: z after every
        piece (M RK4 substeps, the input evaluated by Horner's rule in t - t_j, the running
        cost as the last state), the bound expressions at max(M, DENSE) + 1 samples of every
        piece (their columns, piece after piece) and per piece the largest |psi| there.
        The substeps and samples are loops (``mapaccum``, ``map``) over one RK4 substep and
        one sample, not unrolled: the exported verdict's code does not grow with M. With
        ``compiled`` the loops call the compiled substep and sample (:meth:`_substep`)."""
        key = (k, m, M, n, compiled)
        if key not in self._cache:
            substep, sample = self._substep(k, m, compiled)
            z, c, h, P = _piece_inputs(substep, k, m)
            S = max(M, DENSE)
            states = {}
            for count in {M, S}:
                dt = h / count
                starts = dt * ca.DM(np.arange(count)).T
                states[count] = substep.mapaccum(count)(z, c, starts, dt, P)
            zz = states[M][:, -1]
            ds = h / S
            times = ds * ca.DM(np.arange(S + 1)).T
            H, psis = sample.map(S + 1)(ca.horzcat(z, states[S]), c, times, P)
            psi = ca.mmax(psis) if psis.numel() else ca.MX(0, 1)
            piece = ca.Function("piece", [z, c, h, P], [zz, H, psi])
            self._cache[key] = piece.mapaccum(n)
        return self._cache[key]

    def _path(self, k: int, m: int, M: int, n: int, compiled: bool = False) -> ca.Function:
        """``(z0, coefficients, steps, P) -> z``: z after every piece, as :meth:`_pieces`
        integrates it (the same M RK4 substeps), without the samples of the bounds: the
        doublings of :meth:`run` need only the end (on the quadrotor at N = 256 the samples
        were two thirds of a doubling's time)."""
        key = (k, m, M, n, compiled, "path")
        if key not in self._cache:
            substep, _ = self._substep(k, m, compiled)
            z, c, h, P = _piece_inputs(substep, k, m)
            dt = h / M
            zz = substep.mapaccum(M)(z, c, dt * ca.DM(np.arange(M)).T, dt, P)[:, -1]
            self._cache[key] = ca.Function("path", [z, c, h, P], [zz]).mapaccum(n)
        return self._cache[key]

    def _substep(self, k: int, m: int, compiled: bool = False
                 ) -> tuple[ca.Function, ca.Function]:
        """``substep(z, c, t0, dt, P)``: one RK4 step from t0 over dt of the state with its
        running cost; ``sample(z, c, t, P) -> (H, |psi|)``: the bounds and constraints at a
        state and time; the input a polynomial in t with coefficients c (highest first).
        ``compiled``: both as machine code, built once (module docstring)."""
        key = (k, m, compiled)
        if key not in self._kernels:
            substep, sample = self._symbolic_substep(k, m)
            if compiled:
                substep, sample = library([substep, sample])[0]
            self._kernels[key] = substep, sample
        return self._kernels[key]

    def _symbolic_substep(self, k: int, m: int) -> tuple[ca.Function, ca.Function]:
        """The SX graphs of :meth:`_substep`."""
        rhs, along = self.rhs, self.along
        assert rhs is not None and along is not None
        nz = rhs.size1_in(0)
        z, c, t0, dt, P = (ca.SX.sym(n, d) for n, d in (
            ("z", nz + 1), ("c", k * m), ("t0", 1), ("dt", 1), ("P", rhs.size1_in(2))))
        cm = ca.reshape(c, m, k)

        def u_at(t: ca.SX) -> ca.SX:
            u = cm[:, 0]
            for j in range(1, k):
                u = u * t + cm[:, j]
            return u

        def f(zz: ca.SX, s: float) -> ca.SX:
            u = u_at(t0 + s * dt)
            L = along(zz[:nz], u, P)[0]
            return ca.vertcat(rhs(zz[:nz], u, P), L)

        substep = ca.Function("substep", [z, c, t0, dt, P], [rk4(f, z, dt)])
        vals = along(z[:nz], u_at(t0), P)
        sample = ca.Function("sample", [z, c, t0, P], [vals[1], ca.fabs(vals[2])])
        return substep, sample


def _piece_inputs(substep: ca.Function, k: int, m: int) -> tuple[ca.MX, ...]:
    """The symbols of one piece: the state with its running cost, the input's k m
    coefficients, the piece's length and the parameters."""
    return tuple(ca.MX.sym(name, size) for name, size in (
        ("z", substep.size1_in(0)), ("c", k * m), ("h", 1), ("P", substep.size1_in(4))))


def extreme(S: np.ndarray) -> np.ndarray:
    """The largest value of every row of samples ``S`` (rows x pieces x samples, equally
    spaced in each piece), refined where the largest sample is inside a piece by the vertex
    of the parabola through it and its neighbours (third order in the spacing)."""
    rows, n, m = S.shape
    flat = S.reshape(rows, n * m)
    best = np.nanmax(np.where(np.isnan(flat), np.inf, flat), axis=1)
    i = np.argmax(np.where(np.isnan(S), np.inf, S), axis=2)  # per row and piece
    inside = (i > 0) & (i < m - 1)
    r, p = np.nonzero(inside)
    a, b, c = S[r, p, i[r, p] - 1], S[r, p, i[r, p]], S[r, p, i[r, p] + 1]
    curvature = a - 2 * b + c
    with np.errstate(divide="ignore", invalid="ignore"):
        vertex = b - (c - a) ** 2 / (8 * curvature)
    vertex = np.where(curvature < 0, vertex, b)
    refined = np.full((rows, n), -np.inf)
    refined[r, p] = vertex
    return np.maximum(best, np.max(refined, axis=1))
