"""Hypothesis strategies for algebra elements and rotations."""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st


def vectors(n: int = 3, bound: float = 10.0) -> st.SearchStrategy[np.ndarray]:
    """Vectors with entries in [-bound, bound], small ones included."""
    comp = st.one_of(st.floats(-bound, bound), st.floats(-1e-6, 1e-6))
    return st.lists(comp, min_size=n, max_size=n).map(np.array)


def in_ball(radius: float, n: int = 3) -> st.SearchStrategy[np.ndarray]:
    """Vectors of R^n of norm below ``radius`` (directions and radii both sampled)."""
    return st.tuples(vectors(n, 1.0), st.floats(0.0, 1.0)).filter(
        lambda t: np.linalg.norm(t[0]) > 1e-3).map(
        lambda t: t[0] / np.linalg.norm(t[0]) * t[1] * radius)


def twists(dim: int, turning: slice, radius: float, bound: float = 3.0
           ) -> st.SearchStrategy[np.ndarray]:
    """Algebra elements whose rotation part (``turning``) has norm below ``radius`` and whose
    other components lie in [-bound, bound] (small ones included)."""
    rot = range(dim)[turning]
    return st.tuples(in_ball(radius, len(rot)), vectors(dim - len(rot), bound)).map(
        lambda t: _merge(dim, rot, *t))


def _merge(dim: int, rot: range, r: np.ndarray, other: np.ndarray) -> np.ndarray:
    out = np.zeros(dim)
    out[list(rot)] = r
    out[[i for i in range(dim) if i not in rot]] = other
    return out
