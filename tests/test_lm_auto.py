"""The FRF methods ``lm`` and ``auto`` (issue 14): physical units, noise, restarts, budgets, bad input.

Reference values: the true parameters the data are simulated from (the tests' own
truth), and IPOPT's estimate from the truth (the least-squares estimate both minimise).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import symid as si
from symid.fit.compare import relative_parameter_error
from symid.fit.frf.lm import JUMPS, AutoFRF
from symid.fit.registry import prepare

# a 2-mass chain in SI units: masses of kg, springs of 1e4 N/m, dampers of N·s/m
TRUTH = np.array([3.0, 0.8, 12.0, 4.0, 2.5e4, 8.0e3])  # m1 m2 c1 c2 k1 k2


def chain2(output="position"):
    """Force and sensor on the free mass (collocated): at 1 % noise the least-squares estimate from the truth
    is within 0.4 % of it (measured, 5 records); with the sensor on the other mass it is up to 30 % off, a
    practically non-identifiable direction that would make the noisy tests below test nothing."""
    m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    return si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                               K=[[k1 + k2, -k2], [-k2, k2]], B=[[0], [1]], C=[[0, 1]], output=output)


def grid(theta):
    """Log-spaced lines from 0.3x the slowest to 3x the fastest natural frequency."""
    lam = np.abs(np.linalg.eigvals(chain2().state_space(theta).A))
    return np.logspace(np.log10(0.3 * lam.min()), np.log10(3 * lam.max()), 60)


def rescaled(theta, a_param=1.0, a_time=1.0, a_data=1.0):
    """θ of the same physics in other units: every parameter × a_param (a force unit), time × a_time
    (ω → ω / a_time: M × a_time², V × a_time), and H × a_data (M, V, K / a_data)."""
    m, c, k = theta[:2], theta[2:4], theta[4:]
    return np.concatenate([m * a_time**2, c * a_time, k]) * a_param / a_data


@pytest.mark.parametrize("method", ["lm", "auto"])
@pytest.mark.parametrize(("a_param", "a_time", "a_data"),
                         [(1.0, 1.0, 1.0), (1e-6, 1.0, 1.0), (1e6, 1.0, 1.0), (1.0, 1e-3, 1.0), (1.0, 1e3, 1.0),
                          (1.0, 1.0, 1e-6), (1.0, 1.0, 1e6), (1e4, 1e-2, 1e-5)])
def test_estimates_follow_the_physics_in_any_units(method, a_param, a_time, a_data):
    model = chain2()
    w = grid(TRUTH)
    start = TRUTH * np.array([2.0, 0.5, 3.0, 0.4, 0.6, 1.7])
    base = si.simulate_frf(model, TRUTH, w)
    ref = prepare(model, base, method, {"seed": 1}).run(start)
    theta_u = rescaled(TRUTH, a_param, a_time, a_data)
    H = np.asarray(base.H) * a_data / a_param  # the same response in the new units
    data_u = si.FrequencyData(w / a_time, H)
    out = prepare(model, data_u, method, {"seed": 1}).run(rescaled(start, a_param, a_time, a_data))
    assert ref.success and out.success
    # the estimate in new units is the old one converted (both to the solver's tolerance of the truth)
    np.testing.assert_allclose(out.theta, rescaled(ref.theta, a_param, a_time, a_data), rtol=1e-6)
    assert relative_parameter_error(out.theta, theta_u) <= 1e-6


def test_auto_from_two_decades_off_on_one_percent_noise_matches_ipopt_from_the_truth():
    model = chain2("acceleration")
    w = grid(TRUTH)
    frf = si.simulate_frf(model, TRUTH, w, noise=0.01, seed=3)
    ref = si.identify(model, frf, method="ipopt", x0=TRUTH, identifiability_check=False)
    start = TRUTH * np.array([10.0, 0.1, 8.0, 0.2, 0.15, 9.0])  # every parameter off by about a decade
    res = si.identify(model, frf, method="auto", x0=start, seed=0, identifiability_check=False)
    assert res.success
    assert relative_parameter_error(ref.theta_vector, TRUTH) <= 0.02  # the problem is well posed at this noise
    # both minimise the same misfit: the same estimate, to the solvers' tolerances
    np.testing.assert_allclose(res.theta_vector, ref.theta_vector, rtol=1e-5)
    assert res.cost <= ref.cost * (1 + 1e-8)


def test_a_noisy_fit_is_confirmed_by_a_second_pass():
    """On 1 % noise the first fit is accepted by the noise rule; ``auto`` goes on until a second pass ends at the
    same misfit (``confirm``), ``confirm=0`` stops at the first. Reference: IPOPT from the truth, the least-squares
    estimate both reach."""
    model = chain2("acceleration")
    frf = si.simulate_frf(model, TRUTH, grid(TRUTH), noise=0.01, seed=3)
    start = TRUTH * np.array([2.0, 0.5, 3.0, 0.4, 0.6, 1.7])
    seen = {}
    for confirm in (0, 4):
        misfits = []
        # chain_start=False: one pass from the start, not two (the chain's values, then the start)
        est = prepare(model, frf, "auto", {"seed": 0, "confirm": confirm, "chain_start": False,
                                           "callback": lambda k, info, m=misfits: m.append(info["misfit"])})
        out = est.run(start)
        assert out.success
        seen[confirm] = misfits
    assert len(seen[0]) == 1
    # the second pass ends at the first's misfit (the same minimum, to the stopping rule's 1e-6)
    assert len(seen[4]) == 2
    np.testing.assert_allclose(seen[4][1], seen[4][0], rtol=1e-6)
    ref = si.identify(model, frf, method="ipopt", x0=TRUTH, identifiability_check=False)
    assert min(seen[4]) <= ref.cost * (1 + 1e-8)


def test_lm_alone_can_miss_where_auto_does_not():
    """From 6 starts within a decade of the truth on exact data of a 2-mass chain, ``auto`` reaches the truth from
    all, ``lm`` (one pass, no continuation over frequency bands, no restarts) misses some (measured: 3 of 6, each of
    ``auto``'s from its first pass: the band continuation makes the difference here, not the restarts). Reference:
    the values the exact data are simulated from."""
    model = chain2()
    w = grid(TRUTH)
    frf = si.simulate_frf(model, TRUTH, w)
    starts = [TRUTH * f for f in np.random.default_rng(5).uniform(0.1, 10.0, size=(6, TRUTH.size))]
    lm = [prepare(model, frf, "lm", {}).run(x) for x in starts]
    auto = [prepare(model, frf, "auto", {"seed": 0}).run(x) for x in starts]
    assert all(o.success and relative_parameter_error(o.theta, TRUTH) <= 1e-6 for o in auto)
    assert sum(relative_parameter_error(o.theta, TRUTH) > 1e-3 for o in lm) >= 1


def test_time_limit_and_callback_stop_a_start():
    model = chain2()
    frf = si.simulate_frf(model, TRUTH, grid(TRUTH))
    est = prepare(model, frf, "auto", {"time_limit": 0.05, "restarts": 1000, "bands": 1})
    far = TRUTH * 1e3
    out = est.run(far)
    assert out.wall_time < 5.0  # the budget (0.05 s) plus one residual evaluation and the outcome's test
    seen = []
    stopper = prepare(model, frf, "auto", {"callback": lambda k, info: seen.append(info) or True})
    out = stopper.run(far)
    assert out.status == "stopped" and len(seen) == 1
    assert set(seen[0]) == {"theta", "misfit", "fits", "elapsed"}


def test_verbose_prints_one_line_per_pass(capsys):
    model = chain2()
    frf = si.simulate_frf(model, TRUTH, grid(TRUTH))
    prepare(model, frf, "lm", {"verbose": True}).run(TRUTH * 1.1)
    out = capsys.readouterr().out
    assert out.count("lm pass") == 1 and "misfit" in out


@pytest.mark.parametrize(("options", "match"), [
    ({"scale": [1.0, -2.0, 1.0, 1.0, 1.0, 1.0]}, "scale"),
    ({"spread": 0.5}, "spread"),
    ({"restarts": -1}, "restarts"),
    ({"confirm": -1}, "confirm"),
    ({"bands": 0}, "bands"),
    ({"time_limit": 0}, "time_limit"),
    ({"callback": 3}, "callback must be callable"),
    ({"variance": "wrong"}, "variance must be 'data', 'relative', None or an array"),
    ({"variance": np.zeros(60)}, r"finite and > 0"),
    ({"maxiter": 3}, "no option 'maxiter'"),
])
def test_bad_options_are_named(options, match):
    model = chain2()
    frf = si.simulate_frf(model, TRUTH, grid(TRUTH))
    with pytest.raises(si.OptionError, match=match):
        prepare(model, frf, "auto", options)


def test_a_start_of_the_wrong_length_is_named():
    model = chain2()
    frf = si.simulate_frf(model, TRUTH, grid(TRUTH))
    with pytest.raises(si.OptionError, match="x0"):
        si.identify(model, frf, method="auto", x0=[1.0, 2.0], identifiability_check=False)
    with pytest.raises(si.OptionError, match="6 finite values"):
        prepare(model, frf, "lm", {}).run(np.array([1.0, np.nan, 1.0, 1.0, 1.0, 1.0]))


def test_a_negative_start_of_a_positive_parameter_is_named():
    # θ = s·exp(φ) cannot start below 0 (IPOPT refuses a start outside its bounds θ ≥ 0 the same way); 0 takes
    # the scale. Reference: TRUTH, the values the exact data are simulated from.
    model = chain2()
    frf = si.simulate_frf(model, TRUTH, grid(TRUTH))
    start = model.theta_vector(TRUTH).copy()
    start[2] = -start[2]
    for method in ("auto", "lm"):
        with pytest.raises(si.OptionError, match=rf"the start {model.parameter_names[2]} = .* is negative.*{method}"):
            si.identify(model, frf, method=method, x0=start, identifiability_check=False)
    start[2] = 0.0
    res = si.identify(model, frf, method="auto", x0=start, identifiability_check=False)
    assert res.success and relative_parameter_error(res.theta_vector, model.theta_vector(TRUTH)) <= 1e-6


def test_noise_weighting_uses_the_data_variance():
    model = chain2()
    w = grid(TRUTH)
    H = np.asarray(si.simulate_frf(model, TRUTH, w).H)
    # noise 30x larger on the upper half of the lines: the weighted fit leans on the lower half
    sd = np.where(np.arange(w.size) < w.size // 2, 1e-3, 3e-2)[:, None, None] * np.abs(H)
    sq = {"weighted": [], "equal": []}
    for seed in range(8):
        rng = np.random.default_rng(seed)
        noisy = H + sd * (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape)) / np.sqrt(2)
        frf = si.FrequencyData(w, noisy, variance=sd**2)
        for name, var in (("weighted", "data"), ("equal", None)):
            out = prepare(model, frf, "lm", {"variance": var}).run(TRUTH)
            sq[name].append(np.sum((out.theta / TRUTH - 1) ** 2))
    # Maximum likelihood against equal weights: the linearised covariances at the truth give a ratio of
    # 0.032 for the summed squared relative errors (trace of (JᵀΣ⁻¹J)⁻¹ over that of the sandwich
    # (JᵀJ)⁻¹JᵀΣJ(JᵀJ)⁻¹, J = ∂H/∂log θ); with 8 records, a ratio below 0.3 leaves a margin of ten.
    assert np.mean(sq["weighted"]) < 0.3 * np.mean(sq["equal"])


def test_the_declared_noise_judges_lm_as_it_judges_ipopt():
    """With a per-line variance, lm and auto judge an estimate against the noise it declares, as IPOPT does
    (issue 18: the F-16 fit was 'success' by lm's whiteness rule and not by IPOPT's noise floor)."""
    model = chain2()
    w = grid(TRUTH)
    H = np.asarray(si.simulate_frf(model, TRUTH, w).H)
    sd = 1e-3 * np.abs(H)
    rng = np.random.default_rng(0)
    noisy = H + sd * (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape)) / np.sqrt(2)
    frf = si.FrequencyData(w, noisy, variance=sd**2)
    floors = {m: prepare(model, frf, m, {}).noise_floor for m in ("lm", "auto", "ipopt")}
    # the weighted misfit the declared noise leaves at the truth: Σ wσ² / Σ w|H|² = s / Σ|H/σ|², w = 1/σ²
    expected = w.size / np.sum(np.abs(noisy / sd) ** 2)
    np.testing.assert_allclose(list(floors.values()), expected, rtol=1e-12)
    # the truth fits the declared noise for every method; 2 % off in one spring does not, for any method
    for theta, fits in ((TRUTH, True), (TRUTH * np.array([1, 1, 1, 1, 1.02, 1]), False)):
        verdicts = {m: prepare(model, frf, m, {}).outcome(theta, theta, finished=True, status="given", message="",
                                                          iterations=0, wall_time=0.0).success
                    for m in ("lm", "auto", "ipopt")}
        assert verdicts == dict.fromkeys(verdicts, fits), (theta, verdicts)
    assert prepare(model, frf, "lm", {"variance": None}).noise_floor is None  # equal weights declare no noise


@pytest.fixture(scope="module")
def population_models():
    """The generator of benchmarks/population.py: problems nobody tuned for."""
    import importlib
    import sys
    from pathlib import Path

    bench = str(Path(__file__).resolve().parents[1] / "benchmarks")
    sys.path.insert(0, bench)
    try:
        yield importlib.import_module("population_models")
    finally:
        sys.path.remove(bench)


def test_every_other_restart_is_drawn_around_the_typical_values(population_models, monkeypatch):
    """Restarts 1, 3, … start within a factor ``spread`` of ``scale=`` (the typical values), restarts 2, 4, … within
    that factor of the start; without ``scale`` every restart is drawn around the start.

    The passes are replaced by a stub that returns its own start (never a fit), so the test sees where each pass
    begins whatever the floating-point path of the real passes: whether a restart then reaches the truth depends on
    the machine's rounding (a generated 5-mass chain reached it from the first restart around the typical values on
    one machine and from none of 3 passes on another), which is measured on populations in
    ``benchmarks/auto_restarts.py``, not asserted on one start. Reference: the spread of 10 is ``AutoFRF``'s
    default; the start is 300 times the typical values, so the two centres are 2.5 decades apart in every parameter."""
    p = population_models.make_problem("chain", 3, 0, check=False)
    frf = p.data(0.0)
    x0 = 300.0 * p.typical
    starts = []

    def stub(self, phi, centre, unit, deadline):
        theta = self._theta(phi, centre, unit)
        starts.append(theta)
        return theta, 1, False

    monkeypatch.setattr(AutoFRF, "_pass", stub)
    out = AutoFRF(p.model, frf, scale=p.typical, restarts=4, chain_start=False).run(x0)
    assert not out.success and len(starts) == 5
    np.testing.assert_allclose(starts[0], x0, rtol=1e-12)
    spread = np.log(10.0) * (1 + 1e-12)
    for k, theta in enumerate(starts[1:], start=1):
        centre = p.typical if k % 2 == 1 else x0
        assert np.max(np.abs(np.log(theta / centre))) <= spread, (k, theta / centre)
        other = x0 if k % 2 == 1 else p.typical
        assert np.min(np.abs(np.log(theta / other))) >= np.log(300.0) - spread, (k, theta / other)
    starts.clear()
    AutoFRF(p.model, frf, restarts=4, chain_start=False).run(x0)
    assert len(starts) == 5
    assert all(np.max(np.abs(np.log(theta / x0))) <= spread for theta in starts)


def test_a_minimum_found_again_stops_the_restarts_only_where_the_data_are_no_cleaner(population_models, monkeypatch):
    """Three passes ending at the same misfit stop the restarts (a confirmed minimum) unless a black box of the
    model's order fits the data better than noise explains: on exact data the minimum found again is a local one.

    Every pass is a stub that ends at the same point, 10 % off in every parameter (misfit about 1e-2), so the
    test does not depend on the floating-point path of real passes. Reference: the exact data of a generated
    3-mass chain, which the black box fits to rounding (its misfit ≤ 1e-20 here)."""
    p = population_models.make_problem("chain", 3, 0, check=False)
    frf = p.data(0.0)
    off = 1.1 * p.truth
    passes = []

    def stub(self, phi, centre, unit, deadline):
        passes.append(1)
        return off.copy(), 1, False

    monkeypatch.setattr(AutoFRF, "_pass", stub)
    est = AutoFRF(p.model, frf, scale=p.typical, restarts=6, chain_start=False)
    assert est.black_box()[0] <= 1e-20
    out = est.run(p.typical)
    assert not out.success and len(passes) == 7 and out.status == "max_restarts", out.message
    passes.clear()
    est = AutoFRF(p.model, frf, scale=p.typical, restarts=6, chain_start=False)
    monkeypatch.setattr(AutoFRF, "black_box", lambda self: None)  # no black box: nothing says the data are cleaner
    out = est.run(p.typical)
    assert len(passes) == 3 and out.status == "repeated", out.message


def test_a_fit_a_black_box_beats_tenfold_does_not_stop_the_restarts(population_models):
    """The vector fit of the data with the model's order is at rounding level on exact data and no better than
    noise allows on 1 % noise (so a correct noisy fit is never doubted); reference: the misfit of the true
    parameters the data are simulated from."""
    p = population_models.make_problem("chain", 5, 3, check=False)
    exact = AutoFRF(p.model, p.data(0.0), scale=p.typical)
    assert exact.black_box()[0] <= 1e-20
    for seed in range(3):
        noisy = AutoFRF(p.model, p.data(0.01, seed=seed), scale=p.typical)
        at_truth = noisy.misfit(p.truth)
        # the least-squares estimate fits at most as well as the truth: 10x the floor is out of its reach
        assert 0.2 * at_truth <= noisy.black_box()[0] <= at_truth


def test_a_loose_exact_fit_is_continued_from_its_own_estimate():
    """A 3-mass chain in physical units (force on mass 3, position of mass 1; a user's model from a new-user
    trial): from this start the passes stop at misfit 6e-16 with m3 7 % off, an "exact fit" at the 1e-10 level.
    One more pass from that estimate reaches a fit to rounding at the truth (before: 3 of 4 such starts returned
    a success 3-12 % off). Reference: the values the exact data are simulated from."""
    m1, m2, m3, c1, c2, c3, k1, k2, k3 = si.parameters("m1 m2 m3 c1 c2 c3 k1 k2 k3", positive=True)
    model = si.SecondOrderModel(M=[[m1, 0, 0], [0, m2, 0], [0, 0, m3]],
                                V=[[c1 + c2, -c2, 0], [-c2, c2 + c3, -c3], [0, -c3, c3]],
                                K=[[k1 + k2, -k2, 0], [-k2, k2 + k3, -k3], [0, -k3, k3]],
                                B=[[0], [0], [1]], C=[[1, 0, 0]], output="position")
    truth = model.theta_vector(dict(m1=2.0, m2=5.0, m3=1.2, c1=3.0, c2=1.5, c3=0.8, k1=3000.0, k2=800.0, k3=400.0))
    frf = si.simulate_frf(model, truth, np.logspace(np.log10(2.9), np.log10(132), 100))
    x0 = truth * np.exp(np.random.default_rng(7).uniform(-np.log(3), np.log(3), truth.size))
    out = AutoFRF(model, frf).run(x0)
    assert out.success and out.cost <= 1e-20
    np.testing.assert_allclose(out.theta, truth, rtol=1e-8)


def _half_car():
    a, b = 1.2, 1.5
    m, J, kf, kr, cf, cr = si.parameters("m J kf kr cf cr", positive=True)
    model = si.SecondOrderModel(M=[[m, 0], [0, J]], V=[[cf + cr, a * cf - b * cr], [a * cf - b * cr,
                                                                                     a**2 * cf + b**2 * cr]],
                                K=[[kf + kr, a * kf - b * kr], [a * kf - b * kr, a**2 * kf + b**2 * kr]],
                                B=[[1], [a]], C=[[1, a]], output="acceleration")
    truth = {"m": 700.0, "J": 1100.0, "kf": 35000.0, "kr": 38000.0, "cf": 2500.0, "cr": 2800.0}
    frf = si.simulate_frf(model, truth, 2 * np.pi * np.logspace(np.log10(0.2), np.log10(8), 80), noise=0.01, seed=0)
    reference = si.identify(model, frf, method="lm", x0=truth, identifiability_check=False)
    return model, truth, frf, reference


@pytest.mark.parametrize("factor", [1000.0, 30.0, 0.001])
def test_a_near_singular_noisy_fit_looks_elsewhere(factor):
    """A new user's half car (force and acceleration at the front axle, lever arms known) started at 1000 times its
    values: the passes ran into a rigid rear axle (kr, cr 1000 times their size; misfit 1.031e-4, accepted by the
    noise rule) where the least-squares estimate has 8.761e-5 (lm from the truth, the reference here). The start
    from the black box's poles (choice 8) ended there too (its rear spring 8 times its size, already rigid); the
    passes with the rear spring and damper moved (choice 9) reach 8.761e-5. From 0.001 times the values, the
    pitch inertia and the rear damper ran 1e6 times from their start (misfit 1.007e-4, not a minimum)."""
    model, truth, frf, reference = _half_car()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", si.IdentifiabilityWarning)
        res = si.identify(model, frf, x0={k: factor * v for k, v in truth.items()}, identifiability_check=False)
    msg = res.best_start.message
    assert "unfelt by the response" in msg or "run 1e6 times from the start" in msg
    if factor > 1:
        assert "the fit was near-singular: a start from the black box's poles" in res.best_start.message
    assert res.cost <= reference.cost * (1 + 1e-6)  # the least-squares estimate's misfit (8.761e-5), not 1.031e-4


def test_a_noisy_fit_with_a_parameter_far_from_its_typical_value_tries_it_there():
    """Choice 9 for a parameter far from the typical values given as ``scale=``: on the population benchmark an
    8-mass chain with gains ended at 4.3 times the least-squares misfit with a damper 21 000 times its value, neither
    unfelt nor at the solver's limit, so nothing moved it. Here the 2-mass chain's least-squares estimate (1 %
    noise) with c2 3e4 times its typical value (a rigid link): no parameter is at the limit, and the passes that
    start c2 at 0.1 … 1000 times its typical value reach the least-squares misfit. Reference: ``lm`` from the
    truth (the least-squares estimate, within 1 % of the truth on these data)."""
    model = chain2()
    frf = si.simulate_frf(model, TRUTH, grid(TRUTH), noise=0.01, seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", si.IdentifiabilityWarning)
        reference = si.identify(model, frf, method="lm", x0=TRUTH, identifiability_check=False)
    est = AutoFRF(model, frf, scale=TRUTH)
    centre, unit = est._units(TRUTH)
    far = reference.theta_vector.copy()
    far[3] = 3e4 * TRUTH[3]  # c2
    best = est.outcome(TRUTH, far, finished=True, status="converged", message="", iterations=0, wall_time=0.0)
    assert best.cost > 100 * reference.cost  # the rigid link fits far worse: a point worth leaving
    assert not est._edge(far, centre, unit).any()  # nothing at the solver's limit: only the new rule moves c2
    note, tried, _ = est._jump_saturated(best, TRUTH, centre, unit, None, 0.0, 0)
    assert "c2 more than 100 times from the typical values" in note
    assert len(tried) == len(JUMPS)
    assert min(c.cost for c in tried) <= reference.cost * (1 + 1e-6)
    assert not est._far(reference.theta_vector, unit).any()  # the estimate itself is within a factor 100


def test_an_estimate_stopped_at_the_solvers_limit_says_so():
    """The half car with its masses given in grams (1000 times too large): the rear damper and the front spring
    ran to 1e6 times below their start, the solver's limit, where the passes stop (misfit 1.007e-4 against the
    least-squares 8.761e-5); the message names them and the way out."""
    model, truth, frf, _ = _half_car()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", si.IdentifiabilityWarning)
        res = si.identify(model, frf, x0={**truth, "m": 700e3, "J": 1100e3}, identifiability_check=False)
    msg = res.best_start.message
    start = {**truth, "m": 700e3, "J": 1100e3}
    # the parameters at the limit, read off the estimate itself (measured here: cr and kf, at 1.007e-4)
    edge = [n for n in model.parameter_names if abs(np.log(res.theta[n] / start[n])) >= np.log(1e6) * (1 - 1e-9)]
    import re

    named = [n for group in re.findall(r"(?:; | and )([\w, ]+?) stopped at 1e-?6 times the start", msg)
             for n in group.split(", ")]
    assert sorted(named) == sorted(edge)
    assert all(" stopped at 1e-6 times" in msg for n in edge if res.theta[n] < start[n])  # below the start: 1e-6
    assert not edge or ("the solver's limit" in msg and "x0= or scale=" in msg)
    assert edge or res.cost <= 8.8e-5  # no parameter at the limit: the least-squares fit was reached


def test_a_parameter_at_the_solvers_limit_is_said_on_its_own_side():
    """A new user's motor: frictions that went from 1e-4 down to 1e-10 were said to have "stopped at 1e6 times the
    start". Each side is now named as it is."""
    model = chain2()
    est = prepare(model, si.simulate_frf(model, TRUTH, grid(TRUTH)), "lm", {})
    centre, unit = est._units(TRUTH)
    theta = TRUTH * np.array([1e-6, 1, 1, 1e6, 1, 1])
    said = est._at_edge(theta, centre, unit)
    assert "m1 stopped at 1e-6 times the start and c2 stopped at 1e6 times the start, the solver's limit" in said
