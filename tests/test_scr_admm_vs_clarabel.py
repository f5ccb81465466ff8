"""The ADMM back end solves the same convex SCR sub-problem as Clarabel (fixed Q, R).

Issue 3, item 5: 20 random sub-problems, with and without LMIs and linear equalities,
real and complex blocks, unequal weights and a quadratic objective; the optimal values of
the relaxation (2-7)/(2-9) agree to rtol=1e-4.
"""

from __future__ import annotations

import numpy as np
import pytest

from symid import scr

N_SHARED, S, B = 3, 4, 2


def random_problem(seed: int, *, lmi: bool, equality: bool) -> tuple[scr.BilinearProblem, dict]:
    rng = np.random.default_rng(seed)
    th = scr.Variable("th", (N_SHARED,))
    gs = [scr.Variable(f"g{i}", (B, 1), complex=bool(i % 2)) for i in range(S)]
    terms = []
    for g in gs:
        A = scr.Affine(rng.standard_normal((B, B)), {th: rng.standard_normal((B, B, N_SHARED))})
        Bm = scr.Affine(rng.standard_normal((B, 1)), {g: np.eye(B).reshape(B, 1, B, 1)})
        C = scr.Affine(rng.standard_normal((B, 1)) + (1j if g.complex else 0) * rng.standard_normal((B, 1)),
                       {th: rng.standard_normal((B, 1, N_SHARED))})
        terms.append(scr.Bilinear(A=A, P=rng.standard_normal((B, B)), B=Bm, C=C, weight=float(rng.uniform(0.5, 2))))
    target = 2 * rng.standard_normal(N_SHARED)
    r = rng.standard_normal(N_SHARED)
    if equality:  # th ⟂ r: move the target into that plane
        target -= (r @ target) / (r @ r) * r
    E = rng.standard_normal((3, 3, N_SHARED))
    E = E + E.transpose(1, 0, 2)
    lam_min = np.linalg.eigvalsh(E @ target)[0]
    if lam_min > 0:
        E, lam_min = -E, -np.linalg.eigvalsh(E @ target)[-1]
    # E(th) = c I + Σ th_i E_i with th = 0 strictly feasible and the objective's target infeasible
    lmis = [scr.Affine(0.5 * abs(lam_min) * np.eye(3), {th: E})] if lmi else []
    eqs = [scr.Affine(np.zeros((1, 1)), {th: r.reshape(1, 1, N_SHARED)})] if equality else []
    objective = [scr.SumSquares(scr.Affine(-target.reshape(-1, 1), {th: np.eye(N_SHARED).reshape(
        N_SHARED, 1, N_SHARED)}), weight=10.0)]
    prob = scr.BilinearProblem(variables=[th, *gs], bilinear=terms, objective=objective, equalities=eqs, lmis=lmis)
    x0 = {"th": rng.standard_normal(N_SHARED)}
    for g in gs:
        x0[g.name] = rng.standard_normal((B, 1)) + (1j * rng.standard_normal((B, 1)) if g.complex else 0)
    return prob, x0


CASES = [(seed, seed % 2 == 0, seed % 4 < 2) for seed in range(20)]  # 5 of each (LMI, equality) combination


@pytest.mark.parametrize(("seed", "lmi", "equality"), CASES)
def test_admm_matches_clarabel_on_one_subproblem(seed, lmi, equality):
    prob, x0 = random_problem(seed, lmi=lmi, equality=equality)
    ref = scr.solve(prob, x0=x0, backend="cvxpy", max_iter=1)
    opts = scr.ADMMOptions(inner_first=200000, eps_abs=1e-11, eps_rel=1e-10)
    got = scr.solve(prob, x0=x0, backend="admm", max_iter=1, admm=opts)
    assert ref.history and got.history, (ref.message, got.message)
    assert "cap" not in got.message, got.message  # the ADMM met its own stopping rule
    # the optimal value of the relaxed problem (2-7)/(2-9) is unique even if the minimiser is not
    np.testing.assert_allclose(got.history[0].relaxation, ref.history[0].relaxation, rtol=1e-4)
    x_ref, x_got = ref.x_vector, got.x_vector
    if equality:
        eq = prob.equalities[0]
        np.testing.assert_allclose(eq(x_ref).real, 0, atol=1e-8)
        np.testing.assert_allclose(eq(x_got).real, 0, atol=1e-8)
    if lmi:
        E = prob.lmis[0]
        # the LMI is active at Clarabel's optimum (so the case really tests it), and ADMM keeps it
        assert np.linalg.eigvalsh(E(x_ref).real)[0] < 1e-6
        assert np.linalg.eigvalsh(E(x_got).real)[0] > -1e-6
