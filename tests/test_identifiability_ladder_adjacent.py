"""Chains driven next to the free end and measured there, or the reverse (symid.structural.ladder_adjacent).

Reference for every verdict here: the Gröbner step itself (msolve, or sympy's Buchberger
when msolve is not installed), run on the same model and θ* with the inversions turned
off. Sizes the Gröbner step does not finish within minutes (5 masses: msolve 719 s, one
complex solution, ``benchmarks/research/noncollocated_chains.md``) are checked at two
independent points.
"""

from __future__ import annotations

import mpmath
import pytest
import sympy as sp

import symid as si
import symid.structural.global_ as gg
from symid.structural import ladder_adjacent as la
from symid.structural.global_ import generic_global, star_and_summary
from symid.structural.ladder import Ladder, proves_global
from symid.structural.ladder_adjacent import adjacent_of, invert_adjacent
from symid.structural.msolve import msolve_binary
from symid.structural.summary import model_matrices

MSOLVE = msolve_binary()


def _variant(model, kind: str):
    """The same chain with the force at the end and the sensor beside it, a velocity sensor, or the masses numbered
    in reverse order (the grounded mass last)."""
    mats = model_matrices(model, None)
    n = mats["M"].shape[0]
    if kind == "swapped":
        return si.SecondOrderModel(**{**mats, "B": mats["C"].T, "C": mats["B"].T})
    if kind == "velocity":
        return si.SecondOrderModel(**mats, output="velocity")
    P = sp.Matrix(n, n, lambda i, j: int(i + j == n - 1))
    return si.SecondOrderModel(M=P * mats["M"] * P, V=P * mats["V"] * P, K=P * mats["K"] * P, B=P * mats["B"],
                               C=mats["C"] * P)


@pytest.mark.parametrize("name", ["chain_at-3-2.3", "chain_at-3-2.3-swapped", "chain_at-3-2.3-velocity",
                                  "chain_at-3-2.3-reversed", "chain_at-4-3.4"])
def test_the_case_analysis_agrees_with_the_groebner_step(name, groebner, families):
    parts = name.split("-")
    model = families.build("-".join(parts[:3]))
    if len(parts) == 4:
        model = _variant(model, parts[3])
    assert adjacent_of(model) is not None
    fast = generic_global(model, rank=len(model.parameters), msolve=MSOLVE)
    ref = groebner(model)
    assert fast.engine == "ladder" and ref.engine in ("msolve", "sympy")
    assert (fast.n_complex, fast.n_real, fast.n_admissible) == (ref.n_complex, ref.n_real, ref.n_admissible) \
        == (1, 1, 1)
    assert fast.global_complex == ref.global_complex and all(fast.global_complex.values())
    assert fast.confirmed and fast.theta_confirm


@pytest.mark.parametrize("n", [5, 6, 8])
def test_every_size_is_proven_at_theta_star_and_theta_2(n, families):
    model = families.build(f"chain_at-{n}-{n - 1}.{n}")
    for draw in (0, 500):
        star = star_and_summary(model, seed=3, draw=draw)[1]
        assert proves_global(model, None, star) == "adjacent"


@pytest.mark.parametrize(("n", "count"), [(3, 3), (4, 1)])
def test_free_chains_agree_with_the_groebner_step(n, count, groebner, free_chain):
    """Free at both ends: 3 masses have 3 complex solutions (the case analysis finds more than θ* and claims
    nothing), 4 masses one (proven by the case analysis)."""
    model = free_chain(n, n - 2, n - 1)
    assert adjacent_of(model) is not None
    fast = generic_global(model, rank=len(model.parameters), msolve=MSOLVE)
    ref = groebner(model)
    assert ref.engine in ("msolve", "sympy") and ref.n_complex == fast.n_complex == count
    assert fast.engine == ("ladder" if count == 1 else ref.engine)
    star = star_and_summary(model)[1]
    margins = la.case_margins(adjacent_of(model), model, None, star)
    assert margins["solutions"] >= 2 if count > 1 else margins["solutions"] == 1


@pytest.mark.parametrize("known", [{"m1": 2}, {"k2": 5}])
def test_a_known_value_leaves_one_of_the_free_chains_solutions(known, monkeypatch, free_chain):
    """The free 3-mass chain's 3 solutions (whole structure) are filtered by the known value: only θ*'s has it
    (Gröbner on the model with the known value: 1)."""
    model = free_chain(3, 1, 2)
    rep = si.identifiability(model, known=known)
    with monkeypatch.context() as mpatch:
        mpatch.setattr(gg, "proves_global", lambda *a, **k: "")
        ref = si.identifiability(model, known=known)
    assert ref.engine != "ladder" and ref.n_solutions_complex == 1
    assert rep.engine == "ladder" and rep.verdict == "global" and rep.n_solutions_complex == 1


def test_a_free_chain_of_six_masses_is_proven_at_theta_star_and_theta_2(free_chain):
    model = free_chain(6, 4, 5)
    for draw in (0, 500):
        assert proves_global(model, None, star_and_summary(model, seed=3, draw=draw)[1]) == "adjacent"


def test_the_report_says_how_it_was_proven(families):
    rep = si.identifiability(families.build("chain_at-6-5.6"))
    assert rep.engine == "ladder" and rep.verdict == "global" and rep.n_solutions_complex == 1
    assert set(rep.verdicts.values()) == {"global"}
    assert any("next to its free end" in note and "symid.structural.ladder_adjacent" in note for note in rep.notes)


@pytest.mark.parametrize("name", ["chain_at-4-2.4", "chain_at-4-2.3", "chain_at-4-1.4", "chain_at-4-4.4"])
def test_other_placements_are_not_recognised(name, families):
    assert adjacent_of(families.build(name)) is None


def test_a_missing_element_or_ground_at_the_sensor_end_is_not_recognised(families):
    model = families.build("chain_at-4-3.4")
    mats = model_matrices(model, None)
    c3, k1, c1 = (next(p for p in model.parameters if p.name == name) for name in ("c3", "k1", "c1"))
    no_damper = si.SecondOrderModel(**{**mats, "V": mats["V"].subs(c3, 0)})
    no_ground_spring = si.SecondOrderModel(**{**mats, "K": mats["K"].subs(k1, 0)})
    assert adjacent_of(no_damper) is None and adjacent_of(no_ground_spring) is None
    V, K = mats["V"].subs(c1, 0), mats["K"].subs(k1, 0)  # the ground element moved to the sensor's end
    V[3, 3] += c1
    K[3, 3] += k1
    assert adjacent_of(si.SecondOrderModel(**{**mats, "V": V, "K": K})) is None


def test_a_known_value_keeps_the_proof(families, monkeypatch):
    """Known values restrict the solutions of the full structure: θ* stays the only one (Gröbner: 1)."""
    model = families.build("chain_at-3-2.3")
    known = {"m1": 2, "k2": 5}
    rep = si.identifiability(model, known=known)
    assert rep.engine == "ladder" and rep.verdict == "global"
    with monkeypatch.context() as mpatch:
        mpatch.setattr(gg, "proves_global", lambda *a, **k: "")
        ref = si.identifiability(model, known=known)
    assert ref.engine != "ladder" and ref.n_solutions_complex == rep.n_solutions_complex == 1


def test_a_misread_structure_is_caught(families):
    model = families.build("chain_at-5-4.5")
    lad = adjacent_of(model)
    star = star_and_summary(model)[1]
    wrong = Ladder(lad.order, lad.masses, (lad.edges[1], lad.edges[0], *lad.edges[2:]), lad.grounds, lad.shift,
                   lad.gain, lad.at)
    assert invert_adjacent(lad, model, None, star)
    assert not invert_adjacent(wrong, model, None, star)


def test_a_response_no_chain_has_gives_no_solution():
    """The case analysis can fail: P and N of a 4-mass chain give θ* (to 1e-30) as the one solution, and with N's
    constant term moved by 1e-3 (a response no such chain has) no case passes."""
    m, e, g = [3, 5, 2, 7], [(1, 11), (2, 13), (sp.Rational(1, 2), 17)], (3, 19)
    P, N = la._polys([sp.Rational(x) for x in m], [tuple(map(sp.Rational, x)) for x in e], tuple(map(sp.Rational, g)))
    ctx = mpmath.MPContext()
    ctx.dps = la.DPS
    Pm, Nm = la._exact_mp(P, N, ctx)
    sols, undecided = la._solutions(Pm, Nm, 4, ctx)
    assert not undecided and len(sols) == 1  # values [c, k, m] per node from the ground
    theta = [g[0], g[1], m[0], *(x for j in range(1, 4) for x in (*e[j - 1], m[j]))]
    assert max(abs(v - w) / w for v, w in zip(sols[0], theta, strict=True)) < la.PASS
    Nm[-1] *= 1 + ctx.mpf("1e-3")
    assert la._solutions(Pm, Nm, 4, ctx) == ([], False)
