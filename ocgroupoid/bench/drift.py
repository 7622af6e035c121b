"""How far a shooting baseline's own coordinates left SO(3).

The baselines integrate an attitude as a plain vector (:mod:`~ocgroupoid.nlp.schemes.
coordinates`). The Solution reads it back through a unit quaternion, which hides part of the
drift (rk4_matrix's nine numbers are read back through Shepperd's quaternion, normalised).
Measured on the NLP variables themselves, over the nodes:

* quaternion: ``max_k | |q_k| - 1 |``;
* matrix: ``max_k |R_k^T R_k - I|`` (Frobenius);
* Euler angles: 0 (every triple is a rotation).
"""

from __future__ import annotations

import numpy as np

from ..nlp.transcription import Transcription
from ..solve import Solution


def coordinate_drift(tr: Transcription, sol: Solution) -> dict[str, float]:
    """The drift of every SO(3) state of a baseline's solution (module docstring); {} for
    our schemes, which stay on the group by construction."""
    coords = getattr(tr.scheme, "coords", None)
    if coords is None:
        return {}
    z = np.asarray(tr.unpack(sol.x, sol.p)["z"], dtype=float)  # N x nz
    out: dict[str, float] = {}
    start = 0
    for c in coords:
        block = z[:, start:start + c.size]
        start += c.size
        if c.name == "matrix":
            R = block.reshape(-1, 3, 3).transpose(0, 2, 1)  # ca.vec stacks columns
            gram = np.einsum("kji,kjl->kil", R, R) - np.eye(3)
            out[c.factor.state] = float(np.max(np.linalg.norm(gram, axis=(1, 2))))
        elif c.name == "euler":
            out[c.factor.state] = 0.0
        elif c.size == 4 and sol.manifolds.get(c.factor.state) == "SO(3)":
            out[c.factor.state] = float(np.max(np.abs(np.linalg.norm(block, axis=1) - 1.0)))
    return out
