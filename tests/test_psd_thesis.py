"""Thesis §5-6/§5-7 on the 3-DOF example (slow: minutes; run with ``pytest -m slow``).

The same runs, with their numbers recorded, and the §5-7 comparisons (IPOPT on (5-13) from 20
N(0, 1) starts, SCR without the LMIs) are in benchmarks/psd.py.
"""

from __future__ import annotations

import numpy as np
import pytest

import symid as si
from symid.fit.spectra.scr import ScrPSD
from symid.fit.starts import make_starts

pytestmark = pytest.mark.slow


def test_algorithm_5_1_reaches_the_truth_from_four_of_five_draws():
    """Issue 6 item 2: at least 4 of 5 seeded starts reach max-entry errors ≤ 1e-4 in M, V, K
    (thesis (5-12): errors at the 1e-5 level, from the §5-6 random initialisation)."""
    entry = si.load_model("msd3_psd")
    model, data = entry.model, entry.data()
    truth = model.theta_vector(entry.truth)  # thesis (5-9); full symmetric: each entry is a parameter
    solver = ScrPSD(model, data, backend="cvxpy")
    errors = [float(np.max(np.abs(solver.run(x0).theta - truth))) for x0 in make_starts(model, 5, 0)]
    assert sum(e <= 1e-4 for e in errors) >= 4, errors

