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
    res = si.identify(model, frf, method="ipopt", starts=6, seed=1)
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
    with pytest.raises(si.ModelError, match="unknown method 'pem'"):
        si.identify(model, frf, method="pem")
    with pytest.raises(si.ModelError, match="starts must be a positive integer"):
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
