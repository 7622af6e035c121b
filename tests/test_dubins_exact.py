"""The Dubins oracle (:mod:`tests.dubins_exact`) checked against itself and against a search
that knows no tangent: every word it returns lands on the goal (by the exact arc and line
formulas and by solve_ivp), and a dense search over the first two segments of each word,
refined by Newton, finds no path of that word shorter than the closed form's.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, strategies as st
from scipy.optimize import root

from .dubins_exact import (
    CASES,
    TURN,
    WORDS,
    Pose,
    centre,
    controls,
    drive,
    integrate,
    integrate_numerically,
    shortest,
    turn_rate,
    words,
)

ORIGIN: Pose = (0.0, 0.0, 0.0)
TWO_PI = 2.0 * np.pi

poses = st.tuples(st.floats(-5.0, 5.0), st.floats(-5.0, 5.0), st.floats(-np.pi, np.pi))


def miss(reached: np.ndarray, goal: Pose) -> float:
    """The largest of |Δx|, |Δy| and the heading difference wrapped to (-π, π]."""
    dth = np.angle(np.exp(1j * (reached[2] - goal[2])))
    return float(max(abs(reached[0] - goal[0]), abs(reached[1] - goal[1]), abs(dth)))


def searched(start: Pose, goal: Pose, word: str, r: float = 1.0, seeds: int = 16
             ) -> list[float]:
    """The lengths of every path of ``word`` from start to goal found without the tangent
    geometry: the first two segments (arc angles in [0, 2π), a straight in [0, 2 D + 8 r])
    solve ``centre(pose after them, s3) = centre(goal, s3)`` (the last arc then reaches the
    goal's circle at the goal's heading), by Newton from a ``seeds x seeds`` grid; the last
    arc is the remaining turn."""
    s3 = TURN[word[2]]
    target = centre(goal, s3, r)
    reach = 2.0 * np.hypot(goal[0] - start[0], goal[1] - start[1]) + 8.0 * r

    def lengths(z: np.ndarray) -> tuple[float, float]:
        return tuple(r * np.mod(v, TWO_PI) if TURN[c] else v for v, c in zip(z, word[:2]))

    def after_two(z: np.ndarray) -> Pose:
        a, b = lengths(z)
        return drive(drive(start, word[0], a, r), word[1], b, r)

    spans = [np.linspace(0.0, reach if c == "S" else TWO_PI, seeds, endpoint=False)
             for c in word[:2]]
    found = []
    for z0 in np.stack(np.meshgrid(*spans), -1).reshape(-1, 2):
        sol = root(lambda z: centre(after_two(z), s3, r) - target, z0, method="hybr",
                   options={"xtol": 1e-13})
        if not sol.success or np.max(np.abs(sol.fun)) > 1e-10:
            continue
        a, b = lengths(sol.x)
        if b < -1e-12:  # a straight driven backwards
            continue
        last = r * np.mod(s3 * (goal[2] - after_two(sol.x)[2]), TWO_PI)
        found.append(a + b + last)
    return found


# ------------------------------------------------------------------ every word lands


@given(poses, poses)
def test_every_word_lands_on_the_goal(start: Pose, goal: Pose) -> None:
    for word, seg in words(start, goal).items():
        if seg is None:
            continue
        assert min(seg) >= 0.0, (word, seg)
        assert miss(integrate(start, word, seg)[-1], goal) <= 1e-9, (word, seg)
        times, _ = controls(word, seg)
        reached = integrate_numerically(start, turn_rate(word, seg), times)
        assert miss(reached, goal) <= 1e-8, (word, seg, reached)


@given(poses, poses)
def test_the_shortest_word_is_no_longer_than_any_other(start: Pose, goal: Pose) -> None:
    word, length, seg = shortest(start, goal)
    assert length == pytest.approx(sum(seg), abs=1e-12)
    assert length >= np.hypot(goal[0] - start[0], goal[1] - start[1]) - 1e-12
    for w, other in words(start, goal).items():
        if other is not None:
            assert length <= sum(other) + 1e-12, (word, w)


@given(poses, poses)
def test_mirrored_poses_swap_left_and_right(start: Pose, goal: Pose) -> None:
    """``(x, y, θ) -> (x, -y, -θ)`` maps every path onto one of the mirrored word."""
    mirror = {"L": "R", "R": "L", "S": "S"}
    flipped = words(*((p[0], -p[1], -p[2]) for p in (start, goal)))
    for word, seg in words(start, goal).items():
        twin = flipped["".join(mirror[c] for c in word)]
        assert (seg is None) == (twin is None), word
        if seg is not None:
            assert sum(seg) == pytest.approx(sum(twin), abs=1e-9), word


def test_the_turning_radius_scales_every_length() -> None:
    start, goal = (0.3, -1.0, 0.4), (2.0, 1.5, -2.0)
    unit, scaled = words(start, goal), words((0.6, -2.0, 0.4), (4.0, 3.0, -2.0), r=2.0)
    for word in WORDS:
        assert (unit[word] is None) == (scaled[word] is None), word
        if unit[word] is not None:
            np.testing.assert_allclose(scaled[word], 2.0 * np.array(unit[word]), atol=1e-12)
            seg = scaled[word]
            assert miss(integrate((0.6, -2.0, 0.4), word, seg, r=2.0)[-1],
                        (4.0, 3.0, -2.0)) <= 1e-9


# ------------------------------------------------------------------ minimality


@pytest.mark.parametrize("start, goal", [
    (ORIGIN, (4.0, 4.0, np.pi / 2)), (ORIGIN, (1.0, 1.0, np.pi)), (ORIGIN, (-0.5, 0.5, 0.0)),
    ((1.0, -2.0, 2.5), (-1.5, 0.5, -0.7)), ((0.0, 0.0, 1.0), (0.5, 1.2, -2.0))],
    ids=["LSL", "RLR", "behind", "far", "near"])
def test_a_search_over_the_first_two_segments_finds_nothing_shorter(start: Pose, goal: Pose
                                                                    ) -> None:
    """Per word, the shortest path found by the search is the closed form's (a CSC word has
    one path, a CCC word up to two: the closed form keeps the shorter); so ``shortest`` is
    the least of all six."""
    exact = words(start, goal)
    best = np.inf
    for word in WORDS:
        found = searched(start, goal, word)
        if exact[word] is None:
            assert not found, (word, found)
            continue
        assert min(found) == pytest.approx(sum(exact[word]), abs=1e-9), word
        assert len(set(np.round(found, 6))) <= (1 if word[1] == "S" else 2), (word, found)
        best = min(best, min(found))
    assert shortest(start, goal)[1] == pytest.approx(best, abs=1e-9)


# ------------------------------------------------------------------ the named cases


@pytest.mark.parametrize("word", list(CASES))
def test_each_case_has_its_word_as_the_shortest(word: str) -> None:
    goal, length = CASES[word]
    found, total, seg = shortest(ORIGIN, goal)
    assert found == word and total == pytest.approx(length, abs=1e-12)
    if word[1] != "S":
        assert seg[1] > np.pi, seg  # Dubins: an optimal CCC's middle arc exceeds π r
    others = sorted(sum(s) for w, s in words(ORIGIN, goal).items() if s and w != word)
    assert others[0] >= length + 2.0, others  # no near tie for a solver to fall into


def test_the_lsl_case_is_the_length_issue_31_quotes() -> None:
    assert CASES["LSL"][1] == pytest.approx(np.pi / 2 + 3 * np.sqrt(2), abs=1e-14)
    assert round(CASES["LSL"][1], 4) == 5.8134
    assert {w for w in CASES} == set(WORDS)


@pytest.mark.parametrize("word", list(CASES))
def test_the_turn_rate_drives_each_case_onto_its_goal(word: str) -> None:
    """ω(t) integrated over [0, T] in one go, its switches unannounced to solve_ivp."""
    goal, length = CASES[word]
    seg = shortest(ORIGIN, goal)[2]
    times, rates = controls(word, seg)
    assert times[0] == 0.0 and times[-1] == pytest.approx(length, abs=1e-12)
    assert np.all(np.diff(times) >= 0.0)
    assert list(rates) == [TURN[c] for c in word]
    omega = turn_rate(word, seg)
    for k, rate in enumerate(rates):
        if times[k + 1] > times[k]:
            assert omega(times[k]) == rate == omega(np.nextafter(times[k + 1], 0.0))
    reached = integrate_numerically(ORIGIN, omega, times[[0, -1]], tol=1e-11)
    assert miss(reached, goal) <= 1e-7, reached


def test_integrate_samples_the_path_at_unit_speed() -> None:
    goal, length = CASES["RLR"]
    word, _, seg = shortest(ORIGIN, goal)
    path = integrate(ORIGIN, word, seg, steps=200)
    assert path.shape == (601, 3)
    chords = np.hypot(*np.diff(path[:, :2], axis=0).T)
    assert chords.sum() == pytest.approx(length, rel=1e-4)  # chords of arcs: slightly short
    assert chords.sum() <= length


@pytest.mark.parametrize("start", [ORIGIN, (1.1, 2.2, 0.3), (-1.0, 0.5, -3.0)])
def test_a_goal_straight_ahead_is_reached_by_driving_straight(start: Pose) -> None:
    """No full turn from rounding: the arcs of a straight drive are 0, not 2π."""
    x, y, th = start
    word, length, seg = shortest(start, (x + 5 * np.cos(th), y + 5 * np.sin(th), th))
    assert word[1] == "S" and length == pytest.approx(5.0, abs=1e-12), (word, seg)
