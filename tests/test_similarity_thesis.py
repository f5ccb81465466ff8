"""Thesis results of chapters 6 and 7 (slow: minutes; run with ``pytest -m slow``).

The same runs, with their numbers recorded, are in benchmarks/similarity_thesis.py.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import symid as si
from symid.fit.compare import relative_parameter_error
from symid.fit.registry import prepare
from symid.fit.similarity.data import similarity_data
from symid.fit.similarity.scr import ScrSimilarity
from symid.fit.starts import make_starts

pytestmark = pytest.mark.slow


def test_enose_scr_from_random_starts():
    """Thesis §6-6-2: from random S, T, "roughly 3 out of every 10" starts reach the global minimum.

    A rate, so measured on 30 starts: ten cannot pin it (at 30 %, 2 or fewer of 10 happen with probability
    0.38). Measured: 9 of 30, 12 of 40 (seed 0). The first ten of seed 0 reach it once: the starts are drawn per
    parameter name since d39eab3, which changed every draw (T₀, S₀ are seeded by the start); on the ten starts
    drawn before it, the same code reaches it from the same 3 as then (benchmarks/results/similarity_thesis.json,
    with the same local minima, errors 0.89, 1.07, 1.16, 1.12 elsewhere)."""
    entry = si.load_model("enose")
    cmp = si.compare(entry.model, entry.data(), methods=("scr",), starts=30, seed=0, truth=entry.truth,
                     param_tol=1e-3, options={"scr": {"max_iter": 2000}})
    assert cmp["scr"].n_success >= 6  # thesis §6-6-2: about 3 of 10 (measured 9 of 30)
    best = cmp["scr"].result
    assert relative_parameter_error(best.theta_vector, entry.model.theta_vector(entry.truth)) < 1e-3


def test_enose_zero_start_converges_unlike_the_thesis():
    """Thesis §6-6-2: S, T "initialized as zero matrices ... the method fails". Here it converges (763
    iterations measured): the balanced basis, the scaling α and the implied equalities change the path."""
    entry = si.load_model("enose")
    solver = prepare(entry.model, entry.data(), "scr", {"aux_init": "zero", "max_iter": 2000})
    out = solver.run(np.zeros(6))
    assert relative_parameter_error(out.theta, entry.model.theta_vector(entry.truth)) < 1e-3


def test_overparameterised_enose_finds_a_similarity_transform():
    """Thesis (6-24)/(6-25): a point with TS = I whose frequency response is that of the data."""
    entry = si.load_model("enose_overparameterized")
    model = entry.model
    sd = similarity_data(model, entry.data())
    solver = ScrSimilarity(model, sd, max_iter=2000)
    best = None
    for x in make_starts(model, 10, 0, zero_first=True):
        sol = solver.solve(x)
        theta = np.asarray(sol.x["theta"], dtype=float)
        misfit = sd.misfit(model, theta)
        if best is None or misfit < best[0]:
            best = (misfit, theta, *solver.transform(sol, original=True))
    misfit, theta, T, S = best
    assert misfit < 1e-10  # the frequency responses agree (thesis: "identical to the responses in Figure 6-2")
    np.testing.assert_allclose(T @ S, np.eye(3), atol=1e-6)  # (6-25): "indeed a similarity transformation pair"
    np.testing.assert_allclose(S @ T, np.eye(3), atol=1e-6)
    # same poles as the truth (6-17), though θ̂ need not be the physical point (not identifiable)
    true_poles = np.sort_complex(np.linalg.eigvals(entry.extra["A_printed"]))
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(model.maps["A"](theta))), true_poles, atol=1e-6)


def test_msd3_from_io_data_through_n4sid_and_zoh():
    """Thesis §7-6-1: (7-17) from I/O data (dt = 1 ms, N = 5000); the thesis reaches about 1e-2 in M, V, K."""
    entry = si.load_model("msd3_similarity")
    model = entry.model
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", si.IdentifiabilityWarning)
        res = si.identify(model, entry.data(), method="scr", starts=3, seed=0, max_iter=2000)
    truth = model.matrices(entry.truth)
    est = model.matrices(res.theta_vector)
    for k in "MVK":
        err = np.linalg.norm(est[k] - truth[k]) / np.linalg.norm(truth[k])
        assert err <= 1e-2, f"{k}: relative error {err:.2e}"  # thesis (7-21)/(7-22): about 1e-2
