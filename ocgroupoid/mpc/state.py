"""The plant's state ``z = (s, y)`` against the NLP: parameters, plans and distances.

A measured state enters the NLP as its initial-state parameters (p's ``start`` and ``V0``,
:mod:`~ocgroupoid.nlp.embedding`); a plan is read at any time by interpolating its node
states and velocities; the distance between two states is taken on the groupoid, factor by
factor (:meth:`~ocgroupoid.groupoid.base.Factor.terminal_error` over every component: the
rotation angle of ``R_a^T R_b`` on SO(3), the norm of the twist's log on SE(3), the Euclidean
norm on R^n), and the velocities' Euclidean distance.
"""

from __future__ import annotations

import numpy as np

from ..nlp.transcription import Transcription


def with_state(tr: Transcription, p: np.ndarray, s: np.ndarray, y: np.ndarray) -> np.ndarray:
    """p with the initial state set to ``(s, y)`` (each factor's state packed: normalised)."""
    G = tr.problem.groupoid
    out = np.array(p, dtype=float)
    start = np.concatenate([np.asarray(f.pack_target(np.asarray(s[ss], dtype=float)),
                                       dtype=float).ravel()
                            for f, ss in zip(G.factors, G.state_layout.slices)])
    out[tr.layout.p_slices["start"]] = start
    out[tr.layout.p_slices["V0"]] = y
    return out


def normalised(tr: Transcription, s: np.ndarray) -> np.ndarray:
    """A stored state with every factor normalised (a unit quaternion, ...)."""
    G = tr.problem.groupoid
    return np.concatenate([np.asarray(f.state_of_target(f.pack_target(
        np.asarray(s[ss], dtype=float))), dtype=float).ravel()
        for f, ss in zip(G.factors, G.state_layout.slices)])


def plan_at(tr: Transcription, out: dict[str, np.ndarray], t: float
            ) -> tuple[np.ndarray, np.ndarray]:
    """The state ``(s, y)`` of a read-out plan at time t of its horizon: node states and
    velocities interpolated linearly (states normalised after), held after its end."""
    nodes, vt = out["t"], out["velocity_t"]
    S = np.array([np.interp(t, nodes, col) for col in out["node_states"].T])
    Y = np.array([np.interp(t, vt, col) for col in out["velocities"].T])
    return normalised(tr, S), Y


def distance(tr: Transcription, a: np.ndarray, b: np.ndarray) -> dict[str, float]:
    """Distances of two states ``z = (s, y)``: per factor state, and of the velocities."""
    G = tr.problem.groupoid
    ns = G.state_size
    out = {}
    for f, ss in zip(G.factors, G.state_layout.slices):
        mask = np.ones(f.state_dim, dtype=bool)
        out[f.state] = float(f.terminal_error(normalised(tr, a[:ns])[ss],
                                              normalised(tr, b[:ns])[ss], mask))
    for f, vs in zip(G.factors, G.velocity_layout.slices):
        out[f.velocity] = float(np.linalg.norm(a[ns:][vs] - b[ns:][vs]))
    return out
