"""The top-level sections of a problem file, as pydantic models (unknown keys are errors).

The model-specific sections (``parameters``, ``initial``, ``final``) are each model's own
schemas (:class:`~ocgroupoid.systems.registry.ModelSpec`).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field, StrictBool, model_validator
from pydantic_core import PydanticCustomError

from ..lie.retraction import RETRACTION_NAMES
from ..model.ranges import T_RANGE, TIME_RANGE
from ..model.values import Strict, number, positive
from ..nlp.method import DEFAULT_RETRACTION, DEFAULT_STEPS, MAX_BOUND_POINTS, STEPS
from ..nlp.options import BACKENDS, DEFAULT_BACKEND, MAX_SECONDS
from ..nlp.schemes import DEFAULT_RULE, SCHEME_NAMES
from ..solve.accuracy import ACCURACY_MAX, N_MAX, N_MIN

#: the scheme of a problem file that names none (with a fixed N): order4 lands within 1e-6
#: of the distance at the files' N where order2 needs 4N or more (scripts/bench_default_scheme.py)
FILE_SCHEME = "order4"
#: the seeds' retraction, which only order2 honours (order4 steps with exp)
ORDER2_RETRACTION = "first_order"
#: perturbed starts of ``solver.multistart`` (each is a full IPOPT solve) and coarse grids
#: of ``solver.continuation``
MULTISTART_MAX = 1000
CONTINUATION_MAX = 8
#: the largest ``solver.max_seconds`` (a week)
SECONDS_MAX = 7 * 86400.0


def _time(v: Any, what: str = "T") -> float:
    """A number of seconds within :data:`~ocgroupoid.model.ranges.T_RANGE`."""
    x = positive(v, what)
    message = TIME_RANGE.problem(what, [x])
    if message is not None:
        raise ValueError(message)
    return x


def _final_time(v: Any) -> Any:
    """A time within :data:`T_RANGE`, or ``free`` (a decision variable)."""
    if v == "free":
        return v
    if isinstance(v, str):
        raise ValueError(f"T must be a number > 0 or free, got {v!r}")
    return _time(v, "T")


def _multistart(v: Any) -> bool | int:
    """true, false, or a count of perturbed starts up to :data:`MULTISTART_MAX` (no text)."""
    if isinstance(v, bool):
        return v
    if not isinstance(v, int):
        raise ValueError(f"multistart is true, false or a number of perturbed starts, got "
                         f"{v!r}{' (text: drop the quotes)' if isinstance(v, str) else ''}")
    if not 0 <= v <= MULTISTART_MAX:
        raise ValueError(f"multistart = {v} is outside 0..{MULTISTART_MAX}: each start is a "
                         "full IPOPT solve; a few (true: 3) find the usual local minima")
    return v


def _level(v: Any) -> int | str:
    """A continuation level: a coarser N (an integer >= 2) or a scheme's name."""
    if isinstance(v, str) and v in SCHEME_NAMES:
        return v
    if isinstance(v, bool) or not isinstance(v, int) or v < 2:
        raise ValueError(f"continuation lists coarser N (integers >= 2) and schemes to solve "
                         f"first ({', '.join(SCHEME_NAMES)}), got {v!r}")
    return v


def _ipopt_value(v: Any) -> Any:
    """An IPOPT option's value: a number or a text, never a YAML boolean (which would reach
    IPOPT as 0 or 1, and IPOPT's switches take the text yes or no)."""
    if isinstance(v, bool):
        word = "yes" if v else "no"
        raise ValueError(f"{str(v).lower()} is a YAML boolean (YAML reads an unquoted yes, "
                         f"no, true or false as one); IPOPT's switches take text: write "
                         f"\"{word}\" in quotes")
    return v


def _intervals(v: Any) -> Any:
    """A number of intervals >= 2 (no float, no boolean), or ``auto``."""
    if v == "auto":
        return v
    if isinstance(v, str):
        raise PydanticCustomError("literal_error", "", {"expected": "an integer >= 2 or 'auto'"})
    if isinstance(v, bool) or not isinstance(v, int):
        raise PydanticCustomError("int_from_float" if isinstance(v, float) else "int_type", "")
    if v < 2:
        raise PydanticCustomError("greater_than_equal", "", {"ge": 2})
    return v


def _accuracy(v: Any) -> float:
    """A relative error in (0, :data:`~ocgroupoid.solve.accuracy.ACCURACY_MAX`]."""
    x = number(v, "accuracy")
    if not 0 < x <= ACCURACY_MAX:
        raise ValueError(f"accuracy = {x:g} is outside (0, {ACCURACY_MAX:g}]: it is the "
                         "relative error of the cost to reach, e.g. 1.0e-6")
    return x


def _seconds(v: Any) -> float:
    """A wall-time limit in (0, :data:`SECONDS_MAX`] seconds."""
    x = number(v, "max_seconds")
    if not 0 < x <= SECONDS_MAX:
        raise ValueError(f"max_seconds = {x:g} is outside (0, {SECONDS_MAX:g}]: it is the wall "
                         f"time of one solve in seconds (default {MAX_SECONDS:g})")
    return x


def _nonnegative(v: Any, what: str = "value") -> float:
    """A finite number >= 0."""
    x = number(v, what)
    if x < 0:
        raise ValueError(f"{what} must be >= 0, got {x}")
    return x


PositiveNumber = Annotated[float, BeforeValidator(positive)]
Time = Annotated[float, BeforeValidator(_time)]
Weight = Annotated[float, BeforeValidator(_nonnegative)]


class Horizon(Strict):
    """Final time (fixed, or free within bounds) and number of intervals."""

    T: Annotated[Any, BeforeValidator(_final_time)] = Field(
        description=f"final time (in [{T_RANGE[0]:g}, {T_RANGE[1]:g}]), or free: a decision "
        "variable within [T_min, T_max]")
    N: Annotated[int | Literal["auto"], BeforeValidator(_intervals)] = Field(
        description="number of intervals (>= 2), or auto: the smallest N = N_min 2^k whose "
        "estimated error meets solver.accuracy / solver.replay_accuracy")
    N_min: Annotated[int, Field(strict=True, ge=2)] | None = Field(
        None, description=f"N: auto only: the first grid (default {N_MIN})")
    N_max: Annotated[int, Field(strict=True, ge=2)] | None = Field(
        None, description=f"N: auto only: the largest grid (default {N_MAX})")
    T_min: Time | None = Field(None, description="lower bound of a free T")
    T_max: Time | None = Field(None, description="upper bound of a free T")
    T_guess: Time | None = Field(
        None, description="initial guess of a free T (default: the middle of [T_min, T_max])")

    @model_validator(mode="after")
    def _free_needs_bounds(self) -> "Horizon":
        if self.T == "free":
            if self.T_min is None or self.T_max is None:
                raise ValueError("T: free needs T_min and T_max (the range T may take)")
            if not self.T_min <= self.guess <= self.T_max:
                raise ValueError(f"T_guess {self.guess} must lie in [T_min, T_max] = "
                                 f"[{self.T_min}, {self.T_max}]")
        elif self.T_min is not None or self.T_max is not None or self.T_guess is not None:
            raise ValueError("T_min, T_max and T_guess belong to T: free; remove them or "
                             "write T: free")
        if self.N != "auto" and (self.N_min is not None or self.N_max is not None):
            raise ValueError("N_min and N_max bound the grids of N: auto; remove them or "
                             "write N: auto")
        if not self.grids[0] <= self.grids[1]:
            raise ValueError(f"N_min = {self.grids[0]} must be <= N_max = {self.grids[1]}")
        return self

    @property
    def grids(self) -> tuple[int, int]:
        """The first and the largest grid of N: auto (defaults filled in)."""
        return (self.N_min if self.N_min is not None else N_MIN,
                self.N_max if self.N_max is not None else N_MAX)

    @property
    def guess(self) -> float:
        """T itself, or the initial guess of a free T."""
        if self.T != "free":
            return float(self.T)
        assert self.T_min is not None and self.T_max is not None
        return self.T_guess if self.T_guess is not None else (self.T_min + self.T_max) / 2


class ObjectiveSection(Strict):
    """``effort * (the model's cost) + time * T``."""

    effort: Weight = Field(1.0, description="weight of the model's running cost")
    time: Weight = Field(0.0, description="weight of the final time (needs T: free)")


class DiscretizationSection(Strict):
    """Scheme, retraction of the group factors and rule of the constraints."""

    scheme: Literal[SCHEME_NAMES + ("auto",)] = Field(  # type: ignore[valid-type]
        FILE_SCHEME, description="discretisation scheme (ocgroupoid list shows them), or auto "
        "(with horizon.N: auto): whichever meets the accuracy with less IPOPT time; when the "
        f"file names none: {FILE_SCHEME} with a fixed N, auto with N: auto, order2 where the "
        "file asks for the first_order retraction or a rule other than midpoint")
    retraction: Literal[RETRACTION_NAMES] = Field(  # type: ignore[valid-type]
        DEFAULT_RETRACTION, description="cayley (default), exp, or first_order (the seeds' "
        "rule)")
    rule: str = Field(DEFAULT_RULE, description="discretisation rule of the constraints")
    steps: Literal[STEPS] = Field(  # type: ignore[valid-type]
        DEFAULT_STEPS, description="uniform steps h = T/N, or adaptive ones (order4, "
        "order6)")
    bound_points: int = Field(
        0, ge=0, le=MAX_BOUND_POINTS, description="impose the bounds at this many more "
        "points inside every interval (order4, order6), where a bound is violated between the "
        "scheme's points (order6 on first-order problems: elevate the degree of the hull "
        "the bounds hold on as many times, which tightens it)")


class SolverSection(Strict):
    """IPOPT options and the globalisation strategy."""

    ipopt: dict[str, Annotated[str | int | float, BeforeValidator(_ipopt_value)]] = Field(
        default_factory=dict, description="options passed to IPOPT (e.g. tol, max_iter)")
    fatrop: dict[str, StrictBool | int | float | str] = Field(
        default_factory=dict, description="fatrop's own options by fatrop's names (e.g. "
        "acceptable_iter, tol_acceptable), over our defaults and the IPOPT options fatrop "
        "shares, wherever fatrop runs (solver.backend: fatrop, or a benchmark's @fatrop)")
    multistart: Annotated[bool | int, BeforeValidator(_multistart)] = Field(
        True, description="true (the default), false (the first geodesic only), or the "
        "number of perturbed starts on top of the geodesics and the model's guesses "
        f"(at most {MULTISTART_MAX})")
    workers: Annotated[int, Field(strict=True, ge=1)] | None = Field(
        None, description="processes the starts of a multi-start are solved on at once: "
        "one per core when unset, 1 for one start after the other")
    continuation: list[Annotated[int | str, BeforeValidator(_level)]] = Field(
        default_factory=list, max_length=CONTINUATION_MAX,
        description=f"coarser N solved first, e.g. [16, 32], then schemes solved first on "
        f"the final grid, e.g. [order2] before order4 (at most {CONTINUATION_MAX})")
    accuracy: Annotated[float, BeforeValidator(_accuracy)] | None = Field(
        None, description=f"with horizon.N: auto: the relative error of the cost to reach, "
        f"in (0, {ACCURACY_MAX:g}] (e.g. 1.0e-6), estimated by Richardson from two grids")
    replay_accuracy: PositiveNumber | None = Field(
        None, description="with horizon.N: auto: the largest terminal error of the replay "
        "to reach, in the units the replay reports (rad, m, ...)")
    jit: StrictBool = Field(
        False, description="evaluate the NLP as C compiled by the system compiler (cached per "
        "structure): worth it for repeated solves (multi-start, sweeps, large N)")
    max_seconds: Annotated[float, BeforeValidator(_seconds)] = Field(
        MAX_SECONDS, description="wall-time limit of one solve (every start and grid; each "
        f"grid of N: auto), in seconds, at most {SECONDS_MAX:g}: past it the best point so "
        "far is returned with status Maximum_WallTime_Exceeded")
    backend: Literal[BACKENDS] = Field(  # type: ignore[valid-type]
        DEFAULT_BACKEND, description="the NLP solver: ipopt (the whole sparse KKT system), or "
        "fatrop (the NLP in stage form, factorised stage by stage: faster on long horizons "
        "and plate-ball problems, less robust on hard nonconvex ones such as cart_pole)")


class OutputSection(Strict):
    """Where the CLI writes its results (overridden by --out/--plot)."""

    file: str | None = Field(None, description="solution JSON path")
    plot: str | None = Field(None, description="PNG path for the plot")


class ProblemFile(Strict):
    """The top level of a problem file."""

    @model_validator(mode="before")
    @classmethod
    def _default_scheme(cls, data: Any) -> Any:
        """A file that names no scheme gets the one measured fastest at the accuracy users
        ask (:data:`FILE_SCHEME`; ``scripts/bench_default_scheme.py``), and with
        ``horizon.N: auto`` the choice between the schemes too; a file asking for what only
        order2 does (the seeds' first-order retraction, a rule of the constraints other than
        midpoint: order4 steps with exp and imposes them at its Gauss points) gets order2."""
        if not isinstance(data, dict) or not isinstance(data.get("discretization", {}), dict):
            return data
        section = dict(data.get("discretization") or {})
        if "scheme" in section:
            return data
        horizon = data.get("horizon")
        auto = isinstance(horizon, dict) and horizon.get("N") == "auto"
        if section.get("retraction") == ORDER2_RETRACTION or \
                section.get("rule", DEFAULT_RULE) != DEFAULT_RULE:
            section["scheme"] = "order2"  # the only scheme that honours what the file asks
        else:
            section["scheme"] = "auto" if auto else FILE_SCHEME
        return {**data, "discretization": section}

    model: str = Field(description="a built-in model (see `ocgroupoid list`) or custom")
    name: str | None = Field(None, description="problem name (default: the file's stem)")
    definition: dict[str, Any] | None = Field(
        None, description="model: custom only — groupoid, Lagrangian, cost, constraints")
    parameters: dict[str, Any] = Field(default_factory=dict, description="model parameters")
    horizon: Horizon
    initial: dict[str, Any] = Field(default_factory=dict, description="initial conditions")
    final: dict[str, Any] = Field(default_factory=dict, description="final conditions")
    bounds: dict[str, Any] = Field(
        default_factory=dict, description="name: [lower, upper] (per component: a list of "
        "pairs; null: open) for controls (u: all of them), velocities and R^n states")
    objective: ObjectiveSection = Field(default_factory=ObjectiveSection)
    discretization: DiscretizationSection = Field(default_factory=DiscretizationSection)
    solver: SolverSection = Field(default_factory=SolverSection)
    output: OutputSection = Field(default_factory=OutputSection)
