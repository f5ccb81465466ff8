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
2. **Linear functions** ``a·θ`` whose gradient ``a`` is orthogonal to the Jacobian's
   null space at generic points (e.g. ``θ1 + θ4 − θ5``, a trace; :func:`linear_space`):
   first a basis of the globally identifiable ones (those single-valued on the global
   step's slice), then the rest.
3. **Summary entries** themselves (always identifiable, they generate the field of
   identifiable functions), the simplest first.

Candidates are kept greedily while they raise the rank, together with the identifiable
parameters, up to the rank of the Jacobian: the result is a set of algebraically
independent identifiable functions, so every identifiable function is algebraic over
them (a *local* generating set; it need not generate the field of globally identifiable
functions, whose exact computation — as in StructuralIdentifiability.jl — is out of
scope). Each monomial and linear combination is also marked global when it is
single-valued on every solution of the global step's generic slice
(:mod:`~symid.structural.slicing`); summary entries are global by definition.
"""

from __future__ import annotations

import math
import random
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import sympy as sp
from sympy import QQ
from sympy.polys.matrices import DomainMatrix

from symid.structural.local import LocalResult, PoleError, jacobian_at, random_point
from symid.structural.modp import rank_mod_p

__all__ = ["Combination", "linear_expression", "linear_space", "monomial_candidates", "parameters_to_fix",
           "poly_gradients", "rref_rows", "select_combinations"]


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


def linear_space(local: LocalResult, model=None, known: Mapping[str, object] | None = None, *,
                 seed: int = 0, max_points: int = 12) -> list[list]:
    """A basis of the locally identifiable linear functions Σ a_i θ_i that involve non-identifiable parameters.

    Σ a_i θ_i is locally identifiable iff ``a`` is orthogonal to the Jacobian's null space
    at generic θ. The identifiable parameters are identifiable functions on their own (and
    their null-vector entries vanish), so only the coordinates of the non-identifiable
    ones are kept: each returned vector (QQ entries, one per parameter, zero on the
    identifiable ones) is a row of the reduced row echelon form of that space. The space
    is the intersection over points: it starts from the points of ``local`` and, given the
    ``model``, more random points are added (the exact Jacobian at each) until one more
    point leaves it unchanged (a spurious direction survives a random point with
    probability zero), at most ``max_points``. Without ``model`` only the points of
    ``local`` are used. The space's dimension while points are added is computed modulo a
    31-bit prime; the space itself exactly, once (none when full rank modulo the prime
    proves it is {0}).

    Examples
    --------
    >>> import symid as si
    >>> from symid.structural.local import local_analysis
    >>> from symid.structural.combinations import linear_space
    >>> a, b, c = si.parameters("a b c")
    >>> model = si.StateSpaceModel(A=[[-a - b]], B=[[c]], C=[[1]])
    >>> [[str(v) for v in row] for row in linear_space(local_analysis(model), model)]
    [['1', '1', '0']]
    """
    params = local.parameters
    nonid = [k for k, ok in enumerate(local.identifiable) if not ok]
    rows = [[vec[k] for k in nonid] for ns in local.nullspaces for vec in ns]
    if not nonid or not rows:
        return []

    def kernel_of(rows_: list) -> DomainMatrix:
        return DomainMatrix(rows_, (len(rows_), len(nonid)), QQ).nullspace()

    def dimension(rows_: list) -> int:
        # the kernel's dimension modulo p decides when to stop adding points (the null vectors' entries run to
        # hundreds of digits: the exact kernel is computed once, at the end, and only when it is not {0}; full
        # rank modulo p proves full rank over ℚ); a prime that divides a denominator: exact
        r = rank_mod_p(rows_)
        return len(nonid) - r if r >= 0 else kernel_of(rows_).shape[0]

    dim = dimension(rows)
    rng = random.Random(20_011 + seed)
    for _ in range(max_points if model is not None else 0):
        if dim == 0:
            break
        try:
            J = jacobian_at(model, random_point(rng, len(params)), known)
        except PoleError:
            continue
        new_rows = [[vec[k] for k in nonid] for vec in J.nullspace().to_list()]
        smaller = dimension(rows + new_rows)
        rows += new_rows
        if smaller == dim:
            break
        dim = smaller
    if dim == 0:
        return []
    kernel = kernel_of(rows)
    if kernel.shape[0] == 0:
        return []
    out = []
    for vec in kernel.rref()[0].to_list():
        full = [QQ(0)] * len(params)
        for k, v in zip(nonid, vec, strict=True):
            full[k] = v
        out.append(full)
    return out


def linear_expression(vec: Sequence, params: Sequence[sp.Symbol]) -> sp.Expr:
    """Σ a_i θ_i scaled to coprime integers with a positive first coefficient.

    Examples
    --------
    >>> import sympy as sp
    >>> from sympy import QQ
    >>> from symid.structural.combinations import linear_expression
    >>> a, b = sp.symbols("a b")
    >>> linear_expression([QQ(-1, 2), QQ(3, 4)], [a, b])
    2*a - 3*b
    """
    rats = [QQ.to_sympy(QQ.convert(v)) for v in vec]
    den = sp.ilcm(*[r.q for r in rats])
    ints = [int(r * den) for r in rats]
    g = math.gcd(*ints) or 1
    sign = 1 if next((i for i in ints if i), 1) > 0 else -1
    return sp.Add(*[sign * (i // g) * q for q, i in zip(params, ints, strict=True)])


def rref_rows(vectors: Sequence[Sequence], n: int) -> list[list]:
    """The non-zero rows of the reduced row echelon form of ``vectors`` (QQ entries, length ``n``)."""
    if not vectors:
        return []
    rref = DomainMatrix([list(map(QQ.convert, v)) for v in vectors], (len(vectors), n), QQ).rref()[0].to_list()
    return [row for row in rref if any(row)]


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
    for pt in points:
        if any(v == 0 for v in pt):  # the one-pass rule below divides by the coordinates
            gens = num.ring.gens
            n, d = num(*pt), den(*pt)
            out.append([(num.diff(g)(*pt) * d - n * den.diff(g)(*pt)) / (d * d) for g in gens])
            continue
        inv = [1 / v for v in pt]
        n, dn = _value_and_gradient(num, pt, inv)
        d, dd = _value_and_gradient(den, pt, inv)
        out.append([(a * d - n * b) / (d * d) for a, b in zip(dn, dd, strict=True)])
    return out


def _value_and_gradient(poly, pt, inv) -> tuple:
    """p(pt) and ∇p(pt) in one pass over the terms (pt without zero coordinates): a term t = c·Π θ^e adds t·e_i/θ_i
    to ∂_i p."""
    n = len(pt)
    powers: dict = {}
    value = QQ(0)
    grad = [QQ(0)] * n
    for mono, c in poly.terms():
        t = c
        for i, e in enumerate(mono):
            if e:
                key = (i, e)
                if key not in powers:
                    powers[key] = pt[i] ** e
                t = t * powers[key]
        value += t
        for i, e in enumerate(mono):
            if e:
                grad[i] += t * e * inv[i]
    return value, grad


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
