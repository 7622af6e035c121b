"""The rank test's linear algebra (ocgroupoid.verify.dependencies): the saddle-point solve
with dense columns eliminated apart is the solve with K, and the dependencies it finds are
the same with and without the elimination."""

from __future__ import annotations

import sys
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spl
from hypothesis import given, settings, strategies as st

import ocgroupoid as og
from ocgroupoid.verify import dependencies as deps

sys.path.insert(0, str(Path(__file__).parent))
from test_bounds_time import minimum_time  # noqa: E402


def jacobian(m: int, n: int, dense: int, seed: int) -> sp.csr_matrix:
    """A sparse m x n Jacobian, a band of a few entries per row, with ``dense`` columns full."""
    rng = np.random.default_rng(seed)
    J = sp.random(m, n - dense, density=min(1.0, 4.0 / n), random_state=rng, format="lil")
    for i in range(m):  # every row touches the band, so that it is not empty
        J[i, (i * (n - dense)) // m] = rng.standard_normal()
    return sp.hstack([J.tocsr(), sp.csr_matrix(rng.standard_normal((m, dense)))]).tocsr()


def saddle(J: sp.csr_matrix) -> tuple[sp.csc_matrix, sp.csr_matrix]:
    K, Js, _ = deps._saddle(ca.DM(sp.csc_matrix(J)), np.arange(J.shape[0]))
    return K, Js


@settings(max_examples=25, deadline=None)
@given(m=st.integers(2, 40), extra=st.integers(1, 30), dense=st.integers(0, 3),
       seed=st.integers(0, 2**31 - 1))
def test_elimination_of_dense_columns_solves_with_K(m: int, extra: int, dense: int,
                                                    seed: int) -> None:
    """K Z = B solved by blocks (the last ``dense`` columns of J apart) against the sparse LU
    of K itself, on random right-hand sides."""
    n = m + extra + dense
    K, _ = saddle(jacobian(m, n, dense, seed))
    D = np.arange(n - dense, n)
    B = np.random.default_rng(seed + 1).standard_normal((n + m, 3))
    Z = deps.SaddleSolve(K, D).solve(B)
    reference = spl.splu(K).solve(B)
    assert np.allclose(K @ Z, B, rtol=0, atol=1e-8 * np.abs(reference).max())
    assert np.allclose(Z, reference, rtol=1e-6, atol=1e-9 * np.abs(reference).max())


def test_a_full_column_counts_as_dense_and_a_band_does_not() -> None:
    J = jacobian(400, 600, 1, 0)
    assert deps.dense_columns(J).tolist() == [599]
    assert deps.dense_columns(jacobian(400, 600, 0, 0)).size == 0
    assert deps.dense_columns(jacobian(40, 60, 1, 0)).size == 0  # below DENSE_LEAST


def test_a_dependency_is_found_through_the_eliminated_column() -> None:
    """Two equal rows in J, one column full: the dependency (e_i - e_j) / sqrt 2 is found with
    the column eliminated apart, as with the whole LU."""
    J = jacobian(300, 420, 1, 3).tolil()
    J[17, :] = J[250, :]
    J = J.tocsr()
    K, Js = saddle(J)
    assert deps.dense_columns(Js).tolist() == [419]
    Z = np.random.default_rng(0).standard_normal((K.shape[0], 4))
    for solver in (deps.SaddleSolve(K, deps.dense_columns(Js)), deps.SaddleSolve(K, np.arange(0))):
        Y = Z.copy()
        for _ in range(2):
            Y = solver.solve(Y)
            Y /= np.linalg.norm(Y, axis=0)
        y = np.linalg.qr(Y[420:])[0][:, 0]
        assert np.linalg.norm(Js.T @ y) <= deps.RANK_TOL
        assert abs(abs(y[17]) - 2 ** -0.5) < 1e-6 and abs(abs(y[250]) - 2 ** -0.5) < 1e-6


@pytest.mark.parametrize("least", [deps.DENSE_LEAST, 10**9])
def test_minimum_time_names_the_implied_components_with_and_without_elimination(
        least: int, monkeypatch: pytest.MonkeyPatch) -> None:
    """The underactuated minimum-time slew (a free T: a full column of J) at N = 32: its final
    components about e1, e2 are implied, found whether T's column is eliminated apart or not."""
    monkeypatch.setattr(deps, "DENSE_LEAST", least)
    solver = og.compile_problem(minimum_time(), N=32, scheme="order2")
    sol = solver.solve(multistart=False)
    tr = solver.transcription
    lbg, ubg = (np.array(v).ravel() for v in tr.bounds_function(sol.p)[:2])
    J = ca.DM(tr.solver.get_function("nlp_jac_g")(sol.x, sol.p)[1])
    _, Js, _ = deps._saddle(J, np.flatnonzero(lbg == ubg))
    assert deps.dense_columns(Js).size == (1 if least < 10**9 else 0)
    found = deps.dependent_conditions(tr, sol.x, sol.p)
    assert found and all("is implied by" in f for f in found), found
