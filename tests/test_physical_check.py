"""Estimates the model's declarations rule out are never a success (symid.fit.success.physical_check),
and method 'ls' honours declared positivity."""

from __future__ import annotations

import numpy as np

import symid as si
from symid.fit.success import physical_check

W = np.linspace(0.5, 2.0, 20)


def _one_dof():
    m, c, k = si.parameters("m c k", positive=True)
    return si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])


def test_negative_declared_parameter_is_named():
    assert physical_check(_one_dof(), [2.0, 0.5, 3.0]) is None
    assert physical_check(_one_dof(), [2.0, -0.5, 3.0]) == "parameters declared positive are negative: c = -0.5"
    # rounding at an active bound is not a violation: −1e-12 against |θ| = 3 is below 1e-9 × 3
    assert physical_check(_one_dof(), [2.0, -1e-12, 3.0]) is None


def test_negative_damping_with_positive_parameters():
    m, c1, c2, k = si.parameters("m c1 c2 k", positive=True)
    model = si.SecondOrderModel(M=[[m, 0], [0, m]], V=[[c1, c2], [c2, c1]], K=[[k, 0], [0, k]],
                                B=[[1], [0]], C=[[1, 0]])
    assert physical_check(model, [1.0, 0.3, 0.1, 2.0]) is None
    assert physical_check(model, [1.0, 0.1, 0.3, 2.0]).startswith("negative damping: V(θ) has eigenvalue -0.2")


def test_rigid_body_mode_is_not_unstable():
    m, c = si.parameters("m c", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[0]], B=[[1]], C=[[1]])  # EMPS-like: an integrator
    assert physical_check(model, [95.0, 200.0]) is None


def test_unstable_poles_only_when_every_parameter_is_declared_positive():
    a, b = si.parameters("a b", positive=True)
    model = si.StateSpaceModel(A=[[-a, b], [b, -a]], B=[[1], [0]], C=[[1, 0]])
    assert physical_check(model, [2.0, 1.0]) is None
    assert "unstable: pole 1" in physical_check(model, [2.0, 3.0])  # eigenvalues −a ± b
    g = si.parameters("g")  # a sign-free parameter: the model may be meant to be unstable
    free = si.StateSpaceModel(A=[[-a, b], [b, -a]], B=[[g], [0]], C=[[1, 0]])
    assert physical_check(free, [2.0, 3.0, 1.0]) is None


def test_exact_fit_with_negative_damping_is_not_a_success_for_ipopt():
    model = _one_dof()
    frf = si.simulate_frf(model, [2.0, -0.3, 3.0], W)  # data of an unstable (negatively damped) system
    res = si.identify(model, frf, method="ipopt", x0=[2.0, -0.3, 3.0], positivity=False, identifiability_check=False)
    assert res.cost <= 1e-20  # it reproduces the data ...
    assert not res.success  # ... but contradicts the declaration c > 0
    assert "not physical: parameters declared positive are negative: c" in res.fit


def test_ls_honours_positivity_with_a_bounded_least_squares():
    model = _one_dof()
    frf = si.simulate_frf(model, [2.0, -0.3, 3.0], W)
    res = si.identify(model, frf, method="ls", identifiability_check=False)
    assert res.theta["c"] == 0.0 and res.theta["m"] > 0 and res.theta["k"] > 0
    assert "at the bound: c" in res.message
    assert not res.success and res.cost > 1  # the bound costs the fit: reported as a failure
    free = si.identify(model, frf, method="ls", positivity=False, identifiability_check=False)
    np.testing.assert_allclose(list(free.theta.values()), [2.0, -0.3, 3.0], rtol=1e-9)
    assert not free.success and "not physical" in free.fit


def test_ls_keeps_exact_and_noisy_solutions_that_are_positive():
    model = _one_dof()
    exact = si.identify(model, si.simulate_frf(model, [2.0, 0.3, 3.0], W), method="ls", identifiability_check=False)
    np.testing.assert_allclose(list(exact.theta.values()), [2.0, 0.3, 3.0], rtol=1e-10)
    assert exact.success and "bounded" not in exact.message
    noisy = si.identify(model, si.simulate_frf(model, [2.0, 0.3, 3.0], W, noise=0.01, seed=1), method="ls",
                        identifiability_check=False)
    assert noisy.success


def test_ls_never_reports_success_at_a_large_misfit():
    # data of two modes fitted by a one-mode model: the linear least squares returns its best, which does not fit
    m1, m2, c, k1, k2 = 1.0, 0.5, 0.05, 2.0, 1.0
    two = si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[2 * c, -c], [-c, c]], K=[[k1 + k2, -k2], [-k2, k2]],
                              B=[[1], [0]], C=[[1, 0]], parameters=[])
    frf = si.simulate_frf(two, [], np.linspace(0.3, 3.0, 60))
    for floor in (None, 1e-4):
        res = si.identify(_one_dof(), frf, method="ls", noise_floor=floor, identifiability_check=False)
        assert res.cost > 0.1 and not res.success, res.fit
