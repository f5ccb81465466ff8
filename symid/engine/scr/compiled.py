"""A bilinear problem prepared once for many SCR solves (multi-start).

The presolve (:mod:`symid.engine.scr.presolve`), the grouping of terms into blocks
(:mod:`symid.engine.scr.blocks`) and, for the cvxpy back end, the compiled SDP depend on the
problem only, not on the start. :func:`compile` does this work once and returns a
:class:`CompiledProblem`; :func:`symid.engine.scr.solve` accepts it in place of the problem and
reuses everything in it. A solve from a compiled problem gives the same iterates as a
solve of the bare problem: every SCR step overwrites all parameters of the compiled
SDP, and Clarabel is started from a new solver object on every sub-problem (cvxpy's
``warm_start=False``; with cvxpy's default it would update the previous solver's data
in place, which changes the iterates in the last digits — by up to 5e-7 relative
on some CPUs).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

from symid.engine.scr.blocks import LMIGroup, TermGroup, group_lmis, group_terms
from symid.engine.scr.presolve import INCONSISTENT_TOL, Reduced
from symid.engine.scr.presolve import presolve as _presolve
from symid.engine.scr.problem import BilinearProblem
from symid.errors import ModelError

__all__ = ["INCONSISTENT_TOL", "CompiledProblem", "compile"]


class CompiledProblem:
    """A :class:`BilinearProblem` presolved and grouped, ready for many solves.

    Build it with :func:`compile`. Attributes are read-only by convention: the
    back ends only read them.

    Attributes
    ----------
    problem : BilinearProblem
        The problem it was compiled from.
    presolve, normalize : bool
        The options it was compiled with (see :func:`symid.engine.scr.solve`).
    equalities : str
        ``"exact"`` or ``"least_squares"`` (see :func:`compile`).
    reduced : Reduced
        The presolved problem.
    groups : list of TermGroup
        Blocks of bilinear terms (empty when the equalities are inconsistent).
    lmi_groups : list of LMIGroup
        Blocks of LMIs.
    prepare_time : float
        Seconds spent in the presolve and the grouping.
    """

    def __init__(self, problem: BilinearProblem, *, presolve: bool, normalize: bool,
                 reduced: Reduced, groups: list[TermGroup], lmi_groups: list[LMIGroup], prepare_time: float,
                 equalities: str = "exact"):
        self.problem = problem
        self.equalities = equalities
        self.presolve = bool(presolve)
        self.normalize = bool(normalize)
        self.reduced = reduced
        self.groups = groups
        self.lmi_groups = lmi_groups
        self.prepare_time = prepare_time
        self._cvxpy: dict[Any, Any] = {}

    def cvxpy_backend(self, solver_options: Mapping | None = None):
        """The cvxpy back end of this problem, built (and compiled by cvxpy) once per solver options.

        Unhashable solver options give a new back end every call (no reuse).
        """
        from symid.engine.scr.backend_cvxpy import CvxpyBackend

        try:
            key = tuple(sorted((solver_options or {}).items()))
            hash(key)
        except TypeError:
            return CvxpyBackend(self.reduced, self.groups, self.lmi_groups, solver_options=solver_options)
        if key not in self._cvxpy:
            self._cvxpy[key] = CvxpyBackend(self.reduced, self.groups, self.lmi_groups,
                                            solver_options=solver_options)
        return self._cvxpy[key]

    def __repr__(self) -> str:
        return (f"CompiledProblem({self.problem.layout.n} variables, {len(self.groups)} blocks, "
                f"presolve={self.presolve}, normalize={self.normalize})")


def compile(problem: BilinearProblem, *, presolve: bool = True, normalize: bool = True,
            equalities: str = "exact") -> CompiledProblem:
    """Presolve and group a bilinear problem once, for many :func:`symid.engine.scr.solve` calls.

    Parameters
    ----------
    problem : BilinearProblem
    presolve, normalize : bool, optional
        As in :func:`symid.engine.scr.solve` (both default ``True``).
    equalities : {"exact", "least_squares"}, optional
        Linear equalities (given, or split off the bilinear terms by the presolve) that
        do not hold exactly: ``"exact"`` (default) makes the problem inconsistent (a
        solve returns status ``"infeasible"``); ``"least_squares"`` keeps their
        least-squares solution set, as measured data need (the relative residual is in
        ``reduced.info["equality_residual"]``; :mod:`symid.engine.scr.presolve`).

    Returns
    -------
    CompiledProblem
        Pass it to :func:`symid.engine.scr.solve` in place of ``problem``; every solve then
        reuses the presolve, the blocks and (cvxpy back end) the compiled SDP, with the
        same iterates as a solve of ``problem`` itself.

    Examples
    --------
    >>> import sympy as sp
    >>> from symid import scr
    >>> x, y, a = sp.symbols("x y a")
    >>> prob = scr.BilinearProblem(
    ...     variables=[x, y, a],
    ...     bilinear=[scr.Bilinear(A=[[x]], P=[[1]], B=[[x]], C=[[y - a]], weight=0.1)],
    ...     objective=100 * a**2 + (1 - x)**2)
    >>> compiled = scr.compile(prob)
    >>> s1 = scr.solve(compiled, x0={x: -1.9, y: 2}, backend="cvxpy", max_iter=2)
    >>> s2 = scr.solve(compiled, x0={x: -1.9, y: 2}, backend="cvxpy", max_iter=2)
    >>> s1.x == s2.x, s2.info["compilations"]
    (True, 0)
    """
    if not isinstance(problem, BilinearProblem):
        raise ModelError(f"compile() needs a BilinearProblem, got {type(problem).__name__}")
    if equalities not in ("exact", "least_squares"):
        raise ModelError(f"equalities must be 'exact' or 'least_squares', got {equalities!r}")
    t0 = time.perf_counter()
    red = _presolve(problem, split=bool(presolve), normalize=bool(normalize), equalities=equalities)
    ok = red.inconsistent <= INCONSISTENT_TOL
    groups = group_terms(red.terms) if ok else []
    lmi_groups = group_lmis(red.lmis) if ok else []
    return CompiledProblem(problem, presolve=presolve, normalize=normalize, reduced=red, groups=groups,
                           lmi_groups=lmi_groups, prepare_time=time.perf_counter() - t0, equalities=equalities)
