"""The NLP solvers behind one interface (:mod:`~ocgroupoid.nlp.backends.base`): IPOPT on the
whole sparse KKT system, fatrop on the stage form, and the policy that runs them in turn."""

from __future__ import annotations

from ..options import SolverOptions
from .base import INTERRUPTED, LISTENER_STOP, TIMED_OUT, Backend, Graph, Run, Start
from .fatrop import FatropBackend
from .ipopt import DEFAULT_IPOPT, IpoptBackend, evaluated, ipopt_options
from .policy import in_turn


def compiled_together(options: SolverOptions) -> bool:
    """Whether IPOPT's Functions are compiled beside fatrop's, in one library (fatrop with
    ``jit``): the NLP's assemblies then take every stage Hessian from the stage Lagrangian's
    Function (:class:`~ocgroupoid.nlp.assembly.Derivatives`), which both call."""
    return options.jit and options.backend == FatropBackend.name


def build(nlp: Graph, options: SolverOptions) -> list[Backend]:
    """The backends a solve of ``nlp`` runs in turn (:func:`in_turn`): IPOPT; or fatrop,
    then IPOPT from the same start when fatrop fails, or from its point when it stopped near
    a solution. With ``jit`` both are compiled, into one library (their stage derivatives
    once: ``nlp.derivatives`` with the Lagrangian's Hessian for both)."""
    if options.backend == FatropBackend.name:
        fatrop = FatropBackend(nlp, options, options.jit,
                               evaluated(nlp) if compiled_together(options) else None)
        return [fatrop, IpoptBackend(nlp, options, compiled_functions=fatrop.compiled_beside)]
    return [IpoptBackend(nlp, options, options.jit)]


__all__ = ["Backend", "Graph", "Run", "Start", "IpoptBackend", "FatropBackend", "build",
           "compiled_together", "in_turn", "ipopt_options", "DEFAULT_IPOPT", "TIMED_OUT",
           "LISTENER_STOP", "INTERRUPTED"]
