"""The numerical witness search (issue 17): real curves through θ*, Gauss–Newton starts, the fast Krawczyk test."""

from __future__ import annotations

import random
from fractions import Fraction

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import symid as si
from symid.structural.certify import PolySystem, SummarySystem
from symid.structural.tracing import CurveTracer, ScaledSystem, newton
from symid.structural.witness import find_witnesses

GOLDEN = (1 + 5**0.5) / 2


def _toy(den=None):
    """x·y = 1, x + y² = 2 (θ* = (1, 1)): (y − 1)(y² + y − 1) = 0, so also (φ, 1/φ) and (−1/φ, −φ), φ golden."""
    nums = [[((1, 1), Fraction(1))], [((1, 0), Fraction(1)), ((0, 2), Fraction(1))]]
    dens = den if den is not None else [[((0, 0), Fraction(1))], [((0, 0), Fraction(1))]]
    return SummarySystem(nums, dens, [Fraction(1), Fraction(1)])


def test_krawczyk_certifies_a_true_root_and_rejects_a_near_miss():
    sys_ = _toy()
    positive = np.array([GOLDEN, 1 / GOLDEN])
    box = sys_.certify(positive, [True, True])
    assert box is not None and np.all(box <= 1e-6 * positive)  # a box of relative radius ≤ 1e-6 holds the root
    assert sys_.certify(positive * (1 + 1e-3), [True, True]) is None  # no root within 1e-6 of the point
    assert sys_.certify(np.array([1.0, 1.0]), [True, True]) is None  # θ* itself: never a witness
    negative = np.array([-1 / GOLDEN, -GOLDEN])
    assert sys_.certify(negative, [False, False]) is not None
    assert sys_.certify(negative, [True, True]) is None  # not in the positive orthant
    # a denominator vanishing at the root (y² + y − 1) refuses it
    den = [[((0, 0), Fraction(1))], [((0, 2), Fraction(1)), ((0, 1), Fraction(1)), ((0, 0), Fraction(-1))]]
    assert _toy(den).certify(positive, [True, True]) is None
    assert sys_.certify(np.array([0.0, 1.0]), [False, False]) is None  # a zero coordinate: refused, never wrong


def test_newton_step_with_the_compensated_residual_reaches_the_last_bit():
    sys_ = _toy()
    x = sys_.newton_step(np.array([GOLDEN * (1 + 1e-9), 1 / GOLDEN]))
    x = sys_.newton_step(x)
    assert abs(x[0] - GOLDEN) <= 2e-16 * GOLDEN and abs(x[1] - 1 / GOLDEN) <= 2e-16


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**31))
def test_compensated_enclosure_holds_the_exact_value(seed):
    rng = random.Random(seed)
    nv = rng.randint(1, 4)
    polys = []
    for _ in range(rng.randint(1, 3)):
        terms = {}
        for _ in range(rng.randint(1, 12)):
            mon = tuple(rng.randint(0, 3) for _ in range(nv))
            terms[mon] = Fraction(rng.randint(-10**12, 10**12), rng.randint(1, 10**6))
        polys.append(list(terms.items()))
    ps = PolySystem(polys, nv)
    exact_point = [Fraction(rng.randint(-10**6, 10**6) or 1, rng.randint(1, 997)) for _ in range(nv)]
    hi = np.array([float(v) for v in exact_point])
    lo = np.array([float(v - Fraction(h)) for v, h in zip(exact_point, hi, strict=True)])
    for point, x_hi, x_lo in ((exact_point, hi, lo), ([Fraction(h) for h in hi], hi, None)):
        enc = ps.enclose(x_hi, x_lo)
        assert enc is not None
        for terms, h, l, r in zip(polys, *enc, strict=True):
            exact = sum((c * np.prod([point[v] ** e for v, e in enumerate(m)], dtype=object) for m, c in terms),
                        Fraction(0))
            assert abs(exact - Fraction(h) - Fraction(l)) <= Fraction(r)
            assert r <= 1e-25 * sum(abs(float(c)) * np.prod(np.abs(x_hi) ** np.array(m)) for m, c in terms) + 1e-280


def test_curves_through_theta_star_meet_the_other_real_roots():
    # the toy system in logarithmic coordinates around θ* = (1, 1): the curve {x y = 1} (x + y² = 2 dropped) runs
    # through (φ, 1/φ), where x + y² − 2 changes sign
    E = np.array([[1, 1], [0, 0], [1, 0], [0, 2], [0, 0]])
    coef = np.array([1.0, -1.0, 1.0, 1.0, -2.0])
    scaled = ScaledSystem(E, coef, np.array([0, 2, 5]), [True, True])
    tracer = CurveTracer(scaled, np.array([0, 0, 1, 1]), np.array([1.0, -1.0, 1.0, -1.0]))
    brackets = tracer.advance(40)
    assert brackets
    starts = np.array([ua + ga / (ga - gb) * (ub - ua) for _, ua, ub, ga, gb, _ in brackets])
    U, rel = newton(scaled, starts)
    roots = {tuple(np.round(np.exp(u), 9)) for u, r in zip(U, rel, strict=True) if r < 1e-12}
    assert (round(GOLDEN, 9), round(1 / GOLDEN, 9)) in roots


def test_chain_with_force_and_sensor_at_opposite_ends_is_proven_local(families):
    # chain-4-1n (12 parameters): 204 complex solutions of summary(θ) = summary(θ*), out of reach of the exact
    # step within seconds. The traced curves find a certified admissible witness that moves every parameter but
    # c1 and k1, which are globally identifiable: H(0) = 1/k1 (det K = k1 k2 k3 k4) and 1/H(s) = k1 + c1 s + O(s²)
    model = families.build("chain-4-1n")
    res = find_witnesses(model, positive=[True] * 12)
    star = {k: float(sp.Rational(v)) for k, v in res.theta_star.items()}
    moved = {k for w, ok in zip(res.witnesses, res.certified, strict=True) if ok
             for k in star if abs(w[k] - star[k]) > 1e-6 * star[k]}
    assert moved == set(star) - {"c1", "k1"}
    assert res.n_starts <= 100 and res.seconds < 2.0  # the curves alone, no random starts
    w = np.array([0.1, 1.0, 7.0])
    H0 = model.frequency_response(star, w)
    for sol, ok in zip(res.witnesses, res.certified, strict=True):
        assert ok and all(v > 0 for v in sol.values())
        np.testing.assert_allclose(model.frequency_response(sol, w), H0, rtol=1e-9)
    again = find_witnesses(model, positive=[True] * 12)  # deterministic: a fixed number of steps, no time limit
    assert (again.witnesses, again.certified, again.n_starts) == (res.witnesses, res.certified, res.n_starts)


def test_chain_verdicts_are_local_where_witnesses_move_the_parameter(families):
    model = families.build("chain-4-1n")
    rep = si.identifiability(model, timeout=3.0)
    assert rep.jacobian_ranks[0] == 12
    local = {k for k, v in rep.verdicts.items() if v == "local"}
    assert local == set(rep.parameters) - {"c1", "k1"}
    assert rep.verdicts["c1"] in ("global", "local, global undetermined")  # global in truth (see above)
    assert rep.verdicts["k1"] in ("global", "local, global undetermined")
    assert rep.n_solutions_at_least is None or rep.n_solutions_at_least >= 2


@pytest.mark.parametrize("name", ["belt_drive", "mass_damper_2dof"])
def test_a_globally_identifiable_model_yields_no_witness(name):
    res = find_witnesses(si.load_model(name).model)
    assert res.witnesses == () and res.certified == ()


def test_rational_formulas_prove_the_chain_parameters_witnesses_cannot_move(families):
    from symid.structural.rational_formulas import rational_formulas
    from symid.structural.summary import exhaustive_summary

    model = families.build("chain-4-1n")
    summ = exhaustive_summary(model)
    found = rational_formulas(summ, ["c1", "k1", "m1", "k2"], at=[sp.Rational(3 + i, 2) for i in range(12)])
    assert sorted(found) == ["c1", "k1"]  # m1 and k2 are not global (the certified witness moves them)
    assert found["k1"].text(summ.labels) == "k1 = (c[d s^0]) / (c[N[0,0] s^0])"  # H(0) = 1/k1
    assert found["c1"].text(summ.labels) == ("c1 = (c[d s^1]·c[N[0,0] s^0] - c[d s^0]·c[N[0,0] s^1]) / "
                                             "(c[N[0,0] s^0]^2)")
    th = si.parameters("th")
    square = exhaustive_summary(si.StateSpaceModel(A=[[-1]], B=[[th]], C=[[th]]))  # only th² is determined
    assert rational_formulas(square, ["th"]) == {}


def test_the_solutions_that_witnesses_show_are_told_apart_and_pointed_to():
    """A 3-mass chain driven at the grounded end and measured at the free one: certified witnesses settle "local"
    before the Gröbner step ends, so `.solutions` is empty. The report still says how θ* and the certified
    witness differ, and identify's warning points to `.witnesses`, not to the empty `.solutions` (a new user's
    trial followed the warning to an empty tuple)."""
    from symid.structural.analyse import several_solutions

    m = si.parameters("m1 m2 m3", positive=True)
    c = si.parameters("c1 c2 c3", positive=True)
    k = si.parameters("k1 k2 k3", positive=True)

    def ground(e):
        return [[e[0] + e[1], -e[1], 0], [-e[1], e[1] + e[2], -e[2]], [0, -e[2], e[2]]]

    model = si.SecondOrderModel(M=[[m[0], 0, 0], [0, m[1], 0], [0, 0, m[2]]], V=ground(c), K=ground(k),
                                B=[[1], [0], [0]], C=[[0, 0, 1]])
    rep = si.identifiability(model)
    assert rep.verdict == "local" and not rep.solutions and any(rep.witnesses_certified)
    text = rep.summary()
    assert "telling the solutions apart (at θ*):" in text and "another solution differs in m1" in text
    said = several_solutions(model, timeout=30.0)  # the budget of the report above
    assert said is not None and "si.identifiability(model).witnesses lists those found" in said
