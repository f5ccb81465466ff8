"""si.estimate_frf / si.estimate_coherence: H1, H2 and periodic averaging against theory, by Monte Carlo.

Reference values:
- periodic averaging of P periods, output noise of variance σ² per sample and a line of
  DFT amplitude |U|: var Ĥ = N σ² / (P |U|²) (a white sequence of N samples has
  E|X_k|² = N σ² under numpy's unnormalised DFT); with input noise σᵤ² the first-order
  value (σ² + |H|² σᵤ²) N / (P |U|²) (Pintelon & Schoukens 2012, §2.4);
- the sample variance of P periods has ν = 2(P − 1) real degrees of freedom, so that
  |Ĥ − H|² / var̂ ~ F(2, ν) for Gaussian output noise, whose mean is ν / (ν − 2);
- Welch H1: var Ĥ = (1 − γ²) Syy [Suu⁻¹]_jj / (n_eff − m) (Bendat & Piersol 2010, §9.2),
  checked against the spread of Ĥ over independent records;
- coherence of y = H u + n: γ² = |H|² Suu / (|H|² Suu + Snn).
Tolerances are stated in standard deviations of the Monte-Carlo mean at each test.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.signal

import symid as si
from symid.errors import DataError
from symid.signal.frf import effective_averages

DT = 0.01
B_IIR, A_IIR = [0.05, 0.03], [1.0, -1.6, 0.8]  # a lightly damped second-order discrete filter
PERIOD, LINES = 512, np.arange(3, 120, 2)  # an odd multisine on 59 lines
AMP = PERIOD / 10  # DFT amplitude of every excited line


def _h_iir(w):
    zi = np.exp(-1j * w * DT)
    return np.polyval(B_IIR[::-1], zi) / np.polyval(A_IIR[::-1], zi)


def _multisine(rng, periods):
    U = np.zeros(PERIOD // 2 + 1, complex)
    U[LINES] = AMP * np.exp(2j * np.pi * rng.random(LINES.size))
    return np.tile(np.fft.irfft(U, PERIOD), periods)


def _band_of_lines():
    w = 2 * np.pi * LINES / (PERIOD * DT)
    return (0.99 * w[0], 1.01 * w[-1])


def _periodic_runs(rng, R, P, sig_u, sig_y):
    H, V = [], []
    for _ in range(R):
        u0 = _multisine(rng, P + 1)
        y0 = scipy.signal.lfilter(B_IIR, A_IIR, u0)
        io = si.IOData(u0 + sig_u * rng.standard_normal(u0.size), y0 + sig_y * rng.standard_normal(u0.size), DT)
        frf = si.estimate_frf(io, period=PERIOD, transient_periods=1, band=_band_of_lines(), min_excitation=0.05)
        H.append(frf.H[:, 0, 0])
        V.append(frf.variance[:, 0, 0])
    return frf.w, np.array(H), np.array(V)


@pytest.mark.parametrize(("sig_u", "sig_y"), [(0.0, 0.05), (0.02, 0.05)])
def test_periodic_variance_matches_theory(sig_u, sig_y):
    rng = np.random.default_rng(10)
    R, P = 200, 8
    w, H, V = _periodic_runs(rng, R, P, sig_u, sig_y)
    assert w.size == LINES.size
    Ht = _h_iir(w)
    theory = PERIOD * (sig_y**2 + np.abs(Ht) ** 2 * sig_u**2) / (P * AMP**2)
    # estimated variance: each var̂/theory ~ χ²_14/14 (sd 0.38); the mean of R·s = 11 800 has sd 0.0035
    assert np.mean(V / theory) == pytest.approx(1.0, abs=0.02)
    # the spread of Ĥ over the R records: per line sd 1/√R = 0.071, over 59 lines sd 0.0092
    emp = np.mean(np.abs(H - Ht) ** 2, axis=0)
    assert np.mean(emp / theory) == pytest.approx(1.0, abs=0.05)
    # no bias beyond the noise: the mean over R records is within 4.5 standard errors at every line
    assert np.all(np.abs(H.mean(axis=0) - Ht) <= 4.5 * np.sqrt(theory / R))
    if sig_u == 0:
        # |Ĥ − H|²/var̂ ~ F(2, 14): mean 14/12 (sd 1.38; the mean of 11 800 has sd 0.013)
        assert np.mean(np.abs(H - Ht) ** 2 / V) == pytest.approx(14 / 12, abs=0.065)


def test_periodic_noise_free_is_exact_and_single_period_has_no_variance():
    rng = np.random.default_rng(0)
    u = _multisine(rng, 4)
    y = scipy.signal.lfilter(B_IIR, A_IIR, u)
    frf = si.estimate_frf(si.IOData(u, y, DT), period=PERIOD, transient_periods=1, band=_band_of_lines())
    np.testing.assert_allclose(frf.H[:, 0, 0], _h_iir(frf.w), rtol=1e-9)
    assert np.all(frf.variance <= 1e-18 * np.abs(frf.H) ** 2)
    one = si.estimate_frf(si.IOData(u, y, DT), period=PERIOD, transient_periods=3, band=_band_of_lines())
    assert one.variance is None
    np.testing.assert_allclose(one.H[:, 0, 0], _h_iir(one.w), rtol=1e-9)


def _welch_runs(rng, R, est, sig_u, sig_y, N=2**14, nperseg=256):
    b = [0.5, -0.3, 0.2]
    H, V = [], []
    for _ in range(R):
        u0 = rng.standard_normal(N)
        y0 = scipy.signal.lfilter(b, [1.0], u0)
        io = si.IOData(u0 + sig_u * rng.standard_normal(N), y0 + sig_y * rng.standard_normal(N), DT)
        frf = si.estimate_frf(io, nperseg=nperseg, estimator=est)
        H.append(frf.H[:, 0, 0])
        V.append(frf.variance[:, 0, 0])
    Ht = np.polyval(b[::-1], np.exp(-1j * frf.w * DT))
    return frf.w, np.array(H), np.array(V), Ht


@pytest.mark.parametrize(("est", "sig_u", "sig_y"), [("h1", 0.0, 0.3), ("h2", 0.05, 0.0)])
def test_welch_variance_matches_the_spread_of_estimates(est, sig_u, sig_y):
    rng = np.random.default_rng(11)
    R = 100
    w, H, V, Ht = _welch_runs(rng, R, est, sig_u, sig_y)
    assert w.size == 126  # bins 2 … 127 of 256 (DC, the detrend-biased bin 1 and Nyquist dropped)
    emp = np.mean(np.abs(H - Ht) ** 2, axis=0)
    # per line sd 1/√R = 0.1; neighbouring Hann bins are correlated, so ≈ 63 independent lines: sd 0.013
    assert np.mean(emp / V.mean(axis=0)) == pytest.approx(1.0, abs=0.06)
    assert np.mean(np.abs(H - Ht) ** 2 / V) == pytest.approx(1.0, abs=0.06)
    # H1 is unbiased for output noise, H2 for input noise: mean within 4.5 standard errors at every line
    assert np.all(np.abs(H.mean(axis=0) - Ht) <= 4.5 * np.sqrt(emp / R))


def test_h1_is_biased_by_input_noise_and_h2_is_not():
    rng = np.random.default_rng(3)
    N, b, sig_u = 2**15, [1.0, 0.5], 0.5
    u0 = rng.standard_normal(N)
    io = si.IOData(u0 + sig_u * rng.standard_normal(N), scipy.signal.lfilter(b, [1.0], u0), DT)
    h1 = si.estimate_frf(io, nperseg=128)
    h2 = si.estimate_frf(io, nperseg=128, estimator="h2")
    Ht = np.polyval(b[::-1], np.exp(-1j * h1.w * DT))
    # H1 = H Suu0 / (Suu0 + σᵤ²) = H / 1.25 (Bendat & Piersol §9.1); H2 unbiased
    assert np.median(np.abs(h1.H[:, 0, 0] / Ht)) == pytest.approx(1 / (1 + sig_u**2), rel=0.02)
    assert np.median(np.abs(h2.H[:, 0, 0] / Ht)) == pytest.approx(1.0, rel=0.02)


def test_welch_coherence_matches_signal_to_noise_ratio():
    rng = np.random.default_rng(4)
    N, sig = 2**16, 0.5
    u = rng.standard_normal(N)
    b = [0.5, -0.3, 0.2]
    io = si.IOData(u, scipy.signal.lfilter(b, [1.0], u) + sig * rng.standard_normal(N), DT)
    w, coh = si.estimate_coherence(io, nperseg=256)
    Ht = np.polyval(b[::-1], np.exp(-1j * w * DT))
    theory = np.abs(Ht) ** 2 / (np.abs(Ht) ** 2 + sig**2)  # white input and noise: Suu = 1, Snn = σ² per unit
    # the estimate's sd is about √2 (1 − γ²) γ / √n_eff (Bendat & Piersol 2010, (9.82)), n_eff ≈ 484
    n_eff = effective_averages("hann", 256, 128, (N - 128) // 128)
    sd = np.sqrt(2) * (1 - theory) * np.sqrt(theory) / np.sqrt(n_eff)
    assert np.all(np.abs(coh[:, 0] - theory) <= 4.5 * sd + 1e-3)
    assert np.mean(coh[:, 0] - theory) == pytest.approx(0.0, abs=0.01)


B_MIMO = [[[0.5, -0.3], [0.2, 0.1, 0.05]], [[1.0, 0.4], [-0.3, 0.2]]]  # FIR from input j to output i


def _mimo_out(u):
    return np.column_stack([sum(scipy.signal.lfilter(B_MIMO[i][j], [1.0], u[:, j]) for j in range(2))
                            for i in range(2)])


def _h_mimo(w):
    zi = np.exp(-1j * w * DT)
    return np.array([[np.polyval(B_MIMO[i][j][::-1], zi) for j in range(2)] for i in range(2)]).transpose(2, 0, 1)


def test_mimo_welch_h1_variance():
    rng = np.random.default_rng(5)
    R, N, sig = 60, 2**14, np.array([0.3, 0.1])
    H, V = [], []
    for _ in range(R):
        u = rng.standard_normal((N, 2)) * [1.0, 2.0]
        frf = si.estimate_frf(si.IOData(u, _mimo_out(u) + sig * rng.standard_normal((N, 2)), DT), nperseg=256)
        H.append(frf.H)
        V.append(frf.variance)
    H, V = np.array(H), np.array(V)
    Ht = _h_mimo(frf.w)
    assert H.shape[1:] == (126, 2, 2)
    emp = np.mean(np.abs(H - Ht) ** 2, axis=0)
    # per entry: per line sd 1/√60 = 0.13, ≈ 63 independent lines: sd 0.016
    np.testing.assert_allclose(np.mean(emp / V.mean(axis=0), axis=0), np.ones((2, 2)), atol=0.08)


def test_mimo_periodic_from_two_orthogonal_experiments():
    rng = np.random.default_rng(6)
    R, P, sig = 80, 6, np.array([0.3, 0.1])
    H, V = [], []
    for _ in range(R):
        a, b = _multisine(rng, P + 1), _multisine(rng, P + 1)
        recs = []
        for sign in (1.0, -1.0):  # U = [[Ua, Ua], [Ub, −Ub]]: well conditioned at every line
            u = np.column_stack([a, sign * b])
            recs.append(si.IOData(u, _mimo_out(u) + sig * rng.standard_normal(u.shape), DT))
        frf = si.estimate_frf(recs, period=PERIOD, transient_periods=1, band=_band_of_lines())
        H.append(frf.H)
        V.append(frf.variance)
    H, V = np.array(H), np.array(V)
    Ht = _h_mimo(frf.w)
    # theory: Ĥ = Ȳ Ū⁻¹ with Ū⁻¹ = [[1, 1], [1, −1]] / (2 U) entrywise → var Ĥ_ij = N σᵢ² · 2 / (4 P |U|²)
    theory = (PERIOD * sig**2 / (2 * P * AMP**2))[None, :, None] * np.ones((1, 2, 2))
    np.testing.assert_allclose(np.mean(V, axis=(0, 1))[None], theory, rtol=0.03)  # sd ≈ 0.005
    emp = np.mean(np.abs(H - Ht) ** 2, axis=0)
    np.testing.assert_allclose(np.mean(emp, axis=0)[None], theory, rtol=0.08)  # sd ≈ 0.014


def test_effective_averages_reference_values():
    # no overlap: K independent segments; Hann at half overlap: ρ₁ = 1/6 (Harris 1978, Table 1:
    # overlap correlation 16.7 %), so n_eff = K / (1 + 2 (1 − 1/K) / 36) → K / 1.0556 for K ≫ 1
    assert effective_averages("boxcar", 64, 0, 12) == 12.0
    assert effective_averages("hann", 1024, 512, 10_000) == pytest.approx(10_000 / (1 + 2 / 36), rel=1e-3)


def test_plot_writes_a_png(tmp_path):
    from symid.plots import frf_estimate_plot

    rng = np.random.default_rng(0)
    u = _multisine(rng, 4)
    y = scipy.signal.lfilter(B_IIR, A_IIR, u) + 0.01 * rng.standard_normal(u.size)
    io = si.IOData(u, y, DT)
    frf = si.estimate_frf(io, period=PERIOD, transient_periods=1, band=_band_of_lines())
    w, coh = si.estimate_coherence(io, period=PERIOD, transient_periods=1, band=_band_of_lines())
    np.testing.assert_array_equal(w, frf.w)
    out = frf_estimate_plot(frf, tmp_path / "frf.png", coherence=coh, unit="V/V")
    assert out.stat().st_size > 10_000


# -- bad input --------------------------------------------------------------------------------

def _io(N=4096, m=1, p=1):
    rng = np.random.default_rng(0)
    return si.IOData(rng.standard_normal((N, m)), rng.standard_normal((N, p)), DT)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"period": 1000}, "not a whole number of periods"),
    ({"period": 1024, "transient_periods": 4}, "drops every one"),
    ({"period": 1024, "transient_periods": -1}, "transient_periods must be an integer"),
    ({"period": 1024.0}, "period must be an integer"),
    ({"transient_periods": 1}, "applies to periodic excitation"),
    ({"period": 1024, "nperseg": 256}, "nperseg is a Welch option"),
    ({"period": 1024, "estimator": "h2"}, "Welch estimator"),
    ({"estimator": "h3"}, "estimator must be one of"),
    ({"nperseg": 8192}, "longer than the record"),
    ({"window": "nope"}, "window"),
    ({"detrend": "quadratic"}, "detrend"),
    ({"band": (400.0, 500.0)}, "above the Nyquist frequency"),
    ({"band": (5.0, 1.0)}, "0 <= w_low < w_high"),
    ({"band": (1.0, 1.01)}, "no Welch bin lies in band"),
    ({"band": "low"}, "band must be a pair"),
    ({"min_excitation": 1.0}, "min_excitation must be in"),
])
def test_bad_arguments_are_named(kwargs, match):
    with pytest.raises(DataError, match=match):
        si.estimate_frf(_io(), **kwargs)


def test_band_reaching_above_nyquist_warns():
    with pytest.warns(UserWarning, match="reaches above the Nyquist"):
        frf = si.estimate_frf(_io(), band=(10.0, 1000.0))
    assert frf.w[-1] < np.pi / DT


def test_records_and_inputs_are_checked():
    with pytest.raises(DataError, match="input/output records"):
        si.estimate_frf(np.ones((100, 2)))
    with pytest.raises(DataError, match="same channels"):
        si.estimate_frf([_io(), _io(p=2)])
    with pytest.raises(DataError, match="one sample time"):
        si.estimate_frf([_io(), si.IOData(np.ones(4096), np.ones(4096), 0.02)])
    with pytest.raises(DataError, match="at least 2 records"):
        si.estimate_frf(_io(m=2), period=1024)
    with pytest.raises(DataError, match="H2 estimator is defined here for one input"):
        si.estimate_frf(_io(m=2), estimator="h2")


def test_zero_input_and_zero_coherence():
    rng = np.random.default_rng(1)
    u = rng.standard_normal(4096)
    with pytest.raises(DataError, match="input is zero"):
        si.estimate_frf(si.IOData(np.zeros(4096), u, DT))
    # an output that does not respond: H1 = 0 with the output's power as its variance; H2 does not exist
    h1 = si.estimate_frf(si.IOData(u, np.zeros(4096), DT))
    assert np.all(h1.H == 0) and np.all(h1.variance == 0)
    with pytest.raises(DataError, match="coherence 0"):
        si.estimate_frf(si.IOData(u, np.zeros(4096), DT), estimator="h2")


def test_unexcited_lines_are_left_out_and_kept_on_request():
    rng = np.random.default_rng(2)
    u = _multisine(rng, 3)
    y = scipy.signal.lfilter(B_IIR, A_IIR, u) + 1e-3 * rng.standard_normal(u.size)
    io = si.IOData(u + 1e-9 * rng.standard_normal(u.size), y, DT)  # measured: no line is exactly zero
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        frf = si.estimate_frf(io, period=PERIOD, transient_periods=1)
        every = si.estimate_frf(io, period=PERIOD, transient_periods=1, min_excitation=0)
    np.testing.assert_allclose(frf.w, 2 * np.pi * LINES / (PERIOD * DT))  # exactly the excited lines
    assert every.n_frequencies == PERIOD // 2 - 1  # every line but DC and Nyquist
    with pytest.raises(DataError, match="not excited at any line"):
        si.estimate_frf(io, period=PERIOD, band=(2 * np.pi * 130 / (PERIOD * DT), 2 * np.pi * 140 / (PERIOD * DT)))


def test_the_estimate_says_its_variances_degrees_of_freedom():
    """2(P − 1) from P periods; 2(n_eff − m) from Welch averages (H1), 2(n_eff − 1) for H2."""
    from symid.signal.frf import effective_averages

    rng = np.random.default_rng(0)
    u = _multisine(rng, 9)
    y = scipy.signal.lfilter(B_IIR, A_IIR, u) + 0.01 * rng.standard_normal(u.size)
    frf = si.estimate_frf(si.IOData(u, y, DT), period=PERIOD, transient_periods=1, band=_band_of_lines())
    assert frf.variance_dof == 2 * (8 - 1)
    N, nperseg = 2**12, 256
    u = rng.standard_normal(N)
    io = si.IOData(u, scipy.signal.lfilter([0.5, 0.2], [1.0], u) + 0.1 * rng.standard_normal(N), DT)
    K = (N - nperseg) // (nperseg // 2) + 1  # half-overlapping segments
    n_eff = effective_averages("hann", nperseg, nperseg // 2, K)
    assert si.estimate_frf(io, nperseg=nperseg).variance_dof == pytest.approx(2 * (n_eff - 1), rel=1e-12)
    assert si.estimate_frf(io, nperseg=nperseg, estimator="h2").variance_dof == pytest.approx(2 * (n_eff - 1),
                                                                                              rel=1e-12)


def test_hold_zoh_removes_the_holds_response_from_a_held_input():
    """A new user's motor driven through a DAC: the response of the sampled input to the sampled output differs
    from H(jω) by the hold (a half-sample delay and a sinc), 18 % at the median line there, and the FRF route
    fitted it with success=False. hold="zoh" divides it out. Here a one-mass model (5 rad/s mode), a held
    multisine up to 29 rad/s at 25 samples per period of the mode, exact steady state: the median error against
    H(jω) falls from 36 % to 0.1 % (2.1 % at the top line, the aliases of the response above the Nyquist frequency,
    (ω/(ω_s − ω))³ ≈ 3 % to first order there; measured when this test was written), and the least-squares fit of
    the continuous model is within 0.5 % of the truth."""
    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    truth = [2.0, 0.4, 50.0]
    N, dt = 256, 0.05
    lines = np.arange(1, 60)
    U = np.zeros(N // 2 + 1, complex)
    U[lines] = np.exp(2j * np.pi * np.random.default_rng(0).random(lines.size))
    io = si.simulate_io(model, truth, np.tile(np.fft.irfft(U, N), 9), dt)  # held between samples
    errors = {}
    for hold in (None, "zoh"):
        frf = si.estimate_frf(io, period=N, transient_periods=6, hold=hold)
        H = model.frequency_response(truth, frf.w)[:, 0, 0]
        errors[hold] = np.abs(frf.H[:, 0, 0] - H) / np.abs(H)
    assert np.median(errors[None]) > 0.3
    assert np.median(errors["zoh"]) < 2e-3 and errors["zoh"].max() < 0.03
    res = si.identify(model, frf, method="lm", x0=truth, identifiability_check=False)
    np.testing.assert_allclose(res.theta_vector, truth, rtol=5e-3)
    # "foh" names a sampled input as si.identify does: nothing corrected, the same as None
    np.testing.assert_array_equal(si.estimate_frf(io, period=N, transient_periods=6, hold="foh").H,
                                  si.estimate_frf(io, period=N, transient_periods=6).H)
    with pytest.raises(si.DataError, match="hold must be None, 'foh' or 'bandlimited'"):
        si.estimate_frf(io, period=N, hold="linear")
    # the response estimated without hold=, fitted: it fails, and NEXT names the hold first (two new users' held
    # records were told "units, local minimum"); the estimate says how it was made
    plain = si.estimate_frf(io, period=N, transient_periods=6)
    assert plain.estimated_from == {"dt": dt, "hold": None} and frf.estimated_from["hold"] == "zoh"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        failed = si.identify(model, plain, method="lm", x0=truth, identifiability_check=False)
    assert not failed.success
    assert "NEXT (also): this response was estimated from sampled records (si.estimate_frf, dt = 0.05 s) without " \
        "hold=" in failed.summary()
    assert "sampled_response" not in res.options  # the fit of the corrected response


def test_inputs_that_are_one_signal_warn():
    """An input and its derivative as two inputs (a new user's road displacement and velocity) are one signal: the
    response to each cannot be told apart and the estimate says so; correlated but separable inputs do not warn."""
    from symid.errors import DataWarning

    rng = np.random.default_rng(7)
    N = 2**13
    u0 = rng.standard_normal(N)
    y = scipy.signal.lfilter(B_IIR, A_IIR, u0) + 0.01 * rng.standard_normal(N)
    with pytest.warns(DataWarning, match="2 inputs are nearly one signal"):
        si.estimate_frf(si.IOData(np.column_stack([u0, np.gradient(u0, DT)]), y, DT), nperseg=256)
    # exactly one signal (a scaled copy): named as such, not "the input is zero at every frequency"
    with pytest.raises(DataError, match="the inputs are one signal at every line"):
        si.estimate_frf(si.IOData(np.column_stack([u0, 2.0 * u0]), y, DT), nperseg=256)
    # u1 = u0 + 0.5 e (e independent): |γ| = 1/√1.25 = 0.89 between them, a separation of 0.11 > COLLINEAR_INPUTS
    u1 = u0 + 0.5 * rng.standard_normal(N)
    with warnings.catch_warnings():
        warnings.simplefilter("error", DataWarning)
        frf = si.estimate_frf(si.IOData(np.column_stack([u0, u1]), y, DT), nperseg=256)
    assert frf.H.shape[2] == 2


def test_an_output_not_yet_periodic_is_said():
    """A new user's drive: the motor angle's mean per period moved 0.62, 0.87, 1.03 rad (a slow rigid-body
    transient after the one period skipped) and the periodic estimate took it for response at every line, its
    variance (between periods) blind to it. An output whose period means move by more than PERIODIC_DRIFT of its
    periodic part's rms is now said; skipping the transient says nothing (reference: a first-order lag of time
    constant 20 s under a multisine of 10 s periods, from an initial state away from its steady cycle)."""
    import warnings

    a = si.parameters("a", positive=True)
    model = si.StateSpaceModel(A=[[-a]], B=[[a]], C=[[1]])
    k = np.arange(100)
    u = np.tile(sum(np.sin(2 * np.pi * f * k / 100 + f) for f in (1, 2, 3, 5)), 20)
    io = si.simulate_io(model, {"a": 0.05}, u, dt=0.1, x0=[3.0])
    with pytest.warns(si.DataWarning, match=r"output 0 is not periodic over the periods used: its mean per period"):
        si.estimate_frf(io, period=100)
    with warnings.catch_warnings():
        warnings.simplefilter("error", si.DataWarning)
        si.estimate_frf(io, period=100, transient_periods=15)  # 150 s, 7.5 time constants: periodic to 3 %
