"""Identification from frequency responses: linear LS special cases, IPOPT, compare, bad input."""

from __future__ import annotations

import numpy as np
import pytest

import symid as si

BELT_TRUTH = [-1.0, -0.5, -0.2, -0.15]  # thesis (3-18)
TRUTH_2DOF = {"m1": 1, "m2": 1, "c1": 0.1, "c2": 0.3, "k1": 2, "k2": 1}  # thesis (4-20)


def belt_drive():
    """Thesis (3-17)."""
    t1, t2, t3, t4 = si.parameters("theta1 theta2 theta3 theta4")
    return si.StateSpaceModel(A=[[0, -1, 0.15], [0.2, 0, 0], [t1, t2, t3]], B=[[0], [0], [t4]], C=[[0, 1, 0]])


def two_dof(output="position", B=((1,), (0,))):
    """Thesis (4-19)/(4-21)."""
    m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    return si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                               K=[[k1 + k2, -k2], [-k2, k2]], B=[list(r) for r in B], C=[[1, 0]], output=output)


W_BELT = np.logspace(np.log10(0.4), np.log10(0.6), 10)  # thesis §3-6 (rad/s, see models/belt_drive.py)
W_2DOF = np.logspace(np.log10(0.5), np.log10(2), 30)  # thesis §4-6-2


@pytest.mark.parametrize("output", ["position", "velocity", "acceleration"])
def test_ls_full_actuators_recovers_2dof(output):
    model = two_dof(output, B=((1, 0), (0, 1)))
    frf = si.simulate_frf(model, TRUTH_2DOF, W_2DOF)
    res = si.identify(model, frf, method="ls")
    assert res.method == "ls" and res.success
    np.testing.assert_allclose(res.theta_vector, model.theta_vector(TRUTH_2DOF), rtol=1e-9, atol=1e-12)
    assert res.cost < 1e-20


def test_ls_full_sensors_with_parameterised_B():
    c, k, g = si.parameters("c k g", positive=True)
    model = si.SecondOrderModel(M=[[2.0]], V=[[c]], K=[[k]], B=[[g]], C=[[2.0]])
    truth = {"c": 0.3, "k": 5.0, "g": 1.5}
    frf = si.simulate_frf(model, truth, np.linspace(0.5, 3, 6))
    res = si.identify(model, frf, method="ls")
    assert res.options["case"] == "sensors"
    np.testing.assert_allclose(res.theta_vector, [0.3, 5.0, 1.5], rtol=1e-10)


def test_ls_rank_deficiency_is_reported():
    """With M, V, K and B all free, only ratios are determined: the LS says so instead of guessing."""
    m, c, k, g = si.parameters("m c k g", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[g]], C=[[2.0]])
    frf = si.simulate_frf(model, {"m": 2.0, "c": 0.3, "k": 5.0, "g": 1.5}, np.linspace(0.5, 3, 6))
    with pytest.raises(si.ModelError, match="rank 3 < 4 parameters"):
        si.identify(model, frf, method="ls")


def test_scr_chooses_ls_automatically_for_second_order():
    model = two_dof(B=((1, 0), (0, 1)))
    frf = si.simulate_frf(model, TRUTH_2DOF, W_2DOF)
    res = si.identify(model, frf, method="scr")
    assert res.method == "ls"
    assert "linear special case" in res.options["chosen_because"]


def test_ls_refuses_when_it_does_not_apply():
    with pytest.raises(si.ModelError, match=r"C is 1×2, not square; B is 2×1, not square"):
        si.identify(two_dof(), si.simulate_frf(two_dof(), TRUTH_2DOF, W_2DOF), method="ls")


def test_ipopt_belt_drive_from_a_good_start():
    model = belt_drive()
    frf = si.simulate_frf(model, BELT_TRUTH, W_BELT)
    # the start where the thesis reports MATLAB's PEM failing (§3-7)
    res = si.identify(model, frf, method="ipopt", x0=[-0.5, -0.5, -0.2, -0.1])
    assert res.success, res.message
    np.testing.assert_allclose(res.theta_vector, BELT_TRUTH, rtol=1e-6)


def test_ipopt_2dof_with_bounds():
    model = two_dof()
    frf = si.simulate_frf(model, TRUTH_2DOF, W_2DOF)
    res = si.identify(model, frf, method="ipopt", x0=[1.2, 0.8, 0.2, 0.2, 1.5, 1.2])
    np.testing.assert_allclose(res.theta_vector, model.theta_vector(TRUTH_2DOF), rtol=1e-6)
    assert all(v >= 0 for v in res.theta.values())


def test_multistart_keeps_every_start_and_returns_best():
    model = belt_drive()
    frf = si.simulate_frf(model, BELT_TRUTH, W_BELT)
    res = si.identify(model, frf, method="ipopt", starts=6, seed=1, draws="normal")
    assert res.n_starts == 6
    np.testing.assert_array_equal(res.starts[0].start, np.zeros(4))  # thesis ch. 3: zero start first
    assert res.cost == min(s.cost for s in res.starts)
    text = res.summary(truth=dict(zip(model.parameter_names, BELT_TRUTH, strict=True)))
    assert "rel. error" in text and "theta1" in text


def test_compare_uses_identical_starts_and_reports():
    model = belt_drive()
    frf = si.simulate_frf(model, BELT_TRUTH, W_BELT)
    cmp = si.compare(model, frf, methods=("ipopt",), starts=5, seed=3,
                     truth=BELT_TRUTH)
    st = cmp["ipopt"]
    assert st.n_starts == 5 and 0 <= st.n_success <= 5
    assert "ipopt" in cmp.table() and cmp.to_markdown().startswith("| method")
    d = cmp.to_dict()
    assert d["methods"][0]["n_starts"] == 5
    if st.n_success:
        assert st.time_to_solution == pytest.approx(
            (st.setup_time + sum(s.wall_time for s in st.result.starts)) / st.n_success, rel=1e-12)
    else:
        assert st.time_to_solution == float("inf")


def test_compare_same_starts_for_two_methods():
    model = two_dof(B=((1, 0), (0, 1)))
    frf = si.simulate_frf(model, TRUTH_2DOF, W_2DOF)
    cmp = si.compare(model, frf, methods=("ls", "ipopt"), starts=3, seed=0, truth=TRUTH_2DOF)
    starts_ls = [s.start for s in cmp["ls"].result.starts]
    starts_ip = [s.start for s in cmp["ipopt"].result.starts]
    for a, b in zip(starts_ls, starts_ip, strict=True):
        np.testing.assert_array_equal(a, b)
    assert cmp["ls"].success_rate == 1.0


# -- SCR: thesis results and formulation options ----------------------------------------------------

def test_scr_belt_drive_from_zeros():
    """Thesis §3-6: from the all-zero start ‖θ̂ − θ*‖₂ ≤ 1e-6 (thesis (3-21): 3.5e-7). With C and the first
    two rows of A known, presolve turns (3-10) into linear equalities that fix every Γᵢ."""
    entry = si.load_model("belt_drive")
    res = si.identify(entry.model, entry.data(), method="scr", draws="normal")  # the thesis start: θ = 0
    assert res.method == "scr" and res.success, res.message
    np.testing.assert_array_equal(res.starts[0].start, np.zeros(4))
    truth = entry.model.theta_vector(entry.truth)  # thesis (3-18)
    assert np.linalg.norm(res.theta_vector - truth) <= 1e-6
    assert "no bilinear term left" in res.message


def test_truss_by_least_squares():
    """Thesis §4-6-1: full symmetric M, V, K (108 parameters), B = C = I, 20 log-spaced points in 5–25 rad/s:
    relative Frobenius errors ≤ 1e-8 (thesis (4-18): about 4e-9), by (4-11) as the thesis and by (4-10)."""
    entry = si.load_model("truss8")
    data = entry.data()
    auto = si.identify(entry.model, data, method="scr", identifiability_check=False)
    assert auto.method == "ls"  # B and C known, square, invertible: the linear case is chosen automatically
    for case in ("actuators", "sensors"):  # (4-11), (4-10)
        res = si.identify(entry.model, data, method="ls", case=case, identifiability_check=False)
        est = entry.model.matrices(res.theta_vector)
        for name, printed in (("M", "M_printed"), ("V", "V_printed"), ("K", "K_printed")):
            true = entry.extra[printed]  # thesis (4-15)
            rel = np.linalg.norm(est[name] - true) / np.linalg.norm(true)
            assert rel <= 1e-8, (case, name, rel)


@pytest.mark.parametrize("output", ["position", "acceleration"])
def test_scr_2dof_runs_formulation_4_8_with_lmis(output):
    """Thesis §4-6-2, (4-8)/(4-9): B, C not square, so SCR (not LS) runs, with M, V, K ⪰ 0 as LMIs; from a
    seeded N(0, 1) start it recovers (4-20) for position and acceleration output alike."""
    from symid.fit.frf.scr import ScrFRF

    model = two_dof(output)
    frf = si.simulate_frf(model, TRUTH_2DOF, W_2DOF)
    solver = ScrFRF(model, frf)
    assert len(solver.problem.lmis) == 3 + 6  # M, V, K ⪰ 0 and the six θk ≥ 0
    res = si.identify(model, frf, method="scr", seed=1)
    assert res.method == "scr" and res.success, res.message
    np.testing.assert_allclose(res.theta_vector, model.theta_vector(TRUTH_2DOF), rtol=1e-4, atol=1e-5)


def _lead_lag():
    """A 2-state model with parameters in A, B and C, so C(θ)Γ and Ψ B(θ) are bilinear."""
    a, b, g, c = si.parameters("a b g c")
    return si.StateSpaceModel(A=[[0, 1], [a, b]], B=[[0], [g]], C=[[1, c]])


@pytest.mark.parametrize("substitution", ["gamma", "psi", "both"])
def test_scr_substitutions_with_parameterised_B_and_C(substitution):
    """Both substitutions of thesis (3-10) and (3-12), alone and together as (3-15), recover θ when B and C
    hold parameters too; started at a perturbed truth (from random starts Γ alone is fragile here)."""
    model = _lead_lag()
    truth = np.array([-2.0, -0.4, 1.5, 0.5])  # chosen here: stable, lightly damped, identifiable
    frf = si.simulate_frf(model, truth, np.logspace(-0.5, 0.7, 12))
    x0 = truth + 0.2 * np.random.default_rng(1).standard_normal(4)
    res = si.identify(model, frf, method="scr", x0=x0, substitution=substitution, identifiability_check=False)
    assert res.success, res.message
    np.testing.assert_allclose(res.theta_vector, truth, rtol=1e-5, atol=1e-6)


def test_scr_weights_per_frequency_and_per_family():
    """Algorithm 3.1's λᵢ, γᵢ, δᵢ, ρᵢ: a vector weighs every family at a frequency, a dict weighs families."""
    from symid.fit.frf.scr import ScrFRF

    model = _lead_lag()
    truth = np.array([-2.0, -0.4, 1.5, 0.5])  # chosen here: stable, lightly damped, identifiable
    frf = si.simulate_frf(model, truth, np.logspace(-0.5, 0.7, 12))
    lam = np.linspace(0.5, 2.0, 12)
    solver = ScrFRF(model, frf, substitution="both", weights={"gamma_output": 10.0, "psi_dynamics": lam})
    weights = {t.name: t.weight for t in solver.problem.terms}
    assert weights["gamma_output[3]"] == 10.0 and weights["gamma_dynamics[3]"] == 1.0
    assert weights["psi_dynamics[11]"] == pytest.approx(2.0, rel=1e-12)
    res = si.identify(model, frf, method="scr", x0=truth + 0.1, weights=lam, identifiability_check=False)
    np.testing.assert_allclose(res.theta_vector, truth, rtol=1e-5, atol=1e-6)
    with pytest.raises(si.OptionError, match="unknown constraint family psi_output; this formulation has "
                                            "gamma_dynamics, gamma_output"):
        ScrFRF(model, frf, weights={"psi_output": 2.0})
    with pytest.raises(si.OptionError, match="12 positive finite numbers"):
        ScrFRF(model, frf, weights=np.ones(5))


def test_polish_is_reported_apart_from_scr():
    """polish=True: the SCR estimate and SCR + polish are two results, never mixed."""
    model = two_dof()
    frf = si.simulate_frf(model, TRUTH_2DOF, W_2DOF)
    res = si.identify(model, frf, method="scr", seed=1, max_iter=15, polish=True)
    assert res.method == "scr" and res.polished is not None and res.polished.method == "scr+polish"
    truth = model.theta_vector(TRUTH_2DOF)
    np.testing.assert_allclose(res.polished.theta_vector, truth, rtol=1e-8)
    assert res.polished.cost < res.cost
    assert res.polished.wall_time > res.wall_time
    assert "after polish" in res.summary()


def test_compare_reports_scr_and_scr_plus_polish_from_the_same_starts():
    model = two_dof()
    frf = si.simulate_frf(model, TRUTH_2DOF, W_2DOF)
    cmp = si.compare(model, frf, methods=("scr", "scr+polish"), starts=2, seed=1, truth=TRUTH_2DOF,
                     options={"scr": {"max_iter": 15}})
    scr, pol = cmp["scr"], cmp["scr+polish"]
    assert pol.ran_as == "scr+polish" and scr.n_starts == pol.n_starts == 2
    for a, b in zip(scr.result.starts, pol.result.starts, strict=True):
        np.testing.assert_array_equal(a.start, b.start)
        assert b.cost <= 1e-8 and "handed over to ipopt" in b.message  # SCR + IPOPT, reported as such
        assert "ipopt" not in a.message  # SCR alone: no polish mixed in
    assert pol.best_error < 1e-8 < scr.best_error
    assert "scr+polish" in cmp.table()
    with pytest.raises(si.OptionError, match="method 'ipopt' has no polish step"):
        si.compare(model, frf, methods=("ipopt+polish",), starts=1)


def test_run_polished_hands_over_only_when_the_trial_fits():
    from symid.fit.frf.ipopt import IpoptFRF
    from symid.fit.frf.scr import ScrFRF
    from symid.fit.starts import make_starts

    model = two_dof()
    frf = si.simulate_frf(model, TRUTH_2DOF, W_2DOF)
    x0 = make_starts(model, 1, 1)[0]
    truth = model.theta_vector(TRUTH_2DOF)
    early = ScrFRF(model, frf).run_polished(x0, IpoptFRF(model, frf))
    # a trial after SCR iteration 1, 2, 4, … reached misfit ≤ 1e-8: SCR stopped there (powers of two only)
    k = int(early.message.split("after ")[1].split(" iteration")[0])
    assert "handed over to ipopt" in early.message and k & (k - 1) == 0
    assert early.success and early.cost <= 1e-8 and len(early.history) == k
    np.testing.assert_allclose(early.theta, truth, rtol=1e-6)
    # no trials: SCR runs to its own end, then its final estimate is polished
    late = ScrFRF(model, frf, polish_misfit=None, max_iter=8).run_polished(x0, IpoptFRF(model, frf))
    assert "handed over" not in late.message and len(late.history) == 8
    with pytest.raises(si.OptionError, match="polish_misfit must be a finite number > 0"):
        ScrFRF(model, frf, polish_misfit=0.0)


# -- bad input ------------------------------------------------------------------------------------

def test_shape_mismatch_is_named():
    model = two_dof()
    other = two_dof(B=((1, 0), (0, 1)))
    frf = si.simulate_frf(other, TRUTH_2DOF, W_2DOF)
    with pytest.raises(si.DataError, match=r"1 output\(s\) × 2 input\(s\).*model has 1 output\(s\) × 1 input"):
        si.identify(model, frf, method="ipopt")


def test_too_few_frequencies_says_how_many():
    model = two_dof()
    frf = si.simulate_frf(model, TRUTH_2DOF, [0.5, 1.0])
    with pytest.raises(si.DataError, match="at least 3 frequencies are needed"):
        si.identify(model, frf, method="ipopt")


def test_no_free_parameter():
    model = si.StateSpaceModel(A=[[-1]], B=[[1]], C=[[1]])
    frf = si.simulate_frf(model, [], [1.0, 2.0])
    with pytest.raises(si.ModelError, match="no free parameter"):
        si.identify(model, frf, method="ipopt")


def test_unknown_method_and_bad_starts():
    model = belt_drive()
    frf = si.simulate_frf(model, BELT_TRUTH, W_BELT)
    with pytest.raises(si.OptionError, match="unknown method 'pem'"):
        si.identify(model, frf, method="pem")
    with pytest.raises(si.OptionError, match="starts must be an integer between 1 and 100000; got 0"):
        si.identify(model, frf, method="ipopt", starts=0)


def test_identify_warns_when_parameters_are_not_identifiable():
    a, b, c = si.parameters("a b c", positive=True)
    model = si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[c]])  # only b*c is determined
    frf = si.simulate_frf(model, [1.0, 2.0, 3.0], np.linspace(0.5, 2, 5))
    with pytest.warns(si.IdentifiabilityWarning, match=r"parameter\(s\) b, c are not locally identifiable"):
        si.identify(model, frf, method="ipopt", x0=[1.0, 1.0, 1.0])


def test_numeric_screen_agrees_on_the_zoo():
    """The floating-point screen used for large models agrees with the exact verdicts of the zoo."""
    from symid.structural.numeric import numeric_local_check

    assert numeric_local_check(si.load_model("belt_drive").model).not_identifiable == ()
    over = numeric_local_check(si.load_model("enose_overparameterized").model)  # thesis §6-6-3
    assert over.not_identifiable == ("theta1", "theta2", "theta3", "theta4", "theta5", "theta6")
    assert over.rank == 6


def test_solver_failure_is_a_result_not_a_traceback():
    """A solver that stops short says so: success False and its own message, no exception. (The thesis's N(0, 1)
    starts: the default black-box start is exact on noise-free data, so no solver would stop short from it.)"""
    model = two_dof()
    frf = si.simulate_frf(model, TRUTH_2DOF, W_2DOF)
    res = si.identify(model, frf, method="scr", seed=1, max_iter=2, draws="normal")
    assert not res.success and "maximum number of iterations (2) reached" in res.message
    res = si.identify(model, frf, method="ipopt", seed=1, max_iter=1, draws="normal")
    assert not res.success and res.status == "Maximum_Iterations_Exceeded"
    with pytest.raises(si.OptionError, match="backend must be one of 'admm', 'cvxpy'; got 'mosek'"):
        si.identify(model, frf, method="scr", backend="mosek")


@pytest.mark.slow
@pytest.mark.parametrize("script", ["mass_damper_2dof_scr.py", "belt_drive_ipopt.py"])
def test_example_scripts_assert_the_thesis_results(script):
    """The examples that assert thesis §4-6-2 (≥ 8 of 10 N(0, 1) starts; acceleration output gives the same
    θ) and §3-7 (SCR succeeds from the three starts where PEM failed); minutes, hence slow."""
    import runpy
    from pathlib import Path

    runpy.run_path(str(Path(__file__).resolve().parents[1] / "examples" / script), run_name="__main__")
