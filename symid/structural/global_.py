"""Global identifiability: solve summary(θ) = summary(θ*) at a random rational θ* (Gröbner basis).

Method
------
1. Pick a random rational θ* (p/q, p ≤ 10⁵, q ≤ 10³, :func:`draw_point`) at which
   M(θ*) is invertible, the Jacobian of the summary has its generic rank (at a point
   where solutions merge it drops) and, preferably, the realisation is minimal; build
   the polynomial system ``n_i(θ)·d_i(θ*) − n_i(θ*)·d_i(θ) = 0`` for every summary
   entry ``n_i/d_i``, plus ``t·q(θ) − 1 = 0`` (a saturation variable t) when the
   normalising polynomial q (``det M`` for a second-order model) depends on θ, which
   removes spurious solutions where the normalisation vanishes.
2. Reduced Gröbner basis in grevlex order (sympy). The ideal is zero-dimensional
   iff every variable has a pure power among the leading monomials; otherwise the
   solution set is positive-dimensional: the model is not identifiable.
3. Zero-dimensional: the standard monomials give the quotient algebra (dimension D,
   the number of solutions counted with multiplicity) and the multiplication
   matrices (exact). The characteristic polynomial of a random linear form ℓ of the
   variables must be square-free of degree D: then there are D distinct solutions,
   each simple (the ideal is radical). Otherwise θ* has a multiple solution, which a
   generic point never has (generic fibres are reduced), and
   :class:`NonGenericPoint` asks for another θ*. The solutions are the eigenvectors
   of the multiplication matrix of ℓ (numpy, float64); the number of real ones is
   exact (Sturm count of ℓ's characteristic polynomial). Real solutions with a
   non-positive value of a parameter declared positive are discarded.
4. Per parameter: θ_k takes a single value on every complex solution iff its
   multiplication matrix is θ_k* I (the ideal is radical); in a positive-dimensional
   case iff θ_k − θ_k* lies in the radical of the ideal (normal form, then the
   Rabinowitsch trick).
5. :func:`generic_global` confirms what is claimed global at an independent point θ**,
   modulo a random prime p ≈ 2³⁰ (:func:`confirm_mod_p`: no coefficient growth).

The complex count is the generic (structural) count; the counts of *real* and
*positive* solutions depend on the region of θ*.

Two engines
-----------
Steps 2–4 (and the confirmation of step 5) are done by sympy, or, when an msolve program
is given (``msolve=``; :mod:`~symid.structural.msolve`, found by
:func:`~symid.structural.msolve.msolve_binary`) and the Jacobian has full rank (finitely
many solutions expected), by msolve: F4 and a rational parametrization
(w, w', v_j, c_j) of the solutions, over ℚ at θ* and over GF(p) at θ**. From it:

* first, the count modulo a random prime p (:func:`_degree_mod_p`, a few times faster than
  over ℚ): when it is 1, θ* is the only solution — every parameter is single-valued and the
  real and admissible counts are 1; when it equals the number of points of the orbit of θ*
  under exact symmetries of the summary (:mod:`~symid.structural.symmetry`), those exact
  rational points are the solutions (all real; admissible, single-valued parameters and
  candidates decided exactly on them). In both cases nothing is computed over ℚ;
* otherwise over ℚ: the count is w's degree, which must equal msolve's count with
  multiplicity, and w must be square-free (else a multiple solution:
  :class:`NonGenericPoint`, as in step 3);
* per parameter: θ_j is single-valued on every complex solution iff
  v_j + c_j·θ_j*·w' is the zero polynomial (x_j = −v_j/(c_j w') on the roots of w, and
  that polynomial has degree < deg w); over GF(p), iff v_j is the constant −θ_j**;
* the real solutions: msolve's isolating boxes (one per real root of w), and their signs
  (a box on one side of 0, or an exact zero: as many boxes containing 0 as real roots of
  gcd(w, v_j); else msolve is run again at a higher precision);
* θ* must be a root of the parametrization, checked exactly in rationals (an altered or
  truncated output raises :class:`~symid.structural.msolve.MsolveError`).

Where msolve finds a positive-dimensional set, a non-radical ideal modulo p at θ**, or
anything else outside that case, the sympy computation is done instead, so the result is
the same whichever engine ran (the float values of ``solutions`` agree to rounding: the
two engines compute them differently). What differs is how the counts are established:
sympy's over ℚ is exact; msolve's over ℚ is a multi-modular computation with a
probabilistic stopping criterion (a Monte Carlo answer; see the module
:mod:`~symid.structural.msolve`), as the confirmation modulo a random prime already is,
and a count of 1 found modulo a random prime at θ* is Monte Carlo in the same way (wrong
only for the finitely many primes at which the computation degenerates), then confirmed
at θ** modulo another prime.
The solutions are listed in a canonical order (by their values, θ* given exactly).
"""

from __future__ import annotations

import functools
import random
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from fractions import Fraction
from typing import Any

import numpy as np
import sympy as sp
from sympy import QQ
from sympy.polys.groebnertools import groebner
from sympy.polys.matrices import DomainMatrix
from sympy.polys.polyerrors import NotInvertible
from sympy.polys.rings import PolyElement, PolyRing, ring

from symid.errors import ModelError, SolverError
from symid.structural.ladder import proves_global
from symid.structural.local import rank_at
from symid.structural.modp import BadPrime, compile_poly, residue, value_mod_p
from symid.structural.msolve import MsolveCancelled, MsolveError, input_text, parse_output, run_msolve
from symid.structural.order import grevlex_memo
from symid.structural.summary import (
    KIND_MATRICES,
    KIND_TF,
    analysed_output,
    evaluator,
    exhaustive_summary,
    free_parameters,
    is_minimal_at,
    model_kind,
    model_matrices,
)
from symid.structural.symmetry import orbit, symmetries

__all__ = ["MAX_QUOTIENT", "POSITIVE_TOL", "REAL_TOL", "ExactStepLimit", "GlobalResult", "NonGenericPoint",
           "confirm_mod_p", "draw_point", "generic_global", "global_analysis", "star_and_summary"]

REAL_TOL = 1e-7
"""Relative tolerance on a parameter value when comparing numerical solutions to θ*."""
POSITIVE_TOL = 1e-9
"""A real solution is positive in a coordinate when the value exceeds this (absolute)."""
MAX_QUOTIENT = 400
"""Largest quotient dimension (number of complex solutions with multiplicity) enumerated."""


class ExactStepLimit(SolverError):
    """A documented limit of the exact global step was reached (the count is then undetermined, not wrong).

    Raised when the quotient algebra has more than :data:`MAX_QUOTIENT` standard
    monomials (too many solutions to enumerate), or when no separating linear form is
    found in ten random draws (probability zero for generic draws).
    """


@dataclass(frozen=True)
class GlobalResult:
    """Outcome of the global step (plain data, picklable).

    Attributes
    ----------
    summary_kind : str
        Which exhaustive summary was used.
    summary_labels : tuple of str
        Labels of the non-constant summary entries.
    summary_expressions : tuple of sympy.Expr
        The summary entries (rational in θ); empty unless ``expressions=True``.
    theta_star : dict of str to sympy.Rational
        The random point.
    zero_dimensional : bool
        Whether summary(θ) = summary(θ*) has finitely many solutions.
    n_complex : int or None
        Distinct complex solutions (None when positive-dimensional).
    n_real : int or None
        Distinct real solutions.
    n_admissible : int or None
        Real solutions that satisfy the declared positivity.
    solutions : tuple of dict
        The admissible solutions (floats), θ* among them.
    real_solutions : tuple of dict
        All real solutions (floats).
    global_complex, global_real, global_admissible : dict of str to bool
        Per free parameter: a single value over the complex, real, admissible solutions.
    candidates : tuple of sympy.Expr
        Identifiable-function candidates read off the Gröbner basis (non-constant parts
        of basis elements free of the saturation variable); empty unless ``expressions=True``.
    membership : tuple of bool
        For each extra candidate passed in: f(θ) − f(θ*) lies in the ideal.
    groebner_size : int
        Number of polynomials in the reduced basis (0 when msolve ran: it does not return it).
    times : dict of str to float
        Wall time of the steps.
    notes : tuple of str
    theta_confirm : dict of str to str
        θ** of the confirmation, when a global claim was confirmed.
    confirmed : bool
        The confirmation at θ** agreed.
    draws : int
        Points θ* drawn until a generic one.
    engine : str
        ``"sympy"`` or ``"msolve"`` (:mod:`~symid.structural.msolve`): which computed the
        solutions (the result is the same either way, up to the float rounding of
        ``solutions``); ``"formula"`` when no solution was computed because every verdict
        came from checked formulas (:mod:`~symid.structural.rational_formulas`);
        ``"ladder"`` when a chain driven and measured at one mass was inverted (at an end
        mass by continued fractions, :mod:`~symid.structural.ladder`; at an interior mass by
        a pole split and continued fractions on either side,
        :mod:`~symid.structural.ladder_interior`), or driven next to its free end and
        measured there (a case analysis, :mod:`~symid.structural.ladder_adjacent`): one
        solution, no Gröbner basis.
    slice_values : dict of str to sympy.Rational
        For a model that is not locally identifiable, solved on a slice
        (:mod:`~symid.structural.slicing`): the random values given to the parameters
        that cut the solution set; empty otherwise.
    slice_result : GlobalResult or None
        The sliced system's own result (counts and solutions on the slice).
    local_elsewhere : dict of str to dict
        Parameters that are single-valued on the admissible solutions at θ* but not on the
        complex ones, for which another random point (given, as strings) has two admissible
        solutions that differ in them (:func:`generic_global`): proven not global.
    linear_global : tuple of tuple of Fraction, or None
        A basis of the coefficient vectors λ for which Σ λ_k ℓ_k is single-valued on every
        complex solution, ℓ_k the ``linear_forms`` passed in (empty when none were, or the
        solution set is positive-dimensional; None when not decided).
    partial : bool
        Only some solutions are known (exact, from symmetries; ``settle`` of
        :func:`global_analysis`): the parameters they move are not single-valued, nothing
        else is claimed (the other ``global_*`` values are False, ``membership`` empty).
    """

    summary_kind: str
    summary_labels: tuple[str, ...]
    summary_expressions: tuple
    theta_star: dict
    zero_dimensional: bool
    n_complex: int | None
    n_real: int | None
    n_admissible: int | None
    solutions: tuple
    real_solutions: tuple
    global_complex: dict
    global_real: dict
    global_admissible: dict
    candidates: tuple
    membership: tuple
    groebner_size: int
    times: dict = field(default_factory=dict)
    notes: tuple = ()
    theta_confirm: dict = field(default_factory=dict)
    confirmed: bool = False
    draws: int = 1
    engine: str = "sympy"
    slice_values: dict = field(default_factory=dict)
    slice_result: GlobalResult | None = None
    linear_global: tuple | None = ()
    local_elsewhere: dict = field(default_factory=dict)
    partial: bool = False


STAR_NUMERATORS = (1, 100_000)
"""θ* coordinates are p/q with p and q uniform in these ranges (wide: see :func:`draw_point`)."""
STAR_DENOMINATORS = (1, 1_000)
MAX_DRAWS = 8
"""Draws of θ* (each of up to 50 candidates) before the global step gives up finding a generic point."""


class NonGenericPoint(SolverError):
    """θ* lies on a special set (rank drop, coinciding solutions): draw another (:func:`generic_global`)."""


def draw_point(rng: random.Random, n: int, *, negative: Sequence[bool] | None = None) -> list[sp.Rational]:
    """A random rational point: p/q with p ∈ [1, 10⁵], q ∈ [1, 10³] (about 6·10⁷ distinct values per coordinate).

    By the Schwartz–Zippel lemma a polynomial of degree D that does not vanish
    identically vanishes at such a point with probability at most D / 10⁵; the
    special sets that matter here (a rank drop of the Jacobian, coinciding solutions)
    are moreover checked at the point itself. ``negative``: per coordinate, draw the
    sign at random (parameters not declared positive).

    Examples
    --------
    >>> import random
    >>> from symid.structural.global_ import draw_point
    >>> draw_point(random.Random(0), 2)
    [50495/777, 27563/21]
    """
    out = []
    for i in range(n):
        v = sp.Rational(rng.randint(*STAR_NUMERATORS), rng.randint(*STAR_DENOMINATORS))
        if negative is not None and negative[i] and rng.random() < 0.5:
            v = -v
        out.append(v)
    return out


_NON_MINIMAL_DRAWS = 3
"""Points with the generic rank but a non-minimal realisation tried before settling for the first of them."""


def _pick_theta_star(model, mats, kind, output, params, rng: random.Random, *, known=None, rank: int | None = None):
    """A random θ* where M(θ*) is invertible and, when ``rank`` is given, the Jacobian has that (generic) rank.

    A realisation minimal at θ* is preferred (the transfer-function summary is then
    exhaustive); after three points with the rank where it is not, the first of them is
    taken (a realisation not minimal anywhere: the summary then checks whether the
    transfer function, reduced by a common power of s, is in lowest terms there, else
    uses Markov parameters). Returns ``(point, minimal)``.
    """
    fallback, singular, non_minimal = None, 0, 0
    for _ in range(50):
        pt = draw_point(rng, len(params))
        if kind == "second-order":
            M = mats["M"].xreplace(dict(zip(params, pt, strict=True)))
            if M.det() == 0:
                singular += 1
                continue
        if rank is not None and rank_at(model, pt, known, rng=rng) < rank:
            continue
        if is_minimal_at(mats, kind, output, params, pt):
            return pt, True
        if fallback is None:
            fallback = pt
        non_minimal += 1
        if non_minimal >= _NON_MINIMAL_DRAWS:  # not minimal anywhere, most likely: structural (the summary is
            break  # checked at the point returned in any case)
    if singular == 50:
        raise ModelError("det M(θ) is identically zero (singular at 50 random points); the second-order model is "
                         "degenerate (a mass given as 0 in known=?)")
    if fallback is None:
        raise ExactStepLimit("no point θ* with the generic Jacobian rank found in 50 random draws")
    return fallback, False


def star_and_summary(model, known: Mapping[str, object] | None = None, *, seed: int = 0, draw: int = 0,
                     rank: int | None = None, summary=None):
    """The random point θ* of the global step and the exhaustive summary built for it.

    Parameters
    ----------
    model, known
        As for :func:`global_analysis`.
    seed : int
        The seed of the analysis.
    draw : int
        Which independent point of the seed's sequence (0 is θ*; the confirmation point
        and the redraws after a non-generic θ* use others), 0 ≤ draw < 1000.
    rank : int, optional
        The generic rank of the Jacobian: θ* is redrawn until the Jacobian has it at θ*.
    summary : ExhaustiveSummary, optional
        The transfer-function summary built at another point of the same model: reused
        when the realisation is minimal at this θ* too (the summary's polynomials do not
        depend on the point; only whether they are exhaustive there does).

    Returns
    -------
    (params, star, minimal, summary, rng)
        Free parameters, θ* (sympy Rationals), whether the realisation is minimal there,
        the :class:`~symid.structural.summary.ExhaustiveSummary` and the seeded
        generator, advanced past θ* (for later random choices).
    """
    kind = model_kind(model)
    output = analysed_output(model)
    mats = model_matrices(model, known)
    params = free_parameters(model, known)
    rng = random.Random(10_007 + 1000 * seed + draw)
    star, minimal = _pick_theta_star(model, mats, kind, output, params, rng, known=known, rank=rank)
    if summary is not None and (summary.kind == KIND_MATRICES
                                or (summary.kind == KIND_TF and (minimal or summary.exhaustive_at(star)))):
        # (a summary built where the realisation was minimal keeps no reduced form: built again here)
        return params, star, minimal, summary, rng
    summ = exhaustive_summary(model, known, check_point=star)
    return params, star, minimal, summ, rng


def _lift(p: PolyElement, R: PolyRing) -> PolyElement:
    return p.set_ring(R)


def _standard_monomials(lms: list[tuple[int, ...]], nvars: int, cap: int) -> list[tuple[int, ...]] | None:
    """Monomials not divisible by any leading monomial (None when more than ``cap``)."""
    def divisible(m):
        return any(all(a >= b for a, b in zip(m, lm, strict=True)) for lm in lms)

    start = (0,) * nvars
    if divisible(start):
        return []
    seen, frontier, out = {start}, [start], [start]
    while frontier:
        nxt = []
        for m in frontier:
            for i in range(nvars):
                c = (*m[:i], m[i] + 1, *m[i + 1:])
                if c in seen or divisible(c):
                    continue
                seen.add(c)
                out.append(c)
                nxt.append(c)
                if len(out) > cap:
                    return None
        frontier = nxt
    return out


def _is_zero_dimensional(G: list[PolyElement], nvars: int) -> bool:
    pure = set()
    for g in G:
        lm = g.LM
        nz = [i for i, e in enumerate(lm) if e]
        if len(nz) == 1:
            pure.add(nz[0])
    return len(pure) == nvars


def _mult_matrices(G, R: PolyRing, basis: list[tuple[int, ...]], variables: Sequence[int]) -> dict[int, DomainMatrix]:
    index = {m: i for i, m in enumerate(basis)}
    D = len(basis)
    out = {}
    for v in variables:
        cols = []
        for m in basis:
            mono = list(m)
            mono[v] += 1
            nf = R({tuple(mono): QQ(1)}).rem(G)
            col = [QQ(0)] * D
            for mon, c in nf.terms():
                col[index[mon]] = c
            cols.append(col)
        out[v] = DomainMatrix([[cols[j][i] for j in range(D)] for i in range(D)], (D, D), QQ)
    return out


def _charpoly_expr(M: DomainMatrix, x: sp.Symbol) -> sp.Poly:
    coeffs = M.charpoly()
    return sp.Poly([QQ.to_sympy(c) for c in coeffs], x, domain="QQ")


def _square_free(cp: sp.Poly, x: sp.Symbol) -> bool:
    """Whether a monic rational polynomial is square-free: modulo a prime first (sufficient), else exactly.

    A repeated factor over ℚ stays repeated modulo any prime that divides no
    denominator (the polynomial is monic, so its degree is kept): square-free modulo
    such a prime proves square-free over ℚ.
    """
    for prime in (2**31 - 1, 2**31 - 19):
        F = sp.GF(prime)
        if any(int(c.q) % prime == 0 for c in cp.all_coeffs()):
            continue  # the prime divides a denominator: the reduction says nothing
        coeffs = [F(int(c.p)) / F(int(c.q)) for c in cp.all_coeffs()]
        fp = sp.Poly([F.to_sympy(c) for c in coeffs], x, modulus=prime)
        if fp.degree() == cp.degree() and fp.gcd(fp.diff(x)).degree() == 0:
            return True
    return sp.degree(sp.gcd(cp, cp.diff(x)), x) == 0


def _in_radical(G, R: PolyRing, f: PolyElement) -> bool:
    if f.rem(G) == R.zero:
        return True
    y = sp.Dummy("y")
    Ry = ring([*R.symbols, y], QQ, grevlex_memo)[0]
    Gy = [g.set_ring(Ry) for g in G] + [Ry.one - Ry.gens[-1] * f.set_ring(Ry)]
    return groebner(Gy, Ry) == [Ry.one]


def _system(summ, params, pt, modulus: int | None = None) -> tuple[PolyRing, list[PolyElement], int]:
    """The polynomial system summary(θ) = summary(θ*) over ℚ (or GF(modulus)): ring, equations, auxiliary count."""
    dom = QQ if modulus is None else sp.GF(modulus)
    at = evaluator(pt)

    def lift(p: PolyElement, R: PolyRing) -> PolyElement:
        if modulus is None:
            return _lift(p, R)
        n = R.ngens - len(params)
        return R({(*k, *([0] * n)): dom(int(c.numerator)) / dom(int(c.denominator)) for k, c in p.terms()})

    def const(c) -> object:
        return c if modulus is None else dom(int(c.numerator)) / dom(int(c.denominator))

    R0 = summ.ring
    tsym = sp.Dummy("t")
    eqs = []
    L = summ.normaliser
    if L is not None and not L.is_ground:
        # common normaliser: N_i(θ) = λ N_i(θ*), L(θ) = λ L(θ*), t λ = 1 (fewer terms than cross-multiplying)
        lam = sp.Dummy("lam")
        R = ring([*params, lam, tsym], dom, grevlex_memo)[0]
        lamR, tR = R.gens[-2], R.gens[-1]
        for num, den in [*zip(summ.numerators, summ.denominators, strict=True), (L, L)]:
            raw = num * L.exquo(den)
            eqs.append(lift(raw, R) - lamR * const(at(raw)))
        eqs.append(tR * lamR - R.one)
        aux = 2
    else:
        sat = _saturating(summ)
        if sat is not None:
            R = ring([*params, tsym], dom, grevlex_memo)[0]
        else:
            R = ring(list(params), dom, grevlex_memo)[0]
        aux = 1 if sat is not None else 0
        for num, den in zip(summ.numerators, summ.denominators, strict=True):
            e = num * at(den) - den * at(num)
            if e != R0.zero:
                eqs.append(lift(e, R))
        if sat is not None:
            eqs.append(R.gens[-1] * lift(sat, R) - R.one)
    eqs = [e for e in eqs if e != R.zero] or [R.zero]
    return R, eqs, aux


@functools.lru_cache(maxsize=4)
def _normalised(summ) -> tuple:
    """The polynomials N_i·(L / D_i) of the normaliser form of :func:`_system` (they do not depend on the point)."""
    L = summ.normaliser
    return tuple(num * L.exquo(den) for num, den in
                 [*zip(summ.numerators, summ.denominators, strict=True), (L, L)])


def _system_mod_p(summ, params, star, modulus: int) -> tuple[int, list[dict], list[int]]:
    """The system of :func:`_system` reduced modulo a prime, built on residues (numpy) rather than rationals.

    Returns the number of variables, the equations (monomial → residue) and the known
    solution (θ* and the auxiliary variables) modulo the prime. Raises
    :class:`~symid.structural.modp.BadPrime` when the prime divides a denominator.
    """
    p = modulus
    at = [residue(v, p) for v in star]
    n = len(params)
    L = summ.normaliser
    eqs: list[dict] = []
    if L is not None and not L.is_ground:  # N_i(θ) = λ N_i(θ*), L(θ) = λ L(θ*), t λ = 1
        for raw in _normalised(summ):
            comp = compile_poly(raw, p)
            eq = {(*m, 0, 0): int(c) for m, c in zip(comp.monomials, comp.coeffs, strict=True) if c}
            lam = (*([0] * n), 1, 0)
            eq[lam] = (eq.get(lam, 0) - value_mod_p(comp, at, p)) % p
            eqs.append({m: c for m, c in eq.items() if c})
        eqs.append({(*([0] * n), 1, 1): 1, (*([0] * n), 0, 0): p - 1})
        return n + 2, [e for e in eqs if e], [*at, 1, 1]
    sat = _saturating(summ)
    aux = 1 if sat is not None else 0
    for num, den in zip(summ.numerators, summ.denominators, strict=True):
        cn, cd = compile_poly(num, p), compile_poly(den, p)
        nv, dv = value_mod_p(cn, at, p), value_mod_p(cd, at, p)
        eq: dict = {}
        for comp, factor in ((cn, dv), (cd, p - nv)):
            for m, c in zip(comp.monomials, comp.coeffs, strict=True):
                key = (*m, *([0] * aux))
                eq[key] = (eq.get(key, 0) + int(c) * factor) % p
        eq = {m: c for m, c in eq.items() if c}
        if eq:
            eqs.append(eq)
    point = list(at)
    if sat is not None:
        cs = compile_poly(sat, p)
        sv = value_mod_p(cs, at, p)
        if sv == 0:
            raise BadPrime("the saturating polynomial vanishes at θ* modulo the prime")
        eq = {(*m, 1): int(c) for m, c in zip(cs.monomials, cs.coeffs, strict=True) if c}
        eq[(0,) * (n + 1)] = p - 1
        eqs.append(eq)
        point.append(pow(sv, -1, p))
    return n + aux, eqs or [{}], point


def _saturating(summ) -> PolyElement | None:
    """The square-free lcm of the non-constant denominators (saturated by t·sat − 1 = 0), or None."""
    nonconst_den = [d for d in summ.denominators if not d.is_ground]
    if not nonconst_den:
        return None
    sat = nonconst_den[0]
    for d in nonconst_den[1:]:
        sat = sat.lcm(d)
    return sat.sqf_part()


def _aux_values(summ, pt) -> list[Fraction]:
    """The auxiliary variables of :func:`_system` at θ* itself (λ = t = 1, or t = 1/sat(θ*))."""
    L = summ.normaliser
    if L is not None and not L.is_ground:
        return [Fraction(1), Fraction(1)]
    sat = _saturating(summ)
    if sat is None:
        return []
    v = evaluator(pt)(sat)
    return [Fraction(int(v.denominator), int(v.numerator))]


MAX_PRIME = 1_518_500_213
"""Primes of the confirmation are below this (msolve's FGLM refuses larger ones), and at least 2³⁰."""


def _mod_p_modulus(rng: random.Random) -> int:
    """A random prime in [2³⁰, :data:`MAX_PRIME`)."""
    while True:
        p = rng.randrange(2**30, MAX_PRIME) | 1
        if sp.isprime(p):
            return p


def confirm_mod_p(model, known: Mapping[str, object] | None = None, *, seed: int = 0, draw: int = 500,
                  rank: int | None = None, msolve: str | None = None,
                  summary=None, cancel: threading.Event | None = None,
                  msolve_only: bool = False) -> tuple[bool, int | None, dict, dict] | None:
    """Solve summary(θ) = summary(θ**) modulo a random prime at an independent generic point θ**.

    Used to confirm global claims (:func:`generic_global`): the same algebra as
    :func:`global_analysis` over GF(p), p a random prime in [2³⁰, 1.5·10⁹), so the
    coefficients never grow. For a prime that does not divide the finitely many
    denominators and leading coefficients of the computation (all but a negligible
    fraction), the quotient dimension and the per-parameter answers are those over ℚ.
    With ``msolve`` (the program's path), msolve's parametrization modulo p gives them
    when the ideal is radical there (the generic case); otherwise sympy's computation.
    ``summary``: θ*'s summary, reused when it is exhaustive at θ** too
    (:func:`star_and_summary`). ``cancel``: an event that stops msolve once set
    (:class:`~symid.structural.msolve.MsolveCancelled`); ``msolve_only``: return None
    where msolve does not decide (instead of sympy's computation).

    Returns
    -------
    (zero_dimensional, quotient dimension or None, single-valued per parameter, θ** as strings)
    """
    params, star, _, summ, rng = star_and_summary(model, known, seed=seed, draw=draw, rank=rank, summary=summary)
    names = [p.name for p in params]
    theta2 = {n: str(v) for n, v in zip(names, star, strict=True)}
    if proves_global(model, known, star):  # a chain driven at one mass: one solution, by continued fractions
        return True, 1, dict.fromkeys(names, True), theta2
    pt = [QQ.from_sympy(v) for v in star]
    exact = [Fraction(int(v.p), int(v.q)) for v in star]
    for _ in range(10):  # a prime that divides a denominator of the system cannot reduce it: take another
        modulus = _mod_p_modulus(rng)
        try:
            reduced = _system_mod_p(summ, params, exact, modulus) if msolve is not None else None
            break
        except BadPrime:
            continue
    else:  # pragma: no cover - ten random 31-bit primes dividing the denominators: practically impossible
        raise ExactStepLimit("no prime found that reduces the system at θ**")
    if reduced is not None:
        found = _confirm_msolve(msolve, *reduced[:2], star, names, modulus, rng.randrange(2**31), cancel=cancel)
        if found is not None:
            return (*found, theta2)
    if msolve_only:
        return None
    try:
        R, eqs, _ = _system(summ, params, pt, modulus)
    except (ZeroDivisionError, NotInvertible):  # pragma: no cover - a prime that reduces one form reduces the other
        raise ExactStepLimit("no prime found that reduces the system at θ**") from None
    dom = R.domain
    ptp = [dom(int(v.numerator)) / dom(int(v.denominator)) for v in pt]
    G = groebner(eqs, R)
    nv = R.ngens
    if not _is_zero_dimensional(G, nv):
        single = {}
        for i, name in enumerate(names):
            f = R.gens[i] - ptp[i]
            if f.rem(G) == R.zero:
                single[name] = True
                continue
            y = sp.Dummy("y")
            Ry = ring([*R.symbols, y], dom, grevlex_memo)[0]
            Gy = [g.set_ring(Ry) for g in G] + [Ry.one - Ry.gens[-1] * f.set_ring(Ry)]
            single[name] = groebner(Gy, Ry) == [Ry.one]
        return False, None, single, theta2
    basis = _standard_monomials([g.LM for g in G], nv, MAX_QUOTIENT)
    if basis is None:
        return True, None, dict.fromkeys(names, False), theta2
    if len(basis) == 1:
        return True, 1, dict.fromkeys(names, True), theta2
    single = {}
    for i, name in enumerate(names):  # θ_i single-valued iff (x_i − θ_i**)·m ≡ 0 for every standard monomial m
        ok = True
        for m in basis:
            mono = list(m)
            mono[i] += 1
            nf = (R({tuple(mono): dom(1)}) - R({m: ptp[i]})).rem(G)
            if nf != R.zero:
                ok = False
                break
        single[name] = ok
    return True, len(basis), single, theta2


def global_analysis(model, known: Mapping[str, object] | None = None, *, positive: Sequence[bool] | None = None,
                    seed: int = 0, extra_candidates: Sequence[sp.Expr] = (), expressions: bool = True,
                    prepared: tuple | None = None, msolve: str | None = None,
                    linear_forms: Sequence[Mapping[str, Fraction]] = (),
                    settle: Sequence[str] | None = None) -> GlobalResult:
    """Solve summary(θ) = summary(θ*) exactly at a random rational θ* and classify the solutions.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    known : dict, optional
        Fixed parameter values (substituted first).
    positive : sequence of bool, optional
        Per free parameter, whether solutions with a non-positive value are discarded.
        Default: none.
    seed : int
        Seed of θ*.
    extra_candidates : sequence of sympy.Expr
        Functions of θ whose membership f(θ) − f(θ*) ∈ ideal is checked.
    expressions : bool
        Return the summary entries and the Gröbner-basis candidates as sympy
        expressions (needed only for the combinations of a non-identifiable model;
        building them is a noticeable part of the run on large models).
    prepared : tuple, optional
        The result of :func:`star_and_summary` for the same model, ``known`` and
        ``seed`` (saves recomputing it when the step is re-run; not modified).
    msolve : str, optional
        Path of an msolve program: solve with msolve (see the module docstring) when
        there are no ``extra_candidates`` (membership needs sympy's basis); a
        positive-dimensional solution set is then handed to sympy. The Gröbner-basis
        ``candidates`` are empty when msolve ran.
    linear_forms : sequence of dict of str to Fraction
        Linear forms Σ a_j θ_j (parameter name → coefficient): which of their
        combinations are single-valued is returned in ``linear_global``.
    settle : sequence of str, optional
        Parameters whose verdicts are all that is asked (the counts are not reported, as
        on a slice): when the orbit of θ* under exact symmetries is only part of the
        solutions but already moves each of them, that partial result is returned
        (``partial`` True: those parameters not single-valued, proven by exact admissible
        solutions; nothing else claimed).

    Returns
    -------
    GlobalResult

    Raises
    ------
    NonGenericPoint
        θ* has a multiple solution.
    ExactStepLimit
        More than :data:`MAX_QUOTIENT` complex solutions, or (msolve) the sign of a
        coordinate of a real solution not decided at 8192 bits.
    MsolveError
        msolve failed or its output is malformed or inconsistent with the system.

    Examples
    --------
    >>> import symid as si
    >>> from symid.structural.global_ import global_analysis
    >>> th = si.parameters("th")
    >>> model = si.StateSpaceModel(A=[[-1]], B=[[th]], C=[[th]])
    >>> res = global_analysis(model, positive=[True])
    >>> res.n_complex, res.n_real, res.n_admissible
    (2, 2, 1)
    """
    times = {}
    t0 = time.perf_counter()
    if prepared is None:
        prepared = star_and_summary(model, known, seed=seed)
    params, star, minimal, summ, shared_rng = prepared
    rng = random.Random()
    rng.setstate(shared_rng.getstate())  # a re-run makes the same random choices
    names = [p.name for p in params]
    positive = list(positive) if positive is not None else [False] * len(params)
    theta_star = dict(zip(names, star, strict=True))
    times["summary"] = time.perf_counter() - t0
    notes = []
    if summ.kind == KIND_MATRICES:
        notes.append("B and C are known, square and invertible, so the response determines the model's matrices "
                     "(M s² + V s + K = s^r B H(s)⁻¹ C, or sI − A = B (H(s) − D)⁻¹ C): their entries are the summary")
    elif summ.kind != KIND_TF:
        notes.append("the realisation is not minimal at random points; Markov parameters used as the summary")
    elif not minimal:
        shared = (f"; its numerator and denominator share the factor s^{summ.shift} for every θ (poles at s = 0 "
                  "that zeros at s = 0 cancel: a rigid-body mode, an integrator, a derivative sensor), divided out"
                  if summ.shift else "")
        notes.append(f"the realisation is not minimal at θ*, but the transfer function is in lowest terms there"
                     f"{shared}; so its coefficients are an exhaustive summary")
    if not params:
        return GlobalResult(summ.kind, summ.labels, tuple(summ.expressions()), {}, True, 1, 1, 1, ({},), ({},),
                            {}, {}, {}, (), (), 0, times, tuple(notes))

    # -- polynomial system --------------------------------------------------------
    t1 = time.perf_counter()
    pt = [QQ.from_sympy(v) for v in star]
    exact_star = [Fraction(int(v.p), int(v.q)) for v in star]
    crossed = [_cross_terms(e, params, exact_star) for e in extra_candidates]
    ladder = proves_global(model, known, star)  # a chain driven at one mass: one solution, by continued fractions
    degree = 1 if ladder else _degree_mod_p(msolve, summ, params, exact_star, rng) \
        if msolve is not None and all(c is not None for c in crossed) else None
    if degree is not None and 1 < degree <= MAX_QUOTIENT:
        points = orbit(exact_star, symmetries(model, known, summ), degree)
        if points is not None and len(points) == degree:  # the orbit of θ* under exact symmetries: every solution
            times["groebner"] = time.perf_counter() - t1
            summary_exprs = tuple(summ.expressions()) if expressions else ()
            return _orbit_result(summ, summary_exprs, theta_star, names, positive, points, crossed, linear_forms,
                                 times, notes)
        if points is not None and settle is not None and len(points) > 1 and degree > PARTIAL_ABOVE:
            adm = [x for x in points if all(not pos or v > 0 for v, pos in zip(x, positive, strict=True))]
            moved = {n for i, n in enumerate(names) if any(x[i] != adm[0][i] for x in adm)}
            if set(settle) <= moved:  # exact admissible solutions already prove every verdict asked for
                times["groebner"] = time.perf_counter() - t1
                glob = dict.fromkeys(names, False)
                sols = tuple(_canonical([{n: float(v) for n, v in zip(names, x, strict=True)} for x in adm],
                                        theta_star, glob))
                return GlobalResult(summ.kind, summ.labels, tuple(summ.expressions()) if expressions else (),
                                    theta_star, True, degree, None, None, sols, sols, glob, dict(glob), dict(glob),
                                    (), (), 0, times, tuple(notes), engine="msolve", linear_global=None,
                                    partial=True)
    if degree == 1:
        # one solution, θ*: every parameter and every candidate is single-valued
        times["groebner"] = time.perf_counter() - t1
        if ladder == "end":
            notes.append("a mass chain driven and measured at an end mass: its continued fraction gives every "
                         "parameter as a rational function of the transfer function (symid.structural.ladder), so "
                         "no Gröbner basis was needed")
        elif ladder == "adjacent":
            notes.append("a mass chain driven next to its free end and measured there (or the reverse): of the ways "
                         "a solution could explain the response (a root of the numerator for the last element, a "
                         "pair of zeros of the last mass's dynamic stiffness, each left chain peeled as a continued "
                         "fraction) only θ*'s passes (a floating-point test with wide margins; "
                         "symid.structural.ladder_adjacent), so no Gröbner basis was needed")
        elif ladder:
            notes.append("a mass chain driven and measured at an interior mass: of the splits of the driving-point "
                         "impedance's poles between the two sides only θ*'s meets the necessary conditions (a "
                         "floating-point test with wide margins), and on it each side's continued fraction gives "
                         "its parameters (symid.structural.ladder_interior), so no Gröbner basis was needed")
        sol = {n: float(v) for n, v in theta_star.items()}
        every = dict.fromkeys(names, True)
        k_forms = range(len(linear_forms))
        return GlobalResult(summ.kind, summ.labels, tuple(summ.expressions()) if expressions else (), theta_star,
                            True, 1, 1, 1, (sol,), (sol,), every, dict(every), dict(every), (),
                            (True,) * len(crossed), 0, times, tuple(notes), engine="ladder" if ladder else "msolve",
                            linear_global=tuple(tuple(Fraction(int(i == k)) for i in k_forms) for k in k_forms))
    R, eqs, aux = _system(summ, params, pt)
    if msolve is not None and all(c is not None for c in crossed):
        found = _global_msolve(msolve, R, eqs, _aux_values(summ, pt), star, names, positive, rng.randrange(2**31),
                               candidates=crossed, forms=linear_forms)
        if found is not None:
            times["groebner"] = time.perf_counter() - t1
            n_c, n_r, n_a, sols, real_sols, glob_c, glob_r, glob_a, member_m, lin = found
            summary_exprs = tuple(summ.expressions()) if expressions else ()
            return GlobalResult(summ.kind, summ.labels, summary_exprs, theta_star, True, n_c, n_r, n_a, sols,
                                real_sols, glob_c, glob_r, glob_a, (), member_m, 0, times, tuple(notes),
                                engine="msolve", linear_global=lin)
    G = groebner(eqs, R)
    times["groebner"] = time.perf_counter() - t1
    nv = R.ngens
    theta_idx = list(range(len(params)))
    zero_dim = _is_zero_dimensional(G, nv)

    # -- candidates for identifiable functions from the basis ---------------------
    cands = []
    for g in G if expressions else ():
        if any(g.degree(R.gens[-1 - i]) > 0 for i in range(aux)):
            continue
        f = g - g.const()
        if f == R.zero:
            continue
        f = f.monic()
        cands.append(f.as_expr())

    def member(expr: sp.Expr) -> bool:
        num, den = sp.fraction(sp.together(expr))
        try:
            pn, pd = R.from_expr(num), R.from_expr(den)
        except (ValueError, sp.CoercionFailed):
            return False
        f = pn * pd(*pt, *([0] * aux)) - pd * pn(*pt, *([0] * aux))
        return f.rem(G) == R.zero

    membership = tuple(member(e) for e in extra_candidates)

    t2 = time.perf_counter()
    glob_c, glob_r, glob_a = {}, {}, {}
    sols, real_sols = [], []
    n_c = n_r = n_a = None
    lin: tuple = ()
    if not zero_dim:
        for i, name in enumerate(names):
            f = R.gens[i] - pt[i]
            glob_c[name] = _in_radical(G, R, f)
        glob_r = dict(glob_c)
        glob_a = dict(glob_c)
        if any(positive):
            notes.append("positive-dimensional solution set: positivity not used; per-parameter global "
                         "verdicts are over the complex numbers")
    else:
        basis = _standard_monomials([g.LM for g in G], nv, MAX_QUOTIENT)
        if basis is None:
            raise ExactStepLimit(f"more than {MAX_QUOTIENT} complex solutions; not enumerated")
        if len(basis) == 1:
            n_c = n_r = n_a = 1
            sol = {n: float(v) for n, v in theta_star.items()}
            sols, real_sols = [sol], [sol]
            glob_c = {n: True for n in names}
            glob_r = dict(glob_c)
            glob_a = dict(glob_c)
            k_forms = range(len(linear_forms))
            lin = tuple(tuple(Fraction(int(i == k)) for i in k_forms) for k in k_forms)
        else:
            mm = _mult_matrices(G, R, basis, range(nv))
            lin = _constant_forms(mm, linear_forms, names, pt)
            x = sp.Dummy("x")
            # a separating linear form with a square-free characteristic polynomial proves the ideal radical:
            # len(basis) distinct solutions, each simple (else θ* is where solutions merge: NonGenericPoint)
            sols_all, n_r = _solve_numeric(mm, theta_idx, rng, x)
            n_c = len(basis)
            eye = DomainMatrix.eye(n_c, QQ)
            for i, name in enumerate(names):  # radical: M_i is diagonalisable, single-valued iff M_i = θ_i* I
                glob_c[name] = (mm[i] - eye * pt[i]).is_zero_matrix
            for s in sols_all:
                if s["real"]:
                    real_sols.append({names[i]: s["values"][i] for i in theta_idx})
            for s in real_sols:
                if all(not positive[i] or s[names[i]] > POSITIVE_TOL for i in theta_idx):
                    sols.append(s)
            n_a = len(sols)

            def single(solset, name, i):
                ref = float(pt[i])
                return all(abs(s[name] - ref) <= REAL_TOL * max(1.0, abs(ref)) for s in solset)

            for i, name in enumerate(names):
                glob_r[name] = single(real_sols, name, i)
                glob_a[name] = single(sols, name, i)
            real_sols, sols = _canonical(real_sols, theta_star, glob_c), _canonical(sols, theta_star, glob_c)
    times["solutions"] = time.perf_counter() - t2
    summary_exprs = tuple(summ.expressions()) if expressions else ()
    return GlobalResult(summ.kind, summ.labels, summary_exprs, theta_star, zero_dim, n_c, n_r, n_a,
                        tuple(sols), tuple(real_sols), glob_c, glob_r, glob_a, tuple(cands), membership, len(G),
                        times, tuple(notes), linear_global=lin)


def _constant_forms(mm: dict[int, DomainMatrix], forms: Sequence[Mapping[str, Fraction]], names: Sequence[str],
                    pt) -> tuple:
    """A basis of the λ with Σ λ_k ℓ_k single-valued: Σ_k λ_k Σ_j a_kj (M_j − θ_j* I) = 0 (a radical ideal)."""
    if not forms:
        return ()
    D = mm[0].shape[0]
    eye = DomainMatrix.eye(D, QQ)
    cols = []
    for form in forms:
        acc = DomainMatrix.zeros((D, D), QQ)
        for name, a in form.items():
            if a:
                j = names.index(name)
                acc = acc + (mm[j] - eye * pt[j]) * QQ(Fraction(a).numerator, Fraction(a).denominator)
        cols.append([v for row in acc.to_list() for v in row])
    rows = [[c[i] for c in cols] for i in range(D * D)]
    kernel = DomainMatrix(rows, (D * D, len(forms)), QQ).nullspace().to_list()
    return tuple(tuple(Fraction(int(v.numerator), int(v.denominator)) for v in row) for row in kernel)


def _solve_numeric(mm: dict[int, DomainMatrix], theta_idx, rng: random.Random, x: sp.Symbol):
    """All solutions of a zero-dimensional ideal from its multiplication matrices, and the number of real ones.

    The characteristic polynomial of a random linear form ℓ (exact) must be square-free of
    degree D, the quotient dimension: then ℓ takes D distinct values, so there are D
    distinct solutions, each simple (the ideal is radical). Else :class:`NonGenericPoint`.
    """
    nv = len(mm)
    D = mm[0].shape[0]
    F = {v: np.array([[float(c) for c in row] for row in mm[v].to_list()]) for v in range(nv)}
    for _ in range(3):
        r = [rng.randint(1, 10**6) for _ in range(nv)]
        Ml = sum((mm[v] * QQ(r[v]) for v in range(1, nv)), mm[0] * QQ(r[0]))
        cp = _charpoly_expr(Ml, x)
        if cp.degree() == D and _square_free(cp, x):
            break
    else:  # three random forms (coefficients up to 1e6) fail to separate only at a multiple solution
        raise NonGenericPoint(_multiple_solution(D))
    Fl = sum(r[v] * F[v] for v in range(nv))
    w, vecs = np.linalg.eig(Fl.T)
    real = _certified_real(cp, w)
    out = []
    for k in np.argsort(~real, kind="stable"):
        vec = vecs[:, k]
        vals = []
        for v in range(nv):
            num = np.vdot(vec, F[v].T @ vec)
            vals.append(num / np.vdot(vec, vec))
        out.append({"real": bool(real[k]), "values": [float(np.real(vals[v])) if real[k] else complex(vals[v])
                                                      for v in range(nv)]})
    return out, int(real.sum())


def _certified_real(cp: sp.Poly, w: np.ndarray) -> np.ndarray:
    """Which eigenvalues ``w`` of ℓ's multiplication matrix are real, each proven by an exact sign change of ``cp``.

    ``cp`` (square-free, its roots the values of ℓ at the solutions) changes sign on a
    small rational interval around each numerically real eigenvalue, the intervals
    pairwise disjoint: an odd number of real roots in each, so at least one real
    solution per interval (ℓ separates the solutions, so a real value of ℓ is a real
    solution). Faster than a Sturm sequence, whose coefficients grow with θ*'s. An
    eigenvalue not so proven is counted as not real (the count is then a lower bound;
    for a simple real root it is exact).
    """
    real = np.zeros(len(w), dtype=bool)
    cand = [k for k in range(len(w)) if abs(w[k].imag) <= 1e-6 * max(1.0, abs(w[k]))]
    cand.sort(key=lambda k: w[k].real)
    xs = [w[k].real for k in cand]
    for j, k in enumerate(cand):
        gap = min([abs(xs[j] - xs[i]) for i in (j - 1, j + 1) if 0 <= i < len(xs)] or [1.0])
        delta = min(1e-6 * max(1.0, abs(xs[j])), gap / 3)
        if delta <= 0:
            continue
        lo, hi = sp.Rational(xs[j] - delta), sp.Rational(xs[j] + delta)
        a, b = cp.eval(lo), cp.eval(hi)
        real[k] = (a < 0 < b) or (b < 0 < a)
    return real


def _multiple_solution(degree: int) -> str:
    return f"{degree} solutions counted with multiplicity but fewer distinct ones: a multiple solution"


def _canonical(solutions: list[dict], theta_star: Mapping[str, sp.Rational],
               single: Mapping[str, bool]) -> tuple[dict, ...]:
    """Solutions in a canonical order (by their values to 6 digits), θ* itself and the parameters single-valued over
    every complex solution (``single``) given exactly.

    The engines compute the other values differently (eigenvectors in float64, or the
    midpoints of msolve's 128-bit boxes): their floats agree to rounding, not bit for bit.
    """
    exact = {n: float(v) for n, v in theta_star.items()}
    out = []
    for s in solutions:
        if all(abs(s[n] - exact[n]) <= REAL_TOL * max(1.0, abs(exact[n])) for n in exact):
            s = dict(exact)
        else:
            s = {n: exact[n] if single.get(n) else v for n, v in s.items()}
        out.append(s)
    return tuple(sorted(out, key=lambda s: tuple(float(f"{s[n]:.6g}") for n in exact)))


MSOLVE_PRECISIONS = (128, 1024, 8192)
"""Bits of msolve's real-root boxes (``-p``): a box that straddles 0 in a coordinate whose sign matters, and is not
shown to be an exact zero (:func:`_exact_zeros`), is computed again at the next precision."""


def _square_free_int(coeffs: Sequence[int]) -> bool:
    x = sp.Dummy("x")
    return _square_free(sp.Poly(list(reversed(coeffs)), x, domain="QQ"), x)


def _square_free_mod(coeffs: Sequence[int], p: int) -> bool:
    """Whether a polynomial over GF(p) (coefficients by increasing degree) is square-free: gcd(f, f') = 1."""
    def trim(f):
        while f and f[-1] % p == 0:
            f = f[:-1]
        return f

    def rem(a, b):
        a = list(a)
        inv = pow(b[-1], -1, p)
        while len(a) >= len(b):
            q = a[-1] * inv % p
            shift = len(a) - len(b)
            for i, c in enumerate(b):
                a[shift + i] = (a[shift + i] - q * c) % p
            a = trim(a)
        return a

    f = trim([c % p for c in coeffs])
    g = trim([k * c % p for k, c in enumerate(f)][1:])
    if not g:
        return len(f) <= 1
    while g:
        f, g = g, rem(f, g)
    return len(f) == 1


def _cross_terms(expr, params, point) -> list[tuple[dict[str, int], Fraction]] | None:
    """Terms of P·Q(θ*) − Q·P(θ*) for a rational function f = P/Q of ``params`` (None when f is not one).

    f(θ) − f(θ*) vanishes on a solution where Q ≠ 0 iff this polynomial does (the membership of
    the sympy path, cross-multiplied the same way).

    Examples
    --------
    >>> import sympy as sp
    >>> from fractions import Fraction
    >>> from symid.structural.global_ import _cross_terms
    >>> a, b = sp.symbols("a b")
    >>> _cross_terms(a / b, [a, b], [Fraction(2), Fraction(3)])
    [({'a': 1}, Fraction(3, 1)), ({'b': 1}, Fraction(-2, 1))]
    """
    num, den = sp.fraction(sp.together(sp.sympify(expr)))
    try:
        P, Q = sp.Poly(num, *params, domain="QQ"), sp.Poly(den, *params, domain="QQ")
    except (sp.PolynomialError, sp.CoercionFailed, sp.GeneratorsNeeded):
        return None
    vals = [sp.Rational(v.numerator, v.denominator) for v in point]
    g = P * Q.eval(dict(zip(params, vals, strict=True))) - Q * P.eval(dict(zip(params, vals, strict=True)))
    names = [q.name for q in params]
    return [({n: e for n, e in zip(names, mono, strict=True) if e}, Fraction(int(c.p), int(c.q)))
            for mono, c in g.terms() if c != 0]


def _degree_mod_p(binary: str, summ, params, star: Sequence[Fraction], rng: random.Random) -> int | None:
    """The number of solutions of summary(θ) = summary(θ*), by msolve modulo a random prime; None if not settled.

    The system is built modulo a random prime p in [2³⁰, :data:`MAX_PRIME`)
    (:func:`_system_mod_p`) and msolve's parametrization over GF(p) read: its degree when
    the ideal there is finite and radical (deg w = the degree: every solution simple), after
    checking that θ* is one of its solutions (an answer that is not this system's raises
    :class:`~symid.structural.msolve.MsolveError`). Over ℚ the count is the same unless p is
    one of the finitely many primes at which the computation degenerates (a random 30-bit
    prime: the same Monte Carlo argument as msolve's multi-modular answer over ℚ; a global
    claim is confirmed at an independent point θ** modulo another prime). None (then the
    computation over ℚ decides): a prime that divides a denominator, a positive-dimensional
    or non-radical ideal modulo p.
    """
    modulus = _mod_p_modulus(rng)
    seed = rng.randrange(2**31)
    try:
        nvars, eqs, point = _system_mod_p(summ, params, star, modulus)
    except BadPrime:
        return None
    var = [f"x{i}" for i in range(nvars)]
    out = parse_output(run_msolve(binary, input_text(eqs, nvars, modulus), options=("-P", "2"), seed=seed),
                       var, modulus)
    if out.status != "finite" or out.param.n_distinct != out.param.degree:
        return None
    if out.param.degree > 1 and not _square_free_mod(out.param.elim, modulus):
        return None
    out.param.check_point(dict(zip(var, point, strict=True)))
    return out.param.degree


def _orbit_result(summ, summary_exprs, theta_star, names, positive, points, crossed, linear_forms, times,
                  notes) -> GlobalResult:
    """The global result when the solutions are the orbit of θ* under exact symmetries (exact rationals)."""
    star = points[0]
    admissible = [x for x in points if all(not pos or v > 0 for v, pos in zip(x, positive, strict=True))]

    def single(pts) -> dict[str, bool]:
        return {n: all(x[i] == star[i] for x in pts) for i, n in enumerate(names)}

    def as_dict(x) -> dict[str, float]:
        return {n: float(v) for n, v in zip(names, x, strict=True)}

    glob_c = single(points)
    index = {n: i for i, n in enumerate(names)}

    def value(terms, x) -> Fraction:
        acc = Fraction(0)
        for expo, c in terms:
            t = Fraction(c)
            for n, e in expo.items():
                t *= x[index[n]] ** e
            acc += t
        return acc

    member = tuple(all(value(terms, x) == 0 for x in points) for terms in crossed)
    lin: tuple = ()
    if linear_forms:
        rows = [[QQ(Fraction(d).numerator, Fraction(d).denominator) for d in
                 (sum((Fraction(a) * (x[index[n]] - star[index[n]]) for n, a in form.items()), Fraction(0))
                  for form in linear_forms)] for x in points[1:]]
        if rows:
            kernel = DomainMatrix(rows, (len(rows), len(linear_forms)), QQ).nullspace().to_list()
        else:
            kernel = [[QQ(int(i == k)) for i in range(len(linear_forms))] for k in range(len(linear_forms))]
        lin = tuple(tuple(Fraction(int(v.numerator), int(v.denominator)) for v in row) for row in kernel)
    return GlobalResult(summ.kind, summ.labels, summary_exprs, theta_star, True, len(points), len(points),
                        len(admissible), tuple(_canonical([as_dict(x) for x in admissible], theta_star, glob_c)),
                        tuple(_canonical([as_dict(x) for x in points], theta_star, glob_c)), glob_c, dict(glob_c),
                        single(admissible), (), member, 0, times, tuple(notes), engine="msolve", linear_global=lin)


def _global_msolve(binary: str, R: PolyRing, eqs, aux: Sequence[Fraction], star, names: Sequence[str],
                   positive: Sequence[bool], seed: int, candidates: Sequence[Sequence[tuple]] = (),
                   forms: Sequence[Mapping[str, Fraction]] = ()):
    """msolve's answer at θ* over ℚ: (n_complex, n_real, n_admissible, admissible, real, global per parameter over
    complex / real / admissible solutions, per candidate whether its cross-multiplied form (:func:`_cross_terms`)
    vanishes on every complex solution), or None for a positive-dimensional set (then sympy decides)."""
    var = [f"x{i}" for i in range(R.ngens)]
    text = input_text([dict(p.terms()) for p in eqs], R.ngens, 0)
    exact = [Fraction(int(v.p), int(v.q)) for v in star]
    point = dict(zip(var, [*exact, *aux], strict=True))
    tol = [REAL_TOL * max(1.0, abs(float(v))) for v in exact]
    for prec in MSOLVE_PRECISIONS:
        out = parse_output(run_msolve(binary, text, options=("-P", "1", "-p", str(prec)), seed=seed), var, 0)
        if out.status == "positive-dimensional":
            return None
        if out.status == "empty":
            raise MsolveError("msolve found no solution of summary(θ) = summary(θ*), but θ* is one: its answer is "
                              "wrong")
        par = out.param
        if par.degree > MAX_QUOTIENT:
            raise ExactStepLimit(f"more than {MAX_QUOTIENT} complex solutions; not enumerated")
        if par.n_distinct != par.degree or not _square_free_int(par.elim):
            raise NonGenericPoint(_multiple_solution(par.degree))
        par.check_point(point)
        if par.real_points is None:
            raise MsolveError("msolve did not list the real solutions")
        boxes = [[box[var[i]] for i in range(len(names))] for box in par.real_points]
        if not any(all(lo <= v <= hi for (lo, hi), v in zip(b, exact, strict=True)) for b in boxes):
            raise MsolveError("θ* is not among msolve's real solutions: its answer is inconsistent with the system")
        zero = _exact_zeros(par, var, boxes, positive)
        settled = all(lo > 0 or hi <= 0 or (k, j) in zero for k, b in enumerate(boxes)
                      for j, ((lo, hi), pos) in enumerate(zip(b, positive, strict=True)) if pos)
        if settled:
            break
    else:
        raise ExactStepLimit(f"the sign of a coordinate of a real solution was not decided at {MSOLVE_PRECISIONS[-1]} "
                             "bits (it may be exactly 0)")
    real, adm, moved_r, moved_a = [], [], set(), set()
    for k, b in enumerate(boxes):
        vals = {n: 0.0 if (k, j) in zero else float((lo + hi) / 2) for j, (n, (lo, hi)) in enumerate(zip(names, b,
                                                                                                      strict=True))}
        ok = all(lo > 0 and (k, j) not in zero for j, ((lo, _), pos) in enumerate(zip(b, positive, strict=True))
                 if pos)
        moved = {n for n, (lo, hi), v, t in zip(names, b, exact, tol, strict=True) if hi < v - t or lo > v + t}
        real.append(vals)
        moved_r |= moved
        if ok:
            adm.append(vals)
            moved_a |= moved
    glob_c = {n: par.single_valued(var[i], exact[i]) for i, n in enumerate(names)}
    theta_star = dict(zip(names, star, strict=True))
    index = {n: i for i, n in enumerate(names)}
    member = tuple(par.vanishes([({var[index[n]]: e for n, e in expo.items()}, c) for expo, c in terms])
                   for terms in candidates)
    lin = tuple(tuple(row) for row in par.constant_forms(
        [{var[index[n]]: a for n, a in form.items()} for form in forms],
        {var[index[n]]: v for n, v in zip(names, exact, strict=True)})) if forms else ()
    return (par.n_distinct, len(real), len(adm), _canonical(adm, theta_star, glob_c),
            _canonical(real, theta_star, glob_c), glob_c, {n: n not in moved_r for n in names},
            {n: n not in moved_a for n in names}, member, lin)


def _exact_zeros(par, var: Sequence[str], boxes, positive: Sequence[bool]) -> set[tuple[int, int]]:
    """(solution, coordinate) pairs whose box contains 0 and whose coordinate is exactly 0, for positive coordinates.

    x_j = −v_j(ϑ)/(c_j w'(ϑ)) vanishes exactly on the roots of g = gcd(w, v_j) (ϑ itself: on ϑ = 0). When g has as
    many real roots as there are boxes of x_j that contain 0, those boxes are the exact zeros (each real root of g
    is a real solution with x_j = 0, whose box contains 0); otherwise none is settled here (a finer box will be).
    """
    out: set[tuple[int, int]] = set()
    x = sp.Dummy("x")
    w = sp.Poly(list(reversed(par.elim)), x, domain="ZZ")
    for j, pos in enumerate(positive):
        if not pos:
            continue
        near = [k for k, b in enumerate(boxes) if b[j][0] <= 0 <= b[j][1]]
        if not near or all(boxes[k][j][1] <= 0 for k in near):
            continue
        if var[j] == par.parameter:
            n_zero = 1 if par.elim[0] == 0 else 0
        else:
            v = par.coords[var[j]][0]
            g = w if not v else w.gcd(sp.Poly(list(reversed(v)), x, domain="ZZ"))
            n_zero = g.count_roots() if g.degree() > 0 else 0
        if n_zero == len(near):
            out.update((k, j) for k in near)
    return out


def _confirm_msolve(binary: str, nvars: int, eqs: Sequence[dict], star, names: Sequence[str], modulus: int,
                    seed: int, cancel: threading.Event | None = None):
    """msolve's answer at θ** over GF(p) for the system of :func:`_system_mod_p`: (True, count, single-valued per
    parameter), or None when the ideal is not radical modulo p or not zero-dimensional there (then sympy decides)."""
    var = [f"x{i}" for i in range(nvars)]
    text = input_text(eqs, nvars, modulus)
    out = parse_output(run_msolve(binary, text, options=("-P", "2"), seed=seed, cancel=cancel), var, modulus)
    if out.status != "finite":
        return None
    par = out.param
    if par.degree > MAX_QUOTIENT:
        return True, None, dict.fromkeys(names, False)
    if par.n_distinct != par.degree or not _square_free_mod(par.elim, modulus):
        return None
    single = {n: par.single_valued(var[i], Fraction(int(v.p), int(v.q))) for i, (n, v) in
              enumerate(zip(names, star, strict=True))}
    return True, par.degree, single


PARTIAL_ABOVE = 24
"""With ``settle``, a partial orbit is used only above this many solutions (the exact step over ℚ, which also
decides the combinations' global flags, costs 0.1 s at 6-24 solutions and 3-12 s at 120 on the compartment
families)."""
EXTRA_POINTS = 6
"""Further random points tried for a parameter whose other complex values are not admissible at θ*, and for the
single-valued linear combinations (:func:`_at_more_points`)."""


def _intersect(U: Sequence[Sequence[Fraction]], V: Sequence[Sequence[Fraction]], n: int) -> list[list[Fraction]]:
    """A basis of span(U) ∩ span(V) (rows of length n): the vectors orthogonal to both annihilators."""
    def ann(rows):
        if not rows:
            return [[QQ(int(i == k)) for i in range(n)] for k in range(n)]
        M = DomainMatrix([[QQ(Fraction(v).numerator, Fraction(v).denominator) for v in r] for r in rows],
                         (len(rows), n), QQ)
        return M.nullspace().to_list()

    N = ann(U) + ann(V)
    if not N:
        return [[Fraction(int(i == k)) for i in range(n)] for k in range(n)]
    basis = DomainMatrix(N, (len(N), n), QQ).nullspace().to_list()
    return [[Fraction(int(v.numerator), int(v.denominator)) for v in row] for row in basis]


def _at_more_points(res: GlobalResult, model, known, positive, seed: int, rank, msolve, summary, linear_forms,
                    extra_known=None, only=None) -> GlobalResult:
    """What one point θ* cannot settle, looked at in up to :data:`EXTRA_POINTS` more random points.

    * A parameter single-valued on the admissible solutions at θ* but not on the complex
      ones: two admissible solutions that differ in it at another point prove it not
      globally identifiable (they are simple, so they persist near that point):
      ``local_elsewhere`` (only the parameters in ``only``, when given).
    * The single-valued combinations of the linear forms: whether a *given* function is
      single-valued is decided at one generic point, but the combinations found by solving
      for the coefficients at θ* are those single-valued at that point, a space that can be
      larger than the structural one (with two solutions, any combination orthogonal to
      their difference qualifies). It is intersected with the same at further points until
      one more point leaves it unchanged; what remains does not depend on the point.
    """
    finite = res.zero_dimensional and res.n_complex is not None
    open_ = [n for n, single in res.global_complex.items() if not single and res.global_admissible.get(n, False)
             and (only is None or n in only)] if finite else []
    n_forms = len(linear_forms)
    space = None if res.linear_global is None else [list(r) for r in res.linear_global]
    linear_open = space is not None and 0 < len(space) < n_forms  # empty, or all forms (one solution): settled
    found: dict[str, dict] = {}
    for k in range(EXTRA_POINTS):
        if not open_ and not linear_open:
            break
        known_k = known if extra_known is None else extra_known[k]
        try:
            prepared = star_and_summary(model, known_k, seed=seed, draw=100 + k, rank=rank,
                                        summary=summary if extra_known is None else None)
            other = global_analysis(model, known_k, positive=positive, seed=seed, expressions=False,
                                    prepared=prepared, msolve=msolve, linear_forms=linear_forms if linear_open else ())
        except NonGenericPoint:
            continue
        for n in list(open_):
            if not other.global_admissible.get(n, True):
                fixed = {} if extra_known is None else {q: str(v) for q, v in extra_known[k].items()
                                                         if (known or {}).get(q) != v}
                found[n] = {**fixed, **{q: str(v) for q, v in other.theta_star.items()}}
                open_.remove(n)
        if linear_open:
            if other.linear_global is None:
                space, linear_open = None, False
            else:
                smaller = _intersect(space, other.linear_global, n_forms)
                linear_open = 0 < len(smaller) < len(space)
                space = smaller
    res = replace(res, linear_global=None if space is None else tuple(tuple(r) for r in space))
    if not found:
        return res
    points: dict[str, list[str]] = {}
    for n, pt in found.items():
        points.setdefault(", ".join(f"{q} = {v}" for q, v in pt.items()), []).append(n)
    where = "; ".join(f"{', '.join(ns)} at θ = ({pt})" for pt, ns in points.items())
    note = (f"{', '.join(found)}: a single value on the admissible solutions at θ* but not on the complex ones; at "
            f"another random point two admissible solutions differ in {'it' if len(found) == 1 else 'each'} "
            f"(proven not global): {where}")
    return replace(res, local_elsewhere=found, notes=(*res.notes, note))


class _Ahead:
    """A call run in a thread once a core is spare (``spare.wait``), for a result that may not be wanted.

    :meth:`take` decides: a call not started by then never starts (None); with
    ``wanted=True`` a started call is waited for and its result returned (None where its
    msolve did not decide); with ``wanted=False`` it is cancelled (the call gets
    ``cancel=``, a ``threading.Event`` that kills its msolve run).
    """

    def __init__(self, spare: Any, fn: Callable[..., Any], kwargs: dict):
        self._lock = threading.Lock()
        self._cancel = threading.Event()
        self._closed = False
        self._started = False
        self._result: Any = None
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, args=(spare, fn, kwargs), daemon=True,
                                        name="symid-confirm-ahead")
        self._thread.start()

    def _run(self, spare: Any, fn: Callable[..., Any], kwargs: dict) -> None:
        while True:
            free = spare.wait(0.02)
            with self._lock:
                if self._closed:
                    return
                if free:
                    self._started = True
                    break
        try:
            self._result = fn(**kwargs, cancel=self._cancel)
        except MsolveCancelled:
            pass
        except BaseException as exc:  # raised where the result is taken
            self._error = exc

    def take(self, *, wanted: bool) -> Any:
        with self._lock:
            self._closed = True
            started = self._started
        if not wanted:
            self._cancel.set()
        self._thread.join()
        if not (started and wanted):
            return None
        if self._error is not None:
            raise self._error
        return self._result


def _claims_global(res: GlobalResult) -> bool:
    return (res.zero_dimensional and res.n_complex == 1) or any(res.global_complex.values())


def generic_global(model, known: Mapping[str, object] | None = None, *, positive: Sequence[bool] | None = None,
                   seed: int = 0, rank: int | None = None, extra_candidates: Sequence[sp.Expr] = (),
                   expressions: bool = True, msolve: str | None = None,
                   confirm_known: Mapping[str, object] | None = None,
                   linear_forms: Sequence[Mapping[str, Fraction]] = (),
                   extra_known: Sequence[Mapping[str, object]] | None = None,
                   local_only: Sequence[str] | None = None, settle: Sequence[str] | None = None,
                   spare_core: Any = None) -> GlobalResult:
    """:func:`global_analysis` at a θ* checked to be generic, and its global claims confirmed at a second point.

    1. θ* is drawn (:func:`draw_point`) until the Jacobian has the generic rank
       ``rank`` at θ* itself (a rank drop is where solutions merge), and the global
       step is redone at a new θ* when summary(θ) = summary(θ*) has a multiple
       solution (the quotient algebra is larger than the number of distinct solutions);
    2. when the result claims anything global (a single complex solution, or a
       parameter with a single value over every complex solution), the step is
       repeated at an independent generic point θ** modulo a random prime
       (:func:`confirm_mod_p`), and a parameter is global only when it is at both
       points.

    ``msolve``: path of an msolve program, used (at θ* and θ**) when the Jacobian has
    full rank (``rank`` = the number of free parameters: finitely many solutions); the
    result is the same as sympy's (module docstring), ``engine`` says which ran.
    ``confirm_known``: the known values at θ** (default ``known``; the slices of
    :mod:`~symid.structural.slicing` give their cut parameters other values there).
    ``linear_forms``: as for :func:`global_analysis` (decided at θ* only).
    A parameter single-valued on the admissible solutions at θ* but not on the complex
    ones is looked at in :data:`EXTRA_POINTS` more random points (``extra_known``: the
    known values at each; default ``known``): two admissible solutions that differ in it
    there prove it not global (``local_elsewhere``; only the parameters named in
    ``local_only``, when given). ``settle``: as for :func:`global_analysis`.
    ``spare_core``: a flag (``threading.Event`` or :class:`~symid.structural.steps.SpareFlag`) set when a processor
    core is free; with msolve, the confirmation at θ** then starts beside the step at θ*
    (its msolve in a process of its own), and is used when θ* claims anything global
    (otherwise stopped). The result is the same as without it, only sooner.

    Examples
    --------
    >>> import symid as si
    >>> from symid.structural.global_ import generic_global
    >>> a, b = si.parameters("a b")
    >>> res = generic_global(si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[1]]), rank=2)
    >>> res.n_complex, res.confirmed, sorted(res.global_complex.items())
    (1, True, [('a', True), ('b', True)])
    """
    notes: list[str] = []
    res = None
    ahead: _Ahead | None = None
    confirm_args = {"known": known if confirm_known is None else confirm_known, "seed": seed, "draw": 500,
                    "rank": rank}
    try:
        for draw in range(MAX_DRAWS):
            prepared = star_and_summary(model, known, seed=seed, draw=draw, rank=rank)
            if msolve is not None and rank != len(prepared[0]):
                msolve = None  # infinitely many solutions: sympy (radical membership, basis candidates)
            if draw == 0 and msolve is not None and spare_core is not None:
                ahead = _Ahead(spare_core, confirm_mod_p, {"model": model, **confirm_args, "msolve": msolve,
                                                           "summary": prepared[3] if confirm_known is None else None,
                                                           "msolve_only": True})
            try:
                res = global_analysis(model, known, positive=positive, seed=seed, extra_candidates=extra_candidates,
                                      expressions=expressions, prepared=prepared, msolve=msolve,
                                      linear_forms=linear_forms, settle=settle)
                break
            except NonGenericPoint as exc:
                star = ", ".join(str(v) for v in prepared[1])
                notes.append(f"θ* = ({star}) was not generic ({exc}); drawn again")
        if res is None:
            raise ExactStepLimit(f"no generic point θ* in {MAX_DRAWS} random draws")
        draws = draw + 1
        res = _at_more_points(res, model, known, positive, seed, rank, msolve, prepared[3], linear_forms,
                              extra_known, local_only)
        if not _claims_global(res):
            return replace(res, notes=(*res.notes, *notes), draws=draws)
        # the run started beside θ* had the same arguments as this call when θ* was the first draw and msolve
        # or a chain's inversion decided there (the inversion is tried first at θ** too, whatever the engine);
        # otherwise (or when it never started for want of a spare core) the confirmation runs now (a run not
        # wanted is always closed here: its thread must not outlive this call in a child process)
        found = ahead.take(wanted=draws == 1 and res.engine in ("msolve", "ladder")) if ahead is not None else None
        ahead = None
        if found is None:
            found = confirm_mod_p(model, **confirm_args, msolve=msolve if res.engine == "msolve" else None,
                                  summary=prepared[3] if confirm_known is None else None)
        zero2, count2, single2, theta2 = found
    finally:
        if ahead is not None:
            ahead.take(wanted=False)
    glob_c = {k: v and single2.get(k, False) for k, v in res.global_complex.items()}
    agree = glob_c == res.global_complex and zero2 == res.zero_dimensional and count2 == res.n_complex
    if not agree:
        notes.append(f"the independent point θ** gave a different result ({count2} solutions there counted with "
                     f"multiplicity, modulo a prime; {res.n_complex} at θ*): only the parameters single-valued at "
                     "both points are global")
        glob_r = {k: v and glob_c[k] for k, v in res.global_real.items()}
        glob_a = {k: v and glob_c[k] for k, v in res.global_admissible.items()}
        n_c = res.n_complex
        if count2 is None or (n_c is not None and count2 > n_c) or (zero2 != res.zero_dimensional):
            n_c = None if (count2 is None or not zero2) else count2
        res = replace(res, global_complex=glob_c, global_real=glob_r, global_admissible=glob_a, n_complex=n_c,
                      zero_dimensional=res.zero_dimensional and zero2)
    return replace(res, notes=(*res.notes, *notes), theta_confirm=theta2, confirmed=agree, draws=draws)
