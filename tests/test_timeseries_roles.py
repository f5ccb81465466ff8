"""Input and output columns read the wrong way round: a failed fit's NEXT line asks (symid/fit/timeseries/roles.py).

Reference: the records are built here, a two-level PRBS through a first-order lag with 1 % noise, so which column is
the test signal is known.
"""

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
