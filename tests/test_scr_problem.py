"""Problem specification, validation, presolve and the result object of symid.scr."""

from __future__ import annotations

import json

import numpy as np
import pytest
import sympy as sp

from symid import scr
from symid.engine.scr.presolve import presolve
from symid.errors import ModelError, NonAffineError

x, y, a = sp.symbols("x y a")


def rosenbrock(lam=0.1):
    return scr.BilinearProblem(
        variables=[x, y, a],
        bilinear=[scr.Bilinear(A=[[x]], P=[[1]], B=[[x]], C=[[y - a]], weight=lam)],
        objective=100 * a**2 + (1 - x) ** 2)


def test_non_affine_entry_is_named():
    with pytest.raises(NonAffineError, match=r"mine\.A, entry \(0, 1\)") as exc:
        scr.BilinearProblem(variables=[x, y], bilinear=[
            scr.Bilinear(A=[[x, x * y]], P=np.eye(2), B=[[1], [y]], C=[[0]], name="mine")])
    assert exc.value.matrix == "mine.A" and exc.value.entry == (0, 1)


def test_shape_mismatch_names_term():
    with pytest.raises(ModelError, match=r"bilinear\[0\]: shapes do not chain"):
        scr.BilinearProblem(variables=[x], bilinear=[scr.Bilinear(A=[[x, 1]], P=[[1]], B=[[x]], C=[[0]])])


def test_non_symmetric_lmi_rejected():
    with pytest.raises(ModelError, match=r"lmis\[0\] is not symmetric"):
        scr.BilinearProblem(variables=[x], lmis=[sp.Matrix([[x, 1], [0, 1]])])


def test_bad_x0_rejected():
    prob = rosenbrock()
    with pytest.raises(ModelError, match="unknown variable 'z'"):
        scr.solve(prob, x0={"z": 1.0})
    with pytest.raises(ModelError, match=r"x0\['y'\].*finite"):
        scr.solve(prob, x0={y: float("nan")})


def test_unknown_symbol_and_nonconvex_objective_rejected():
    with pytest.raises(ModelError, match="not variables"):
        scr.BilinearProblem(variables=[x], bilinear=[scr.Bilinear(A=[[x]], P=[[1]], B=[[x]], C=[[y]])])
    with pytest.raises(ModelError, match="not convex"):
        scr.BilinearProblem(variables=[x, y], objective=x * y)


def test_numeric_and_sympy_paths_agree():
    # the same Rosenbrock relaxation posed with Affine maps (no sympy)
    num = scr.BilinearProblem(
        variables=[scr.Variable("x"), scr.Variable("y"), scr.Variable("a")],
        bilinear=[scr.Bilinear(A=scr.Affine([[0.0]], {"x": [[1.0]]}), P=[[1.0]], B=scr.Affine([[0.0]], {"x": [[1.0]]}),
                               C=scr.Affine([[0.0]], {"y": [[1.0]], "a": [[-1.0]]}), weight=0.1)],
        objective=[scr.SumSquares(scr.Affine([[0.0]], {"a": [[1.0]]}), weight=100),
                   scr.SumSquares(scr.Affine([[-1.0]], {"x": [[1.0]]}))])
    s1 = scr.solve(num, x0={"x": -1.9, "y": 2}, backend="admm", max_iter=3)
    s2 = scr.solve(rosenbrock(), x0={x: -1.9, y: 2}, backend="admm", max_iter=3)
    for i1, i2 in zip(s1.iterates, s2.iterates, strict=True):
        np.testing.assert_allclose([i1["x"], i1["y"]], [i2["x"], i2["y"]], rtol=1e-9, atol=1e-12)


def test_complex_scalar_term_via_real_representation():
    # z² = 2j has the roots ±(1 + j); from near 1 + j SCR must find that root
    z = scr.Variable("z", complex=True)
    prob = scr.BilinearProblem(variables=[z], bilinear=[scr.Bilinear(A=z.sym, P=1, B=z.sym, C=2j)])
    for backend in ("admm", "cvxpy"):
        sol = scr.solve(prob, x0={"z": 0.8 + 1.3j}, backend=backend, max_iter=200, tol=1e-8)
        assert sol.success, sol.message
        np.testing.assert_allclose(sol.x["z"], 1 + 1j, atol=1e-6)
        assert sol.history[-1].residuals[0] < 1e-7


def belt_drive(s=10):
    """Thesis (3-17) with the state equations (3-10a) and output equation (3-10b), numeric path."""
    th = np.array([-1, -0.5, -0.2, -0.15])  # thesis (3-18)
    A0 = np.array([[0, -1, 0.15], [0.2, 0, 0], [0, 0, 0]])
    Ak = np.zeros((3, 3, 4))
    Ak[2, 0, 0] = Ak[2, 1, 1] = Ak[2, 2, 2] = 1
    Bk = np.zeros((3, 1, 4))
    Bk[2, 0, 3] = 1
    Cm = np.array([[0, 1, 0.0]])
    w = 2 * np.pi * np.logspace(np.log10(0.4), np.log10(0.6), s)
    H = [Cm @ np.linalg.solve(1j * wi * np.eye(3) - (A0 + Ak @ th), Bk @ th) for wi in w]
    theta = scr.Variable("theta", (4,))
    G = [scr.Variable(f"G{i}", (3, 1), complex=True) for i in range(s)]
    eye = np.eye(3).reshape(3, 1, 3, 1)
    terms = [scr.Bilinear(A=scr.Affine(A0, {theta: Ak}), P=np.eye(3), B=scr.Affine(np.zeros((3, 1)), {G[i]: eye}),
                          C=scr.Affine(np.zeros((3, 1)), {G[i]: 1j * w[i] * eye, theta: -Bk}), name=f"state[{i}]")
             for i in range(s)]
    eqs = [scr.Affine(-H[i], {G[i]: Cm.reshape(1, 1, 3, 1)}) for i in range(s)]
    return scr.BilinearProblem(variables=[theta, *G], bilinear=terms, equalities=eqs), th


def test_presolve_splits_constant_rows_and_solves_belt_drive_exactly():
    prob, th = belt_drive()
    red = presolve(prob, split=False)
    assert len(red.terms) == 10 and red.terms[0].dims == (6, 6, 6, 2)  # whole complex 3×3 block, (2-8)
    red = presolve(prob)
    # known rows of A and the output equation fix every Γ_i; the last row is then
    # linear in θ and, with 10 frequencies, fixes θ too: no unknown is left, no SCR iteration needed
    assert red.terms == [] and red.nz == 0 and red.info["fixed"] == 64
    for backend in ("admm", "cvxpy"):
        sol = scr.solve(prob, backend=backend)
        assert sol.success and sol.iterations == 1, sol.message
        np.testing.assert_allclose(sol.x["theta"], th, rtol=1e-6)  # thesis (3-18)


def test_presolve_keeps_only_the_bilinear_row():
    prob, _ = belt_drive(3)
    # without the output equation Γ is not determined, but rows 1, 2 of A are constant
    prob = scr.BilinearProblem(variables=prob.variables, bilinear=[scr.Bilinear(
        A=t.A, P=t.P, B=t.B, C=t.C) for t in prob.terms])
    red = presolve(prob)
    assert [t.dims for t in red.terms] == [(2, 6, 6, 2)] * 3  # one complex row = 2 real rows
    assert red.D.shape == (3 * 4, prob.n)  # 2 complex rows per term = 4 real equalities


def test_max_iter_message_says_when_the_iterate_is_stationary():
    # x² = 1 and x² = 4 cannot both hold: SCR stops moving with a residual it cannot reduce
    inconsistent = scr.BilinearProblem(variables=[x], bilinear=[
        scr.Bilinear(A=[[x]], P=[[1]], B=[[x]], C=[[1]]), scr.Bilinear(A=[[x]], P=[[1]], B=[[x]], C=[[4]])])
    sol = scr.solve(inconsistent, x0={x: 1.0}, max_iter=5, stationary=None)
    assert sol.status == "max_iter" and not sol.success
    assert "the iterate is stationary" in sol.message and "cannot all hold" in sol.message
    # by default SCR stops once the iterate has stopped moving (3 steps in a row) short of tol
    sol = scr.solve(inconsistent, x0={x: 1.0}, max_iter=50)
    assert sol.status == "stationary" and not sol.success and sol.info["stationary"]
    assert sol.iterations < 50 and "cannot all hold" in sol.message
    moving = scr.solve(rosenbrock(), x0={x: -1.9, y: 2}, max_iter=1)  # one step from far away
    assert "last step" in moving.message and "stationary" not in moving.message


def test_result_object():
    sol = scr.solve(rosenbrock(), x0={x: -1.9, y: 2}, backend="admm", max_iter=2)
    assert sol.status == "max_iter" and not sol.success
    assert "maximum number of iterations" in sol.message
    assert sol.iterations == 2 and sol.wall_time > 0
    h = sol.history[0]
    assert h.objective >= 0 and h.relaxation >= h.objective and h.time > 0
    d = json.loads(json.dumps(sol.to_dict()))
    assert d["iterations"] == 2 and len(d["history"]) == 2
    assert "SCR solution" in sol.summary() and "max_iter" in sol.summary()
    with pytest.raises(AttributeError):
        sol.status = "x"


def test_truncated_nuclear_norm_option():
    # thesis §6-7-1 (Hu et al. 2012): ||M||_* − <U_r V_rᵀ, M>; Rosenbrock's minimum (1, 1), thesis §2-5-2
    for backend in ("admm", "cvxpy"):
        sol = scr.solve(rosenbrock(), x0={x: -1.9, y: 2}, backend=backend, max_iter=30, tol=1e-8,
                        heuristic="truncated", truncate_after=1)
        assert sol.success, (backend, sol.message)
        np.testing.assert_allclose([sol.x["x"], sol.x["y"]], [1, 1], atol=1e-5)
        plain = scr.solve(rosenbrock(), x0={x: -1.9, y: 2}, backend=backend, max_iter=2)
        # iteration 2 differs: the relaxation subtracts the linear term (its value drops below the plain one)
        assert sol.history[1].relaxation < plain.history[1].relaxation - 1e-6
    with pytest.raises(ModelError, match="heuristic"):
        scr.solve(rosenbrock(), heuristic="logdet")


def test_cvxpy_backend_is_dpp_and_compiles_once(monkeypatch):
    import cvxpy as cp
    from cvxpy.reductions.chain import Chain

    from symid.engine.scr.backend_cvxpy import CvxpyBackend

    problems: list[cp.Problem] = []
    init = CvxpyBackend.__init__

    def spy_init(self, *args, **kwargs):
        init(self, *args, **kwargs)
        problems.append(self.problem)

    applied = []
    apply = Chain.apply

    def spy_apply(self, problem, verbose=False):  # the reduction chain: cvxpy's compilation
        applied.append(problem)
        return apply(self, problem, verbose)

    monkeypatch.setattr(CvxpyBackend, "__init__", spy_init)
    monkeypatch.setattr(Chain, "apply", spy_apply)
    # two bilinear terms of different shapes, an LMI and an equality: every kind of parameter
    prob = scr.BilinearProblem(
        variables=[x, y, a],
        bilinear=[scr.Bilinear(A=[[x]], P=[[1]], B=[[x]], C=[[y - a]], weight=0.1),
                  scr.Bilinear(A=[[x, y]], P=np.eye(2), B=[[y], [a]], C=[[1]], weight=0.5)],
        objective=100 * a**2 + (1 - x) ** 2, equalities=[x + y + a - 1], lmis=[sp.Matrix([[x, 0], [0, 1 - y]])])
    sol = scr.solve(prob, x0={x: -1.9, y: 2}, backend="cvxpy", max_iter=4, tol=1e-12)
    assert sol.iterations == 4, sol.message
    assert len(problems) == 1 and problems[0].is_dpp()
    assert sol.info["is_dpp"] is True
    assert len(applied) == 1  # compiled at the first iteration only; the other three re-used it
    assert sol.info["compilations"] == 1


def test_solver_failure_is_reported_not_hidden():
    # infeasible LMI: x ⪰ 1 and −x ⪰ 0
    prob = scr.BilinearProblem(variables=[x, y], bilinear=[scr.Bilinear(A=[[x]], P=[[1]], B=[[y]], C=[[1]])],
                               lmis=[sp.Matrix([[x - 1]]), sp.Matrix([[-x]])])
    sol = scr.solve(prob, x0={x: 1, y: 1}, backend="cvxpy", max_iter=3)
    assert not sol.success and sol.status == "solver_error"
    assert "infeasible" in sol.message


def test_normalisation_makes_weight_independent_of_equation_scale():
    # issue 3 notes: one λ behaves the same across problems. Multiplying the equation x·x = y − a by
    # 1000 and P by 5 (C with them) leaves the solution set unchanged; after presolve's equilibration
    # the iterates must be identical, while without it λ effectively changes.
    scaled = scr.BilinearProblem(
        variables=[x, y, a],
        bilinear=[scr.Bilinear(A=[[1000 * x]], P=[[5]], B=[[x]], C=[[5000 * (y - a)]], weight=0.1)],
        objective=100 * a**2 + (1 - x) ** 2)
    for backend in ("admm", "cvxpy"):
        ref = scr.solve(rosenbrock(), x0={x: -1.9, y: 2}, backend=backend, max_iter=3)
        got = scr.solve(scaled, x0={x: -1.9, y: 2}, backend=backend, max_iter=3)
        for i1, i2 in zip(ref.iterates, got.iterates, strict=True):
            np.testing.assert_allclose([i2["x"], i2["y"]], [i1["x"], i1["y"]], rtol=1e-6, atol=1e-6)
    raw = scr.solve(scaled, x0={x: -1.9, y: 2}, backend="cvxpy", max_iter=1, normalize=False)
    assert abs(raw.iterates[0]["y"] - (-6.03)) > 1  # thesis §2-5-2 first iterate only with λ = 0.1 as meant


def test_matrix_block_variable_through_sympy():
    # X² = S² for a 2×2 real block X, posed with the variable's sympy matrix; from near S, SCR finds S
    X = scr.Variable("X", (2, 2))
    S = np.array([[2.0, 0.5], [0.3, 1.5]])
    prob = scr.BilinearProblem(variables=[X], bilinear=[scr.Bilinear(A=X.sym, P=np.eye(2), B=X.sym, C=S @ S)])
    x0 = {"X": S + 0.1 * np.array([[1.0, -1.0], [0.5, 0.2]])}
    for backend in ("admm", "cvxpy"):
        sol = scr.solve(prob, x0=x0, backend=backend, max_iter=200, tol=1e-9)
        assert sol.success, sol.message
        assert sol.x["X"].shape == (2, 2)
        np.testing.assert_allclose(sol.x["X"], S, atol=1e-6)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"backend": "scs"}, "unknown backend 'scs'"),
    ({"max_iter": 0}, "max_iter must be ≥ 1"),
    ({"tol": -1.0}, "tol must be finite and > 0"),
    ({"step_tol": -1.0}, "step_tol must be finite"),
    ({"heuristic": "truncated", "truncate_after": -1}, "truncate_after must be ≥ 0"),
    ({"admm": {"rho": 1.0}}, "admm must be an scr.ADMMOptions"),
    ({"backend": "cvxpy", "solver_options": {"no_such_setting": 1}}, "refused by CLARABEL"),
])
def test_bad_solve_arguments_are_named(kwargs, match):
    with pytest.raises(ModelError, match=match):
        scr.solve(rosenbrock(), x0={x: -1.9, y: 2}, **({"max_iter": 2} | kwargs))


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"rho": -1.0}, "rho must be finite and > 0"),
    ({"alpha": 2.0}, "alpha must lie in"),
    ({"inner": 0}, "inner must be ≥ 1"),
    ({"eps_abs": -1e-3}, "eps_abs must be ≥ 0"),
])
def test_bad_admm_options_are_named(kwargs, match):
    with pytest.raises(ModelError, match=match):
        scr.ADMMOptions(**kwargs)


def test_bad_problem_input_is_named():
    G = scr.Variable("G", (2, 1))
    with pytest.raises(ModelError, match=r"bilinear\[0\]\.A: the coefficient of G has shape \(1, 2, 3\)"):
        scr.BilinearProblem(variables=[G], bilinear=[scr.Bilinear(
            A=scr.Affine(np.zeros((1, 2)), {G: np.ones((1, 2, 3))}), P=np.eye(2), B=G.sym, C=[[1]])])
    with pytest.raises(ModelError, match=r"x0\['G'\] has shape \(3,\)"):
        prob = scr.BilinearProblem(variables=[G], bilinear=[scr.Bilinear(A=G.sym.T, P=np.eye(2), B=G.sym, C=[[1]])])
        scr.solve(prob, x0={"G": [1.0, 2.0, 3.0]})
    with pytest.raises(ModelError, match=r"lmis\[0\] must be square"):
        scr.BilinearProblem(variables=[x], lmis=[sp.Matrix([[x, 1]])])
    with pytest.raises(ModelError, match=r"lmis\[0\] is not symmetric"):
        scr.BilinearProblem(variables=[x], lmis=[np.array([[1.0, 2.0], [0.0, 1.0]])])
    with pytest.raises(ModelError, match=r"bilinear\[0\]\.P must be constant"):
        scr.BilinearProblem(variables=[x], bilinear=[scr.Bilinear(A=[[x]], P=[[x]], B=[[x]], C=[[1]])])
    with pytest.raises(NonAffineError, match=r"lmis\[0\], entry \(0, 0\)"):
        scr.BilinearProblem(variables=[x, y], lmis=[sp.Matrix([[x * y]])])


def test_admm_kkt_sparse_and_dense_factorisations_agree():
    # the z-update of appendix B (B-9): [[N, Dᵀ], [D, 0]] [z; ν] = [b; d], with an arrow-shaped N
    from symid.engine.scr.backend_admm import _KKT

    rng = np.random.default_rng(3)
    n_shared, blocks, size = 3, 40, 4
    n = n_shared + blocks * size
    rows, cols, vals = [], [], []
    for t in range(blocks):
        idx = np.r_[np.arange(n_shared), n_shared + t * size + np.arange(size)]
        F = rng.standard_normal((2 * idx.size, idx.size))
        ii, jj = np.meshgrid(idx, idx, indexing="ij")
        rows.append(ii.ravel())
        cols.append(jj.ravel())
        vals.append((F.T @ F).ravel())
    import scipy.sparse as sps

    N = sps.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
    D = sps.csr_matrix(rng.standard_normal((5, n)))
    rhs = rng.standard_normal(n + 5)
    K = np.block([[N.toarray(), D.T.toarray()], [D.toarray(), np.zeros((5, 5))]])
    ref = np.linalg.solve(K, rhs)[:n]
    assert _KKT(N, D).sparse is None and _KKT(N, D, dense_max=10).sparse is not None
    np.testing.assert_allclose(_KKT(N, D).solve(rhs), ref, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(_KKT(N, D, dense_max=10).solve(rhs), ref, rtol=1e-9, atol=1e-12)


def test_admm_backend_runs_without_cvxpy():
    # issue 3 item 4: the ADMM back end is pure numpy/scipy; cvxpy is never imported
    import subprocess
    import sys

    code = ("import sys, sympy as sp\nfrom symid import scr\nx, y, a = sp.symbols('x y a')\n"
            "p = scr.BilinearProblem(variables=[x, y, a], bilinear=[scr.Bilinear(A=[[x]], P=[[1]], B=[[x]], "
            "C=[[y - a]], weight=0.1)], objective=100 * a**2 + (1 - x)**2, lmis=[sp.Matrix([[1 - a]])])\n"
            "sol = scr.solve(p, x0={x: -1.9, y: 2}, backend='admm', max_iter=3)\n"
            "print(len(sol.history), 'cvxpy' in sys.modules, 'clarabel' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["3", "False", "False"]


def test_admm_warm_start_and_tightening():
    # belt drive (3-17), whole 3×3 blocks relaxed (presolve=False): 10 blocks of 12×8 in the real representation
    prob, th = belt_drive()
    x0 = {"theta": th + 0.1 * np.random.default_rng(1).standard_normal(4)}
    opts = {"backend": "admm", "max_iter": 60, "tol": 1e-5, "step_tol": 1e9, "presolve": False}
    sol = scr.solve(prob, x0=x0, admm=scr.ADMMOptions(eps_rel=1e-5, eps_abs=1e-6), **opts)
    assert sol.success, sol.message
    inner = sol.info["inner_iterations"]
    # warm start across SCR iterations: the cold first sub-problem costs far more ADMM steps than the next ones
    # (measured 545 against a median of 50; an ADMM step count moves with the machine's rounding, so the margin
    # asserted is wide)
    assert inner[0] > 3 * np.median(inner[1:10])
    # with loose ADMM tolerances the reachable bilinear residual is capped near them, unless the
    # tolerances are tightened to the residual as SCR converges (ADMMOptions.tighten)
    loose = {"eps_rel": 1e-4, "eps_abs": 1e-5}
    capped = scr.solve(prob, x0=x0, admm=scr.ADMMOptions(tighten=None, **loose), **opts)
    tightened = scr.solve(prob, x0=x0, admm=scr.ADMMOptions(**loose), **opts)
    assert not capped.success and capped.residual > 1e-4
    assert tightened.success and tightened.residual <= 1e-5


def test_rank_deficient_P_is_compressed_without_changing_the_iterates(monkeypatch):
    # A P B with A = [x, x], P = ones/4, B = [x; x] is x·x = y − a: presolve step 6 compresses P to
    # rank 1; SCR on the compressed block must give the iterates of the uncompressed one

    def padded():  # a new object each time: the presolve is cached on the problem
        return scr.BilinearProblem(
            variables=[x, y, a],
            bilinear=[scr.Bilinear(A=[[x, x]], P=np.full((2, 2), 0.25), B=[[x], [x]], C=[[y - a]], weight=0.1)],
            objective=100 * a**2 + (1 - x) ** 2)

    assert presolve(padded()).terms[0].dims == (1, 1, 1, 1)  # (j, k, l, m): P 2×2 → 1×1
    exact = {"admm": scr.ADMMOptions(eps_abs=1e-11, eps_rel=1e-11, inner_max=100_000), "cvxpy": None}
    opts = {b: {"backend": b, "admm": exact[b], "max_iter": 3, "tol": 1e-12} for b in exact}
    got = {b: scr.solve(padded(), x0={x: -1.9, y: 2}, **o) for b, o in opts.items()}
    import symid.engine.scr.presolve as pre

    monkeypatch.setattr(pre, "_compress", lambda A, P, B: (A, P, B))
    assert presolve(padded()).terms[0].dims == (1, 2, 2, 1)
    for backend, sol in got.items():
        ref = scr.solve(padded(), x0={x: -1.9, y: 2}, **opts[backend])
        assert len(ref.iterates) == len(sol.iterates) == 3
        # the same sub-problems: equal optimal values; equal iterates, to 1e-6 for the ADMM, and to
        # 1e-3 for Clarabel, whose y (the sub-problem is flat in y near its optimum) moves by 3e-4
        np.testing.assert_allclose([h.relaxation for h in sol.history], [h.relaxation for h in ref.history],
                                   rtol=1e-6)
        atol = 1e-6 if backend == "admm" else 1e-3
        for i1, i2 in zip(ref.iterates, sol.iterates, strict=True):
            np.testing.assert_allclose([i2["x"], i2["y"]], [i1["x"], i1["y"]], rtol=0, atol=atol)


def test_callback_stops_the_iteration():
    seen = []

    def stop_at_two(k, xk):
        seen.append((k, xk["x"]))
        return k >= 2

    sol = scr.solve(rosenbrock(), x0={x: -1.9, y: 2}, backend="admm", max_iter=10, callback=stop_at_two)
    assert sol.status == "stopped" and not sol.success and sol.iterations == 2
    assert [k for k, _ in seen] == [1, 2] and "stopped by the callback after 2 iterations" in sol.message
    assert seen[0][1] == pytest.approx(0.900, abs=1e-3)  # the thesis's first iterate, §2-5-2
    with pytest.raises(ModelError, match="callback must be callable"):
        scr.solve(rosenbrock(), callback=3)


def test_compiled_problem_is_reused_with_identical_iterates():
    # The promise of scr.compile: later solves reuse the presolve and the compiled SDP and
    # give the iterates of a solve of the bare problem. Every sub-problem hands Clarabel
    # identical data in a new solver (warm_start=False), and Clarabel is deterministic, so
    # the iterates agree to the last bit; rtol 1e-12 only allows for a platform whose BLAS
    # sums in a different order between two calls (never seen). Before the fix, cvxpy's
    # default warm_start=True updated the previous solver in place: 3.7e-11 apart here,
    # 4.7e-7 on another CPU.
    compiled = scr.compile(rosenbrock())
    first = scr.solve(compiled, x0={x: -1.9, y: 2}, backend="cvxpy", max_iter=3)
    again = scr.solve(compiled, x0={x: -1.9, y: 2}, backend="cvxpy", max_iter=3)
    fresh = scr.solve(rosenbrock(), x0={x: -1.9, y: 2}, backend="cvxpy", max_iter=3)
    assert first.info["compilations"] == 1 and again.info["compilations"] == 0
    assert fresh.info["compilations"] == 1
    assert again.info["presolve_time"] < compiled.prepare_time + 1.0  # nothing presolved again
    for i1, i2, i3 in zip(first.iterates, again.iterates, fresh.iterates, strict=True):
        np.testing.assert_allclose([i2["x"], i2["y"]], [i1["x"], i1["y"]], rtol=1e-12, atol=0)
        np.testing.assert_allclose([i3["x"], i3["y"]], [i1["x"], i1["y"]], rtol=1e-12, atol=0)


def test_bare_problem_is_not_cached_between_solves():
    # no hidden state on the problem object: each solve of a bare problem compiles afresh
    prob = rosenbrock()
    scr.solve(prob, x0={x: -1.9, y: 2}, backend="cvxpy", max_iter=1)
    again = scr.solve(prob, x0={x: -1.9, y: 2}, backend="cvxpy", max_iter=1)
    assert again.info["compilations"] == 1
    assert not any(k.startswith("_scr") for k in vars(prob))


def test_compiled_problem_options_cannot_be_overridden_by_solve():
    compiled = scr.compile(rosenbrock(), presolve=True)
    with pytest.raises(ModelError, match="presolve=False differs from the compiled"):
        scr.solve(compiled, x0={x: -1.9, y: 2}, presolve=False)
    with pytest.raises(ModelError, match="BilinearProblem or a CompiledProblem"):
        scr.solve("x*y - 1")
    with pytest.raises(ModelError, match="compile\\(\\) needs a BilinearProblem"):
        scr.compile(None)


def test_a_constant_sum_of_squares_is_a_constant_objective():
    # found by hypothesis in a fresh CI environment (tests/test_safe_expressions.py): SumSquares([["0"]]) has no
    # variable, so its Jacobian has no column; it used to raise numpy's "cannot reshape array of size 0"
    x, y = sp.symbols("x y")
    for text, value in (("0", 0.0), ("3", 9.0)):
        prob = scr.BilinearProblem(variables=[x, y], objective=scr.SumSquares([[text]]))
        assert prob.objective_value(np.zeros(2)) == pytest.approx(value, abs=1e-15)
