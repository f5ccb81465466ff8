"""Global identifiability by an explicit rational formula in a few summary entries.

If θ_j = P(c_S(θ)) / Q(c_S(θ)) identically, with c_S a few entries of an exhaustive
summary (what the input-output map determines) and P, Q polynomials with rational
coefficients, then θ_j is a rational function of the input-output map: single-valued on
every complex solution of summary(θ) = summary(θ*) wherever Q(c_S) ≠ 0 — globally
identifiable, with no Gröbner basis. Example: the mass chain with the force on mass 1 and
the sensor on mass n, where the exact step meets hundreds of solutions, has
k1 = c[d s^0] / c[N s^0] (H(0) = 1/k1) and
c1 = (c[d s^1] c[N s^0] − c[d s^0] c[N s^1]) / c[N s^0]² (1/H(s) = k1 + c1 s + O(s²)),
the second not a monomial in the entries.

Method (a guess, then an exact check; only the check proves anything):

1. the entries: at a random point modulo a 31-bit prime, the gradients ∇c_k; entries are
   added, fewest terms first, while they raise the rank, until ∇θ_j (a unit vector) lies
   in their span, then removed again where it stays in the span — a minimal set S whose
   gradients are independent (so the entries of S are algebraically independent and a
   relation θ_j Q(c_S) = P(c_S) has Q ≠ 0);
2. the formula: for degree D = 1, 2, …, the unknown coefficients of P and Q over the
   monomials of degree ≤ D in c_S solve a linear system, one row per random point
   (θ_j Q(c_S) − P(c_S) = 0 there), modulo the prime; a null vector is lifted to small
   rationals (rational reconstruction);
3. the check, exact in ℚ[θ]: θ_j · Q̃ = P̃, with P̃, Q̃ the formula multiplied out by
   Π_k d_k^D (c_k = n_k / d_k), and Q̃ ≠ 0.
"""

from __future__ import annotations

import random
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from itertools import combinations_with_replacement

import numpy as np

from symid.structural.modp import PRIME, residue, term_values

__all__ = ["RationalFormula", "rational_formulas"]

_P = PRIME
"""The prime of the linear algebra (largest below 2³¹: products of two residues fit in int64)."""
MAX_UNKNOWNS = 80
"""Formulas with more unknown coefficients (2 × monomials of degree ≤ D in |S| entries) are not tried."""
MAX_TERMS = 20_000
"""A formula whose multiplied-out sides exceed this many terms is not checked (and so not used)."""
MAX_ENTRY_TERMS = 2_000
"""Entry sets whose numerators and denominators have more terms in all are not tried (the products to check grow
with them)."""


@dataclass(frozen=True)
class RationalFormula:
    """θ_j = P(c_S) / Q(c_S): ``numerator`` and ``denominator`` map exponent tuples over ``entries`` to coefficients."""

    parameter: str
    entries: tuple
    numerator: dict
    denominator: dict

    def text(self, labels: Sequence[str]) -> str:
        """The formula with the summary entries named by their labels (``c[d s^0]`` …)."""
        def poly(coeffs: dict) -> str:
            parts = []
            for mono, c in sorted(coeffs.items(), key=lambda kv: (-sum(kv[0]), kv[0])):
                factors = [f"c[{labels[k]}]" + (f"^{e}" if e > 1 else "") for k, e in zip(self.entries, mono,
                                                                                           strict=True) if e]
                coef = "" if c == 1 and factors else ("-" if c == -1 and factors else str(c))
                parts.append(coef + ("·" if coef and coef != "-" and factors else "") + "·".join(factors))
            return " + ".join(parts).replace("+ -", "- ") or "0"
        return f"{self.parameter} = ({poly(self.numerator)}) / ({poly(self.denominator)})"


class _ModEvaluator:
    """Values and gradients modulo the prime of polynomials given by their terms, vectorised over terms."""

    def __init__(self, polys, nv: int):
        self.nv = nv
        sizes = [len(t) for t in polys]
        self.starts = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        self.E = np.array([m for t in polys for m, _ in t], dtype=np.int64).reshape(-1, nv)
        self.c = np.array([residue(c, _P) for t in polys for _, c in t], dtype=np.int64)

    def _sums(self, x: np.ndarray) -> np.ndarray:
        out = np.zeros(len(self.starts) - 1, dtype=np.int64)
        for k, (a, b) in enumerate(zip(self.starts[:-1], self.starts[1:], strict=True)):
            if b > a:
                out[k] = int(x[a:b].sum()) % _P  # < 2³¹ terms of < 2³¹ each: no overflow below 2⁶²
        return out

    def terms(self, pt: Sequence[int]) -> np.ndarray:
        return term_values(self.E, self.c, pt, _P)

    def values(self, pt: Sequence[int]) -> np.ndarray:
        return self._sums(self.terms(pt))

    def gradients(self, pt: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
        """Values (n_polys,) and gradients (n_polys, nv) at pt (no zero coordinate)."""
        t = self.terms(pt)
        grads = np.empty((len(self.starts) - 1, self.nv), dtype=np.int64)
        for v in range(self.nv):
            inv = pow(int(pt[v]), -1, _P)
            grads[:, v] = self._sums(t * (self.E[:, v] % _P) % _P) * inv % _P
        return self._sums(t), grads


def _reduce(rows: list[np.ndarray], v: np.ndarray) -> np.ndarray:
    """v reduced against an echelon basis ``rows`` (each with its pivot normalised to 1) modulo the prime."""
    v = v % _P
    for r in rows:
        piv = int(np.flatnonzero(r)[0])
        if v[piv]:
            v = (v - int(v[piv]) * r) % _P
    return v


def _echelon_add(rows: list[np.ndarray], v: np.ndarray) -> bool:
    """Add v to the echelon basis if independent (kept sorted by pivot); whether it was."""
    v = _reduce(rows, v)
    nz = np.flatnonzero(v)
    if len(nz) == 0:
        return False
    v = v * pow(int(v[nz[0]]), -1, _P) % _P
    for i, r in enumerate(rows):  # keep the basis reduced: clear v's pivot from the others
        if r[nz[0]]:
            rows[i] = (r - int(r[nz[0]]) * v) % _P
    rows.append(v)
    return True


def _in_span(vectors: list[np.ndarray], target: np.ndarray) -> bool:
    rows: list[np.ndarray] = []
    for v in vectors:
        _echelon_add(rows, v)
    return not np.any(_reduce(rows, target))


def _entry_set(grads: np.ndarray, j: int, order: Sequence[int]) -> list[int] | None:
    """A minimal set of entries whose gradients span the unit vector e_j (see the module notes)."""
    nv = grads.shape[1]
    e_j = np.zeros(nv, dtype=np.int64)
    e_j[j] = 1
    rows: list[np.ndarray] = []
    chosen: list[int] = []
    for k in order:
        if _echelon_add(rows, grads[k]):
            chosen.append(k)
            if not np.any(_reduce(rows, e_j)):
                break
    else:
        return None
    for k in list(reversed(chosen)):  # prune
        rest = [c for c in chosen if c != k]
        if _in_span([grads[c] for c in rest], e_j):
            chosen = rest
    return sorted(chosen)


def _null_vector(A: np.ndarray) -> np.ndarray | None:
    """A nonzero vector of the null space of A modulo the prime (the last free column set to 1), or None."""
    A = A % _P
    m, n = A.shape
    pivots = []
    r = 0
    for c in range(n):
        nz = np.flatnonzero(A[r:, c])
        if len(nz) == 0:
            continue
        p = r + int(nz[0])
        A[[r, p]] = A[[p, r]]
        A[r] = A[r] * pow(int(A[r, c]), -1, _P) % _P
        others = np.flatnonzero(A[:, c])
        others = others[others != r]
        if len(others):
            A[others] = (A[others] - (A[others, c][:, None] * A[r][None, :]) % _P) % _P
        pivots.append(c)
        r += 1
        if r == m:
            break
    free = [c for c in range(n) if c not in pivots]
    if not free:
        return None
    f = free[-1]
    x = np.zeros(n, dtype=np.int64)
    x[f] = 1
    for i, c in enumerate(pivots):
        x[c] = (-A[i, f]) % _P
    return x


def _lift(v: int) -> Fraction | None:
    """The rational a/b ≡ v modulo the prime with |a|, b ≤ √(p/2) (Wang's reconstruction), or None."""
    bound = int((_P // 2) ** 0.5)
    r0, r1, s0, s1 = _P, v % _P, 0, 1
    while r1 > bound:
        q = r0 // r1
        r0, r1, s0, s1 = r1, r0 - q * r1, s1, s0 - q * s1
    if s1 == 0 or abs(s1) > bound:
        return None
    return Fraction(r1, s1)


def _monomials(k: int, degree: int) -> list[tuple[int, ...]]:
    out = []
    for d in range(degree + 1):
        for combo in combinations_with_replacement(range(k), d):
            out.append(tuple(combo.count(i) for i in range(k)))
    return out


def _check(summ, j: int, entries: Sequence[int], monos, num: dict, den: dict, degree: int, at) -> bool:
    """θ_j · Q̃ == P̃ exactly, Q̃ ≠ 0 (both sides multiplied by Π_k d_k^degree), and Q̃, d_k ≠ 0 at ``at``."""
    R = summ.ring
    ns = [summ.numerators[k] for k in entries]
    ds = [summ.denominators[k] for k in entries]
    cache: dict = {}

    def term(mono):
        if mono not in cache:
            out = R.one
            for n_k, d_k, e in zip(ns, ds, mono, strict=True):
                out = out * n_k**e * d_k ** (degree - e)
                if len(out) > MAX_TERMS:
                    return None
            cache[mono] = out
        return cache[mono]

    sides = []
    for coeffs in (num, den):
        total = R.zero
        for mono, c in coeffs.items():
            t = term(mono)
            if t is None:
                return False
            total += t * R.domain.convert(c.numerator) / R.domain.convert(c.denominator)
            if len(total) > MAX_TERMS:
                return False
        sides.append(total)
    P, Q = sides
    if not Q or R.gens[j] * Q != P:
        return False
    if at is None:
        return True
    pt = [R.domain.convert(v.numerator) / R.domain.convert(v.denominator) for v in at]
    return Q(*pt) != 0 and all(d_k(*pt) != 0 for d_k in ds)


def rational_formulas(summ, names: Sequence[str], *, seed: int = 0, max_degree: int = 2,
                      at: Sequence[object] | None = None) -> dict[str, RationalFormula]:
    """Checked formulas θ_j = P(c_S) / Q(c_S) for the parameters ``names`` that have one of degree ≤ max_degree.

    Parameters
    ----------
    summ : ExhaustiveSummary
        The model's exhaustive summary (:func:`~symid.structural.summary.exhaustive_summary`).
    names : sequence of str
        Parameters to try (locally identifiable ones: only they can have a formula).
    seed : int
        Seed of the random points (the check is exact whatever they are).
    max_degree : int
        Largest total degree of P and Q in the entries.
    at : sequence of rational, optional
        A point (θ*) where the formula must hold: Q(c_S) and the entries' denominators
        are checked to be nonzero there, exactly (θ_j is then the same on every complex
        solution of summary(θ) = summary(at)).

    Returns
    -------
    dict of str to RationalFormula
        One per parameter proven globally identifiable this way.

    Examples
    --------
    >>> import symid as si
    >>> from symid.structural.summary import exhaustive_summary
    >>> from symid.structural.rational_formulas import rational_formulas
    >>> a, b, c = si.parameters("a b c")
    >>> summ = exhaustive_summary(si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[c]]))  # H = b c / (s + a)
    >>> sorted(rational_formulas(summ, ["a", "b"]))
    ['a']
    """
    rng = random.Random(40_009 + seed)
    index = {q.name: i for i, q in enumerate(summ.parameters)}
    nv = len(summ.parameters)
    if nv == 0 or len(summ) == 0:
        return {}
    polys = []
    for num, den in zip(summ.numerators, summ.denominators, strict=True):
        polys.extend([list(num.items()), list(den.items())])
    ev = _ModEvaluator(polys, nv)
    pt = [rng.randrange(2, _P) for _ in range(nv)]
    vals, grads = ev.gradients(pt)
    n_vals, d_vals = vals[0::2], vals[1::2]
    if np.any(n_vals == 0) or np.any(d_vals == 0):
        return {}
    inv_d = np.array([pow(int(d), -1, _P) for d in d_vals], dtype=np.int64)
    # ∇(n/d) = (∇n − (n/d) ∇d) / d
    ratio = n_vals * inv_d % _P
    entry_grads = (grads[0::2] - ratio[:, None] * grads[1::2] % _P) % _P * inv_d[:, None] % _P
    order = sorted(range(len(summ)), key=lambda k: (len(polys[2 * k]) + len(polys[2 * k + 1]), k))
    out = {}
    for name in names:
        j = index[name]
        entries = _entry_set(entry_grads, j, order)
        if entries is None or sum(len(polys[2 * k]) + len(polys[2 * k + 1]) for k in entries) > MAX_ENTRY_TERMS:
            continue
        sub = _ModEvaluator([polys[2 * k + i] for k in entries for i in (0, 1)], nv)
        for degree in range(1, max_degree + 1):
            monos = _monomials(len(entries), degree)
            if 2 * len(monos) > MAX_UNKNOWNS:
                break
            rows = []
            for _ in range(2 * len(monos) + 8):
                q = [rng.randrange(1, _P) for _ in range(nv)]
                v = sub.values(q)
                c = [int(v[2 * i]) * pow(int(v[2 * i + 1]), -1, _P) % _P if v[2 * i + 1] else 0
                     for i in range(len(entries))]
                m = [int(np.prod([pow(ci, e, _P) for ci, e in zip(c, mono, strict=True)], dtype=object)) % _P
                     for mono in monos]
                rows.append([(q[j] * x) % _P for x in m] + [(-x) % _P for x in m])  # θ_j Q(c) − P(c) = 0
            x = _null_vector(np.array(rows, dtype=np.int64))
            if x is None:
                continue
            coeffs = [_lift(int(v)) for v in x]
            if any(cf is None for cf in coeffs):
                continue
            den = {mono: cf for mono, cf in zip(monos, coeffs[:len(monos)], strict=True) if cf}
            num = {mono: cf for mono, cf in zip(monos, coeffs[len(monos):], strict=True) if cf}
            if den and _check(summ, j, entries, monos, num, den, degree, at):
                out[name] = RationalFormula(name, tuple(entries), num, den)
                break
    return out
