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
``"cvxpy"`` (Clarabel, compiled once per solve thanks to DPP parameters).
"""

from symid.scr.backend_admm import ADMMOptions
from symid.scr.maps import Affine
from symid.scr.problem import Bilinear, BilinearProblem, SumSquares
from symid.scr.result import Iteration, SCRSolution
from symid.scr.solve import solve
from symid.scr.variables import Layout, Variable

__all__ = [
    "ADMMOptions",
    "Affine",
    "Bilinear",
    "BilinearProblem",
    "Iteration",
    "Layout",
    "SCRSolution",
    "SumSquares",
    "Variable",
    "solve",
]
