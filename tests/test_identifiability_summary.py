"""The transfer-function summary of a realisation that is not minimal only by a power of s.

A chain free at both ends has a rigid-body mode: det(s²M + sV + K) has the factor s² for
every θ. Measured in velocity (acceleration) the numerator carries s (s²), so the
realisation is never minimal, yet the transfer function divided by the common power of s
is in lowest terms at random points; its coefficients are then an exhaustive summary
(the denominator is the least common denominator of the entries, of full degree, at θ*
and so at every θ with the same response), far smaller than the Markov parameters.
References: the reduced summary must give the same global answer as the Markov
parameters (which need no minimality), computed here on the same θ*.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import symid as si
import symid.structural.summary as summary_module
from symid.structural import exhaustive_summary
from symid.structural.global_ import global_analysis, star_and_summary
from symid.structural.summary import KIND_MARKOV, KIND_TF, SummaryTooLarge


def _free_chain(n: int, drive: int, sensor: int, output: str) -> si.SecondOrderModel:
    m = si.parameters(" ".join(f"m{i + 1}" for i in range(n)), positive=True)
    c = si.parameters(" ".join(f"c{i + 1}" for i in range(n - 1)), positive=True)
    k = si.parameters(" ".join(f"k{i + 1}" for i in range(n - 1)), positive=True)
    c, k = (list(x) if n > 2 else [x] for x in (c, k))

    def laplacian(v):
        X = sp.zeros(n, n)
        for i, x in enumerate(v):
            X[i, i] += x
            X[i + 1, i + 1] += x
            X[i, i + 1] -= x
            X[i + 1, i] -= x
        return X

    B, C = sp.zeros(n, 1), sp.zeros(1, n)
    B[drive], C[sensor] = 1, 1
    return si.SecondOrderModel(M=sp.diag(*m), V=laplacian(c), K=laplacian(k), B=B, C=C, output=output)


def test_free_chain_velocity_uses_the_reduced_transfer_function():
    for output, shift in (("position", 0), ("velocity", 1), ("acceleration", 2)):
        summ = exhaustive_summary(_free_chain(3, 0, 2, output))
        assert summ.kind == KIND_TF and summ.shift == shift, (output, summ.kind, summ.shift)
        assert summ.minimal == (shift == 0)
        # det = s²·(quartic) for every θ; after dividing by s^shift the denominator's non-constant coefficients
        # below the leading one are those of s^(2 − shift) … s^(5 − shift)
        kept = [lab for lab in summ.labels if lab.startswith("d s^")]
        assert kept == [f"d s^{k}" for k in range(2 - shift, 6 - shift)]


def _global_pair(model):
    params, star, minimal, summ, rng = star_and_summary(model)
    assert summ.kind == KIND_TF and summ.shift > 0 and not minimal
    tf = global_analysis(model, prepared=(params, star, minimal, summ, rng))
    return params, star, minimal, summ, rng, tf


def test_reduced_summary_agrees_with_markov_parameters():
    # drive and sensor anywhere on free 2-mass chains, and the end of a 3-mass one: identifiable or not, the
    # same solutions as with the Markov parameters (on the other 3-mass placements those take minutes)
    cases = [(2, 0, 0, "velocity"), (2, 0, 1, "velocity"), (2, 1, 1, "acceleration"), (2, 0, 1, "acceleration"),
             (3, 0, 0, "velocity"), (3, 0, 0, "acceleration")]
    for n, drive, sensor, output in cases:
        model = _free_chain(n, drive, sensor, output)
        params, star, minimal, _summ, rng, tf = _global_pair(model)
        markov = exhaustive_summary(model, check_point=star, kind=KIND_MARKOV)
        mk = global_analysis(model, prepared=(params, star, minimal, markov, rng))
        assert (tf.n_complex, tf.global_complex) == (mk.n_complex, mk.global_complex), (n, drive, sensor, output)
        assert any("s^" in note and "divided out" in note for note in tf.notes)


def test_reduced_summary_solutions_reproduce_the_response():
    # where the Markov parameters take minutes: every solution found gives θ*'s response (a wrong summary
    # would let others through); the middle of a free 3-mass chain sees its mirror image too (2 solutions)
    for drive, sensor, output, count, real in ((1, 1, "velocity", 2, 2), (0, 1, "acceleration", 3, 1)):
        model = _free_chain(3, drive, sensor, output)
        params, star, _, _, _, tf = _global_pair(model)
        assert (tf.n_complex, tf.n_real, len(tf.real_solutions)) == (count, real, real)
        names = [p.name for p in params]
        ref = model.frequency_response(dict(zip(names, (float(v) for v in star), strict=True)), [0.3, 1.1, 4.0])
        for sol in tf.real_solutions:
            H = model.frequency_response({k: float(v) for k, v in sol.items()}, [0.3, 1.1, 4.0])
            np.testing.assert_allclose(H, ref, rtol=1e-9)


def test_free_chain_velocity_report():
    # a free 4-mass chain driven and measured (velocity) at an end: globally identifiable by continued
    # fractions once the summary is the transfer function (the Markov summary took > 25 s before)
    rep = si.identifiability(_free_chain(4, 0, 0, "velocity"), timeout=30)
    assert set(rep.verdicts.values()) == {"global"}
    assert rep.summary_kind == KIND_TF


def test_common_factor_other_than_s_keeps_markov_parameters():
    a, b = si.parameters("a b", positive=True)
    # an integrator the output does not see (shift 1) and a mode it does not see either: after dividing by s
    # the numerator (s + b) still divides the denominator (s + a)(s + b), so Markov parameters are needed
    model = si.StateSpaceModel(A=[[0, 1, 0], [0, -a, 0], [0, 0, -b]], B=[[0], [1], [1]], C=[[0, 1, 0]])
    summ = exhaustive_summary(model)
    assert summ.kind == KIND_MARKOV
    rep = si.identifiability(model)
    assert rep.verdicts["a"] == "global" and rep.verdicts["b"] == "none"


def test_integrator_divided_out_of_a_state_space_model():
    a, b = si.parameters("a b", positive=True)
    # position state unobservable from the velocity: H = b s / (s (s + a)) = b / (s + a)
    model = si.StateSpaceModel(A=[[0, 1], [0, -a]], B=[[0], [b]], C=[[0, 1]])
    summ = exhaustive_summary(model)
    assert summ.kind == KIND_TF and summ.shift == 1
    assert sorted(str(e) for e in summ.expressions()) == ["a", "b"]
    rep = si.identifiability(model)
    assert rep.verdicts == {"a": "global", "b": "global"}


def test_a_summary_too_large_is_a_documented_limit(monkeypatch):
    # the determinant of a 4-mass chain's dynamic stiffness has 171 terms: with the limit below that, the summary
    # is refused before it is built (on a 12-mass chain it took 12.7 GB) and the report says why
    monkeypatch.setattr(summary_module, "MAX_TERMS", 100)
    model = _free_chain(4, 0, 0, "position")
    with pytest.raises(SummaryTooLarge, match="more than 100 terms"):
        exhaustive_summary(model)
    rep = si.identifiability(model, timeout=30)
    assert rep.jacobian_ranks == (10, 10)  # the local step does not need the summary
    assert set(rep.verdicts.values()) == {"local, global undetermined"}
    assert "too large to compute" in str(rep)
