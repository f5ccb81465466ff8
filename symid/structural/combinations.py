"""Identifiable combinations of non-identifiable parameters and a suggested reparameterisation.

Method
------
A function f(θ) is locally identifiable iff its gradient lies in the row space of the
Jacobian of the exhaustive summary at generic θ (a random rational point; checked
exactly at both points of the local test). Candidates, tried simplest first:

1. **Monomials** ``Π θ_i^{a_i}`` from the scaling symmetries. ∇(θ^a) = θ^a (a_i/θ_i),
   so θ^a is identifiable iff ``a`` is orthogonal to every null vector divided
   elementwise by θ. When that space is the same at both random points (a scaling
   symmetry such as b → λb, c → c/λ), its integer kernel gives the exponents.
2. **Gröbner-basis elements** at θ*: an element ``f(θ) − c`` of the reduced basis of
   summary(θ) = summary(θ*) whose non-constant part ``f`` passes the gradient test at
   the independent points is an identifiable function (e.g. ``θ1 + θ4 − θ5``, a trace).
3. **Summary entries** themselves (always identifiable, they generate the field of
   identifiable functions), as a fall-back.

Candidates are kept greedily while they raise the rank, together with the identifiable
parameters, up to the rank of the Jacobian: the result is a set of algebraically
independent identifiable functions, so every identifiable function is algebraic over
them (a *local* generating set; it need not generate the field of globally identifiable
functions, whose exact computation — as in StructuralIdentifiability.jl — is out of
scope). Each combination is also marked global when f(θ) − f(θ*) lies in the ideal.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import sympy as sp
from sympy import QQ
from sympy.polys.matrices import DomainMatrix

from symid.structural.local import LocalResult

__all__ = ["Combination", "monomial_candidates", "parameters_to_fix", "poly_gradients", "select_combinations"]


@dataclass(frozen=True)
class Combination:
    """An identifiable function of the parameters.

    Attributes
    ----------
    expression : sympy.Expr
    source : str
        ``"scaling"``, ``"groebner"`` or ``"summary"``.
    is_global : bool or None
        f(θ) − f(θ*) lies in the ideal of summary(θ) = summary(θ*) (None: not checked).
    """

    expression: sp.Expr
    source: str
    is_global: bool | None = None

    def __str__(self) -> str:
        return sp.sstr(self.expression)


def _gradient(expr: sp.Expr, params: Sequence[sp.Symbol], point: Sequence) -> list | None:
    subs = {p: QQ.to_sympy(v) for p, v in zip(params, point, strict=True)}
    out = []
    for p in params:
        val = sp.diff(expr, p).xreplace(subs)
        if not val.is_Rational:
            val = sp.nsimplify(sp.simplify(val))
            if not val.is_Rational:
                return None
        out.append(QQ.from_sympy(val))
    return out


def _rank(rows: list[list]) -> int:
    if not rows:
        return 0
    return DomainMatrix(rows, (len(rows), len(rows[0])), QQ).rank()


def monomial_candidates(local: LocalResult) -> list[sp.Expr]:
    """Identifiable monomials of the non-identifiable parameters from scaling symmetries."""
    params = local.parameters
    nonid = [k for k, ok in enumerate(local.identifiable) if not ok]
    if not nonid or not local.nullspace:
        return []
    spans = []
    for pt, ns in zip(local.points, local.nullspaces, strict=True):
        if len(ns) != len(local.nullspace):
            return []
        W = [[vec[k] / pt[k] for k in nonid] for vec in ns]
        spans.append(DomainMatrix(W, (len(W), len(nonid)), QQ).rref()[0])
    if any(s != spans[0] for s in spans[1:]):
        return []
    kernel = spans[0].nullspace().to_list()
    out = []
    for vec in kernel:
        rats = [QQ.to_sympy(v) for v in vec]
        den = sp.ilcm(*[r.q for r in rats])
        ints = [int(r * den) for r in rats]
        g = sp.igcd(*[abs(i) for i in ints if i]) or 1
        ints = [i // g for i in ints]
        if sum(1 for i in ints if i) < 2:
            continue
        if next(i for i in ints if i) < 0:
            ints = [-i for i in ints]
        expr = sp.Mul(*[params[k] ** e for k, e in zip(nonid, ints, strict=True)])
        out.append(expr)
    return out


def select_combinations(local: LocalResult, candidates: Sequence[tuple[sp.Expr, str, bool | None]]
                        ) -> list[Combination]:
    """Choose identifiable candidates that, with the identifiable parameters, reach the Jacobian rank.

    Parameters
    ----------
    local : LocalResult
    candidates : sequence of (expression, source, is_global) or (expression, source, is_global, gradients)
        Tried in order. ``gradients``: the exact gradient at each point of ``local``
        (skips differentiating the expression, e.g. :func:`poly_gradients` for a summary
        entry).
    """
    params = local.parameters
    nonid = {p for p, ok in zip(params, local.identifiable, strict=True) if not ok}
    if not nonid:
        return []
    best = local.best
    basis = [[QQ(int(i == k)) for i in range(len(params))] for k, ok in enumerate(local.identifiable) if ok]
    rank = len(basis)
    chosen: list[Combination] = []
    seen = set()
    for expr, source, is_global, *given in candidates:
        if rank >= local.rank:
            break
        if not given:
            expr = sp.factor_terms(expr)
        if expr in seen or not (expr.free_symbols & nonid):
            continue
        seen.add(expr)
        grads = given[0] if given else [_gradient(expr, params, pt) for pt in local.points]
        if any(g is None for g in grads):
            continue
        if not all(local.in_rowspace(g, which=i) for i, g in enumerate(grads)):
            continue
        new_rank = _rank([*basis, grads[best]])
        if new_rank > rank:
            basis.append(grads[best])
            rank = new_rank
            chosen.append(Combination(expr, source, is_global))
    return chosen


def poly_gradients(num, den, points: Sequence[Sequence]) -> list[list]:
    """Exact gradients of ``num/den`` (sympy ``PolyElement`` s over ℚ in θ) at each point (QQ coordinates).

    Examples
    --------
    >>> from sympy import QQ
    >>> from sympy.polys.rings import ring
    >>> from symid.structural.combinations import poly_gradients
    >>> R, a, b = ring("a b", QQ)
    >>> g = poly_gradients(a * b, R.one + b, [[QQ(2), QQ(1)]])  # ∂(ab/(1+b)) = (b/(1+b), a/(1+b)²)
    >>> [[str(v) for v in row] for row in g]
    [['1/2', '1/2']]
    """
    out = []
    gens = num.ring.gens
    dnum = [num.diff(g) for g in gens]
    dden = [den.diff(g) for g in gens]
    for pt in points:
        n, d = num(*pt), den(*pt)
        out.append([(dn(*pt) * d - n * dd(*pt)) / (d * d) for dn, dd in zip(dnum, dden, strict=True)])
    return out


def parameters_to_fix(local: LocalResult) -> tuple[sp.Symbol, ...]:
    """A smallest set of parameters whose values, once known, make the rest locally identifiable.

    Chosen among the non-identifiable parameters, the last ones in θ order first.
    """
    ns = local.nullspace
    if not ns:
        return ()
    params = local.parameters
    chosen: list[int] = []
    rank = 0
    for k in reversed(range(len(params))):
        if local.identifiable[k]:
            continue
        cols = [*chosen, k]
        r = _rank([[vec[c] for c in cols] for vec in ns])
        if r > rank:
            chosen.append(k)
            rank = r
        if rank == len(ns):
            break
    return tuple(params[k] for k in sorted(chosen))
