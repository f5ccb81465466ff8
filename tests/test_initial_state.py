"""StateSpaceModel(..., x0=...): known, affine in θ, or estimated; simulated with it (issue 15, item 2)."""

from __future__ import annotations

import numpy as np
import pytest

import symid as si


def _pk(x0):
    k10, k12, k21 = si.parameters("k10 k12 k21", positive=True)
    return si.StateSpaceModel(A=[[-k10 - k12, k21], [k12, -k21]], B=[[0], [0]], C=[[1, 0]], x0=x0)


def test_affine_initial_state_is_a_parameter_and_simulates_the_free_response():
    """Two-compartment bolus: x(t) = e^{At} x0 exactly (scipy.linalg.expm as the reference)."""
    import scipy.linalg

    d = si.parameters("d", positive=True)
    model = _pk([d, 0])
    assert model.parameter_names == ("k10", "k12", "k21", "d")
    assert model.initial_state_kind == "affine"
    theta = {"k10": 0.3, "k12": 0.5, "k21": 0.2, "d": 10.0}
    io = si.simulate_io(model, theta, np.zeros(30), dt=0.5)
    A = model.state_space(theta).A
    ref = [(scipy.linalg.expm(A * 0.5 * k) @ [10.0, 0.0])[0] for k in range(30)]
    np.testing.assert_allclose(io.y[:, 0], ref, rtol=1e-12)


def test_known_and_zero_initial_states():
    model = _pk([[2.0], [1.0]])
    assert model.initial_state_kind == "known"
    theta = [0.3, 0.5, 0.2]
    np.testing.assert_array_equal(model.initial_state(theta), [2.0, 1.0])
    assert _pk(None).initial_state_kind == "zero"
    np.testing.assert_array_equal(_pk(None).initial_state(theta), [0.0, 0.0])
    # an explicit x0 to the simulator replaces the model's
    io = si.simulate_io(model, theta, np.zeros(3), dt=0.1, x0=[5.0, 0.0])
    assert io.y[0, 0] == 5.0
    assert "x0 =" in model.summary()


def test_estimated_initial_state_needs_a_value_to_simulate():
    model = _pk("estimate")
    assert model.initial_state_kind == "estimate"
    assert model.initial_state_map is None
    with pytest.raises(si.ModelError, match="to be estimated"):
        model.initial_state([0.3, 0.5, 0.2])
    with pytest.raises(si.DataError, match="pass x0="):
        si.simulate_io(model, [0.3, 0.5, 0.2], np.zeros(5), dt=0.1)
    io = si.simulate_io(model, [0.3, 0.5, 0.2], np.zeros(5), dt=0.1, x0=[1.0, 0.0])
    assert io.y[0, 0] == 1.0
    assert "estimated per experiment" in model.summary()


@pytest.mark.parametrize("bad, match", [([1.0, 2.0, 3.0], "one value per state, n = 2"),
                                        ([[1.0, 2.0], [3.0, 4.0]], "one value per state"),
                                        ("guess", "the word 'estimate'"),
                                        ([float("nan"), 0.0], "must be finite")])
def test_initial_state_of_the_wrong_size_or_kind_is_refused(bad, match):
    with pytest.raises(si.ModelError, match=match):
        _pk(bad)


def test_non_affine_initial_state_is_refused():
    a, b = si.parameters("a b")
    with pytest.raises(si.NonAffineError):
        si.StateSpaceModel(A=[[-a]], B=[[1]], C=[[1]], x0=[a * b])


def test_simulator_x0_of_the_wrong_size_is_refused():
    with pytest.raises(si.DataError, match=r"x0 must have shape \(n,\) = \(2,\)"):
        si.simulate_io(_pk(None), [0.3, 0.5, 0.2], np.zeros(5), dt=0.1, x0=[1.0])
