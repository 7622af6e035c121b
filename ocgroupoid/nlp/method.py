"""How a problem is discretised: the method (N, scheme, retraction, rule, steps), one object.

rockit writes ``ocp.method(MultipleShooting(N=20))``; here ``og.Method(N=64,
scheme="order4")``. It is validated once, when it is made, and passed whole to everything
that builds an NLP. Every default of a discretisation is here (the scheme's and the rule's
are the schemes' own, :mod:`~ocgroupoid.nlp.schemes`).
:class:`Discretization` is a method with the phases of adaptive steps, which the solver
places itself (:mod:`~ocgroupoid.nlp.mesh`).
"""

from __future__ import annotations

from dataclasses import KW_ONLY, asdict, dataclass, fields

from ..errors import ConfigError
from ..lie.retraction import RETRACTION_NAMES
from .schemes import DEFAULT_RULE, DEFAULT_SCHEME, SCHEME_NAMES

#: the number of intervals of a method that names none
DEFAULT_N = 64
#: the retraction of the group factors: rational, branch-free, no singularity below pi
DEFAULT_RETRACTION = "cayley"
#: uniform steps h = T/N, or adaptive ones (a step per phase, the phases' durations free)
STEPS = ("uniform", "adaptive")
DEFAULT_STEPS = "uniform"
#: the most points per interval where the bounds are imposed besides the scheme's own
MAX_BOUND_POINTS = 16
#: adaptive steps stay within [STEP_RANGE[0], STEP_RANGE[1]] times the uniform step T/N
STEP_RANGE = (0.1, 10.0)


@dataclass(frozen=True)
class Method:
    """N intervals, a scheme, the retraction of the group factors, the rule of the
    constraints, the steps (uniform h = T/N, or adaptive) and the bounds' extra points.

    >>> Method(N=64, scheme="order4")        # doctest: +SKIP
    """

    N: int = DEFAULT_N
    _: KW_ONLY
    scheme: str = DEFAULT_SCHEME
    retraction: str = DEFAULT_RETRACTION
    rule: str = DEFAULT_RULE
    steps: str = DEFAULT_STEPS
    #: bounds imposed at this many more points inside every interval (uniformly spaced),
    #: beyond the scheme's own; order4 and order6 only
    bound_points: int = 0

    def __post_init__(self) -> None:
        if not isinstance(self.N, int) or isinstance(self.N, bool) or self.N < 2:
            raise ConfigError(f"N must be an integer >= 2, got {self.N!r}")
        if self.retraction not in RETRACTION_NAMES:
            raise ConfigError(
                f"unknown retraction {self.retraction!r}; choose one of "
                f"{', '.join(RETRACTION_NAMES)}"
            )
        if self.scheme not in SCHEME_NAMES:
            raise ConfigError(f"unknown scheme {self.scheme!r}; choose one of "
                              f"{', '.join(SCHEME_NAMES)}")
        if self.steps not in STEPS:
            raise ConfigError(f"steps are {' or '.join(STEPS)}, got {self.steps!r}")
        if isinstance(self.bound_points, bool) or not isinstance(self.bound_points, int) or \
                not 0 <= self.bound_points <= MAX_BOUND_POINTS:
            raise ConfigError(f"bound_points is an integer in 0..{MAX_BOUND_POINTS} (more points "
                              f"per interval where the bounds hold), got {self.bound_points!r}")


#: the names of a method's options (the keyword shortcuts of og.solve that make one)
METHOD_KEYS = tuple(f.name for f in fields(Method) if f.name != "_")


@dataclass(frozen=True, kw_only=True)
class Discretization(Method):
    """A method with adaptive steps placed: ``phases`` (interval counts summing to N),
    uniform within each phase, the phases' durations free (seed 001, §6.3: time as a variable
    of the discrete problem). The solver chooses the phases so that phase boundaries — nodes
    — fall on the switches of the controls (:mod:`ocgroupoid.nlp.mesh`)."""

    phases: tuple[int, ...] = ()
    #: adaptive steps: per phase, per bound row, the side held throughout the phase (+1 upper,
    #: -1 lower, 0 none): a bang-bang arc as an equality, so that the phases' durations are
    #: the switching times (:mod:`ocgroupoid.nlp.mesh`)
    active: tuple[tuple[int, ...], ...] = ()

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.active and len(self.active) != len(self.phases):
            raise ConfigError(f"active sides are given for {len(self.active)} phases, the "
                              f"grid has {len(self.phases)}")
        if self.phases and (sum(self.phases) != self.N or min(self.phases) < 1):
            raise ConfigError(f"phases {self.phases} must be positive interval counts summing "
                              f"to N = {self.N}")

    @classmethod
    def of(cls, method: Method) -> Discretization:
        """The discretisation of a method (itself when it is one already)."""
        if isinstance(method, Discretization):
            return method
        if not isinstance(method, Method):
            raise ConfigError(f"method must be an og.Method, got {type(method).__name__}")
        return cls(**asdict(method))
