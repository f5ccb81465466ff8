"""Ruiz equilibration of the ADMM back end (``ADMMOptions.equilibrate``): one factor per block, one per variable.

The scaled iteration must solve the same sub-problem as Clarabel (the scaling is a change of
variables, ŷ = D y, ẑ = E⁻¹ z, with D constant on every nuclear-norm and PSD block), and the
factors must equilibrate what they claim to.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import scipy.sparse as sps
import sympy as sp

from symid import scr
from symid.engine.scr.backend_admm import ADMMBackend, ruiz
from symid.engine.scr.compiled import compile as compile_problem


def _blocky(rng: np.random.Generator, sizes: list[int], n: int) -> tuple[sps.csr_matrix, np.ndarray]:
    """A sparse matrix whose row blocks differ in scale by up to 10⁶, its columns by up to 10², within the
    range ruiz() lets the factors take (10⁻⁴…10⁴)."""
    blocks = [sps.random(s, n, density=0.6, random_state=rng, data_rvs=rng.standard_normal) * 10.0 ** rng.uniform(-3, 3)
              for s in sizes]
    A = sps.csr_matrix(sps.vstack(blocks) @ sps.diags(10.0 ** rng.uniform(-1, 1, n)))
    return A, np.concatenate([[0], np.cumsum(sizes)])


@pytest.mark.parametrize("seed", range(5))
def test_ruiz_brings_every_block_and_column_maximum_to_one(seed):
    rng = np.random.default_rng(seed)
    A, starts = _blocky(rng, [int(v) for v in rng.integers(2, 20, size=8)], 6)
    d, e = ruiz(A, starts)
    B = abs(sps.diags(np.repeat(d, np.diff(starts))) @ A @ sps.diags(e)).toarray()
    block_max = np.array([B[a:b].max() for a, b in itertools.pairwise(starts)])
    # the stopping rule of ruiz(): every maximum within 10 % of 1 (before the last update, which moves it closer)
    np.testing.assert_allclose(block_max, 1.0, atol=0.1)
    np.testing.assert_allclose(B.max(axis=0), 1.0, atol=0.1)
    # before: maxima spread over many decades
    B0 = abs(A).toarray()
    raw = np.array([B0[a:b].max() for a, b in itertools.pairwise(starts)])
    assert raw.max() / raw.min() > 1e3


def test_ruiz_keeps_factor_one_for_empty_blocks_and_columns_and_counts_the_objective():
    A = sps.csr_matrix(np.array([[0.0, 4.0, 0.0], [0.0, 0.0, 0.0], [0.0, 1e-2, 0.0]]))
    d, e = ruiz(A, np.array([0, 1, 2, 3]))
    assert d[1] == 1.0 and e[0] == 1.0 and e[2] == 1.0  # nothing to scale there
    np.testing.assert_allclose([4.0 * d[0] * e[1], 1e-2 * d[2] * e[1]], 1.0, atol=0.1)
    # with H = diag(0, 0, 100) the third column is scaled by the objective: e₃² · 100 → 1
    d, e = ruiz(A, np.array([0, 1, 2, 3]), H=sps.diags([0.0, 0.0, 100.0]).tocsr())
    np.testing.assert_allclose(e[2] ** 2 * 100.0, 1.0, atol=0.1)


def _scaled_problem(seed: int) -> tuple[scr.BilinearProblem, dict]:
    """Terms and an LMI whose sizes differ by up to 10⁶ (the situation equilibration is for)."""
    rng = np.random.default_rng(seed)
    th = scr.Variable("th", (3,))
    gs = [scr.Variable(f"g{i}", (2, 1), complex=bool(i % 2)) for i in range(4)]
    terms = []
    for g in gs:
        s = 10.0 ** rng.uniform(-3, 3)
        A = scr.Affine(s * rng.standard_normal((2, 2)), {th: s * rng.standard_normal((2, 2, 3))})
        Bm = scr.Affine(rng.standard_normal((2, 1)), {g: np.eye(2).reshape(2, 1, 2, 1)})
        C = scr.Affine(s * rng.standard_normal((2, 1)), {th: s * rng.standard_normal((2, 1, 3))})
        terms.append(scr.Bilinear(A=A, P=rng.standard_normal((2, 2)), B=Bm, C=C, weight=float(rng.uniform(0.5, 2))))
    target = 2 * rng.standard_normal(3)
    E = rng.standard_normal((3, 3, 3))
    E = 1e3 * (E + E.transpose(1, 0, 2))
    lam = np.linalg.eigvalsh(E @ target)
    if lam[0] > 0:
        E, lam = -E, -lam[::-1]
    lmis = [scr.Affine(0.5 * abs(lam[0]) * np.eye(3), {th: E})]  # th = 0 strictly feasible, the target not
    objective = [scr.SumSquares(scr.Affine(-target.reshape(-1, 1), {th: np.eye(3).reshape(3, 1, 3)}), weight=10.0)]
    prob = scr.BilinearProblem(variables=[th, *gs], bilinear=terms, objective=objective, lmis=lmis)
    x0 = {"th": rng.standard_normal(3)}
    for g in gs:
        x0[g.name] = rng.standard_normal((2, 1)) + (1j * rng.standard_normal((2, 1)) if g.complex else 0)
    return prob, x0


@pytest.mark.parametrize("seed", range(4))
def test_equilibrated_admm_solves_the_same_subproblem_as_clarabel(seed):
    prob, x0 = _scaled_problem(seed)
    ref = scr.solve(prob, x0=x0, backend="cvxpy", max_iter=1)
    opts = scr.ADMMOptions(inner_first=200_000, eps_abs=1e-11, eps_rel=1e-10, equilibrate=True)
    got = scr.solve(prob, x0=x0, backend="admm", max_iter=1, admm=opts)
    assert "cap" not in got.message, got.message  # ADMM met its own stopping rule
    # the optimal value of the relaxation (2-7)/(2-9) is unique even where the minimiser is not
    np.testing.assert_allclose(got.history[0].relaxation, ref.history[0].relaxation, rtol=1e-4)
    E = prob.lmis[0]
    ev_ref, ev_got = np.linalg.eigvalsh(E(ref.x_vector).real), np.linalg.eigvalsh(E(got.x_vector).real)
    assert ev_ref[0] < 1e-6 * np.abs(ev_ref).max()  # the LMI (scaled by 10³) is active, so the case tests it
    assert ev_got[0] > -1e-6 * np.abs(ev_got).max()


def test_equilibrated_admm_reproduces_the_thesis_rosenbrock_step():
    # thesis §2-5-2, Algorithm 2.3 with λ = 0.1 from (−1.9, 2): first iterate (0.9000, −6.0300) (text below Fig. 2-2)
    x, y, a = sp.symbols("x y a")
    prob = scr.BilinearProblem(variables=[x, y, a],
                               bilinear=[scr.Bilinear(A=[[x]], P=[[1]], B=[[x]], C=[[y - a]], weight=0.1)],
                               objective=100 * a**2 + (1 - x) ** 2)
    opts = scr.ADMMOptions(inner_first=100_000, eps_abs=1e-12, eps_rel=1e-11, equilibrate=True)
    sol = scr.solve(prob, x0={x: -1.9, y: 2}, backend="admm", max_iter=1, admm=opts, presolve=False)
    np.testing.assert_allclose([sol.iterates[0]["x"], sol.iterates[0]["y"]], [0.9, -6.03], atol=1e-4)


def test_rescaling_keeps_the_dual_of_the_original_problem():
    # Λ = ρ D u is what the warm start carries from one sub-problem to the next: new factors
    # must change the scaled dual u, never Λ
    prob, _ = _scaled_problem(0)
    c = compile_problem(prob)
    be = ADMMBackend(c.reduced, c.groups, c.lmi_groups, scr.ADMMOptions(equilibrate=True))
    z = np.random.default_rng(1).standard_normal(c.reduced.nz)
    built = [g.build(-g.A(z), -g.B(z)) for g in c.groups]
    be.step(built, None, z)
    lam = be.rho * be.d_rows * be.u
    z2 = z + 10.0 * np.random.default_rng(2).standard_normal(z.size)
    A2, _ = be._assemble([g.build(-g.A(z2), -g.B(z2)) for g in c.groups])
    d_old = be.d_rows.copy()
    be._equilibrate(A2)
    assert not np.allclose(be.d_rows, d_old)  # the factors did change
    np.testing.assert_allclose(be.rho * be.d_rows * be.u, lam, rtol=1e-12, atol=0)
