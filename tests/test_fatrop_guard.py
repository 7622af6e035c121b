"""fatrop in the caller's process, guarded (issue 26: the helper's way there and back was half
a small solve): a guarded solve is the solve to the last bit; it is left at its deadline
even inside fatrop's endless inertia correction (which never calls back), when its caller
says stop, or when that question raises; and after it was left the next solve is what a new
solver gives."""

from __future__ import annotations

import sys
import threading
import time

import numpy as np
import pytest

from ocgroupoid.nlp.backends.fatrop_ocp import FatropOcp, Guard
from ocgroupoid.nlp.isolated import Stopped

from .test_fatrop_ocp import CASES, fatrop
from .test_faults import hanging_heavy_top

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="guarded on Linux only")

#: a guard that never leaves a solve that ends
LOOSE = Guard(600.0, lambda: False, 10**9, 0.05)


def test_guarded_where_the_driver_runs() -> None:
    tr, fb = fatrop("so3_rest_to_rest", 4, "order6")
    assert fb.direct is not None and fb.direct.guardable and fb.guarded


@pytest.mark.parametrize("name,scheme", CASES, ids=[f"{n}-{s}" for n, s in CASES])
def test_a_guarded_solve_is_the_unguarded_solve(name: str, scheme: str) -> None:
    """From the first two guesses, there and back: the same iterations, status, point and
    multipliers as the same solve unguarded (the helper's)."""
    tr, fb = fatrop(name, 8, scheme)
    p = tr.pack()
    starts = [tr.point(g, p) for g in tr.guesses(p)[:2]]
    starts += starts[::-1]
    for x0 in starts:
        a, b = fb._solve_here((x0, p), LOOSE), fb._solve_here((x0, p))
        assert not isinstance(a, Stopped) and not isinstance(b, Stopped)
        assert (a.iterations, a.status, a.success) == (b.iterations, b.status, b.success)
        for x, y in ((a.x, b.x), (a.lam_g, b.lam_g), (a.lam_x, b.lam_x), (a.f, b.f)):
            np.testing.assert_array_equal(x, y)


def _arguments(fb, tr, guess: int = 0) -> tuple:
    p = tr.pack()
    a = fb.arguments(tr.point(tr.guesses(p)[guess], p), p)
    return a["x0"], a["p"], a["lbg"], a["ubg"], a["lbx"], a["ubx"]


def _same(one: tuple, other: tuple) -> None:
    assert one[1:] == other[1:]
    for key in one[0]:
        np.testing.assert_array_equal(one[0][key], other[0][key])


def test_a_stop_leaves_at_once_and_the_next_solve_is_a_new_solvers() -> None:
    """Asked at every evaluation (``every`` 0), a stop request leaves the solve at the first;
    the next solve from the same start equals a new solver's."""
    tr, fb = fatrop("cart_pole", 8, "order4")
    args = _arguments(fb, tr)
    asked = []
    left = fb.direct.solve(*args, guard=Guard(600.0, lambda: asked.append(1) or True, 20, 0.0))
    assert left == Stopped("stop") and len(asked) == 1
    fresh = FatropOcp(fb.form, fb.options["cache"], fb.direct.library, fb.options["fatrop"])
    _same(fb.direct.solve(*args, guard=LOOSE), fresh.solve(*args))


def test_an_exception_of_the_stop_request_is_raised_after_the_solve() -> None:
    """A second Ctrl-C raises KeyboardInterrupt in the stop request: it stops the solve and is
    raised once the solve has returned; the next solve runs."""
    tr, fb = fatrop("so3_rest_to_rest", 8, "order6")
    args = _arguments(fb, tr)

    def interrupted() -> bool:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        fb.direct.solve(*args, guard=Guard(600.0, interrupted, 20, 0.0))
    assert fb.direct.solve(*args, guard=LOOSE)[3] == 0


@pytest.mark.parametrize("in_thread", [False, True], ids=["main-thread", "other-thread"])
def test_the_timer_leaves_the_endless_inertia_correction(monkeypatch, in_thread: bool) -> None:
    """The heavy top's long way round: fatrop's inertia correction loops without calling back,
    so only the timer can leave it; it does, at the deadline, in the main thread or another.
    The solves before and after it agree (the process and the driver are sound)."""
    solver, guess = hanging_heavy_top(max_seconds=60.0)
    tr, fb = solver.transcription, solver.transcription.fatrop
    p = tr.pack()
    x0 = tr.point(guess, p)
    ok = tr.point(tr.guesses(p)[0], p)
    before = fb._solve_here((ok, p), LOOSE)
    out: list = []

    def hang() -> None:
        t0 = time.perf_counter()
        out.append(fb._solve_here((x0, p), Guard(0.5, lambda: False, 10**9, 3600.0)))
        out.append(time.perf_counter() - t0)

    if in_thread:
        worker = threading.Thread(target=hang)
        worker.start()
        worker.join(30)
        assert not worker.is_alive()
    else:
        hang()
    assert out[0] == Stopped("time") and 0.5 <= out[1] < 2.0
    after = fb._solve_here((ok, p), LOOSE)
    assert (after.iterations, after.status) == (before.iterations, before.status)
    np.testing.assert_array_equal(after.x, before.x)


def test_a_second_driver_guards_its_own_solves(tmp_path, monkeypatch) -> None:
    """A driver built again into another cache folder is another library, with its guard's
    state of its own (its own timer signal): its solves are guarded too, and so are the first
    driver's still."""
    from ocgroupoid.nlp.backends import fatrop_ocp
    tr, fb = fatrop("so3_rest_to_rest", 8, "order6")
    monkeypatch.setenv("OCGROUPOID_JIT_CACHE", str(tmp_path))
    fatrop_ocp._driver.cache_clear()
    try:
        tr2, fb2 = fatrop("so3_rest_to_rest", 8, "order6")
        assert fb2.direct._lib is not fb.direct._lib
        for t, b in ((tr2, fb2), (tr, fb)):
            p = t.pack()
            assert t.solve(t.guesses(p)[0], p).success
            assert b.guarded and b.direct.times is not None  # it ran here, guarded
    finally:
        fatrop_ocp._driver.cache_clear()
