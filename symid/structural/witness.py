"""Numerical witnesses against global identifiability, for when the Gröbner basis does not finish.

When the exact global step exceeds its deadline, the model may still be shown *not*
globally identifiable by exhibiting a second admissible solution θ ≠ θ* of
summary(θ) = summary(θ*). The search:

1. writes the equations ``F_i(θ) = n_i(θ) d_i(θ*) − d_i(θ) n_i(θ*)`` of the
   exhaustive summary (the same θ* as the Gröbner step), each scaled to unit largest
   coefficient, as exponent matrices for vectorised evaluation;
2. runs Gauss–Newton from random starts around θ* (log-normal in magnitude, random
   sign for parameters not declared positive), all starts at once in numpy;
3. keeps converged points that differ from θ* and satisfy the declared positivity,
   with every summary denominator away from zero (a true solution of
   summary(θ) = summary(θ*), not of the cross-multiplied equations only);
4. verifies each candidate by Newton's method at 60 significant digits with the exact
   rational coefficients (mpmath): it is accepted when the residual falls below 1e-40
   and the steps shrink quadratically, at a well-conditioned Jacobian (condition
   number below 1e12). That is the numerical signature of a simple exact root within
   the last step;
5. when the system is square (as many equations as unknowns, e.g. the 2n normalised
   transfer-function coefficients of a SISO model with 2n unknowns), *certifies* each
   verified point with the Krawczyk test in outward-rounded interval arithmetic
   (``mpmath.iv``, 256 bits): for a box X around the point x̃ and Y ≈ F′(x̃)⁻¹,
   ``K(X) = x̃ − Y F(x̃) + (I − Y F′(X))(X − x̃) ⊂ int X`` proves that X holds exactly
   one real root of F (Krawczyk 1969; Neumaier, *Interval Methods for Systems of
   Equations*, Thm. 5.1.7). The same interval evaluation shows that X excludes θ*,
   lies in the declared positive orthant and keeps every summary denominator away
   from zero, and certified boxes are pairwise disjoint, so each certified witness is
   a distinct admissible solution, proven.

A witness shows the model is not globally identifiable at θ* (the solution count is
at least 1 + the number of witnesses); a certified one proves it. Finding none proves
nothing.
"""

from __future__ import annotations

import random
import time
from collections.abc import Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass

import mpmath
import numpy as np
from sympy import QQ

from symid.structural.global_ import POSITIVE_TOL, star_and_summary

__all__ = ["WitnessResult", "find_witnesses"]

_DIGITS = 60
_RESIDUAL_HP = 1e-40
_MAX_WITNESSES = 8
_IV_BITS = 256
"""Working precision (bits) of the interval arithmetic of the Krawczyk test."""
_BOX_RADIUS = 1e-20
"""Relative half-width of the box around a 60-digit witness in which the Krawczyk test proves a root."""


@dataclass(frozen=True)
class WitnessResult:
    """Other admissible solutions of summary(θ) = summary(θ*) found numerically.

    Attributes
    ----------
    theta_star : dict of str to str
        The point θ* (rational, as strings).
    witnesses : tuple of dict
        Verified solutions θ ≠ θ* (floats), at most eight.
    n_starts : int
        Starts tried.
    seconds : float
        Wall time of the search.
    certified : tuple of bool
        Per witness, whether the Krawczyk test proved an exact admissible solution in a
        box of relative radius 1e-20 around it (only for square systems).
    square : bool
        Whether the system had as many equations as unknowns (certification possible).
    """

    theta_star: dict
    witnesses: tuple
    n_starts: int
    seconds: float
    certified: tuple = ()
    square: bool = False


def _compile(polys) -> list[tuple[np.ndarray, np.ndarray]]:
    """Exponent matrix and float coefficients (scaled to unit maximum) of each polynomial."""
    out = []
    for f in polys:
        terms = f.terms()
        E = np.array([m for m, _ in terms], dtype=np.int64)
        c = np.array([float(v) for _, v in terms])
        out.append((E, c / np.abs(c).max()))
    return out


def _exact(polys) -> list[list[tuple[tuple[int, ...], object]]]:
    """Terms of each polynomial with exact rational coefficients, scaled like :func:`_compile`."""
    out = []
    for f in polys:
        top = max(abs(c) for _, c in f.terms())
        out.append([(m, c / top) for m, c in f.terms()])
    return out


def _eval(compiled, X: np.ndarray):
    """Residuals (S, neq), Jacobians (S, neq, nv) and Σ|terms| (S, neq) at the rows of X (no zero entries).

    Monomials as exp(log|X| Eᵀ) with the sign (−1)^(neg(X) Eᵀ): two matrix products per
    polynomial instead of a power per term and variable.
    """
    S, nv = X.shape
    F = np.empty((S, len(compiled)))
    J = np.empty((S, len(compiled), nv))
    size = np.empty((S, len(compiled)))
    with np.errstate(all="ignore"):
        logs = np.log(np.abs(X))
        neg = (X < 0).astype(float)
        for i, (E, c) in enumerate(compiled):
            Ef = E.T.astype(float)
            mon = np.exp(logs @ Ef) * (1.0 - 2.0 * np.mod(neg @ Ef, 2.0))  # (S, T)
            cm = mon * c
            F[:, i] = cm.sum(axis=1)
            size[:, i] = np.abs(cm).sum(axis=1)
            J[:, i, :] = (cm @ E) / X
    return F, J, size


def _newton(compiled, X: np.ndarray, iterations: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Newton from every row of X at once (steps capped); returns the points and max |F_i| / Σ|terms of F_i|."""
    X = X.copy()
    alive = np.ones(len(X), dtype=bool)
    for _ in range(iterations):
        F, J, _ = _eval(compiled, X[alive])
        ok = np.isfinite(F).all(axis=1) & np.isfinite(J).all(axis=(1, 2))
        idx = np.flatnonzero(alive)
        alive[idx[~ok]] = False
        if not ok.any():
            break
        F, J, Xa = F[ok], J[ok], X[idx[ok]]
        with np.errstate(all="ignore"):
            step = -np.einsum("sij,sj->si", np.linalg.pinv(J), F)
            size = np.linalg.norm(step, axis=1, keepdims=True)
            cap = 0.5 * (np.linalg.norm(Xa, axis=1, keepdims=True) + 1.0)
            step = np.where(size > cap, step * cap / size, step)
        X[idx[ok]] = Xa + step
    X[~alive] = np.nan
    F, _, size = _eval(compiled, X)
    with np.errstate(all="ignore"):
        return X, (np.abs(F) / np.maximum(size, 1e-300)).max(axis=1)


def _nonzero(compiled, x: np.ndarray) -> bool:
    """Every polynomial is away from zero at x, relative to the size of its terms."""
    for E, c in compiled:
        terms = c * np.prod(x[None, :] ** E, axis=1)
        if abs(terms.sum()) <= 1e-9 * np.abs(terms).sum():
            return False
    return True


def _verify(exact, x: np.ndarray) -> list | None:
    """Newton at 60 digits with exact coefficients; the refined point (mpf list) if it converges quadratically."""
    nv = len(x)
    with mpmath.workdps(_DIGITS):
        X = [mpmath.mpf(float(v)) for v in x]
        coefs = [[(mon, mpmath.mpf(int(c.numerator)) / int(c.denominator)) for mon, c in terms] for terms in exact]
        last, floor = None, mpmath.mpf(10) ** (5 - _DIGITS)
        for _ in range(12):
            F = mpmath.matrix(len(exact), 1)
            J = mpmath.matrix(len(exact), nv)
            for i, terms in enumerate(coefs):
                for mon, c in terms:
                    val = c
                    for v, e in enumerate(mon):
                        if e:
                            val *= X[v] ** e
                    F[i] += val
                    for v, e in enumerate(mon):
                        if e:
                            J[i, v] += val * e / X[v]
            try:
                step = mpmath.lu_solve(J.T * J, -(J.T * F))
            except ZeroDivisionError:
                return None
            X = [X[v] + step[v] for v in range(nv)]
            size = mpmath.norm(step)
            quadratic = last is not None and size <= max(last**1.5, floor)
            if mpmath.norm(F) < _RESIDUAL_HP and quadratic:
                break
            last = size
        else:
            return None
        cond = np.linalg.cond(np.array(J.tolist(), dtype=float))
    if not np.isfinite(cond) or cond > 1e12:
        return None
    return X


@contextmanager
def _iv_precision():
    """``mpmath.iv`` at ``_IV_BITS`` bits for the duration (its context has no ``workprec``)."""
    old = mpmath.iv.prec
    mpmath.iv.prec = _IV_BITS
    try:
        yield
    finally:
        mpmath.iv.prec = old


def _interval_terms(exact) -> list[list[tuple[tuple[tuple[int, int], ...], object]]]:
    """Per polynomial: (sparse monomial ((variable, exponent), ...), enclosing interval of the coefficient)."""
    with _iv_precision():
        return [[(tuple((v, e) for v, e in enumerate(mon) if e),
                  mpmath.iv.mpf(int(c.numerator)) / mpmath.iv.mpf(int(c.denominator))) for mon, c in terms]
                for terms in exact]


def _iv_eval(terms, X, jacobian: bool):
    """Interval values (and Jacobian rows) of the polynomials over the box X (list of iv.mpf).

    Powers are tabulated once per box. A partial derivative is the term divided by its
    variable, times the exponent: a rigorous enclosure whenever the variable's interval
    excludes 0, else the derivative's own product is formed.
    """
    iv = mpmath.iv
    nv = len(X)
    table: dict[tuple[int, int], object] = {}

    def power(v: int, e: int):
        key = (v, e)
        if key not in table:
            table[key] = X[v] ** e if e > 1 else X[v]
        return table[key]

    nonzero = [not (x.a <= 0 <= x.b) for x in X]
    F, J = [], []
    for poly in terms:
        f = iv.mpf(0)
        row = [iv.mpf(0) for _ in range(nv)]
        for mon, c in poly:
            val = c
            for v, e in mon:
                val = val * power(v, e)
            f += val
            if jacobian:
                for k, (v, e) in enumerate(mon):
                    if nonzero[v]:
                        d = val * e / X[v]
                    else:
                        d = c * e * (power(v, e - 1) if e > 1 else iv.mpf(1))
                        for j, (u, eu) in enumerate(mon):
                            if j != k:
                                d = d * power(u, eu)
                    row[v] += d
        F.append(f)
        J.append(row)
    return F, J


def _krawczyk(terms, den_terms, x, star, positive) -> tuple | None:
    """Certified box around the 60-digit point x, or None (see step 5 of the module notes).

    ``star`` holds θ* as exact rationals (``QQ``). Returns the box (list of iv.mpf)
    when K(X) ⊂ int X, X excludes θ*, the positive coordinates are > 0 on X and no
    denominator vanishes on X.
    """
    iv = mpmath.iv
    nv = len(x)
    with _iv_precision():
        mid = [iv.mpf(v) for v in x]  # exact: 60 digits fit in the working precision
        box = [m + iv.mpf([-_BOX_RADIUS * max(1.0, abs(float(v))), _BOX_RADIUS * max(1.0, abs(float(v)))])
               for m, v in zip(mid, x, strict=True)]
        Fm, _ = _iv_eval(terms, mid, jacobian=False)
        _, JX = _iv_eval(terms, box, jacobian=True)
        Jmid = np.array([[float(e.mid) for e in row] for row in JX])
        try:
            Y = np.linalg.inv(Jmid)  # any matrix makes K rigorous; a good one makes it contract
        except np.linalg.LinAlgError:
            return None
        Yi = [[iv.mpf(float(v)) for v in row] for row in Y]
        for i in range(nv):
            k = mid[i] - sum((Yi[i][j] * Fm[j] for j in range(nv)), iv.mpf(0))
            for j in range(nv):
                m = (iv.mpf(1) if i == j else iv.mpf(0)) - sum((Yi[i][q] * JX[q][j] for q in range(nv)), iv.mpf(0))
                k += m * (box[j] - mid[j])
            if not (k.a > box[i].a and k.b < box[i].b):
                return None
        star_iv = [iv.mpf(int(v.numerator)) / iv.mpf(int(v.denominator)) for v in star]
        if not any(star_iv[i].b < box[i].a or star_iv[i].a > box[i].b for i in range(nv)):
            return None  # the box may contain θ*
        if any(positive[i] and not box[i].a > 0 for i in range(nv)):
            return None
        dens, _ = _iv_eval(den_terms, box, jacobian=False)
        if any(d.a <= 0 <= d.b for d in dens):
            return None
    return box


def _disjoint(a, b) -> bool:
    return any(x.b < y.a or y.b < x.a for x, y in zip(a, b, strict=True))


def find_witnesses(model, known: Mapping[str, object] | None = None, *, positive: Sequence[bool] | None = None,
                   seed: int = 0, batches: int = 8, batch: int = 48,
                   prepared: tuple | None = None) -> WitnessResult:
    """Search for admissible solutions θ ≠ θ* of summary(θ) = summary(θ*), and verify them.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    known : dict, optional
        Fixed parameter values.
    positive : sequence of bool, optional
        Per free parameter, whether only positive values are admissible.
    seed : int
        Seed of θ* (the same as :func:`~symid.structural.global_.global_analysis`) and of the starts.
    batches : int
        Number of batches of starts (the search stops earlier, after a batch, once eight
        witnesses are found or certified witnesses move every parameter). A fixed number
        of starts, not a time limit: the same model and seed give the same witnesses on
        any machine.
    batch : int
        Starts per batch.
    prepared : tuple, optional
        The result of :func:`~symid.structural.global_.star_and_summary` for the same
        model, ``known`` and ``seed``.

    Returns
    -------
    WitnessResult

    Examples
    --------
    >>> import symid as si
    >>> from symid.structural.witness import find_witnesses
    >>> th = si.parameters("th")
    >>> model = si.StateSpaceModel(A=[[-1]], B=[[th]], C=[[th]])  # θ and −θ give the same H
    >>> res = find_witnesses(model, batches=1)
    >>> from fractions import Fraction
    >>> [round(w["th"] / float(Fraction(res.theta_star["th"])), 9) for w in res.witnesses]
    [-1.0]
    """
    t0 = time.perf_counter()
    params, star, _, summ, _ = prepared if prepared is not None else star_and_summary(model, known, seed=seed)
    names = [p.name for p in params]
    theta_star = {n: str(v) for n, v in zip(names, star, strict=True)}
    nv = len(params)
    positive = list(positive) if positive is not None else [False] * nv
    if nv == 0 or len(summ) == 0:
        return WitnessResult(theta_star, (), 0, time.perf_counter() - t0)
    pt = [QQ.from_sympy(v) for v in star]
    polys = []
    for num, den in zip(summ.numerators, summ.denominators, strict=True):
        f = num * den(*pt) - den * num(*pt)
        if f:
            polys.append(f)
    compiled, exact = _compile(polys), _exact(polys)
    den_polys = [d for d in summ.denominators if not d.is_ground]
    dens = _compile(den_polys)
    square = len(polys) == nv
    if square:
        terms, den_terms = _interval_terms(exact), _interval_terms(_exact(den_polys))
    boxes: list = []
    certified: list[bool] = []
    xs = np.array([float(v) for v in star])
    pos = np.array(positive, dtype=bool)
    rng = np.random.default_rng(random.Random(seed).randrange(2**32))
    found: list[np.ndarray] = []
    n_starts = 0
    for _ in range(batches):
        if len(found) >= _MAX_WITNESSES:
            break
        moved = np.zeros(nv, dtype=bool)
        for f, ok in zip(found, certified, strict=True):
            if ok:
                moved |= np.abs(f - xs) > 1e-6 * np.maximum(1.0, np.abs(xs))
        if moved.all():  # certified witnesses already move every parameter: the verdicts are settled
            break
        mag = xs * np.exp(rng.normal(0.0, 1.5, (batch, nv)))
        sign = np.where(pos, 1.0, rng.choice([-1.0, 1.0], (batch, nv)))
        X, res = _newton(compiled, mag * sign, 40)
        n_starts += batch
        for x, r in zip(X, res, strict=True):
            if not np.isfinite(r) or r > 1e-9 or not np.all(np.isfinite(x)):
                continue
            if np.all(np.abs(x - xs) <= 1e-6 * np.maximum(1.0, np.abs(xs))):
                continue  # θ* itself
            if np.any(x[pos] <= POSITIVE_TOL):
                continue
            if any(np.all(np.abs(x - f) <= 1e-6 * np.maximum(1.0, np.abs(f))) for f in found):
                continue
            sol_mp = _verify(exact, x)
            if sol_mp is None:
                continue
            sol = np.array([float(v) for v in sol_mp])
            if np.any(sol[pos] <= POSITIVE_TOL) or not _nonzero(dens, sol):
                continue
            if np.all(np.abs(sol - xs) <= 1e-9 * np.maximum(1.0, np.abs(xs))):
                continue
            if any(np.all(np.abs(sol - f) <= 1e-9 * np.maximum(1.0, np.abs(f))) for f in found):
                continue
            box = _krawczyk(terms, den_terms, sol_mp, pt, pos) if square else None
            if box is not None and not all(_disjoint(box, b) for b in boxes):
                box = None  # cannot happen for distinct points 1e-9 apart; kept for rigour
            if box is not None:
                boxes.append(box)
            certified.append(box is not None)
            found.append(sol)
            if len(found) >= _MAX_WITNESSES:
                break
    witnesses = tuple({n: float(v) for n, v in zip(names, sol, strict=True)} for sol in found)
    return WitnessResult(theta_star, witnesses, n_starts, time.perf_counter() - t0, tuple(certified), square)
