"""Gauss–Newton Hessian for least-squares IPOPT problems (output error on samples)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import symid as si
from symid.engine.ipopt import GAUSS_NEWTON, ScaledIpopt
from symid.errors import OptionError
from symid.fit.timeseries.oe import EXACT_BUILD_RATE, OutputError


def _rosenbrock(hessian: str, jacobian=None) -> ScaledIpopt:
    t, q = ca.SX.sym("t", 2), ca.SX.sym("q", 0)
    r = ca.vertcat(10 * (t[1] - t[0] ** 2), 1 - t[0])
    J = ca.Function("J", [t, q], [ca.jacobian(r, t)]) if jacobian is None else jacobian
    return ScaledIpopt("rosenbrock", t, ca.sumsqr(r), lower=np.full(2, -np.inf), upper=np.full(2, np.inf),
                       max_iter=200, tol=1e-12, hessian=hessian, residual_jacobian=J)


def test_gauss_newton_reaches_the_least_squares_minimum():
    # Rosenbrock's function as ‖r‖², r = (10 (t2 − t1²), 1 − t1): its only minimum is (1, 1) with r = 0
    # (zero residual: Gauss–Newton converges there as fast as Newton)
    run = _rosenbrock(GAUSS_NEWTON).solve(np.array([-1.2, 1.0]))
    assert run.status == "Solve_Succeeded"
    np.testing.assert_allclose(run.z, [1.0, 1.0], rtol=1e-8)


def test_gauss_newton_needs_the_residual_jacobian():
    t = ca.SX.sym("t", 1)
    with pytest.raises(ValueError, match="residual's Jacobian"):
        ScaledIpopt("x", t, t[0] ** 2, lower=np.zeros(1), upper=np.ones(1), max_iter=10, tol=1e-8,
                    hessian=GAUSS_NEWTON)


@pytest.fixture(scope="module")
def oscillator():
    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    u = np.random.default_rng(3).standard_normal(400)
    truth = {"m": 2.0, "c": 0.8, "k": 50.0}
    return model, si.simulate_io(model, truth, u, dt=0.05), np.array([2.0, 0.8, 50.0])


def test_output_error_gauss_newton_reaches_the_truth(oscillator):
    model, io, truth = oscillator
    est = OutputError(model, io, hessian=GAUSS_NEWTON, solver="ipopt")
    out = est.run(truth * np.array([1.3, 0.7, 1.2]))
    assert out.success
    # noise-free samples of the model itself: the truth is the exact fit (simulate_io, zero-order hold as the fit)
    np.testing.assert_allclose(out.theta, truth, rtol=1e-7)


def test_gauss_newton_hessian_is_two_jtj_of_the_residual(oscillator):
    model, io, truth = oscillator
    est = OutputError(model, io, hessian=GAUSS_NEWTON, solver="ipopt")
    gaps = []
    for factor in (1.1, 1.01):
        theta = truth * factor
        q = est._balance(theta)
        s = est._squarings(theta, q)
        solver = est._solver(s)
        # one Jacobian function for the Hessian, built once (the costly part at n ≥ 5)
        assert solver.residual_jacobian is est._jacobian_function(s)
        J = np.asarray(solver.residual_jacobian(theta, q))
        # the covariance's Jacobian, by the sensitivity recursion in numpy, is the same matrix: two exact
        # derivatives of one discretisation (Taylor polynomial and scipy's Padé both at rounding level)
        _, J_numpy = est.jacobian(theta)
        np.testing.assert_allclose(J_numpy, J, rtol=0, atol=1e-10 * np.abs(J).max())
        v, qq, rr = est._symbolic(s)
        exact = np.asarray(ca.Function("H", [v, qq], [ca.hessian(ca.sumsqr(rr), v)[0]])(theta, q))
        gaps.append(np.linalg.norm(exact - 2 * J.T @ J) / np.linalg.norm(exact))
    # ∇²‖r‖² = 2 JᵀJ + 2 Σ rᵢ ∇²rᵢ: the Gauss–Newton Hessian misses the second term only, which is O(‖r‖) and
    # so O(θ − θ*) on noise-free data (measured: 0.119 at 10 % off, 0.0133 at 1 % off)
    assert gaps[0] < 0.2
    assert 5 < gaps[0] / gaps[1] < 20


def test_auto_hessian_is_exact_unless_its_build_would_take_a_quarter_of_the_time_limit(oscillator):
    model, io, truth = oscillator
    start = truth * 1.2
    probe = OutputError(model, io, solver="ipopt")
    q = probe._balance(start)
    s = probe._squarings(start, q)
    v, qq, r = probe._symbolic(s)
    size = ca.Function("size", [v, qq], [r]).n_nodes() * v.numel()
    predicted = EXACT_BUILD_RATE * size
    assert probe.options["hessian"] == "auto"
    assert probe._solver(s).hessian == "exact"  # no time limit: exact
    roomy = OutputError(model, io, time_limit=4.5 * predicted, solver="ipopt")
    assert roomy._solver(s).hessian == "exact"
    tight = OutputError(model, io, time_limit=3.5 * predicted, solver="ipopt")
    assert tight._solver(s).hessian == GAUSS_NEWTON
    out = tight.run(start)
    assert "Gauss–Newton Hessian (hessian='auto'" in out.message


def test_hessian_choices_are_named():
    m = si.parameters("m", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[1]], K=[[1]], B=[[1]], C=[[1]])
    io = si.simulate_io(model, {"m": 1.0}, np.ones(50), dt=0.1)
    with pytest.raises(OptionError, match="gauss-newton"):
        OutputError(model, io, hessian="newton")
