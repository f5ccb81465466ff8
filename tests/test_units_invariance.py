"""Units do not matter (issue 14 item 3): rescaling a parameter, the frequency (or time) axis or the data by a
power of ten in 1e-6 … 1e6 changes each method's estimate exactly as the physics says, and nothing else.

The system is the two-mass chain of thesis (4-19)–(4-21) (truth (4-20), 30 lines in 0.5–2 rad/s, position of
mass 1, force on mass 1), with 1 % noise so that the estimate is a specific least-squares point, from a start
off by factors 0.4–3 (IPOPT needs 17 iterations there). The transformations, for H(ω) = C (K − ω²M + jωV)⁻¹ B:

- a parameter p declared as 10^a·p' (a unit change of p): p̂' = p̂ / 10^a, the others unchanged;
- frequencies ω' = α ω (a time unit change): the same H at ω' needs M' = M/α², V' = V/α, K' = K;
- data H' = β H (a unit change of the output or the input): M, V, K all divided by β.

Spectra Φyy = H Φuu Hᴴ follow H (Φyy' = β² Φyy). For output-error fitting of sampled records, time t' = t/α
and outputs y' = β y transform alike.
"""

from __future__ import annotations

import numpy as np
import pytest

import symid as si
from symid.fit.frf.ipopt import IpoptFRF
from symid.fit.frf.ls import LinearFRF
from symid.fit.spectra.ipopt import IpoptPSD
from symid.fit.timeseries.oe import OutputError

TRUTH = np.array([1.0, 1.0, 0.1, 0.3, 2.0, 1.0])  # thesis (4-20): m1, m2, c1, c2, k1, k2
W = np.logspace(np.log10(0.5), np.log10(2.0), 30)  # thesis §4-6-2
START = TRUTH * np.array([2.0, 0.5, 1.5, 3.0, 0.7, 0.4])
EXPONENTS = (-6, -3, 3, 6)
RTOL = 1e-9  # measured: 1e-14 … 6e-15 for ipopt, ls and spectra (rounding only)


def chain(factors=None, sensors=((1, 0),)) -> si.SecondOrderModel:
    """The 2-DOF chain with each parameter entering as factor × parameter (a unit change)."""
    factors = np.ones(6) if factors is None else factors
    names = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    m1, m2, c1, c2, k1, k2 = (f * p for f, p in zip(factors, names, strict=True))
    return si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                               K=[[k1 + k2, -k2], [-k2, k2]], B=[[1], [0]], C=[list(r) for r in sensors],
                               parameters=list(names))


def time_factor(alpha: float) -> np.ndarray:
    """θ' / θ when ω' = α ω: m / α², c / α, k."""
    return np.array([alpha**-2, alpha**-2, 1 / alpha, 1 / alpha, 1.0, 1.0])


def same(out, ref, back):
    """``out`` (the rescaled problem's outcome) is ``ref`` once mapped back by ``back``; nothing else moved."""
    np.testing.assert_allclose(out.theta * back, ref.theta, rtol=RTOL)
    assert out.cost == pytest.approx(ref.cost, rel=1e-7)
    assert (out.status, out.iterations, out.success) == (ref.status, ref.iterations, ref.success)


def draws(count: int = 3) -> list[np.ndarray]:
    """Exponents of ten for every parameter at once, seeded, in −6 … 6."""
    rng = np.random.default_rng(14)
    return [rng.integers(-6, 7, size=6) for _ in range(count)]


# -- IPOPT on a frequency response ------------------------------------------------------------------

@pytest.fixture(scope="module")
def frf():
    return si.simulate_frf(chain(), TRUTH, W, noise=0.01, seed=3)


@pytest.fixture(scope="module")
def ipopt_ref(frf):
    out = IpoptFRF(chain(), frf).run(START)
    assert out.status == "Solve_Succeeded" and np.all(np.abs(out.theta / TRUTH - 1) < 0.05)
    return out


@pytest.mark.parametrize("k", range(6))
@pytest.mark.parametrize("a", (-6, 6))
def test_ipopt_frf_one_parameter_rescaled(frf, ipopt_ref, k, a):
    f = np.ones(6)
    f[k] = 10.0**a
    same(IpoptFRF(chain(f), frf).run(START / f), ipopt_ref, f)


@pytest.mark.parametrize("exps", draws(), ids=lambda e: ",".join(map(str, e)))
def test_ipopt_frf_every_parameter_rescaled_at_once(frf, ipopt_ref, exps):
    f = 10.0**exps
    same(IpoptFRF(chain(f), frf).run(START / f), ipopt_ref, f)


@pytest.mark.parametrize("a", EXPONENTS)
def test_ipopt_frf_frequency_axis_and_data_rescaled(frf, ipopt_ref, a):
    alpha = 10.0**a
    T = time_factor(alpha)
    same(IpoptFRF(chain(), si.FrequencyData(W * alpha, frf.H)).run(START * T), ipopt_ref, 1 / T)
    same(IpoptFRF(chain(), si.FrequencyData(W, frf.H * alpha)).run(START / alpha), ipopt_ref, alpha)


def test_ipopt_frf_all_units_changed_together(frf, ipopt_ref):
    f = 10.0 ** np.array([3, -2, 5, -6, 1, 4])
    alpha, beta = 1e-4, 1e5
    T = time_factor(alpha) / beta / f
    data = si.FrequencyData(W * alpha, frf.H * beta)
    same(IpoptFRF(chain(f), data).run(START * T), ipopt_ref, 1 / T)


def test_the_unscaled_set_up_was_not_invariant(frf, ipopt_ref):
    """What the start scaling is for: with θ as it is (scale 1), masses declared in a unit 1e6 times larger
    (unknowns of 1e-6) are another problem for IPOPT (measured: an estimate 8e10 × off); a given ``scale``
    equal to the start restores invariance."""
    f = np.array([1e6, 1e6, 1.0, 1.0, 1.0, 1.0])
    out = IpoptFRF(chain(f), frf, scale=np.ones(6)).run(START / f)
    assert np.max(np.abs(out.theta * f / ipopt_ref.theta - 1)) > 1.0
    same(IpoptFRF(chain(f), frf, scale=np.abs(START / f)).run(START / f), ipopt_ref, f)


# -- the linear least squares (ls) ------------------------------------------------------------------------

@pytest.fixture(scope="module")
def two_sensors():
    model = chain(sensors=((1, 0), (0, 1)))
    data = si.simulate_frf(model, TRUTH, W, noise=0.01, seed=3)
    return data, LinearFRF(model, data).run(START)


@pytest.mark.parametrize("exps", [np.full(6, 6), np.full(6, -6), *draws()], ids=lambda e: ",".join(map(str, e)))
def test_ls_parameters_rescaled(two_sensors, exps):
    data, ref = two_sensors
    f = 10.0**exps
    out = LinearFRF(chain(f, ((1, 0), (0, 1))), data).run(START / f)
    np.testing.assert_allclose(out.theta * f, ref.theta, rtol=RTOL)
    assert out.cost == pytest.approx(ref.cost, rel=1e-7)


@pytest.mark.parametrize("a", EXPONENTS)
def test_ls_frequency_axis_and_data_rescaled(two_sensors, a):
    data, ref = two_sensors
    alpha = 10.0**a
    model = chain(sensors=((1, 0), (0, 1)))
    out = LinearFRF(model, si.FrequencyData(W * alpha, data.H)).run(START)
    np.testing.assert_allclose(out.theta / time_factor(alpha), ref.theta, rtol=RTOL)
    out = LinearFRF(model, si.FrequencyData(W, data.H * alpha)).run(START)
    np.testing.assert_allclose(out.theta * alpha, ref.theta, rtol=RTOL)


# -- IPOPT on spectra ------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def spectra():
    spec = si.simulate_spectra(chain(), TRUTH, W, Phi_uu=1.0, noise=0.01, seed=3)
    ref = IpoptPSD(chain(), spec).run(START)
    assert ref.status == "Solve_Succeeded"
    return spec, ref


@pytest.mark.parametrize("exps", [np.full(6, 6), np.full(6, -6), *draws()], ids=lambda e: ",".join(map(str, e)))
def test_ipopt_spectra_parameters_rescaled(spectra, exps):
    spec, ref = spectra
    f = 10.0**exps
    same(IpoptPSD(chain(f), spec).run(START / f), ref, f)


@pytest.mark.parametrize("a", EXPONENTS)
def test_ipopt_spectra_frequency_axis_and_data_rescaled(spectra, a):
    spec, ref = spectra
    alpha = 10.0**a
    T = time_factor(alpha)
    moved = si.SpectralData(W * alpha, spec.Phi_yy, spec.Phi_uu)
    same(IpoptPSD(chain(), moved).run(START * T), ref, 1 / T)
    louder = si.SpectralData(W, spec.Phi_yy * alpha**2, spec.Phi_uu)
    same(IpoptPSD(chain(), louder).run(START / alpha), ref, alpha)


# -- output error on sampled records (oe) -----------------------------------------------------------------

def oscillator(factors=None) -> si.SecondOrderModel:
    factors = np.ones(3) if factors is None else factors
    m, c, k = si.parameters("m c k", positive=True)
    return si.SecondOrderModel(M=[[factors[0] * m]], V=[[factors[1] * c]], K=[[factors[2] * k]], B=[[1]], C=[[1]],
                               parameters=[m, c, k])


OE_TRUTH = np.array([2.0, 0.8, 50.0])
OE_START = OE_TRUTH * np.array([1.5, 0.6, 1.3])
DT = 0.05


@pytest.fixture(scope="module")
def records():
    u = np.random.default_rng(0).standard_normal(200)
    io = si.simulate_io(oscillator(), OE_TRUTH, u, DT, noise=0.01, seed=2)
    ref = OutputError(oscillator(), io, scale=OE_START).run(OE_START)
    assert ref.status == "Solve_Succeeded"
    return io, ref


@pytest.mark.parametrize("a", (-6, 6))
@pytest.mark.parametrize("k", range(3))
def test_oe_parameter_rescaled_with_the_start_as_scale(records, k, a):
    io, ref = records
    f = np.ones(3)
    f[k] = 10.0**a
    out = OutputError(oscillator(f), io, scale=OE_START / f).run(OE_START / f)
    np.testing.assert_allclose(out.theta * f, ref.theta, rtol=RTOL)
    assert (out.status, out.iterations) == (ref.status, ref.iterations)


@pytest.mark.xfail(strict=True, reason="oe (symid/fit/timeseries/oe.py) scales θ by scale=1 unless given: a "
                                       "parameter in other units is another problem for IPOPT (measured: ×1e6 on m "
                                       "gives an estimate 4e6 × off); reported in the issue-14 IPOPT note")
def test_oe_parameter_rescaled_by_default(records):
    io, ref = records
    f = np.array([1e6, 1.0, 1.0])
    out = OutputError(oscillator(f), io).run(OE_START / f)
    np.testing.assert_allclose(out.theta * f, ref.theta, rtol=1e-6)


@pytest.mark.xfail(strict=True, reason="oe on a time axis or outputs rescaled by 1e±6 stops at IPOPT's iteration "
                                       "limit (500) even with scale= the start (measured: estimates within 2e-8, "
                                       "status Maximum_Iterations_Exceeded); reported in the issue-14 IPOPT note")
@pytest.mark.parametrize("a", (-6, 6))
def test_oe_time_axis_and_outputs_rescaled(records, a):
    io, ref = records
    alpha = 10.0**a
    T = time_factor(alpha)[[0, 2, 4]]
    out = OutputError(oscillator(), si.IOData(io.u, io.y, DT / alpha), scale=OE_START * T).run(OE_START * T)
    assert out.status == ref.status
    np.testing.assert_allclose(out.theta / T, ref.theta, rtol=RTOL)
    out = OutputError(oscillator(), si.IOData(io.u, io.y * alpha, DT), scale=OE_START / alpha).run(OE_START / alpha)
    assert out.status == ref.status
    np.testing.assert_allclose(out.theta * alpha, ref.theta, rtol=RTOL)
