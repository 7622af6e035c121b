"""The QP Hessian a Riccati recursion can factor: each stage's block projected onto the
positive definite matrices.

HPIPM (and every Riccati-based QP solver) eliminates the stages one after the other and
factors, at each, the stage Hessian plus the cost-to-go (Frison and Diehl 2020, §3); it needs
each of these positive definite. The exact Hessian of the Lagrangian does not give that on a
mechanical problem away from zero multipliers: the curvature of the dynamics and of the
stage equality rows (the discrete Euler-Lagrange equations, the reaction wheels' momentum
rows, the quadrotor's underactuation rows) enters with the multipliers and makes the stage
blocks indefinite — measured at the converged plans: smallest eigenvalues -0.27 (reaction
wheels), -3.3 (quadrotor), -2.9 (free flyer), while the reduced Hessian of the whole NLP is
positive definite. HPIPM's interior point method holds an equality row as two inequalities
with a barrier that only becomes stiff near convergence, so the early Riccati factorisations
meet the indefinite blocks and the method stalls at its iteration limit.

The Hessian is block diagonal in the stage order (:mod:`~ocgroupoid.nlp.stageform`), so
the projection acts on each block alone: ``H_k = V diag(e) V^T`` becomes
``V diag(max(e, delta)) V^T`` (Verschueren, Zanon, Quirynen, Diehl, "A sparsity preserving
convexification procedure for indefinite quadratic programs arising in direct optimal
control", SIAM J. Optim. 27(3), 2017, §2: the ``project`` strategy acados offers beside
``mirror`` and ``convexify``). A block that is already positive definite is kept exactly,
with it the exact Hessian's quadratic contraction; the floor ``delta`` is relative to the
largest entry of H (:data:`~ocgroupoid.nlp.rti.FLOOR`). The blocks are gathered from and
scattered back to the nonzeros with index maps built once; blocks of equal size are
decomposed in one batched ``numpy.linalg.eigh`` call (the free flyer at N = 64, 64 blocks of
19: 2.5 ms, and 4 ms to build the CasADi matrix of the result). The exported C projects the
same blocks with Jacobi rotations (``{prefix}mpc.c``: :mod:`ocgroupoid.export.mpc`).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..nlp.rti import FLOOR
from ..nlp.stageform import NotStaged


class StageProjection:
    """Projects a Hessian with the sparsity ``sp`` (inside the stage blocks of ``sizes``,
    each stage's ``nx + nu``) block by block (module docstring); :attr:`sparsity` is the
    pattern of the result (dense blocks)."""

    def __init__(self, sp: ca.Sparsity, sizes: list[int]) -> None:
        start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        n = int(start[-1])
        stage = np.repeat(np.arange(len(sizes)), sizes)
        self.sparsity = ca.diagcat(*[ca.Sparsity.dense(s, s) for s in sizes])
        rows, cols = (np.asarray(v, dtype=np.int64) for v in sp.get_triplet())
        if np.any(stage[rows] != stage[cols]):
            raise NotStaged("the Hessian couples two stages")
        self._groups: list[tuple[np.ndarray, int]] = []  # (stages, block size)
        slot = np.empty(len(sizes), dtype=np.int64)  # the stage's index in its group
        for size in sorted(set(sizes) - {0}):
            members = np.flatnonzero(np.asarray(sizes) == size)
            slot[members] = np.arange(members.size)
            self._groups.append((members, size))
        group_of = {size: g for g, (_, size) in enumerate(self._groups)}
        offsets = np.concatenate([[0], np.cumsum([m.size * s * s for m, s in self._groups])])

        def flat(r: np.ndarray, c: np.ndarray) -> np.ndarray:
            """Where entry (r, c) lives in the concatenation of the groups' block stacks."""
            k = stage[r]
            size = np.asarray(sizes)[k]
            g = np.array([group_of[s] for s in size], dtype=np.int64)
            return offsets[g] + slot[k] * size * size + (r - start[k]) * size + (c - start[k])

        self._gather = flat(rows, cols)
        out_rows, out_cols = (np.asarray(v, dtype=np.int64) for v in self.sparsity.get_triplet())
        self._scatter = flat(out_rows, out_cols)
        self._size = int(offsets[-1])
        self._offsets = offsets
        self.n = n

    def __call__(self, H: ca.DM) -> ca.DM:
        """The projected Hessian, on :attr:`sparsity`."""
        values = np.asarray(H.nonzeros(), dtype=float)
        stacked = np.zeros(self._size)
        stacked[self._gather] = values
        delta = FLOOR * max(float(np.max(np.abs(values), initial=0.0)), 1e-12)
        for (members, size), a, b in zip(self._groups, self._offsets[:-1], self._offsets[1:]):
            blocks = stacked[a:b].reshape(members.size, size, size)
            e, V = np.linalg.eigh(blocks)
            stacked[a:b] = ((V * np.maximum(e, delta)[:, None, :]) @ V.transpose(0, 2, 1)).ravel()
        return ca.DM(self.sparsity, stacked[self._scatter].tolist())  # a list: converted fastest
