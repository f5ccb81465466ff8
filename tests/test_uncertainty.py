"""Uncertainty of θ̂ for every data kind (issue 15, item 3): exact sensitivities, covariance, coverage.

References: central finite differences for the derivatives; for Gaussian noise a least-squares estimate is
asymptotically normal with the sandwich covariance (JᵀJ)⁻¹JᵀVJ(JᵀJ)⁻¹ (Ljung, System Identification, 2nd ed.,
§9.2; White, Econometrica 48, 1980), so a 95 % interval holds the truth in about 95 % of noisy records and the
standard errors match the spread of the estimates. The fast tests count that over 100 records (binomial sd of the
rate 2.2 %: the band 0.88–0.99 is about 3 sd); the slow ones over 500 records of larger models.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import symid as si
from symid.errors import DataError, OptionError
from symid.fit.identify import FAILED_FIT_NOTE
from symid.fit.sensitivity import frf_sensitivity, spectra_sensitivity

W20 = np.linspace(0.5, 2.5, 20)
T1 = {"m": 1.0, "c": 0.4, "k": 2.0}


def one_dof(output="position", C=((1,),)):
    m, c, k = si.parameters("m c k", positive=True)
    return si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[list(r) for r in C], output=output)


def two_dof(C):
    m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    return si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                               K=[[k1 + k2, -k2], [-k2, k2]], B=[[1], [0]], C=C)


T2 = {"m1": 1.0, "m2": 1.0, "c1": 0.1, "c2": 0.3, "k1": 2.0, "k2": 1.0}  # thesis (4-20)


def state_space_with_d():
    a, b, c, d, e = si.parameters("a b c d e")
    return si.StateSpaceModel(A=[[-a, 1], [-b, -0.5]], B=[[0, 1], [c, 0]], C=[[1, d]], D=[[0, e]])


def central_differences(fun, theta, h=1e-6):
    th = np.asarray(theta, dtype=float)
    return np.stack([(fun(th + h * e) - fun(th - h * e)) / (2 * h) for e in np.eye(th.size)], axis=-1)


@pytest.mark.parametrize("case", ["ss_with_D", "position", "velocity", "acceleration"])
def test_frf_sensitivity_is_the_derivative(case):
    if case == "ss_with_D":
        model, theta = state_space_with_d(), [0.7, 2.0, 1.5, -0.3, 0.2]
    else:
        model, theta = two_dof([[1, 0], [1, -1]]), list(T2.values())
        model = si.SecondOrderModel(M=model.symbolic["M"], V=model.symbolic["V"], K=model.symbolic["K"],
                                    B=model.symbolic["B"], C=model.symbolic["C"], output=case)
    w = np.linspace(0.3, 3.0, 7)
    H, dH = frf_sensitivity(model, theta, w)
    np.testing.assert_allclose(H, model.frequency_response(theta, w), rtol=1e-12, atol=0)
    fd = central_differences(lambda t: model.frequency_response(t, w), theta)
    np.testing.assert_allclose(dH, fd, rtol=0, atol=1e-7 * np.abs(fd).max())


def test_spectra_sensitivity_is_the_derivative():
    model, theta = two_dof([[1, 0], [0, 1]]), list(T2.values())
    w = np.linspace(0.3, 3.0, 7)
    Puu = np.broadcast_to(np.array([[2.0]]), (7, 1, 1))

    def spectra(t):
        H = model.frequency_response(t, w)
        return H @ Puu @ np.conj(np.swapaxes(H, 1, 2))

    P, dP = spectra_sensitivity(model, theta, w, Puu)
    np.testing.assert_allclose(P, spectra(theta), rtol=1e-12, atol=0)
    fd = central_differences(spectra, theta)
    np.testing.assert_allclose(dP, fd, rtol=0, atol=1e-7 * np.abs(fd).max())


def coverage_study(model, truth, make, method, n, **options):
    """Fraction of records whose 95 % interval holds the truth, and empirical sd / mean standard error."""
    names = model.parameter_names
    t = np.array([truth[k] for k in names])
    hits, est, se = np.zeros(t.size), [], []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for i in range(n):
            res = si.identify(model, make(i), method=method, x0=truth, identifiability_check=False, **options)
            unc = res.uncertainty
            assert unc is not None and np.all(np.isfinite(unc.standard_errors)), i
            lo, hi = unc.intervals.T
            hits += (lo <= t) & (t <= hi)
            est.append(res.theta_vector)
            se.append(unc.standard_errors)
    return hits / n, np.std(est, axis=0) / np.mean(se, axis=0), res


def assert_calibrated(rate, spread, low=0.88, high=0.99):
    assert np.all((rate >= low) & (rate <= high)), rate
    assert np.all((spread > 0.8) & (spread < 1.2)), spread  # sd of an sd from 100 draws: 7 %


def test_frf_intervals_cover_the_truth_fast():
    """1-DOF FRF, 20 frequencies, 1 % relative noise, IPOPT, 100 records (measured: coverage 0.91–0.97,
    sd/SE 0.97–1.06)."""
    model = one_dof()
    rate, spread, res = coverage_study(
        model, T1, lambda i: si.simulate_frf(model, T1, W20, noise=0.01, seed=i), "ipopt", 100)
    assert_calibrated(rate, spread)
    assert res.uncertainty.noise_units == "relative" and res.uncertainty.note == ""


def test_ls_frf_intervals_are_its_own_fast():
    """The equation-error least squares (4-10): its covariance propagated from the noise on H (measured 0.93–0.96);
    the covariance of the output least squares at its θ̂ covered only 0.61–0.86 (2-DOF, 200 records)."""
    model = one_dof()
    rate, spread, res = coverage_study(
        model, T1, lambda i: si.simulate_frf(model, T1, W20, noise=0.01, seed=i), "ls", 100)
    assert_calibrated(rate, spread)
    assert "equation-error" in res.uncertainty.note


def test_spectra_intervals_cover_the_truth_fast():
    """1-DOF output spectrum (white input), 30 frequencies, 1 % relative noise, IPOPT, 100 records (measured 0.95)."""
    model = one_dof()
    w = np.linspace(0.5, 3.0, 30)
    rate, spread, res = coverage_study(
        model, T1, lambda i: si.simulate_spectra(model, T1, w, Phi_uu=1.0, noise=0.01, seed=i), "ipopt", 100)
    assert_calibrated(rate, spread)
    assert res.uncertainty.noise_units == "relative"


def test_time_series_intervals_cover_the_truth_fast():
    """First-order system, 40 samples of a square wave, 5 % noise, output error, 100 records (measured 0.93–0.94)."""
    k, g = si.parameters("k g", positive=True)
    model = si.StateSpaceModel(A=[[-k]], B=[[g]], C=[[1]])
    truth = {"k": 0.5, "g": 2.0}
    u = np.sign(np.sin(0.4 * np.arange(40)))
    rate, spread, res = coverage_study(
        model, truth, lambda i: si.simulate_io(model, truth, u, dt=0.25, noise=0.05, seed=i), "oe", 100)
    assert_calibrated(rate, spread)
    assert res.uncertainty.noise_units == "data units" and res.uncertainty.dof == 40 - 2


def test_given_noise_agrees_with_the_noise_from_the_residuals():
    model = one_dof()
    exact = si.simulate_frf(model, T1, W20)
    frf = si.simulate_frf(model, T1, W20, noise=0.01, seed=3)
    est = si.identify(model, frf, method="ipopt", x0=T1, identifiability_check=False)
    given = si.identify(model, frf, method="ipopt", x0=T1, identifiability_check=False,
                        noise_std=0.01 * np.abs(exact.H))
    ug, ue = given.uncertainty, est.uncertainty
    assert ug.noise_source == "given" and ug.dof is None and 0.7 < ug.residual_ratio < 1.3
    np.testing.assert_allclose(ug.standard_errors, ue.standard_errors, rtol=0.3)
    assert "residual/noise" in given.summary()
    d = given.to_dict()["uncertainty"]
    assert d["noise_source"] == "given" and len(d["standard_errors"]) == 3


def test_bad_noise_std_is_a_named_error():
    model = one_dof()
    frf = si.simulate_frf(model, T1, W20, noise=0.01, seed=3)
    with pytest.raises(DataError, match="does not fit"):
        si.identify(model, frf, method="ipopt", identifiability_check=False, noise_std=np.ones(7))
    with pytest.raises(DataError, match="> 0"):
        si.identify(model, frf, method="ipopt", identifiability_check=False, noise_std=-1.0)
    bb = si.BlackBox(*model.state_space(T1))
    ss = si.StateSpaceModel(A=[["-a", 1], ["-b", "-c"]], B=[[0], [1]], C=[[1, 0]])
    with pytest.raises(OptionError, match="noise_std"):
        si.identify(ss, bb, method="ipopt", identifiability_check=False, noise_std=0.1)


def test_scr_reports_which_covariance_it_gives():
    m1 = two_dof([[1, 0]])
    frf = si.simulate_frf(m1, T2, np.logspace(np.log10(0.5), np.log10(2), 30), noise=0.01, seed=1)
    res = si.identify(m1, frf, method="scr", x0=T2, identifiability_check=False, polish=True)
    unc = res.uncertainty
    assert "does not minimise" in unc.note and unc.shift is not None
    # intervals around θ̂ only when θ̂ is within SHIFT_LIMIT standard errors of the least-squares estimate
    assert np.all(np.isnan(unc.intervals)) == (unc.shift > 0.5)
    pol = res.polished.uncertainty
    assert pol is not None and pol.note == "" and np.all(np.isfinite(pol.standard_errors))


def test_near_singular_frf_is_flagged():
    """H = 1/(jω + a + b): only a + b is determined."""
    a, b = si.parameters("a b", positive=True)
    model = si.StateSpaceModel(A=[[-a - b]], B=[[1]], C=[[1]])
    frf = si.simulate_frf(model, [0.3, 0.2], W20, noise=0.01, seed=0)
    res = si.identify(model, frf, method="ipopt", x0=[0.2, 0.2], identifiability_check=False)
    assert res.uncertainty.near_singular
    assert abs(abs(res.uncertainty.weakest["a"]) - np.sqrt(0.5)) < 1e-3


def _monte_carlo(model, truth, make, method, n=500, **options):
    """500 records: the binomial sd of a rate of 0.95 is 1.0 %, so a calibrated interval leaves the 90–98 % band
    for one of six parameters by chance about once in 100 studies (with 200 records, once in 7)."""
    rate, spread, _ = coverage_study(model, truth, make, method, n, **options)
    print(method, "coverage", np.round(rate, 3).tolist(), "sd/SE", np.round(spread, 3).tolist())
    assert np.all((rate >= 0.90) & (rate <= 0.98)), rate


@pytest.mark.slow
def test_monte_carlo_frf_two_dof():
    """Thesis 2-DOF (4-19) at 30 frequencies (§4-6-2), 1 % noise, IPOPT, 500 records."""
    model = two_dof([[1, 0]])
    w = np.logspace(np.log10(0.5), np.log10(2), 30)
    _monte_carlo(model, T2, lambda i: si.simulate_frf(model, T2, w, noise=0.01, seed=1000 + i), "ipopt")


@pytest.mark.slow
def test_monte_carlo_frf_ls_two_dof():
    """Both positions measured (sensors case of (4-10)), 1 % noise, 500 records."""
    model = two_dof([[1, 0], [0, 1]])
    w = np.logspace(np.log10(0.5), np.log10(2), 30)
    _monte_carlo(model, T2, lambda i: si.simulate_frf(model, T2, w, noise=0.01, seed=1000 + i), "ls")


@pytest.mark.slow
def test_monte_carlo_spectra_two_dof():
    """Both positions' 2×2 output spectrum, white input, 40 frequencies in 0.3–3 rad/s, 1 % noise, 500 records;
    unweighted (5-13) and weighting='frequency'."""
    model = two_dof([[1, 0], [0, 1]])
    w = np.logspace(np.log10(0.3), np.log10(3), 40)
    make = lambda i: si.simulate_spectra(model, T2, w, Phi_uu=1.0, noise=0.01, seed=1000 + i)  # noqa: E731
    _monte_carlo(model, T2, make, "ipopt")
    _monte_carlo(model, T2, make, "ipopt", weighting="frequency")


def test_a_singular_fisher_information_leaves_the_determined_parameters_finite():
    """H = c/(jω + a + b): a and b only as a + b, c on its own. The linearised least squares determines c, and
    a + b, but not a or b: c's standard error is that of the same fit with a + b as one parameter, a's and b's
    are inf (a new-user trial found inf for every parameter whenever the information was singular)."""
    a, b, c = si.parameters("a b c", positive=True)
    model = si.StateSpaceModel(A=[[-a - b]], B=[[1]], C=[[c]])
    frf = si.simulate_frf(model, [0.3, 0.2, 2.0], W20, noise=0.01, seed=0)
    res = si.identify(model, frf, method="ipopt", x0=[0.3, 0.2, 2.0], identifiability_check=False)
    unc = res.uncertainty
    assert unc.near_singular and np.isinf(unc.standard_errors[0]) and np.isinf(unc.standard_errors[1])
    s, cc = si.parameters("s cc", positive=True)
    merged = si.StateSpaceModel(A=[[-s]], B=[[1]], C=[[cc]])
    ref = si.identify(merged, frf, method="ipopt", x0=[0.5, 2.0], identifiability_check=False).uncertainty
    np.testing.assert_allclose(unc.standard_errors[2], ref.standard_errors[1], rtol=1e-3)
    assert np.isfinite(unc.intervals[2]).all()


@pytest.mark.parametrize("method", ["lm", "auto", "ipopt"])
@pytest.mark.parametrize("C", [[[1, 0]], [[1, 0], [0, 1]]], ids=["one output", "two outputs"])
def test_a_fit_with_zero_residual_has_zero_standard_errors(method, C):
    # Started at the truth on noise-free data, these methods return the truth with every residual exactly 0.
    # The noise level estimated from the residuals is then 0, and so is the covariance. Before the fix, two
    # output channels raised "SVD did not converge" from numpy (the channel levels divided the residual by 0),
    # and one channel reported infinite standard errors. Reference: the sandwich covariance scales with the
    # noise variance (Ljung, System Identification, 2nd ed., §9.2), here 0.
    model = two_dof(C)
    frf = si.simulate_frf(model, T2, np.linspace(0.2, 3.0, 40))
    res = si.identify(model, frf, method=method, x0=T2, identifiability_check=False)
    assert res.success
    assert res.cost == 0.0
    np.testing.assert_allclose(res.theta_vector, list(T2.values()), rtol=0, atol=0)
    unc = res.uncertainty
    np.testing.assert_allclose(unc.standard_errors, 0.0, atol=0)
    np.testing.assert_allclose(unc.intervals, np.column_stack([res.theta_vector] * 2), atol=0)
    assert np.isfinite(unc.condition)


def test_residuals_that_are_not_finite_give_no_intervals_and_say_why():
    # An estimate where the model blows up (measured: method 'als' on noise-free records of a two-compartment model
    # diverged to negative rates; the output sensitivities overflowed) used to raise numpy's "SVD did not converge"
    # after the fit had finished, and the estimate was lost. Two channels, as there.
    from symid.fit.uncertainty import fisher_uncertainty

    t = np.linspace(0, 1, 40)
    J = -np.column_stack([np.ones(40), t])
    r = np.sin(7 * t) * 0.1
    J[5, 1] = np.inf
    unc = fisher_uncertainty(np.array([1.0, 2.0]), ("a", "b"), r, J, np.arange(40) % 2)
    assert np.all(np.isinf(unc.standard_errors))
    assert "not finite" in unc.note


def test_a_failed_fit_shows_no_intervals():
    # found by a new-user sweep: a failed fit (IPOPT 'Solve_Succeeded' at a zero response) printed "relative noise
    # 3.89e+14 %" and standard errors of 1e26 in its summary; intervals describe an estimate that fits the data
    model = one_dof()
    frf = si.simulate_frf(model, T1, W20)
    res = si.identify(model, frf, method="ipopt", x0={"m": 1e4, "c": 1e-4, "k": 1e-3}, max_iter=3,
                      identifiability_check=False)
    assert not res.success
    text = res.summary()
    assert "uncertainty: not shown, the estimate does not fit the data" in text
    assert "std. error" not in text
    assert res.uncertainty is not None
    # and none for a script to read either (a new user's shake-table record read 8 intervals, none holding the truth)
    assert np.all(np.isnan(res.uncertainty.intervals))


def test_a_failed_fit_at_the_least_squares_estimate_has_nan_intervals_and_says_why():
    """The least-squares estimate of 1 % noisy data judged against a noise floor 1e4 times too small: a failed fit
    whose intervals would otherwise be finite (shift 0). They are NaN, the note says why, the standard errors stay."""
    model = one_dof()
    frf = si.simulate_frf(model, T1, W20, noise=0.01, seed=3)
    res = si.identify(model, frf, method="ipopt", noise_floor=1e-8, identifiability_check=False)
    assert not res.success and res.uncertainty.shift < 1e-3  # at the minimum: only the failed fit withholds them
    assert np.all(np.isnan(res.uncertainty.intervals))
    assert np.all(np.isfinite(res.uncertainty.standard_errors))  # the Fisher information at the estimate is kept
    assert res.uncertainty.note.endswith(FAILED_FIT_NOTE)


def test_intervals_are_withheld_wherever_the_estimate_is_not_the_least_squares_one():
    """For every method, not only those that do not minimise the misfit: one Gauss-Newton step says how far the
    least-squares estimate lies, in standard errors (SHIFT_LIMIT = 0.5)."""
    from symid.fit.registry import prepare

    model = one_dof()
    frf = si.simulate_frf(model, T1, W20, noise=0.01, seed=3)
    res = si.identify(model, frf, method="ipopt", identifiability_check=False)
    at_minimum = res.uncertainty
    assert at_minimum.shift < 1e-3 and np.all(np.isfinite(at_minimum.intervals)) and at_minimum.note == ""
    est = prepare(model, frf, "ipopt", {})
    theta = np.array([res.theta[k] for k in model.parameter_names])
    off = theta + 3 * at_minimum.standard_errors * np.array([1.0, 0.0, 0.0])  # the mass 3 standard errors off
    unc = est.uncertainty(off, model.parameter_names)
    # to first order the step lands back on the estimate, δ = 3 σ_m e_m, whose length in the covariance's metric is
    # 3 σ_m √((cov⁻¹)_mm) (≥ 3: the other parameters correlate with m); within 20 %, the covariance at the shifted
    # point differing from that at the minimum
    C = at_minimum.covariance
    assert unc.shift == pytest.approx(3 * np.sqrt(C[0, 0] * np.linalg.inv(C)[0, 0]), rel=0.2)
    assert np.all(np.isnan(unc.intervals)) and "standard errors from the least-squares estimate" in unc.note


def test_an_unweighted_frf_fit_takes_the_noise_shape_its_residuals_have():
    """Additive noise (one level on every line, as a flat multisine's estimated response has it) against relative
    noise (si.simulate_frf's): the residuals' likelihood chooses, and the standard errors match the spread of the
    estimates over 40 records within a factor 1.35 either way (0.96–1.11 for both when this test was written;
    with additive noise taken as relative, as before, 29–44 times too large, and a new user's 4-storey frame
    60–150 times). Reference: the truth chosen here."""
    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    truth = np.array([2.0, 0.4, 50.0])  # resonance at 5 rad/s, damping ratio 2 %
    w = np.linspace(2.0, 12.0, 150)
    clean = si.simulate_frf(model, truth, w)
    level = 0.01 * np.sqrt(np.mean(np.abs(clean.H) ** 2))
    for kind in ("additive", "relative"):
        est, se = [], []
        for seed in range(40):
            rng = np.random.default_rng(seed)
            if kind == "additive":
                e = level * (rng.standard_normal(clean.H.shape) + 1j * rng.standard_normal(clean.H.shape)) / np.sqrt(2)
                frf = si.FrequencyData(w, clean.H + e)
            else:
                frf = si.simulate_frf(model, truth, w, noise=0.01, seed=seed)
            res = si.identify(model, frf, method="lm", x0=truth, identifiability_check=False)
            assert res.uncertainty.noise_units == ("data units" if kind == "additive" else "relative")
            est.append(res.theta_vector)
            se.append(res.uncertainty.standard_errors)
        ratio = np.median(se, axis=0) / np.std(est, axis=0, ddof=1)
        assert np.all((ratio > 1 / 1.35) & (ratio < 1.35)), (kind, ratio)


def test_a_fit_to_rounding_keeps_its_intervals():
    """Noise-free data fitted to rounding (a new user's trial: every interval NaN, "θ̂ lies 26 standard errors
    from the least-squares estimate"): the Gauss–Newton step is rounding, so the intervals are kept, as narrow as
    the rounding, and the note says so. Reference: the thesis's 2-DOF mass-damper (4-20), from the zoo."""
    entry = si.load_model("mass_damper_2dof")
    start = {k: 1.5 * v for k, v in entry.truth.items()}
    res = si.identify(entry.model, entry.data(), method="ipopt", x0=start, identifiability_check=False)
    unc = res.uncertainty
    assert unc.shift > 0.5 and "a fit to rounding" in unc.note  # what withheld every interval before
    assert np.all(np.isfinite(unc.intervals))
    np.testing.assert_allclose(unc.intervals.mean(axis=1), res.theta_vector, rtol=1e-12)
    assert np.all(unc.standard_errors <= 1e-12 * np.abs(res.theta_vector))


def test_the_weakest_direction_is_shown_in_relative_changes():
    """A new user's motor with its torque constant free: the response fixes only ratios, and the common scaling of
    every parameter is the null direction. In absolute units it read "-0.73·ks -0.69·Kt -0.00·ds" (the small
    inertias and dampers at 0); in relative changes each of J, b and Kt here has an equal part, 1/√3."""
    J, b, Kt = si.parameters("J b Kt", positive=True)
    model = si.SecondOrderModel(M=[[J]], V=[[b]], K=[[0]], B=[[Kt]], C=[[1]], output="velocity")
    truth = {"J": 2e-4, "b": 1e-4, "Kt": 0.05}
    frf = si.simulate_frf(model, truth, np.logspace(-1, 2, 30), noise=0.01, seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", si.IdentifiabilityWarning)
        res = si.identify(model, frf, method="ipopt", x0=truth, identifiability_check=False)
    unc = res.uncertainty
    assert unc.near_singular
    rel = np.array([unc.weakest_relative[n] for n in ("J", "b", "Kt")])
    np.testing.assert_allclose(np.abs(rel), 1 / np.sqrt(3), rtol=1e-3)
    assert np.all(np.sign(rel) == np.sign(rel[0]))
    assert abs(unc.weakest["Kt"]) > 0.99  # in absolute units the largest parameter takes the direction
    line = next(x for x in unc.summary().splitlines() if "NEAR-SINGULAR" in x)
    assert all(f"·δ{n}/{n}" in line for n in ("J", "b", "Kt")) and "(relative changes)" in line


def test_an_interval_is_found_by_the_parameters_name():
    """A new user could index the intervals by position only; unc.interval(name) gives one by name (the same row),
    and a name the estimate has not is a named error listing its parameters."""
    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    frf = si.simulate_frf(model, [2.0, 0.5, 3.0], np.linspace(0.5, 2.0, 40), noise=0.01, seed=0)
    unc = si.identify(model, frf, x0=[2.0, 0.5, 3.0], identifiability_check=False).uncertainty
    assert unc.interval("c") == tuple(float(v) for v in unc.intervals[1])
    with pytest.raises(si.DataError, match=r"'k2' is not a parameter of this estimate; its parameters are m, c, k"):
        unc.interval("k2")


def _ladder() -> si.SecondOrderModel:
    """A new user's two-section LC ladder (L in mH, C in µF, R in Ω; E x' = F x + G u in second-order form), with R1
    and L1 known: resonances at 1280 and 4211 Hz."""
    L1, C1, L2, C2, R1, R2 = si.parameters("L1 C1 L2 C2 R1 R2", positive=True)
    E = [[1e-3 * L1, 0, 0, 0], [0, 1e-6 * C1, 0, 0], [0, 0, 1e-3 * L2, 0], [0, 0, 0, 1e-6 * C2]]
    F = [[-R1, -1, 0, 0], [1, 0, -1, 0], [0, 1, -R2, -1], [0, 0, 1, 0]]
    model = si.SecondOrderModel(M=E, V=[[-f for f in row] for row in F], K=[[0] * 4 for _ in range(4)],
                                B=[[1], [0], [0], [0]], C=[[0, 0, 0, 1]], output="velocity")
    return model.with_known({"R1": 10.0, "L1": 10.0})


def test_a_fit_the_data_pull_beyond_its_bounds_is_not_a_success():
    """A new user's frequency response in Hz read as rad/s: the fit put R2 on its positivity bound (1e-5 Ω for 22)
    at a misfit the whiteness rule accepted, success True and exit 0. The least-squares estimate lies 12 standard
    errors beyond the bound, far more than noise explains (χ²(4) at 1e-6: 5.8), so the model within its bounds does
    not fit: success False, the fit line and NEXT say so. Read in rad/s, the same data fit (truth: the values
    simulated, 1 % noise)."""
    model = _ladder()
    truth = {"C1": 1.0, "L2": 4.7, "C2": 0.47, "R2": 22.0}
    f = np.logspace(2, np.log10(2e4), 150)
    frf = si.simulate_frf(model, truth, 2 * np.pi * f, noise=0.01, seed=3)
    start = {"C1": 2.0, "L2": 2.0, "C2": 1.0, "R2": 10.0}
    right = si.identify(model, frf, x0=start, scale=start, identifiability_check=False)
    assert right.success and right.uncertainty.bounds_rejected() is None
    np.testing.assert_allclose(right.theta_vector, model.theta_vector(truth), rtol=0.02)
    wrong = si.identify(model, si.FrequencyData(f, frf.H), x0=start, scale=start, identifiability_check=False)
    assert not wrong.success and not wrong.best_start.success
    assert wrong.fit.startswith("pulled beyond the bounds: the data pull R2")
    assert set(wrong.uncertainty.beyond_bounds) == {"R2"} and wrong.uncertainty.shift > 5.78
    assert "a frequency in Hz read as rad/s" in wrong.summary().split("NEXT: ")[1]


def test_nuisance_unknowns_do_not_make_theta_near_singular():
    """Two nuisance columns (initial states, say) nearly collinear, θ's two well determined and independent of them:
    θ's conditioning is that of its information with the nuisance profiled out, F_θθ − F_θn F_nn⁺ F_nθ (the flag
    and the weakest direction said "NEAR-SINGULAR" for the nuisance alone before). The standard errors are the same
    either way (the marginal covariance); a θ that trades off against a nuisance column is still flagged.
    Reference: the regression by hand, cov = σ² (JᵀJ)⁻¹."""
    from symid.fit.uncertainty import fisher_uncertainty

    rng = np.random.default_rng(0)
    N = 400
    t1, t2, n1 = rng.standard_normal((3, N))
    n2 = n1 + 1e-7 * rng.standard_normal(N)  # the nuisance columns agree to 1e-7
    J = np.column_stack([t1, t2, n1, n2])
    r = 0.1 * rng.standard_normal(N)
    unc = fisher_uncertainty(np.array([1.0, 2.0]), ("a", "b"), r, J, np.zeros(N, dtype=int))
    assert not unc.near_singular and unc.condition < 10  # θ's own: two nearly orthogonal unit-variance columns
    sigma2 = float(r @ r) / (N - 4)
    expected = np.sqrt(np.diag(np.linalg.pinv(J.T @ J))[:2] * sigma2)
    # (symid's noise level per channel differs from r·r/(N − 4) by 0.15 % here: measured)
    np.testing.assert_allclose(unc.standard_errors, expected, rtol=5e-3)
    tied = np.column_stack([t1, t2, t1 + 1e-7 * rng.standard_normal(N), n1])  # a depends on a nuisance column
    assert fisher_uncertainty(np.array([1.0, 2.0]), ("a", "b"), r, tied, np.zeros(N, dtype=int)).near_singular
