"""Starts at physical scale (issue 18, item 3; issue 14): typical values read off a frequency response by
dimensional analysis, default draws around them, the thesis's N(0, 1) draws as an explicit option."""

from __future__ import annotations

import numpy as np
import pytest

import symid as si
from symid.fit.frf.modal import black_box_start
from symid.fit.frf.scale import parameter_roles, typical_scale
from symid.fit.starts import draw_starts


def chain(n_units=1.0, t_units=1.0):
    """Two masses in SI units (kg, N·s/m, N/m), optionally in other force and time units."""
    m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    model = si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                                K=[[k1 + k2, -k2], [-k2, k2]], B=[[0], [1]], C=[[0, 1]], output="velocity")
    truth = np.array([12.0, 3.0, 40.0, 15.0, 2e6, 5e5])
    truth = np.concatenate([truth[:2] * t_units**2, truth[2:4] * t_units, truth[4:]]) * n_units
    return model, truth


@pytest.mark.parametrize(("n_units", "t_units"), [(1.0, 1.0), (1e-3, 1.0), (1e6, 1e-3), (1.0, 1e3)])
def test_typical_values_are_within_a_factor_ten_in_any_units(n_units, t_units):
    model, truth = chain(n_units, t_units)
    lam = np.abs(np.linalg.eigvals(model.state_space(truth).A))
    frf = si.simulate_frf(model, truth, np.logspace(np.log10(0.3 * lam.min()), np.log10(3 * lam.max()), 80))
    typ = typical_scale(model, frf)
    # dimensional analysis: masses L/ω0², dampers 2·0.05·L/ω0, springs L; the measured population of
    # benchmarks/population.py has 90-97 % of such parameters within a factor 10 (gains aside)
    assert np.all(np.abs(np.log10(typ / truth)) < 1)


def test_roles_follow_the_first_matrix_a_parameter_appears_in():
    a, b, c = si.parameters("a b c", positive=True)
    ss = si.StateSpaceModel(A=[[-a, 0], [1, -a]], B=[[b], [0]], C=[[0, c]])
    assert parameter_roles(ss) == ("A", "B", "C")


def test_default_draws_are_at_the_data_scale_and_normal_draws_are_the_thesis():
    model, truth = chain()
    frf = si.simulate_frf(model, truth, np.logspace(1.5, 3.5, 60))
    typ = typical_scale(model, frf)
    bb = black_box_start(model, frf, typ, seed=0)
    x = np.array(draw_starts(model, frf, 200, seed=0))
    np.testing.assert_array_equal(x[0], bb.theta)  # the black-box start first
    assert np.all(np.abs(np.log(x[1:] / bb.typical)) <= np.log(3) + 1e-12)  # log-uniform within a factor 3
    assert np.all(np.abs(np.log10(bb.typical / typ)) < 1.5)  # its magnitudes refine the dimensional analysis
    normal = np.array(draw_starts(model, frf, 200, seed=0, draws="normal"))
    assert np.all(normal >= 0) and np.max(normal) < 6  # |N(0, 1)|: the thesis's draws, not at physical scale
    given = np.array(draw_starts(model, frf, 50, seed=0, scale=truth))  # the user's scale= wins for the draws
    assert np.all(np.abs(np.log(given[1:] / truth)) <= np.log(3) + 1e-12)
    own = np.array(draw_starts(model, frf, 5, seed=0, x0=truth))  # a user's start replaces the black-box start
    np.testing.assert_array_equal(own[0], truth)
    assert np.all(np.abs(np.log(own[1:] / typ)) <= np.log(3) + 1e-12)


def test_identify_without_a_start_reaches_a_physical_model():
    model, truth = chain()
    lam = np.abs(np.linalg.eigvals(model.state_space(truth).A))
    frf = si.simulate_frf(model, truth, np.logspace(np.log10(0.3 * lam.min()), np.log10(3 * lam.max()), 80))
    res = si.identify(model, frf, seed=0, identifiability_check=False)  # default method and default starts
    assert res.method == "auto" and res.success
    np.testing.assert_allclose(res.theta_vector, truth, rtol=1e-6)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"draws": "uniform"}, "draws must be one of"),
    ({"scale": [1.0, 2.0]}, "scale"),
])
def test_bad_draws_are_named(kwargs, match):
    model, truth = chain()
    frf = si.simulate_frf(model, truth, np.logspace(1.5, 3.5, 20))
    with pytest.raises(si.OptionError, match=match):
        draw_starts(model, frf, 3, seed=0, **kwargs)


def test_data_without_typical_values_need_a_scale():
    k, g = si.parameters("k g", positive=True)
    model = si.StateSpaceModel(A=[[-k]], B=[[g]], C=[[1]])
    io = si.simulate_io(model, [0.5, 2.0], np.random.default_rng(0).standard_normal(200), dt=0.1)
    with pytest.raises(si.OptionError, match="needs typical values: give scale="):
        draw_starts(model, io, 3, seed=0, draws="scale")
    x = np.array(draw_starts(model, io, 3, seed=0, draws="scale", scale=[0.5, 2.0]))
    assert np.all(np.abs(np.log(x / [0.5, 2.0])) <= np.log(3) + 1e-12)
