"""Global identifiability of a mass-spring-damper chain driven and measured at one end, by continued fractions.

The chains users write most (a chain of masses tied to the ground at one end, a shear
building) are driven and measured at an end mass. Their driving-point dynamic stiffness
is a continued fraction whose terms are the chain's elements, which makes them globally
identifiable with no Gröbner basis: the Gröbner step over all 3n parameters of an
8-mass chain takes about 3 s per point, this inversion a few milliseconds.

Structure recognised (:func:`ladder_of`)
----------------------------------------
A second-order model M q'' + V q' + K q = B u, y = C q (or q', q'') with

- M diagonal; V and K the weighted Laplacians of a path through all n masses, plus
  ground elements: off the diagonal, -V[i, j] and -K[i, j] are the damper and spring of
  the element joining masses i and j; on it, what is left after the elements to the
  other masses is the element to the ground;
- B and C^T a nonzero known number times the same unit vector e_a, mass a at an end of
  the path (path order from it: nodes 0, 1, …, n − 1);
- every mass, damper and spring value either 0 (absent; masses never), a known number or
  one free parameter, each free parameter in exactly one place;
- ground elements at node 0 only (the grounded end driven: a chain "11") or at node
  n − 1 only (the free end driven: "nn", a shear building driven at the roof), or none.

Anything else returns None and the usual global step decides (a chain driven and
measured at an interior mass: :mod:`~symid.structural.ladder_interior`).

The inversion (:func:`invert`)
------------------------------
Write D_j(s) for the dynamic stiffness seen at node j of the sub-chain j … n − 1 (the
element joining j − 1 and j left out), e_j(s) = c_j s + k_j for the element joining j and
j + 1 and g_j(s) for node j's ground element. Then (Schur complement)

    D_j = m_j s² + g_j + e_j D_{j+1} / (e_j + D_{j+1}),   D_{n-1} = m_{n-1} s² + g_{n-1},

and the transfer function is H(s) = γ s^r / D_0(s) (γ = b c, r = 0, 1, 2 for a
position, velocity or acceleration sensor). From D_j, known as a rational function in s
whose coefficients lie in the field K(Y) the transfer-function coefficients generate:

1. m_j is the leading coefficient of D_j / s² (the rest is O(s) at s = ∞);
2. with R = D_j − m_j s²: at the last node R = g_{n-1}, a polynomial read off. At node 0
   with a ground element, the sub-chain beyond is free, and its driving-point stiffness
   D_1 is O(s²) at s = 0 as a rational function over ℚ(θ) (from the far end: D_{n-1} =
   m s²; e D′/(e + D′) is O(s²) when D′ is, since e + D′ → k ≠ 0, or with no spring
   e = c s and c D′/(c + D′/s) with c + D′/s → c ≠ 0), so the series term e_0 D_1/(e_0 + D_1)
   is O(s²) too and g₀ = R(0) + R'(0) s (before: a check that det(K_sub + k₀ E₁₁) ≠ 0 at
   θ*, which a missing spring anywhere in the sub-chain fails although the term is O(s²));
3. then R (less g₀) = e_j D_{j+1} / (e_j + D_{j+1}), so 1/R = 1/e_j + 1/D_{j+1} with
   1/D_{j+1} = O(s⁻²): the coefficient of s⁻¹ of 1/R at ∞ is 1/c_j (its constant is 1/k_j
   for a spring alone). The pole −k_j/c_j of 1/e_j is a simple pole of 1/R with residue
   1/c_j; it is the only such pole when gcd(Q, c_j P − Q') has degree 1 (1/R = P/Q), and
   then its root gives k_j;
4. D_{j+1} = 1 / (1/R − 1/e_j), and on to node j + 1.

Each step is a rational operation on coefficients in K(Y), so every element value lies
in K(Y): every parameter is a rational function of the input-output map, i.e. globally
identifiable, and the map θ ↦ H is generically one-to-one (one complex solution of
summary(θ) = summary(θ*) for generic θ*). The steps hold as identities over ℚ(θ) when the
conditions checked at θ* hold there (a polynomial in θ that is nonzero at θ* is nonzero
in ℚ(θ); a reduced rational function of θ* having the largest degrees the structure
allows has them generically, so no factor cancels and no pole of 1/e_j is a pole of
1/D_{j+1}; the gcd of step 3 has degree at most its degree at θ* once the leading
coefficients do not vanish there):

- every D_j at θ* has numerator degree 2(n − j) − d_j and denominator degree
  2(n − j − 1) − d_j in lowest terms, d_j the number of elements from node j on that have
  no spring and join a sub-chain with no spring to the ground: each cancels a factor s for
  every θ (e = c s and D′(0) = 0 in e D′ / (e + D′)), the largest degrees the structure
  allows (:func:`_degree_drops`);
- at a node with both c_j and k_j, R has numerator degree 2(n − j) − 1 − d_j in lowest
  terms, and the gcd of step 3 has degree 1.

Each recovered value is compared with θ*'s, and γ / D_0 from the recursion with the
model's own transfer function, exactly, at 4n + 1 frequencies (more than two different
rational functions of these degrees can share): a structure misread returns False,
never a wrong verdict. This is the classical synthesis of a driving-point function as a
ladder (Cauer's continued fraction; for an undamped string of beads, Krein's inverse
problem: Gladwell, *Inverse Problems in Vibration*, 2nd ed., Kluwer 2004, ch. 4).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from itertools import pairwise

import sympy as sp

from symid.errors import ModelError, OptionError
from symid.structural.summary import analysed_output, free_parameters, model_kind, model_matrices

__all__ = ["ChainParts", "Ladder", "chain_parts", "impedance", "invert", "ladder_of", "peel", "proves_global", "series",
           "values_at"]

_S = sp.Symbol("s")
_SHIFT = {"position": 0, "velocity": 1, "acceleration": 2}


@dataclass(frozen=True)
class Ladder:
    """A chain recognised by :func:`ladder_of`: its elements in path order from the driven mass.

    Every value is 0, a known ``sympy.Rational`` or a free parameter (``sympy.Symbol``).

    Attributes
    ----------
    order : tuple of int
        The model's mass indices from the driven end.
    masses : tuple of sympy.Expr
        m_j of node j.
    edges : tuple of (sympy.Expr, sympy.Expr)
        (damper, spring) joining nodes j and j + 1 (n − 1 of them).
    grounds : tuple of (sympy.Expr, sympy.Expr)
        (damper, spring) from node j to the ground.
    shift : int
        0, 1 or 2: the sensor measures position, velocity or acceleration.
    gain : sympy.Rational
        b c, the product of the input and sensor gains.
    at : int
        Position of the driven mass in ``order``: 0 (an end) unless ``ladder_of`` was asked
        for chains driven anywhere; then the path runs from its grounded end (if any).
    """

    order: tuple
    masses: tuple
    edges: tuple
    grounds: tuple
    shift: int
    gain: sp.Rational
    at: int = 0


def _slot(expr: sp.Expr, params: set) -> sp.Expr | None:
    """The value of one element: 0, a known number or a free parameter; None for anything else."""
    expr = sp.expand(expr)
    if expr == 0 or (expr.is_Rational and expr != 0) or expr in params:
        return expr
    return None


def _unit(vec: sp.Matrix) -> tuple[int, sp.Rational] | None:
    nz = [(i, v) for i, v in enumerate(vec) if v != 0]
    if len(nz) != 1 or not nz[0][1].is_Rational:
        return None
    return nz[0]


@dataclass(frozen=True)
class ChainParts:
    """A second-order model read as masses joined by elements (:func:`chain_parts`).

    Attributes
    ----------
    n : int
        Number of masses.
    params : set of sympy.Symbol
        The free parameters.
    masses : list of sympy.Expr
        Mass of each model coordinate (never 0).
    edge : dict
        ``edge[i, j]`` (both orders) = (damper, spring) of the element joining masses i and j.
    ground : list of (sympy.Expr, sympy.Expr)
        (damper, spring) from each mass to the ground.
    shift : int
        0, 1 or 2: position, velocity or acceleration output.
    b, c : (int, sympy.Rational)
        The mass B and C^T act on and their nonzero known value.
    """

    n: int
    params: set
    masses: list
    edge: dict
    ground: list
    shift: int
    b: tuple
    c: tuple


def chain_parts(model, known: Mapping[str, object] | None = None) -> ChainParts | None:
    """``model`` as masses, elements and ground elements with a single input and a single sensor, each acting on
    one mass (M diagonal, V and K weighted Laplacians plus ground elements, every value 0, known or one free
    parameter; module notes), or None."""
    try:
        if model_kind(model) != "second-order":
            return None
    except ModelError:  # not a model this module handles: the usual step reports it
        return None
    shift = _SHIFT.get(analysed_output(model))
    if shift is None:
        return None
    mats = model_matrices(model, known)
    M, V, K, B, C = (mats[k] for k in "MVKBC")
    n = M.shape[0]
    if B.shape != (n, 1) or C.shape != (1, n):
        return None
    params = set(free_parameters(model, known))
    b, c = _unit(B), _unit(C)
    if b is None or c is None:
        return None
    if any(M[i, j] != 0 for i in range(n) for j in range(n) if i != j):
        return None
    masses = [_slot(M[i, i], params) for i in range(n)]
    if any(v is None or v == 0 for v in masses):
        return None
    edge = {}
    for i in range(n):
        for j in range(i + 1, n):
            for X in (V, K):
                if sp.expand(X[i, j] - X[j, i]) != 0:
                    return None
            if V[i, j] != 0 or K[i, j] != 0:
                pair = (_slot(-V[i, j], params), _slot(-K[i, j], params))
                if pair[0] is None or pair[1] is None:
                    return None
                edge[i, j] = edge[j, i] = pair
    ground = []
    for i in range(n):
        pair = (_slot(V[i, i] + sum(V[i, j] for j in range(n) if j != i), params),
                _slot(K[i, i] + sum(K[i, j] for j in range(n) if j != i), params))
        if pair[0] is None or pair[1] is None:
            return None
        ground.append(pair)
    return ChainParts(n, params, masses, edge, ground, shift, b, c)


def ladder_of(model, known: Mapping[str, object] | None = None, *, driven_anywhere: bool = False) -> Ladder | None:
    """The chain structure of ``model`` (see the module notes), or None when it is not one.

    ``driven_anywhere=True`` also recognises a chain driven and measured at an interior
    mass (for :mod:`symid.fit.frf.chain` and :mod:`symid.structural.ladder_interior`; the
    inversion of this module needs an end):
    ``order`` then runs from the end that has the ground element (ground elements at one
    end only, never at the driven mass) and ``at`` says where the driven mass is.

    Examples
    --------
    >>> import sympy as sp
    >>> import symid as si
    >>> from symid.structural.ladder import ladder_of
    >>> m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    >>> chain = si.SecondOrderModel(M=sp.diag(m1, m2), V=[[c1 + c2, -c2], [-c2, c2]],
    ...                             K=[[k1 + k2, -k2], [-k2, k2]], B=[[0], [1]], C=[[0, 1]])
    >>> lad = ladder_of(chain)
    >>> lad.order, lad.masses, lad.edges, lad.grounds
    ((1, 0), (m2, m1), ((c2, k2),), ((0, 0), (c1, k1)))
    """
    parts = chain_parts(model, known)
    if parts is None or parts.b[0] != parts.c[0]:
        return None
    n, params, masses, edge, ground, shift = parts.n, parts.params, parts.masses, parts.edge, parts.ground, parts.shift
    b, c = parts.b, parts.c
    # the path from the driven mass
    start = b[0]
    around = [j for j in range(n) if (start, j) in edge]
    if driven_anywhere and len(around) == 2:
        return _interior(start, around, edge, ground, masses, params, shift, b[1] * c[1])
    order, prev = [start], None
    while True:
        nxt = [j for j in range(n) if (order[-1], j) in edge and j != prev]
        if len(nxt) > 1:
            return None
        if not nxt:
            break
        prev = order[-1]
        if nxt[0] in order:
            return None
        order.append(nxt[0])
    if len(order) != n or sum(1 for j in range(n) if (start, j) in edge) > 1:
        return None
    grounded = [j for j, i in enumerate(order) if ground[i] != (0, 0)]
    if grounded and grounded not in ([0], [n - 1]):
        return None
    slots = [*masses, *(v for i, j in pairwise(order) for v in edge[i, j]),
             *(v for g in ground for v in g)]
    used = [v for v in slots if v in params]
    if len(used) != len(set(used)) or set(used) != params:
        return None
    return Ladder(tuple(order), tuple(masses[i] for i in order),
                  tuple(edge[i, j] for i, j in pairwise(order)),
                  tuple(ground[i] for i in order), shift, b[1] * c[1])


def _interior(start: int, around: list[int], edge: dict, ground: list, masses: list, params: set, shift: int,
              gain: sp.Rational) -> Ladder | None:
    """A chain driven at an interior mass (``ladder_of(..., driven_anywhere=True)``), or None."""
    sides = []
    for first in around:
        path, prev = [first], start
        while True:
            nxt = [j for j in range(len(masses)) if (path[-1], j) in edge and j != prev]
            if len(nxt) > 1:
                return None
            if not nxt:
                break
            prev = path[-1]
            if nxt[0] in path or nxt[0] == start:
                return None
            path.append(nxt[0])
        sides.append(path)
    if ground[sides[1][-1]] != (0, 0):  # the grounded end first
        sides.reverse()
    order = [*reversed(sides[0]), start, *sides[1]]
    n = len(masses)
    if len(order) != n:
        return None
    grounded = [j for j, i in enumerate(order) if ground[i] != (0, 0)]
    if grounded and grounded != [0]:
        return None
    slots = [*masses, *(v for i, j in pairwise(order) for v in edge[i, j]), *(v for g in ground for v in g)]
    used = [v for v in slots if v in params]
    if len(used) != len(set(used)) or set(used) != params:
        return None
    return Ladder(tuple(order), tuple(masses[i] for i in order), tuple(edge[i, j] for i, j in pairwise(order)),
                  tuple(ground[i] for i in order), shift, gain, at=len(sides[0]))


class _RF:
    """A rational function of s over ℚ in lowest terms, monic denominator."""

    def __init__(self, num: sp.Poly, den: sp.Poly):
        if den.is_zero:
            raise ZeroDivisionError("zero denominator")
        g = num.gcd(den)
        num, den = num.quo(g), den.quo(g)
        lc = den.LC()
        self.num, self.den = num.quo_ground(lc), den.quo_ground(lc)

    @classmethod
    def poly(cls, p: sp.Poly) -> _RF:
        return cls(p, sp.Poly(1, _S, domain="QQ"))

    def __add__(self, o: _RF) -> _RF:
        return _RF(self.num * o.den + o.num * self.den, self.den * o.den)

    def __sub__(self, o: _RF) -> _RF:
        return _RF(self.num * o.den - o.num * self.den, self.den * o.den)

    def inv(self) -> _RF:
        return _RF(self.den, self.num)

    def at(self, x: sp.Rational) -> sp.Rational:
        return self.num.eval(x) / self.den.eval(x)


def _lin(c: sp.Rational, k: sp.Rational) -> sp.Poly:
    return sp.Poly(c * _S + k, _S, domain="QQ")


def _value(v: sp.Expr, subs: Mapping) -> sp.Rational:
    return sp.Rational(subs.get(v, v))


def values_at(ladder: Ladder, model, known: Mapping[str, object] | None, star: Sequence[object]
              ) -> tuple[dict, list, list, list]:
    """The chain's values at θ* = ``star``: (θ* by symbol, masses, edges, grounds) in ``ladder``'s node order, and
    an :class:`~symid.errors.OptionError` when ``star`` has not one value per free parameter."""
    params = free_parameters(model, known)
    if len(star) != len(params):
        raise OptionError(f"star has {len(star)} values for {len(params)} free parameters")
    subs = {p: sp.Rational(v) for p, v in zip(params, star, strict=True)}
    return (subs, [_value(v, subs) for v in ladder.masses],
            [tuple(_value(v, subs) for v in pair) for pair in ladder.edges],
            [tuple(_value(v, subs) for v in pair) for pair in ladder.grounds])


def invert(ladder: Ladder, model, known: Mapping[str, object] | None, star: Sequence[object]) -> bool:
    """Whether the continued-fraction inversion recovers every element at θ* = ``star`` (module notes).

    True proves every free parameter globally identifiable (a rational function of the
    transfer function) and the generic solution count 1; False proves nothing (the
    usual global step decides).

    Examples
    --------
    >>> import sympy as sp
    >>> import symid as si
    >>> from symid.structural.ladder import invert, ladder_of
    >>> m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    >>> chain = si.SecondOrderModel(M=sp.diag(m1, m2), V=[[c1 + c2, -c2], [-c2, c2]],
    ...                             K=[[k1 + k2, -k2], [-k2, k2]], B=[[1], [0]], C=[[1, 0]])
    >>> invert(ladder_of(chain), chain, None, [3, 5, sp.Rational(1, 2), 7, 11, 2])
    True
    """
    subs, m, e, g = values_at(ladder, model, known, star)
    slots = [*m, *(x for pair in e for x in pair), *(x for pair in g for x in pair)]
    present = [*ladder.masses, *(x for pair in ladder.edges for x in pair),
               *(x for pair in ladder.grounds for x in pair)]
    if any(x == 0 and p != 0 for x, p in zip(slots, present, strict=True)):
        return False  # an element of the structure is 0 at θ*: not a generic point
    # D_0 at θ* by the recursion, checked against the model's own transfer function
    if any(c == 0 and k == 0 for c, k in e):
        return False
    D = impedance(m, e, g)
    if not _matches_model(D, ladder, model, known, subs):
        return False
    return peel(D, ladder, m, e, g, subs)


def impedance(m: list, e: list, g: list) -> _RF:
    """D_0 of an end-driven chain at θ*, exactly: node values ``m`` and ``g`` (damper, spring to the ground) and
    edges ``e`` (damper, spring; none both zero), from node 0 (module notes)."""
    D = _RF.poly(sp.Poly(m[-1] * _S**2, _S, domain="QQ") + _lin(*g[-1]))
    for j in range(len(m) - 2, -1, -1):
        D = _RF.poly(sp.Poly(m[j] * _S**2, _S, domain="QQ") + _lin(*g[j])) + series(e[j], D)
    return D


def series(edge: tuple, D: _RF) -> _RF:
    """The impedance D seen through the element ``edge`` = (damper, spring): e D / (e + D)."""
    return (_RF.poly(_lin(*edge)).inv() + D.inv()).inv()


def peel(D: _RF, ladder: Ladder, m: list, e: list, g: list, subs: Mapping) -> bool:
    """Steps 1–4 of the module notes from node 0 of ``ladder``, D = D_0 exact: whether each recovered value is
    θ*'s (``m``, ``e``, ``g``: the masses, edges and grounds at θ*) and every step's uniqueness condition holds."""
    n = len(ladder.masses)
    drops = _degree_drops(ladder)
    for j in range(n):
        L = n - j
        if D.num.degree() != 2 * L - drops[j] or D.den.degree() != 2 * L - 2 - drops[j]:
            return False
        mj = D.num.LC() / D.den.LC()
        if mj != m[j]:
            return False
        R = D - _RF.poly(sp.Poly(mj * _S**2, _S, domain="QQ"))
        if j == n - 1:
            if R.den.degree() != 0 or R.num.degree() > 1:
                return False
            return (R.num.coeff_monomial(_S), R.num.coeff_monomial(1)) == g[j]
        if ladder.grounds[j] != (0, 0):  # node 0 with a ground element: the free sub-chain's series term is O(s²)
            if j != 0:
                return False
            if R.den.eval(0) == 0:
                return False
            k0 = R.at(0)
            c0 = (R.num.diff(_S).eval(0) * R.den.eval(0) - R.num.eval(0) * R.den.diff(_S).eval(0)) / R.den.eval(0) ** 2
            if (c0, k0) != g[j]:
                return False
            R = R - _RF.poly(_lin(c0, k0))
        cj, kj = e[j]
        P, Q = R.den, R.num  # 1/R = P / Q
        if Q.is_zero:
            return False
        if ladder.edges[j][0] != 0:
            if Q.degree() != P.degree() + 1:
                return False
            c_hat = Q.LC() / P.LC()
            k_hat = sp.Rational(0)
            if ladder.edges[j][1] != 0:
                if Q.degree() != 2 * L - 1 - drops[j]:
                    return False
                G = Q.gcd(P.mul_ground(c_hat) - Q.diff(_S))
                if G.degree() != 1:
                    return False
                k_hat = c_hat * G.coeff_monomial(1) / G.LC()
        else:
            if Q.degree() != P.degree():
                return False
            c_hat, k_hat = sp.Rational(0), Q.LC() / P.LC()
        if (c_hat, k_hat) != (cj, kj):
            return False
        rest = R.inv() - _RF.poly(_lin(c_hat, k_hat)).inv()
        if rest.num.is_zero:
            return False
        D = rest.inv()
    return False  # pragma: no cover - the loop returns at the last node


def _degree_drops(ladder: Ladder) -> list[int]:
    """Per node j: how far below 2L and 2L − 2 (L masses from j on) the degrees of D_j's numerator and
    denominator lie for every θ. An element without a spring (e = c s) joining a sub-chain with no spring to
    the ground (free, or grounded by a damper alone: its D′ vanishes at s = 0) cancels a factor s from
    e D′ / (e + D′), one degree less for it and every node before it; any other element keeps the degrees."""
    n = len(ladder.masses)
    drops = [0] * (n + 1)
    for j in range(n - 2, -1, -1):
        free_beyond = all(g[1] == 0 for g in ladder.grounds[j + 1:])  # no ground spring: D′(0) = 0
        damper_only = ladder.edges[j][0] != 0 and ladder.edges[j][1] == 0
        drops[j] = drops[j + 1] + int(damper_only and free_beyond)
    return drops[:n]


def _solve(A: list[list[Fraction]], b: list[Fraction]) -> list[Fraction] | None:
    """A x = b exactly (Gaussian elimination on fractions), or None when A is singular."""
    n = len(b)
    M = [[*row, rhs] for row, rhs in zip(A, b, strict=True)]
    for c in range(n):
        piv = next((r for r in range(c, n) if M[r][c] != 0), None)
        if piv is None:
            return None
        M[c], M[piv] = M[piv], M[c]
        for r in range(c + 1, n):
            f = M[r][c] / M[c][c]
            if f:
                M[r] = [x - f * y for x, y in zip(M[r], M[c], strict=True)]
    x = [Fraction(0)] * n
    for r in range(n - 1, -1, -1):
        x[r] = (M[r][n] - sum(M[r][j] * x[j] for j in range(r + 1, n))) / M[r][r]
    return x


def _matches_model(D: _RF, ladder: Ladder, model, known, subs: Mapping) -> bool:
    """γ / D_0(s) equals the model's C (M s² + V s + K)⁻¹ B as rational functions of s.

    Both sides have numerators and denominators of degree at most 2n, so their difference,
    cross-multiplied, has degree at most 4n: equal values at 4n + 1 frequencies prove them
    equal (exact arithmetic).
    """
    mats = model_matrices(model, known)
    M, V, K, B, C = ([[Fraction(int(x.p), int(x.q)) for x in row] for row in mats[k].xreplace(subs).tolist()]
                     for k in "MVKBC")
    n = len(M)
    gain = Fraction(int(ladder.gain.p), int(ladder.gain.q))
    dnum = [Fraction(int(x.p), int(x.q)) for x in D.num.all_coeffs()]
    dden = [Fraction(int(x.p), int(x.q)) for x in D.den.all_coeffs()]

    def horner(coeffs: list[Fraction], x: Fraction) -> Fraction:
        out = Fraction(0)
        for a in coeffs:
            out = out * x + a
        return out

    for i in range(4 * n + 1):
        s0 = Fraction(2 * i + 3, 7)  # distinct frequencies (positive: poles of passive chains lie left of 0)
        Z = [[M[r][c] * s0 * s0 + V[r][c] * s0 + K[r][c] for c in range(n)] for r in range(n)]
        x = _solve(Z, [row[0] for row in B])
        num, den = horner(dnum, s0), horner(dden, s0)
        if x is None or num == 0:
            return False  # a pole of either side here: no conclusion, so no claim
        if sum(C[0][j] * x[j] for j in range(n)) != gain * den / num:
            return False
    return True


def proves_global(model, known: Mapping[str, object] | None, star: Sequence[object]) -> str:
    """Whether ``model`` is a chain whose inversion succeeds at θ* = ``star``: ``"end"`` (driven and measured at an
    end mass, :func:`invert`), ``"interior"`` (at an interior mass,
    :func:`~symid.structural.ladder_interior.invert_interior`), ``"adjacent"`` (driven next to the free end and
    measured there, or the reverse, :func:`~symid.structural.ladder_adjacent.invert_adjacent`), or ``""`` (no
    proof).

    Non-empty: every free parameter is globally identifiable and summary(θ) = summary(θ*)
    has one complex solution for generic θ* (module notes).
    """
    ladder = ladder_of(model, known)
    if ladder is not None:
        return "end" if invert(ladder, model, known, star) else ""
    inner = ladder_of(model, known, driven_anywhere=True)
    if inner is None or not 0 < inner.at < len(inner.masses) - 1:
        from symid.structural.ladder_adjacent import adjacent_of, invert_adjacent  # they build on this module

        near = adjacent_of(model, known)
        return "adjacent" if near is not None and invert_adjacent(near, model, known, star) else ""
    from symid.structural.ladder_interior import invert_interior  # it builds on this module

    return "interior" if invert_interior(inner, model, known, star) else ""
