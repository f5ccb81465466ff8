"""si.validate (issue 15, item 4): fit per output, simulated vs measured, residual tests, figures.

References: the fit is MATLAB compare's normalised rms fit 100 (1 − ‖y − ŷ‖ / ‖y − mean y‖), recomputed here with
numpy; for additive white noise of standard deviation ε·std(y) (si.simulate_io) the true model's fit is about
100 (1 − ε). The whiteness statistic is Ljung–Box (χ²(M) for white residuals) and the independence statistic
Ljung, System Identification, 2nd ed., (16.58)–(16.60).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import symid as si
from symid.errors import DataError

TRUTH = {"m": 2.0, "c": 0.5, "k": 3.0}


def mck(B=((1,),)):
    m, c, k = si.parameters("m c k", positive=True)
    return si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[list(r) for r in B], C=[[1]])


def white_input_record(model, noise=0.02, seed=1, n=2000):
    u = np.random.default_rng(1000 + seed).standard_normal(n)  # not the noise's seed: they would be equal
    return si.simulate_io(model, TRUTH, u, dt=0.1, noise=noise, seed=seed)


def test_true_model_fits_and_leaves_white_independent_residuals():
    model = mck()
    io = white_input_record(model)
    v = si.validate(model, TRUTH, io)
    y, ys = io.y[:, 0], v.y_sim[0][:, 0]
    ref = 100 * (1 - np.linalg.norm(y - ys) / np.linalg.norm(y - y.mean()))
    np.testing.assert_allclose(v.fit_percent, [ref], rtol=1e-12)
    assert 97.5 < v.fit_percent[0] < 98.5  # 2 % noise
    np.testing.assert_allclose(v.rms_error, [np.sqrt(np.mean((y - ys) ** 2))], rtol=1e-12)
    assert v.white[0] and v.independent[0, 0]
    assert "white and independent" in v.summary()
    json.dumps(v.to_dict())


def test_wrong_model_is_caught_by_the_tests():
    """Damping off by 80 %: residual not white; a gain off by 10 % (white input): residual correlated with u."""
    model = mck()
    io = white_input_record(model)
    wrong_c = si.validate(model, {**TRUTH, "c": 0.9}, io)
    assert not wrong_c.white[0] and "NOT white" in wrong_c.summary()
    m, c, k, g = si.parameters("m c k g", positive=True)
    gained = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[g]], C=[[1]])
    wrong_g = si.validate(gained, {**TRUTH, "g": 1.1}, io)
    assert not wrong_g.independent[0, 0] and wrong_g.independence_p[0, 0] < 1e-6


def test_constant_input_several_records_and_estimated_initial_state(tmp_path):
    model = mck(B=((1, 1),))
    u = np.column_stack([np.sign(np.sin(0.05 * np.arange(600))), np.ones(600)])
    recs = [si.simulate_io(model, TRUTH, u, dt=0.1, noise=0.02, seed=s, x0=[0.3 * s, 0.0]) for s in (1, 2)]
    v = si.validate(model, TRUTH, recs, initial_state="estimate")
    assert np.all(np.isnan(v.cross_correlation[0, 1])) and v.independent[0, 1]
    assert any("constant" in n for n in v.notes) and any("2 records pooled" in n for n in v.notes)
    np.testing.assert_allclose(v.initial_states[1], [0.3 * 2, 0.0], atol=0.05)
    assert v.fit_percent[0] > 97
    at_rest = si.validate(model, TRUTH, recs)
    assert at_rest.fit_percent[0] < v.fit_percent[0]
    assert "input(s) 1 constant: no cross-correlation" in v.notes
    # read from a table, the note names the column (a new user's "input(s) 2 constant" beside named tables)
    path = tmp_path / "record.csv"
    np.savetxt(path, np.column_stack([recs[0].t, u, recs[0].y]), delimiter=",", header="t,valve,one,y", comments="")
    named = si.IOData.from_table(path, columns={"time": "t", "input": ["valve", "one"], "output": "y"},
                                 units={"time": "s"})
    assert "input(s) 'one' constant: no cross-correlation" in si.validate(model, TRUTH, named).notes


def test_non_uniform_samples_are_said():
    model = mck()
    io = white_input_record(model, n=400)
    idx = np.sort(np.random.default_rng(0).choice(400, 300, replace=False))
    ts = si.TimeSeries(io.t[idx], io.u[idx], io.y[idx])
    v = si.validate(model, TRUTH, ts, initial_state="estimate")
    assert any("not uniform" in n for n in v.notes)


def test_figures_are_written(tmp_path):
    model = mck()
    v = si.validate(model, TRUTH, white_input_record(model, n=500))
    first, second = v.plot(tmp_path / "val.png", output_names=["position"], output_units=["m"],
                           input_names=["force"], title="mass-spring-damper")
    for f in (first, second):
        assert f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and f.stat().st_size > 10_000
    assert first.name == "val_output.png" and second.name == "val_residual.png"
    with pytest.raises(DataError, match="expected 1 name"):
        v.plot(tmp_path / "x", output_units=["m", "s"])


def test_bad_arguments_are_named_errors():
    model = mck()
    io = white_input_record(model, n=100)
    with pytest.raises(DataError, match="max_lag"):
        si.validate(model, TRUTH, io, max_lag=0)
    with pytest.raises(DataError, match="longer than 200"):
        si.validate(model, TRUTH, io, max_lag=200)
    with pytest.raises(DataError, match="confidence"):
        si.validate(model, TRUTH, io, confidence=0.9)
    with pytest.raises(DataError, match="IOData, TimeSeries"):
        si.validate(model, TRUTH, si.simulate_frf(model, TRUTH, [1.0, 2.0]))


def test_tests_reject_the_true_model_about_once_in_a_hundred():
    """At 99 % the true model fails each test in about 1 % of records (measured over 300: 0.7 % and 0.3 %);
    over 200 records at most 3 % (binomial: exceeded by chance about once in 200 runs)."""
    model = mck()
    white, independent = [], []
    for seed in range(200):
        v = si.validate(model, TRUTH, white_input_record(model, seed=seed, n=1000))
        white.append(v.white[0])
        independent.append(v.independent[0, 0])
    assert 1 - np.mean(white) <= 0.03 and 1 - np.mean(independent) <= 0.03


def test_the_independence_test_holds_its_level_for_a_slowly_varying_input():
    """A PRBS held for 20 samples: its cross-correlation lags are correlated with each other, and S must weigh them
    by their covariance (module notes). Summed as if independent, the true model was rejected in 27 of 200 records
    (13.5 % at the 99 % level); measured now 1 of 200. Over 100 records at most 4 (binomial at 1 %: exceeded by chance
    about once in 300 runs); a gain 10 % off is still rejected in each of 10 records (measured p ≤ 4.7e-6)."""
    k, g = si.parameters("k g", positive=True)
    model = si.StateSpaceModel(A=[[-k]], B=[[g]], C=[[1]])
    truth = {"k": 0.5, "g": 2.0}
    rejected, wrong = 0, []
    for seed in range(100):
        u = np.repeat(np.random.default_rng(seed).choice([-1.0, 1.0], 51), 20)[:1000]
        io = si.simulate_io(model, truth, u, dt=0.1, noise=0.05, seed=1000 + seed)
        rejected += int(not si.validate(model, truth, io).independent[0, 0])
        if seed < 10:
            wrong.append(si.validate(model, {**truth, "g": 2.2}, io).independence_p[0, 0])
    assert rejected <= 4
    assert max(wrong) < 1e-3


def test_a_sampled_band_limited_input_is_simulated_linear_between_samples_with_hold_foh():
    """A sum of sines (not held) through the true model, acceleration with 2 % noise, its steady state computed
    exactly (a new user's trial: the true model rejected, fit 68–78 %): taken as held, the simulation errs by the
    hold and the fit is 80 %; linear between samples, 97.3 % when this test was written (the noise alone leaves
    98 %). Asserted: hold="foh" within 1.5 points of the noise's limit and above "zoh" by 10; a bad hold is named.
    Reference: the model's exact frequency response at the sines' frequencies."""
    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]], output="acceleration")
    truth = {"m": 1.0, "c": 0.4, "k": 100.0}  # 10 rad/s
    rng = np.random.default_rng(0)
    freqs, phases = rng.uniform(1, 12, 40), rng.uniform(0, 2 * np.pi, 40)
    t = np.arange(3000) * 0.04
    H = model.frequency_response(truth, freqs)[:, 0, 0]
    u = np.sin(np.outer(t, freqs) + phases).sum(axis=1)
    y = (np.abs(H) * np.sin(np.outer(t, freqs) + phases + np.angle(H))).sum(axis=1)
    y = y + 0.02 * np.std(y) * rng.standard_normal(y.shape)
    io = si.IOData(u, y, 0.04)
    held = si.validate(model, truth, io, initial_state="estimate").fit_percent[0]
    linear = si.validate(model, truth, io, initial_state="estimate", hold="foh").fit_percent[0]
    assert linear >= 98.0 - 1.5 and linear >= held + 10, (held, linear)
    with pytest.raises(DataError, match=r"hold must be 'zoh' .* 'foh' .* or 'bandlimited'"):
        si.validate(model, truth, io, hold="linear")


def _infusion_records(seed: int, wrong: bool = False):
    """One-compartment infusion (ke = 0.2 /h, q = 1/V = 0.025 /L; two infusions of 500 mg/h), 48 h sampled every
    15 min, 15 % proportional noise on the concentration: a new user's dose-response records."""
    ke, q = si.parameters("ke q", positive=True)
    model = si.StateSpaceModel(A=[[-ke]], B=[[q]], C=[[1]])
    t = np.arange(0, 48.125, 0.25)
    u = np.where(t < 2, 500.0, 0.0) + np.where((t >= 12) & (t < 13), 500.0, 0.0)
    y0 = si.simulate_io(model, {"ke": 0.2, "q": 0.025}, u, 0.25).y[:, 0]
    y = y0 * (1 + 0.15 * np.random.default_rng(2000 + seed).standard_normal(t.size))
    return model, si.TimeSeries(t, u[:, None], y[:, None], time_unit="h")


def test_residual_tests_standardise_by_the_error_model_under_proportional_noise():
    """A new user's trial: under 15 % proportional noise si.validate called the true model's residual coloured in
    30 of 30 records (y − ŷ is large where the concentration is, small where it is not: not white). With the
    error model, the tests run on (y − ŷ)/σ(ŷ): the true model passes both at 99 % in at least 27 of 30 records
    (binomial, 1 % rejections: fewer than 27 has probability below 1e-3), and a wrong elimination rate (half)
    is still rejected in every record. The first sample, 0 before the infusion, has no noise under a proportional
    model: with σ from the prediction that is no error (it was one for the fit's first weights)."""
    error_model = {"proportional": 0.15}
    plain, standardised, wrong = 0, 0, 0
    for seed in range(30):
        model, ts = _infusion_records(seed)
        p = si.validate(model, {"ke": 0.2, "q": 0.025}, ts)
        plain += bool(p.white[0] and p.independent[0, 0])
        v = si.validate(model, {"ke": 0.2, "q": 0.025}, ts, variance=error_model)
        standardised += bool(v.white[0] and v.independent[0, 0])
        w = si.validate(model, {"ke": 0.1, "q": 0.025}, ts, variance=error_model)
        wrong += bool(w.white[0] and w.independent[0, 0])
    assert plain <= 3, plain  # 0 of 30 when this test was written
    assert standardised >= 27, standardised
    assert wrong == 0, wrong
    assert any("residual tests on (y − ŷ)/σ" in n for n in v.notes)


def test_a_failure_near_the_level_is_said_to_be_possibly_chance():
    """A new user's trial: the true structure got "dynamics not captured" (p = 0.0058) beside success True, and
    nothing said that chance is a reading. Records 7 and 90 of the true one-mass model fail one test at p 0.0091
    and 0.0018 (within a factor 10 of the 1 % level): the verdict says how often a true model fails one of the
    tests; record 22 fails at p 3.5e-4, beyond that, and is not excused."""
    model = mck()
    for seed, marginal in ((7, True), (90, True), (22, False)):
        summary = si.validate(model, TRUTH, white_input_record(model, seed=seed, n=1000)).summary()
        verdict = next(line for line in summary.splitlines() if line.startswith("verdict"))
        assert ("marginal" in verdict) == marginal, verdict
        if marginal:
            assert "a true model fails one of these 2 tests in 2 % of records" in verdict


def test_the_summary_names_the_channels_by_the_tables_columns(tmp_path):
    """A new user's trial: the command line named the channels, Python's si.validate(...).summary() said 0 and 1.
    A record read from a table keeps its columns (io.stated_units), and the summary uses them."""
    model = mck()
    io = white_input_record(model, n=300)
    rows = "\n".join(f"{0.1 * k:.1f},{u!r},{y!r}" for k, (u, y) in enumerate(zip(io.u[:, 0].tolist(),
                                                                                  io.y[:, 0].tolist(), strict=True)))
    (tmp_path / "rec.csv").write_text(f"t,force,position\n{rows}\n")
    rec = si.IOData.from_table(str(tmp_path / "rec.csv"), columns={"time": "t", "input": "force",
                                                                    "output": "position"}, units={"time": "s"})
    assert rec.stated_units == {"input": (("force", None),), "output": (("position", None),),
                                "file": repr(str(tmp_path / "rec.csv"))}
    text = si.validate(model, TRUTH, rec).summary()
    assert "position" in text.splitlines()[2] and "force" in text
