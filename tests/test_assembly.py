"""The assembled derivatives are the derivatives: gradient, Jacobian and Hessian of the
Lagrangian, scattered from the mapped stage functions, against CasADi's AD of f and g."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import ocgroupoid as og
from ocgroupoid.systems.heavy_top import heavy_top
from ocgroupoid.systems.plate_ball import plate_ball
from ocgroupoid.systems.rigid_body import rigid_body

from .test_api_general import minimum_acceleration
from .test_transcription import free_end_velocity, rolling


def reference(tr) -> ca.Function:
    """grad f, jac g and the upper triangle of the Hessian of the Lagrangian by CasADi's AD."""
    x, p = tr.nlp["x"], tr.nlp["p"]
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", tr.ng)
    f, g = tr.nlp["f"], tr.nlp["g"]
    H = ca.hessian(lam_f * f + ca.dot(lam_g, g), x)[0]
    return ca.Function("ref", [x, p, lam_f, lam_g], [ca.gradient(f, x), ca.jacobian(g, x),
                                                     ca.triu(H)])


@pytest.mark.parametrize("factory", [rigid_body, free_end_velocity, minimum_acceleration,
                                     rolling, heavy_top, plate_ball])
@pytest.mark.parametrize("N", [3, 24])
@pytest.mark.parametrize("scheme", og.nlp.SCHEME_NAMES)
def test_scattered_derivatives_equal_automatic_differentiation(factory, N: int,
                                                               scheme: str) -> None:
    problem = factory()
    tr = og.compile_problem(problem, N=N, scheme=scheme).transcription
    p = tr.pack()
    rng = np.random.default_rng(N)
    x = rng.normal(size=tr.nx) * 0.3
    lam_f, lam_g = 0.7, rng.normal(size=tr.ng)
    grad = tr.solver.get_function("nlp_grad_f")(x, p)[1]
    jac = tr.solver.get_function("nlp_jac_g")(x, p)[1]
    hess = tr.solver.get_function("nlp_hess_l")(x, p, lam_f, lam_g)
    ref = reference(tr)(x, p, lam_f, lam_g)
    for name, got, want in (("grad", grad, ref[0]), ("jac", jac, ref[1]), ("hess", hess, ref[2])):
        got, want = np.array(ca.DM(got)), np.array(ca.DM(want))
        scale = max(1.0, float(np.max(np.abs(want))))
        assert np.max(np.abs(got - want)) <= 1e-12 * scale, name
    # the declared patterns hold every structural nonzero of the AD result
    assert set(zip(*ca.DM(ref[1]).sparsity().get_triplet())) <= set(
        zip(*jac.sparsity().get_triplet()))


def test_sums_into_entries_every_stage_touches() -> None:
    """The scatter's row sums equal numpy's, for targets hit a few times (the padded gather)
    and one hit by 2000 sources (a free horizon's Hessian entry: the sparse product)."""
    from ocgroupoid.nlp.assembly import DENSE_ROW, _sum_into
    rng = np.random.default_rng(3)
    n_target, n_src = 40, 2400
    target = np.concatenate([rng.integers(1, n_target, 400), np.zeros(2000, dtype=np.int64)])
    source = rng.permutation(n_src)
    values = rng.standard_normal(n_src)
    x = ca.MX.sym("x", n_src)
    out = ca.Function("f", [x], [_sum_into(x, source, target, n_target)])
    expected = np.bincount(target, weights=values[source], minlength=n_target)
    assert np.bincount(target).max() > DENSE_ROW  # both paths are taken
    np.testing.assert_allclose(np.array(out(values)).ravel(), expected, rtol=1e-12,
                               atol=1e-12)


@pytest.mark.parametrize("factory", [rigid_body, rolling, heavy_top, plate_ball])
@pytest.mark.parametrize("scheme", og.nlp.SCHEME_NAMES)
def test_whole_lagrangian_equals_automatic_differentiation(factory, scheme: str) -> None:
    """fatrop's signature (``whole``): the gradient of the Lagrangian and its whole symmetric
    Hessian, summed from the stages, equal CasADi's AD of the plain graph."""
    from ocgroupoid.nlp.assembly import assemble
    problem = factory()
    tr = og.compile_problem(problem, N=5, scheme=scheme).transcription
    x, p = tr.nlp["x"], tr.nlp["p"]
    fns = assemble(tr.blocks, ca.MX.sym("x", tr.nx), ca.MX.sym("p", tr.np), whole=True)
    assert fns["nlp_hess_l"].name_out() == ["grad_gamma_x", "hess_gamma_x_x"]
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", tr.ng)
    H, grad_l = ca.hessian(lam_f * tr.nlp["f"] + ca.dot(lam_g, tr.nlp["g"]), x)
    ref = ca.Function("ref", [x, p, lam_f, lam_g], [grad_l, H])
    rng = np.random.default_rng(5)
    point = (rng.normal(size=tr.nx) * 0.3, tr.pack(), 0.7, rng.normal(size=tr.ng))
    got, want = fns["nlp_hess_l"](*point), ref(*point)
    for name, a, b in zip(("gradient", "Hessian"), got, want):
        a, b = np.array(ca.DM(a)), np.array(ca.DM(b))
        assert np.max(np.abs(a - b)) <= 1e-12 * max(1.0, float(np.max(np.abs(b)))), name
    np.testing.assert_array_equal(np.array(ca.DM(got[1])), np.array(ca.DM(got[1])).T)
