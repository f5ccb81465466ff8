"""Vector fitting (symid.signal.vectfit): a rational black box with common poles.

Reference values are the rational functions the data are built from (stated in each test):
noise-free, vector fitting with the right number of poles recovers them to rounding.
"""

from __future__ import annotations

import numpy as np
import pytest

from symid.errors import DataError, OptionError
from symid.signal.vectfit import modes_of_poles, vector_fit

# reference: three lightly damped modes, one real pole, a 2 x 1 response with D
POLES = np.array([-3.0, -0.5 + 20j, -0.5 - 20j, -2.0 + 55j, -2.0 - 55j, -1.2 + 130j, -1.2 - 130j])
RES = np.array([[4.0, -1.0], [1 + 2j, 0.5 - 1j], [1 - 2j, 0.5 + 1j], [-3 + 1j, 2 + 0j], [-3 - 1j, 2 - 0j],
                [6 - 2j, -4 + 3j], [6 + 2j, -4 - 3j]])[:, :, None]
D = np.array([[0.1], [-0.05]])


def reference(w, t=1.0):
    """The rational function above with time in units t (poles and residues scale by 1/t)."""
    s = 1j * np.asarray(w)
    return np.einsum("ki,ipm->kpm", 1 / (s[:, None] - POLES[None] / t), RES / t) + D[None]


@pytest.mark.parametrize("t", [1.0, 1e-6, 1e6])
def test_noise_free_fit_recovers_poles_and_residues_in_any_unit_of_time(t):
    w = np.linspace(2.0, 200.0, 400) / t
    fit = vector_fit(w, reference(w, t), 7)
    order = np.lexsort((fit.poles.imag, np.abs(fit.poles)))
    ref = np.lexsort((POLES.imag, np.abs(POLES)))
    np.testing.assert_allclose(fit.poles[order] * t, POLES[ref], rtol=1e-8)
    np.testing.assert_allclose(fit.residues[order] * t, RES[ref], rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(fit.D, D, atol=1e-9)
    assert fit.rms < 1e-9
    np.testing.assert_allclose(fit.response(w), reference(w, t), rtol=1e-8, atol=1e-12)


def test_proportional_term_is_fitted_when_asked():
    w = np.linspace(2.0, 200.0, 300)
    H = reference(w) + (1j * w)[:, None, None] * np.array([[1e-3], [2e-3]])[None]
    np.testing.assert_allclose(vector_fit(w, H, 7, E=True).E, [[1e-3], [2e-3]], rtol=1e-7)
    assert vector_fit(w, H, 7).rms > 1e-3  # without E the same data cannot be fitted exactly


def test_relative_weights_fit_to_the_noise_level():
    """Relative complex noise of level ε = 1 %: with 1/|H| weights the relative rms residual is ε·√(1 − q/n)
    (q real unknowns, n real equations: 29 of 1600 here, so within 1 % of ε), up to the spread of a
    chi-square over 1600 values (about 2.5 %)."""
    w = np.linspace(2.0, 200.0, 400)
    rng = np.random.default_rng(3)
    H = reference(w)
    noisy = H * (1 + 0.01 * (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape)) / np.sqrt(2))
    fit = vector_fit(w, noisy, 7, weight="relative")
    assert fit.rms == pytest.approx(0.01, rel=0.08)
    wn, zeta = fit.modes()
    wn_ref, zeta_ref = modes_of_poles(POLES)
    np.testing.assert_allclose(wn[1:], wn_ref[1:], rtol=1e-3)  # resonances: within a fraction of their bandwidth
    np.testing.assert_allclose(wn[0], wn_ref[0], rtol=1e-2)  # the real pole, a broad feature at the band's edge
    np.testing.assert_allclose(zeta[1:], zeta_ref[1:], rtol=0.1)  # lightly damped modes: ζ to 10 %


def test_modes_of_poles_pairs_and_real_poles():
    # reference: s² + 2ζωs + ω² with ω = 10, ζ = 0.1 has poles −1 ± j√99; two real poles −1, −4 are ω = 2, ζ = 1.25
    wn, zeta = modes_of_poles([-1 + 1j * np.sqrt(99), -1 - 1j * np.sqrt(99), -1.0, -4.0, -7.0])
    np.testing.assert_allclose(wn, [2.0, 7.0, 10.0])
    np.testing.assert_allclose(zeta, [1.25, 1.0, 0.1])
    with pytest.raises(DataError, match="conjugate pairs"):
        modes_of_poles([-1 + 2j, -1 + 3j])


@pytest.mark.parametrize(("args", "kwargs", "error", "match"), [
    ((np.linspace(1, 10, 5), np.ones(5), 4), {}, DataError, "needs at least 6 frequencies"),
    ((np.linspace(0, 10, 20), np.ones(20), 2), {}, DataError, "positive and finite"),
    ((np.linspace(1, 10, 20), np.r_[np.ones(19), np.nan], 2), {}, DataError, "non-finite"),
    ((np.linspace(1, 10, 20), np.ones((20, 2, 2, 2)), 2), {}, DataError, "shape"),
    ((np.linspace(1, 10, 20), np.ones(20), 0), {}, OptionError, "n_poles"),
    ((np.linspace(1, 10, 20), np.ones(20), 2), {"weight": "log"}, OptionError, "relative"),
    ((np.linspace(1, 10, 20), np.ones(20), 2), {"weight": -np.ones(20)}, OptionError, ">= 0"),
    ((np.linspace(1, 10, 20), np.ones(20), 2), {"poles": [-1 + 1j, -2 + 1j]}, OptionError, "conjugation"),
    ((np.linspace(1, 10, 20), np.ones(20), 2), {"n_iter": -1}, OptionError, "n_iter"),
])
def test_bad_input_is_named(args, kwargs, error, match):
    with pytest.raises(error, match=match):
        vector_fit(*args, **kwargs)
