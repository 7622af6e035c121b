"""Dependent conditions at a solution: the rank test of the equality-constraint Jacobian.

When prescribed conditions are redundant on the feasible set (a reaction-wheel slew with zero
total momentum and both ``Omega(T)`` and ``dphi(T)`` prescribed: conservation of angular
momentum makes one imply the other), the Jacobian ``J`` of the equality rows loses rank at
the solution, LICQ fails, the multipliers are not unique, and IPOPT converges slowly or to a
degraded point. A generic point does not show it (the dependency holds only where the
conservation law does), so the test runs at the solution itself.

Each vector ``y`` with ``J^T y = 0`` is a dependency among the rows it touches. With the rows
of ``J`` scaled to unit length, such ``y`` are found by two steps of inverse iteration with
the sparse LU of the saddle-point matrix ``K = [[gamma I, J^T], [J, -delta I]]``, whose
eigenvalues near zero are ``-sigma^2 / gamma - delta`` for the small singular values
``sigma`` of ``J``: cheap at any N (one sparse LU, in the band order of the stages:
:class:`BandedLU`), and never squaring the conditioning of ``J`` as ``J J^T`` would. A
column of ``J`` with an entry in most rows (a free T, which every row of the dynamics holds)
is eliminated apart (:class:`SaddleSolve`): left in, it filled the LU of the quadrotor's
minimum-time slew at N = 256 with 14.6 million nonzeros (0.55 s), where the same ``K``
without it takes 0.74 million. A ``y`` with ``|J^T y| <= RANK_TOL`` is a dependency.
Prescribed values are not rows (they are parameters p), so each dependency is named by the
parameters it constrains: ``y^T dg/dp != 0`` means moving that value makes the conditions
inconsistent.
Bounds are left out: active bounds are often dependent (more active points than control
freedom on a bang arc) and their multipliers keep their sign.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl
from scipy.sparse.csgraph import reverse_cuthill_mckee

from ..nlp.transcription import Transcription
from .once import per_transcription

RANK_TOL = 1e-9  # |J^T y| of a dependency, rows of J of unit length, |y| = 1
GAMMA, DELTA = 1e-6, 1e-13  # the saddle-point matrix K
#: a column of J with more nonzeros than this share of the rows, and than DENSE_LEAST, is
#: eliminated apart from the sparse LU (:class:`SaddleSolve`)
DENSE_SHARE, DENSE_LEAST = 0.1, 64
PROBES = 8  # inverse-iteration vectors: more than the dependencies a problem may hold


def _saddle(J: ca.DM, rows: np.ndarray) -> tuple[sp.csc_matrix, sp.csr_matrix, np.ndarray]:
    """The saddle-point matrix ``K`` of the rows ``rows`` of ``J`` scaled to unit length, that
    scaled block, and the rows' norms. Assembled from the coordinates of J's nonzeros at once:
    through scipy's block and diagonal builders it took 3 ms at so3's N = 8 (35 x 101)."""
    colind, rowind = J.sparsity().get_ccs()
    col = np.repeat(np.arange(J.shape[1]), np.diff(colind))
    row, data = np.asarray(rowind), np.array(J.nonzeros())
    index = np.full(J.shape[0], -1)
    index[rows] = np.arange(rows.size)
    keep = index[row] >= 0
    r, c, v = index[row[keep]], col[keep], data[keep]
    m, n = rows.size, J.shape[1]
    norms = np.sqrt(np.bincount(r, v * v, minlength=m))
    v = v / np.where(norms > 0, norms, 1.0)[r]
    K = sp.csc_matrix((np.concatenate([np.full(n, GAMMA), v, v, np.full(m, -DELTA)]),
                       (np.concatenate([np.arange(n), c, n + r, n + np.arange(m)]),
                        np.concatenate([np.arange(n), n + r, c, n + np.arange(m)]))),
                      shape=(n + m, n + m))
    return K, sp.csr_matrix((v, (r, c)), shape=(m, n)), norms


def dense_columns(J: sp.csr_matrix) -> np.ndarray:
    """The columns of J with more nonzeros than :data:`DENSE_SHARE` of its rows and than
    :data:`DENSE_LEAST` (a free T: one entry in every row of the dynamics)."""
    counts = np.bincount(J.indices, minlength=J.shape[1])
    return np.flatnonzero(counts > max(DENSE_LEAST, DENSE_SHARE * J.shape[0]))


class BandedLU:
    """The sparse LU of a matrix A with a symmetric pattern, its rows and columns ordered by
    reverse Cuthill-McKee and factorised in that order (SuperLU's partial pivoting, no column
    ordering of its own): the stages of a transcription follow each other along a band. On
    the saddle-point matrices of the problem files at N = 256 it took 1.6-2.8 times less than
    SuperLU's COLAMD on the quadrotors, the reaction wheels and the heavy top (the quadrotor
    35 -> 22 ms), 0.7-1.1 times on the others (within 1.3 ms), with the same residuals."""

    def __init__(self, A: sp.csc_matrix) -> None:
        self.perm = reverse_cuthill_mckee(A.tocsr(), symmetric_mode=True)
        self.lu = spl.splu(A[self.perm][:, self.perm].tocsc(), permc_spec="NATURAL")

    def solve(self, B: np.ndarray) -> np.ndarray:
        """X with ``A X = B``."""
        X = np.empty(B.shape)
        X[self.perm] = self.lu.solve(np.ascontiguousarray(B[self.perm]))
        return X


class SaddleSolve:
    """Solves ``K Z = B`` for the saddle-point matrix K (:func:`_saddle`) with the variables
    ``dense`` (columns of J, rows and columns of K) eliminated apart, by blocks: with R the
    other indices, ``K_DD = gamma I`` and ``K_DR = K_RD^T`` (K is symmetric),

        Z_D = S^{-1} (B_D - K_DR K_RR^{-1} B_R),   S = K_DD - K_DR K_RR^{-1} K_RD,
        Z_R = K_RR^{-1} B_R - (K_RR^{-1} K_RD) Z_D,

    one sparse LU of ``K_RR`` (whose ordering the dense rows no longer spoil) and ``|D|``
    solves with it. ``S = gamma I + K_DR (delta I + J_R J_R^T / gamma)^{-1} K_RD`` (the
    y-block of ``K_RR^{-1}`` is negative definite): symmetric positive definite, never a
    difference of near-equal terms. Without dense columns, the LU of K itself."""

    def __init__(self, K: sp.csc_matrix, dense: np.ndarray) -> None:
        self.D = np.asarray(dense)
        if not self.D.size:
            self.lu = BandedLU(K)
            return
        keep = np.ones(K.shape[0], dtype=bool)
        keep[dense] = False
        self.R = np.flatnonzero(keep)
        self.lu = BandedLU(K[:, self.R][self.R, :].tocsc())
        self.K_RD = K[:, self.D][self.R, :].toarray()
        self.W = self.lu.solve(self.K_RD)
        self.S = K[:, self.D][self.D, :].toarray() - self.K_RD.T @ self.W

    def solve(self, B: np.ndarray) -> np.ndarray:
        """Z with ``K Z = B`` (B: a matrix of right-hand sides)."""
        if not self.D.size:
            return self.lu.solve(B)
        t = self.lu.solve(B[self.R])
        Z = np.empty_like(t, shape=B.shape)
        Z[self.D] = np.linalg.solve(self.S, B[self.D] - self.K_RD.T @ t)
        Z[self.R] = t - self.W @ Z[self.D]
        return Z


@per_transcription
def _jacobian_p(tr: Transcription) -> ca.Function:
    """``dg/dp (x, p)``: how the constraints move with the parameters, built once."""
    x, p = tr.nlp["x"], tr.nlp["p"]
    return ca.Function("jac_g_p", [x, p], [ca.jacobian(tr.nlp["g"], p)])


def parameter_labels(tr: Transcription) -> list[str]:
    """The condition every entry of p stands for: ``final.Omega``, ``parameters.inertia``..."""
    pb, G, lay = tr.problem, tr.problem.groupoid, tr.layout
    labels = [f"p[{i}]" for i in range(tr.np)]
    for name, sl in pb.parameter_slices.items():
        for i in range(sl.start, sl.stop):
            labels[lay.p_slices["P"].start + i] = f"parameters.{name}"
    for key, end, slices, attr in (("start", "initial", G.target_layout.slices, "state"),
                                   ("end", "final", G.target_layout.slices, "state"),
                                   ("V0", "initial", G.velocity_layout.slices, "velocity"),
                                   ("VN", "final", G.velocity_layout.slices, "velocity")):
        base = lay.p_slices[key].start
        for f, sl in zip(G.factors, slices):
            for i in range(sl.start, sl.stop):
                labels[base + i] = f"{end}.{getattr(f, attr)}"
    labels[lay.p_slices["T"].start] = "horizon.T"
    return labels


def dependencies(tr: Transcription, x: np.ndarray, p: np.ndarray) -> list[np.ndarray]:
    """The dependencies among the equality rows of g at (x, p): unit vectors y over those rows
    with ``|J^T y| <= RANK_TOL`` (module docstring), as vectors over all rows of g."""
    lbg, ubg = (np.array(v).ravel() for v in tr.bounds_function(p)[:2])
    eq = np.flatnonzero(lbg == ubg)
    if eq.size == 0:
        return []
    K, J, norms = _saddle(ca.DM(tr.solver.get_function("nlp_jac_g")(x, p)[1]), eq)
    m, n = J.shape
    solver = SaddleSolve(K, dense_columns(J))
    Z = np.random.default_rng(0).standard_normal((n + m, min(PROBES, m)))
    for _ in range(2):
        Z = solver.solve(Z)
        Z /= np.linalg.norm(Z, axis=0)
    Y = np.linalg.qr(Z[n:])[0]
    residuals = np.linalg.norm(J.T @ Y, axis=0)  # |J^T y| of every column y of Y
    found = []
    for y, residual in zip(Y.T, residuals):
        if residual <= RANK_TOL:
            full = np.zeros(len(lbg))
            full[eq] = y / np.where(norms > 0, norms, 1.0)
            found.append(full)
    return found


def dependent_conditions(tr: Transcription, x: np.ndarray, p: np.ndarray) -> list[str]:
    """One sentence per dependency at (x, p), naming the prescribed values involved and the
    one to leave free; [] when the equality rows are independent (LICQ holds)."""
    deps = dependencies(tr, x, p)
    if not deps:
        return []
    Jp = np.array(_jacobian_p(tr)(x, p))
    labels, rows = parameter_labels(tr), tr.row_labels()
    out: list[str] = []
    for y in deps:
        w = np.abs(y @ Jp)
        hit = np.flatnonzero(w > 1e-6 * w.max(initial=0.0))
        named = list(dict.fromkeys(labels[j] for j in hit
                                   if not labels[j].startswith(("parameters.", "p["))))
        finals = [n for n in named if n.startswith("final.")]
        if finals:
            others = [n for n in named if n != finals[-1]]
            text = (f"{finals[-1]} is implied by {', '.join(others) or 'the other conditions'} "
                    "and the equations of motion (an unactuated direction or a conservation "
                    f"law): leave {finals[-1]} free")
        else:
            big = np.flatnonzero(np.abs(y) > 1e-3 * np.abs(y).max())
            involved = list(dict.fromkeys(rows[i].split(" at ")[0] for i in big))
            text = (f"the constraints {', '.join(involved[:4])} are dependent (LICQ fails): "
                    "remove a redundant constraint")
        if text not in out:
            out.append(text)
    return out
