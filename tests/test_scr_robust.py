"""SCR on frequency responses that are not exact, not O(1), or started where a user would start it.

Reference values: the belt drive (thesis §3-6, (3-17), (3-18)) and the 2-DOF mass-damper
(thesis §4-6-2, (4-19)–(4-21)) from the zoo; the least-squares estimate of the belt drive's
equations is computed here with numpy, independently of the engine.
"""

from __future__ import annotations

import numpy as np
import pytest

import symid as si
from symid import scr
from symid.fit.frf.ipopt import IpoptFRF
from symid.fit.frf.scr import ScrFRF
from symid.fit.polish import polish_outcome
from symid.fit.starts import make_starts


def belt():
    entry = si.load_model("belt_drive")
    return entry.model, entry.model.theta_vector(entry.truth), entry.data()  # truth: thesis (3-18)


def two_dof():
    entry = si.load_model("mass_damper_2dof")
    return entry.model, entry.model.theta_vector(entry.truth), entry.data()  # truth: thesis (4-20)


def belt_reference(data) -> np.ndarray:
    """The estimate SCR's presolve must return on belt-drive data, built here from the equations.

    C = [0, 1, 0] and the known rows of A in (3-10) give Γ₂ = Hᵢ, Γ₁ = jωᵢHᵢ/0.2,
    Γ₃ = (jωᵢΓ₁ + Γ₂)/0.15; the third row θ₁Γ₁ + θ₂Γ₂ + θ₃Γ₃ + θ₄ = jωᵢΓ₃ gives two real
    equations per frequency, each weighted by the size of its terms at the estimate.
    """
    w, H = np.asarray(data.w), np.asarray(data.H)[:, 0, 0]
    g1 = 1j * w * H / 0.2
    g3 = (1j * w * g1 + H) / 0.15
    rows = np.stack([g1, H, g3, np.ones_like(g1)], axis=1)
    D = np.vstack([rows.real, rows.imag])
    d = np.concatenate([(1j * w * g3).real, (1j * w * g3).imag])

    def lstsq(W, b):  # unit columns, so that the units of H cannot make lstsq rank-deficient
        cn = np.linalg.norm(W, axis=0)
        return np.linalg.lstsq(W / cn, b, rcond=None)[0] / cn

    x = lstsq(D, d)
    for _ in range(50):  # fixed point of the term weights
        T = np.sqrt(np.sum((D * x) ** 2, axis=1) + d**2)
        x = lstsq(D / T[:, None], d / T)
    return x


# -- noise ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("kind", ["noise 1e-4", "rounded to 6 decimals"])
@pytest.mark.parametrize("backend", ["admm", "cvxpy"])
def test_belt_drive_on_noisy_data_returns_the_least_squares_estimate_of_its_equations(kind, backend):
    model, truth, exact = belt()
    data = (si.simulate_frf(model, truth, exact.w, noise=1e-4, seed=1) if kind == "noise 1e-4" else
            si.FrequencyData(exact.w, np.round(np.asarray(exact.H), 6)))
    out = ScrFRF(model, data, backend=backend).run(np.zeros(4))
    assert out.status == "converged", out.message
    assert "least-squares sense" in out.message
    np.testing.assert_allclose(out.theta, belt_reference(data), rtol=1e-10)
    # and it is an estimate from noisy data, not the truth
    assert 1e-7 < np.max(np.abs(out.theta - truth) / np.abs(truth)) < 1e-3
    # The least-squares estimate of SCR's equations is not the least-squares fit of H: on these 10 lines its
    # misfit is 3.7 (noise) and 15 (rounding) times what the truth leaves, more than ten times what a vector
    # fit of order 3 leaves, so the success rule does not call it a fit (measured: 9.4e-9 against 2.6e-9 at
    # the truth and 7.6e-10 for the black box; 1.2e-10 against 7.8e-12 and 5.9e-12). Polished, it is one.
    est = IpoptFRF(model, data)
    assert out.cost > 2 * est.misfit(truth) and not out.success and "black box" in out.fit
    polished = polish_outcome(est, out)
    assert polished.success and polished.cost <= est.misfit(truth)


def test_presolve_judges_consistency_relative_to_the_data():
    """The same noisy equations are inconsistent (exact mode) at every scale of H, and their least-squares
    estimate moves with the units exactly: H × s with θ₄ × s (B = [0, 0, θ₄]) is the same system."""
    model, truth, exact = belt()
    noisy = si.simulate_frf(model, truth, exact.w, noise=1e-4, seed=1)
    ref = ScrFRF(model, noisy).run(np.zeros(4)).theta
    residuals = []
    for s in (1e-12, 1.0, 1e9):
        data = si.FrequencyData(noisy.w, np.asarray(noisy.H) * s)
        est = ScrFRF(model, data)
        exact_mode = scr.compile(est.problem, equalities="exact")
        residuals.append(exact_mode.reduced.inconsistent)
        out = est.run(np.zeros(4))
        np.testing.assert_allclose(out.theta, ref * np.array([1, 1, 1, s]), rtol=1e-9)
        clean = scr.compile(ScrFRF(model, si.FrequencyData(exact.w, np.asarray(exact.H) * s)).problem,
                            equalities="exact")
        assert clean.reduced.inconsistent <= 1e-12, s
    assert min(residuals) > scr.INCONSISTENT_TOL  # noise of relative size 1e-4 is never "consistent"
    np.testing.assert_allclose(residuals, residuals[0], rtol=1e-6)


def test_two_dof_with_one_percent_noise_same_estimate_as_ipopt():
    """SCR alone stops once stationary and fits (white residual); SCR + polish returns IPOPT's estimate."""
    model, truth, exact = two_dof()
    data = si.simulate_frf(model, truth, exact.w, noise=1e-2, seed=1)
    ip = IpoptFRF(model, data)
    ref = ip.run(truth)
    assert ref.success
    est = ScrFRF(model, data)
    se = np.sqrt(np.diag(ip.uncertainty(ref.theta, model.parameter_names).covariance))
    for x0 in (truth * np.array([0.5, 2.0, 2.5, 0.4, 0.6, 1.8]),):  # within a factor 3, as the default starts
        alone = est.run(x0)
        assert alone.success and alone.status == "stationary", alone.message
        assert alone.iterations < 200  # stopped when it stopped moving, not at max_iter = 500
        # SCR's own estimate (its equations' fixed point) lies within a few standard errors of IPOPT's
        assert np.all(np.abs(alone.theta - ref.theta) <= 3 * se), (alone.theta - ref.theta) / se
        pol = est.run_polished(x0, ip)
        assert pol.success and "handed over to ipopt" in pol.message, pol.message
        np.testing.assert_allclose(pol.theta, ref.theta, rtol=1e-7)  # IPOPT's tol is 1e-12 on the misfit


# -- the start is honoured --------------------------------------------------------------------------

def lead_lag():
    a, b, g, c = si.parameters("a b g c")
    return si.StateSpaceModel(A=[[0, 1], [a, b]], B=[[0], [g]], C=[[1, c]])


def physical_chain():
    """Three masses (kg), dampers (N s/m), springs (N/m): force on mass 3, position of mass 1 (issue 14)."""
    m = si.parameters("m1 m2 m3", positive=True)
    c = si.parameters("c1 c2 c3", positive=True)
    k = si.parameters("k1 k2 k3", positive=True)

    def tri(p):
        return [[p[0] + p[1], -p[1], 0], [-p[1], p[1] + p[2], -p[2]], [0, -p[2], p[2]]]

    model = si.SecondOrderModel(M=[[m[0], 0, 0], [0, m[1], 0], [0, 0, m[2]]], V=tri(c), K=tri(k),
                                B=[[0], [0], [1]], C=[[1, 0, 0]], parameters=[*m, *c, *k])
    theta = np.array([2.0, 1.5, 3.0, 8.0, 5.0, 12.0, 4000.0, 9000.0, 6000.0])  # chosen here: kg, N s/m, N/m
    poles = np.abs(np.linalg.eigvals(model.state_space(theta).A))
    w = np.logspace(np.log10(0.3 * poles.min()), np.log10(3 * poles.max()), 100)  # covers the three modes
    return model, theta, w


def cases(backend):
    model, truth, data = two_dof()
    yield "2dof", model, truth, data, {}
    model, truth, data = belt()
    yield "belt", model, truth, data, {"presolve": False}
    ll, th = lead_lag(), np.array([-2.0, -0.4, 1.5, 0.5])
    yield "lead-lag psi", ll, th, si.simulate_frf(ll, th, np.logspace(-0.5, 0.7, 12)), {"substitution": "both"}
    if backend == "admm":  # Clarabel on 100 frequencies takes half a minute: in the slow variant below
        chain, th, w = physical_chain()
        yield "chain", chain, th, si.simulate_frf(chain, th, w), {"scale": th * 1.7}


@pytest.mark.slow
def test_started_at_the_truth_clarabel_stays_on_the_chain():
    chain, th, w = physical_chain()
    est = ScrFRF(chain, si.simulate_frf(chain, th, w), backend="cvxpy", scale=th * 1.7)
    out = est.run(th)
    assert out.success and out.iterations == 1 and np.linalg.norm(out.theta - th) / np.linalg.norm(th) <= 1e-6


@pytest.mark.parametrize("backend", ["admm", "cvxpy"])
def test_started_at_the_truth_every_scr_method_stays_there(backend):
    # the sub-problem at a fixed point is solved to the back end's accuracy: the ADMM's first step from a
    # feasible point is exact; Clarabel's interior point stops at its default relative tolerances (1e-8),
    # which leave θ within SCR's own tol (1e-6) on the 9-parameter chain
    tol = {"admm": 1e-9, "cvxpy": 1e-6}[backend]
    for name, model, truth, data, opts in cases(backend):
        est = ScrFRF(model, data, backend=backend, **opts)
        alone = est.run(truth)
        err = np.linalg.norm(alone.theta - truth) / np.linalg.norm(truth)
        assert alone.success and alone.iterations == 1 and err <= tol, (name, err, alone.message)
        # SCR + polish: as close as the polisher (IPOPT, tol 1e-12 on the relative misfit) stays on its own;
        # on the chain (Jacobian condition number ~1e5) that is ~1e-6, elsewhere machine precision
        polisher = est.polisher()
        own = np.linalg.norm(polisher.run(truth).theta - truth) / np.linalg.norm(truth)
        pol = est.run_polished(truth, polisher)
        err = np.linalg.norm(pol.theta - truth) / np.linalg.norm(truth)
        assert pol.success and err <= max(10 * own, tol), (name, err, own, pol.message)


def test_model_gamma_falls_back_to_random_draws_where_the_start_is_unusable():
    model, truth, data = two_dof()
    est = ScrFRF(model, data)
    at_zero = est._aux_start(np.zeros(6))  # M = V = K = 0: Z(θ₀) is singular
    g = np.stack([at_zero[v.name] for v in est.gamma_vars])
    assert np.all(np.isfinite(g)) and np.all(np.abs(g) > 0)
    at_truth = est._aux_start(truth)
    np.testing.assert_allclose(at_truth["Gamma3"], est._model_gamma(truth)[3], rtol=1e-12)


def test_trial_polishes_are_capped():
    """Every trial polish runs at most trial_max_iter IPOPT iterations; the final polish is not capped."""
    model, _, data = two_dof()
    polisher = IpoptFRF(model, data)
    calls = []
    run = polisher.run

    def spy(x0, **caps):
        out = run(x0, **caps)
        calls.append((caps.get("max_iter"), out.iterations))
        return out

    polisher.run = spy
    x0 = np.array([0.3, 0.05, 2.0, 0.01, 0.2, 3.0])  # far from the truth (4-20): early trials do not fit
    est = ScrFRF(model, data, trial_max_iter=7, max_iter=16, polish_misfit=1e-30)  # no trial accepted by misfit
    out = est.run_polished(x0, polisher)
    trials = [c for c in calls if c[0] is not None]
    assert [cap for cap, _ in trials] == [7] * len(trials) and len(trials) >= 2
    assert all(iters <= 7 for _, iters in trials)
    assert out.iterations >= sum(i for _, i in calls)
    with pytest.raises(si.OptionError, match="trial_max_iter must be an integer between 1 and"):
        ScrFRF(model, data, trial_max_iter=0)


# -- long runs talk, and stop on time ----------------------------------------------------------------

def test_progress_callback_and_verbose(capsys):
    model, _, data = two_dof()
    seen = []
    est = ScrFRF(model, data, callback=seen.append, verbose=True)
    x0 = make_starts(model, 1, 1)[0]
    out = est.run(x0)
    assert [p.iteration for p in seen] == list(range(1, out.iterations + 1))
    assert np.all(np.diff([p.elapsed for p in seen]) >= 0)
    assert seen[-1].misfit == pytest.approx(out.cost, rel=1e-12)  # the misfit of the returned θ
    np.testing.assert_array_equal(seen[-1].theta, out.theta)
    assert [p.residual for p in seen] == [h.residual for h in out.history]
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == out.iterations and lines[0].startswith("scr    iteration     1  residual")
    stopped = ScrFRF(model, data, callback=lambda p: p.iteration == 3).run(x0)  # a true return stops the start
    assert stopped.status == "stopped" and stopped.iterations == 3
    with pytest.raises(si.OptionError, match="callback must be a function of one ScrProgress"):
        ScrFRF(model, data, callback=3)
    with pytest.raises(si.OptionError, match="verbose must be True or False"):
        ScrFRF(model, data, verbose="yes")


@pytest.mark.parametrize("backend", ["admm", "cvxpy"])
def test_time_limit_cuts_the_iteration_under_way(backend):
    """A budget far below one SCR iteration stops inside it (ADMM keeps its inexact iterate, Clarabel's
    unfinished solve is discarded) instead of letting the start run on."""
    chain, th, w = physical_chain()
    data = si.simulate_frf(chain, th, w)
    x0 = th * np.array([2.0, 0.5, 1.5, 0.4, 2.5, 0.6, 1.8, 0.7, 2.2])
    opts = {"backend": backend, "scale": th}
    if backend == "admm":  # an ADMM sub-problem that would take 10⁵ inner iterations without the budget
        opts["admm"] = scr.ADMMOptions(inner_first=100_000, eps_abs=0.0, eps_rel=0.0, tighten=None)
    est = ScrFRF(chain, data, time_limit=0.05, **opts)
    sol = est.solve(x0)
    assert sol.status == "time_limit" and "cut short" in sol.message, sol.message
    assert sol.iterations <= 1
    if backend == "admm":
        assert sol.iterations == 1 and sol.info["inner_iterations"][0] < 100_000
        assert sol.history[0].timing["time_limit"]
    else:
        assert sol.iterations == 0 and "time limit" in sol.message
    out = est.run(x0)
    assert out.status == "time_limit" and not out.success


# -- units ---------------------------------------------------------------------------------------------

def rescaled(model, factors):
    """The same model with parameter k in units 1/factors[k] (θ'ₖ = factors[k]·θₖ: θₖ → θ'ₖ/factors[k] in
    every matrix)."""
    import sympy as sp

    subs = {p: p / sp.Float(f) for p, f in zip(model.parameters, factors, strict=True)}
    mats = {k: v.subs(subs) for k, v in model.symbolic.items()}
    if "M" in mats:
        return si.SecondOrderModel(**mats, output=model.output, parameters=list(model.parameters))
    return si.StateSpaceModel(**mats, parameters=list(model.parameters))


def lead_lag_free():
    """Lead-lag with every entry of A a parameter or zero (so time units can change): A = [[0, u], [a, b]]."""
    u, a, b, g, c = si.parameters("u a b g c")
    return si.StateSpaceModel(A=[[0, u], [a, b]], B=[[0], [g]], C=[[1, c]], D=[[0]])


UNIT_GRID = [(-6, 6, 0, 0), (0, 0, 6, -6), (0, 0, -6, 6), (-3, 5, 4, -6)]  # exponents of: the odd
# parameters, the even ones, ω, H (each of the three kinds to ±6, and all at once)


@pytest.mark.parametrize("kind", ["2dof", "lead-lag"])
@pytest.mark.parametrize("p_odd, p_even, p_w, p_h", UNIT_GRID)
def test_scr_estimate_moves_with_the_units(kind, p_odd, p_even, p_w, p_h):
    """Parameters, the frequency axis and the response rescaled by powers of ten (1e-6 … 1e6): with the
    automatic scale from the start (the default), SCR's estimate from the same physical start is the same
    physical estimate, in the new units. The data carry 1 % noise, so the estimate is not simply the truth."""
    if kind == "2dof":
        model, truth, exact = two_dof()
        w = np.asarray(exact.w)
    else:
        model, truth = lead_lag_free(), np.array([1.0, -2.0, -0.4, 1.5, 0.5])
        w = np.logspace(-0.5, 0.7, 12)
    data = si.simulate_frf(model, truth, w, noise=1e-2, seed=3)
    x0 = truth * np.array([1.6, 0.7, 1.3, 0.8, 1.2, 0.9][: truth.size])
    f = 10.0 ** np.where(np.arange(truth.size) % 2, p_even, p_odd)
    c_w, c_h = 10.0**p_w, 10.0**p_h  # ω' = c_w ω (time in 1/c_w of the old unit), H' = c_h H
    if kind == "2dof":  # −ω'²M' + jω'V' + K' = (−ω²M + jωV + K)/c_h: M' = M/(c_h c_w²), V' = V/(c_h c_w), K' = K/c_h
        phys = np.array([1 / (c_h * c_w**2)] * 2 + [1 / (c_h * c_w)] * 2 + [1 / c_h] * 2)
    else:  # A' = c_w A, B' = c_w c_h B (the gain g), C and D as they are
        phys = np.array([c_w, c_w, c_w, c_w * c_h, 1.0])
    model2 = rescaled(model, f)
    theta_map = f * phys  # θ' of a θ: the unit change of each parameter times the physical one
    data2 = si.FrequencyData(w * c_w, np.asarray(data.H) * c_h)
    # 25 SCR iterations: every iterate, not only a converged one, must map (and the test stays fast)
    ref = ScrFRF(model, data, max_iter=25).run(x0)
    out = ScrFRF(model2, data2, max_iter=25).run(x0 * theta_map)
    assert out.status == ref.status and out.iterations == ref.iterations, (ref.message, out.message)
    # the same arithmetic in other units: rounding (1e-16) amplified over 25 iterations, not a tolerance of SCR
    np.testing.assert_allclose(out.theta / theta_map, ref.theta, rtol=1e-7)
    assert out.cost == pytest.approx(ref.cost, rel=1e-7)


def test_scr_returns_the_iterate_that_fits_best_not_the_last():
    # Found by a new-user sweep: a quarter car driven through the tyre, 1 % noise, started two decades off with
    # scale= the truth. SCR's iterates pass misfit 5.0 at iteration 3 and end at 25.5 (worse than the start's 20.5);
    # the last iterate was returned. The engine's last iterate minimises its relaxation, not the data misfit.
    mu, cs, ks, kt = si.parameters("mu cs ks ktyre", positive=True)
    model = si.SecondOrderModel(M=[[300.0, 0], [0, mu]], V=[[cs, -cs], [-cs, cs]], K=[[ks, -ks], [-ks, ks + kt]],
                                B=[[0], [kt]], C=[[1, 0]])
    truth = np.array([40.0, 1500.0, 2.0e4, 2.0e5])
    frf = si.simulate_frf(model, truth, 2 * np.pi * np.logspace(-1, 1.5, 60), noise=0.01, seed=1)
    seen = []
    res = si.identify(model, frf, method="scr", x0=truth * 100.0 ** np.array([1, -1, 1, -1]), scale=truth,
                      max_iter=60, identifiability_check=False, callback=lambda p: seen.append(p.misfit))
    assert res.cost == pytest.approx(min(seen), rel=1e-9)  # the best iterate, on any path
    if int(np.argmin(seen)) < len(seen) - 1:  # measured here: best at iteration 3 of 60, 0.18 times the last
        assert res.cost < seen[-1]
        assert "the estimate is iteration" in res.message


def test_a_declared_positive_parameter_below_zero_is_projected_onto_the_bound():
    # Found by a new-user trial: ADMM met θ ≥ 0 only to its tolerance and reported mu = -0.0033 (1e-5 of the
    # parameter's size) for a mass declared positive. The engine's answer is stubbed here (status, message, no
    # history) so that the test sees only what solved_outcome does with a slightly negative θ. Reference: the
    # exact data of the quarter car at the truth, whose misfit is 0 to rounding.
    from types import SimpleNamespace

    mu, cs, ks, kt = si.parameters("mu cs ks ktyre", positive=True)
    model = si.SecondOrderModel(M=[[300.0, 0], [0, mu]], V=[[cs, -cs], [-cs, cs]], K=[[ks, -ks], [-ks, ks + kt]],
                                B=[[0], [kt]], C=[[1, 0]])
    truth = np.array([40.0, 1500.0, 2.0e4, 2.0e5])
    frf = si.simulate_frf(model, truth, 2 * np.pi * np.logspace(-1, 1.5, 60))
    est = ScrFRF(model, frf)
    sol = SimpleNamespace(status="converged", message="converged", iterations=7, info={}, history=[], iterates=[])
    theta = truth.copy()
    theta[1] = -1e-3
    out = est.solved_outcome(truth, theta, sol, 0.0, history=())
    np.testing.assert_array_equal(out.theta, [40.0, 0.0, 2.0e4, 2.0e5])
    assert "projected onto the bound 0 of parameters declared positive: cs (was -0.001)" in out.message
    assert out.cost == pytest.approx(est.misfit(out.theta), rel=1e-12)
    assert "not physical" not in out.fit
    out = est.solved_outcome(truth, truth, sol, 0.0, history=())  # nothing below 0: nothing projected
    np.testing.assert_array_equal(out.theta, truth)
    assert "projected" not in out.message
