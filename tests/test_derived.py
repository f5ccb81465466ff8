"""Quantities computed from an estimate, with delta-method uncertainty (symid/fit/derived.py).

References: the delta method by hand (the derivative of 1/q is −1/q², of k·V is V and k), the estimate's own
covariance, and a model with a parameter the data do not determine.
"""

import warnings

import numpy as np
import pytest

import symid as si
from symid.errors import OptionError


def _fit(noise=0.02):
    """A one-compartment infusion: concentration = amount · q (q = 1/V), elimination k."""
    k, q = si.parameters("k q", positive=True)
    model = si.StateSpaceModel(A=[[-k]], B=[[1.0]], C=[[q]])
    u = np.where(np.arange(200) < 20, 100.0, 0.0)
    io = si.simulate_io(model, {"k": 0.1, "q": 1 / 30}, u, 0.25, noise=noise, seed=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        # the noise floor of such noise (relative misfit about noise²), so that a noisy fit is judged a fit
        return si.identify(model, io, x0={"k": 0.2, "q": 0.05}, identifiability_check=False,
                           noise_floor=2 * noise**2)


def test_volume_and_clearance_by_the_delta_method():
    res = _fit()
    assert res.success
    d = res.derived({"V": lambda th: 1 / th["q"], "CL": lambda th: th["k"] / th["q"]})
    k, q = res.theta["k"], res.theta["q"]
    np.testing.assert_allclose(d.values, [1 / q, k / q], rtol=1e-12)
    cov = res.uncertainty.covariance
    g_v = np.array([0.0, -1 / q**2])
    g_cl = np.array([1 / q, -k / q**2])
    # central differences of a smooth function with steps of 1e-6: the gradient to ~1e-10 relative
    np.testing.assert_allclose(d.standard_errors, np.sqrt([g_v @ cov @ g_v, g_cl @ cov @ g_cl]), rtol=1e-6)
    half = (res.uncertainty.intervals[1, 1] - q) / res.uncertainty.standard_errors[1]  # the parameters' quantile
    np.testing.assert_allclose(d.intervals[:, 1] - d.values, half * d.standard_errors, rtol=1e-12)
    assert d.intervals[0, 0] < 30 < d.intervals[0, 1] and d["V"] == pytest.approx(1 / q, rel=1e-12)
    assert "V" in d.summary() and not d.notes


def test_a_nonlinear_quantity_and_an_undetermined_one_are_said():
    res = _fit(noise=2.5)  # q known to about 20 %: 1/q is not linear over one standard error
    assert res.success and res.uncertainty.standard_errors[1] > 0.15 * res.theta["q"]
    d = res.derived({"V": lambda th: 1 / th["q"]})
    assert any("V: f changes by" in n for n in d.notes)
    m, c, k, b = si.parameters("m c k b", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[b]], C=[[1]])  # only b/m, c/m, k/m determined
    frf = si.simulate_frf(model, [2.0, 0.5, 200.0, 1.0], np.linspace(5.0, 15.0, 60), noise=0.01, seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = si.identify(model, frf, x0=[2.0, 0.5, 200.0, 1.0], identifiability_check=False)
    d = fit.derived({"m": lambda th: th["m"]})
    assert np.isinf(d.standard_errors[0]) and any("do not determine" in n for n in d.notes)


def test_bad_quantities_are_named_errors():
    res = _fit()
    with pytest.raises(OptionError, match="dict of name"):
        res.derived(["V"])
    with pytest.raises(OptionError, match=r"quantity 'V': the function failed at the estimate: KeyError"):
        res.derived({"V": lambda th: 1 / th["Q"]})
    with pytest.raises(OptionError, match=r"quantity 'bad' is inf"):
        res.derived({"bad": lambda th: np.inf})
