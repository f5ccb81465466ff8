"""Problem specification, validation, presolve and the result object of symid.scr."""

from __future__ import annotations

import json

import numpy as np
import pytest
import sympy as sp

from symid import scr
from symid.errors import ModelError, NonAffineError
from symid.scr.presolve import presolve

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
    # scr-lessons 7: known rows of A and the output equation fix every Γ_i; the last row is then
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
    sol = scr.solve(rosenbrock(), x0={x: -1.9, y: 2}, backend="admm", max_iter=30, tol=1e-8,
                    heuristic="truncated", truncate_after=1)
    assert sol.success, sol.message
    np.testing.assert_allclose([sol.x["x"], sol.x["y"]], [1, 1], atol=1e-5)
    with pytest.raises(ModelError, match="heuristic"):
        scr.solve(rosenbrock(), heuristic="logdet")


def test_cvxpy_backend_is_dpp_and_compiles_once():
    sol = scr.solve(rosenbrock(), x0={x: -1.9, y: 2}, backend="cvxpy", max_iter=4, tol=1e-12)
    assert sol.iterations == 4
    assert sol.info["is_dpp"] is True
    assert sol.info["compilations"] == 1


def test_solver_failure_is_reported_not_hidden():
    # infeasible LMI: x ⪰ 1 and −x ⪰ 0
    prob = scr.BilinearProblem(variables=[x, y], bilinear=[scr.Bilinear(A=[[x]], P=[[1]], B=[[y]], C=[[1]])],
                               lmis=[sp.Matrix([[x - 1]]), sp.Matrix([[-x]])])
    sol = scr.solve(prob, x0={x: 1, y: 1}, backend="cvxpy", max_iter=3)
    assert not sol.success and sol.status == "solver_error"
    assert "infeasible" in sol.message
