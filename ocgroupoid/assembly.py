"""Sparse derivatives of a sum of mapped stage functions, assembled without global AD.

An NLP built as  f = sum_b sum_c F_b(z_bc)_f,  g = [vec(F_b(z_bc)_g)]_b  with every stage
input ``z_bc = w[idx_b[:, c]]`` gathered from ``w = [x; p]`` has block-sparse derivatives.
Each stage's gradient, Jacobian and Hessian of the Lagrangian are derived symbolically once
(SX, a few dozen entries), evaluated with ``Function.map`` over the columns, and scattered into
the global sparse matrices by a constant 0/1 matrix. Building costs the same for any N, and an
evaluation is one pass over the stages (no colouring sweeps over the whole graph).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np


@dataclass
class Block:
    """One kind of stage: ``fun(z) -> (f, g)`` applied to the columns of ``w[idx]``."""

    name: str
    fun: ca.Function
    idx: np.ndarray  # (len(z), ncols) indices into w = [x; p]
    n_param: int = 0  # trailing entries of z that are parameters in every column
    g_offset: int = 0

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


def _gather(v: ca.MX, idx: np.ndarray) -> ca.MX:
    """``v[idx]`` for an integer array of any shape (a flat list converts fastest)."""
    idx = np.asarray(idx)
    flat = v[idx.ravel(order="F").tolist()]
    return ca.reshape(flat, idx.shape[0], idx.shape[1]) if idx.ndim == 2 else flat


def _sum_into(src: ca.MX, target: np.ndarray, n_target: int) -> ca.MX:
    """``out[t] = sum of src[i] over i with target[i] = t`` as one gather and a row sum.

    Sources are grouped by target; groups are padded to the largest multiplicity with an
    index pointing at an appended zero.
    """
    order = np.argsort(target, kind="stable")
    counts = np.bincount(target, minlength=n_target)
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    slot = np.arange(target.size) - np.repeat(start, counts)
    G = np.full((n_target, max(int(counts.max(initial=1)), 1)), src.numel())
    G[target[order], slot] = order
    padded = ca.vertcat(src, ca.MX(1, 1))
    return ca.sum2(_gather(padded, G))


def _sparsity(rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int]
              ) -> tuple[ca.Sparsity, np.ndarray]:
    """CCS sparsity of the unique (row, col) pairs, and each pair's nonzero index."""
    keys = cols.astype(np.int64) * shape[0] + rows
    uniq, inverse = np.unique(keys, return_inverse=True)
    urows, ucols = uniq % shape[0], uniq // shape[0]
    colind = np.searchsorted(ucols, np.arange(shape[1] + 1))
    return ca.Sparsity(shape[0], shape[1], colind.tolist(), urows.tolist()), inverse


class StageDerivatives:
    """Symbolic first and second derivatives of one block's stage function."""

    def __init__(self, block: Block) -> None:
        fun = block.fun
        z = ca.SX.sym("z", fun.size1_in(0))
        v = z[: block.n_var]
        f, g = fun(z)
        lam_f, lam = ca.SX.sym("lam_f"), ca.SX.sym("lam", g.numel())
        J = ca.jacobian(g, v)
        H = ca.hessian(lam_f * f + ca.dot(lam, g), v)[0]
        self.jac_rows, self.jac_cols = _triplet(J)
        self.hess_rows, self.hess_cols = _triplet(H)
        self.grad = ca.Function(f"{block.name}_grad", [z], [ca.gradient(f, v)])
        self.jac = ca.Function(f"{block.name}_jac", [z], [_nonzeros(J)])
        self.hess = ca.Function(f"{block.name}_hess", [z, lam_f, lam], [_nonzeros(H)])


def _triplet(M: ca.SX) -> tuple[np.ndarray, np.ndarray]:
    rows, cols = M.sparsity().get_triplet()
    return np.array(rows, dtype=np.int64), np.array(cols, dtype=np.int64)


def _nonzeros(M: ca.SX) -> ca.SX:
    return ca.vertcat(*M.nonzeros()) if M.nnz() else ca.SX(0, 1)


def assemble(blocks: list[Block], x: ca.MX, p: ca.MX) -> dict[str, ca.Function]:
    """The NLP functions IPOPT needs, from the blocks: f, g and their derivatives.

    Returns ``{"f", "g", "nlp_grad_f", "nlp_jac_g", "nlp_hess_l"}``; the last three carry
    the names and signatures ``casadi.nlpsol`` looks up in its function cache.
    """
    nx = x.numel()
    w = ca.vertcat(x, p)
    offset = 0
    for b in blocks:
        b.g_offset = offset
        offset += b.m * b.ncols
    ng = offset
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", ng)

    f_terms, g_terms, grad_src, jac_src, hess_src = [], [], [], [], []
    grad_t: list[tuple[np.ndarray, np.ndarray]] = []
    jac_t: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    hess_t: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    n_grad = n_jac = n_hess = 0
    for b in blocks:
        d = StageDerivatives(b)
        Z = _gather(w, b.idx)
        F, G = b.fun.map(b.ncols)(Z)
        f_terms.append(ca.sum2(F))
        g_terms.append(ca.vec(G))
        LAM = ca.reshape(lam_g[b.g_offset:b.g_offset + b.m * b.ncols], b.m, b.ncols)
        grad_src.append(ca.vec(d.grad.map(b.ncols)(Z)))
        jac_src.append(ca.vec(d.jac.map(b.ncols)(Z)))
        hess_src.append(ca.vec(d.hess.map(b.ncols)(Z, lam_f, LAM)))
        cols = np.arange(b.ncols)
        # gradient: source (c, j) -> x index idx[j, c]
        gi = b.idx[: b.n_var].T.reshape(-1)
        grad_t.append((gi, n_grad + np.arange(gi.size)))
        n_grad += gi.size
        # Jacobian: source (c, e) -> (g_offset + c m + row_e, idx[col_e, c])
        ne = d.jac_rows.size
        jr = (b.g_offset + cols[:, None] * b.m + d.jac_rows[None, :]).reshape(-1)
        jc = b.idx[d.jac_cols, :].T.reshape(-1)
        jac_t.append((jr, jc, n_jac + np.arange(jr.size)))
        n_jac += ne * b.ncols
        # Hessian: source (c, e) -> (idx[row_e, c], idx[col_e, c]), upper triangle kept
        ne = d.hess_rows.size
        hr = b.idx[d.hess_rows, :].T.reshape(-1)
        hc = b.idx[d.hess_cols, :].T.reshape(-1)
        hess_t.append((hr, hc, n_hess + np.arange(hr.size)))
        n_hess += ne * b.ncols

    def scatter(src: list[ca.MX], t: list, n_src: int, shape: tuple[int, int], triu: bool
                ) -> ca.MX:
        rows = np.concatenate([a[0] for a in t])
        cols = np.concatenate([a[1] for a in t])
        srcs = np.concatenate([a[2] for a in t])
        keep = (rows < shape[0]) & (cols < nx)
        if triu:
            keep &= rows <= cols
        sp, inverse = _sparsity(rows[keep], cols[keep], shape)
        values = _gather(ca.vertcat(*src), srcs[keep])
        return ca.MX(sp, _sum_into(values, inverse, sp.nnz()))

    grad_rows = np.concatenate([a[0] for a in grad_t])
    grad_srcs = np.concatenate([a[1] for a in grad_t])
    keep = grad_rows < nx
    f = sum(f_terms[1:], f_terms[0])
    g = ca.vertcat(*g_terms)
    grad_f = _sum_into(_gather(ca.vertcat(*grad_src), grad_srcs[keep]), grad_rows[keep], nx)
    jac_g = scatter(jac_src, jac_t, n_jac, (ng, nx), triu=False)
    hess = scatter(hess_src, hess_t, n_hess, (nx, nx), triu=True)
    return {
        "f": f,
        "g": g,
        "nlp_grad_f": ca.Function("nlp_grad_f", [x, p], [f, grad_f], ["x", "p"],
                                  ["f", "grad_f_x"]),
        "nlp_jac_g": ca.Function("nlp_jac_g", [x, p], [g, jac_g], ["x", "p"],
                                 ["g", "jac_g_x"]),
        "nlp_hess_l": ca.Function("nlp_hess_l", [x, p, lam_f, lam_g], [hess],
                                  ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"]),
    }
