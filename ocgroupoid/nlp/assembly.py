"""Sparse derivatives of a sum of mapped stage functions, assembled without global AD.

An NLP built as  f = sum_b sum_c F_b(z_bc)_f,  g = [vec(F_b(z_bc)_g)]_b  with every stage
input ``z_bc = w[idx_b[:, c]]`` gathered from ``w = [x; p]`` has block-sparse derivatives.
Each stage's gradient, Jacobian and Hessian of the Lagrangian are derived symbolically once
(SX, a few dozen entries), evaluated with ``Function.map`` over the columns, and scattered into
the global sparse matrices by one gather and a row sum (entries that land on the same position
add up). The symbolic work is the same for any N (only index bookkeeping grows), and an
evaluation is one pass over the stages (no colouring sweeps over the whole graph).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import Any, Callable

import casadi as ca
import numpy as np


class Kind(Enum):
    """What a block's constraint rows are; the value is how reports name them."""

    RECONSTRUCTION = "reconstruction"  # s_{k+1} = step(s_k, tau(...)): multipliers unused
    PATH = "Phi_d"  # the discrete constraints Phi_d: their multipliers are the seeds' lambda^k
    FINAL = "final conditions"  # prescribed final states, in the factors' charts
    FINAL_CONDITION = "final conditions (user)"  # Problem.final_condition equations
    INEQUALITY = "bounds"  # Problem.bound: lower <= expr <= upper at the constraint points
    MESH = "mesh"  # the steps of a free or adaptive time grid
    COST = "cost"  # cost terms without constraints (time, terminal)


@dataclass
class Block:
    """One kind of stage: ``fun(z) -> (f, g)`` applied to the columns of ``w[idx]``.

    ``rows`` names the m constraint rows of one column and ``columns`` each column (e.g.
    ``node 3``). A column may impose its constraints at several times (``points``, e.g. the
    two Gauss points of an interval): its m rows are then ``points`` groups of m/points rows,
    one group per time. ``times`` are the times of every (column, point), as fractions of T.
    """

    name: str
    fun: ca.Function
    idx: np.ndarray  # (len(z), ncols) indices into w = [x; p]
    n_param: int = 0  # trailing entries of z that are parameters in every column (a hint:
    # assemble() recounts them from idx, e.g. T is a variable when the horizon is free)
    kind: Kind = Kind.PATH
    rows: list[str] = field(default_factory=list)
    columns: list[str] = field(default_factory=list)
    times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    points: int = 1
    #: ``lower <= g <= upper`` per row of a column, expressions of the parameters P (None:
    #: equalities, g = 0)
    bounds: tuple[ca.SX, ca.SX] | None = None
    g_offset: int = 0
    #: a dynamics block: the stage inputs that are the next stage's state, one per row
    #: (``g = z[next] - F(other inputs)``, :mod:`~ocgroupoid.nlp.stageform`)
    next: slice | None = None

    @property
    def n_var(self) -> int:
        """Leading entries of z that may be decision variables (differentiated)."""
        return int(self.idx.shape[0]) - self.n_param

    @property
    def ncols(self) -> int:
        return int(self.idx.shape[1])

    @property
    def m(self) -> int:
        return int(self.fun.size1_out(1))

    @property
    def g_rows(self) -> np.ndarray:
        """Global constraint rows, shaped (m/points, ncols*points), one column per time: with
        one point, column c holds stage c's rows."""
        per = self.m // self.points
        return self.g_offset + np.arange(self.m * self.ncols).reshape(
            self.ncols * self.points, per).T

    def labels(self) -> list[str]:
        """A readable name for each of its constraint rows, column by column."""
        rows = self.rows or [f"row {r}" for r in range(self.m)]
        cols = self.columns or [f"column {c}" for c in range(self.ncols)]
        return [f"{rows[r]} at {cols[c]}" if cols[c] else rows[r]
                for c in range(self.ncols) for r in range(self.m)]


def _gather(v: ca.MX, idx: np.ndarray) -> ca.MX:
    """``v[idx]`` for an integer array of any shape (a flat list converts fastest)."""
    idx = np.asarray(idx)
    flat = v[idx.ravel(order="F").tolist()]
    return ca.reshape(flat, idx.shape[0], idx.shape[1]) if idx.ndim == 2 else flat


#: targets that more sources than this add into (an entry every stage touches, such as the
#: Hessian of a free horizon T) are summed by a sparse product instead of the padded gather
DENSE_ROW = 16


def _sum_into(src: ca.MX, source: np.ndarray, target: np.ndarray, n_target: int) -> ca.MX:
    """``out[t] = sum of src[source[i]] over i with target[i] = t``: one gather, one row sum.

    Sources are grouped by target; groups are padded to the largest multiplicity with an
    index pointing at an appended zero. Targets with more than :data:`DENSE_ROW` sources (a
    padding as wide as N for every target: quadratic in N) are summed by one product with a
    constant sparse 0/1 matrix instead.
    """
    counts = np.bincount(target, minlength=n_target)
    heavy = counts[target] > DENSE_ROW
    light_source, light_target = source[~heavy], target[~heavy]
    order = np.argsort(light_target, kind="stable")
    light = np.bincount(light_target, minlength=n_target)
    start = np.concatenate([[0], np.cumsum(light)[:-1]])
    slot = np.arange(light_target.size) - np.repeat(start, light)
    G = np.full((n_target, max(int(light.max(initial=1)), 1)), src.numel())
    G[light_target[order], slot] = light_source[order]
    out = ca.sum2(_gather(ca.vertcat(src, ca.MX(1, 1)), G))
    if heavy.any():
        S = ca.DM(ca.Sparsity.triplet(n_target, src.numel(), target[heavy].tolist(),
                                      source[heavy].tolist()), 1.0)
        out = out + ca.mtimes(S, src)
    return out


def _sparsity(rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int]
              ) -> tuple[ca.Sparsity, np.ndarray]:
    """CCS sparsity of the unique (row, col) pairs, and each pair's nonzero index."""
    keys = cols.astype(np.int64) * shape[0] + rows
    uniq, inverse = np.unique(keys, return_inverse=True)
    urows, ucols = uniq % shape[0], uniq // shape[0]
    colind = np.searchsorted(ucols, np.arange(shape[1] + 1))
    return ca.Sparsity(shape[0], shape[1], colind.tolist(), urows.tolist()), inverse


class _Scatter:
    """Stage outputs (columns of mapped nonzeros) and the global (row, col) of each entry."""

    def __init__(self) -> None:
        self.values: list[ca.MX] = []
        self.rows: list[np.ndarray] = []
        self.cols: list[np.ndarray] = []

    def add(self, values: ca.MX, rows: np.ndarray, cols: np.ndarray) -> None:
        """``values`` (entries x columns, mapped output) with same-shaped target indices."""
        self.values.append(ca.vec(values))
        self.rows.append(rows.reshape(-1, order="F"))  # column-major, as ca.vec
        self.cols.append(cols.reshape(-1, order="F"))

    def _kept(self, keep: Callable[[np.ndarray, np.ndarray], np.ndarray]
              ) -> tuple[ca.MX, np.ndarray, np.ndarray, np.ndarray]:
        rows, cols = np.concatenate(self.rows), np.concatenate(self.cols)
        mask = keep(rows, cols)
        return ca.vertcat(*self.values), np.flatnonzero(mask), rows[mask], cols[mask]

    def dense(self, n: int, keep: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> ca.MX:
        """A dense column of length n (entries summed by row)."""
        src, source, rows, _ = self._kept(keep)
        return _sum_into(src, source, rows, n)

    def sparse(self, shape: tuple[int, int],
               keep: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> ca.MX:
        """A sparse matrix (entries summed by position)."""
        src, source, rows, cols = self._kept(keep)
        sp, inverse = _sparsity(rows, cols, shape)
        return ca.MX(sp, _sum_into(src, source, inverse, sp.nnz()))


class StageDerivatives:
    """Symbolic first and second derivatives of one block's stage function."""

    def __init__(self, block: Block) -> None:
        fun = block.fun
        z = ca.SX.sym("z", fun.size1_in(0))
        v = z[: block.n_var]
        f, g = fun(z)
        lam_f, lam = ca.SX.sym("lam_f"), ca.SX.sym("lam", g.numel())
        J = ca.jacobian(g, v)
        H, grad_l = ca.hessian(lam_f * f + ca.dot(lam, g), v)
        self.jac_rows, self.jac_cols = _triplet(J)
        self.hess_rows, self.hess_cols = _triplet(H)
        self.grad = ca.Function(f"{block.name}_grad", [z], [ca.gradient(f, v)])
        self.jac = ca.Function(f"{block.name}_jac", [z], [_nonzeros(J)])
        self.hess = ca.Function(f"{block.name}_hess", [z, lam_f, lam], [_nonzeros(H)])
        #: the stage Lagrangian's gradient with its Hessian, from one shared graph
        self.lagrangian = ca.Function(f"{block.name}_lagrangian", [z, lam_f, lam],
                                      [grad_l, _nonzeros(H)])


class Derivatives:
    """The stage derivatives (:class:`StageDerivatives`) of an NLP's block functions, made
    once per function: the assemblies of one NLP (IPOPT's, and fatrop's of its stage form,
    whose blocks call the same functions) then call the same derivative Functions, and one
    library compiled for both (:func:`~ocgroupoid.nlp.jit.compiled`) holds each once.
    With ``lagrangian``, every assembly's Hessian comes from the stage Lagrangian's Function
    (:attr:`StageDerivatives.lagrangian`, the one fatrop's assembly needs) rather than from
    the Hessian's own (:attr:`StageDerivatives.hess`, which skips the gradient)."""

    def __init__(self, lagrangian: bool = False) -> None:
        self.lagrangian = lagrangian
        self._made: dict[tuple[int, int], tuple[ca.Function, StageDerivatives]] = {}

    def of(self, block: Block) -> StageDerivatives:
        """The derivatives of ``block``'s stage function (made on first use)."""
        key = (id(block.fun), block.n_var)  # the Function is held beside: its id stays its
        if key not in self._made:
            self._made[key] = (block.fun, StageDerivatives(block))
        return self._made[key][1]


def _triplet(M: ca.SX) -> tuple[np.ndarray, np.ndarray]:
    rows, cols = M.sparsity().get_triplet()
    return np.array(rows, dtype=np.int64), np.array(cols, dtype=np.int64)


def _nonzeros(M: ca.SX) -> ca.SX:
    return ca.vertcat(*M.nonzeros()) if M.nnz() else ca.SX(0, 1)  # type: ignore[call-overload]  # SXElem


def _stage_sums(blocks: list[Block], w: ca.MX) -> tuple[ca.MX, ca.MX, list[ca.MX]]:
    """f (the sum of the mapped stage costs), g (the stacked stage constraints) and each
    block's gathered stage inputs; sets the blocks' row offsets in g."""
    offset = 0
    f_terms, g_terms, inputs = [], [], []
    for b in blocks:
        b.g_offset = offset
        offset += b.m * b.ncols
        Z = _gather(w, b.idx)
        F, G = b.fun.map(b.ncols)(Z)
        f_terms.append(ca.sum2(F))
        g_terms.append(ca.vec(G))
        inputs.append(Z)
    return sum(f_terms[1:], f_terms[0]), ca.vertcat(*g_terms), inputs


def plain_nlp(blocks: list[Block], x: ca.MX, p: ca.MX) -> dict[str, ca.MX]:
    """The same NLP as a plain ``{x, p, f, g}`` dict, for ``nlpsol`` to differentiate with
    CasADi's own AD: the baselines the assembly is measured against (scripts/bench_so3.py)."""
    f, g, _ = _stage_sums(blocks, ca.vertcat(x, p))
    return {"x": x, "p": p, "f": f, "g": g}


def assemble(blocks: list[Block], x: ca.MX, p: ca.MX, whole: bool = False,
             derivatives: Derivatives | None = None) -> dict[str, Any]:
    """The NLP functions IPOPT needs, from the blocks: f, g and their derivatives.

    Returns ``{"f", "g", "nlp_grad_f", "nlp_jac_g", "nlp_hess_l"}``: the expressions f and g
    (``MX``) and three ``Function``s that carry the names and signatures ``casadi.nlpsol``
    looks up in its function cache. ``nlp_hess_l`` is IPOPT's, the upper triangle of the
    Hessian of the Lagrangian ``lam_f f + lam_g . g``; with ``whole``, fatrop's: the
    Lagrangian's gradient and its whole (symmetric) Hessian, both summed from the stages'
    (one graph per stage, so the gradient costs no Jacobian product). The stages'
    derivatives are ``derivatives``' (:class:`Derivatives`; default: made for this call).
    """
    derivatives = derivatives if derivatives is not None else Derivatives()
    nx = x.numel()
    for b in blocks:  # the trailing entries that point into p in every column
        in_p = np.all(b.idx >= nx, axis=1)
        b.n_param = int(np.argmin(in_p[::-1])) if not in_p.all() else len(in_p)
    f, g, inputs = _stage_sums(blocks, ca.vertcat(x, p))
    ng = int(g.numel())
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", ng)
    grad, jac, hess, grad_l = _Scatter(), _Scatter(), _Scatter(), _Scatter()
    for b, Z in zip(blocks, inputs):
        d = derivatives.of(b)
        LAM = ca.reshape(lam_g[b.g_offset:b.g_offset + b.m * b.ncols], b.m, b.ncols)
        var = b.idx[: b.n_var]  # (stage entry, column) -> index into w
        grad.add(d.grad.map(b.ncols)(Z), var, np.zeros_like(var))
        # Jacobian entry e of column c sits at row g_offset + c m + row_e, column idx[col_e, c]
        jac.add(d.jac.map(b.ncols)(Z),
                b.g_offset + np.arange(b.ncols)[None, :] * b.m + d.jac_rows[:, None],
                var[d.jac_cols, :])
        if whole or derivatives.lagrangian:
            gl, H = d.lagrangian.map(b.ncols)(Z, lam_f, LAM)
            if whole:
                grad_l.add(gl, var, np.zeros_like(var))
        else:
            H = d.hess.map(b.ncols)(Z, lam_f, LAM)
        hess.add(H, var[d.hess_rows, :], var[d.hess_cols, :])
    grad_f = grad.dense(nx, lambda r, c: r < nx)
    jac_g = jac.sparse((ng, nx), lambda r, c: c < nx)
    inside = (lambda r, c: (r < nx) & (c < nx)) if whole else \
        (lambda r, c: (r < nx) & (c < nx) & (r <= c))
    hess_l = hess.sparse((nx, nx), inside)
    lagrangian = ([grad_l.dense(nx, lambda r, c: r < nx), hess_l],
                  ["grad_gamma_x", "hess_gamma_x_x"]) if whole else \
        ([hess_l], ["triu_hess_gamma_x_x"])
    return {
        "f": f,
        "g": g,
        "nlp_grad_f": ca.Function("nlp_grad_f", [x, p], [f, grad_f], ["x", "p"],
                                  ["f", "grad_f_x"]),
        "nlp_jac_g": ca.Function("nlp_jac_g", [x, p], [g, jac_g], ["x", "p"],
                                 ["g", "jac_g_x"]),
        "nlp_hess_l": ca.Function("nlp_hess_l", [x, p, lam_f, lam_g], lagrangian[0],
                                  ["x", "p", "lam_f", "lam_g"], lagrangian[1]),
    }
