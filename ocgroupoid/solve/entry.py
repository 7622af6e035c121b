"""The two calls of the API: ``compile_problem`` a problem with a method and solver options, and
``solve`` it in one go.

>>> method = og.Method(N=64, scheme="order4")                         # doctest: +SKIP
>>> sol = og.solve(problem, method, og.SolverOptions(multistart=True))  # doctest: +SKIP
>>> sol = og.solve(problem, N=64, scheme="order4", multistart=True)     # doctest: +SKIP

The last line is the same solve: the keywords are the shortcuts of the two objects
(:mod:`~ocgroupoid.nlp.shortcuts`).
"""

from __future__ import annotations

from typing import Any

from ..model.problem import Problem
from ..nlp.method import METHOD_KEYS, Method
from ..nlp.options import OPTION_KEYS, SolverOptions
from .compiled import CompiledProblem
from .solution import Solution


def compile_problem(problem: Problem, method: Method | int | None = None,
            options: SolverOptions | str | None = None, *positional: Any,
            **keywords: Any) -> CompiledProblem:
    """Build the NLP of ``problem`` once with ``method`` (N intervals, scheme, retraction,
    rule, uniform or adaptive steps, bound points) and ``options`` (backend, IPOPT's options,
    compiled evaluation ``jit``, the wall time ``max_seconds`` of one solve, multi-start and
    continuation); see :class:`CompiledProblem`. Keywords replace fields of either
    (``compile_problem(problem, N=64, backend="fatrop")``)."""
    return CompiledProblem(problem, method, options, *positional, **keywords)


def solve(problem: Problem, method: Method | int | None = None,
          options: SolverOptions | str | None = None, *positional: Any,
          **keywords: Any) -> Solution:
    """Build and solve in one call: the keywords of a method or of the options as in
    :func:`compile_problem`, the others (``params``, ``initial``, ``final``, ``T``, ``guess``, ...)
    go to :meth:`CompiledProblem.solve`."""
    ours = {k: v for k, v in keywords.items() if k in METHOD_KEYS or k in OPTION_KEYS}
    rest = {k: v for k, v in keywords.items() if k not in ours}
    return compile_problem(problem, method, options, *positional, **ours).solve(**rest)
