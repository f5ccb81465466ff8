"""Global identifiability by an explicit formula: a parameter that is a monomial in the summary entries.

If θ_j = κ Π_k c_k(θ)^{e_k} identically, with c_k the entries of an exhaustive summary
(the normalised transfer-function coefficients: what the input-output map determines),
integer exponents e_k and a non-zero constant κ, then θ_j is a rational function of the
input-output map, hence globally identifiable — at every θ where the entries used are
defined and non-zero, with no random point and no Gröbner basis. For example, in an RLC
ladder driven in the first mesh and measured in the last, the elastance of the last
capacitor is det K / (S_1 ⋯ S_{n−1}) = c_0 / b_1, the ratio of two coefficients.

The exponents are found by linear algebra on logarithmic derivatives: the identity implies
∇θ_j / θ_j = Σ_k e_k ∇c_k / c_k at every θ, a linear system for e stacked at random
points, solved modulo a 31-bit prime and lifted to small integers (a guess: nothing
rests on it). The formula is then *checked exactly* as a polynomial identity
(θ_j · Π_{e_k<0} n_k^{−e_k} d_k^{...} = κ · Π ..., with c_k = n_k / d_k multiplied out in
ℚ[θ]); only a checked formula proves anything.
"""

from __future__ import annotations

import random
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

import numpy as np
import sympy as sp
from sympy.polys.domains import GF
from sympy.polys.matrices import DomainMatrix

__all__ = ["MonomialFormula", "formula_expression", "monomial_formulas"]

GF_P = GF(2_147_483_629)
MAX_TERMS = 20_000
"""A formula whose products exceed this many terms is not checked (and so not used)."""


@dataclass(frozen=True)
class MonomialFormula:
    """θ_j = κ Π_k c_k^{e_k}: ``exponents`` maps summary entry index k to e_k (non-zero ones)."""

    parameter: str
    constant: Fraction
    exponents: dict

    def text(self, labels: Sequence[str]) -> str:
        """The formula with the summary entries named by their labels (``c[d s^0]`` …)."""
        parts = [f"c[{labels[k]}]" + (f"^{e}" if e != 1 else "") for k, e in sorted(self.exponents.items())]
        const = "" if self.constant == 1 else f"{self.constant}·"
        return f"{self.parameter} = {const}{' · '.join(parts)}"


_PRIME = 2_147_483_629
"""The linear algebra is done modulo this prime (largest below 2³¹; the check that follows is exact)."""


def _compile(poly, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Exponent matrix and coefficients modulo :data:`_PRIME` of a polynomial over ℚ."""
    terms = list(poly.terms())
    E = np.array([m for m, _ in terms], dtype=np.int64).reshape(len(terms), n)
    c = np.array([int(v.numerator) % _PRIME * pow(int(v.denominator), -1, _PRIME) % _PRIME for _, v in terms],
                 dtype=np.int64)
    return E, c


def _value_and_gradient(compiled, pt: np.ndarray, inv: np.ndarray) -> tuple[int, np.ndarray]:
    """f(pt) and ∇f(pt) modulo p: each term t = c·Π θ^e contributes t·e_i/θ_i to ∂_i."""
    E, c = compiled
    p = _PRIME
    t = c.copy()
    for i in range(E.shape[1]):
        col = E[:, i]
        for e in np.unique(col[col > 0]):
            t[col == e] = t[col == e] * pow(int(pt[i]), int(e), p) % p
    value = int(t.sum() % p)
    grad = np.array([int((t * (E[:, i] % p) % p).sum() % p) * int(inv[i]) % p for i in range(E.shape[1])],
                    dtype=np.int64)
    return value, grad


def _exponents(compiled, j: int, n: int, rng: random.Random, n_points: int = 3) -> list[int] | None:
    """Integer exponents e with Σ e_k ∇log c_k = ∇log θ_j at random points modulo p (lifted to small integers)."""
    p = _PRIME
    K = len(compiled)
    rows = []
    for _ in range(n_points):
        pt = np.array([rng.randrange(2, p) for _ in range(n)], dtype=np.int64)
        inv = np.array([pow(int(v), -1, p) for v in pt], dtype=np.int64)
        cols = []
        for num, den in compiled:
            nv, ng = _value_and_gradient(num, pt, inv)
            dv, dg = _value_and_gradient(den, pt, inv)
            if nv == 0 or dv == 0:
                return None
            cols.append((ng * pow(nv, -1, p) - dg * pow(dv, -1, p)) % p)
        for i in range(n):
            rows.append([int(cols[k][i]) for k in range(K)] + [int(inv[j]) if i == j else 0])
    A = DomainMatrix([[GF_P(v) for v in r] for r in rows], (len(rows), K + 1), GF_P)
    rref, pivots = A.rref()
    if K in pivots:  # inconsistent: no such monomial
        return None
    sol = [0] * K
    mat = rref.to_list()
    for r, c in enumerate(pivots):
        v = int(mat[r][K]) % p
        sol[c] = v - p if v > p // 2 else v
    if any(abs(v) > 64 for v in sol):  # not a small integer vector: no formula of this kind
        return None
    return sol


def _check(summ, j: int, exps: dict[int, int]) -> Fraction | None:
    """κ when θ_j = κ Π c_k^{e_k} holds as a polynomial identity (exact), else None."""
    R = summ.ring
    left, right = R.gens[j], R.one  # θ_j · Π(denominators of the positive powers) … = κ · Π(...)
    for k, e in exps.items():
        num, den = summ.numerators[k], summ.denominators[k]
        a, b = (num, den) if e > 0 else (den, num)
        for _ in range(abs(e)):
            right, left = right * a, left * b
            if len(right) > MAX_TERMS or len(left) > MAX_TERMS:
                return None
    # left / right must be a constant κ: compare leading terms, then the whole polynomials
    if not right or not left:
        return None
    lm = left.LM
    if lm not in dict(right.terms()):
        return None
    kappa = left[lm] / right[lm]
    if left != right * kappa:
        return None
    return Fraction(int(kappa.numerator), int(kappa.denominator))


def monomial_formulas(summ, names: Sequence[str], *, seed: int = 0) -> dict[str, MonomialFormula]:
    """Checked formulas θ_j = κ Π c_k^{e_k} (integer exponents) for the parameters ``names`` that have one.

    Parameters
    ----------
    summ : ExhaustiveSummary
        The model's exhaustive summary (:func:`~symid.structural.summary.exhaustive_summary`).
    names : sequence of str
        Parameters to try (the locally identifiable ones: only they can have a formula).
    seed : int
        Seed of the random points of the linear algebra (the check is exact whatever they are).

    Examples
    --------
    >>> import symid as si
    >>> from symid.structural.summary import exhaustive_summary
    >>> from symid.structural.formulas import monomial_formulas
    >>> a, b, c = si.parameters("a b c")
    >>> summ = exhaustive_summary(si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[c]]))  # H = b c / (s + a)
    >>> sorted(monomial_formulas(summ, ["a", "b"]))
    ['a']
    """
    rng = random.Random(30_011 + seed)
    index = {q.name: i for i, q in enumerate(summ.parameters)}
    n = len(summ.parameters)
    compiled = [(_compile(num, n), _compile(den, n)) for num, den in zip(summ.numerators, summ.denominators,
                                                                          strict=True)]
    out = {}
    for name in names:
        j = index[name]
        sol = _exponents(compiled, j, n, rng)
        if sol is None:
            continue
        exps = {k: v for k, v in enumerate(sol) if v}
        kappa = _check(summ, j, exps)
        if kappa is not None and kappa != 0:
            out[name] = MonomialFormula(name, kappa, exps)
    return out


def formula_expression(formula: MonomialFormula, summ) -> sp.Expr:
    """The formula's right-hand side as a sympy expression in θ (it simplifies to the parameter)."""
    expr = sp.Rational(formula.constant.numerator, formula.constant.denominator)
    for k, e in formula.exponents.items():
        expr *= (summ.numerators[k].as_expr() / summ.denominators[k].as_expr()) ** e
    return expr
