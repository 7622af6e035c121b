"""A Solution from one IPOPT result: the read-out Function evaluated, then diagnosed.

Everything the Solution reports about the trajectory — node states by exact reconstruction,
velocities and controls with their time stamps, the multipliers lambda^k of Phi_d and of
the final conditions — comes from
:attr:`~ocgroupoid.nlp.transcription.Transcription.readout_function`, the Function that
exported C evaluates too.
"""

from __future__ import annotations

import copy
import time
from dataclasses import replace
from typing import Any, Sequence
from weakref import WeakKeyDictionary

import numpy as np

from ..nlp.assembly import Kind
from ..nlp.transcription import RawResult, Transcription
from ..verify.diagnostics import diagnose
from ..verify.verdict import REPLAY_TOLERANCE, check_tolerance, scales, tolerances, verdict
from .hints import hint_for
from .rows import Rows
from .solution import Solution


def make_solution(tr: Transcription, r: RawResult, minima: Sequence[Any],
                  replay: bool = True, ipopt: dict[str, Any] | None = None,
                  replay_tolerance: float = REPLAY_TOLERANCE) -> Solution:
    """Assemble a Solution (trajectory, controls, multipliers, diagnostics) from a result;
    ``success`` is the :mod:`~ocgroupoid.verify.verdict` (``ipopt``: the options solved with)."""
    pb, G = tr.problem, tr.problem.groupoid
    t0 = time.perf_counter()
    g_nlp = np.array(tr.g_fun(r.x, r.p)).ravel()
    recon_nlp = float(np.max(np.abs(g_nlp[tr.rows(Kind.RECONSTRUCTION).ravel()])))
    out = tr.readout(r.x, r.p, r.lam_g)
    r = replace(r, x=out["x_solution"])
    shown = out["states"]
    states, k = {}, 0
    for f in G.factors:
        n = int(np.prod(f.matrix_shape))
        states[f.state] = shown[:, k:k + n].reshape(-1, *f.matrix_shape)
        k += n
    velocities = {f.velocity: out["velocities"][:, vs]
                  for f, vs in zip(G.factors, G.velocity_layout.slices)}
    mult: dict[str, Any] = {"t": out["multiplier_t"],
                            "names": [n for n, c in pb.constraints for _ in range(c.numel())]}
    if out["multipliers"].size:
        mult["Phi"] = out["multipliers"]
    if out["final_multipliers"].size:
        mult["final"] = out["final_multipliers"]
    ppoly = control_ppoly(out)
    diagnostics = diagnose(tr, r.x, r.p, r.lam_g, out, ppoly, replay=replay, solved=r.success)
    diagnostics["reconstruction_residual_nlp"] = recon_nlp
    diagnostics["runs"] = runs(r)
    scale = scales(tr, out, r.p)  # the distances covered, for the verdict and its record
    failures = verdict(tr, r, out, diagnostics, ipopt, replay_tolerance, scale)
    diagnostics["verdict"] = {"verified": r.success and not failures, "failures": failures,
                              "check_tolerance": check_tolerance(ipopt),
                              "replay_tolerance": replay_tolerance,
                              "tolerances": tolerances(tr, out, r.p, replay_tolerance, scale)}
    diagnostics["seconds"] = time.perf_counter() - t0
    hint = "; ".join(failures) if failures else hint_for(tr, r, out["steps"])
    T = tr.horizon(r.x, r.p)
    P = tr.part(r.p, "P")
    params = {name: P[sl].tolist() for name, sl in pb.parameter_slices.items()}
    return Solution(
        problem=pb.name, success=r.success and not failures, status=r.status, N=tr.N, T=T,
        cost=r.cost,
        iterations=r.iterations, solve_seconds=r.solve_seconds, backend=r.backend,
        build_seconds=tr.build_seconds,
        discretization={"scheme": tr.disc.scheme, "retraction": tr.scheme.retraction,
                        "rule": tr.disc.rule, "order": pb.order, "start": r.label,
                        "steps": tr.disc.steps,
                        **({"T_range": list(pb.T_bounds)} if pb.T_free else {})},
        parameters=params, t=out["t"], states=states, velocity_t=out["velocity_t"],
        velocities=velocities, controls_t=out["control_t"], controls=out["controls"],
        control_names=[n for n, _ in pb.controls], multipliers=mult, diagnostics=diagnostics,
        minima=[m.__dict__ for m in minima], hint=hint, x=r.x, p=r.p, lam_g=r.lam_g,
        lam_x=r.lam_x,
        control_ppoly=ppoly, manifolds={f.state: f.manifold for f in G.factors},
        labels=labels_at(tr, P), rows=Rows.of(tr),
    )


#: per transcription, the parameter values of its last labels and those labels
_labels: WeakKeyDictionary[Transcription, tuple[bytes, dict[str, Any]]] = WeakKeyDictionary()


def labels_at(tr: Transcription, P: np.ndarray) -> dict[str, Any]:
    """The problem's labels (``Problem.labels``) at the parameter values P, a copy of the
    last ones while P repeats: their symbolic analysis of every bound took 4-6 ms a solve on
    the quadrotor and the reaction wheels."""
    key = np.asarray(P, dtype=float).tobytes()
    if tr not in _labels or _labels[tr][0] != key:
        _labels[tr] = (key, tr.problem.labels(P))
    return copy.deepcopy(_labels[tr][1])


def runs(r: RawResult) -> list[dict[str, Any]]:
    """Every run of the solve from the start that produced ``r``, in order: the runs before it
    (a fatrop run that stopped at an acceptable point before IPOPT's polish, a failed one
    before a rescue or IPOPT's fallback) and its own, each ``{"backend", "status",
    "iterations"}``. ``Solution.iterations`` is the last run's; ``solve_seconds`` counts them
    all."""
    return [{"backend": who, "status": status, "iterations": int(iterations)}
            for who, status, iterations in (*r.earlier, (last_run(r.backend), r.status,
                                                         r.iterations))]


def last_run(backend: str) -> str:
    """Who ran last in a solve's label (``ipopt polish`` of ``ipopt polish after fatrop``)."""
    return backend.split(" after ")[0]


def control_ppoly(out: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """``{"x": breakpoints, "c": (k, pieces, m)}`` of the read-out's control polynomial."""
    x, coeff = out["control_breaks"], out["control_coefficients"]  # coeff: pieces x (k m)
    m = out["controls"].shape[1]
    pieces = x.size - 1
    k = coeff.size // max(pieces * m, 1) if m else 0
    return {"x": x, "c": coeff.T.reshape(k, m, pieces).transpose(0, 2, 1)}
