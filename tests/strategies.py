"""Hypothesis strategies for algebra elements and rotations."""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st


def vectors(n: int = 3, bound: float = 10.0) -> st.SearchStrategy[np.ndarray]:
    """Vectors with entries in [-bound, bound], small ones included."""
    comp = st.one_of(st.floats(-bound, bound), st.floats(-1e-6, 1e-6))
    return st.lists(comp, min_size=n, max_size=n).map(np.array)


def in_ball(radius: float) -> st.SearchStrategy[np.ndarray]:
    """Vectors of norm below ``radius`` (directions and radii both sampled)."""
    return st.tuples(vectors(3, 1.0), st.floats(0.0, 1.0)).filter(
        lambda t: np.linalg.norm(t[0]) > 1e-3).map(
        lambda t: t[0] / np.linalg.norm(t[0]) * t[1] * radius)
