"""The arithmetic of a closed loop as CasADi Functions: one definition for Python and C.

The closed loop (:mod:`ocgroupoid.mpc`) and the exported C loop (``{prefix}mpc.c``,
:mod:`ocgroupoid.export`) run the same computations; each is defined once here, as a
CasADi Function the Python loop evaluates and the export generates C of, so that both do the
same operations in the same order:

* :func:`plant_piece` — the plant over one piece of the applied control polynomial:
  :data:`SUBSTEPS` classical RK4 steps of the continuous dynamics;
* :func:`shift_function` — the last primal-dual point moved along its own time to the
  fractional stages sigma, an input (:func:`stages_after`: a receding or a shrinking
  horizon; :mod:`~ocgroupoid.mpc.shift` says how);
* :func:`with_state_function` — a measured state ``z = (s, y)`` into the parameters' initial
  state (each factor's state packed: quaternions normalised), and :func:`initial_state`,
  the state ``z`` p starts from;
* :func:`distance_function`, :func:`terminal_function`, :func:`violation_function` — what a
  step records: distances on the groupoid, the errors of a final state against p's targets,
  the largest violation of the NLP's bounds at their points.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import casadi as ca
import numpy as np

from ..errors import ConfigError
from ..model.problem import Problem
from .dynamics import Dynamics, rk4
from .stageform import StageForm
from .transcription import Transcription

#: RK4 substeps per control piece: at the samples of the problem files (h ~ 0.1-0.3 s,
#: rates ~ 1 rad/s) the integration error is ~1e-9, far below any noise or mismatch studied
SUBSTEPS = 16
#: the shortest horizon a shrinking loop solves, in samples, by default (Python's loop,
#: :mod:`ocgroupoid.mpc.loop`, and the exported C's ``MPC_MIN_HORIZON``): re-solve every sample
MIN_HORIZON = 1


def check_fixed_horizon(problem: Problem) -> None:
    """Refuse a problem whose final time is free: a closed loop samples a fixed horizon."""
    if problem.T_free:
        raise ConfigError("MPC needs a fixed horizon T; this problem's final time is free: "
                          "fix it (horizon.T) for the loop")


def plant_dynamics(tr: Transcription) -> ca.Function:
    """The continuous right-hand side ``rhs(z, u, P)`` a plant integrates; ConfigError for a
    problem without continuous second-order dynamics."""
    pb = tr.problem
    dyn = Dynamics(pb, tr.scheme.stages)
    if dyn.rhs is None or not dyn.second:
        raise ConfigError(f"{pb.name!r} has no continuous second-order dynamics to run a "
                          f"plant on ({dyn.reason or 'a first-order problem'}); MPC needs "
                          "a mechanical problem (mechanics() or accelerations as controls)")
    return dyn.rhs


def plant_piece(rhs: ca.Function, nz: int, k: int, m: int, n_P: int,
                name: str = "plant_piece") -> ca.Function:
    """``(z, c, tau0, dt, P) -> z``: :data:`SUBSTEPS` RK4 steps of ``dz/dt = rhs(z, u, P)``
    over dt from the local time tau0 of one polynomial piece (coefficients c, highest power
    first, m components, component fastest)."""
    z, c, tau0, dt, P = (ca.SX.sym(n, d) for n, d in (
        ("z", nz), ("c", k * m), ("tau0", 1), ("dt", 1), ("P", n_P)))
    cm = ca.reshape(c, m, k)
    step = dt / SUBSTEPS

    def u_at(t: Any) -> Any:
        u = cm[:, 0]
        for j in range(1, k):
            u = u * t + cm[:, j]
        return u

    zz = z
    for i in range(SUBSTEPS):
        t0 = tau0 + i * step

        def f(v: Any, s: float, t0: Any = t0) -> Any:
            return rhs(v, u_at(t0 + s * step), P)

        zz = rk4(f, zz, step)
    return ca.Function(name, [z, c, tau0, dt, P], [zz], ["z", "c", "tau0", "dt", "P"], ["z_end"])


# ---------------------------------------------------------------------------- the shift


@dataclass(frozen=True)
class Part:
    """One part of every stage: its offset and size per stage in a stage-ordered vector."""

    start: np.ndarray
    size: np.ndarray


def parts(sf: StageForm) -> tuple[list[Part], list[Part]]:
    """The (x, u) parts of z and the (gap, stage rows) parts of the rows, per stage."""
    nx, nu, ng = (np.asarray(v) for v in (sf.nx, sf.nu, sf.ng))
    z_start = np.concatenate([[0], np.cumsum(nx + nu)[:-1]])
    gaps = np.concatenate([nx[1:], [0]])  # stage k's gap rows define x_{k+1}
    r_start = np.concatenate([[0], np.cumsum(gaps + ng)[:-1]])
    return ([Part(z_start, nx), Part(z_start + nx, nu)],
            [Part(r_start, gaps), Part(r_start + gaps, ng)])


def stages_after(K: int, h: float, T: float, T_next: float) -> np.ndarray:
    """The fractional stage of the last point where each stage of the next sample's problem
    sits, ``sigma_k = K h / T + k T' / T`` (:mod:`~ocgroupoid.mpc.shift`; the exported C loop,
    ``{prefix}mpc.c``, computes it with the same operations in the same order)."""
    return K * h / T + np.arange(K + 1) * T_next / T


def _tent(sigma: ca.MX, J: np.ndarray) -> ca.MX:
    """The (m x m) tent weights ``w_jk = max(0, 1 - |min(max(sigma_k, 0), K) - j|)`` of the
    stages J (rows: sources j, columns: targets k)."""
    K, m = sigma.numel() - 1, J.size
    s = ca.fmin(ca.fmax(sigma[J.tolist()], 0.0), float(K))
    j = ca.repmat(ca.MX(ca.DM(J.astype(float))), 1, m)  # m numbers in the C, not m^2
    return ca.fmax(0.0, 1.0 - ca.fabs(ca.repmat(s.T, m, 1) - j))


def _moved(v: ca.MX, layout: Sequence[Part], sigma: ca.MX, tents: dict[bytes, ca.MX]
           ) -> ca.MX:
    """Every stage's parts of the stage-ordered vector v taken at the fractional stages sigma
    (:mod:`~ocgroupoid.mpc.shift`): per part and per group of stages J whose part has the
    same size n, the (n x m) matrix of their blocks times the tent weights of J
    (:func:`_tent`, kept in ``tents``), each column divided by its total — linear
    interpolation between the two stages around sigma_k; a column of total 0 (no stage of
    that size around sigma_k) keeps its own block."""
    index, blocks = np.arange(v.numel()), list[ca.MX]()
    for part in layout:
        for n in sorted(set(part.size.tolist()) - {0}):
            J = np.flatnonzero(part.size == n)
            if J.tobytes() not in tents:
                tents[J.tobytes()] = _tent(sigma, J)
            W = tents[J.tobytes()]
            at = (part.start[J][None, :] + np.arange(n)[:, None]).T.ravel()  # block by block
            V = ca.reshape(v[at.tolist()], n, J.size)
            total = ca.repmat(ca.sum1(W), n, 1)
            some = total > 0
            out = ca.if_else(some, ca.mtimes(V, W) / ca.if_else(some, total, 1.0), V)
            index[at] = v.numel() + sum(b.numel() for b in blocks) + np.arange(at.size)
            blocks.append(ca.vec(out))
    return ca.vertcat(v, *blocks)[index.tolist()]


def shift_function(tr: Transcription, sf: StageForm, name: str = "shift") -> ca.Function:
    """``(x, lam_g, lam_x, sigma) -> the same moved to the fractional stages sigma``
    (:func:`stages_after`; :mod:`~ocgroupoid.mpc.shift`): the point's variables and bound
    multipliers move as the parts of z, its constraint multipliers as the parts of the rows
    (:func:`parts`), in MX with one dense product per part and size, so that the generated C
    stays small. Python's loop evaluates it and the exported C runs it generated: the same
    arithmetic for both horizons."""
    x, lam_g, lam_x = ca.MX.sym("x", tr.nx), ca.MX.sym("lam_g", tr.ng), ca.MX.sym("lam_x", tr.nx)
    sigma = ca.MX.sym("sigma", sf.K + 1)
    z_parts, row_parts = parts(sf)
    tents: dict[bytes, ca.MX] = {}
    out = [sf.x_of(_moved(sf.z_of(x), z_parts, sigma, tents)),
           sf.rows_x(_moved(sf.rows_z(lam_g), row_parts, sigma, tents)),
           sf.x_of(_moved(sf.z_of(lam_x), z_parts, sigma, tents))]
    return ca.Function(name, [x, lam_g, lam_x, sigma], out, ["x", "lam_g", "lam_x", "sigma"],
                       ["x_next", "lam_g_next", "lam_x_next"])


# ------------------------------------------------------------------ states and parameters


def _packed(tr: Transcription, s: Any) -> list[Any]:
    """Each factor's state of s packed as a target (normalised, with its chart data)."""
    G = tr.problem.groupoid
    return [f.pack_target(s[ss]) for f, ss in zip(G.factors, G.state_layout.slices)]


def _states(tr: Transcription, packed: list[Any]) -> Any:
    """The stored state of each factor's packed target, concatenated."""
    return ca.vertcat(*(f.state_of_target(t) for f, t in zip(tr.problem.groupoid.factors,
                                                              packed)))


def with_state_function(tr: Transcription, name: str = "with_state") -> ca.Function:
    """``(p, z) -> p`` with the initial state (p's ``start`` and ``V0``) set to z."""
    G = tr.problem.groupoid
    p, z = ca.SX.sym("p", tr.np), ca.SX.sym("z", G.state_size + G.algebra_dim)
    ns, sl = G.state_size, tr.layout.p_slices
    parts_of_p = [p[i] for i in range(tr.np)]
    start = ca.vertcat(*_packed(tr, z[:ns]))
    parts_of_p[sl["start"]] = [start[i] for i in range(start.numel())]
    parts_of_p[sl["V0"]] = [z[ns + i] for i in range(G.algebra_dim)]
    return ca.Function(name, [p, z], [ca.vertcat(*parts_of_p)], ["p", "z"], ["p_measured"])


def initial_state(tr: Transcription, name: str = "initial_state") -> ca.Function:
    """``p -> z``: the state ``(s, y)`` p starts from."""
    G = tr.problem.groupoid
    p = ca.SX.sym("p", tr.np)
    sl = tr.layout.p_slices
    start = p[sl["start"]]
    packed = [start[ts] for ts in G.target_layout.slices]
    return ca.Function(name, [p], [ca.vertcat(_states(tr, packed), p[sl["V0"]])],
                       ["p"], ["z"])


def distance_names(tr: Transcription) -> list[str]:
    """The entries of :func:`distance_function`: each factor's state, then velocity."""
    G = tr.problem.groupoid
    return [f.state for f in G.factors] + [f.velocity for f in G.factors]


def distance_function(tr: Transcription, name: str = "distance") -> ca.Function:
    """``(a, b) -> d``: the distances of two states ``z = (s, y)`` (:func:`distance_names`),
    each state normalised first: the norm of ``rminus`` per factor (the rotation angle on
    SO(3)) and the Euclidean norm of each factor's velocities."""
    G = tr.problem.groupoid
    ns, nz = G.state_size, G.state_size + G.algebra_dim
    a, b = ca.SX.sym("a", nz), ca.SX.sym("b", nz)
    sa, sb = (_states(tr, _packed(tr, v[:ns])) for v in (a, b))
    d: list[Any] = [ca.norm_2(f.rminus(sa[ss], sb[ss]))
                    for f, ss in zip(G.factors, G.state_layout.slices)]
    d += [ca.norm_2(a[ns:][vs] - b[ns:][vs]) for vs in G.velocity_layout.slices]
    return ca.Function(name, [a, b], [ca.vertcat(*d)], ["a", "b"], ["d"])


def terminal_names(tr: Transcription) -> list[str]:
    """The entries of :func:`terminal_function` (those of
    :func:`~ocgroupoid.verify.replay.terminal_errors`)."""
    G, m = tr.problem.groupoid, tr.masks
    names = [f.state for f, mask in zip(G.factors, m.end_state) if mask.any()]
    if tr.problem.end_velocities:
        names += [f.velocity for f, vs in zip(G.factors, G.velocity_layout.slices)
                  if m.end_velocity[vs].any()]
    return names


def terminal_function(tr: Transcription, name: str = "terminal") -> ca.Function:
    """``(z, p) -> errors``: :func:`~ocgroupoid.verify.replay.terminal_errors` as a Function
    (:func:`terminal_names`): the final state's distance from p's targets over the
    prescribed components."""
    G, m = tr.problem.groupoid, tr.masks
    ns = G.state_size
    z, p = ca.SX.sym("z", ns + G.algebra_dim), ca.SX.sym("p", tr.np)
    target, VT = p[tr.layout.p_slices["end"]], p[tr.layout.p_slices["VN"]]
    out = []
    for f, ss, ts, mask in zip(G.factors, G.state_layout.slices, G.target_layout.slices,
                               m.end_state):
        if mask.any():
            v = f.rminus(z[ss], f.state_of_target(target[ts]))
            out.append(ca.norm_2(v[np.flatnonzero(mask).tolist()] if f.componentwise else v))
    if tr.problem.end_velocities:
        for vs in G.velocity_layout.slices:
            keep = np.flatnonzero(m.end_velocity[vs])
            if keep.size:
                out.append(ca.norm_2((z[ns:][vs] - VT[vs])[keep.tolist()]))
    return ca.Function(name, [z, p], [ca.vertcat(*out) if out else ca.SX(0, 1)], ["z", "p"],
                       ["errors"])


def violation_function(tr: Transcription, rows: np.ndarray,
                       name: str = "violation") -> ca.Function:
    """``(x, p) -> v``: the largest violation of the NLP's rows ``rows`` (its bounds at their
    points) by x; 0 without rows."""
    x, p = ca.MX.sym("x", tr.nx), ca.MX.sym("p", tr.np)
    if not rows.size:
        return ca.Function(name, [x, p], [ca.MX(0.0)], ["x", "p"], ["v"])
    idx = rows.tolist()
    g = tr.g_fun(x, p)[idx]
    lbg, ubg = (b[idx] for b in tr.bounds_function(p)[:2])
    v = ca.mmax(ca.fmax(0.0, ca.fmax(lbg - g, g - ubg)))
    return ca.Function(name, [x, p], [v], ["x", "p"], ["v"])
