"""Signal-layer robustness: N4SID never raises a raw numpy error, a constant (offset) input, d2c dropping modes."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import scipy.signal

import symid as si
from symid.signal.simulate import zoh_discretize


def _drifting_record():
    """A drifting, poorly exciting record on which a 5-state N4SID estimate has a pole at |z| ≈ 1.1: before the
    check, numpy raised LinAlgError('SVD did not converge in Linear Least Squares') from the B, D, x0 step."""
    rng = np.random.default_rng(0)
    N = 20_000
    u = np.cumsum(rng.standard_normal(N)) * 0.01 + rng.standard_normal(N) * 0.001
    y = np.cumsum(scipy.signal.lfilter([0.01], [1, -0.99], u)) + 0.1 * rng.standard_normal(N)
    return si.IOData(u, y, 0.001)


def test_unstable_n4sid_estimate_is_a_named_data_error():
    with pytest.raises(si.DataError, match=r"N4SID's estimate of A is unstable: pole z = .* over the 20000 samples"):
        si.n4sid(_drifting_record(), 5, feedthrough=False)


def _two_mode():
    A = np.array([[0, 1, 0, 0], [-4.0, -0.2, 0, 0], [0, 0, 0, 1], [0, 0, -25.0, -0.5]])
    return si.BlackBox(A, [[0], [1], [0], [1]], [[1, 0, 1, 0]])


def test_constant_input_is_an_offset_recovered_exactly():
    rng = np.random.default_rng(1)
    N, dt, c, d = 3000, 0.05, 0.7, -0.2
    u = rng.standard_normal(N)
    bb = _two_mode()
    y = si.simulate_io(bb, None, u + c, dt).y[:, 0] + d  # a constant force c and a sensor bias d
    for io in (si.IOData(u, y, dt), si.IOData(np.column_stack([u, np.ones(N)]), y, dt)):
        dss = si.n4sid(io, 4, offset=io.n_inputs == 1)
        assert dss.B.shape == (4, 2) and dss.D.shape == (1, 2)
        ct = dss.to_continuous()
        # the offset input's static gain: c·G(0) + d, with G(0) = 1/4 + 1/25 (thesis-free: C A⁻¹ B of _two_mode)
        static = -(ct.C @ np.linalg.solve(ct.A, ct.B) - ct.D)[0]
        np.testing.assert_allclose(static[1], c * (1 / 4 + 1 / 25) + d, rtol=1e-7)
        w = np.array([0.5, 2.0, 5.0])
        np.testing.assert_allclose(ct.frequency_response(w)[:, 0, 0], bb.frequency_response(w)[:, 0, 0], rtol=1e-7)


def test_constant_input_errors():
    rng = np.random.default_rng(2)
    u = rng.standard_normal(500)
    y = scipy.signal.lfilter([0.5], [1, -0.5], u)
    with pytest.raises(si.DataError, match="inputs 1, 2 are all constant"):
        si.n4sid(si.IOData(np.column_stack([u, np.ones(500), 2 * np.ones(500)]), y, 0.1), 1)
    with pytest.raises(si.DataError, match="input 1 is zero"):
        si.n4sid(si.IOData(np.column_stack([u, np.zeros(500)]), y, 0.1), 1)
    with pytest.raises(si.DataError, match="offset must be True or False"):
        si.n4sid(si.IOData(u, y, 0.1), 1, offset="yes")


def _with_nyquist_mode():
    dt = 0.1
    A = np.array([[0, 1], [-4.0, -0.2]])
    Ad, Bd = zoh_discretize(A, np.array([[0.0], [1.0]]), dt)
    T = np.random.default_rng(0).standard_normal((3, 3))  # hide the modes in a random basis
    Ad3 = T @ scipy.linalg.block_diag(Ad, [[-0.9]]) @ np.linalg.inv(T)
    return Ad3, T @ np.vstack([Bd, [[0.3]]]), np.array([[1.0, 0, 0.5]]) @ np.linalg.inv(T), dt, A


def test_d2c_drops_a_nyquist_mode_on_request_and_keeps_the_others_exactly():
    Ad, Bd, Cd, dt, A = _with_nyquist_mode()
    with pytest.raises(si.DataError, match=r"eigenvalue -0.9 .* drop that mode with band=\(0, w_high\)"):
        si.d2c(Ad, Bd, Cd, dt=dt)
    bb = si.d2c(Ad, Bd, Cd, dt=dt, band=(0, 0.9 * np.pi / dt))
    assert bb.n_states == 2
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(bb.A)), np.sort_complex(np.linalg.eigvals(A)),
                               rtol=1e-12)
    w = np.array([0.5, 2.0, 5.0])
    truth = si.BlackBox(A, [[0], [1]], [[1, 0]])
    np.testing.assert_allclose(bb.frequency_response(w), truth.frequency_response(w), rtol=1e-11)
    dss = si.signal.subspace.DiscreteStateSpace(Ad, Bd, Cd, np.zeros((1, 1)), dt)
    np.testing.assert_allclose(dss.to_continuous(band=(0, 30.0)).frequency_response(w), truth.frequency_response(w),
                               rtol=1e-11)


def test_d2c_band_errors():
    Ad, Bd, Cd, dt, _ = _with_nyquist_mode()
    with pytest.raises(si.DataError, match="no mode of the discrete model"):
        si.d2c(Ad, Bd, Cd, dt=dt, band=(100.0, 200.0))
    with pytest.raises(si.DataError, match="band must be"):
        si.d2c(Ad, Bd, Cd, dt=dt, band=(5.0, 1.0))
    with pytest.raises(si.DataError, match="band must be a pair"):
        si.d2c(Ad, Bd, Cd, dt=dt, band="all")
