"""The ADMM back end solves the same convex SCR sub-problem as Clarabel (fixed Q, R)."""

from __future__ import annotations

import numpy as np
import pytest

from symid import scr


def random_problem(seed: int, *, lmi: bool, equality: bool) -> tuple[scr.BilinearProblem, dict]:
    rng = np.random.default_rng(seed)
    n_shared, s, b = 3, 4, 2
    th = scr.Variable("th", (n_shared,))
    gs = [scr.Variable(f"g{i}", (b, 1), complex=bool(i % 2)) for i in range(s)]
    terms = []
    for g in gs:
        A = scr.Affine(rng.standard_normal((b, b)), {th: rng.standard_normal((b, b, n_shared))})
        B = scr.Affine(rng.standard_normal((b, 1)), {g: np.eye(b).reshape(b, 1, b, 1)})
        C = scr.Affine(rng.standard_normal((b, 1)) + (1j if g.complex else 0) * rng.standard_normal((b, 1)),
                       {th: rng.standard_normal((b, 1, n_shared))})
        terms.append(scr.Bilinear(A=A, P=rng.standard_normal((b, b)), B=B, C=C, weight=float(rng.uniform(0.5, 2))))
    lmis, eqs = [], []
    if lmi:
        E = rng.standard_normal((3, 3, n_shared))
        lmis.append(scr.Affine(np.eye(3), {th: E + E.transpose(1, 0, 2)}))
    if equality:
        eqs.append(scr.Affine(np.zeros((1, 1)), {th: rng.standard_normal((1, 1, n_shared))}))  # th = 0 feasible
    objective = [scr.SumSquares(scr.Affine(-rng.standard_normal((n_shared, 1)), {th: np.eye(n_shared).reshape(
        n_shared, 1, n_shared)}), weight=0.3)]
    prob = scr.BilinearProblem(variables=[th, *gs], bilinear=terms, objective=objective, equalities=eqs, lmis=lmis)
    x0 = {"th": rng.standard_normal(n_shared)}
    for g in gs:
        x0[g.name] = rng.standard_normal((b, 1)) + (1j * rng.standard_normal((b, 1)) if g.complex else 0)
    return prob, x0


CASES = [(seed, seed % 2 == 0, seed % 4 < 2) for seed in range(20)]


@pytest.mark.parametrize(("seed", "lmi", "equality"), CASES)
def test_admm_matches_clarabel_on_one_subproblem(seed, lmi, equality):
    prob, x0 = random_problem(seed, lmi=lmi, equality=equality)
    ref = scr.solve(prob, x0=x0, backend="cvxpy", max_iter=1)
    opts = scr.ADMMOptions(inner_first=200000, eps_abs=1e-11, eps_rel=1e-10)
    got = scr.solve(prob, x0=x0, backend="admm", max_iter=1, admm=opts)
    assert ref.history and got.history, (ref.message, got.message)
    # the optimal value of the relaxed problem (2-7)/(2-9) is unique even if the minimiser is not
    np.testing.assert_allclose(got.history[0].relaxation, ref.history[0].relaxation, rtol=1e-4)
