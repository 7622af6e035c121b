"""Buffered calls (``nlp.buffered``): the same numbers as a plain call, clear errors."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import ocgroupoid as og
from ocgroupoid.nlp.buffered import Buffered
from ocgroupoid.systems.rigid_body import rigid_body


@pytest.mark.parametrize("backend", ["ipopt", "fatrop"])
def test_buffered_solve_equals_plain_call(backend: str) -> None:
    """Every output of a buffered nlpsol call equals the plain call's bit for bit, twice in a
    row (the buffer is reused), and its statistics are the call's."""
    tr = og.compile_problem(rigid_body(), N=8,
                            options=og.SolverOptions(backend=backend)).transcription
    runner = tr.backends[0]
    p = tr.pack()
    x0 = tr.point(tr.guesses(p)[0], p)
    if backend == "fatrop":
        args = runner.arguments(x0, p)
    else:
        lbg, ubg, lbx, ubx = (np.array(v).ravel() for v in runner.bounds(p))
        args = {"x0": x0, "p": p, "lbg": lbg, "ubg": ubg, "lbx": lbx, "ubx": ubx}
    call = Buffered(runner.solver)
    plain = runner.solver(**args)
    iterations = runner.solver.stats()["iter_count"]
    for _ in range(2):
        got = call(**args)
        assert set(got) == set(runner.solver.name_out())
        for name, value in got.items():
            np.testing.assert_array_equal(value, np.array(plain[name]).ravel(), err_msg=name)
        assert call.stats()["iter_count"] == iterations > 0


def test_buffered_defaults_and_errors() -> None:
    x, p = ca.MX.sym("x", 3), ca.MX.sym("p", 0)
    f = ca.Function("f", [x, p], [2 * x, ca.MX(0, 1)], ["x", "p"], ["y", "e"])
    f_default = ca.Function("f", [x, p], [2 * x, ca.MX(0, 1)], ["x", "p"], ["y", "e"],
                            {"default_in": [4.0, 0.0]})
    call = Buffered(f)
    first = call(x=[1.0, 2.0, 3.0])
    np.testing.assert_array_equal(first["y"], [2.0, 4.0, 6.0])
    call(x=np.ones(3))
    np.testing.assert_array_equal(first["y"], [2.0, 4.0, 6.0])  # a copy, not the buffer
    np.testing.assert_array_equal(Buffered(f_default)()["y"], [8.0, 8.0, 8.0])
    with pytest.raises(ValueError, match="input x has 2 entries, expected 3"):
        call(x=[1.0, 2.0])
    with pytest.raises(TypeError, match=r"has no input \['y'\]"):
        call(y=[1.0])
    with pytest.raises(RuntimeError, match="has not been called"):
        Buffered(f).stats()
