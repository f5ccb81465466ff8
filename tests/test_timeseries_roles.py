"""Input and output columns read the wrong way round: a failed fit's NEXT line asks (symid/fit/timeseries/roles.py).

Reference: the records are built here, a two-level PRBS through a first-order lag with 1 % noise, so which column is
the test signal is known.
"""

import warnings

import numpy as np

import symid as si
from symid.fit.timeseries.roles import swapped_roles


def _record():
    k, g = si.parameters("k g", positive=True)
    model = si.StateSpaceModel(A=[[-k]], B=[[g]], C=[[1]])
    rng = np.random.default_rng(0)
    prbs = np.repeat(rng.integers(0, 2, 40), 10).astype(float)  # a valve switched between two positions
    io = si.simulate_io(model, {"k": 0.2, "g": 0.5}, prbs, 1.0, noise=0.01, seed=1)
    return model, io


def test_a_failed_fit_of_swapped_columns_asks_whether_they_are():
    model, io = _record()
    swapped = si.IOData(io.y, io.u, io.dt)
    res = si.identify(model, swapped, x0={"k": 0.1, "g": 1.0}, time_limit=3.0, identifiability_check=False)
    assert not res.success
    assert res.options["swapped_roles"].startswith("output 0 takes only 2 values over 400 samples")
    next_lines = [line for line in res.summary().splitlines() if line.startswith("NEXT")]
    assert next_lines[0].startswith("NEXT: output 0 takes only 2 values") and "columns swapped?" in next_lines[0]
    right = si.identify(model, io, x0={"k": 0.1, "g": 1.0}, identifiability_check=False)
    assert right.success and "swapped_roles" not in right.options


def test_levels_alone_are_not_enough():
    _, io = _record()
    assert swapped_roles(si.IOData(io.y, io.u, io.dt)) is not None
    # a test signal on both sides (two PRBS channels), a short record, or an output of many levels: no question
    assert swapped_roles(si.IOData(io.u, io.u, io.dt)) is None
    assert swapped_roles(si.IOData(io.y[:40], io.u[:40], io.dt)) is None
    assert swapped_roles(io) is None


def test_a_reversed_sensor_in_records_is_named(grounded_two_mass):
    """A new user's building with one accelerometer mounted the other way, fitted from its samples: "more starts".
    The frequency-response flips are tried on the response of an N4SID black box of the record (a fit of which is
    judged by its misfit: a black box's response is exactly of the model's order), and the flip that fits is named.
    Reference: the record is simulated here and output 1 negated."""
    model = grounded_two_mass(B=[[0], [1]], C=[[1, 0], [0, 1]], output="acceleration")
    truth = {"m1": 2.0, "m2": 1.0, "c1": 5.0, "c2": 3.0, "k1": 4e3, "k2": 2e3}
    io = si.simulate_io(model, truth, np.random.default_rng(0).standard_normal((1500, 1)), 2e-3, noise=0.01, seed=1)
    y = io.y.copy()
    y[:, 1] *= -1
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = si.identify(model, si.IOData(io.u, y, io.dt), x0={k: 1.3 * v for k, v in truth.items()},
                          time_limit=5.0, identifiability_check=False)
    assert not res.success and res.options["polarity"]["flip"] == "output 1"
    np.testing.assert_allclose(res.options["polarity"]["theta"], model.theta_vector(truth), rtol=0.02)
    assert "NEXT: the response of a black box of the records fits with output 1 negated" in res.summary()
    assert "MISFIT PER OUTPUT: " in res.summary()
