"""Output spectra from Welch averages weighed by their scatter (symid.fit.spectra.welch).

Reference values: a Welch average of K segments has Var Φ̂ⱼₖ = Φⱼⱼ Φₖₖ / K (complex Wishart, Percival &
Walden 1993, §6.7), with K the averages the overlapping segments are worth (Welch 1967; Hann at 50 %
overlap about 0.947 K, ``tests/test_estimate_spectra.py``). The frame below is that file's (thesis (4-19) at
laboratory scale, positions of both masses, a white force on mass 1 of known intensity).
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import symid as si
from symid.fit.spectra.ipopt import IpoptPSD
from symid.fit.spectra.welch import WELCH_FLOOR_MARGIN, spectra_averages, welch_noise_floor
from symid.signal.frf import effective_averages

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_estimate_spectra import BAND, DT, PHI, TRUTH, frame_model  # the same frame

RECORDS = 6
SECONDS = 60.0
NPERSEG = 4096


def _record(seed: int) -> np.ndarray:
    model = frame_model()
    skip, n = round(2.0 / DT), round(SECONDS / DT)
    force = np.random.default_rng(seed).standard_normal(skip + n) * np.sqrt(PHI / DT)
    return si.simulate_io(model, TRUTH, force, DT).y[skip:]


@pytest.fixture(scope="module")
def records():
    """Output-only Welch spectra of RECORDS independent minutes of the frame."""
    return [si.estimate_spectra(_record(seed), dt=DT, Phi_uu=PHI, band=BAND, nperseg=NPERSEG)
            for seed in range(RECORDS)]


def test_auto_weighs_welch_spectra_and_judges_them_by_their_averages(records):
    model, spec = frame_model(), records[0]
    res = si.identify(model, spec, x0=model.theta_vector(TRUTH) * 1.5, identifiability_check=False)
    samples = round(SECONDS / DT)
    K = (samples - NPERSEG // 2) // (NPERSEG // 2)
    assert res.options["weighting"] == "variance"
    np.testing.assert_allclose(res.options["averages"], effective_averages("hann", NPERSEG, NPERSEG // 2, K),
                               rtol=1e-12)
    assert res.success and "scatter" in res.cost_kind and "noise floor" in res.fit
    # the fit's misfit lies near what the averages' scatter leaves: within the margin, above a third of it
    floor = float(res.fit.split("noise floor ")[1].split(" ")[0]) / WELCH_FLOOR_MARGIN
    assert floor / 3 < res.cost < WELCH_FLOOR_MARGIN * floor


def test_weights_cut_the_scatter_of_the_estimates(records):
    """Over 6 records the masses' and springs' rms errors were 4.6-6.4 % with equal weights (IPOPT from the truth:
    the least-squares estimate) and 1.3-1.7 % weighted (measured when written); asserted: under 0.6 times; and the
    intervals hold the truth about as often as they say."""
    model = frame_model()
    truth = model.theta_vector(TRUTH)
    none, weighted, covered = [], [], []
    for spec in records:
        none.append(IpoptPSD(model, spec).run(truth).theta / truth - 1)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = si.identify(model, spec, x0=truth * 1.5, identifiability_check=False, progress=False)
        assert res.success
        weighted.append(res.theta_vector / truth - 1)
        lo, hi = np.asarray(res.uncertainty.intervals).T
        covered.extend((lo <= truth) & (truth <= hi))
    # the 95 % intervals, with the Welch entries' correlation (SpectraFisher.residual_correlation): 34 of 36 held the
    # truth here; taken as independent, 23 of 36
    assert np.mean(covered) >= 0.85
    rms_none = np.sqrt(np.mean(np.square(none), axis=0))
    rms_weighted = np.sqrt(np.mean(np.square(weighted), axis=0))
    masses_springs = [model.parameter_names.index(n) for n in ("m1", "m2", "k1", "k2")]
    assert np.all(rms_weighted[masses_springs] < 0.6 * rms_none[masses_springs]), (rms_weighted, rms_none)


def test_exact_spectra_are_fitted_exactly_in_the_variance_weights():
    model = frame_model()
    truth = model.theta_vector(TRUTH)
    spec = si.simulate_spectra(model, truth, np.linspace(BAND[0], BAND[1], 80), Phi_uu=PHI)
    out = IpoptPSD(model, spec, weighting="variance").run(truth * 1.3)
    np.testing.assert_allclose(out.theta, truth, rtol=1e-6)
    assert out.success and "reweighted" in out.message


def test_spectra_from_elsewhere_take_averages_to_be_weighted(records):
    model = frame_model()
    plain = si.SpectralData(records[0].w, records[0].Phi_yy, records[0].Phi_uu)  # a copy keeps no metadata
    assert spectra_averages(plain) is None
    res = si.identify(model, plain, x0=model.theta_vector(TRUTH), identifiability_check=False, restarts=0,
                      scr=False)
    assert res.options["weighting"] == "none" and "scatter" not in res.cost_kind
    res = si.identify(model, plain, x0=model.theta_vector(TRUTH), identifiability_check=False, averages=26.0)
    assert res.options["weighting"] == "variance" and res.options["averages"] == 26.0
    assert res.success


def test_the_noise_floor_is_the_scatter_over_the_weighted_data():
    """A lone line per frequency: Σ w Φ̂ⱼⱼ Φ̂ₖₖ / K over Σ w |Φ̂|² is 1/K whatever the weights."""
    spec = si.SpectralData([1.0, 2.0, 3.0], [[[2.0]], [[8.0]], [[0.5]]], np.ones(3))
    for w in ([1.0, 1.0, 1.0], [0.25, 1 / 64, 4.0]):
        assert welch_noise_floor(spec, np.asarray(w)[:, None, None], averages=40.0) == pytest.approx(1 / 40, rel=1e-12)


def test_measured_input_spectra_are_not_given_a_number_of_averages():
    model = frame_model()
    force = np.random.default_rng(0).standard_normal(20_000) * np.sqrt(PHI / DT)
    io = si.simulate_io(model, TRUTH, force, DT)
    assert spectra_averages(si.estimate_spectra(io, band=BAND, nperseg=2048)) is None
    assert spectra_averages(si.estimate_spectra(io.y, dt=DT, Phi_uu=PHI, band=BAND, nperseg=2048)) > 1


@pytest.mark.parametrize("kwargs, match", [
    ({"method": "ipopt", "weighting": "variance", "objective": "equation"}, "objective='output'"),
    ({"method": "ipopt", "weighting": "relative"}, "weighting"),
    ({"method": "auto", "weighting": "frequency"}, "weighting"),
    ({"method": "auto", "averages": 0.5}, "averages"),
    ({"method": "ipopt", "weighting": "variance", "averages": -3}, "averages"),
])
def test_bad_weighting_options_are_named(records, kwargs, match):
    model = frame_model()
    with pytest.raises(si.OptionError, match=match):
        si.identify(model, records[0], x0=model.theta_vector(TRUTH), identifiability_check=False, **kwargs)


def test_white_sensor_noise_is_fitted_beside_the_model():
    """Position sensors with white noise of 30 % of each output's standard deviation: the model's spectra fall far
    below that floor above the modes. Fitted as a nuisance unknown, the noise's level is found (a sampled white
    sequence of variance σ² has the two-sided density σ²·dt, module notes of symid.signal.spectra: measured 5 % and
    2 % low) and the masses and springs stay within 1 % (measured: at most 0.3 %; the dampers, which one minute
    determines less well, 8 % and 4 %, as without the noise); without it the fit fails (the variance weights let
    those lines carry it), its masses and springs 3-6 % off."""
    model = frame_model()
    truth = model.theta_vector(TRUTH)
    y = _record(0)
    sigma = 0.3 * y.std(axis=0)
    y = y + sigma * np.random.default_rng(99).standard_normal(y.shape)
    spec = si.estimate_spectra(y, dt=DT, Phi_uu=PHI, band=BAND, nperseg=NPERSEG)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = si.identify(model, spec, x0=truth * 1.5, identifiability_check=False, progress=False)
        bare = si.identify(model, spec, x0=truth * 1.5, identifiability_check=False, progress=False,
                           sensor_noise=False, restarts=0, scr=False)  # one pass: its failure, not the rescue
    assert res.options["sensor_noise"] and res.success
    masses_springs = [model.parameter_names.index(n) for n in ("m1", "m2", "k1", "k2")]
    np.testing.assert_allclose(res.theta_vector[masses_springs], truth[masses_springs], rtol=0.01)
    lo, hi = np.asarray(res.uncertainty.intervals).T
    assert np.all((lo <= truth) & (truth <= hi))
    np.testing.assert_allclose(res.options["sensor_noise_levels"], sigma**2 * DT, rtol=0.1)
    assert "sensor noise" in res.summary()
    assert not bare.success


def test_welch_spectra_keep_their_averages_through_a_csv_file(records, tmp_path):
    """A new user's spectra saved (to_csv) and refitted lost `estimated_from`: the refit fell back to equal weights
    and accepted a local minimum (a mass 430 times its value). The file now carries how they were estimated."""
    path = tmp_path / "spec.csv"
    records[0].to_csv(path)
    back = si.SpectralData.from_csv(path)
    assert back.estimated_from == pytest.approx(records[0].estimated_from)
    assert spectra_averages(back) == pytest.approx(spectra_averages(records[0]), rel=1e-12)
    text = path.read_text(encoding="utf-8")
    broken = text.replace("# welch_window: hann", "# welch_window: __import__('os')")
    (tmp_path / "bad.csv").write_text(broken, encoding="utf-8")
    with pytest.raises(si.DataError, match=r"welch_window.*not a window"):
        si.SpectralData.from_csv(tmp_path / "bad.csv")
    partial = "\n".join(line for line in text.splitlines() if not line.startswith("# welch_dt")) + "\n"
    (tmp_path / "partial.csv").write_text(partial, encoding="utf-8")
    with pytest.raises(si.DataError, match=r"incomplete \(missing welch_dt\)"):
        si.SpectralData.from_csv(tmp_path / "partial.csv")


def test_spectra_of_many_lines_are_said_to_be_slow():
    """A new user's default Welch estimate (8190 lines, two outputs) ran one IPOPT iteration in 300 s. Beyond
    MANY_LINES lines IPOPT and auto say so and how to keep the lines around the modes."""
    from symid.fit.spectra import MANY_LINES, prepare

    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    spec = si.simulate_spectra(model, [1.0, 0.5, 4.0], np.linspace(0.5, 3, MANY_LINES + 1), Phi_uu=1.0)
    with pytest.warns(si.DataWarning, match=r"2001 lines: .* band=\(w_low, w_high\), n_frequencies=500"):
        prepare(model, spec, "ipopt", {})
    few = si.simulate_spectra(model, [1.0, 0.5, 4.0], np.linspace(0.5, 3, MANY_LINES), Phi_uu=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", si.DataWarning)
        prepare(model, few, "ipopt", {})
