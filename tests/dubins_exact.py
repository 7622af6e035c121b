"""The Dubins car in closed form: an exact oracle for the tests, nothing of ocgroupoid used.

The car moves at unit speed, ``x' = cos θ, y' = sin θ, θ' = ω``, with ``|ω| <= 1/r``.
Dubins (1957): the shortest path between two poses is one of six words of three segments,
``LSL, RSR, LSR, RSL`` (two arcs joined by a tangent) and ``RLR, LRL`` (three arcs, the
middle one longer than π r), each arc on a circle of radius r. Written after the geometry
of Shkel & Lumelsky (2001, "Classification of the Dubins set"), through circle centres:

    turning s = +1 (L, anticlockwise) or -1 (R) from the pose (x, y, θ):
    centre       c = (x - s r sin θ, y + s r cos θ),
    on the circle p(ψ) = c + s r (sin ψ, -cos ψ) at heading ψ,
    an arc of angle φ >= 0 turns the heading by s φ.

CSC (circles c1 of turn s1, c2 of turn s2, ``δ = (s1 - s2) r``): the tangent of heading ψ
and length ℓ satisfies ``c2 - c1 = ℓ (cos ψ, sin ψ) + δ (sin ψ, -cos ψ)``, hence
``ℓ = sqrt(D² - δ²)`` (none when ``D = |c2 - c1| < |δ|``) and ``ψ = atan2(c2 - c1) +
atan2(δ, ℓ)``. CCC (s1 = s2 = s): a middle circle of turn -s touching both, its centre c3 at
2r from c1 and from c2 (none when D > 4r); of the two such centres the word takes the one
that gives the shorter path (when a CCC word is the shortest path, that is Dubins' one, its
middle arc longer than π r).

Segment lengths are arc angles times r for L and R, the length for S; arc angles lie in
[0, 2π). ``CASES``: six goal poses from the origin, one per word, with their lengths.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from scipy.integrate import solve_ivp

WORDS = ("LSL", "RSR", "LSR", "RSL", "RLR", "LRL")
TURN = {"L": 1.0, "S": 0.0, "R": -1.0}  # s: the sign of ω on a segment
TWO_PI = 2.0 * np.pi

Pose = tuple[float, float, float]
Segments = tuple[float, float, float]


def _angle(a: float) -> float:
    """``a`` reduced to [0, 2π); within 1e-12 of 2π it is 0 (rounding, not a full turn)."""
    m = float(np.mod(a, TWO_PI))
    return 0.0 if m > TWO_PI - 1e-12 else m


def centre(pose: Pose, s: float, r: float) -> np.ndarray:
    """The centre ``(x - s r sin θ, y + s r cos θ)`` of the circle of turn s through a pose."""
    x, y, th = pose
    return np.array([x - s * r * np.sin(th), y + s * r * np.cos(th)])


def heading_at(p: np.ndarray, c: np.ndarray, s: float, r: float) -> float:
    """The heading ψ at the point p of the circle (centre c, turn s): ``(p - c) / (s r) =
    (sin ψ, -cos ψ)``."""
    u = (p - c) / (s * r)
    return float(np.arctan2(u[0], -u[1]))


def _csc(start: Pose, goal: Pose, word: str, r: float) -> Segments | None:
    """The tangent word ``word`` (module docstring, CSC), None when the circles overlap."""
    s1, s2 = TURN[word[0]], TURN[word[2]]
    c1, c2 = centre(start, s1, r), centre(goal, s2, r)
    delta = (s1 - s2) * r
    d = c2 - c1
    D2 = float(d @ d)
    if D2 < delta**2:
        return None
    ell = float(np.sqrt(D2 - delta**2))
    psi = float(np.arctan2(d[1], d[0]) + np.arctan2(delta, ell))
    return (r * _angle(s1 * (psi - start[2])), ell, r * _angle(s2 * (goal[2] - psi)))


def _ccc(start: Pose, goal: Pose, word: str, r: float) -> Segments | None:
    """The three-arc word ``word`` (module docstring, CCC), None when the end circles are
    more than 4r apart; of the two middle circles, the shorter path."""
    s = TURN[word[0]]
    c1, c2 = centre(start, s, r), centre(goal, s, r)
    d = c2 - c1
    D = float(np.hypot(*d))
    if D > 4.0 * r:
        return None
    normal = np.array([-d[1], d[0]]) / D if D > 0 else np.array([0.0, 1.0])
    h = np.sqrt(max(4.0 * r**2 - (D / 2.0) ** 2, 0.0))
    best: Segments | None = None
    for side in (1.0, -1.0):
        c3 = (c1 + c2) / 2.0 + side * h * normal
        psi1 = heading_at((c1 + c3) / 2.0, c1, s, r)
        psi2 = heading_at((c3 + c2) / 2.0, c2, s, r)
        seg = (r * _angle(s * (psi1 - start[2])), r * _angle(-s * (psi2 - psi1)),
               r * _angle(s * (goal[2] - psi2)))
        if best is None or sum(seg) < sum(best):
            best = seg
    return best


def words(start: Pose, goal: Pose, r: float = 1.0) -> dict[str, Segments | None]:
    """The three segment lengths of each of the six words from ``start`` to ``goal`` (poses
    (x, y, θ)), None where the word does not exist."""
    return {w: (_csc if w[1] == "S" else _ccc)(start, goal, w, r) for w in WORDS}


def shortest(start: Pose, goal: Pose, r: float = 1.0) -> tuple[str, float, Segments]:
    """Dubins' shortest path: the word of least total length, that length, its segments."""
    found = {w: seg for w, seg in words(start, goal, r).items() if seg is not None}
    word = min(found, key=lambda w: sum(found[w]))
    return word, float(sum(found[word])), found[word]


def drive(pose: Pose, letter: str, length: float, r: float = 1.0) -> Pose:
    """The pose after one segment of the given length: ``θ' = θ + s φ``, ``x' = x + s r (sin
    θ' - sin θ)``, ``y' = y - s r (cos θ' - cos θ)`` for an arc of angle ``φ = length / r``;
    ``x' = x + ℓ cos θ``, ``y' = y + ℓ sin θ`` for a straight of length ℓ."""
    x, y, th = pose
    s = TURN[letter]
    if s == 0.0:
        return (x + length * np.cos(th), y + length * np.sin(th), th)
    th2 = th + s * length / r
    return (x + s * r * (np.sin(th2) - np.sin(th)), y - s * r * (np.cos(th2) - np.cos(th)),
            th2)


def integrate(start: Pose, word: str, segments: Segments, r: float = 1.0, steps: int = 1
              ) -> np.ndarray:
    """The poses along the word by the exact formulas of :func:`drive`, ``steps`` equal parts
    per segment: ``(3 steps + 1) x 3``, the start first, the pose reached last (θ not
    wrapped)."""
    poses = [tuple(map(float, start))]
    for letter, length in zip(word, segments):
        origin = poses[-1]
        poses += [drive(origin, letter, length * k / steps, r) for k in range(1, steps + 1)]
    return np.array(poses)


def controls(word: str, segments: Segments, r: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """The turn rate of the word: switch times ``[0, t1, t2, T]`` (unit speed: the cumulated
    segment lengths; a segment of zero length gives two equal times) and the rates ``ω_k =
    s_k / r`` in {1/r, 0, -1/r} that hold on ``[t_k, t_k+1)``."""
    times = np.concatenate([[0.0], np.cumsum(segments)])
    return times, np.array([TURN[letter] / r for letter in word])


def turn_rate(word: str, segments: Segments, r: float = 1.0) -> Callable[[float], float]:
    """ω(t) of the word, piecewise constant (:func:`controls`), the last rate held beyond T."""
    times, rates = controls(word, segments, r)
    return lambda t: float(rates[min(int(np.searchsorted(times[1:], t, side="right")), 2)])


def integrate_numerically(start: Pose, omega: Callable[[float], float], times: np.ndarray,
                          tol: float = 1e-11) -> np.ndarray:
    """The pose reached at ``times[-1]`` by integrating ``x' = cos θ, y' = sin θ, θ' = ω(t)``
    with scipy's ``solve_ivp`` (DOP853), interval by interval of ``times`` (breakpoints: no
    step straddles one; on ``[a, b]`` ω is read at ``t < b``, its value before a switch at b).
    A word: ``integrate_numerically(start, turn_rate(word, seg), controls(word, seg)[0])``."""
    pose = np.array(start, dtype=float)
    for a, b in zip(times[:-1], times[1:]):
        if b > a:
            last = np.nextafter(b, a)
            sol = solve_ivp(lambda t, z: [np.cos(z[2]), np.sin(z[2]),
                                          omega(min(t, last))],  # noqa: B023 (called here)
                            (a, b), pose, method="DOP853", rtol=tol, atol=tol)
            pose = sol.y[:, -1]
    return pose


# Six goal poses from the origin (0, 0, 0), r = 1, one per word: (goal, the shortest length),
# each the word's by a margin of at least 2 (LSL: π/2 + 3√2, the number issue 31 quotes).
CASES: dict[str, tuple[Pose, float]] = {
    "LSL": ((4.0, 4.0, np.pi / 2), 5.813437013914181),
    "RSR": ((4.0, -4.0, -np.pi / 2), 5.813437013914181),
    "LSR": ((4.0, 2.0, -np.pi / 2), 6.033225584375924),
    "RSL": ((4.0, -2.0, np.pi / 2), 6.033225584375924),
    "RLR": ((1.0, 1.0, np.pi), 5.777824796895429),
    "LRL": ((1.0, -1.0, np.pi), 5.777824796895429),
}
