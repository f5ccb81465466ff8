"""Polynomials over ℚ evaluated modulo a prime, vectorised (numpy int64, primes below 2³¹).

Used where only a residue is needed: the summary system modulo a random prime for msolve
(:mod:`~symid.structural.global_`). A prime that divides a coefficient's denominator makes
the reduction impossible: :class:`BadPrime` is raised and the caller takes another prime.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["BadPrime", "Compiled", "compile_poly", "residue", "value_mod_p"]


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
    E, t = compiled.exponents, compiled.coeffs.copy()
    for i in range(E.shape[1]):
        col = E[:, i]
        top = int(col.max()) if col.size else 0
        if top == 0:
            continue
        powers = np.empty(top + 1, dtype=np.int64)
        powers[0] = 1
        for e in range(1, top + 1):
            powers[e] = powers[e - 1] * int(point[i]) % p
        t = t * powers[col] % p
    return int(t.sum() % p)
