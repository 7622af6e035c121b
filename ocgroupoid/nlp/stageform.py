"""The stage form of a block NLP: the variable and row order a Riccati solver (fatrop) needs.

fatrop solves  min sum_k l_k(x_k, u_k)  s.t.  x_{k+1} = F_k(x_k, u_k),  c_k(x_k, u_k) in
[lo, up]  with the variables ordered ``z = [x_0, u_0, x_1, u_1, ..., x_K, u_K]`` and the rows
``[gaps into x_1, stage 0 rows, gaps into x_2, stage 1 rows, ..., stage K rows]``; every gap
row reads ``x_{k+1}[i] - F_k(x_k, u_k)_i`` (coefficient +1 on one state), and every other row
and cost term reads one stage only (the Hessian of the Lagrangian is block diagonal).

Every scheme's blocks (:mod:`~ocgroupoid.nlp.assembly`) are already stage-wise but for two
things: a stage reads variables of earlier stages (a node of ``order2`` reads xi_{k-1} and
xi_k; every interval reads a free horizon T), and the variables are not in this order.
:func:`stage_form` fixes both without touching a scheme: the dynamics blocks
(:attr:`Block.next`: the stage inputs that are ``x_{k+1}``) chain the stages; every other
variable is a control of the first stage that reads it (a variable of no dynamics block: of
the earliest stage its readers allow); a variable read at a later stage than its own is
carried there as a state copy with the gap row ``copy_{j+1} - copy_j = 0``. The result is
the same NLP — the same Functions at the same points, plus the copies — in fatrop's order,
with the maps between its point and the original one (rows of the original g keep their
signs, so multipliers map by a permutation).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TypeVar

import casadi as ca
import numpy as np

from ..errors import ConfigError
from .assembly import Block, Kind
from .schemes.base import stage_function


class NotStaged(ConfigError):
    """The blocks do not form a chain of stages (a reason in the message)."""


@dataclass(frozen=True)
class StageForm:
    """The stage-ordered NLP of a list of blocks (module docstring).

    ``z_slot[v]`` is the z-index of the original variable v; ``source[j]`` the original
    variable z_j holds (its own slot or a copy); ``order[i]`` the row of the assembled blocks
    (the original rows, then one per copy) that stage-form row i is.
    """

    blocks: list[Block]  # the original blocks re-indexed into [z; p], then the copy block
    nz: int
    nx: list[int]  # states per stage, K + 1 entries
    nu: list[int]  # controls per stage
    ng: list[int]  # non-gap rows per stage
    z_slot: np.ndarray
    source: np.ndarray
    order: np.ndarray
    n_rows: int  # rows of the original NLP

    @property
    def K(self) -> int:
        return len(self.nx) - 1

    @cached_property
    def bound_index(self) -> np.ndarray:
        """For every z_j, the original variable whose bounds it takes; copies point one past
        the end (an appended free bound)."""
        index = np.full(self.nz, self.z_slot.size)
        index[self.z_slot] = np.arange(self.z_slot.size)
        return index

    @cached_property
    def gap_rows(self) -> np.ndarray:
        """Whether each stage-form row is a gap row (``x_{k+1} - F_k = 0``)."""
        gap = np.zeros(self.order.size, dtype=bool)
        start = 0
        for nx_next, ng in zip(self.nx[1:], self.ng):
            gap[start:start + nx_next] = True
            start += nx_next + ng
        return gap

    @cached_property
    def rank(self) -> np.ndarray:
        """Stage-form row of each assembled row (the inverse of :attr:`order`)."""
        r = np.empty_like(self.order)
        r[self.order] = np.arange(self.order.size)
        return r

    # -- maps between the two points (numbers, or graphs for the exported solver) -------------

    def z_of(self, x: Values) -> Values:
        """The stage-form point of an original point (copies hold their variable's value)."""
        return _pick(x, self.source)

    def bounds_z(self, lbx: Values, ubx: Values) -> tuple[Values, Values]:
        """Variable bounds on the own slots; copies are free (their gap rows tie them)."""
        index = self.bound_index
        return (_pick(_append(lbx, 1, -np.inf), index), _pick(_append(ubx, 1, np.inf), index))

    def rows_z(self, g: Values) -> Values:
        """Original row values (bounds, multipliers) in stage-form order; copy rows zero."""
        return _pick(_append(g, self.order.size - self.n_rows, 0.0), self.order)

    def rows_x(self, g: Values) -> Values:
        """Stage-form row values back in the original order (copy rows dropped)."""
        return _pick(g, self.rank[:self.n_rows])

    def x_of(self, z: Values) -> Values:
        """The original point (or bound multipliers) of a stage-form one: the own slots."""
        return _pick(z, self.z_slot)


Values = TypeVar("Values", np.ndarray, ca.MX, ca.SX)


def _pick(v: Values, index: np.ndarray) -> Values:
    """``v[index]`` of a vector of numbers or a graph."""
    if isinstance(v, (ca.MX, ca.SX)):
        return v[index.tolist()]
    return np.asarray(v, dtype=float).ravel()[index]


def _append(v: Values, n: int, value: float) -> Values:
    """``v`` followed by n copies of ``value``."""
    if isinstance(v, (ca.MX, ca.SX)):
        return ca.vertcat(v, type(v)(ca.DM.ones(n) * value))
    return np.concatenate([np.asarray(v, dtype=float).ravel(), np.full(n, value)])


def _next_rows(b: Block) -> np.ndarray:
    """The stage inputs of a block that are the next stage's state (none: not dynamics)."""
    rows = np.arange(b.idx.shape[0])
    return rows[b.next] if b.next is not None else rows[:0]


def _read_rows(b: Block) -> np.ndarray:
    """The stage inputs of a block that it reads (all but the next stage's state)."""
    return np.setdiff1d(np.arange(b.idx.shape[0]), _next_rows(b))


def _dynamics_stages(blocks: list[Block], nx: int) -> tuple[np.ndarray, list[np.ndarray]]:
    """The stage each gap row puts its variable in (``x_{k+1}``; -1: no gap defines it), and
    the stage of every column of every dynamics block (-1 elsewhere): a column is at the
    stage after the latest state it reads, in block and column order (the chain)."""
    state = np.full(nx, -1, dtype=np.int64)
    col_stage = [np.full(b.ncols, -1, dtype=np.int64) for b in blocks]
    for b, stages in zip(blocks, col_stage):
        nxt = _next_rows(b)
        if not nxt.size:
            continue
        rest = _read_rows(b)
        for c in range(b.ncols):
            reads = b.idx[rest, c]
            reads = reads[reads < nx]
            stages[c] = max(int(state[reads].max(initial=-1)), 0)
            defined = b.idx[nxt, c]
            defined = defined[defined < nx]  # a prescribed value: that row is a stage row
            if np.any(state[defined] >= 0):
                raise NotStaged(f"block {b.name!r}: a variable is the next state of two gap "
                                "rows")
            state[defined] = stages[c] + 1
    return state, col_stage


def stage_form(blocks: list[Block], nx: int) -> StageForm:
    """The stage form of ``blocks`` over ``w = [x; p]`` with nx variables (module docstring);
    raises :class:`NotStaged` with the reason when they are not a chain of stages."""
    state, col_stage = _dynamics_stages(blocks, nx)
    K = int(state.max(initial=0))
    if K == 0:
        raise NotStaged("no dynamics block (Block.next) chains the stages")
    is_state = state >= 0
    # home stage: a state's own; else the first dynamics column reading it ...
    big = np.iinfo(np.int64).max
    home = np.where(is_state, state, big)
    reads = [_read_rows(b) for b in blocks]
    for b, rest, stages in zip(blocks, reads, col_stage):
        if b.next is not None:
            vs = b.idx[rest]
            cols = np.broadcast_to(stages, vs.shape)
            inside = (vs < nx) & ~is_state[np.minimum(vs, nx - 1)]
            np.minimum.at(home, vs[inside], cols[inside])
    # ... else the earliest stage its other readers allow (the latest of their homes)
    for _ in range(3):
        for b, rest in zip(blocks, reads):
            vs = b.idx[rest]
            known = np.where(vs < nx, home[np.minimum(vs, nx - 1)], -1)
            known = np.where(known == big, -1, known)
            tau = known.max(axis=0, initial=-1)
            open_ = (vs < nx) & (known < 0) & (tau >= 0)[None, :]
            np.minimum.at(home, vs[open_], np.broadcast_to(tau, vs.shape)[open_])
    home = np.where(home == big, 0, home)
    # the stage of every column, and the last stage that reads each variable
    homes = np.concatenate([home, [-1]])
    tau_of, need = [], home.copy()
    for b, rest, stages in zip(blocks, reads, col_stage):
        vs = np.where(b.idx[rest] < nx, b.idx[rest], nx)
        tau = np.where(stages >= 0, stages, homes[vs].max(axis=0, initial=0))
        late = homes[vs] > tau[None, :]
        if late.any():
            r, c = np.argwhere(late)[0]
            raise NotStaged(f"block {b.name!r} at stage {tau[c]} reads variable "
                            f"{vs[r, c]} of the later stage {homes[vs[r, c]]}")
        inside = vs < nx
        np.maximum.at(need, vs[inside], np.broadcast_to(tau, vs.shape)[inside])
        tau_of.append(tau)
    # the gap rows, in block, column and row order, with the variable each defines
    row_start = np.cumsum([0] + [b.m * b.ncols for b in blocks])
    gap_row, gap_var = [], []
    for b, r0 in zip(blocks, row_start):
        nxt = _next_rows(b)
        if nxt.size:
            vs = b.idx[nxt]  # (m, ncols): row r of column c defines vs[r, c]
            rows = r0 + np.arange(b.ncols)[None, :] * b.m + np.arange(nxt.size)[:, None]
            keep = (vs < nx).T.ravel()
            gap_row.append(rows.T.ravel()[keep])
            gap_var.append(vs.T.ravel()[keep])
    gap_row_a, gap_var_a = np.concatenate(gap_row), np.concatenate(gap_var)
    n_rows = int(row_start[-1])
    # z: per stage, the gap-defined states (in gap-row order), the copies, the controls
    copies = np.maximum(need - home, 0)
    first_copy = np.concatenate([[0], np.cumsum(copies)[:-1]])  # of variable v, by stage
    copy_var = np.repeat(np.arange(nx), copies)
    copy_stage = home[copy_var] + 1 + np.arange(copy_var.size) - first_copy[copy_var]
    controls = np.flatnonzero(~is_state)
    stage_z = np.concatenate([state[gap_var_a], copy_stage, home[controls]])
    kind_z = np.concatenate([np.zeros(gap_var_a.size), np.ones(copy_var.size),
                             np.full(controls.size, 2)])
    within = np.concatenate([np.arange(gap_var_a.size), copy_var, controls])
    order_z = np.lexsort((within, kind_z, stage_z))
    position = np.empty_like(order_z)
    position[order_z] = np.arange(order_z.size)
    n_gap, n_copy = gap_var_a.size, copy_var.size
    source = np.concatenate([gap_var_a, copy_var, controls])[order_z]
    z_slot = np.empty(nx, dtype=np.int64)
    z_slot[gap_var_a] = position[:n_gap]
    z_slot[controls] = position[n_gap + n_copy:]
    copy_slot = position[n_gap:n_gap + n_copy]
    padded = np.concatenate([copy_slot, [-1]])  # (np.where evaluates both branches)

    def slot(v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """z-index of variable v at stage tau (its own slot, or its copy there)."""
        own = home[v] == tau
        k = np.where(own, 0, first_copy[v] + tau - home[v] - 1)
        return np.where(own, z_slot[v], padded[np.minimum(k, n_copy)])

    nz = int(source.size)
    nxs = np.bincount(stage_z[kind_z < 2], minlength=K + 1).tolist()
    nus = np.bincount(stage_z[kind_z == 2], minlength=K + 1).tolist()
    # the blocks re-indexed into [z; p]
    out = []
    for b, rest, tau in zip(blocks, reads, tau_of):
        vs = b.idx
        idx = np.where(vs >= nx, nz + vs - nx, 0)
        taus = np.broadcast_to(tau, vs.shape)
        read = np.zeros(vs.shape, dtype=bool)
        read[rest] = True
        inside = vs < nx
        idx[inside & read] = slot(vs[inside & read], taus[inside & read])
        idx[inside & ~read] = z_slot[vs[inside & ~read]]
        out.append(Block(b.name, b.fun, idx, b.n_param, b.kind, b.rows, b.columns, b.times,
                         b.points, b.bounds, next=b.next))
    if n_copy:
        copy = stage_function("copy", [1, 1], lambda a, b: (ca.SX(1, 1), b - a))
        cidx = np.vstack([slot(copy_var, copy_stage - 1), slot(copy_var, copy_stage)])
        out.append(Block("copy", copy, cidx, 0, Kind.RECONSTRUCTION, ["copy"],
                         [f"stage {j}" for j in copy_stage], next=slice(1, 2)))
    # row order: per stage, the gap rows into x_{k+1} in state order, then the stage's rows
    n_all = n_rows + n_copy
    defines = np.full(n_all, -1, dtype=np.int64)  # the z-index a gap row defines
    defines[gap_row_a] = z_slot[gap_var_a]
    defines[n_rows + np.arange(n_copy)] = copy_slot
    row_tau = np.concatenate([np.repeat(tau, b.m) for b, tau in zip(blocks, tau_of)] +
                             [copy_stage - 1])
    is_gap = defines >= 0
    stage_row = np.where(is_gap, np.concatenate([stage_z[order_z], [0]])[defines] - 1,
                         row_tau)
    within_row = np.where(is_gap, defines, np.arange(n_all))
    order = np.lexsort((within_row, ~is_gap, stage_row))
    ngs = np.bincount(stage_row[~is_gap], minlength=K + 1).tolist()
    return StageForm(out, nz, nxs, nus, ngs, z_slot, source, order, n_rows)
