"""The verdict's checks as one CasADi Function, for the exported C solver.

``verify(x, p, lam_g) -> (ratios, figures)``: what :mod:`~ocgroupoid.verify.verdict` checks
of a solution that a compiled program can check too, each as a ratio to its tolerance (a
check passes when its ratio is at most 1):

* ``residual``: the largest equality residual and bound violation at the points where the
  bounds are imposed, over :func:`~ocgroupoid.verify.verdict.check_tolerance`;
* ``landing``: the largest miss of the replayed plan (:mod:`~ocgroupoid.verify.replay`, RK4
  with a fixed number of substeps per piece) over its landing tolerance;
* ``bounds``: the largest bound violation along the replay over its tolerance;
* ``constraints``: for a plan driven by its velocities, the constraints along the replay;
* ``integration``: the replay's own error (its substeps against half as many, /15) over a
  thousandth of the landing tolerance: a replay that has not converged verifies nothing.

``figures`` are the numbers behind them: the largest miss, the largest bound violation along
the replay, the cost recomputed along it. The Python path runs the same replay with its
substeps doubled until converged; the exported solver uses the count a Python solve of the
exported instance needed, doubled.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..nlp.program import READOUT_OUTPUTS
from ..nlp.transcription import Transcription
from .replay import Replay
from .verdict import FLOOR

#: the ratios, in the order the Function returns them (exported C: enum ocg_check)
CHECKS = ("residual", "landing", "bounds", "constraints", "integration")
#: the figures behind them
FIGURES = ("max_terminal_error", "bound_violation_max", "replay_cost")


def verify_function(tr: Transcription, replay: Replay, substeps: int, check_tol: float,
                    replay_tolerance: float) -> ca.Function:
    """``verify(x, p, lam_g) -> (ratios, figures)`` (module docstring)."""
    pb, G = tr.problem, tr.problem.groupoid
    x, p, lam = ca.MX.sym("x", tr.nx), ca.MX.sym("p", tr.np), ca.MX.sym("lam_g", tr.ng)
    out = dict(zip(READOUT_OUTPUTS, tr.readout_function(x, p, lam)))
    g = ca.Function("g", [tr.nlp["x"], tr.nlp["p"]], [tr.nlp["g"]])(x, p)
    lbg, ubg, _, _ = tr.bounds_function(p)
    residual = ca.mmax(ca.fmax(lbg - g, g - ubg))
    ratios = {"residual": residual / check_tol}
    P = p[tr.layout.p_slices["P"]]
    states, velocities = out["node_states"], out["velocities"]
    if replay.rhs is None:  # nothing to drive: the verdict cannot be given
        nan = ca.MX(np.nan)
        return _function(x, p, lam, {**ratios, "landing": nan, "bounds": nan,
                                     "constraints": nan, "integration": nan},
                         {"max_terminal_error": nan, "bound_violation_max": nan,
                          "replay_cost": nan})
    if replay.input == "velocities":
        breaks, coeff = out["t"], _velocity_coefficients(out["velocity_t"], velocities,
                                                          out["t"], tr.N)
    else:
        breaks, coeff = out["control_breaks"], out["control_coefficients"]
    n = tr.N if replay.input == "velocities" else int(coeff.size2())
    m = (velocities.size1() if replay.input == "velocities"
         else out["controls"].size1())
    k = int(coeff.size1()) // max(m, 1) if m else 0
    second = pb.end_velocities and replay.input == "controls"
    z0 = ca.vertcat(states[:, 0], velocities[:, 0] if second else ca.MX(0, 1), 0)
    h = breaks[:, 1:] - breaks[:, :-1]
    Ps = ca.repmat(P, 1, n)
    coarse = replay._path(k, m, substeps // 2, n)(z0, coeff, h, Ps)[:, -1]
    zs, H, psi = replay._pieces(k, m, substeps, n)(z0, coeff, h, Ps)
    z = zs[:, -1]
    ns = G.state_size
    s_end = z[:ns]
    y_end = z[ns:-1] if second else None
    errors, scales = _landing(tr, states, velocities, out["steps"], s_end, y_end, p)
    tolerance = replay_tolerance * scales + FLOOR
    worst_miss = ca.mmax(errors) if errors.numel() else ca.MX(0)
    ratios["landing"] = ca.mmax(errors / tolerance) if errors.numel() else ca.MX(0)
    integration = ca.mmax(ca.fabs(z[:-1] - coarse[:-1])) / 15
    ratios["integration"] = integration / (1e-3 * ca.mmin(tolerance)) if errors.numel() \
        else ca.MX(0)
    if H.numel():
        lo, hi = replay.sides(P)
        over = _rowmax(H) - hi
        under = lo + _rowmax(-H)
        violation = ca.fmax(ca.fmax(over, under), 0)
        finite = lambda v: ca.if_else(ca.fabs(v) < 1e300, ca.fabs(v), 0)  # noqa: E731
        size = ca.fmax(ca.fmax(finite(lo), finite(hi)), 1)
        ratios["bounds"] = ca.mmax(violation / (replay_tolerance * size))
        worst_violation = ca.mmax(violation)
    else:
        ratios["bounds"], worst_violation = ca.MX(0), ca.MX(0)
    if psi.numel():
        limit = replay_tolerance * ca.fmax(1, ca.mmax(ca.fabs(states)))
        ratios["constraints"] = ca.mmax(psi) / limit
    else:
        ratios["constraints"] = ca.MX(0)
    T = tr.layout.gather(ca.vertcat(x, p), tr.layout.T)
    cost = z[-1] + pb.weights["time"] * T
    return _function(x, p, lam, ratios, {"max_terminal_error": worst_miss,
                                         "bound_violation_max": worst_violation,
                                         "replay_cost": cost})


def _function(x: ca.MX, p: ca.MX, lam: ca.MX, ratios: dict[str, ca.MX],
              figures: dict[str, ca.MX]) -> ca.Function:
    return ca.Function("verify", [x, p, lam],
                       [ca.vertcat(*[ratios[c] for c in CHECKS]),
                        ca.vertcat(*[figures[f] for f in FIGURES])],
                       ["x", "p", "lam_g"], ["ratios", "figures"])


def _rowmax(A: ca.MX) -> ca.MX:
    """The largest entry of every row."""
    return ca.mmax(A.T) if A.size1() == 1 else ca.vertcat(*[ca.mmax(A[i, :])
                                                             for i in range(A.size1())])


def _velocity_coefficients(tv: ca.MX, V: ca.MX, t: ca.MX, N: int) -> ca.MX:
    """:func:`~ocgroupoid.verify.replay.velocity_ppoly` as a graph: per interval the
    polynomial through its k velocity samples (one: a constant; two: a line; three: a
    quadratic), from its Newton form; rows ``power * m + component``, highest power first."""
    k = tv.size2() // N
    m = V.size1()
    a = [ca.repmat(tv[:, i::k] - t[:, :-1], m, 1) for i in range(k)]  # sample times in t - t_k
    d = [V[:, i::k] for i in range(k)]  # divided differences, built in place
    for j in range(1, k):
        for i in range(k - 1, j - 1, -1):
            d[i] = (d[i] - d[i - 1]) / (a[i] - a[i - j])
    coeff = [d[k - 1]]  # Horner: multiply by (x - a_j) and add d_j, low powers first
    for j in range(k - 2, -1, -1):
        coeff = [-a[j] * coeff[0] + d[j]] + \
            [coeff[p - 1] - a[j] * coeff[p] for p in range(1, len(coeff))] + [coeff[-1]]
    return ca.vertcat(*coeff[::-1])


def _landing(tr: Transcription, states: ca.MX, velocities: ca.MX, steps: ca.MX, s: ca.MX,
             y: ca.MX | None, p: ca.MX) -> tuple[ca.MX, ca.MX]:
    """The replay's misses of the prescribed final values and the distances they are
    measured against (:func:`~ocgroupoid.verify.verdict.scales`), as graphs."""
    G, m = tr.problem.groupoid, tr.masks
    target = p[tr.layout.p_slices["end"]]
    errors: list[ca.MX] = []
    scales: list[ca.MX] = []
    for f, ss, ts, vs, mask in zip(G.factors, G.state_layout.slices, G.target_layout.slices,
                                   G.velocity_layout.slices, m.end_state):
        if not mask.any():
            continue
        goal = f.state_of_target(target[ts])
        keep = np.flatnonzero(mask).tolist() if f.componentwise else slice(None)
        errors.append(ca.norm_2(ca.vec(f.rminus(s[ss], goal))[keep]))  # type: ignore[index, arg-type]
        path = ca.sum2(ca.sqrt(ca.sum1(steps[vs, :] ** 2)))
        straight = ca.norm_2(ca.vec(f.rminus(states[ss, 0], goal))[keep])  # type: ignore[index]
        scales.append(ca.fmax(path, straight))
    if y is not None and tr.problem.end_velocities:
        VT = p[tr.layout.p_slices["VN"]]
        for vs in G.velocity_layout.slices:
            mask = m.end_velocity[vs]
            if mask.any():
                keep = np.flatnonzero(mask).tolist()
                errors.append(ca.norm_2((y[vs] - VT[vs])[keep]))
                scales.append(ca.mmax(ca.sqrt(ca.sum1(velocities[vs, :] ** 2))))
    if not errors:
        return ca.MX(0, 1), ca.MX(0, 1)
    return ca.vertcat(*errors), ca.vertcat(*scales)
