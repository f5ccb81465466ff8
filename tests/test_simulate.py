"""Simulators: FRF, spectra Φyy = H Φuu Hᴴ, exact zero-order-hold I/O, relative noise with seeds."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal

import symid as si
from symid.errors import DataError, ModelError
from symid.signal.simulate import zoh_discretize

W = np.logspace(-1, 1, 40)


@pytest.fixture(scope="module")
def siso():
    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    return model, {"m": 2.0, "c": 0.4, "k": 3.0}


@pytest.fixture(scope="module")
def two_mass():
    # the two-mass chain of thesis (4-19), as in the README tour
    m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    truth = {"m1": 1, "m2": 1, "c1": 0.1, "c2": 0.3, "k1": 2, "k2": 1}

    def make(output: str, B=((1, 0), (0, 1)), C=((1, 0), (0, 1))):
        return si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                                   K=[[k1 + k2, -k2], [-k2, k2]], B=[list(r) for r in B], C=[list(r) for r in C],
                                   output=output)
    return make, truth


@pytest.fixture(scope="module")
def statespace():
    a, b, g = si.parameters("a b g")
    model = si.StateSpaceModel(A=[[0, 1, 0], [-a, -b, 1], [0, 0, -g]], B=[[0, 0], [1, 0], [0, 1]],
                               C=[[1, 0, 0], [0, 1, 0]], D=[[0, 0], [0, "b/10"]])
    return model, {"a": 4.0, "b": 0.6, "g": 1.5}


# -- FRF ------------------------------------------------------------------------------------

def test_simulate_frf_is_the_model_response(two_mass):
    make, truth = two_mass
    model = make("velocity")
    frf = si.simulate_frf(model, truth, W)
    assert isinstance(frf, si.FrequencyData) and frf.shape == (40, 2, 2)
    np.testing.assert_array_equal(frf.H, model.frequency_response(truth, W))
    np.testing.assert_array_equal(frf.w, W)
    by_sequence = si.simulate_frf(model, [truth[n] for n in model.parameter_names], W)
    assert by_sequence == frf


def test_simulate_frf_siso_analytic(siso):
    model, th = siso
    frf = si.simulate_frf(model, th, W)
    H = 1 / (th["k"] - th["m"] * W**2 + 1j * th["c"] * W)  # 1/(k − mω² + jcω), by hand
    np.testing.assert_allclose(frf.H[:, 0, 0], H, rtol=1e-12, atol=0)


def test_simulate_frf_of_a_blackbox(statespace):
    model, th = statespace
    ss = model.state_space(th)
    bb = si.BlackBox.from_state_space(ss)
    assert si.simulate_frf(bb, None, W) == si.simulate_frf(ss, None, W)
    np.testing.assert_allclose(si.simulate_frf(bb, None, W).H, si.simulate_frf(model, th, W).H,
                               rtol=1e-12, atol=1e-14)


# -- spectra -----------------------------------------------------------------------------------

def test_spectra_white_noise_siso_analytic(siso):
    model, th = siso
    spec = si.simulate_spectra(model, th, W, 0.7)
    # white noise: Φyy = |H|² Φuu with H = 1/(k − mω² + jcω)  (thesis (5-3), SISO)
    H2 = 1 / ((th["k"] - th["m"] * W**2) ** 2 + (th["c"] * W) ** 2)
    np.testing.assert_allclose(spec.Phi_yy[:, 0, 0], 0.7 * H2, rtol=1e-12, atol=0)
    np.testing.assert_array_equal(spec.Phi_uu[:, 0, 0], np.full(40, 0.7))
    assert isinstance(spec, si.SpectralData)


def test_spectra_pink_noise_callable(siso):
    model, th = siso
    spec = si.simulate_spectra(model, th, W, lambda w: w**-0.5)  # pink noise, thesis (5-11)
    H2 = np.abs(model.frequency_response(th, W)[:, 0, 0]) ** 2
    np.testing.assert_allclose(spec.Phi_yy[:, 0, 0].real, W**-0.5 * H2, rtol=1e-12)
    np.testing.assert_allclose(spec.Phi_uu[:, 0, 0].real, W**-0.5, rtol=1e-15)


def test_spectra_mimo_all_input_forms_agree(two_mass):
    make, truth = two_mass
    model = make("position")
    H = model.frequency_response(truth, W)
    P = np.array([[2.0, 0.5 - 0.25j], [0.5 + 0.25j, 1.0]])
    expected = np.stack([H[i] @ P @ H[i].conj().T for i in range(W.size)])  # Φyy = H Φuu Hᴴ, loop by hand
    forms = [P, np.broadcast_to(P, (40, 2, 2)), lambda w: P]
    for Phi_uu in forms:
        spec = si.simulate_spectra(model, truth, W, Phi_uu)
        np.testing.assert_allclose(spec.Phi_yy, expected, rtol=1e-12, atol=1e-15)
        np.testing.assert_array_equal(spec.Phi_yy, np.conj(np.swapaxes(spec.Phi_yy, 1, 2)))  # exactly Hermitian
    scalar = si.simulate_spectra(model, truth, W, 3.0)
    per_freq = si.simulate_spectra(model, truth, W, np.full(40, 3.0))
    by_call = si.simulate_spectra(model, truth, W, lambda w: 3.0)
    assert scalar == per_freq == by_call
    np.testing.assert_allclose(scalar.Phi_yy, 3.0 * H @ np.conj(np.swapaxes(H, 1, 2)), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize(("Phi_uu", "phrase"), [
    (np.ones((3, 2, 2)), "Phi_uu must be a scalar, a callable of ω, or an array of shape (s, m, m) = (40, 2, 2)"),
    (np.ones((2, 3)), "got shape (2, 3)"),
    (lambda w: np.ones(3), "Phi_uu(0.1) must be a scalar (times the identity) or an (m, m) = (2, 2) matrix"),
    (np.array([[1.0, 1.0], [0.0, 1.0]]), "Phi_uu[0] is not Hermitian"),
    (np.nan, "Phi_uu must be finite"),
    ("white", "Phi_uu must hold numbers"),
])
def test_spectra_bad_input_spectrum(two_mass, Phi_uu, phrase):
    make, truth = two_mass
    with pytest.raises(DataError) as info:
        si.simulate_spectra(make("position"), truth, W, Phi_uu)
    assert phrase in str(info.value), str(info.value)


# -- I/O ----------------------------------------------------------------------------------------

def _scipy_reference(ss, u, dt, x0=None):
    """scipy.signal.cont2discrete(method="zoh") followed by dlsim: the independent reference."""
    Ad, Bd, Cd, Dd, _ = scipy.signal.cont2discrete(tuple(ss), dt, method="zoh")
    _, y, _ = scipy.signal.dlsim((Ad, Bd, Cd, Dd, dt), u, x0=x0)
    return y


def test_simulate_io_statespace_matches_scipy(statespace):
    model, th = statespace
    rng = np.random.default_rng(0)
    u = rng.standard_normal((400, 2))
    io = si.simulate_io(model, th, u, 0.05)
    assert isinstance(io, si.IOData) and io.y.shape == (400, 2) and io.dt == 0.05
    np.testing.assert_array_equal(io.u, u)
    ref = _scipy_reference(model.state_space(th), u, 0.05)
    np.testing.assert_allclose(io.y, ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())
    x0 = np.array([1.0, -0.5, 0.25])
    io0 = si.simulate_io(model, th, u, 0.05, x0=x0)
    ref0 = _scipy_reference(model.state_space(th), u, 0.05, x0=x0)
    np.testing.assert_allclose(io0.y, ref0, rtol=1e-10, atol=1e-12 * np.abs(ref0).max())


@pytest.mark.parametrize("output", ["position", "velocity", "acceleration"])
def test_simulate_io_second_order_matches_scipy(two_mass, output):
    make, truth = two_mass
    model = make(output, B=((1,), (0,)), C=((1, 0), (0, 1)))
    ss = model.state_space(truth)
    if output == "acceleration":
        assert np.any(ss.D != 0)  # the feedthrough must be used
    rng = np.random.default_rng(1)
    u = rng.standard_normal(300)  # (N,) for a single-input model
    io = si.simulate_io(model, truth, u, 0.1)
    ref = _scipy_reference(ss, u.reshape(-1, 1), 0.1)
    np.testing.assert_allclose(io.y, ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())
    if output == "acceleration":
        np.testing.assert_allclose(io.y[0], ss.D[:, 0] * u[0], rtol=1e-14)  # x0 = 0: y[0] = D u[0]


def test_simulate_io_first_order_step_analytic():
    a = si.parameters("a")
    model = si.StateSpaceModel(A=[[-a]], B=[[a]], C=[[1]])
    dt, N = 0.01, 500
    io = si.simulate_io(model, {"a": 2.0}, np.ones(N), dt)
    t = np.arange(N) * dt
    np.testing.assert_allclose(io.y[:, 0], 1 - np.exp(-2.0 * t), rtol=1e-12, atol=1e-15)  # exact under ZOH


def test_zoh_discretize_matches_scipy(statespace):
    model, th = statespace
    A, B, C, D = model.state_space(th)
    Ad, Bd = zoh_discretize(A, B, 0.3)
    ref = scipy.signal.cont2discrete((A, B, C, D), 0.3, method="zoh")
    np.testing.assert_allclose(Ad, ref[0], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(Bd, ref[1], rtol=1e-12, atol=1e-15)


def test_simulate_io_of_a_blackbox(statespace):
    model, th = statespace
    u = np.random.default_rng(2).standard_normal((100, 2))
    bb = si.BlackBox(*model.state_space(th))
    assert si.simulate_io(bb, None, u, 0.05) == si.simulate_io(model, th, u, 0.05)


@pytest.mark.parametrize(("kwargs", "phrase"), [
    ({"u": np.ones(50)}, "u of shape (N,) is only accepted for a single-input model"),
    ({"u": np.ones((50, 3))}, "u must have shape (N, m) = (N, 2)"),
    ({"u": np.ones((1, 2))}, "at least 2 samples"),
    ({"u": np.full((5, 2), np.nan)}, "u must be finite"),
    ({"dt": 0.0}, "dt must be a finite number > 0"),
    ({"dt": -1.0}, "dt must be a finite number > 0"),
    ({"x0": np.ones(2)}, "x0 must have shape (n,) = (3,)"),
    ({"x0": [np.inf, 0, 0]}, "x0 must be finite"),
    ({"noise": -0.1}, "noise must be a finite number >= 0"),
    ({"noise": np.nan}, "noise must be a finite number >= 0"),
    ({"noise": "lots"}, "noise must be a number >= 0"),
])
def test_simulate_io_bad_arguments(statespace, kwargs, phrase):
    model, th = statespace
    args = {"u": np.ones((50, 2)), "dt": 0.1} | kwargs
    with pytest.raises(DataError) as info:
        si.simulate_io(model, th, args.pop("u"), args.pop("dt"), **args)
    assert phrase in str(info.value), str(info.value)


def test_simulate_io_unstable_overflow_is_a_data_error():
    bb = si.BlackBox([[5.0]], [[1.0]], [[1.0]])
    with pytest.raises(DataError, match=r"overflows .* unstable"):
        si.simulate_io(bb, None, np.ones(2000), 1.0)


def test_model_and_theta_errors(siso, statespace):
    model, th = siso
    with pytest.raises(ModelError, match="theta is required"):
        si.simulate_frf(model, None, W)
    with pytest.raises(ModelError, match="missing parameter"):
        si.simulate_frf(model, {"m": 1.0}, W)
    bb = si.BlackBox(*model.state_space(th))
    with pytest.raises(ModelError, match="BlackBox has no parameters"):
        si.simulate_frf(bb, th, W)
    with pytest.raises(ModelError, match="model must be"):
        si.simulate_frf("mass", th, W)
    with pytest.raises(DataError, match="w must be strictly increasing"):
        si.simulate_frf(model, th, [1.0, 0.5])
    with pytest.raises(DataError, match="must be positive"):
        si.simulate_spectra(model, th, [0.0, 1.0], 1.0)


# -- noise --------------------------------------------------------------------------------------

def test_frf_noise_reproducible_and_of_the_requested_size(two_mass):
    make, truth = two_mass
    model = make("position")
    w = np.logspace(-1, 1, 500)
    exact = si.simulate_frf(model, truth, w)
    assert si.simulate_frf(model, truth, w, noise=0) == exact
    assert si.simulate_frf(model, truth, w, noise=None, seed=3) == exact
    a = si.simulate_frf(model, truth, w, noise=0.05, seed=7)
    b = si.simulate_frf(model, truth, w, noise=0.05, seed=7)
    c = si.simulate_frf(model, truth, w, noise=0.05, seed=8)
    assert a == b and a != c
    rel = np.abs(a.H - exact.H) / np.abs(exact.H)
    rms = np.sqrt(np.mean(rel**2))  # 2000 entries: rms relative error ≈ noise within a few %
    assert rms == pytest.approx(0.05, rel=0.1)
    gen = np.random.default_rng(7)
    assert si.simulate_frf(model, truth, w, noise=0.05, seed=gen) == a


def test_spectra_noise_hermitian_reproducible_and_sized(two_mass):
    make, truth = two_mass
    model = make("position")
    w = np.logspace(-1, 1, 1000)
    exact = si.simulate_spectra(model, truth, w, 1.0)
    a = si.simulate_spectra(model, truth, w, 1.0, noise=0.1, seed=11)
    assert a == si.simulate_spectra(model, truth, w, 1.0, noise=0.1, seed=11)
    assert a != si.simulate_spectra(model, truth, w, 1.0, noise=0.1, seed=12)
    np.testing.assert_array_equal(a.Phi_yy, np.conj(np.swapaxes(a.Phi_yy, 1, 2)))
    np.testing.assert_array_equal(a.Phi_uu, exact.Phi_uu)  # the input spectrum stays exact
    rel = np.abs(a.Phi_yy - exact.Phi_yy) / np.abs(exact.Phi_yy)
    for i, j in [(0, 0), (1, 1), (0, 1)]:  # 1000 draws each: rms within ~10 %
        assert np.sqrt(np.mean(rel[:, i, j] ** 2)) == pytest.approx(0.1, rel=0.1)


def test_io_noise_reproducible_and_sized(statespace):
    model, th = statespace
    u = np.random.default_rng(5).standard_normal((4000, 2))
    exact = si.simulate_io(model, th, u, 0.05)
    a = si.simulate_io(model, th, u, 0.05, noise=0.02, seed=1)
    assert a == si.simulate_io(model, th, u, 0.05, noise=0.02, seed=1)
    assert a != si.simulate_io(model, th, u, 0.05, noise=0.02, seed=2)
    np.testing.assert_array_equal(a.u, exact.u)
    ratio = np.std(a.y - exact.y, axis=0) / np.std(exact.y, axis=0)
    np.testing.assert_allclose(ratio, [0.02, 0.02], rtol=0.1)


@pytest.mark.parametrize("seed", ["a", 1.5, -1, True, [1, 2]])
@pytest.mark.parametrize("noise", [0.0, 0.1])
def test_bad_seed_is_a_data_error_even_without_noise(siso, seed, noise):
    model, th = siso
    for simulate in (lambda: si.simulate_frf(model, th, W, noise=noise, seed=seed),
                     lambda: si.simulate_spectra(model, th, W, 1.0, noise=noise, seed=seed),
                     lambda: si.simulate_io(model, th, np.ones(10), 0.1, noise=noise, seed=seed)):
        with pytest.raises(DataError, match=r"seed must be None, an int >= 0 or a numpy\.random\.Generator"):
            simulate()


def test_numpy_integer_seed_is_accepted(siso):
    model, th = siso
    assert si.simulate_frf(model, th, W, noise=0.1, seed=np.int64(4)) == si.simulate_frf(model, th, W, noise=0.1,
                                                                                          seed=4)


def test_a_negative_power_is_a_data_error(siso):
    # The diagonal of a power spectrum is a power. A negative input spectrum used to be accepted, and IPOPT then
    # "fitted" the negative output spectra it implied with success True (found trying symid as a new user).
    model, th = siso
    with pytest.raises(DataError, match=r"Phi_uu\[0, 0, 0\] = -1 at frequency line 0: the diagonal of a power"):
        si.simulate_spectra(model, th, W, -1.0)
    with pytest.raises(DataError, match=r"Phi_uu\[2, 0, 0\] = -0.5"):
        si.SpectralData(W, np.ones(W.size), np.where(np.arange(W.size) == 2, -0.5, 1.0))
    with pytest.raises(DataError, match=r"Phi_yy\[0, 0, 0\] = -2"):
        si.SpectralData(W, -2 * np.ones(W.size), np.ones(W.size))


def test_heavy_noise_keeps_the_output_power_non_negative(siso):
    model, th = siso
    spec = si.simulate_spectra(model, th, np.linspace(0.5, 3.0, 400), 1.0, noise=0.5, seed=3)
    assert spec.Phi_yy.real.min() >= 0.0


def test_a_model_without_parameters_needs_no_theta():
    # found by a new-user sweep: simulate_frf(model, None, w) said "theta is required: values for no parameters"
    model = si.SecondOrderModel(M=[[1]], V=[[0.2]], K=[[4]], B=[[1]], C=[[1]])
    a, b = si.simulate_frf(model, None, W), si.simulate_frf(model, {}, W)
    np.testing.assert_array_equal(a.H, b.H)
    m = si.parameters("m", positive=True)
    with pytest.raises(ModelError, match="theta is required: values for m"):
        si.simulate_frf(si.SecondOrderModel(M=[[m]], V=[[0.2]], K=[[4]], B=[[1]], C=[[1]]), None, W)


def test_a_text_theta_is_named_as_text(siso):
    # found by a new-user sweep: x0="truth" said "theta has 1 value(s)"
    model, th = siso
    with pytest.raises(ModelError, match="theta is the text 'truth'; give a dict by name or a sequence of 3"):
        si.simulate_frf(model, "truth", W)
    with pytest.raises(si.OptionError, match="x0: theta is the text 'truth'"):
        si.identify(model, si.simulate_frf(model, th, W), x0="truth", identifiability_check=False)


def test_absolute_noise_has_the_given_standard_deviation_per_output():
    # a new user added 0.05 K of thermometer noise by hand: simulate_io had only relative noise
    a, b = si.parameters("a b", positive=True)
    model = si.StateSpaceModel(A=[[-a, 0], [0, -b]], B=[[1], [1]], C=[[1, 0], [0, 1]])
    u = np.zeros(40000)
    exact = si.simulate_io(model, {"a": 1.0, "b": 2.0}, u, 0.1)
    noisy = si.simulate_io(model, {"a": 1.0, "b": 2.0}, u, 0.1, noise_std=[0.05, 2.0], seed=3)
    # zero input: the output is pure noise; 40 000 samples give the standard deviation to about 0.35 % (1/√(2N)),
    # 2 % allows six of those
    np.testing.assert_allclose(np.std(noisy.y - exact.y, axis=0), [0.05, 2.0], rtol=0.02)
    for bad, match in ((-1.0, ">= 0"), ([0.1, 0.2, 0.3], "one per output"), (np.nan, "finite")):
        with pytest.raises(DataError, match=match):
            si.simulate_io(model, {"a": 1.0, "b": 2.0}, u[:5], 0.1, noise_std=bad)


def test_simulate_io_labels_the_record_in_the_models_time_unit():
    """A model file's rates per hour gave records labelled in seconds (simulate_io had no time unit), so fitting them
    back warned of a mismatch; now the record carries the model's unit, and another unit is refused."""
    a = si.parameters("a", positive=True)
    model = si.StateSpaceModel(A=[[-a]], B=[[a]], C=[[1]])
    assert si.simulate_io(model, {"a": 0.5}, np.ones(4), dt=0.1).time_unit == "s"
    assert si.simulate_io(model, {"a": 0.5}, np.ones(4), dt=0.1, time_unit="min").time_unit == "min"
    model.io_units = {"time": ("h",)}  # as a model file with time_unit = "h" sets it
    io = si.simulate_io(model, {"a": 0.5}, np.ones(4), dt=0.25)
    assert io.time_unit == "h" and io.dt == 0.25
    with pytest.raises(DataError, match=r"time_unit='s', but the model's rates are per h"):
        si.simulate_io(model, {"a": 0.5}, np.ones(4), dt=900.0, time_unit="s")


def test_simulating_at_a_negative_value_of_a_positive_parameter_is_said():
    """A new user's C1 = -1000 for a capacitance declared positive was simulated silently; it still is simulated
    (a study may want it), with a ModelWarning naming it."""
    a = si.parameters("a", positive=True)
    model = si.StateSpaceModel(A=[[-1.0]], B=[[a]], C=[[1]])
    with pytest.warns(si.ModelWarning, match=r"simulating at a = -2, negative for parameter\(s\) declared positive"):
        io = si.simulate_io(model, {"a": -2.0}, np.ones(3), dt=0.5)
    np.testing.assert_allclose(io.y[:, 0], [0.0, -2 * (1 - np.exp(-0.5)), -2 * (1 - np.exp(-1.0))], rtol=1e-12)
