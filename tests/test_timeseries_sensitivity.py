"""The output error's Jacobian by the sensitivity recursion in numpy (symid/fit/timeseries/sensitivity.py).

References: central differences of the model's own matrices, and CasADi's exact Jacobian of the output-error
graph (the same discretisation differentiated symbolically; both at rounding level).
"""

import numpy as np
import pytest

import symid as si
from symid.fit.timeseries.oe import OutputError
from symid.fit.timeseries.sensitivity import state_space_derivatives


def _chain(output):
    m1, m2, c1, c2, k1, k2, g = si.parameters("m1 m2 c1 c2 k1 k2 g", positive=True)
    model = si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                                K=[[k1 + k2, -k2], [-k2, k2]], B=[[0], [g]], C=[[1, 0], [0, 2]], output=output)
    truth = np.array([1.0, 2.0, 0.3, 0.5, 50.0, 80.0, 1.5])
    return model, truth


def _casadi_jacobian(est, theta):
    """∂r/∂v from CasADi's graph of the same residual (what jacobian() returned before)."""
    q = est._balance(theta)
    s = est._graph_for(est._squarings(theta, q))
    return np.asarray(est._jacobian_function(s)(est._unknowns(theta), q))


@pytest.mark.parametrize("output", ["position", "velocity", "acceleration", ("acceleration", "position")])
def test_state_space_derivatives_match_central_differences(output):
    model, truth = _chain(output)
    mats, dmats = state_space_derivatives(model, truth)
    for X, Y in zip(mats, model.state_space(truth), strict=True):
        np.testing.assert_array_equal(X, Y)
    for k in range(truth.size):
        h = 1e-6 * truth[k]
        up, down = truth.copy(), truth.copy()
        up[k] += h
        down[k] -= h
        for dX, Xu, Xd in zip(dmats, model.state_space(up), model.state_space(down), strict=True):
            fd = (Xu - Xd) / (2 * h)
            # central differences: error O(h²) relative, ~1e-10 here; rounding ~1e-10 / 1e-6
            np.testing.assert_allclose(dX[k], fd, rtol=1e-6, atol=1e-8 * max(1.0, np.abs(fd).max()))


@pytest.mark.parametrize("output", ["position", "acceleration", ("velocity", "acceleration")])
def test_jacobian_equals_casadi_with_estimated_initial_states_and_uneven_sampling(output):
    model, truth = _chain(output)
    rng = np.random.default_rng(4)
    records = []
    for n in (150, 90):  # the Jacobian does not need y to come from the model: random outputs will do
        t = np.cumsum(np.r_[0.0, rng.uniform(0.005, 0.02, n - 1)])  # every interval different
        records.append(si.TimeSeries(t, rng.standard_normal((n, 1)), rng.standard_normal((n, 2))))
    est = OutputError(model, records, initial_state="estimate")
    theta = truth * np.array([1.2, 0.8, 1.1, 0.9, 1.05, 0.95, 1.3])
    r, J = est.jacobian(theta)
    assert J.shape == (r.size, truth.size + 2 * 4)
    np.testing.assert_allclose(np.sum(r**2), est.misfit(theta), rtol=1e-10)
    J_ca = _casadi_jacobian(est, theta)
    # two exact derivatives of one zero-order hold (scipy's Padé exponential, CasADi's Taylor one): rounding apart
    np.testing.assert_allclose(J, J_ca, rtol=0, atol=1e-9 * np.abs(J_ca).max())


def test_jacobian_of_an_initial_state_affine_in_theta():
    a, b, d = si.parameters("a b d", positive=True)
    model = si.StateSpaceModel(A=[[-a, b], [0, -2 * a]], B=[[0], [b]], C=[[1, 0]], x0=[d, 0])
    rng = np.random.default_rng(5)
    io = si.simulate_io(model, {"a": 0.5, "b": 2.0, "d": 3.0}, rng.standard_normal(200), dt=0.1)
    est = OutputError(model, io)
    theta = np.array([0.6, 1.5, 2.0])
    _, J = est.jacobian(theta)
    J_ca = _casadi_jacobian(est, theta)
    assert np.abs(J[:, 2]).max() > 0.1 * np.abs(J).max()  # d enters through x(0) only, and it is in J
    np.testing.assert_allclose(J, J_ca, rtol=0, atol=1e-10 * np.abs(J_ca).max())
