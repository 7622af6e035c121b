"""What a benchmark compares: a scheme with a retraction (``order2:exp``), and the grids.

A method is written ``SCHEME[:RETRACTION][@BACKEND][+jit][+coarse]`` (``order2``,
``order4:exp``, ``rk4_quat``, ``order4@fatrop+jit``, ``order4@fatrop+jit+coarse``); the
retraction defaults to cayley and is ignored by the RK4 baselines, which integrate the
continuous dynamics in their own coordinates; the backend (``solver.backend``) defaults to
ipopt, ``+jit`` compiles the evaluations (``solver.jit``), and ``+coarse`` solves on N /
:data:`COARSE_FACTOR` intervals first and on N from that solution, interpolated
(``solver.continuation: [N/4]``; :meth:`Method.coarse_N`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from typing import Any

from ..errors import ConfigError
from ..lie.retraction import RETRACTION_NAMES
from ..lie.rn import Rn
from ..model.problem import Problem
from ..nlp.method import DEFAULT_RETRACTION, Method as Discretisation
from ..nlp.options import BACKENDS, DEFAULT_BACKEND, MAX_SECONDS, SolverOptions
from ..nlp.schemes import BASELINES, DEFAULT_RULE, SCHEME_NAMES
from ..nlp.schemes.coordinates import coordinates

#: a ``+coarse`` method on N intervals solves on N / COARSE_FACTOR first (plate_ball,
#: order4@fatrop+jit from its geodesic, N = 32, 64, 128: 37, 29, 42 iterations cold, 16, 26,
#: 76 ms; 50, 48, 37 iterations on N / 4 and 6, 5, 4 on N, 11, 18, 26 ms in all; N / 2: 15,
#: 22, 36 ms; N / 8: 8, 14, 23 ms, but the heavy top's N = 4 found another minimum than its
#: N = 32's)
COARSE_FACTOR = 4
#: the coarsest grid a ``+coarse`` method solves first; below it the method solves cold
COARSE_MIN = 8
#: the flags a method's label may end with, in this order
FLAGS = ("jit", "coarse")


@dataclass(frozen=True)
class Method:
    """A scheme and the retraction of its group factors."""

    scheme: str
    retraction: str = DEFAULT_RETRACTION
    backend: str = DEFAULT_BACKEND
    jit: bool = False
    #: solved on :meth:`coarse_N` intervals first, then on N from that solution
    coarse: bool = False

    @property
    def baseline(self) -> bool:
        """Whether it is an RK4 shooting baseline (:data:`~ocgroupoid.nlp.schemes.BASELINES`)."""
        return self.scheme in BASELINES

    @property
    def label(self) -> str:
        """``order2`` (cayley), ``order2:exp``, ``rk4_quat``: how options and charts name it."""
        name = self.scheme if self.baseline or self.retraction == DEFAULT_RETRACTION else \
            f"{self.scheme}:{self.retraction}"
        return name + ("" if self.backend == DEFAULT_BACKEND else f"@{self.backend}") + \
            ("+jit" if self.jit else "") + ("+coarse" if self.coarse else "")

    def coarse_N(self, N: int) -> int | None:
        """The grid solved first on N intervals: N / :data:`COARSE_FACTOR` for a ``+coarse``
        method when that is at least :data:`COARSE_MIN`, else None (solved cold)."""
        n = N // COARSE_FACTOR
        return n if self.coarse and n >= COARSE_MIN else None

    @staticmethod
    def split(label: str) -> tuple[str, str]:
        """A label's ``SCHEME[:RETRACTION]`` and the rest (``@fatrop+jit``, or "")."""
        head = re.split("[@+]", label)[0]
        return head, label[len(head):]

    def rule(self, file_rule: str) -> str:
        """The problem file's rule applies to order2; every other scheme has only the
        midpoint rule."""
        return file_rule if self.scheme == "order2" else DEFAULT_RULE

    def on(self, N: int, file_rule: str, steps: str) -> Discretisation:
        """The API's method (:class:`~ocgroupoid.nlp.method.Method`) of this one on N
        intervals, with the problem file's rule where it applies (:meth:`rule`) and steps."""
        return Discretisation(N, scheme=self.scheme, retraction=self.retraction,
                              rule=self.rule(file_rule), steps=steps)

    def options(self, ipopt: dict[str, Any], max_seconds: float = MAX_SECONDS,
                N: int | None = None, fatrop: dict[str, Any] | None = None) -> SolverOptions:
        """The solver options of this method on N intervals: its backend and jit, IPOPT's
        ``ipopt`` and fatrop's ``fatrop`` (the problem file's), the wall time of one run, and
        for ``+coarse`` the continuation from :meth:`coarse_N` (what a solve of the compiled
        problem does; the timed solves of :mod:`~ocgroupoid.bench.timing` take the same two
        steps)."""
        n = None if N is None else self.coarse_N(N)
        return SolverOptions(backend=self.backend, ipopt=dict(ipopt), fatrop=dict(fatrop or {}),
                             jit=self.jit, max_seconds=max_seconds,
                             continuation=() if n is None else (n,))


#: ours (order2 with cayley and exp), then the baselines
OURS_DEFAULT = (Method("order2"), Method("order4"), Method("order6"), Method("order2", "exp"))
BASELINES_DEFAULT = (Method("rk4_quat"), Method("rk4_matrix"), Method("rk4_euler"))
WORK_PRECISION = (*OURS_DEFAULT, *BASELINES_DEFAULT)
#: the same and the first-order retraction (SO(3) problems only)
STABILITY = (*OURS_DEFAULT, Method("order2", "first_order"), *BASELINES_DEFAULT)


def parse_methods(text: str | None, default: tuple[Method, ...]) -> list[Method]:
    """``"order2,order4:exp,rk4_quat"`` -> methods (``default`` when None); ConfigError naming
    an unknown scheme or retraction."""
    if text is None:
        return list(default)
    methods = []
    for item in (s.strip() for s in text.split(",")):
        head, *flags = item.split("+")
        if flags != [f for f in FLAGS if f in flags]:
            raise ConfigError(f"--schemes: {item!r} ends with +{'+'.join(flags)}; a method "
                              f"may end with {', '.join('+' + f for f in FLAGS)}, in this "
                              "order (order4@fatrop+jit+coarse)")
        head, _, backend = head.partition("@")
        backend = backend or DEFAULT_BACKEND
        if backend not in BACKENDS:
            raise ConfigError(f"--schemes: unknown backend {backend!r} in {item!r}; choose "
                              f"from {', '.join(BACKENDS)} (order4@fatrop, rk4_quat+jit)")
        scheme, _, retraction = head.partition(":")
        if scheme not in SCHEME_NAMES:
            raise ConfigError(f"--schemes: unknown scheme {scheme!r}; choose from "
                              f"{', '.join(SCHEME_NAMES)} (a retraction after a colon: "
                              "order2:exp)")
        retraction = retraction or DEFAULT_RETRACTION
        if retraction not in RETRACTION_NAMES:
            raise ConfigError(f"--schemes: unknown retraction {retraction!r} in {item!r}; "
                              f"choose from {', '.join(RETRACTION_NAMES)}")
        methods.append(Method(scheme, retraction, backend, "jit" in flags, "coarse" in flags))
    if len(set(methods)) != len(methods):
        raise ConfigError(f"--schemes names a method twice: {text!r}")
    return methods


def parse_grids(text: str | None, default: tuple[int, ...], option: str = "--N") -> list[int]:
    """``"8,16,32"`` -> sorted distinct N (``default`` when None); ConfigError for N < 2."""
    if text is None:
        return list(default)
    try:
        Ns = [int(s) for s in text.split(",")]
    except ValueError:
        raise ConfigError(f"{option}: {text!r} is not a comma-separated list of integers "
                          "(e.g. 8,16,32)") from None
    small = [N for N in Ns if N < 2]
    if small:
        raise ConfigError(f"{option}: N must be at least 2 (one interval has no interior "
                          f"node), got {small[0]}")
    return sorted(set(Ns))


def parse_floats(text: str | None, default: tuple[float, ...], option: str) -> list[float]:
    """``"0.5,1,2.6"`` -> floats (``default`` when None); ConfigError when not numbers."""
    if text is None:
        return list(default)
    try:
        return [float(s) for s in text.split(",")]
    except ValueError:
        raise ConfigError(f"{option}: {text!r} is not a comma-separated list of numbers") \
            from None


def left_out(methods: list[Method], problem: Problem) -> dict[str, str]:
    """Methods not run on ``problem``, with the reason: those that would repeat another one's
    computation (the matrix and Euler baselines equal rk4_quat without an SO(3) factor, and
    every retraction equals cayley on R^n factors)."""
    factors = problem.groupoid.factors
    own_coordinates = any(coordinates("matrix", f).name != "quaternion" for f in factors)
    curved = any(not isinstance(f.group, Rn) for f in factors)
    present = set(methods)
    out = {}
    for m in methods:
        quat, cayley = replace(m, scheme="rk4_quat"), replace(m, retraction=DEFAULT_RETRACTION)
        if m.baseline and m.scheme != "rk4_quat" and not own_coordinates and quat in present:
            out[m.label] = f"identical to {quat.label} here: no SO(3) factor to carry " \
                           "otherwise"
        elif not m.baseline and m.retraction != DEFAULT_RETRACTION and not curved and \
                cayley in present:
            out[m.label] = f"identical to {cayley.label} here: every retraction is the " \
                           "translation on R^n"
    return out
