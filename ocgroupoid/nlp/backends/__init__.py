"""The NLP solvers behind one interface (:mod:`~ocgroupoid.nlp.backends.base`): IPOPT on the
whole sparse KKT system, fatrop on the stage form, and the policy that runs them in turn."""

from __future__ import annotations

from ..options import SolverOptions
from .base import INTERRUPTED, TIMED_OUT, Backend, Graph, Run, Start
from .fatrop import FatropBackend
from .ipopt import DEFAULT_IPOPT, IpoptBackend, ipopt_options
from .policy import in_turn


def build(nlp: Graph, options: SolverOptions) -> list[Backend]:
    """The backends a solve of ``nlp`` runs in turn (:func:`in_turn`): IPOPT; or fatrop,
    then IPOPT from the same start when fatrop fails. Compiled evaluation (``jit``) is the
    first backend's."""
    if options.backend == FatropBackend.name:
        ipopt = IpoptBackend(nlp, options)
        return [FatropBackend(nlp, options, options.jit), ipopt]
    return [IpoptBackend(nlp, options, options.jit)]


__all__ = ["Backend", "Graph", "Run", "Start", "IpoptBackend", "FatropBackend", "build",
           "in_turn", "ipopt_options", "DEFAULT_IPOPT", "TIMED_OUT", "INTERRUPTED"]
