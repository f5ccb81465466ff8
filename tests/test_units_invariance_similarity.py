"""The similarity methods follow the units (issue 14 item 3): a parameter declared in other units, the time axis
or the outputs in other units (powers of ten to 1e±6) change the estimate exactly as the physics says.

Reference system: the 2-DOF chain of thesis (4-19)–(4-21) (m = 1, 2 kg, c = 0.1, 0.3 N·s/m, k = 2, 1 N/m; force on
mass 1), positions of both masses measured (the full set of sensors of thesis §7-5-2), 3000 samples at 0.05 s of a
white-noise force with 1 % output noise (seeded), through N4SID and d2c to a black box of order 4. With time
t' = t / c: M' = M c², V' = V c, K' = K; with outputs y' = β y: M, V, K divided by β.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import symid as si
from symid.fit.registry import prepare

TRUTH = np.array([1.0, 2.0, 0.1, 0.3, 2.0, 1.0])  # m1 m2 c1 c2 k1 k2
START = TRUTH * np.array([1.3, 0.7, 1.5, 0.8, 1.2, 0.9])
DT = 0.05
RTOL = 1e-9


def two_dof(factors=None):
    factors = np.ones(6) if factors is None else factors
    names = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    m1, m2, c1, c2, k1, k2 = (f * p for f, p in zip(factors, names, strict=True))
    return si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]], K=[[k1 + k2, -k2], [-k2, k2]],
                               B=[[1], [0]], C=[[1, 0], [0, 1]], parameters=list(names))


def time_factor(c):
    """θ' / θ with time t' = t / c (sample time dt' = dt / c)."""
    return np.array([c**-2, c**-2, 1 / c, 1 / c, 1.0, 1.0])


@pytest.fixture(scope="module")
def records():
    u = np.random.default_rng(0).standard_normal(3000)
    return si.simulate_io(two_dof(), TRUTH, u, DT, noise=0.01, seed=1)


def estimate(model, data, method, x0, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", si.IdentifiabilityWarning)
        return prepare(model, data, method, options).run(x0)


# -- the linear special case (ls, thesis §7-5-2) ----------------------------------------------------------

@pytest.fixture(scope="module")
def ls_ref(records):
    ref = estimate(two_dof(), records, "ls", START)
    assert np.max(np.abs(ref.theta / TRUTH - 1)) < 0.02  # 1 % noise: a least-squares point near the truth
    return ref


@pytest.mark.parametrize("k", [0, 4])
@pytest.mark.parametrize("a", [-6, 6])
def test_ls_parameter_in_other_units(records, ls_ref, k, a):
    """Before: a mass declared in units of 1e6 kg made the full-rank system look rank 5 of 6 (a ModelError)."""
    f = np.ones(6)
    f[k] = 10.0**a
    out = estimate(two_dof(f), records, "ls", START / f)
    np.testing.assert_allclose(out.theta * f, ls_ref.theta, rtol=RTOL)


@pytest.mark.parametrize("a", [-6, -3, 3, 6])
def test_ls_time_axis_in_other_units(records, ls_ref, a):
    """Before (plain least squares over blocks of equations in different units): 50–200 % apart."""
    c = 10.0**a
    T = time_factor(c)
    out = estimate(two_dof(), si.IOData(records.u, records.y, DT / c), "ls", START * T)
    np.testing.assert_allclose(out.theta / T, ls_ref.theta, rtol=RTOL)


@pytest.mark.parametrize("a", [-6, -3, 3, 6])
def test_ls_outputs_in_other_units(records, ls_ref, a):
    """Outputs × 1e±6 reach the black box through N4SID, whose LQ factorisation of input and output Hankel rows
    1e±6 apart is equivariant to its rounding only: the black box moves by up to 1e-8 relative (IPOPT on its
    frequency response moves alike, measured 1e-8), so 1e-7 here; the time axis above does not enter N4SID."""
    beta = 10.0**a
    out = estimate(two_dof(), si.IOData(records.u, records.y * beta, DT), "ls", START / beta)
    np.testing.assert_allclose(out.theta * beta, ls_ref.theta, rtol=1e-7 if abs(a) == 6 else RTOL)


# -- ALS, GB and IPOPT on the similarity misfit (thesis ch. 6, appendix C) ---------------------------------
#
# A state-space model A = [[0, 1], [a, b]], B = [0; c], C = [1, 0] (truth a = −2, b = −0.5, c = 1.5), its exact
# black box in another basis. With T₀ from the start (aux_init="model", (C-7)) every method works on θ / |θ₀| and
# T by its rows at the start: a parameter declared in other units gives the same iterations and the same estimate
# (measured: 4e-15 at most). The time axis, the inputs and the outputs in other units give the same iterations too
# (symid.fit.similarity.start.working_problem). So does the default aux_init="random": its T₀ is seeded by numbers
# of the start's model that no unit changes (symid.fit.similarity.start.start_key); it was seeded by the bytes of
# the start, and a start in other units drew another T₀ (a new user's two-compartment model: GB reached the truth
# from 3 of 6 unit variants of one start).

def state_space(factors=None):
    factors = np.ones(3) if factors is None else factors
    a, b, c = si.parameters("a b c")
    return si.StateSpaceModel(A=[[0, 1], [a * factors[0], b * factors[1]]], B=[[0], [c * factors[2]]], C=[[1, 0]],
                              parameters=[a, b, c])


SS_TRUTH = np.array([-2.0, -0.5, 1.5])
SS_START = SS_TRUTH * np.array([1.3, 0.6, 0.8])


@pytest.fixture(scope="module")
def black_box():
    A, B, C, D = state_space().state_space(SS_TRUTH)
    T = np.array([[1.0, 0.4], [-0.3, 0.8]])
    return si.BlackBox(T @ A @ np.linalg.inv(T), T @ B, C @ np.linalg.inv(T), D)


@pytest.mark.parametrize("method", ["als", "gb", "ipopt"])
def test_similarity_methods_follow_a_parameter_in_other_units(black_box, method):
    ref = estimate(state_space(), black_box, method, SS_START, aux_init="model")
    assert np.max(np.abs(ref.theta / SS_TRUTH - 1)) < 1e-5  # ALS stops at its step tolerance 1e-6
    for k in range(3):
        for a in (-6, 6):
            f = np.ones(3)
            f[k] = 10.0**a
            out = estimate(state_space(f), black_box, method, SS_START / f, aux_init="model")
            np.testing.assert_allclose(out.theta * f, ref.theta, rtol=RTOL)
            assert (out.status, out.iterations) == (ref.status, ref.iterations)


@pytest.mark.parametrize("method", ["als", "gb", "ipopt"])
def test_similarity_methods_follow_the_time_axis(black_box, method):
    """Before: the misfit (C-1) summed ‖T𝔸 − A(θ)T‖², ‖T𝔹 − B(θ)‖² and ‖ℂ − C(θ)T‖², blocks in different units:
    with 𝔸 × 1e6 ALS stopped after 1 sweep, GB after 4 iterations, IPOPT at its 3000-iteration limit, 40 % off.
    Now the methods work with time in units of 1/ρ(𝔸) (symid.fit.similarity.start.time_normalised)."""
    ref = estimate(state_space(), black_box, method, SS_START, aux_init="model")
    assert np.max(np.abs(ref.theta / SS_TRUTH - 1)) < 1e-5
    for c in (1e-6, 1e-3, 1e3, 1e6):  # t' = t / c: A' = c A, B' = c B; a' = c² a, b' = c b, c' = c² c
        faster = si.BlackBox(black_box.A * c, black_box.B * c, black_box.C, black_box.D)
        phys = np.array([c**2, c, c**2])
        out = estimate(state_space(), faster, method, SS_START * phys, aux_init="model")
        # the same iterations: with this model's fixed 1 in A the second state is a rate, whose unit changes with
        # time; the methods work with states of size one at the start (Gramians of the model there), so that
        # does not change the misfit's weights either
        np.testing.assert_allclose(out.theta / phys, ref.theta, rtol=RTOL)
        assert (out.status, out.iterations) == (ref.status, ref.iterations)


@pytest.mark.parametrize("method", ["als", "gb", "ipopt"])
def test_similarity_methods_follow_the_inputs_and_outputs(black_box, method):
    """Outputs y' = β y (the model's C = [1, 0] is fixed, so its states follow: B' = β B, c' = β c) and inputs
    u' = u / γ (B' = γ B, c' = γ c): the same iterations. Before, the output block ‖ℂ − C(θ)T‖² weighed β² against
    the others (working_problem: each input and output in units of its own size)."""
    ref = estimate(state_space(), black_box, method, SS_START, aux_init="model")
    for f in (1e-6, 1e-3, 1e3, 1e6):
        phys = np.array([1.0, 1.0, f])
        for bb in (si.BlackBox(black_box.A, black_box.B, black_box.C * f, black_box.D),
                   si.BlackBox(black_box.A, black_box.B * f, black_box.C, black_box.D)):
            out = estimate(state_space(), bb, method, SS_START * phys, aux_init="model")
            np.testing.assert_allclose(out.theta / phys, ref.theta, rtol=RTOL)
            assert (out.status, out.iterations) == (ref.status, ref.iterations)


@pytest.mark.parametrize("method", ["als", "gb", "ipopt"])
def test_the_default_random_transform_follows_the_units(black_box, method):
    """aux_init="random" (the default): a parameter, the time axis, the inputs or the outputs in other units draw
    the same T₀ and give the same iterations and estimate (rtol as for aux_init="model")."""
    ref = estimate(state_space(), black_box, method, SS_START)
    variants = []
    for k in range(3):
        for a in (-6, 6):
            f = np.ones(3)
            f[k] = 10.0**a
            variants.append((state_space(f), black_box, SS_START / f, 1 / f))
    for c in (1e-6, 1e6):
        phys = np.array([c**2, c, c**2])
        variants.append((state_space(), si.BlackBox(black_box.A * c, black_box.B * c, black_box.C, black_box.D),
                         SS_START * phys, phys))
    for f in (1e-6, 1e6):
        phys = np.array([1.0, 1.0, f])
        variants.append((state_space(), si.BlackBox(black_box.A, black_box.B, black_box.C * f, black_box.D),
                         SS_START * phys, phys))
    for model, bb, x0, phys in variants:
        out = estimate(model, bb, method, x0)
        np.testing.assert_allclose(out.theta / phys, ref.theta, rtol=RTOL)
        assert (out.status, out.iterations) == (ref.status, ref.iterations)


def test_another_start_draws_another_transform(black_box):
    """The key tells starts apart: two starts draw different T₀ (else every random start would share one)."""
    from symid.fit.similarity.start import initial_point

    maps = state_space().maps
    _, T1, _ = initial_point("random", SS_START, 0, maps, black_box)
    _, T2, _ = initial_point("random", SS_START * 1.01, 0, maps, black_box)
    _, T3, _ = initial_point("random", SS_START, 1, maps, black_box)
    assert not np.allclose(T1, T2, rtol=0.1) and not np.allclose(T1, T3, rtol=0.1)


# -- SCR (Algorithm 6.1) ---------------------------------------------------------------------------------------
#
# A two-compartment model (k10, k12, k21 in 1/h; c = 1/V in 1/L; dose into compartment 1, its concentration
# measured; truth 0.3, 0.8, 0.2, 1/12) and its exact black box in another basis. From this start SCR stops at a
# stationary point after some 30 iterations: a path of many relaxation steps, so that a change of units shows.
# SCR builds each start's problem in that start's units (symid.fit.similarity.scr.ScrSimilarity.start_problem),
# keeping the model's states in the units it declares them in.
# Before, on this model (another basis), time in ms changed the path (320 iterations to a 30 s budget instead of
# 37), and a rate declared in units of 1e-6 made the implied equalities look inconsistent (dropped: 85 iterations
# instead of 36, to another point).

def compartments(factors=None):
    factors = np.ones(4) if factors is None else factors
    names = si.parameters("k10 k12 k21 c", positive=True)
    k10, k12, k21, c = (f * p for f, p in zip(factors, names, strict=True))
    return si.StateSpaceModel(A=[[-(k10 + k12), k21], [k12, -k21]], B=[[1], [0]], C=[[c, 0]],
                              parameters=list(names))


PK_TRUTH = np.array([0.3, 0.8, 0.2, 1 / 12])
PK_START = PK_TRUTH * np.array([1.3, 0.7, 1.2, 0.8])


def pk_black_box(tau=1.0, beta=1.0, gamma=1.0):
    """Time t' = t / tau (A times tau: the rates times tau), input times 1/gamma (B times gamma), output times beta
    (c times beta). With the model's fixed B = [1; 0], an input not in units of the new time (gamma ≠ 1) changes
    the unit of the model's states: x' = x / gamma, and c' = gamma c."""
    A, B, C, _ = compartments().state_space(PK_TRUTH)
    T = np.array([[2.5, 0.4], [-0.3, 2.3]])
    Ti = np.linalg.inv(T)
    return si.BlackBox(tau * T @ A @ Ti, gamma * T @ B, beta * C @ Ti, np.zeros((1, 1)))


@pytest.fixture(scope="module")
def scr_ref():
    ref = estimate(compartments(), pk_black_box(), "scr", PK_START, max_iter=300)
    assert ref.iterations > 20  # a path, not a presolve that solves it at once
    return ref


def assert_same_scr_run(out, ref, phys):
    """θ / phys equals the reference to 1e-10 of the truth's size (two rates end at their bound 0, where a
    relative comparison means nothing), after the same iterations."""
    np.testing.assert_allclose(out.theta / phys, ref.theta, rtol=0, atol=1e-10 * float(np.max(PK_TRUTH)))
    assert (out.status, out.iterations) == (ref.status, ref.iterations)


@pytest.mark.parametrize("k", [0, 3])
@pytest.mark.parametrize("a", [-6, 6])
def test_scr_follows_a_parameter_in_other_units(scr_ref, k, a):
    f = np.ones(4)
    f[k] = 10.0**a
    out = estimate(compartments(f), pk_black_box(), "scr", PK_START / f, max_iter=300)
    assert_same_scr_run(out, scr_ref, 1 / f)


@pytest.mark.parametrize("tau", [1e-6, 1e6])
def test_scr_follows_the_time_axis(scr_ref, tau):
    """Time t' = t / tau with the dose rate in units of the new time: the rates times tau, the states as they were."""
    phys = np.array([tau, tau, tau, 1.0])
    out = estimate(compartments(), pk_black_box(tau=tau), "scr", PK_START * phys, max_iter=300)
    assert_same_scr_run(out, scr_ref, phys)


@pytest.mark.parametrize("beta", [1e-6, 1e6])
def test_scr_follows_the_output_unit(scr_ref, beta):
    phys = np.array([1.0, 1.0, 1.0, beta])
    out = estimate(compartments(), pk_black_box(beta=beta), "scr", PK_START * phys, max_iter=300)
    assert_same_scr_run(out, scr_ref, phys)


@pytest.mark.parametrize("gamma", [1e-6, 1e6])
def test_scr_follows_the_input_unit(scr_ref, gamma):
    """The dose in other units with the model's B fixed at [1; 0]: the states change unit with it (x' = x / gamma,
    c' = gamma c); T scales as a whole, which the size of T at the start absorbs."""
    phys = np.array([1.0, 1.0, 1.0, gamma])
    out = estimate(compartments(), pk_black_box(gamma=gamma), "scr", PK_START * phys, max_iter=300)
    assert_same_scr_run(out, scr_ref, phys)


@pytest.mark.xfail(strict=True, reason="SCR keeps the model's states in the units it declares (per-start state sizes "
                                       "cost it successes: e-nose 15 -> 5 of 40), so the model written with one "
                                       "state in other units is another problem to it")
def test_scr_does_not_follow_one_state_in_other_units(scr_ref):
    """The peripheral amount in units of 1e-3 (x2' = 1e3 x2): A = [[-(k10 + k12), k21/d], [d k12, -k21]], the same
    θ and the same black box; ALS, GB and IPOPT follow it (their states of size one at the start)."""
    d = 1e3
    k10, k12, k21, c = names = si.parameters("k10 k12 k21 c", positive=True)
    model = si.StateSpaceModel(A=[[-(k10 + k12), k21 / d], [k12 * d, -k21]], B=[[1], [0]], C=[[c, 0]],
                               parameters=list(names))
    out = estimate(model, pk_black_box(), "scr", PK_START, max_iter=300)
    assert_same_scr_run(out, scr_ref, np.ones(4))
