"""Baselines: RK4 multiple shooting, as a rockit or CasADi Opti user transcribes a problem.

Not variational and not for use: they exist to be measured against (``ocgroupoid bench``).
Built from the same Problem as our schemes: the continuous dynamics of
:mod:`ocgroupoid.nlp.dynamics` (derived from ``mechanics``, not typed again), the same cost,
bounds and boundary conditions, the same IPOPT options, Solution and diagnostics.

Per interval k (h = T/N): a constant control ``u_k``, and one RK4 step of the dynamics in the
baseline's coordinates (:mod:`~ocgroupoid.nlp.schemes.coordinates`: unit quaternions,
rotation matrices or ZYX Euler angles, integrated as plain vectors)

    X_{k+1} = RK4(X_k, u_k),   X = (z, y) (second-order problems) or z (first-order),

closed as equality constraints (the gaps). The cost is RK4's quadrature of the running cost
along the same stages, ``h/6 (l_1 + 2 l_2 + 2 l_3 + l_4)``; bounds and constraints that the
dynamics do not already satisfy are imposed at the start of every interval. Fourth order in
h for smooth solutions; a rotation represented by a vector drifts off SO(3) at the same
order, Euler angles fail at a pitch of 90 degrees.
"""

from __future__ import annotations

from typing import Any, ClassVar

import casadi as ca
import numpy as np

from ...errors import ConfigError
from ...model.problem import Problem
from ..assembly import Block, Kind
from ..dynamics import Dynamics, rk4
from ..layout import Layout
from .base import DEFAULT_RULE, Pick, Readout, Scheme, columns, stage_function
from .coordinates import Coordinates, coordinates


class RK4Shooting(Scheme):
    """RK4 multiple shooting with piecewise-constant controls (module docstring)."""

    accuracy = 4
    variational = False
    coordinates: ClassVar[str] = "quaternion"

    def __init__(self, problem: Problem, N: int, retraction_name: str, rule: str) -> None:
        super().__init__(problem, N, retraction_name, rule)
        if rule != DEFAULT_RULE:
            raise ConfigError(f"the baseline {self.name} has no rule {rule!r}; it integrates "
                              "the continuous dynamics (rule midpoint)")
        self.dynamics = Dynamics(problem, self.stages)
        if self.dynamics.rhs is None:
            raise ConfigError(f"the baseline {self.name} integrates the continuous dynamics, "
                              f"which {problem.name!r} lacks ({self.dynamics.reason}); "
                              "use order2 or order4")
        G = problem.groupoid
        self.coords: list[Coordinates] = [coordinates(self.coordinates, f) for f in G.factors]
        self.nz = sum(c.size for c in self.coords)
        self.nu = len(problem.controls)
        self.second = self.dynamics.second
        s, z = ca.SX.sym("s", G.state_size), ca.SX.sym("z", self.nz)
        zs = ca.vertsplit(z, np.cumsum([0, *[c.size for c in self.coords]]).tolist())
        ss = [s[sl] for sl in G.state_layout.slices]
        #: ``to_z(s) -> z`` and ``to_s(z) -> s``: the baseline's coordinates of a stored state
        self.to_z = ca.Function("to_z", [s], [ca.vertcat(*[c.of_stored(x) for c, x in
                                                           zip(self.coords, ss)])])
        self.to_s = ca.Function("to_s", [z], [ca.vertcat(*[c.stored(x) for c, x in
                                                           zip(self.coords, zs)])])
        y = ca.SX.sym("y", G.algebra_dim)
        ys = [y[sl] for sl in G.velocity_layout.slices]
        self.z_rate = ca.Function("z_rate", [z, y], [ca.vertcat(*[
            c.rate(x, v) for c, x, v in zip(self.coords, zs, ys)])])
        self.extra = [(n, c) for n, c in problem.constraints if n not in self.dynamics.implied]
        self._build_flow()

    # -- the stage: one RK4 step and its quadrature ------------------------------------------

    def _build_flow(self) -> None:
        """``flow(X, u, T, P) -> (X_next, L)`` (one RK4 step of h = T/N with its cost
        quadrature) and ``at_start(X, u, P) -> (constraints, bounds, controls)``."""
        pb, G = self.problem, self.problem.groupoid
        nX = self.nz + (G.algebra_dim if self.second else 0)
        X, u, T = ca.SX.sym("X", nX), ca.SX.sym("u", self.nu), ca.SX.sym("T")
        cost = self.stages.running_cost()
        extra = ca.vertcat(*[c for _, c in self.extra]) if self.extra else ca.SX(0, 1)
        quantities = [cost, extra, self.stages.inequalities, self.stages.controls]

        def field(X: ca.SX) -> tuple[ca.SX, list[ca.SX]]:
            z = X[:self.nz]
            s = self.to_s(z)
            if self.second:
                assert self.dynamics.acceleration is not None
                y = X[self.nz:]
                dy = self.dynamics.acceleration(s, y, u, pb.P)
                return ca.vertcat(self.z_rate(z, y), dy), self.stages.at(quantities, s, y, dy,
                                                                         u)
            assert self.dynamics.velocity is not None
            y = self.dynamics.velocity(s, u, pb.P)
            return self.z_rate(z, y), self.stages.at(quantities, s, y)

        def with_cost(XL: ca.SX, _: float) -> ca.SX:
            """The dynamics with the running cost as one more state: its RK4 step is the
            cost quadrature along the same stages."""
            rate, q = field(XL[:nX])
            return ca.vertcat(rate, q[0])

        XL = rk4(with_cost, ca.vertcat(X, 0), T / self.N)
        self.flow = ca.Function("flow", [X, u, T, pb.P], [XL[:nX], XL[nX]],
                                ["X", "u", "T", "P"], ["X_next", "L"])
        self.at_start = ca.Function("at_start", [X, u, pb.P], field(X)[1][1:],
                                    ["X", "u", "P"], ["Phi", "H", "controls"])
        self.n_X = nX

    # -- variables ----------------------------------------------------------------------------

    @property
    def n_stage(self) -> int:
        dg = self.problem.groupoid.algebra_dim
        return self.N * (self.nu + self.nz) + ((self.N - 1) * dg if self.second else 0)

    def index(self, layout: Layout) -> None:
        """Per interval k: ``u_k``, ``z_{k+1}`` and (second order, k < N-1) ``y_{k+1}``."""
        G, N = self.problem.groupoid, self.N
        dg = G.algebra_dim
        self.layout = layout
        U, Z, Y = [], [], []
        k = 0
        for j in range(N):
            U.append(np.arange(k, k + self.nu))
            k += self.nu
            Z.append(np.arange(k, k + self.nz))
            k += self.nz
            if self.second and j < N - 1:
                Y.append(np.arange(k, k + dg))
                k += dg
        assert k == self.n_stage
        self.U = np.array(U, dtype=np.int64).reshape(N, self.nu).T
        self.Z = np.array(Z, dtype=np.int64).T  # nz x N: z_1 .. z_N
        inner = np.array(Y, dtype=np.int64).reshape(-1, dg).T
        self.Y = np.hstack([layout.V0[:, None], inner, layout.VN[:, None]]) if self.second \
            else np.zeros((dg, 0), dtype=np.int64)
        self.identity = self.nz == G.state_size and all(
            type(c) is Coordinates for c in self.coords)
        self.states = np.hstack([layout.s0[:, None], self.Z]) if self.identity else \
            np.zeros((0, N + 1), dtype=np.int64)
        self.end_velocity = layout.VN

    def final_state(self) -> tuple[np.ndarray, ca.Function]:
        return self.Z[:, -1], self.to_s

    def reconstructed(self, r: Readout) -> list[tuple[np.ndarray, ca.MX]]:
        return []  # the states are the shooting's own variables: nothing to recompute

    # -- blocks -------------------------------------------------------------------------------

    def _X(self, nodes: list[int]) -> np.ndarray:
        """w-indices of ``X_k`` (z, then y) at the nodes k >= 1, one column per node."""
        cols = [k - 1 for k in nodes]
        return np.vstack([self.Z[:, cols], self.Y[:, nodes]]) if self.second else \
            self.Z[:, cols]

    def blocks(self) -> list[Block]:
        G, N, lay, pb = self.problem.groupoid, self.N, self.layout, self.problem
        assert lay is not None
        ds, npar, nX, dg = G.state_size, pb.P.numel(), self.n_X, G.algebra_dim
        first = np.concatenate([lay.s0, self.Y[:, 0]]) if self.second else lay.s0
        n_first = ds + (dg if self.second else 0)

        def start(X0: ca.SX) -> ca.SX:
            """X_0 from the stored initial state (and V_0)."""
            z0 = self.to_z(X0[:ds])
            return ca.vertcat(z0, X0[ds:]) if self.second else z0

        def gap(convert: bool) -> Any:
            def body(X: ca.SX, u: ca.SX, X1: ca.SX, T: ca.SX, P: ca.SX) -> Any:
                X_next, L = self.flow(start(X) if convert else X, u, T, P)
                return L, X1 - X_next
            return body

        def at_start(convert: bool, kind: Kind) -> Any:
            def body(X: ca.SX, u: ca.SX, P: ca.SX) -> Any:
                phi, H, _ = self.at_start(start(X) if convert else X, u, P)
                return ca.SX(1, 1), (phi if kind is Kind.PATH else H)
            return body

        labels = [f"{f.state}[{j}]" for f, c in zip(G.factors, self.coords) for j in range(c.size)]
        labels += [f"{f.velocity}[{j}]" for f in G.factors for j in range(f.algebra_dim)] \
            if self.second else []
        parts = [("0", True, n_first, first[:, None], [0]),
                 ("", False, nX, self._X(list(range(1, N))), list(range(1, N)))]
        blocks = []
        for suffix, convert, n_in, X_idx, ks in parts:
            if not ks:
                continue
            n = len(ks)
            blocks.append(Block(
                f"shoot{suffix}", stage_function(f"shoot{suffix}", [n_in, self.nu, nX, 1, npar],
                                                 gap(convert)),
                columns(X_idx, self.U[:, ks], self._X([k + 1 for k in ks]), lay.T,
                        lay.P, ncols=n), 1 + npar, Kind.RECONSTRUCTION,
                rows=[f"continuity {c}" for c in labels],
                columns=[f"interval {k}" for k in ks],
                next=slice(n_in + self.nu, n_in + self.nu + nX)))
            names = [n_ for n_, c in self.extra for _ in range(c.numel())]
            for kind, rows, bounds, there in (
                    (Kind.PATH, names, None, bool(self.extra)),
                    (Kind.INEQUALITY, self.stages.inequality_names,
                     self.stages.inequality_bounds(), bool(pb.inequalities))):
                if there:
                    tag = "path" if kind is Kind.PATH else "bounds"
                    blocks.append(Block(
                        f"{tag}{suffix}", stage_function(f"{tag}{suffix}",
                                                         [n_in, self.nu, npar],
                                                         at_start(convert, kind)),
                        columns(X_idx, self.U[:, ks], lay.P, ncols=n), npar, kind, rows,
                        [f"node {k}" for k in ks], np.array(ks, dtype=float) / N,
                        bounds=bounds))
        return blocks

    # -- guesses and read-out -----------------------------------------------------------------

    def point(self, XI: ca.MX, pick: Pick) -> list[tuple[np.ndarray, ca.MX]]:
        """States by forward composition of the interval velocities, node velocities their
        means, controls those the guess implies (inverse dynamics)."""
        lay, N, pb = self.layout, self.N, self.problem
        assert lay is not None
        T, P = pick(lay.T), pick(lay.P)
        h = T / N
        S = ca.horzcat(pick(lay.s0), self.stages.step.mapaccum(N)(pick(lay.s0), h * XI))
        Zg = self.to_z.map(N)(S[:, 1:])
        s, y, dy = ca.SX.sym("s", S.size1()), ca.SX.sym("y", XI.size1()), \
            ca.SX.sym("dy", XI.size1())
        ctrl = ca.Function("ctrl", [s, y, dy, pb.P], [self.stages.estimate(
            s, y, dy, pb.P, ca.DM.zeros(self.nu))] if self.stages.estimate is not None else
            self.stages.at([self.stages.controls], s, y, dy if pb.order == 2 else None))
        out = [(self.Z, Zg)]
        if not self.second:
            return out + [(self.U, ctrl.map(N)(S[:, :N], XI, ca.MX.zeros(XI.shape), P))]
        m = lay.masks
        V0 = ca.vertcat(*[pick(lay.V0[i:i + 1]) if m.start_velocity[i] else XI[i, 0]
                          for i in range(XI.size1())])
        VN = ca.vertcat(*[pick(lay.VN[i:i + 1]) if m.end_velocity[i] else XI[i, N - 1]
                          for i in range(XI.size1())])
        Y = ca.horzcat(V0, (XI[:, :-1] + XI[:, 1:]) / 2, VN)
        dY = (Y[:, 1:] - Y[:, :-1]) / h
        return out + [(self.Y[:, 1:N], Y[:, 1:N]), (lay.V0, V0), (lay.VN, VN),
                      (self.U, ctrl.map(N)(S[:, :N], Y[:, :N], dY, P))]

    def readout(self, pick: Pick) -> Readout:
        """Node states and (second order) node velocities as solved; the controls constant on
        each interval (PPoly of degree 0)."""
        lay, N = self.layout, self.N
        assert lay is not None
        T, P, U = pick(lay.T), pick(lay.P), pick(self.U)
        S = ca.horzcat(pick(lay.s0), self.to_s.map(N)(pick(self.Z)))
        t = np.arange(N + 1) / N
        if self.second:
            V = pick(self.Y)
            velocity_t, steps = t, T / N * (V[:, :-1] + V[:, 1:]) / 2
        else:
            assert self.dynamics.velocity is not None
            V = self.dynamics.velocity.map(N)(S[:, :N], U, P)
            velocity_t, steps = t[:N], T / N * V
        return Readout(steps, S, velocity_t, V, t[:N], U, t, U)

    def readout_steps(self, pick: Pick) -> ca.MX:
        return self.readout(pick).steps

    def unpack(self, w: np.ndarray) -> dict[str, np.ndarray]:
        lay = self.layout
        assert lay is not None
        out = {"u": w[self.U].T, "z": w[self.Z].T, "T": w[lay.T][0], "P": w[lay.P]}
        if self.second:
            out["y"] = w[self.Y].T
        return out

    def coordinate_values(self, w: np.ndarray) -> list[tuple[Any, np.ndarray]]:
        """The factors in this baseline's own coordinates, each with its values at the point
        w (size x N, nodes 1..N)."""
        z, start, found = w[self.Z], 0, []
        for f, c in zip(self.problem.groupoid.factors, self.coords):
            if c.name == self.coordinates and c.name != "quaternion":
                found.append((f, z[start:start + c.size]))
            start += c.size
        return found

class RK4Quaternion(RK4Shooting):
    name = "rk4_quat"
    coordinates = "quaternion"
    summary = ("baseline (to measure against): RK4 multiple shooting on unit quaternions, "
               "piecewise-constant controls, as a rockit/Opti user writes it")


class RK4Matrix(RK4Shooting):
    name = "rk4_matrix"
    coordinates = "matrix"
    summary = ("baseline (to measure against): RK4 multiple shooting on the 9 entries of "
               "the rotation matrix, piecewise-constant controls")

    def troubles(self, w: np.ndarray, failed: bool = False) -> list[str]:
        """The matrices' own distance from SO(3), ``max |R^T R - I|`` over the nodes: the
        read-out (a quaternion of R) cannot show it."""
        out = []
        for f, z in self.coordinate_values(w):
            R = z.T.reshape(-1, 3, 3).transpose(0, 2, 1)  # z holds R column by column
            drift = float(np.max(np.abs(R.transpose(0, 2, 1) @ R - np.eye(3))))
            if drift > ORTHOGONALITY_TOLERANCE:
                out.append(f"{f.state}'s rotation matrices are off SO(3) by {drift:.2g} "
                           "(max |R^T R - I|; nothing keeps them orthogonal): increase N, or "
                           "use rk4_quat, order2 or order4")
        return out


class RK4Euler(RK4Shooting):
    name = "rk4_euler"
    coordinates = "euler"
    summary = ("baseline (to measure against): RK4 multiple shooting in ZYX Euler angles "
               "(gimbal lock at pitch 90 deg), piecewise-constant controls")

    def troubles(self, w: np.ndarray, failed: bool = False) -> list[str]:
        """The largest pitch on the grid when it nears 90 degrees (gimbal lock), or, after a
        failed solve, wherever it is (the iterates may have fled the singular pitch)."""
        out = []
        for f, z in self.coordinate_values(w):
            pitch = float(np.degrees(np.max(np.abs(z[1]))))
            if pitch > PITCH_WARNING:
                out.append(f"{f.state}'s Euler pitch reaches {pitch:.1f} deg, where ZYX "
                           "angles are singular (gimbal lock, the rates tan(theta) and "
                           "1/cos(theta) blow up): use rk4_quat, order2 or order4")
            elif failed:
                out.append(f"the Euler-angle baseline failed (largest pitch on the last "
                           f"iterate {pitch:.1f} deg); ZYX angles are singular at a pitch of "
                           "90 deg, which a slew through it must pass: use rk4_quat, order2 "
                           "or order4")
        return out


PITCH_WARNING = 80.0  # degrees: a pitch the Euler baseline reports as near gimbal lock
ORTHOGONALITY_TOLERANCE = 1e-6  # max |R^T R - I| the matrix baseline lets pass
