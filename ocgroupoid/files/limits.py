"""What a problem file may ask of this machine: N and the starts within a memory estimate and a
time estimate, and IPOPT's linear solver among those that are installed.

``horizon.N`` is bounded by memory: a scheme has at most ``2 dim(y) + dim(s)`` decision
variables per interval, and a variable costs about :data:`BYTES_PER_VARIABLE` once the stage
graphs, the derivatives, IPOPT and MUMPS's factor exist (3-8 kB measured on the shipped
problems at N = 10 000); every start of a multi-start keeps a few vectors of its own. The
estimate must stay below half of the machine's memory, and the time a solve takes (build,
iterations per variable, starts: :func:`estimate`) below ``solver.max_seconds``: beyond, the
problem is refused up front with the estimate. CasADi's IPOPT ships the linear
solvers MUMPS and SPRAL; the HSL solvers (``ma27``, ``ma57``...) and Pardiso are loaded at
run time from their libraries, which are looked for before IPOPT is asked for them (an IPOPT
asked for a missing one reports Invalid_Option, or crashes).
"""

from __future__ import annotations

import ctypes.util
import io
import math
import os
import re
import sys
from contextlib import contextmanager, redirect_stdout
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any, Callable, Iterator

import casadi as ca

from ..errors import ConfigError
from ..lie.rn import Rn
from ..model.problem import Problem
from ..nlp.backends.fatrop_ocp import option_kinds

BYTES_PER_VARIABLE = 16_000
BYTES_PER_START = 4 * 8  # per variable and start: the guess, x, and the multipliers
HSL = ("ma27", "ma57", "ma77", "ma86", "ma97")
LINEAR_SOLVERS = ("mumps", "spral", *HSL, "pardiso", "pardisomkl")


def memory_bytes() -> int:
    """The machine's physical memory (8 GiB when the system does not say)."""
    try:
        return int(os.sysconf("SC_PHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):  # pragma: no cover - non-POSIX systems
        return 8 * 2 ** 30


def variables_per_interval(pb: Problem) -> int:
    """An upper bound of the decision variables per interval over every scheme (order6: a node
    velocity and two bubbles, or three stage rates; order4 and order6 draw bounded recovered
    controls as lines: two values per control and interval, as controls of their own)."""
    G = pb.groupoid
    return 3 * G.algebra_dim + G.state_size + 2 * max(pb.U.numel(), len(pb.controls))


def check_size(pb: Problem, N: int, starts: int, where: str) -> None:
    """Refuse ``N`` intervals (and ``starts`` starts) whose memory estimate exceeds half of
    the machine's memory; ``where`` locates ``horizon.N`` for the message."""
    per = variables_per_interval(pb)
    budget = memory_bytes() // 2
    cost = per * (BYTES_PER_VARIABLE + max(starts, 1) * BYTES_PER_START)
    n_max = max(budget // cost, 2)
    if N > n_max:
        raise ConfigError(
            f"{where}: horizon.N = {N} needs about {N * cost / 1e9:.3g} GB of memory ({per} "
            f"variables per interval, ~{BYTES_PER_VARIABLE // 1000} kB each), more than half "
            f"of this machine's {memory_bytes() / 1e9:.3g} GB: the limit here is N <= {n_max}; "
            "lower N (use solver.continuation to reach a fine grid from coarse ones)")


#: seconds per NLP variable on the machine the package is measured on (2 cores;
#: ``scripts/bench_backends.py`` over every problem file, both schemes, N = 256 and 1024,
#: ``results/bench_backends.json``; ranges in brackets): IPOPT's build (5-34 us), one
#: interior-point iteration (2-13 us; more at larger N: 10 us for the reaction wheels at
#: N = 5000), and fatrop's build per variable and interval (150-740 ns: it grows like N^2).
#: The estimate is good to a factor of 2 or 3 either way: plate_ball at N = 2000 on fatrop
#: 85 s estimated, 39 s measured; reaction_wheels at N = 5000 92 s estimated, 149 s measured
BUILD_SECONDS = 15e-6
ITERATION_SECONDS = 6e-6
FATROP_BUILD_SECONDS = 300e-9
#: iterations of the first start (measured 4-68) and of each further one (whose budget is
#: max(30, 3 x the first's)); starts besides the perturbed ones: both geodesics and, if the
#: model has guesses, about six of them
FIRST_ITERATIONS, FURTHER_ITERATIONS = 40, 30
MODEL_GUESSES = 6


@dataclass(frozen=True)
class Estimate:
    """What a solve of N intervals costs, about: the build, the first start, the starts."""

    build: float
    first: float
    further: float
    starts: int

    @property
    def seconds(self) -> float:
        return self.build + self.first + (self.starts - 1) * self.further

    def __str__(self) -> str:
        return (f"about {self.seconds:.3g} s here (a build of ~{self.build:.2g} s, then "
                f"{self.starts} start{'s' if self.starts > 1 else ''} of ~{self.first:.2g} s "
                "or less)")


def estimate(pb: Problem, N: int, multistart: bool | int, backend: str) -> Estimate:
    """The time a solve of ``pb`` on N intervals takes, about (the constants above)."""
    nx = variables_per_interval(pb) * N
    build = nx * BUILD_SECONDS + (nx * N * FATROP_BUILD_SECONDS if backend == "fatrop" else 0)
    starts = 1
    if multistart is not False:
        groups = any(not isinstance(f.group, Rn) for f in pb.groupoid.factors)
        starts = (2 if groups else 1) + (MODEL_GUESSES if pb.guess_hook else 0) + \
            (3 if multistart is True else int(multistart))
    return Estimate(build, FIRST_ITERATIONS * nx * ITERATION_SECONDS,
                    FURTHER_ITERATIONS * nx * ITERATION_SECONDS, starts)


def check_time(pb: Problem, N: int, multistart: bool | int, backend: str, max_seconds: float,
               where: str) -> Estimate:
    """Refuse ``N`` intervals whose solve would take longer than ``max_seconds``
    (``solver.max_seconds``), by :func:`estimate`; ``where`` locates ``horizon.N``."""
    est = estimate(pb, N, multistart, backend)
    if est.seconds > max_seconds:
        raise ConfigError(
            f"{where}: horizon.N = {N}: a solve takes {est}, more than solver.max_seconds = "
            f"{max_seconds:g}; lower N (use solver.continuation to reach a fine grid from "
            "coarse ones), solve one start (solver.multistart: false)"
            + (", use solver.backend: ipopt (fatrop's build grows like N^2)"
               if backend == "fatrop" else "") + ", or raise solver.max_seconds")
    return est


def _library(*names: str) -> bool:
    """True when one of the shared libraries ``names`` (``hsl`` for libhsl.so) is installed,
    on the loader's path or beside CasADi's own."""
    folder = Path(ca.__file__).parent
    return any(ctypes.util.find_library(n) or any(folder.glob(f"lib{n}.*")) for n in names)


@lru_cache(maxsize=None)
def linear_solvers() -> tuple[str, ...]:
    """IPOPT's linear solvers available here: MUMPS and SPRAL are built into CasADi's IPOPT;
    the others are loaded at run time from their libraries (HSL, Pardiso, MKL) when found."""
    found = ["mumps", "spral"]
    if _library("hsl", "coinhsl"):
        found += HSL
    if _library("pardiso"):
        found.append("pardiso")
    if _library("mkl_rt"):
        found.append("pardisomkl")
    return tuple(found)


def check_linear_solver(ipopt: dict, where: str) -> None:
    """Refuse ``solver.ipopt.linear_solver`` when IPOPT cannot load it, naming those it can
    (an HSL solver is trusted when ``hsllib`` names its library)."""
    name = ipopt.get("linear_solver")
    name = name.lower() if isinstance(name, str) else name  # IPOPT reads it in any case
    if name is None or name in linear_solvers() or \
            (name in HSL and "hsllib" in ipopt) or (name == "pardiso" and "pardisolib" in ipopt):
        return
    known = "" if name in LINEAR_SOLVERS else \
        f" (IPOPT's linear solvers are {', '.join(LINEAR_SOLVERS)})"
    raise ConfigError(f"{where}: solver.ipopt.linear_solver: {name!r} is not available with "
                      f"this IPOPT{known}; choose one of {', '.join(linear_solvers())} (HSL's "
                      "ma27, ma57, ... need the HSL library, libhsl, installed)")


OPTIONS_URL = "https://coin-or.github.io/Ipopt/OPTIONS.html"
# options not tried on a probe: checked above, or with effects beyond the probe (files)
UNTRIED = {"linear_solver", "hsllib", "pardisolib", "output_file", "file_print_level",
           "option_file_name", "file_append"}


@contextmanager
def _captured_stdout() -> Iterator[io.StringIO]:
    """What IPOPT prints (through CasADi, to Python's stdout) while refusing an option: the
    option's documentation, with its range or choices. File descriptor 1 is silenced too, for
    builds of CasADi that print there."""
    buffer = io.StringIO()
    sys.stdout.flush()
    try:
        saved, null = os.dup(1), os.open(os.devnull, os.O_WRONLY)
    except OSError:  # no descriptor 1 to silence
        saved = null = -1
    if saved >= 0:
        os.dup2(null, 1)
    try:
        with redirect_stdout(buffer):
            yield buffer
    finally:
        if saved >= 0:
            os.dup2(saved, 1)
            os.close(saved)
            os.close(null)


def _documented(text: str) -> str:
    """The range (``0 < (1e-08) <= +inf``) or the choices of an option, from IPOPT's
    documentation of it."""
    lines = [ln.strip() for ln in text.splitlines()]
    for ln in lines:
        if re.fullmatch(r"\S+ <=? \(.*\) <=? \S+", ln):
            return f"its range is {ln} (the default in brackets)"
    if "Valid Settings:" in lines:
        start = lines.index("Valid Settings:") + 1
        choices = [ln.split(" ")[0] for ln in lines[start:] if ln and not ln.startswith(
            "Default:")]
        return f"choose one of {', '.join(choices[:12])}"
    return f"see {OPTIONS_URL}"


@lru_cache(maxsize=256)
def ipopt_refuses(key: str, value: Any, kind: str) -> str | None:
    """Why IPOPT refuses the option ``key: value`` (None if it takes it), from a
    one-variable problem built with it (``kind``, the value's type, keys the cache)."""
    x = ca.SX.sym("x")
    try:
        with _captured_stdout() as printed:
            ca.nlpsol("ipopt_option_probe", "ipopt", {"x": x, "f": x ** 2},
                      {"ipopt": {"sb": "yes", "print_level": 0, key: value},
                       "print_time": False})
    except RuntimeError as err:
        reason = str(err).strip().splitlines()[-1] if str(err).strip() else ""
        if "No such IPOPT option" in reason:
            return f"IPOPT has no option {key!r}; see {OPTIONS_URL}"
        if "type mismatch" in reason:
            return (f"{value!r} has the wrong type for this option (a number, an integer or a "
                    f"text: see {OPTIONS_URL})")
        return f"IPOPT refuses {value!r}: {_documented(printed.getvalue())}"
    return None


def check_ipopt_options(ipopt: dict, where: Callable[..., str]) -> None:
    """Refuse ``solver.ipopt`` options IPOPT would refuse, before anything is built;
    ``where(*key)`` locates a key for the message."""
    check_linear_solver(ipopt, where("solver", "ipopt", "linear_solver"))
    for key, value in ipopt.items():
        at = f"{where('solver', 'ipopt', key)}: solver.ipopt.{key}"
        if isinstance(value, float) and not math.isfinite(value):
            raise ConfigError(f"{at}: {value} is not finite; write a number (IPOPT reads "
                              "1.0e+19 as infinity)")
        if key in UNTRIED:
            continue
        reason = ipopt_refuses(key, value, type(value).__name__)
        if reason:
            raise ConfigError(f"{at}: {reason}")


def check_fatrop_options(fatrop: dict, where: Callable[..., str]) -> None:
    """Refuse ``solver.fatrop`` options fatrop does not have, or whose values are not of their
    option's kind, before anything is built; ``where(*key)`` locates a key for the message."""
    for key, value in fatrop.items():
        try:
            option_kinds({key: value})
        except ConfigError as err:
            raise ConfigError(f"{where('solver', 'fatrop', key)}: solver.fatrop.{key}: "
                              f"{err}") from None
