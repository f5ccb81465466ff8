"""Global identifiability of a mass chain driven next to its free end and measured at that end.

A sensor on the last mass of a chain and the force on the mass before it (or the
reverse: M, V and K are symmetric, so the response is the same) is a placement the
continued fractions of :mod:`~symid.structural.ladder` do not reach: the transfer
function is not a driving-point function. This module decides it by listing every way a
solution could explain the response, in the spirit of
:mod:`~symid.structural.ladder_interior`; each way but θ*'s fails a necessary condition.

Structure recognised (:func:`adjacent_of`)
------------------------------------------
A chain in the sense of :func:`~symid.structural.ladder.ladder_of` (M diagonal, V and K
weighted Laplacians of a path through all n ≥ 3 masses, every value 0, known or one free
parameter) with

- the ground element at one end only (node 0), with a damper and a spring, or none (a free
  chain);
- every element joining two masses with a damper and a spring;
- B and C^T nonzero known numbers times unit vectors of the two masses at the other
  end (nodes n − 2 and n − 1, either way round), any sensor derivative.

Anything else returns None and the usual global step decides.

The identities (a study of issue 17; ``benchmarks/research/noncollocated_chains.md``)
---------------------------------------------------------------------------------------
Write e = c (s + z₀) for the element joining the last two masses, m = m_{n−1} for the
last mass, X for the dynamic stiffness at node n − 2 of the chain of nodes 0 … n − 2
(grounded at node 0 or free; e left out), and P / N for the transfer function with the sensor's s^r and
the gains divided out (P = det(M s² + V s + K), N = e · l, l the determinant of nodes
0 … n − 3 with the element to node n − 2 grounding the last of them). Then

    H := P / N = X + Y + X Y / e,   Y = m s²,   so   (X + e)(Y + e) = e (e + H).

At the two zeros σ₁, σ₂ of V := Y + e = m s² + c s + c z₀ the right side vanishes, so
c = Ω(σ₁) = Ω(σ₂) with Ω(s) = −H(s) / (s + z₀); and 1/σ₁ + 1/σ₂ = −1/z₀, i.e.
σ₂ = φ(σ₁) with the involution φ(σ) = −z₀ σ / (σ + z₀). So every solution θ gives

1. −z₀ a root of N (N = e l);
2. σ₁ a root of E_{z₀}(σ) = (σ + z₀)^d [Ω(σ) − Ω(φ(σ))] (cleared of denominators, of
   degree at most 4n − 4, less the fixed points 0 and −2 z₀ of φ), or σ₁ = −2 z₀ (a
   double zero of V);
3. c = Ω(σ₁) and m = H(σ₁) / σ₁²; then V divides Q = P + e N = (X + e) l V, and
   X = c Q / (V N) · (s + z₀) − e;
4. X the driving-point stiffness at an end of a chain of n − 1 masses, grounded at the
   other end or free (then every remainder vanishes to second order at s = 0, checked):
   it peels as a continued fraction (:func:`_peel`, steps as in
   :mod:`~symid.structural.ladder`), uniquely when it does.

Degenerate choices are impossible on a solution: σ₁ = 0 and σ₁ = −z₀ are no zeros of V
(V(0) = c z₀, V(−z₀) = m z₀²), σ₁ a pole of Ω would make P and N share a root (they are
coprime, checked exactly at θ*), and σ₁ a zero of P gives c = 0. Every solution is one of
at most deg N · (4n − 3) cases, each giving at most one θ; θ* is the only one when one
case passes and gives θ*'s values. A free chain of 3 masses has 3 solutions (the case
analysis finds them, as the Gröbner step counts); from 4 masses on, free chains are
global. Known values: the case analysis finds every solution of the whole structure (every
element free), and the model's solutions are those among them with its known values; so
a free 3-mass chain with a known mass or element is global when only θ* has it (the
usual step decides when a known value is neither clearly met nor clearly missed).

How it is computed
------------------
P and N are built exactly at θ* (a continuant recursion), checked against the model's own
transfer function (:func:`~symid.structural.ladder._matches_model`) and for coprimality.
Every case is then computed in :data:`DPS` digits (gmpy2's MPFR numbers, :class:`_Num`), one
of each complex-conjugate pair (the other gives the conjugate solution, and a solution that
is not real stands for two): the roots of N and of each E (numpy's
roots of the balanced polynomial refined by Newton's method, a cluster numpy does not
resolve found on the deflated quotient), and the peel, where a check passes below
:data:`PASS` and fails above :data:`FAIL`. A check in between, or two roots passing one
peel step, leaves the case undecided; then everything is computed again in twice the
digits (widely spread values lose that many: an 8-mass chain with springs from 0.008 to
545 left checks at 1e-29 … 1e-15 in 80 digits, none in 160), and an undecided case there
means no claim. A double-precision screen of the cases (the study's prototype) was
measured and not kept: it lost θ*'s case on a 4-mass chain with integer values (smallest
residual 0.035) and on 7–8 masses, where the continued fraction is ill-conditioned in the
monomial basis.
This is a floating-point test with wide margins, not an interval proof (as in
:mod:`~symid.structural.pole_split`): on 3–8 masses, five random points each
(``benchmarks/adjacent_margins.py``), θ*'s case reproduces θ* to 8e-51 or better and
every other case fails a check at 5e-7 or above. As for the Gröbner step, the claim is confirmed at a
second random point θ** (:func:`~symid.structural.global_.generic_global`).
Checked against the Gröbner step on random structures: ``benchmarks/ladder_check.py
--adjacent``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from itertools import pairwise

import gmpy2
import mpmath
import numpy as np
import sympy as sp
from mpmath.libmp import NoConvergence

from symid.structural.ladder import _RF, _S, Ladder, _matches_model, chain_parts, values_at

__all__ = ["DPS", "FAIL", "PASS", "adjacent_of", "case_margins", "invert_adjacent"]

DPS = 80
"""Decimal digits of the high-precision steps."""
PASS = 1e-30
"""A step whose residual in :data:`DPS` digits is below this passes."""
FAIL = 1e-10
"""A step whose residual in :data:`DPS` digits is above this fails; in between nothing is decided."""


def adjacent_of(model, known: Mapping[str, object] | None = None) -> Ladder | None:
    """The chain of the module notes, or None.

    Returns a :class:`~symid.structural.ladder.Ladder` whose ``order`` runs from the
    grounded end (node 0) to the free end, the input and the sensor on its last two
    nodes (``at`` = n − 2).

    Examples
    --------
    >>> import sympy as sp
    >>> import symid as si
    >>> from symid.structural.ladder_adjacent import adjacent_of
    >>> m1, m2, m3, c1, c2, c3, k1, k2, k3 = si.parameters("m1 m2 m3 c1 c2 c3 k1 k2 k3", positive=True)
    >>> chain = si.SecondOrderModel(M=sp.diag(m1, m2, m3), V=[[c1 + c2, -c2, 0], [-c2, c2 + c3, -c3], [0, -c3, c3]],
    ...                             K=[[k1 + k2, -k2, 0], [-k2, k2 + k3, -k3], [0, -k3, k3]],
    ...                             B=[[0], [1], [0]], C=[[0, 0, 1]])
    >>> adjacent_of(chain).order
    (0, 1, 2)
    """
    parts = chain_parts(model, known)
    if parts is None or parts.n < 3 or parts.b[0] == parts.c[0]:
        return None
    n, edge, ground = parts.n, parts.edge, parts.ground
    pair = {parts.b[0], parts.c[0]}
    if (parts.b[0], parts.c[0]) not in edge:
        return None
    end = [i for i in pair if sum(1 for j in range(n) if (i, j) in edge) == 1]
    if len(end) != 1:
        return None
    order, prev = [end[0]], None
    while True:
        nxt = [j for j in range(n) if (order[-1], j) in edge and j != prev]
        if len(nxt) > 1 or (nxt and nxt[0] in order):
            return None
        if not nxt:
            break
        prev = order[-1]
        order.append(nxt[0])
    if len(order) != n:
        return None
    order.reverse()  # from the grounded end
    if any(ground[i] != (0, 0) for i in order[1:]) or (0 in ground[order[0]] and ground[order[0]] != (0, 0)):
        return None  # a ground element elsewhere than node 0, or one without a damper or a spring
    edges = [edge[i, j] for i, j in pairwise(order)]
    if any(0 in pair_ for pair_ in edges):
        return None
    slots = [*parts.masses, *(v for pair_ in edges for v in pair_), *(v for g in ground for v in g)]
    used = [v for v in slots if v in parts.params]
    if len(used) != len(set(used)) or set(used) != parts.params:
        return None
    return Ladder(tuple(order), tuple(parts.masses[i] for i in order), tuple(edges),
                  tuple(ground[i] for i in order), parts.shift, parts.b[1] * parts.c[1], at=n - 2)


def invert_adjacent(ladder: Ladder, model, known: Mapping[str, object] | None, star: Sequence[object]) -> bool:
    """Whether the case analysis of the module notes shows θ* = ``star`` to be the only solution.

    ``ladder`` from :func:`adjacent_of`. True proves (up to the floating-point exclusions
    of the module notes) that summary(θ) = summary(θ*) has one complex solution; False
    proves nothing (the usual global step decides).

    Examples
    --------
    >>> import sympy as sp
    >>> import symid as si
    >>> from symid.structural.ladder_adjacent import adjacent_of, invert_adjacent
    >>> m1, m2, m3, c1, c2, c3, k1, k2, k3 = si.parameters("m1 m2 m3 c1 c2 c3 k1 k2 k3", positive=True)
    >>> chain = si.SecondOrderModel(M=sp.diag(m1, m2, m3), V=[[c1 + c2, -c2, 0], [-c2, c2 + c3, -c3], [0, -c3, c3]],
    ...                             K=[[k1 + k2, -k2, 0], [-k2, k2 + k3, -k3], [0, -k3, k3]],
    ...                             B=[[0], [1], [0]], C=[[0, 0, 1]])
    >>> invert_adjacent(adjacent_of(chain), chain, None, [3, 5, 7, sp.Rational(1, 2), 11, 2, 13, 17, 19])
    True
    """
    setup = _setup(ladder, model, known, star)
    if setup is None:
        return False
    P, N, theta, n, free, fixed = setup
    for dps in (DPS, 2 * DPS):  # twice the digits when a check is in the grey zone (rounding on spread values)
        with _Num(dps) as mp:  # a context of its own (thread-local): another thread's precision is not this one's
            try:
                sols, undecided = _solutions(*_exact_mp(P, N, mp), n, mp, free=free)
            except NoConvergence:  # a polynomial whose roots mpmath does not find: no claim
                return False
            if not undecided:
                sols = _with_known(sols, theta, fixed, mp)
                return sols is not None and len(sols) == 1 and _gap(sols[0], theta, mp) < PASS
    return False


def _with_known(sols: list, theta: list, fixed: list, mp: _Num) -> list | None:
    """The solutions whose known values (``fixed[i]``: θ[i] is known) are the model's: a known value is a
    constraint the full structure's solutions need not meet. None when one is neither clearly equal (1e-20) nor
    clearly different (1e-8)."""
    out = []
    for values in sols:
        gaps = [abs(v - _mpq(w, mp)) / abs(_mpq(w, mp)) for v, w, f in zip(values, theta, fixed, strict=True) if f]
        if all(g < 1e-20 for g in gaps):
            out.append(values)
        elif not any(g > 1e-8 for g in gaps):
            return None
    return out


def case_margins(ladder: Ladder, model, known: Mapping[str, object] | None, star: Sequence[object]) -> dict | None:
    """How clearly the case analysis separates θ*'s case from the others, at θ* = ``star``.

    Returns ``{"cases": number of cases that failed a check, "solutions": number passing
    (solutions of the whole structure, one of each complex-conjugate pair), "with_known": of
    them, those with the model's known values, "theta_star": the largest relative
    difference of the one left from θ*,
    "nearest": the smallest residual of a failed check, "undecided": bool, "digits": 80, or
    160 where a check was undecided in 80 as in :func:`invert_adjacent`}``, or None
    outside the structure of the module notes. For the benchmarks: a case passes below
    :data:`PASS` and fails above :data:`FAIL`.
    """
    setup = _setup(ladder, model, known, star)
    if setup is None:
        return None
    P, N, theta, n, free, fixed = setup
    for dps in (DPS, 2 * DPS):  # as invert_adjacent
        with _Num(dps) as mp:
            misses: list = []
            sols, undecided = _solutions(*_exact_mp(P, N, mp), n, mp, misses, free=free)
            mine = _with_known(sols, theta, fixed, mp)
            gap = float(_gap(mine[0], theta, mp)) if mine and len(mine) == 1 else None
        if not undecided:
            break
    return {"cases": len(misses), "solutions": len(sols), "with_known": None if mine is None else len(mine),
            "theta_star": gap, "nearest": float(min(misses)) if misses else None, "undecided": undecided,
            "digits": dps}


def _setup(ladder: Ladder, model, known, star) -> tuple[sp.Poly, sp.Poly, list, int, bool, list] | None:
    """P, N, θ* as [c, k, m] per node from node 0 (no c, k at node 0 of a free chain; checked against the model's
    response), the number of masses, whether the chain is free and which values of θ* are known, or None."""
    subs, m, e, grounds = values_at(ladder, model, known, star)
    g = grounds[0]
    free = ladder.grounds[0] == (0, 0)
    if any(x == 0 for x in (*m, *(x for pair in e for x in pair), *(() if free else g))):
        return None  # an element of the structure is 0 at θ*: not a generic point
    P, N = _polys(m, e, g)
    if P.gcd(N).degree() != 0 or not _matches_model(_RF(P, N), ladder, model, known, subs):
        return None
    theta = [*(() if free else g), m[0], *(x for j in range(1, len(m)) for x in (*e[j - 1], m[j]))]
    slots = [*(() if free else ladder.grounds[0]), ladder.masses[0],
             *(x for j in range(1, len(m)) for x in (*ladder.edges[j - 1], ladder.masses[j]))]
    return P, N, theta, len(m), free, [x not in subs for x in slots]


def _gap(values: list, theta: list, mp: _Num) -> gmpy2.mpfr:
    """The largest relative difference of ``values`` from the exact ``theta``."""
    return max(abs(v - _mpq(w, mp)) / abs(_mpq(w, mp)) for v, w in zip(values, theta, strict=True))


# -- exact polynomials at θ* ----------------------------------------------------------------------------------------

def _lin(c, k) -> sp.Poly:
    return sp.Poly(c * _S + k, _S, domain="QQ")


def _polys(m: list, e: list, g: tuple) -> tuple[sp.Poly, sp.Poly]:
    """P = det(M s² + V s + K) and the cofactor N = e_{n−2} · det(first n − 2 nodes) of the chain at θ*, by the
    continuant recursion from the grounded node 0."""
    n = len(m)
    elems = [_lin(*g), *(_lin(*pair) for pair in e), sp.Poly(0, _S, domain="QQ")]  # elems[j] ties node j to j − 1

    def d(j: int) -> sp.Poly:
        return sp.Poly(m[j] * _S**2, _S, domain="QQ") + elems[j] + elems[j + 1]

    dets = [sp.Poly(1, _S, domain="QQ"), d(0)]
    for j in range(1, n):
        dets.append(d(j) * dets[j] - elems[j] ** 2 * dets[j - 1])
    return dets[n], elems[n - 1] * dets[n - 2]


def _exact_mp(P: sp.Poly, N: sp.Poly, mp: _Num) -> tuple[list, list]:
    """P and N divided by P's leading coefficient, in the working precision."""
    lc = _mpq(P.LC(), mp)
    return [_mpq(x, mp) / lc for x in P.all_coeffs()], [_mpq(x, mp) / lc for x in N.all_coeffs()]


def _mpq(x: sp.Rational, mp: _Num) -> gmpy2.mpfr:
    x = sp.Rational(x)
    return mp.mpf(int(x.p)) / int(x.q)


# -- small polynomial helpers (coefficient lists, highest degree first) -------------------------------------------

def _add(p: list, q: list) -> list:
    size = max(len(p), len(q))
    return [x + y for x, y in zip([0] * (size - len(p)) + list(p), [0] * (size - len(q)) + list(q), strict=True)]


def _scale(p: list, a) -> list:
    return [a * x for x in p]


def _mul(p: list, q: list) -> list:
    out = [0] * (len(p) + len(q) - 1)
    for i, x in enumerate(p):
        for j, y in enumerate(q):
            out[i + j] += x * y
    return out


def _divmod(p: list, q: list) -> tuple[list, list]:
    p, out = list(p), []
    while len(p) >= len(q):
        f = p[0] / q[0]
        out.append(f)
        for i in range(len(q)):
            p[i] -= f * q[i]
        p.pop(0)
    return out, p


def _deriv(p: list) -> list:
    d = len(p) - 1
    return [x * (d - i) for i, x in enumerate(p[:-1])]


def _roots(p: list, mp: _Num) -> list:
    """Every root to the working precision.

    numpy's roots of the balanced polynomial p(w t) (w the roots' geometric mean), each
    refined by Newton's method; the roots Newton's method does not reach from there
    (a cluster that double precision does not resolve) from the quotient left when the
    refined ones are divided out (mpmath's polyroots, then Newton on p); mpmath's
    polyroots on p when two roots still coincide.
    """
    while len(p) > 1 and p[0] == 0:
        p = p[1:]
    zeros = 0
    while len(p) > 1 and p[-1] == 0:
        p, zeros = p[:-1], zeros + 1
    d = len(p) - 1
    if d < 1:
        return [mp.mpc(0)] * zeros
    w = abs(p[-1] / p[0]) ** (mp.mpf(1) / d)
    scaled = [complex(c * w ** (d - i)) for i, c in enumerate(p)]
    top = max(abs(c) for c in scaled)
    tol = mp.mpf(10) ** (-mp.dps // 2)  # a Newton step this small leaves an error of about its square
    sep = mp.mpf(10) ** (-mp.dps // 3)

    def newton(x, steps: int):
        for _ in range(steps):
            value, slope = p[0], 0
            for c in p[1:]:
                slope = slope * x + value
                value = value * x + c
            if slope == 0:
                return None
            step = value / slope
            x -= step
            if abs(step) <= tol * max(abs(x), 1):
                return x
        return None

    def apart(a, b) -> bool:
        return abs(a - b) > sep * max(abs(a), abs(b), 1)

    found: list = []
    for t0 in np.roots([c / top for c in scaled]):
        x = newton(mp.mpc(complex(t0) * complex(w)), 60)
        if x is not None and all(apart(x, y) for y in found):
            found.append(x)
    if len(found) < d:  # deflate the refined roots, find the rest on the quotient, polish them on p
        q = list(p)
        for x in found:
            q, _ = _divmod(q, [1, -x])
        try:
            rest = mp.polyroots(q, maxsteps=200, extraprec=mp.dps)
        except NoConvergence:
            rest = [mp.mpc(0)] * (d - len(found))  # coincide with a found root: the fallback below
        found += [newton(x0, 20) or x0 for x0 in rest]
    if any(not apart(a, b) for i, a in enumerate(found) for b in found[:i]):
        found = list(mp.polyroots(p, maxsteps=500, extraprec=4 * mp.dps))  # NoConvergence: no claim
    return found + [mp.mpc(0)] * zeros


class _Num:
    """The few mpmath context functions this module uses, in gmpy2's numbers (MPFR and MPC, in C), as a ``with``
    block that makes a gmpy2 context of ``dps`` digits (and 16 bits more) the thread's current one (thread-local,
    unlike mpmath's global precision). A division by zero and an invalid operation (NaN) raise, as in mpmath.

    Measured (``benchmarks/adjacent_margins.py``, five points each): a median 0.29 s per point at 8 masses
    against 1.17 s in mpmath's numbers (0.077 against 0.32 s at 6), with the same solutions, the same nearest
    failed case and the same digits at every point."""

    def __init__(self, dps: int):
        self.dps = dps
        self.prec = int(dps * 3.33) + 3  # bits, as mpmath's dps → prec
        self._mpm = mpmath.MPContext()
        self._mpm.dps = dps
        self._ctx = gmpy2.context(precision=self.prec + 16, trap_divzero=True, trap_invalid=True)

    def __enter__(self) -> _Num:
        self._outer = gmpy2.get_context()
        gmpy2.set_context(self._ctx)
        return self

    def __exit__(self, *exc: object) -> None:
        gmpy2.set_context(self._outer)

    @staticmethod
    def mpf(x) -> gmpy2.mpfr:
        return gmpy2.mpfr(x)

    @staticmethod
    def mpc(x) -> gmpy2.mpc:
        return gmpy2.mpc(x)

    @staticmethod
    def fsum(terms) -> gmpy2.mpfr:
        return sum(terms, gmpy2.mpfr(0))

    @staticmethod
    def polyval(p: list, x):
        value = p[0]
        for c in p[1:]:
            value = value * x + c
        return value

    @staticmethod
    def isfinite(x) -> bool:
        return bool(gmpy2.is_finite(x))

    def polyroots(self, p: list, *, maxsteps: int, extraprec: int) -> list:
        """mpmath's polyroots (the rare fallback of :func:`_roots`), in and out of gmpy2's numbers."""
        roots = self._mpm.polyroots([_to_mp(gmpy2.mpc(c), self._mpm) for c in p], maxsteps=maxsteps,
                                    extraprec=extraprec)
        return [_to_gmpy(r) for r in roots]


def _to_gmpy(z) -> gmpy2.mpc:
    """An mpmath number as gmpy2's (exactly, at the current gmpy2 context's precision, set by the caller to the
    mpmath context's and more)."""
    # the raw tuples: an MPContext has number classes of its own, so isinstance(z, mpmath.mpc) would not hold
    # and mpmath.mpc(z) would round z to the global context's 15 digits
    if not hasattr(z, "_mpc_") and not hasattr(z, "_mpf_"):  # an int, a float, a complex: exact in binary
        return gmpy2.mpc(z)
    re, im = z._mpc_ if hasattr(z, "_mpc_") else (z._mpf_, None)

    def part(x) -> gmpy2.mpfr:
        if x is None:
            return gmpy2.mpfr(0)
        sign, man, exp, _ = x
        if not man:
            return gmpy2.mpfr(0)
        v = gmpy2.mul_2exp(gmpy2.mpfr(man), int(exp))
        return -v if sign else v

    return gmpy2.mpc(part(re), part(im))


def _to_mp(z: gmpy2.mpc, mp: mpmath.MPContext) -> mpmath.mpc:
    """gmpy2's complex number in the mpmath context ``mp`` (rounded to its precision)."""
    def part(x: gmpy2.mpfr) -> gmpy2.mpfr:
        man, exp = x.as_mantissa_exp()
        return mp.mpf((int(man), int(exp)))

    return mp.mpc(part(z.real), part(z.imag))


def _phi_poly(F: list, z0, mp: _Num) -> list:
    """(s + z₀)^d F(φ(s)), φ(s) = −z₀ s / (s + z₀), d = deg F."""
    d = len(F) - 1
    pw, qw = [[mp.mpf(1)]], [[mp.mpf(1)]]
    for _ in range(d):
        pw.append(_mul(pw[-1], [-z0, 0]))
        qw.append(_mul(qw[-1], [1, z0]))
    out = [mp.mpf(0)]
    for i, f in enumerate(F):  # f is the coefficient of s^(d − i)
        out = _add(out, _scale(_mul(pw[d - i], qw[i]), f))
    return out


# -- the peel of the left chain (step 4) ----------------------------------------------------------------------------

def _peel(A: list, B: list, nmass: int, mp: _Num, free: bool = False) -> tuple[list | None, gmpy2.mpfr]:
    """Invert X = A / B as the driving-point stiffness at an end of a chain of ``nmass`` masses grounded at the
    other (``free``: not grounded; every element with a damper and a spring).

    Returns (values, worst): values [m, c, k] per node from the driven end (c, k of the element towards the
    ground; [m] at the last node of a free chain), worst the largest residual of a check that held; or (None, r),
    r the residual of the first check that failed (0 when two roots pass one step: undecided). Every check is a
    necessary condition. A free sub-chain's stiffness vanishes to second order at s = 0 (it moves as a rigid
    body), so beyond a node whose sub-chain is free the remainder has the double root 0, checked and divided out
    before the roots are sought.
    """
    out, worst = [], mp.mpf(0)
    A, B = list(A), list(B)
    for j in range(nmass, 0, -1):
        mj = A[0] / B[0]  # A / B = m s² + e D / (e + D): deg A = 2j, deg B = 2j − 2
        rest = _add(A, _scale(_mul([1, 0, 0], B), -mj))[1:]
        if j == 1 and free:  # the last node is a mass alone: rest = 0
            res = max(abs(x) for x in rest) / mp.fsum(abs(x) for x in A)
            if res > PASS:
                return None, res
            out.append([mj])
            return out, max(worst, res)
        if j == 1:  # the last node's element is the ground's: rest = e B, B constant
            res = max(abs(x) for x in rest[:-2]) / mp.fsum(abs(x) for x in rest) if len(rest) > 2 else mp.mpf(0)
            if res > PASS:
                return None, res
            out.append([mj, rest[-2] / B[-1], rest[-1] / B[-1]])
            return out, max(worst, res)
        cj = rest[0] / B[0]
        d_rest = _deriv(rest)
        sought = rest
        if free:  # the free sub-chain beyond: rest = O(s²)
            res = (abs(rest[-1]) + abs(rest[-2])) / mp.fsum(abs(x) for x in rest)
            if res > PASS:
                return None, res
            worst = max(worst, res)
            sought = rest[:-2]
        best, s0, passing = None, None, 0
        for z in _roots(sought, mp):  # −k/c: a root of rest where rest′ = c B (e − Z has a double zero there)
            r = (abs(cj * mp.polyval(B, z) - mp.polyval(d_rest, z))
                 / (abs(cj * mp.polyval(B, z)) + abs(mp.polyval(d_rest, z))))
            passing += r < FAIL
            if best is None or r < best:
                best, s0 = r, z
        if best is None or best > PASS:
            return None, best if best is not None else mp.mpf(1)
        if passing > 1:
            return None, mp.mpf(0)
        worst = max(worst, best)
        e = [cj, -cj * s0]
        num, rem1 = _divmod(rest, [1, -s0])  # D = rest e / (B e − rest), both divisible by (s − s0)²
        den, rem2 = _divmod(_add(_mul(B, e), _scale(rest, -1))[1:], [1, -s0])
        den, rem3 = _divmod(den, [1, -s0])
        size = mp.fsum(abs(x) for x in B) * abs(cj) * (1 + abs(s0))
        res = max(abs(rem1[0]) / mp.fsum(abs(x) for x in rest), abs(rem2[0]) / size, abs(rem3[0]) / size)
        if res > PASS:
            return None, res
        worst = max(worst, res)
        out.append([mj, cj, -cj * s0])
        A, B = _scale(num, cj), den
    return None, mp.mpf(1)  # pragma: no cover - the loop returns at the last node


# -- the cases (steps 1–3) --------------------------------------------------------------------------------------------

def _case(Pm: list, Nm: list, z0, sig, n: int, mp: _Num, free: bool = False,
          ) -> tuple[list | None, gmpy2.mpfr]:
    """Steps 3 and 4 for the zero −z₀ of N and σ₁ = ``sig`` in working precision: (θ as [c, k, m] per node from
    node 0 (c, k of the element towards the ground), residual) or (None, residual of the failed check)."""
    H = mp.polyval(Pm, sig) / mp.polyval(Nm, sig)
    c = -H / (sig + z0)
    mn = H / sig**2
    Q = _add(Pm, _mul([c, c * z0], Nm))
    Lq, rem = _divmod(Q, [mn, c, c * z0])
    res = max(abs(x) for x in rem) / mp.fsum(abs(x) for x in Q)
    if not res <= PASS:  # NaN or inf: σ = 0 or c infinite, impossible on a solution
        return None, res if mp.isfinite(res) else mp.mpf(1)
    lhat, _ = _divmod(Nm, [Nm[0], Nm[0] * z0])  # N / (ν (s + z₀)): the left determinant, monic
    X = _add(_scale(Lq, c / Nm[0]), _scale(_mul([c, c * z0], lhat), -1))
    got, r = _peel(X, lhat, n - 1, mp, free)
    if got is None:
        return None, r
    values = [x for node in reversed(got) for x in (node[1:] + node[:1])]  # [c, k, m] per node from node 0
    return [*values, c, c * z0, mn], max(res, r)


def _solutions(Pm: list, Nm: list, n: int, mp: _Num, misses: list | None = None, *,
               free: bool = False) -> tuple[list, bool]:
    """Every case of the module notes in working precision: (solutions as in :func:`_case`, undecided).

    P and N have real coefficients, so the cases come in complex-conjugate pairs whose
    solutions are conjugate: (z̄₀, σ̄) gives θ̄ when (z₀, σ) gives θ. Only one of each pair
    is computed (Im z₀ ≥ 0, and Im σ ≥ 0 for a real z₀); a solution found that is not
    real then stands for two, and the caller, which asks for θ* alone, claims nothing.
    ``misses``: a list that gets the residual of each case's failed check.
    """
    sols, undecided = [], False
    real = mp.mpf(10) ** (-mp.dps // 3)  # |Im| below this (relative): a real number to rounding
    for r0 in _roots(Nm, mp):
        z0 = -r0
        if z0.imag < -real * abs(z0):
            continue  # its conjugate's cases give the conjugate solutions
        real_z0 = abs(z0.imag) <= real * abs(z0)
        if real_z0:
            z0 = mp.mpc(z0.real)
        first = _mul(_scale(_mul(Pm, _phi_poly(Nm, z0, mp)), z0**2), [1, z0])
        second = _scale(_mul(_phi_poly(Pm, z0, mp), Nm), -1)
        E, _ = _divmod(_add(first, second), [1, 2 * z0, 0])  # the fixed points 0 and −2 z₀ of φ
        if mp.fsum(abs(x) for x in E) <= mp.mpf(10) ** (-mp.dps // 2) * mp.fsum(abs(x) for x in first + second):
            undecided = True  # E ≡ 0 to rounding: every σ a candidate, no finite list of cases
            continue
        tiny = mp.mpf(10) ** (-mp.dps // 2) * mp.fsum(abs(x) for x in E)
        while len(E) > 1 and abs(E[0]) < tiny:
            E = E[1:]  # the leading coefficient cancels (degree 4n − 5), to rounding
        while len(E) > 1 and abs(E[-1]) < tiny:
            E = E[:-1]  # a root at 0: no candidate (V(0) = c z₀ ≠ 0)
        seen = []
        for sig, pair in [(x, True) for x in _roots(E, mp)] + [(-2 * z0, False)]:
            if real_z0 and sig.imag < -real * abs(sig):
                continue  # the conjugate case
            if min(abs(sig), abs(sig + z0)) <= real * abs(z0):
                continue  # σ = 0 or −z₀: V(σ) = c z₀ or m z₀², never 0, so no solution has it
            if pair and any(abs(sig - t) < mp.mpf(10) ** (-mp.dps // 4) * (1 + abs(t)) for t in seen):
                continue  # the other zero of a pair already tried
            seen += [sig, -z0 * sig / (sig + z0)]
            size = mp.fsum(abs(x) * abs(sig) ** i for i, x in enumerate(reversed(Nm))) * (abs(sig) + abs(z0))
            if abs(mp.polyval(Nm, sig) * (sig + z0)) / size < mp.mpf(10) ** (-mp.dps // 3):
                continue  # σ a pole of Ω: P and N are coprime, so no solution has it (to a third of the digits;
                # the test ran in 20 digits, so at 1e-6, before: cases that near a pole were left out, not tried)
            try:
                got, r = _case(Pm, Nm, z0, sig, n, mp, free)
            except (ZeroDivisionError, gmpy2.InvalidOperationError):  # a zero damper or mass (σ a zero of P) or a
                got, r = None, mp.mpf(1)  # zero leading coefficient in the peel: no solution has one (θ* generic)
            if got is None:
                undecided = undecided or r < FAIL
                if misses is not None:
                    misses.append(r)
                continue
            _keep(sols, got, mp)
    return sols, undecided


def _keep(sols: list, values: list, mp: _Num) -> None:
    if not any(max(abs(v - w) / abs(w) for v, w in zip(values, s, strict=True)) < mp.mpf(10) ** (-mp.dps // 2)
               for s in sols):
        sols.append(values)
