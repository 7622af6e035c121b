"""``model: custom`` — a new problem described in the problem file, without Python.

The ``definition`` section lists the factors of the groupoid and writes the reduced Lagrangian,
the cost and extra constraints as expression strings (see :mod:`ocgroupoid.expressions`)::

    definition:
      groupoid: [{type: so3, state: R, velocity: Omega}]   # so3 | se3 | se2 | pair | sphere
      lagrangian: "0.5*dot(Omega, inertia*Omega)"          # second order: mechanics
      actuated: [Omega]                                    # velocities carrying controls
      input_matrix: "diag(inertia)"                        # F = input_matrix u (default I)
      cost: "0.5*dot(u, u)"                                # u: the controls
    parameters: {inertia: [1.0, 2.0, 3.0]}                 # names and sizes come from here

Controls of their own (thrust along a body axis, fewer controls than velocities) are named
with their sizes and push through ``force``, the generalised force on the actuated
velocities as an expression of the states and the controls::

      lagrangian: "0.5*dot(xi[0:3], J*xi[0:3]) + 0.5*m*dot(xi[3:6], xi[3:6]) - m*gravity*g[2, 3]"
      controls: {f: 1, tau: 3}
      force: "[tau, 0, 0, f]"                              # thrust f along body z
      cost: "(f - m*gravity)**2 + dot(tau, tau)"

Symbols in expressions: the parameters; the base coordinates of pair and sphere factors (by
their state name) and the states of group factors (a rotation as its 3x3 matrix, a pose as
its 4x4 homogeneous matrix: ``g[2, 3]`` is the height); the velocities (by name); their
rates ``<velocity>_dot`` (order 2); and, with a Lagrangian, the controls ``u`` (and each
control by its name). ``path`` entries are ``expression <= 0``, or comparisons
``lhs <= rhs``, ``lhs >= rhs`` and ``lhs == rhs`` (an equality path constraint). Without a
Lagrangian, ``controls`` maps names to expressions. ``order: 1`` gives a first-order problem
``min int cost(q, y) dt`` subject to the constraints. The optional ``describe`` maps names to
their unit (``x: m``) or to ``{meaning, unit, components, group}`` for plots and solution
files (:meth:`~ocgroupoid.model.problem.Problem.describe`).
"""

from __future__ import annotations

import difflib
import re
from contextlib import contextmanager
from typing import Annotated, Any, Iterator, Literal

import casadi as ca
from pydantic import BaseModel, BeforeValidator, Field, create_model

from ..errors import BoundaryError, ConfigError, DimensionError
from ..groupoid import Groupoid, LieGroupFactor, Pair, SphereAction
from ..groupoid.base import Factor
from ..lie import SE2, SE3, SO3
from ..model.problem import Problem
from ..model.values import Strict, check_vector, vector
from ..systems.registry import ModelSpec
from .described import Described, UnitText
from .expressions import CONSTANTS, FUNCTIONS, compile_expression


class FactorDefinition(Strict):
    """One factor of the product groupoid."""

    type: Literal["so3", "se3", "se2", "pair", "sphere"] = Field(
        description="so3, se3, se2: SO(3), SE(3) (poses), SE(2) (planar poses) over a point; "
        "pair: pair groupoid of R^dim; sphere: S^2 x SO(3)")
    state: str = Field(description="name of the node state (boundary-condition key)")
    velocity: str = Field(description="name of the velocity")
    dim: int | None = Field(None, ge=1, description="dimension of a pair factor")
    side: Literal["body", "spatial"] = Field(
        "body", description="so3, se3, se2 only: body g_{k+1} = g_k w_k or spatial "
        "g_{k+1} = w_k g_k")


class Definition(Strict):
    """The ``definition`` section of a custom model."""

    groupoid: list[FactorDefinition] = Field(min_length=1, description="factors of the product")
    order: Literal[1, 2] = Field(2, description="2: second-order cost; 1: first-order cost")
    lagrangian: str | None = Field(None, description="reduced Lagrangian l(q, y) (order 2)")
    actuated: str | list[str | int] | None = Field(
        None, description="velocities that carry controls: names (Omega), components "
        "(Omega[0], dphi[0:2]) or indices of all the velocities, as a list or one string")
    input_matrix: str | None = Field(None, description="F = input_matrix @ u (default I)")
    force: str | None = Field(
        None, description="the generalised force on the actuated velocities as an expression "
        "of the states and the controls of their own (controls: {name: size}), e.g. "
        "'[tau, 0, 0, f]' for thrust along body z; instead of input_matrix")
    controls: list[str] | dict[str, str | int] | None = Field(
        None, description="control names (with a Lagrangian), name: size (with force), or "
        "name: expression (without a Lagrangian)")
    cost: str = Field(description="running cost integrand")
    constraints: dict[str, str] = Field(default_factory=dict,
                                        description="extra constraints name: expression = 0")
    path: dict[str, str] = Field(
        default_factory=dict, description="path constraints name: expression (meaning "
        "expression <= 0) or a comparison 'lhs <= rhs', 'lhs >= rhs', 'lhs == rhs', imposed "
        "wherever the scheme evaluates its constraints (a keep-out cone, R e3 == e3)")
    terminal_cost: str | None = Field(None, description="Mayer term on the final node")
    describe: dict[str, Described | UnitText] = Field(
        default_factory=dict, description="optional names and units for plots and solution "
        "files: name: unit, or name: {meaning, unit, components, group}; a name is a state, "
        "a velocity, a control, u (all the controls), a constraint (its multipliers) or t")


GROUPS = {"so3": SO3, "se3": SE3, "se2": SE2}  # the group factor types


def _factor(d: FactorDefinition) -> Factor:
    if d.type in GROUPS:
        return LieGroupFactor(GROUPS[d.type], state=d.state, velocity=d.velocity,
                              side="right" if d.side == "body" else "left")
    if d.type == "sphere":
        return SphereAction(state=d.state, velocity=d.velocity)
    if d.dim is None:
        raise ConfigError(f"definition.groupoid: the pair factor {d.state!r} needs dim: n")
    return Pair(d.dim, state=d.state, velocity=d.velocity)


def _reserved(name: str, where: str) -> None:
    if name in FUNCTIONS or name in CONSTANTS or not name.isidentifier() or "__" in name:
        raise ConfigError(f"{where}: {name!r} cannot be a symbol name (it is a function, a "
                          "constant or not an identifier); rename it")


def spec(definition: Definition, where: Any) -> ModelSpec:
    """A ModelSpec whose sections and builder follow ``definition``.

    ``where(*path)`` returns the ``file:line`` prefix of a key for error messages.
    """
    factors = [_factor(d) for d in definition.groupoid]
    G = Groupoid(*factors)
    names = [*G.state_names, *G.velocity_names]
    for n in names:
        _reserved(n, where("definition", "groupoid"))

    initial_fields: dict[str, Any] = {}
    final_fields: dict[str, Any] = {}
    for f in factors:
        # a factor reads its own state values; R^n components may be left free (null)
        kind: Any = vector(f.state_size, allow_none=True) if f.componentwise else \
            Annotated[Any, BeforeValidator(f.parse_state)]
        initial_fields[f.state] = (kind if not f.componentwise else kind | None,
                                   Field(... if not f.componentwise else None))
        final_fields[f.state] = (kind | None, Field(None))
        if definition.order == 2:
            vel = vector(f.algebra_dim, allow_none=True)
            initial_fields[f.velocity] = (vel | None, Field(None))
            final_fields[f.velocity] = (vel | None, Field(None))
    Initial = create_model("Initial", __base__=Strict, **initial_fields)
    Final = create_model("Final", __base__=Strict, **final_fields)

    def build(params: BaseModel, initial: BaseModel, final: BaseModel, T: float,
              name: str) -> Problem:
        return _problem(definition, G, params, initial, final, T, name, where)

    return ModelSpec("custom", "a problem written in the file", _Parameters, Initial, Final,
                     build)


class _Parameters(BaseModel):
    """Any number of named parameters, each a number or a list of numbers."""

    model_config = {"extra": "allow", "frozen": True}


def _values(params: BaseModel, where: Any) -> dict[str, list[float]]:
    out: dict[str, list[float]] = {}
    for name, value in (params.model_extra or {}).items():
        _reserved(name, where("parameters", name))
        vec = value if isinstance(value, list) else [value]
        if not vec:
            raise ConfigError(f"{where('parameters', name)}: parameters.{name} is an empty "
                              "list; give it at least one number, or remove it")
        try:
            out[name] = check_vector(vec, len(vec))
        except ConfigError as err:
            raise ConfigError(f"{where('parameters', name)}: parameters.{name}: {err}") from None
    return out


def _problem(d: Definition, G: Groupoid, params: BaseModel, initial: BaseModel,
             final: BaseModel, T: float, name: str, where: Any) -> Problem:
    pb = Problem(G, name=name, order=d.order)
    symbols: dict[str, Any] = {}
    for pname, vec in _values(params, where).items():
        sym = pb.parameter(pname, len(vec), vec)
        symbols[pname] = sym if len(vec) > 1 else sym[0]
    for f in G.factors:  # a state over a point (a rotation) as its matrix: costs, paths
        symbols[f.state] = pb.state(f.state) if f.base_size else pb.node_state(f.state)
        symbols[f.velocity] = pb.velocity(f.velocity)
        if d.order == 2:
            symbols[f"{f.velocity}_dot"] = pb.acceleration(f.velocity)

    def expr(text: str, *path: str) -> Any:
        return compile_expression(text, symbols, f"{where(*path)}: {'.'.join(path)}")

    if d.lagrangian is not None:
        if d.order != 2:
            raise ConfigError(f"{where('definition', 'lagrangian')}: a Lagrangian needs order 2")
        lagrangian = expr(d.lagrangian, "definition", "lagrangian")
        if d.force is not None:
            u = _force_controls(d, G, pb, symbols, expr, lagrangian, where)
        else:
            if not d.actuated:
                raise ConfigError(f"{where('definition', 'lagrangian')}: with a Lagrangian, "
                                  "list the actuated velocities in definition.actuated")
            if isinstance(d.controls, dict):
                raise ConfigError(f"{where('definition', 'controls')}: with a Lagrangian and "
                                  "an input matrix, controls is a list of names; name: size "
                                  "declares controls of their own, which need definition.force")
            B = expr(d.input_matrix, "definition", "input_matrix") if d.input_matrix else None
            actuated = actuated_indices(G, d.actuated, where("definition", "actuated"))
            with located(where, "definition", "lagrangian"):
                u = pb.mechanics(lagrangian, actuated, B, d.controls)
            for (cname, _), k in zip(pb.controls, range(u.numel())):
                symbols[cname] = u[k]
        symbols["u"] = u
    elif d.force is not None:
        raise ConfigError(f"{where('definition', 'force')}: a force drives the mechanics of a "
                          "Lagrangian; write definition.lagrangian too")
    elif isinstance(d.controls, dict):
        if any(not isinstance(v, str) for v in d.controls.values()):
            raise ConfigError(f"{where('definition', 'controls')}: without a Lagrangian, "
                              "controls maps names to expressions (strings)")
        exprs = [expr(str(v), "definition", "controls", k) for k, v in d.controls.items()]
        with located(where, "definition", "controls"):
            pb.report_controls(ca.vertcat(*[ca.vec(e) for e in exprs]), list(d.controls))
    cost = expr(d.cost, "definition", "cost")
    with located(where, "definition", "cost"):
        pb.minimize(cost)
    for cname, text in d.constraints.items():
        c = expr(text, "definition", "constraints", cname)
        with located(where, "definition", "constraints", cname):
            pb.subject_to(c, name=cname)
    for qname, entry in d.describe.items():
        e = Described(unit=entry) if isinstance(entry, str) else entry
        try:
            pb.describe(qname, e.meaning, e.unit, e.components, e.group)
        except ConfigError as err:
            raise ConfigError(f"{where('definition', 'describe', qname)}: {err}") from None
    for cname, text in d.path.items():
        try:
            lhs, op, rhs = comparison(text)
        except ConfigError as err:
            raise ConfigError(f"{where('definition', 'path', cname)}: {err}") from None
        c = expr(lhs, "definition", "path", cname)
        if rhs is not None:
            c = c - expr(rhs, "definition", "path", cname)
        with located(where, "definition", "path", cname):
            if op == "==":
                pb.subject_to(c, name=cname)
            else:
                pb.bound(c if op == "<=" else -c, upper=0.0, name=cname)
    if d.terminal_cost is not None:
        c = expr(d.terminal_cost, "definition", "terminal_cost")
        with located(where, "definition", "terminal_cost"):
            pb.terminal_cost(c)
    with located(where, "initial"):
        pb.initial(**{k: v for k, v in initial.model_dump().items() if v is not None})
    with located(where, "final"):
        pb.final(**{k: v for k, v in final.model_dump().items() if v is not None})
    pb.horizon(T)
    return pb


def _force_controls(d: Definition, G: Groupoid, pb: Problem, symbols: dict[str, Any],
                    expr: Any, lagrangian: Any, where: Any) -> Any:
    """Declare ``definition.controls`` (name: size) as controls of their own and build the
    mechanics with ``definition.force``; returns the stacked controls."""
    if d.input_matrix is not None:
        raise ConfigError(f"{where('definition', 'force')}: give input_matrix (controls "
                          "recovered from the dynamics) or force (controls of their own), "
                          "not both")
    if not d.controls:
        raise ConfigError(f"{where('definition', 'controls')}: with a force, name the controls "
                          "and their sizes, e.g. controls: {f: 1, tau: 3}")
    sizes = {c: 1 for c in d.controls} if isinstance(d.controls, list) else d.controls
    for cname, size in sizes.items():
        _reserved(cname, where("definition", "controls", cname))
        if isinstance(size, bool) or not isinstance(size, int) or size < 1:
            raise ConfigError(f"{where('definition', 'controls', cname)}: with a force, a "
                              f"control maps to its number of components (an integer >= 1), "
                              f"got {size!r}")
        with located(where, "definition", "controls", cname):
            sym = pb.control(cname, size)
        symbols[cname] = sym if size > 1 else sym[0]
    force = expr(d.force, "definition", "force")
    actuated = actuated_indices(G, d.actuated, where("definition", "actuated")) \
        if d.actuated else None
    with located(where, "definition", "force"):
        return pb.mechanics(lagrangian, actuated, force=force)


_COMPARISON = re.compile(r"(<=|>=|==)")


def comparison(text: str) -> tuple[str, str, str | None]:
    """``lhs <= rhs`` -> (lhs, "<=", rhs); a plain expression -> (text, "<=", None)
    (meaning ``text <= 0``). One comparison at most."""
    parts = _COMPARISON.split(text)
    if len(parts) == 1:
        return text, "<=", None
    if len(parts) != 3 or not parts[0].strip() or not parts[2].strip():
        raise ConfigError(f"path constraint {text!r}: write one comparison, 'lhs <= rhs', "
                          "'lhs >= rhs' or 'lhs == rhs' (or an expression meaning <= 0)")
    return parts[0], parts[1], parts[2]


@contextmanager
def located(where: Any, *path: str) -> Iterator[None]:
    """Errors of the Problem API (and CasADi's, on shapes) as messages at ``path``."""
    try:
        yield
    except (ConfigError, DimensionError, BoundaryError) as err:
        raise ConfigError(f"{where(*path)}: {'.'.join(path)}: {err}") from None
    except RuntimeError as err:  # CasADi: e.g. a dimension mismatch between expressions
        reason = str(err).strip().splitlines()[-1][:200] if str(err).strip() else ""
        raise ConfigError(f"{where(*path)}: {'.'.join(path)}: the expressions do not fit "
                          f"together ({reason}); check the sizes of the parameters and "
                          "symbols used") from None


_COMPONENT = re.compile(r"\s*([A-Za-z_]\w*)\s*(?:\[\s*([^\]]*)\])?\s*")


def actuated_indices(G: Groupoid, entries: str | list[str | int] | None, where: str
                     ) -> list[int]:
    """Indices into the velocities y of ``definition.actuated``: velocity names (``Omega``),
    components (``Omega[0]``, ``dphi[0:2]``, ``Omega[-1]``) or indices of y, in a list or in
    one string separated by commas."""
    items: list[str | int] = []
    for e in [entries] if isinstance(entries, str) else entries or []:
        if isinstance(e, str):
            items.extend(part for part in re.split(r",(?![^\[]*\])", e) if part.strip())
        else:
            items.append(e)
    if not items:
        raise ConfigError(f"{where}: definition.actuated is empty; list the actuated "
                          f"velocities, e.g. [{G.velocity_names[0]}]")
    out: list[int] = []
    n = G.algebra_dim
    for item in items:
        if isinstance(item, bool) or not isinstance(item, (int, str)):
            raise ConfigError(f"{where}: definition.actuated: {item!r} is not a velocity name "
                              f"or an index; velocities are {', '.join(G.velocity_names)}")
        picked = _actuated_item(G, item, where) if isinstance(item, str) else [item]
        for i in picked:
            if not 0 <= i < n:
                raise ConfigError(f"{where}: definition.actuated: index {i} is out of range; "
                                  f"the velocities have {n} components (0..{n - 1})")
            if i in out:
                raise ConfigError(f"{where}: definition.actuated: {item!r} names velocity "
                                  f"component {i} a second time; list each component once")
            out.append(i)
    return out


def _actuated_item(G: Groupoid, item: str, where: str) -> list[int]:
    """The indices of y one entry of ``definition.actuated`` names."""
    m = _COMPONENT.fullmatch(item)
    if m is None:
        raise ConfigError(f"{where}: definition.actuated: {item!r} is not a velocity or a "
                          "component of one; write e.g. Omega, Omega[0] or Omega[0:2]")
    name, index = m.group(1), m.group(2)
    if name not in G.velocity_names:
        states = {f.state: f.velocity for f in G.factors}
        hint = f" {name} is a state: its velocity is {states[name]}." if name in states else ""
        close = difflib.get_close_matches(name, G.velocity_names, 1)
        hint += f" did you mean {close[0]!r}?" if close and not hint else ""
        raise ConfigError(f"{where}: definition.actuated: unknown velocity {name!r};{hint} "
                          f"velocities are {', '.join(G.velocity_names)}")
    i, _ = G.by_velocity(name)
    span = G.velocity_layout.slices[i]
    block = range(span.start, span.stop)
    if index is None:
        return list(block)
    parts: list[int | None] = []
    for p in index.split(":"):
        text = p.strip()
        if text and not re.fullmatch(r"[-+]?\d{1,9}", text):
            raise ConfigError(f"{where}: definition.actuated: {item!r}: write an integer "
                              f"index or a slice such as {name}[0] or {name}[0:2]")
        parts.append(int(text) if text else None)
    if len(parts) == 1:
        k = parts[0]
        if k is None or not -len(block) <= k < len(block):
            raise ConfigError(f"{where}: definition.actuated: {item!r}: {name} has "
                              f"{len(block)} components (0..{len(block) - 1})")
        return [block[k]]
    if len(parts) > 3 or (len(parts) == 3 and parts[2] == 0):
        raise ConfigError(f"{where}: definition.actuated: {item!r}: write a slice such as "
                          f"{name}[0:2] (a step, if any, is not 0)")
    picked = list(block[slice(*parts)])
    if not picked:
        raise ConfigError(f"{where}: definition.actuated: {item!r} selects no component of "
                          f"{name}, which has {len(block)}")
    return picked
