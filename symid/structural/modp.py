"""Polynomials over ℚ evaluated modulo a prime, vectorised (numpy int64, primes below 2³¹).

Used where only a residue is needed: the summary system modulo a random prime for msolve
(:mod:`~symid.structural.global_`), the rank check at θ* (:mod:`~symid.structural.local`)
and the formula search (:mod:`~symid.structural.rational_formulas`). A prime that divides
a coefficient's denominator makes the reduction impossible: :class:`BadPrime` is raised
and the caller takes another prime.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["PRIME", "BadPrime", "Compiled", "compile_poly", "inverse_mod_p", "matmul_mod_p", "matrix_mod_p",
           "rank_mod_p", "residue", "term_values", "value_mod_p"]

PRIME = 2_147_483_629
"""The largest prime below 2³¹: products of two residues fit in a signed 64-bit integer."""


class BadPrime(ArithmeticError):
    """The prime divides a denominator: the polynomial or point has no residue modulo it."""


def residue(value, p: int) -> int:
    """A rational number (anything with ``numerator``/``denominator``) modulo p.

    Examples
    --------
    >>> from fractions import Fraction
    >>> from symid.structural.modp import residue
    >>> residue(Fraction(1, 3), 7)  # 3 · 5 = 15 ≡ 1 (mod 7)
    5
    """
    den = int(value.denominator) % p
    if den == 0:
        raise BadPrime(f"{p} divides the denominator of {value}")
    return int(value.numerator) % p * pow(den, -1, p) % p


class Compiled:
    """A polynomial's exponent matrix and its coefficients modulo p."""

    __slots__ = ("coeffs", "exponents", "monomials")

    def __init__(self, monomials: list[tuple[int, ...]], exponents: np.ndarray, coeffs: np.ndarray):
        self.monomials = monomials
        self.exponents = exponents
        self.coeffs = coeffs


def compile_poly(poly, p: int) -> Compiled:
    """Exponents and coefficients modulo p of a sympy ``PolyElement`` over ℚ."""
    terms = list(poly.terms())
    n = poly.ring.ngens
    monos = [m for m, _ in terms]
    E = np.array(monos, dtype=np.int64).reshape(len(terms), n)
    c = np.array([residue(v, p) for _, v in terms], dtype=np.int64)
    return Compiled(monos, E, c)


def term_values(exponents: np.ndarray, coeffs: np.ndarray, point: Sequence[int], p: int) -> np.ndarray:
    """Each term's value c·Π θ^e modulo p (rows of ``exponents``, one coefficient each), vectorised over terms."""
    t = coeffs.copy()
    for i in range(exponents.shape[1]):
        col = exponents[:, i]
        top = int(col.max()) if col.size else 0
        if top == 0:
            continue
        powers = np.empty(top + 1, dtype=np.int64)
        powers[0] = 1
        for e in range(1, top + 1):
            powers[e] = powers[e - 1] * int(point[i]) % p
        t = t * powers[col] % p
    return t


def value_mod_p(compiled: Compiled, point: Sequence[int], p: int) -> int:
    """The compiled polynomial at ``point`` (residues modulo p).

    Examples
    --------
    >>> from sympy import QQ
    >>> from sympy.polys.rings import ring
    >>> from symid.structural.modp import compile_poly, value_mod_p
    >>> R, x, y = ring("x y", QQ)
    >>> value_mod_p(compile_poly(x**2 * y + QQ(1, 2), 101), [3, 4], 101)  # 36 + 51 (= 1/2 mod 101)
    87
    """
    return int(term_values(compiled.exponents, compiled.coeffs, point, p).sum() % p)


def rank_mod_p(rows: Sequence[Sequence], p: int = PRIME) -> int:
    """Rank of a matrix of rationals modulo p (numpy, int64), or −1 when p divides a denominator.

    A lower bound on the rank over ℚ (a minor that is non-zero modulo p is non-zero), so a
    full rank modulo p proves full rank; a lower value proves nothing.

    Examples
    --------
    >>> from fractions import Fraction
    >>> from symid.structural.modp import rank_mod_p
    >>> rank_mod_p([[1, 2], [Fraction(1, 2), 1]]), rank_mod_p([[1, 2], [3, 4]])
    (1, 2)
    """
    try:
        A = np.array([[residue(v, p) if not isinstance(v, int) else v % p for v in row] for row in rows],
                     dtype=np.int64)
    except BadPrime:
        return -1
    if A.size == 0:
        return 0
    rank = 0
    n_rows, n_cols = A.shape
    for c in range(n_cols):
        piv = next((r for r in range(rank, n_rows) if A[r, c]), None)
        if piv is None:
            continue
        A[[rank, piv]] = A[[piv, rank]]
        A[rank] = A[rank] * pow(int(A[rank, c]), -1, p) % p
        below = A[rank + 1:, c].copy()
        nz = np.nonzero(below)[0]
        if nz.size:
            A[rank + 1 + nz] = (A[rank + 1 + nz] - (below[nz, None] * A[rank]) % p) % p
        rank += 1
        if rank == n_rows:
            break
    return rank


def matrix_mod_p(rows: Sequence[Sequence], p: int = PRIME) -> np.ndarray:
    """A matrix of rationals (or ints) modulo p, as int64 residues; :class:`BadPrime` when p divides a denominator."""
    return np.array([[residue(v, p) if not isinstance(v, int) else v % p for v in row] for row in rows],
                    dtype=np.int64).reshape(len(rows), -1 if rows else 0)


def matmul_mod_p(A: np.ndarray, B: np.ndarray, p: int = PRIME) -> np.ndarray:
    """A·B modulo p, exactly (Python integers inside: the sums of products would overflow int64)."""
    return ((A.astype(object) @ B.astype(object)) % p).astype(np.int64)


def inverse_mod_p(A: np.ndarray, p: int = PRIME) -> np.ndarray | None:
    """The inverse of a square matrix of residues modulo p, or None when it is singular modulo p.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.structural.modp import inverse_mod_p
    >>> inverse_mod_p(np.array([[2, 0], [0, 3]]), 7).tolist()  # 2·4 ≡ 3·5 ≡ 1 (mod 7)
    [[4, 0], [0, 5]]
    >>> inverse_mod_p(np.array([[1, 2], [2, 4]]), 7) is None
    True
    """
    n = A.shape[0]
    W = np.hstack([np.asarray(A, dtype=np.int64) % p, np.eye(n, dtype=np.int64)])
    for c in range(n):
        piv = next((r for r in range(c, n) if W[r, c]), None)
        if piv is None:
            return None
        W[[c, piv]] = W[[piv, c]]
        W[c] = W[c] * pow(int(W[c, c]), -1, p) % p
        col = W[:, c].copy()
        col[c] = 0
        nz = np.nonzero(col)[0]
        if nz.size:
            W[nz] = (W[nz] - (col[nz, None] * W[c]) % p) % p
    return W[:, n:]
