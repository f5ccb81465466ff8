"""N4SID and the exact zero-order-hold d2c (thesis Algorithms 6.1/7.1, steps 1 and 2)."""

from __future__ import annotations

import numpy as np
import pytest

import symid as si
from symid.signal.simulate import zoh_discretize
from symid.signal.subspace import DiscreteStateSpace


def random_stable(rng, n, m, p, margin=0.3):
    A = rng.standard_normal((n, n))
    A -= (np.linalg.eigvals(A).real.max() + margin) * np.eye(n)
    return A, rng.standard_normal((n, m)), rng.standard_normal((p, n)), rng.standard_normal((p, m))


def rel_frf_error(bb_est, bb_true, w):
    H, H0 = bb_est.frequency_response(w), bb_true.frequency_response(w)
    return float(np.max(np.abs(H - H0)) / np.max(np.abs(H0)))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_n4sid_mimo_noise_free_matches_the_true_frequency_response(seed):
    rng = np.random.default_rng(seed)
    A, B, C, D = random_stable(rng, 4, 2, 3)
    truth = si.BlackBox(A, B, C, D)
    io = si.simulate_io(truth, None, rng.standard_normal((600, 2)), dt=0.05)
    dss = si.n4sid(io, 4)
    w = np.logspace(-2, np.log10(np.pi / 0.05) - 0.1, 80)
    # discrete-time response against the exact ZOH sampling of the truth
    Ad, Bd = zoh_discretize(A, B, 0.05)
    exact = DiscreteStateSpace(Ad, Bd, C, D, 0.05)
    H, H0 = dss.frequency_response(w), exact.frequency_response(w)
    assert np.max(np.abs(H - H0)) / np.max(np.abs(H0)) < 1e-6  # issue 7: 1e-6 relative on noise-free data
    # and, after d2c, the continuous-time response
    assert rel_frf_error(dss.to_continuous(), truth, w) < 1e-6


def test_n4sid_strictly_proper_and_oversampled_second_order_model():
    """The 3-DOF system of thesis (7-17) at dt = 1 ms, N = 5000 (§7-6-1): the record is short for its slowest mode.

    Noise-free, so the only error is rounding, and this problem amplifies it: the discrete
    poles lie within 5e-5 of the unit circle and the oblique projection has σ1/σ6 = 1.3e7.
    A perturbation of the record of relative size ε (machine epsilon) moves the estimated
    discrete poles by about ε·σ1/σ6, the continuous ones by that over dt, and the
    frequency response near the slowest, lightest-damped mode by that over |Re λ|: the
    first-order bound ε·(σ1/σ6)/(dt·min|Re λ|) = 6e-5 asserted here. Measured: 1-ulp
    perturbations of y give errors 1.2e-7 … 7.1e-6 (median 1.6e-6, 100 draws); the
    unperturbed record gives 6.3e-7 on one machine and 1.06e-6 on another.
    """
    entry = si.load_model("msd3_similarity")
    truth = si.BlackBox(*entry.model.state_space(entry.truth))
    io = entry.data()
    dss = si.n4sid(io, 6, feedthrough=False)
    assert dss.horizon == 10 and np.all(dss.D == 0)
    sv = dss.singular_values
    assert sv[5] / sv[6] > 1e6  # the order is clear-cut: noise-free data
    bound = np.finfo(float).eps * (sv[0] / sv[5]) / (io.dt * np.min(np.abs(np.linalg.eigvals(truth.A).real)))
    assert bound < 1e-4  # 6.0e-5 on this record (the derivation above)
    assert rel_frf_error(dss.to_continuous(), truth, np.logspace(-2, 2, 200)) < bound


def test_n4sid_with_noise_stays_close():
    """0.1 % output noise: the weakest state (third singular value 9e-3) is still well above the noise floor."""
    rng = np.random.default_rng(5)
    A, B, C, D = random_stable(rng, 3, 1, 1, margin=0.5)
    truth = si.BlackBox(A, B, C, D)
    io = si.simulate_io(truth, None, rng.standard_normal(4000), dt=0.1, noise=1e-3, seed=1)
    bb = si.n4sid(io, 3).to_continuous()
    assert rel_frf_error(bb, truth, np.logspace(-1.5, 1, 50)) < 1e-2  # measured 4.7e-3


def test_n4sid_bad_input():
    rng = np.random.default_rng(0)
    A, B, C, D = random_stable(rng, 3, 1, 1)
    u = rng.standard_normal(200)
    io = si.simulate_io(si.BlackBox(A, B, C, D), None, u, dt=0.1)
    with pytest.raises(si.DataError, match="too short for order 3"):
        si.n4sid(si.IOData(u[:15], io.y[:15], 0.1), 3)
    with pytest.raises(si.DataError, match="at most 3 state"):
        si.n4sid(io, 5)
    with pytest.raises(si.DataError, match="not persistently exciting"):
        si.n4sid(si.IOData(np.ones(200), io.y, 0.1), 3)
    with pytest.raises(si.DataError, match="needs input/output records"):
        si.n4sid((u, io.y), 3)
    with pytest.raises(si.DataError, match="order must be a positive integer"):
        si.n4sid(io, 0)
    with pytest.raises(si.DataError, match="can reveal at most 2 states"):
        si.n4sid(io, 3, horizon=2)


def test_d2c_round_trip_many_random_systems():
    rng = np.random.default_rng(11)
    worst = 0.0
    for _ in range(100):
        n, m = int(rng.integers(1, 7)), int(rng.integers(1, 4))
        A = rng.standard_normal((n, n)) * rng.uniform(0.1, 3)
        B = rng.standard_normal((n, m))
        dt = float(rng.uniform(1e-3, 0.5))
        if np.abs(np.linalg.eigvals(A).imag).max() * dt >= 3.0:  # beyond Nyquist: d2c returns an alias
            continue
        Ad, Bd = zoh_discretize(A, B, dt)
        bb = si.d2c(Ad, Bd, np.ones((1, n)), None, dt)
        worst = max(worst, np.abs(bb.A - A).max() / max(1, np.abs(A).max()),
                    np.abs(bb.B - B).max() / max(1, np.abs(B).max()))
    assert worst < 1e-10  # issue 7: c2d → d2c round trip to 1e-10


def test_d2c_integrator_and_feedthrough():
    A, B = np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0], [1.0]])  # double integrator: singular A
    Ad, Bd = zoh_discretize(A, B, 0.2)
    bb = si.d2c(Ad, Bd, [[1.0, 0.0]], [[0.5]], dt=0.2)
    np.testing.assert_allclose(bb.A, A, atol=1e-12)
    np.testing.assert_allclose(bb.B, B, atol=1e-12)
    np.testing.assert_allclose(bb.D, [[0.5]], rtol=0, atol=0)


@pytest.mark.parametrize("Ad", [[[-0.5]], [[0.0]], [[0.9, 0.0], [0.0, -0.2]]])
def test_d2c_refuses_when_no_real_logarithm_exists(Ad):
    n = len(Ad)
    with pytest.raises(si.DataError, match="negative real axis"):
        si.d2c(Ad, np.ones((n, 1)), np.ones((1, n)), dt=0.1)


def test_d2c_bad_input():
    with pytest.raises(si.DataError, match="needs the sample time dt"):
        si.d2c([[0.5]], [[1.0]], [[1.0]])
    with pytest.raises(si.DataError, match="dt"):
        si.d2c([[0.5]], [[1.0]], [[1.0]], dt=-1)
    with pytest.raises(si.DataError, match="B must have 1 rows"):
        si.d2c([[0.5]], [[1.0], [2.0]], [[1.0]], dt=0.1)


@pytest.mark.parametrize("seed", [0, 1])
def test_n4sid_does_not_depend_on_the_units_of_any_channel(seed):
    """Each input and output in other units (factors 1e-3 … 1e4, one per channel) on noisy records: the same poles
    (to rounding), and B, C, D follow the units. Without normalise=True the projections weigh the channels by their
    size: a new user's thermal network with one output in mK had its poles moved by 30 %."""
    rng = np.random.default_rng(seed)
    A, B, C, D = random_stable(rng, 3, 2, 3)
    truth = si.BlackBox(A, B, C, D)
    io = si.simulate_io(truth, None, rng.standard_normal((800, 2)), dt=0.05, noise=0.01, seed=seed)
    gu, gy = np.array([1e-3, 10.0]), np.array([1e4, 1.0, 1e-2])
    ref = si.n4sid(io, 3)
    out = si.n4sid(si.IOData(io.u * gu, io.y * gy, io.dt), 3)
    np.testing.assert_allclose(np.sort_complex(out.poles), np.sort_complex(ref.poles), rtol=1e-9)
    w = np.logspace(-1, 1.5, 30)
    np.testing.assert_allclose(out.frequency_response(w), gy[:, None] * ref.frequency_response(w) / gu[None, :],
                               rtol=1e-8)
    raw = si.n4sid(si.IOData(io.u * gu, io.y * gy, io.dt), 3, normalise=False)  # the channels weighed by size
    assert np.max(np.abs(np.sort_complex(raw.poles) - np.sort_complex(ref.poles))) > 1e-6
