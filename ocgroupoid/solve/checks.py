"""``ocgroupoid check``: dimensions and boundary conditions of a problem, without solving.

Reports the NLP's size (variables, constraints, degrees of freedom: variables minus
equality rows; inequality rows are counted apart), which boundary values
are prescribed and which are left free (natural boundary conditions), and tests the
constraints for redundancy: the Jacobian of all constraints is evaluated at a generic point
on a small grid (the geodesic guess plus a deterministic perturbation: a constant-velocity
path itself can be a singular point of the end-point map, e.g. for the rolling ball on a
fixed plate, where no boundary condition is redundant); each vector of its left null space
is a dependency among constraint rows, reported by the boundary conditions it involves (a
redundant boundary condition makes LICQ fail and IPOPT stall).

A condition redundant only on the feasible set (implied through a conservation law, such as a
reaction-wheel slew with zero total momentum and both ``Omega(T)`` and ``dphi(T)``
prescribed) is invisible at a generic point; when the generic test finds nothing, the small
grid is solved (one start, at most :data:`SMALL_ITER` iterations, tens of ms) and the rank
test of :mod:`~ocgroupoid.verify.dependencies` runs at the point reached.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import casadi as ca
import numpy as np

from ..errors import ConfigError
from ..model.problem import Problem
from ..nlp.assembly import Kind
from ..nlp.method import Method
from ..nlp.options import SolverOptions
from ..nlp.shortcuts import choose
from ..nlp.transcription import Transcription
from ..verify.dependencies import dependent_conditions
from .guesses import geodesic_guesses, perturbed_guesses

SMALL_N = 8
SMALL_ITER = 100


@dataclass
class CheckReport:
    """What ``check`` found."""

    variables: int
    constraints: dict[str, int]
    degrees_of_freedom: int
    inequalities: int = 0
    prescribed: list[str] = field(default_factory=list)
    free: list[str] = field(default_factory=list)
    redundant: list[str] = field(default_factory=list)

    @property
    def total_constraints(self) -> int:
        return sum(self.constraints.values())


def boundary_lists(tr: Transcription) -> tuple[list[str], list[str]]:
    """Prescribed and free boundary values, as ``initial.R``/``final.Omega[2]`` strings."""
    pb, G, m = tr.problem, tr.problem.groupoid, tr.masks
    given, free = [], []
    by_factor = lambda flags: [flags[vs] for vs in G.velocity_layout.slices]  # noqa: E731
    for end, states, vels in (("initial", m.start_state, by_factor(m.start_velocity)),
                              ("final", m.end_state, by_factor(m.end_velocity))):
        for f, sm, vm in zip(G.factors, states, vels):
            for name, mask in ((f.state, sm), (f.velocity, vm if pb.end_velocities else None)):
                if mask is None:
                    continue
                if mask.all():
                    given.append(f"{end}.{name}")
                elif not mask.any():
                    free.append(f"{end}.{name}")
                else:
                    given += [f"{end}.{name}[{j}]" for j in np.flatnonzero(mask)]
                    free += [f"{end}.{name}[{j}]" for j in np.flatnonzero(~mask)]
    return given, free


def equality_rows(tr: Transcription, p: np.ndarray) -> np.ndarray:
    """Rows of g with ``lbg == ubg`` (equalities); the others are inequalities (bounds)."""
    lbg, ubg = (np.array(v).ravel() for v in tr.bounds_function(p)[:2])
    return np.flatnonzero(lbg == ubg)


def redundant_rows(tr: Transcription, tol: float = 1e-9) -> list[str]:
    """Dependent equality-constraint rows at a generic point, boundary conditions first.

    Every vector y with ``J_E^T y = 0`` (``J_E`` the Jacobian of the equality rows) is a
    linear dependency among the rows it touches; for each, the boundary-condition rows
    involved are reported (or, if none, the first rows). Inequality rows are left out: an
    inactive bound costs LICQ nothing.
    """
    p = tr.pack()
    x = tr.point(perturbed_guesses(geodesic_guesses(tr, p)[0], tr.horizon_of(p), 1)[0], p)
    eq = equality_rows(tr, p)
    J = np.array(ca.DM(tr.solver.get_function("nlp_jac_g")(x, p)[1]))[eq]
    if J.size == 0:
        return []
    if not np.all(np.isfinite(J)):
        raise ConfigError("the constraints' derivatives are not finite at a start on the "
                          "geodesic guess: a parameter or boundary value is beyond what double "
                          "precision resolves here (of the order of 1e300?); give values of "
                          "physical size")
    U, sv, _ = np.linalg.svd(J, full_matrices=True)
    rank = int(np.sum(sv > tol * max(1.0, sv.max(initial=0.0))))
    labels = [tr.row_labels()[i] for i in eq]
    found: list[str] = []
    for y in U[:, rank:].T:
        rows = np.flatnonzero(np.abs(y) > 1e-8 * np.abs(y).max())
        named = [labels[i] for i in rows if labels[i].startswith("final")] or \
            [labels[i] for i in rows[:3]]
        others = len(rows) - len(named)
        text = " and ".join(named) + (f" (with {others} other rows)" if others > 0 else "")
        if text not in found:
            found.append(text)
    return found


def check(problem: Problem, method: Method | int | None = None,
          options: SolverOptions | str | None = None, *positional: Any,
          **keywords: Any) -> CheckReport:
    """Build the NLP with ``method`` (dimensions) and at a small N (redundancy test);
    ``method`` and ``options`` as in :func:`~ocgroupoid.solve.entry.compile_problem`, of which the
    test reads the IPOPT options (it builds IPOPT, without jit)."""
    method, options = choose(method, options, *positional, **keywords)
    # the one solve (implied_conditions) stops early
    capped = SolverOptions(ipopt={**options.ipopt, "max_iter": SMALL_ITER})
    tr = Transcription(problem, method, capped)
    blocks: dict[str, int] = {}
    for b in tr.blocks:
        key = "final conditions" if b.kind is Kind.FINAL_CONDITION else b.kind.value
        blocks[key] = blocks.get(key, 0) + b.m * b.ncols
    given, free = boundary_lists(tr)
    n_eq = len(equality_rows(tr, tr.pack()))
    small = tr if method.N <= SMALL_N else \
        Transcription(problem, replace(method, N=SMALL_N), capped)
    return CheckReport(tr.nx, blocks, tr.nx - n_eq, tr.ng - n_eq, given, free,
                       redundant_rows(small) or implied_conditions(small))


def implied_conditions(tr: Transcription) -> list[str]:
    """Conditions implied on the feasible set: the rank test at the point a short solve of
    the small grid ``tr`` (built with ``max_iter`` :data:`SMALL_ITER`) reaches (module
    docstring)."""
    p = tr.pack()
    r = tr.solve(geodesic_guesses(tr, p)[0], p)
    return dependent_conditions(tr, r.x, r.p)
