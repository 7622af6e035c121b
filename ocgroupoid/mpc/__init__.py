"""Closed-loop model predictive control: converged re-solves or real-time iterations.

``og.mpc(problem, N, ...)`` (:mod:`~ocgroupoid.mpc.loop`) runs a problem against a simulated
plant (:mod:`~ocgroupoid.mpc.plant`) and returns an :class:`MpcResult`
(:mod:`~ocgroupoid.mpc.report`: ``DIR/mpc.json``, the figure). The pieces the exported C
loop shares (:mod:`ocgroupoid.export.mpc`): the initial-value embedding
(:mod:`~ocgroupoid.nlp.embedding`), the shift of the last point (:mod:`~ocgroupoid.mpc.shift`),
the real-time iteration's prepare/feedback split (:mod:`~ocgroupoid.mpc.rti` on
:mod:`~ocgroupoid.nlp.rti`) and the two feedback laws (:mod:`~ocgroupoid.mpc.controller`).
"""

from .loop import HORIZONS, mpc
from .plant import Plant
from .report import MpcResult, Step
from .rti import HESSIANS, QP_SOLVERS, RealTimeIteration

__all__ = ["mpc", "MpcResult", "Step", "Plant", "RealTimeIteration", "HORIZONS", "QP_SOLVERS",
           "HESSIANS"]
