"""Grey boxes from black boxes and I/O records: thesis ch. 6 (state space) and ch. 7 (second order).

Fast tests only; the thesis examples (e-nose, over-parameterised e-nose, 3-D mass-spring-
damper) are reproduced in tests/test_similarity_thesis.py (slow) and
benchmarks/similarity_thesis.py.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import symid as si
from symid.fit.compare import relative_parameter_error
from symid.fit.registry import prepare
from symid.fit.similarity.data import similarity_data
from symid.fit.similarity.objective import SimilarityMisfit
from symid.fit.similarity.start import initial_point, least_squares_theta, least_squares_transform
from symid.fit.starts import make_starts

T_SMALL = np.array([[1.0, 0.4], [-0.3, 0.8]])  # an arbitrary invertible basis change


def small_model():
    """A 2-state SISO structure with 3 unknowns (3 ≤ n(p + m) = 4), known C."""
    a, b, c = si.parameters("a b c")
    model = si.StateSpaceModel(A=[[0, 1], [a, b]], B=[[0], [c]], C=[[1, 0]])
    return model, {"a": -2.0, "b": -0.5, "c": 1.5}


def transformed(model, truth, T):
    A, B, C, D = model.state_space(truth)
    Ti = np.linalg.inv(T)
    return si.BlackBox(T @ A @ Ti, T @ B, C @ Ti, D)


def two_dof(B, C, output="position"):
    """Thesis (4-19)/(4-21) with chosen actuators and sensors."""
    m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    return si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]], K=[[k1 + k2, -k2], [-k2, k2]],
                               B=B, C=C, output=output)


TRUTH_2DOF = {"m1": 1.0, "m2": 2.0, "c1": 0.1, "c2": 0.3, "k1": 2.0, "k2": 1.0}  # thesis (4-20), m2 = 2


# -- the similarity misfit (C-1) and its pieces ------------------------------------------------

def test_gradients_c12_c15_match_finite_differences():
    entry = si.load_model("enose")
    F = SimilarityMisfit(entry.model.maps, entry.data())
    z = np.random.default_rng(0).standard_normal(6 + 9)
    _, g = F.value_and_grad(z)
    h = 1e-6
    fd = np.array([(F.value_and_grad(z + h * e)[0] - F.value_and_grad(z - h * e)[0]) / (2 * h) for e in np.eye(15)])
    np.testing.assert_allclose(g, fd, rtol=1e-6, atol=1e-9 * np.abs(g).max())


def test_least_squares_steps_recover_the_truth():
    """(C-7) and (C-8) are exact: at the true θ the LS transform is the true T, and back."""
    model, truth = small_model()
    bb = transformed(model, truth, T_SMALL)
    theta = model.theta_vector(truth)
    # T maps the black box to the model: T𝔸 = A T with 𝔸 = T_SMALL A T_SMALL⁻¹, so T = T_SMALL⁻¹
    T = least_squares_transform(model.maps, bb, theta)
    np.testing.assert_allclose(T, np.linalg.inv(T_SMALL), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(least_squares_theta(model.maps, bb, T), theta, rtol=1e-10)
    assert SimilarityMisfit(model.maps, bb).value(theta, T) < 1e-25


def test_starts_are_seeded_and_shared():
    entry = si.load_model("enose")
    maps, bb = entry.model.maps, entry.data()
    x0 = np.arange(6.0)
    a, b = initial_point("random", x0, 3, maps, bb), initial_point("random", x0.copy(), 3, maps, bb)
    for u, v in zip(a, b, strict=True):
        np.testing.assert_array_equal(u, v)
    c = initial_point("random", x0, 4, maps, bb)
    assert not np.allclose(a[1], c[1])


# -- identify / compare for state-space models ---------------------------------------------------

@pytest.mark.parametrize("method", ["scr", "als", "gb", "ipopt"])
def test_every_method_recovers_the_small_model(method):
    model, truth = small_model()
    bb = transformed(model, truth, T_SMALL)
    # SCR: from seed 0's four starts, three converge in ≤ 14 iterations (the zero start does not)
    opts = {"backend": "cvxpy", "weights": 1.0, "max_iter": 40} if method == "scr" else {}
    res = si.identify(model, bb, method=method, starts=4, seed=0, **opts)
    assert res.method == method
    # ALS stops on a relative step of 1e-6 (thesis (6-31)) while still creeping: 6e-6 measured
    tol = 1e-4 if method == "als" else 1e-6
    assert relative_parameter_error(res.theta_vector, model.theta_vector(truth)) < tol
    assert res.cost < tol**2


def test_scr_returns_an_invertible_transform():
    model, truth = small_model()
    bb = transformed(model, truth, T_SMALL)
    solver = prepare(model, bb, "scr", {"backend": "cvxpy", "weights": 1.0, "max_iter": 40})
    sol = solver.solve(make_starts(model, 4, 0)[1])  # a start that converges (see above)
    T, S = solver.transform(sol, original=True)  # the black box as given, not its balanced form
    np.testing.assert_allclose(T @ S, np.eye(2), atol=1e-7)
    np.testing.assert_allclose(T, np.linalg.inv(T_SMALL), rtol=1e-6, atol=1e-7)


def test_compare_runs_the_four_methods_from_identical_starts():
    model, truth = small_model()
    bb = transformed(model, truth, T_SMALL)
    cmp = si.compare(model, bb, methods=("scr", "als", "gb", "ipopt"), starts=4, seed=0, truth=truth,
                     options={"scr": {"backend": "cvxpy", "weights": 1.0, "max_iter": 40}})
    starts = [np.array([o.start for o in s.result.starts]) for s in cmp.stats]
    for s in starts[1:]:
        np.testing.assert_array_equal(s, starts[0])
    assert cmp["ipopt"].n_success >= 1 and cmp["scr"].n_success >= 1
    assert "best param. error" in cmp.table() and "largest relative parameter error" in cmp.table()


def test_polish_uses_the_similarity_ipopt():
    model, truth = small_model()
    bb = transformed(model, truth, T_SMALL)
    res = si.identify(model, bb, method="scr", starts=1, backend="cvxpy", weights=1.0, max_iter=3, polish=True)
    assert res.polished is not None
    assert relative_parameter_error(res.polished.theta_vector, model.theta_vector(truth)) < 1e-8


def test_io_records_go_through_n4sid_and_d2c():
    model, truth = small_model()
    u = np.random.default_rng(0).standard_normal(400)
    io = si.simulate_io(model, truth, u, dt=0.05)
    res = si.identify(model, io, method="ipopt", starts=3, seed=0)
    assert relative_parameter_error(res.theta_vector, model.theta_vector(truth)) < 1e-6
    assert res.options["black_box"] == "io"


def test_implied_equalities_are_dropped_when_an_estimated_black_box_contradicts_them():
    """With 0.1 % output noise the N4SID black box has ℂ𝔹 ≠ 0, which T𝔹 = B and ℂ = C T would contradict."""
    model, truth = small_model()
    u = np.random.default_rng(0).standard_normal(2000)
    exact = prepare(model, si.simulate_io(model, truth, u, dt=0.05), "scr", {})
    assert exact.options["implied"] is True
    noisy = prepare(model, si.simulate_io(model, truth, u, dt=0.05, noise=1e-3, seed=1), "scr", {})
    assert noisy.options["implied"].startswith("dropped")


# -- second-order models -----------------------------------------------------------------------

@pytest.mark.parametrize("output", ["position", "velocity"])
@pytest.mark.parametrize(("B", "C", "case"), [
    ([[1, 0], [0, 1]], [[1, 0]], "actuators"),          # thesis (7-13)–(7-16): F invertible
    ([[1], [0]], [[1, 0], [0, 1]], "sensors"),           # thesis (7-12): H invertible
    ([[1, 0.5], [0.2, 1]], [[1, 1]], "actuators"),
    ([[1], [0.3]], [[1, 0], [1, 1], [0, 2]], "sensors"),  # more sensors than DOF: H⁺
    ([[1, 0, 1], [0, 1, 1]], [[0, 1]], "actuators"),      # more actuators than DOF: F⁺
])
def test_second_order_linear_special_cases_are_exact(B, C, case, output):
    model = two_dof(B, C, output)
    bb = transformed(model, TRUTH_2DOF, np.random.default_rng(3).standard_normal((4, 4)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", si.IdentifiabilityWarning)
        res = si.identify(model, bb, method="scr")
    assert res.method == "ls" and res.options["case"] == case
    np.testing.assert_allclose(res.theta_vector, model.theta_vector(TRUTH_2DOF), rtol=1e-9)


def test_second_order_from_io_records_full_sensors():
    model = two_dof([[1], [0]], [[1, 0], [0, 1]])
    u = np.random.default_rng(1).standard_normal(3000)
    io = si.simulate_io(model, TRUTH_2DOF, u, dt=0.05)
    res = si.identify(model, io, method="ls")
    np.testing.assert_allclose(res.theta_vector, model.theta_vector(TRUTH_2DOF), rtol=1e-6)


def test_second_order_general_case_scr_from_a_near_start():
    """(7-10) on the 2-DOF system with one actuator and one sensor (no linear special case)."""
    model = two_dof([[1], [0]], [[0, 1]])
    bb = transformed(model, TRUTH_2DOF, np.random.default_rng(4).standard_normal((4, 4)))
    solver = prepare(model, bb, "scr", {"backend": "cvxpy", "max_iter": 3, "aux_init": "identity"})
    assert solver.problem.n == len(TRUTH_2DOF) + 2 + 2 * 16  # θ, diagonal M⁻¹(τ), T, S
    assert solver.minv_basis.shape == (2, 2, 2)  # M diagonal ⇒ M⁻¹(τ) diagonal (§7-5-1)
    out = solver.run(model.theta_vector(TRUTH_2DOF))
    assert out.iterations == 3 and np.isfinite(out.cost)


def test_second_order_methods_that_do_not_apply():
    model = two_dof([[1], [0]], [[0, 1]])
    bb = transformed(model, TRUTH_2DOF, np.eye(4))
    with pytest.raises(si.ModelError, match="needs a StateSpaceModel"):
        si.identify(model, bb, method="gb")
    with pytest.raises(si.ModelError, match="full set of sensors"):
        si.identify(model, bb, method="ls")
    acc = two_dof([[1], [0]], [[0, 1]], output="acceleration")
    bb_acc = si.BlackBox(*acc.state_space(TRUTH_2DOF))
    with pytest.raises(si.ModelError, match="acceleration output"):
        si.identify(acc, bb_acc, method="scr")


# -- bad input ---------------------------------------------------------------------------------

def test_black_box_of_the_wrong_order():
    model, _ = small_model()
    bb = si.BlackBox(-np.eye(3), np.ones(3), np.ones(3))
    with pytest.raises(si.DataError, match="has 3 states but the model has 2"):
        si.identify(model, bb, method="scr")


def test_unstable_black_box_needs_consent():
    model, _ = small_model()
    unstable = {"a": 2.0, "b": -0.5, "c": 1.5}
    bb = transformed(model, unstable, T_SMALL)
    with pytest.raises(si.DataError, match=r"not stable.*allow_unstable=True"):
        si.identify(model, bb, method="ipopt")
    res = si.identify(model, bb, method="ipopt", starts=3, seed=0, allow_unstable=True)
    assert relative_parameter_error(res.theta_vector, model.theta_vector(unstable)) < 1e-6


def test_non_minimal_black_box():
    model, _ = small_model()
    bb = si.BlackBox([[-1.0, 0.0], [0.0, -2.0]], [[1.0], [0.0]], [[1.0, 1.0]])  # mode −2 not controllable
    with pytest.raises(si.DataError, match="not minimal: the mode λ = -2 is not controllable"):
        si.identify(model, bb, method="scr")


def test_io_records_too_short_for_the_order():
    model, truth = small_model()
    io = si.simulate_io(model, truth, np.random.default_rng(0).standard_normal(12), dt=0.1)
    with pytest.raises(si.DataError, match="too short for order 2"):
        si.identify(model, io, method="scr")


def test_missing_sample_time():
    with pytest.raises(si.DataError, match="dt is missing"):
        si.IOData(np.ones(10), np.ones(10), None)
    with pytest.raises(si.DataError, match="needs the sample time dt"):
        si.d2c([[0.9]], [[0.1]], [[1.0]])


def test_data_options_and_methods_are_checked():
    model, truth = small_model()
    bb = transformed(model, truth, T_SMALL)
    with pytest.raises(si.OptionError, match="horizon is an N4SID option"):
        si.identify(model, bb, method="scr", horizon=5)
    with pytest.raises(si.OptionError, match="unknown method 'newton'"):
        si.identify(model, bb, method="newton")
    with pytest.raises(si.OptionError, match="aux_init must be one of"):
        si.identify(model, bb, method="gb", aux_init="ones")
    with pytest.raises(si.OptionError, match="no option 'init' \\(did you mean 'aux_init'\\?\\)"):
        si.identify(model, bb, method="gb", init="random")
    with pytest.raises(si.ModelError, match=r"'ls'.*is for SecondOrderModel"):
        si.identify(model, bb, method="ls")


def test_fixed_feedthrough_must_match():
    model, truth = small_model()
    A, B, C, _ = model.state_space(truth)
    bb = si.BlackBox(A, B, C, [[0.3]])
    with pytest.raises(si.DataError, match="a similarity transform does not change D"):
        si.identify(model, bb, method="scr")


def test_misfit_sees_high_frequency_differences():
    """The per-frequency relative misfit weighs every frequency (see similarity_data's notes)."""
    model, truth = small_model()
    bb = transformed(model, truth, T_SMALL)
    sd = similarity_data(model, bb)
    theta = model.theta_vector(truth)
    assert sd.misfit(model, theta) < 1e-25
    assert sd.misfit(model, theta * [1, 1.01, 1]) > 1e-6


@pytest.mark.parametrize("method", ["scr", "ipopt", "gb", "als"])
def test_a_start_at_the_truth_stays_there_on_noise_free_records(method):
    # Issue 14, item 4: started at the true θ on exact data, the method stays there. With random T₀ (the default
    # aux_init) the similarity methods drew T₀ at random whatever the start, and from the truth of this
    # two-compartment model 'scr', the default for I/O records, ended at misfit 0.44 with k21 ≈ 1e-19 (found by
    # trying symid as a new user). A start that already explains the black box now keeps its own T.
    k10, k12, k21, q = si.parameters("k10 k12 k21 q", positive=True)
    model = si.StateSpaceModel(A=[[-k10 - k12, k21], [k12, -k21]], B=[[1], [0]], C=[[q, 0]])
    truth = {"k10": 0.2, "k12": 0.5, "k21": 0.15, "q": 0.02}
    u = np.repeat(np.random.default_rng(0).choice([0.0, 100.0], size=60), 8)
    io = si.simulate_io(model, truth, u, dt=0.25)
    res = si.identify(model, io, method=method, x0=truth, identifiability_check=False, time_limit=60)
    assert res.success, res.message
    np.testing.assert_allclose(res.theta_vector, list(truth.values()), rtol=1e-6)


@pytest.mark.parametrize("method", ["scr", "als", "gb", "ipopt"])
def test_a_black_box_with_another_fixed_feedthrough_is_refused_in_the_users_units(method):
    """The model's D is fixed at 0 and the black box has D = 0.3: a similarity transform cannot change D. Found by a
    new user: SCR refused it with the value in its internal units (3.25), ALS, GB and IPOPT ran on (misfits
    0.7–0.8)."""
    model, truth = small_model()
    bb = transformed(model, truth, T_SMALL)
    with_d = si.BlackBox(bb.A, bb.B, bb.C, [[0.3]])
    with pytest.raises(si.DataError, match=r"fixed at \[\[0\.0\]\] but the black box has D = \[\[0\.3\]\]"):
        prepare(model, with_d, method, {})


def test_scr_keeps_contradicted_equalities_in_the_least_squares_sense():
    """A DC motor with both states measured (C = I, B = [g; 0]): on 1 % noisy records the N4SID black box
    contradicts T𝔹 = B(θ), ℂS = C(θ) (relative residual 1.7e-4). Found by a new user: SCR, the default, stopped
    'infeasible' at iteration 0, from the truth too, and returned negative 'positive' parameters. Now those
    equalities are kept in the least-squares sense (no bilinear term is left: one step), and SCR meets IPOPT's fit.
    Truth: R = 2 Ω, L = 10 mH, K = 0.05, J = 1.25e-4, b = 2.5e-4 (r = R/L, ke = K/L, kt = K/J, d = b/J, g = 1/L)."""
    names = "r ke kt d g"
    r, ke, kt, d, g = si.parameters(names, positive=True)
    motor = si.StateSpaceModel(A=[[-r, -ke], [kt, -d]], B=[[g], [0]], C=[[1, 0], [0, 1]], parameters=[r, ke, kt, d, g])
    truth = np.array([200.0, 5.0, 400.0, 2.0, 100.0])
    u = np.random.default_rng(0).standard_normal(2000)
    io = si.simulate_io(motor, truth, u, 1e-3, noise=0.01, seed=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", si.IdentifiabilityWarning)
        res = si.identify(motor, io, method="scr", x0=truth * np.array([1.3, 0.7, 1.2, 1.5, 0.8]))
        ref = si.identify(motor, io, method="ipopt", x0=truth)
    assert "least squares" in res.options["equalities"]
    assert res.success and ref.success
    assert res.cost <= 1.01 * ref.cost  # the same fit of the records (both about 9.7e-5)
    assert relative_parameter_error(res.theta_vector, truth) < 0.05  # 1 % noise


def test_least_squares_equalities_on_a_thermal_chain_fit_only_after_a_polish():
    """A model the change was not written for: a 3-node thermal chain (rates in 1/s, b = 1/C1 in K/J; truth chosen
    as a building's: 2e-4 … 1e-3), all three temperatures measured (C = I), 1 % noisy records at 100 s. SCR's one
    step solves the contradicted equalities in their own weighting: within 0.5 % of the truth (measured 5.3e-3) but
    at a misfit 6 % above IPOPT's, which the success rule refuses (structured residual); polish=True fits."""
    names = si.parameters("a0 a1 a2 a3 a4 a5 b", positive=True)
    a0, a1, a2, a3, a4, a5, b = names
    model = si.StateSpaceModel(A=[[-a0 - a1, a1, 0], [a2, -a2 - a3, a3], [0, a4, -a4 - a5]], B=[[b], [0], [0]],
                               C=np.eye(3), parameters=list(names))
    truth = np.array([2e-4, 1e-3, 8e-4, 5e-4, 6e-4, 3e-4, 1e-3])
    u = np.random.default_rng(0).standard_normal(3000)
    io = si.simulate_io(model, truth, u, 100.0, noise=0.01, seed=1)
    x0 = truth * np.array([1.2, 0.8, 1.1, 0.9, 1.15, 0.85, 1.1])
    res = si.identify(model, io, method="scr", x0=x0, identifiability_check=False, polish=True)
    assert "least squares" in res.options["equalities"]
    assert np.max(np.abs(res.starts[0].theta / truth - 1)) < 0.02  # 1 % noise; measured 5.3e-3
    assert not res.starts[0].success and "structured" in res.starts[0].fit
    assert res.polished is not None and res.polished.success
