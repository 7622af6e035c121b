"""The Euler-Lagrange operator is derived, not typed in: compare with textbook equations."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from ocgroupoid.errors import ConfigError, DimensionError
from ocgroupoid.groupoid import Groupoid, LieGroupFactor, Pair, SphereAction
from ocgroupoid.model.mechanics import euler_lagrange, split
from ocgroupoid.model.problem import Problem


def test_rigid_body_gives_euler_equations() -> None:
    """EL(1/2 Omega . I Omega) = I dOmega/dt + Omega x I Omega."""
    G = Groupoid(LieGroupFactor())
    q, y, dy, I = ca.SX.sym("q", 0), ca.SX.sym("y", 3), ca.SX.sym("dy", 3), ca.SX.sym("I", 3)
    EL = ca.Function("EL", [y, dy, I], [euler_lagrange(G, 0.5 * ca.dot(y, I * y), q, y, dy)])
    rng = np.random.default_rng(0)
    for _ in range(5):
        w, dw, In = rng.normal(size=3), rng.normal(size=3), rng.uniform(0.5, 3, size=3)
        expected = In * dw + np.cross(w, In * w)
        assert np.allclose(np.array(EL(w, dw, In)).ravel(), expected, atol=1e-12)


def test_heavy_top_with_rotors_matches_problems_md() -> None:
    """dPi/dt = Pi x Omega + mgl Gamma x e3 and J_i (dOmega_i + ddtheta_i) = u_i."""
    G = Groupoid(SphereAction(), Pair(2, "theta", "dtheta"))
    q, y, dy = ca.SX.sym("q", 5), ca.SX.sym("y", 5), ca.SX.sym("dy", 5)
    Ib, J, mgl = ca.SX.sym("Ib", 3), ca.SX.sym("J", 2), ca.SX.sym("mgl")
    O, dth, Gam = y[:3], y[3:], q[:3]
    g1, g2 = Ib[0] + J[0], Ib[1] + J[1]
    l = 0.5 * (g1 * O[0] ** 2 + g2 * O[1] ** 2 + Ib[2] * O[2] ** 2 + J[0] * dth[0] ** 2
               + J[1] * dth[1] ** 2) + J[0] * O[0] * dth[0] + J[1] * O[1] * dth[1] - mgl * Gam[2]
    EL = ca.Function("EL", [q, y, dy, Ib, J, mgl], [euler_lagrange(G, l, q, y, dy)])
    rng = np.random.default_rng(1)
    Ibn, Jn, m = np.array([1.1, 1.2, 0.6]), np.array([0.1, 0.1]), 1.0
    for _ in range(5):
        Gn = rng.normal(size=3)
        Gn /= np.linalg.norm(Gn)
        Om, dOm, th, dth_, ddth = (rng.normal(size=n) for n in (3, 3, 2, 2, 2))
        Pi = np.array([(Ibn[0] + Jn[0]) * Om[0] + Jn[0] * dth_[0],
                       (Ibn[1] + Jn[1]) * Om[1] + Jn[1] * dth_[1], Ibn[2] * Om[2]])
        dPi = np.array([(Ibn[0] + Jn[0]) * dOm[0] + Jn[0] * ddth[0],
                        (Ibn[1] + Jn[1]) * dOm[1] + Jn[1] * ddth[1], Ibn[2] * dOm[2]])
        top = dPi - np.cross(Pi, Om) - m * np.cross(Gn, [0, 0, 1])
        rotors = Jn * (dOm[:2] + ddth)
        out = np.array(EL(np.r_[Gn, th], np.r_[Om, dth_], np.r_[dOm, ddth], Ibn, Jn, m)).ravel()
        assert np.allclose(out, np.r_[top, rotors], atol=1e-12)


def test_split_into_controls_and_constraints() -> None:
    G = Groupoid(LieGroupFactor())
    q, y, dy = ca.SX.sym("q", 0), ca.SX.sym("y", 3), ca.SX.sym("dy", 3)
    mech = split(G, 0.5 * ca.dot(y, y), q, y, dy, [0, 2], ca.diag(ca.DM([2.0, 4.0])))
    assert mech.actuated == (0, 2) and mech.unactuated == (1,)
    f = ca.Function("f", [y, dy], [mech.u, mech.phi])
    u, phi = f([1, 2, 3], [0.5, 0.5, 0.5])
    EL = np.array([0.5, 0.5, 0.5]) + np.cross([1, 2, 3], [1, 2, 3])
    assert np.allclose(np.array(u).ravel(), [EL[0] / 2, EL[2] / 4])
    assert np.allclose(np.array(phi).ravel(), [EL[1]])


def test_bad_mechanics_input_is_named() -> None:
    pb = Problem(LieGroupFactor())
    Om = pb.velocity("Omega")
    with pytest.raises(DimensionError, match="scalar"):
        pb.mechanics(Om, actuated="Omega")
    with pytest.raises(DimensionError, match="input matrix must be 3 x 3"):
        pb.mechanics(ca.dot(Om, Om), actuated="Omega", input_matrix=ca.DM.eye(2))
    with pytest.raises(ConfigError, match="no velocity called 'w'"):
        pb.mechanics(ca.dot(Om, Om), actuated="w")


def test_foreign_symbols_are_rejected() -> None:
    pb = Problem(LieGroupFactor())
    z = ca.SX.sym("z")
    with pytest.raises(ConfigError, match=r"the cost uses 'z', declared outside this problem"):
        pb.minimize(z**2)
