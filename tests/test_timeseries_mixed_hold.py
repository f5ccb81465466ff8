"""One hold per input (symid.fit.timeseries.oe.parse_hold): a controller's held input beside a measured one.

Reference: the records are simulated here by scipy alone, by superposition of the two inputs' paths,
``scipy.signal.lsim(..., interp=False)`` (the input held between samples) for the heater and ``interp=True``
(linear between samples) for the outdoor temperature. The model is a one-node room (a new user's, reduced):
C·T' = P − G_a (T − T_a), T measured, C in kJ/K and G_a in W/K (time in s).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal

import symid as si
from symid.fit.timeseries.records import band_limited
from symid.fit.timeseries.response import simulate_output

CAP, COND = 500.0, 40.0  # kJ/K, W/K: a time constant of 12 500 s
DT, N = 600.0, 400  # 10 min samples, 2.8 days


def room() -> si.SecondOrderModel:
    """E x' = F x + G u with the capacity in E, in the form symid's affine models take (velocity output)."""
    cap, cond = si.parameters("cap cond", positive=True)
    return si.SecondOrderModel(M=[[1000 * cap]], V=[[cond]], K=[[0]], B=[[1, cond]], C=[[1]], output="velocity")


@pytest.fixture(scope="module")
def records() -> si.IOData:
    t = np.arange(N) * DT
    rng = np.random.default_rng(3)
    heater = 1500.0 * (rng.random(N // 6 + 1) < 0.5).repeat(6)[:N]  # on/off for an hour at a time
    outdoor = 5.0 + 4.0 * np.sin(2 * np.pi * t / 86_400.0) + np.cumsum(rng.standard_normal(N)) * 0.05
    a, b = -COND / (1000 * CAP), 1 / (1000 * CAP)
    held = scipy.signal.lsim(([[a]], [[b]], [[1]], [[0]]), heater, t, X0=[12.0], interp=False)[1]
    linear = scipy.signal.lsim(([[a]], [[COND * b]], [[1]], [[0]]), outdoor, t, X0=[0.0], interp=True)[1]
    return si.IOData(np.column_stack([heater, outdoor]), held + linear, DT)


def _fit(io: si.IOData, hold) -> si.IdentificationResult:
    return si.identify(room(), io, x0={"cap": 200.0, "cond": 100.0}, hold=hold, initial_state="estimate",
                       identifiability_check=False, progress=False)


def test_one_hold_per_input_fits_the_records_exactly(records):
    res = _fit(records, ["zoh", "foh"])
    assert res.success and res.options["hold"] == ["zoh", "foh"]
    np.testing.assert_allclose(res.theta_vector, [CAP, COND], rtol=1e-6)  # noise-free: to the simulation's rounding
    same = _fit(records, "zoh,foh")  # as the command line passes it
    np.testing.assert_allclose(same.theta_vector, res.theta_vector, rtol=1e-9)


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_one_hold_for_both_inputs_misses(records, hold):
    """Held, the temperature's ramps become steps; linear, the heater's steps become ramps: no exact fit."""
    res = _fit(records, hold)
    assert res.cost > 1e3 * _fit(records, ["zoh", "foh"]).cost
    assert np.max(np.abs(res.theta_vector / [CAP, COND] - 1)) > 1e-4


def test_held_inputs_are_held_in_the_simulation():
    """simulate_output with every input marked held is the zero-order hold's; with none, the linear one's."""
    A, B = np.array([[-0.3, 1.0], [-2.0, -0.5]]), np.array([[0.0, 1.0], [1.0, 0.5]])
    C, D = np.eye(2), np.zeros((2, 2))
    t = np.arange(50) * 0.4
    u = np.random.default_rng(0).standard_normal((50, 2))
    zoh = simulate_output(A, B, C, D, t, u, np.zeros(2), hold="zoh")
    foh = simulate_output(A, B, C, D, t, u, np.zeros(2), hold="foh")
    assert np.max(np.abs(zoh - foh)) > 0.1
    np.testing.assert_allclose(simulate_output(A, B, C, D, t, u, np.zeros(2), hold="foh", held=np.ones(2, bool)),
                               zoh, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(simulate_output(A, B, C, D, t, u, np.zeros(2), hold="foh", held=np.zeros(2, bool)),
                               foh, rtol=1e-10, atol=1e-12)


def test_band_limited_points_keep_a_held_input_held():
    t = np.arange(8) * 0.1
    rec = si.TimeSeries(t, np.column_stack([np.arange(8.0), np.sin(t)]), np.zeros((8, 1)))
    fine = band_limited(rec, "the record", 4, emphasis=0.0, holds=("zoh", "bandlimited"))
    np.testing.assert_array_equal(fine.u[:4, 0], [0.0, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(fine.u[4:8, 0], [1.0, 1.0, 1.0, 1.0])
    np.testing.assert_allclose(fine.u[::4, 1], np.sin(t), atol=1e-12)


@pytest.mark.parametrize("hold, match", [
    (["zoh"], "1 hold\\(s\\) for 2 input"),
    (["zoh", "linear"], "hold\\[1\\]"),
    ("zoh,foh,foh", "3 hold\\(s\\) for 2 input"),
    (3, "hold"),
])
def test_bad_holds_are_named(records, hold, match):
    with pytest.raises(si.OptionError, match=match):
        _fit(records, hold)


def test_validation_takes_one_hold_per_input(records):
    """si.validate (and the command line's validation after `--option hold=zoh,foh`) simulates as the fit did."""
    res = _fit(records, "zoh,foh")
    val = si.validate(room(), res.theta, records, hold="zoh,foh", initial_state="estimate")
    assert float(np.min(val.fit_percent)) > 99.99  # noise-free records, the estimate to rounding
    assert len(val.t_fine) == 1 and val.t_fine[0].size > records.n_samples  # the curve between samples drawn
