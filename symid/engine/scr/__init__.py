"""Sequential Convex Relaxation (SCR): the bilinear-optimisation engine of symid.

Solves problems of the form (2-1) of the thesis, with an optional convex quadratic
objective f(x)::

    minimise f(x)  s.t.  A_i(x) P_i B_i(x) = C_i(x),  D(x) = 0,  E(x) ⪰ 0

by Algorithm 2.1: each bilinear equation is replaced by the nuclear norm of the matrix
M of (2-6), the convex problem is solved, Q := −A(x), R := −B(x), and again.

Two ways to pose a problem:

* sympy: variables are symbols (or :class:`Variable` blocks, whose ``.sym`` is a sympy
  matrix), matrices are sympy expressions;
* numeric (for formulations with many blocks): matrices are :class:`Affine` maps,
  ``Affine(const, {variable: coef})``, compiled without sympy.

Back ends: ``"admm"`` (numpy, vectorised over blocks, LMIs by PSD projection) and
``"cvxpy"`` (Clarabel, compiled once per solve thanks to DPP parameters). For many solves
of one problem (multi-start), :func:`compile` prepares it once (presolve, blocks, the
compiled SDP) and :func:`solve` reuses the :class:`CompiledProblem`.

Scaling, so that one weight λ means the same in every problem (``solve(normalize=True)``,
the default; details in :mod:`symid.engine.scr.presolve`): every bilinear equation is
equilibrated without changing its solutions — P divided by its spectral norm (C with it),
each row of the equation divided by the largest coefficient of that row of A(x) and C(x),
each column by the largest coefficient of that column of B(x) and C(x) — and a complex
term, which enters through the real representation (2-8) whose singular values are those
of the complex matrix twice over, gets half the weight, so that λ weighs the nuclear norm
of the complex M. Multiplying an equation, or P, by a constant therefore leaves the
iterates unchanged. LMIs are divided by their largest coefficient. The stopping residual
is that of the equilibrated terms; ``sol.history[k].residuals`` are the user's, unscaled.
"""

from symid.engine.scr.backend_admm import ADMMOptions
from symid.engine.scr.compiled import INCONSISTENT_TOL, CompiledProblem, compile
from symid.engine.scr.maps import Affine
from symid.engine.scr.problem import Bilinear, BilinearProblem, SumSquares
from symid.engine.scr.result import Iteration, ScrProgress, SCRSolution
from symid.engine.scr.solve import solve
from symid.engine.scr.variables import Layout, Variable

__all__ = [
    "INCONSISTENT_TOL",
    "ADMMOptions",
    "Affine",
    "Bilinear",
    "BilinearProblem",
    "CompiledProblem",
    "Iteration",
    "Layout",
    "SCRSolution",
    "ScrProgress",
    "SumSquares",
    "Variable",
    "compile",
    "solve",
]
