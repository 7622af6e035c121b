"""A problem file's ``discretization`` and ``solver`` sections as the API's two objects:
:class:`~ocgroupoid.nlp.method.Method` and :class:`~ocgroupoid.nlp.options.SolverOptions`.

The sections are validated as the file is loaded (:mod:`~ocgroupoid.files.schema`); the
objects validate the same values again, so a file and a script that say the same thing
build the same solver: ``og.compile_problem(*files.build_all(cfg))``.
"""

from __future__ import annotations

from ..errors import ConfigError
from ..model.problem import Problem
from ..nlp.method import Method
from ..nlp.options import SolverOptions
from ..solve.accuracy import AUTO_BUILT
from .load import Config, build


def method(cfg: Config) -> Method:
    """The method of a problem file: ``horizon.N`` and the ``discretization`` section. With
    ``horizon.N: auto``, the first grid of the search (``horizon.N_min``) and, with
    ``scheme: auto``, :data:`~ocgroupoid.solve.accuracy.AUTO_BUILT` (the search itself tries
    each of :data:`~ocgroupoid.solve.accuracy.AUTO_SCHEMES`)."""
    f = cfg.file
    d = f.discretization
    N = f.horizon.grids[0] if f.horizon.N == "auto" else f.horizon.N
    scheme = AUTO_BUILT if d.scheme == "auto" else d.scheme
    try:
        return Method(N, scheme=scheme, retraction=d.retraction, rule=d.rule, steps=d.steps,
                      bound_points=d.bound_points)
    except ConfigError as err:
        raise ConfigError(f"{cfg.locate('discretization')}: {err}") from None


def options(cfg: Config) -> SolverOptions:
    """The solver options of a problem file: its ``solver`` section (the accuracy targets of
    ``horizon.N: auto`` are the search's, :func:`~ocgroupoid.solve.accuracy.solve_to_accuracy`)."""
    s = cfg.file.solver
    try:
        return SolverOptions(backend=s.backend, ipopt=dict(s.ipopt), fatrop=dict(s.fatrop),
                             jit=s.jit, max_seconds=s.max_seconds, multistart=s.multistart,
                             continuation=tuple(s.continuation), workers=s.workers)
    except ConfigError as err:
        raise ConfigError(f"{cfg.locate('solver')}: {err}") from None


def build_all(cfg: Config) -> tuple[Problem, Method, SolverOptions]:
    """The problem (:func:`~ocgroupoid.files.load.build`), the method and the solver options
    of a problem file."""
    return build(cfg), method(cfg), options(cfg)
