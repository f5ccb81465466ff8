"""Proof that a point is within a tiny box of an exact root of summary(θ) = summary(θ*), fast.

The witnesses of :mod:`~symid.structural.witness` are roots of the square system
``F_i(θ) = n_i(θ) d_i(θ*) − d_i(θ) n_i(θ*)`` (``n_i / d_i`` the entries of the
exhaustive summary, exact rational coefficients). :func:`SummarySystem.certify`
proves that a box ``X = [x̃ − r, x̃ + r]`` (``r_v = ρ |x̃_v|``, ρ ≤ 1e-6) around a
floating-point point x̃ holds exactly one root, by Krawczyk's test: with
``Y ≈ F′(x̃)⁻¹``, ``K(X) = x̃ − Y F(x̃) + (I − Y F′(X))(X − x̃) ⊂ int X`` proves a unique
root of F in X (Krawczyk 1969; Neumaier, *Interval Methods for Systems of Equations*,
1990, Thm. 5.1.7; the form used, ``|Y F(x̃)| + |I − Y F′(X)| r < r``, is Rump's, *Acta
Numerica* 19, 2010, §13). The same bounds show that X excludes θ*, lies in the
declared positive orthant and keeps every summary denominator away from zero.

Every bound is rigorous in IEEE double arithmetic (round to nearest, numpy's
element-wise operations, no fused multiply-add in them), without interval types:

* ``F(x̃)`` by *compensated* evaluation: each term's product is formed with the
  error-free transformation TwoProduct (Dekker's splitting), carrying its rounding
  error (Graillat, "Accurate floating-point product and exponentiation", *IEEE Trans.
  Comput.* 58, 2009); the pieces of every polynomial are summed by ``math.fsum``
  (correctly rounded, Shewchuk 1997), twice for a double-length result. The enclosure
  is then about 1e-30 of the size of the terms, where plain double evaluation is good
  to ~1e-13 — not enough for the systems of 20 and more unknowns (condition numbers
  1e7 and over), where ``|Y F(x̃)|`` must be far below the box radius. θ* (rational) is
  entered as a double-double, the coefficients likewise, with their errors bounded;
* ``F′`` at x̃ in plain double with an a-priori bound (γ_k = k u/(1 − k u) times the
  sum of the absolute values of the terms, Higham, *Accuracy and Stability of
  Numerical Algorithms*, 2002, §3.1), and its variation over X by the majorant
  ``|∂mon(x) − ∂mon(x̃)| ≤ ((1 + ρ)^deg − 1) |∂mon(x̃)|`` for x ∈ X;
* the small matrix algebra of the test in double, every result bounded upwards.

Refusing is always safe: a point outside the safe exponent range (no underflow or
overflow in the error-free transformations), a zero coordinate, or a test that fails
at every radius of a fixed list gives no certificate. Cost: a few numpy passes over the
terms, about 40 ms for 44 000 terms (the 8-mass chain), against seconds for
60-digit interval arithmetic (``mpmath.iv``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from fractions import Fraction
from itertools import chain

import numpy as np

__all__ = ["PolySystem", "SummarySystem"]

U = 2.0**-53
"""Unit roundoff of IEEE double."""
_SPLIT = 134217729.0  # 2**27 + 1, Dekker/Veltkamp splitting
_SAFE = (2.0**-900, 2.0**900)
"""Magnitudes within which TwoProduct is error-free (no underflow of the error term, no overflow in the split)."""
_TINY = 1e-290
"""Absolute slack added to every upper bound (covers underflow of the small error terms)."""
RADII = (1e-14, 1e-12, 1e-10, 1e-8, 1e-6)
"""Relative box radii ρ tried in turn: the smallest that fits the residual first (a fixed list: deterministic)."""


def _two_prod(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """p = fl(a b) and e with a b = p + e exactly (Dekker 1971), element-wise."""
    p = a * b
    ca = _SPLIT * a
    ah = ca - (ca - a)
    al = a - ah
    cb = _SPLIT * b
    bh = cb - (cb - b)
    bl = b - bh
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


def _up(x, k: int):
    """An upper bound of the exact value of a nonnegative result computed with at most k roundings."""
    return x * (1.0 + 2.0 * (k + 2) * U) + _TINY


def _split_rational(n: int, d: int) -> tuple[float, float]:
    """(hi, lo) doubles with |c − hi − lo| ≤ u |c − hi| for the rational c = n / d (d > 0)."""
    hi = n / d  # correctly rounded
    p, q = hi.as_integer_ratio()
    return hi, (n * q - p * d) / (d * q)


class PolySystem:
    """Polynomials with exact rational coefficients, compiled for vectorised evaluation.

    Parameters
    ----------
    polys : sequence of sequence of (tuple of int, rational)
        Per polynomial, its terms (exponent tuple, coefficient with ``numerator`` and
        ``denominator``).
    nv : int
        Number of variables.
    """

    def __init__(self, polys: Sequence[Sequence[tuple[tuple[int, ...], object]]], nv: int):
        self.nv = nv
        self.n_polys = len(polys)
        sizes = [len(terms) for terms in polys]
        T = sum(sizes)
        self.E = np.fromiter(chain.from_iterable(m for terms in polys for m, _ in terms), dtype=np.int64,
                             count=T * nv).reshape(T, nv)
        his, los = [], []
        for terms in polys:
            for _, c in terms:
                n, d = int(c.numerator), int(c.denominator)
                if d == 1 and -(2**53) < n < 2**53:
                    his.append(float(n))
                    los.append(0.0)
                else:
                    hi, lo = _split_rational(n, d)
                    his.append(hi)
                    los.append(lo)
        self.Ef = self.E.astype(float)
        self.c_hi = np.array(his, dtype=float)
        self.c_lo = np.array(los, dtype=float)
        self.sizes = np.array(sizes, dtype=np.int64)
        self.starts = np.concatenate([[0], np.cumsum(self.sizes)])
        self.deg = self.E.sum(axis=1)
        self.maxdeg = self.E.max(axis=0) if T else np.zeros(nv, dtype=np.int64)
        self.poly_deg = np.array([self.deg[a:b].max() if b > a else 0
                                  for a, b in zip(self.starts[:-1], self.starts[1:], strict=True)])
        m = self.deg + 1.0  # factors per term, the coefficient included
        self._bound_factor = (8.0 * m * m + 4.0 * m * nv + 8.0 * m + 8.0) * U * U
        with np.errstate(divide="ignore", invalid="ignore"):
            self._alpha = np.where(self.c_hi != 0, self.c_lo / self.c_hi, 0.0)

    def _segments(self):
        return zip(self.starts[:-1], self.starts[1:], strict=True)

    def enclose(self, x_hi: np.ndarray, x_lo: np.ndarray | None = None):
        """Enclosures of the values at ``x = x_hi + x_lo`` (doubles; ``x_lo`` a double-double's low part).

        Returns
        -------
        (hi, lo, rad) : three arrays, one entry per polynomial, or None
            The exact value lies in ``[hi + lo − rad, hi + lo + rad]`` (``hi + lo`` the
            exact sum of two doubles). None when a coordinate or a partial product
            leaves the safe exponent range.
        """
        x_hi = np.asarray(x_hi, dtype=float)
        if not np.all(np.isfinite(x_hi)) or np.any((x_hi != 0) & ((np.abs(x_hi) < _SAFE[0])
                                                                   | (np.abs(x_hi) > _SAFE[1]))):
            return None
        p = self.c_hi.copy()
        e = np.zeros_like(p)
        smallest, largest = np.inf, 0.0
        for v in range(self.nv):
            col = self.E[:, v]
            for level in range(int(self.maxdeg[v])):
                f = np.where(col > level, x_hi[v], 1.0)
                p, pi = _two_prod(p, f)
                e = e * f + pi
                a = np.abs(p[p != 0])
                if a.size:
                    smallest, largest = min(smallest, a.min()), max(largest, a.max())
        if largest > _SAFE[1] or smallest < _SAFE[0]:
            return None
        delta = self._alpha
        if x_lo is not None:
            with np.errstate(divide="ignore", invalid="ignore"):
                beta = np.where(x_hi != 0, np.asarray(x_lo, dtype=float) / x_hi, 0.0)
            if np.any(np.abs(beta) > 4 * U):
                raise ValueError("x_lo must be the low part of a double-double (|x_lo| ≤ u |x_hi|)")
            delta = delta + self.Ef @ beta
        q = p * delta
        bound = self._bound_factor * np.abs(p)
        hi = np.empty(self.n_polys)
        lo = np.empty(self.n_polys)
        rad = np.empty(self.n_polys)
        for k, (a, b) in enumerate(self._segments()):
            pieces = [*p[a:b].tolist(), *e[a:b].tolist(), *q[a:b].tolist()]
            s1 = math.fsum(pieces)
            pieces.append(-s1)
            s2 = math.fsum(pieces)
            hi[k], lo[k] = s1, s2
            rad[k] = _up(float(bound[a:b].sum()), int(b - a)) + 2.0 * U * abs(s2) + (b - a) * _TINY
        return hi, lo, rad

    def evaluate(self, x: np.ndarray):
        """Plain double values, Jacobian and their a-priori error bounds at the double point x (no zero coordinate).

        Returns
        -------
        (f, fabs, J, Jabs, Jerr)
            Values f (per polynomial), ``fabs`` ≥ Σ |terms| (an upper bound), the
            Jacobian J, ``Jabs`` ≥ Σ_t |c_t ∂mon_t(x)| and ``Jerr`` ≥ |J_exact − J|.
        """
        x = np.asarray(x, dtype=float)
        mon = self.c_hi.copy()
        for v in range(self.nv):
            col = self.E[:, v]
            for level in range(int(self.maxdeg[v])):
                mon = mon * np.where(col > level, x[v], 1.0)
        amon = np.abs(mon)
        f = np.empty(self.n_polys)
        fabs = np.empty(self.n_polys)
        J = np.empty((self.n_polys, self.nv))
        Jabs = np.empty((self.n_polys, self.nv))
        Jerr = np.empty((self.n_polys, self.nv))
        for k, (a, b) in enumerate(self._segments()):
            T = int(b - a)
            k_round = T + int(self.poly_deg[k]) + 6  # products, coefficient rounding, sum, the division by x_v
            f[k] = mon[a:b].sum()
            fabs[k] = _up(amon[a:b].sum(), k_round)
            J[k] = (mon[a:b] @ self.Ef[a:b]) / x
            Jabs[k] = _up((amon[a:b] @ self.Ef[a:b]) / np.abs(x), k_round)
            gamma = k_round * U / (1.0 - k_round * U)
            Jerr[k] = _up(gamma * Jabs[k], 2)
        return f, fabs, J, Jabs, Jerr


def _growth(k: int, rho: float) -> float:
    """An upper bound of (1 + ρ)^k − 1 for kρ ≤ 1 (e^y ≤ 1 + y + y² there), by basic operations only."""
    y = _up(k * rho, 1)
    if y > 1.0:
        return math.inf
    return _up(y + y * y, 2)


def _frac(hi: float, lo: float = 0.0) -> Fraction:
    return Fraction(hi) + Fraction(lo)


def _float_up(q: Fraction) -> float:
    """A double ≥ |q|."""
    return abs(float(q)) * (1.0 + 4.0 * U) + _TINY


class SummarySystem:
    """The square system ``F_i(θ) = n_i(θ) d_i(θ*) − d_i(θ) n_i(θ*)`` with rigorous evaluation.

    Parameters
    ----------
    numerators, denominators : sequence of sequence of (tuple of int, rational)
        The terms of ``n_i`` and ``d_i``.
    star : sequence of rational
        θ* (exact).
    """

    def __init__(self, numerators, denominators, star: Sequence[object]):
        self.nv = len(star)
        self.neq = len(numerators)
        polys = []
        for num, den in zip(numerators, denominators, strict=True):
            polys.extend([num, den])
        self.polys = PolySystem(polys, self.nv)
        self.star = [Fraction(int(v.numerator), int(v.denominator)) for v in star]
        s_hi = np.array([float(v) for v in self.star])
        s_lo = np.array([float(v - Fraction(h)) for v, h in zip(self.star, s_hi, strict=True)])
        enc = self.polys.enclose(s_hi, s_lo)
        if enc is None:
            raise ValueError("θ* is outside the safe exponent range of the compensated evaluation")
        hi, lo, rad = enc
        # values at θ*: n_i* = num_star[i] ± num_rad[i], d_i* likewise
        self.num_star = [_frac(hi[2 * i], lo[2 * i]) for i in range(self.neq)]
        self.den_star = [_frac(hi[2 * i + 1], lo[2 * i + 1]) for i in range(self.neq)]
        self.num_rad = rad[0::2].copy()
        self.den_rad = rad[1::2].copy()
        self.num_star_f = np.array([float(v) for v in self.num_star])
        self.den_star_f = np.array([float(v) for v in self.den_star])

    def residual(self, x: np.ndarray):
        """F(x) at the double point x: centres (Fractions) and radii (doubles), or None (unsafe range)."""
        enc = self.polys.enclose(x)
        if enc is None:
            return None
        hi, lo, rad = enc
        centre, radius = [], []
        for i in range(self.neq):
            n, d = _frac(hi[2 * i], lo[2 * i]), _frac(hi[2 * i + 1], lo[2 * i + 1])
            a, b = rad[2 * i], rad[2 * i + 1]
            ns, ds, a_s, b_s = self.num_star[i], self.den_star[i], self.num_rad[i], self.den_rad[i]
            centre.append(n * ds - d * ns)
            bound = (_float_up(n) * b_s + a * _float_up(ds) + a * b_s
                     + _float_up(d) * a_s + b * _float_up(ns) + b * a_s)
            radius.append(_up(bound, 12))
        return centre, np.array(radius), (hi, lo, rad)

    def jacobian(self, x: np.ndarray):
        """Double Jacobian of F at x, an upper bound of its error, Σ|terms| of each derivative, and the plain values."""
        f, fabs, J, Jabs, Jerr = self.polys.evaluate(x)
        ds = self.den_star_f[:, None]
        ns = self.num_star_f[:, None]
        ds_err = np.array([_float_up(self.den_star[i] - Fraction(self.den_star_f[i])) + self.den_rad[i]
                           for i in range(self.neq)])[:, None]
        ns_err = np.array([_float_up(self.num_star[i] - Fraction(self.num_star_f[i])) + self.num_rad[i]
                           for i in range(self.neq)])[:, None]
        Jn, Jd = J[0::2], J[1::2]
        JF = Jn * ds - Jd * ns
        JFabs = _up(Jabs[0::2] * np.abs(ds) + Jabs[1::2] * np.abs(ns), 4)
        JFerr = _up(Jerr[0::2] * np.abs(ds) + Jerr[1::2] * np.abs(ns) + Jabs[0::2] * ds_err + Jabs[1::2] * ns_err
                    + 4.0 * U * (np.abs(Jn * ds) + np.abs(Jd * ns)), 8)
        return JF, JFerr, JFabs, (f, fabs)

    def newton_step(self, x: np.ndarray) -> np.ndarray | None:
        """x − F′(x)⁻¹ F(x), F(x) from the compensated evaluation (refines a double root to the last bits)."""
        res = self.residual(x)
        if res is None:
            return None
        centre = np.array([float(c) for c in res[0]])
        JF = self.jacobian(x)[0]
        try:
            step = np.linalg.solve(JF, centre)
        except np.linalg.LinAlgError:
            return None
        out = x - step
        return out if np.all(np.isfinite(out)) else None

    def certify(self, x: np.ndarray, positive: Sequence[bool]) -> np.ndarray | None:
        """Radii r of a box around x proven to hold exactly one admissible root ≠ θ*, or None.

        Proven: K(X) ⊂ int X (a unique root of F in X), X excludes θ*, the declared
        positive coordinates are > 0 on X, and every denominator ``d_i`` is nonzero on X.
        The radii are ``ρ |x_v|`` for the first ρ of :data:`RADII` that passes.
        """
        x = np.asarray(x, dtype=float)
        nv = self.nv
        if self.neq != nv or not np.all(np.isfinite(x)) or np.any(x == 0):
            return None
        res = self.residual(x)
        if res is None:
            return None
        centre, radius, (hi, lo, rad) = res
        JF, JFerr, JFabs, (_, fabs) = self.jacobian(x)
        try:
            Y = np.linalg.inv(JF)
        except np.linalg.LinAlgError:
            return None
        if not np.all(np.isfinite(Y)):
            return None
        aY = np.abs(Y)
        # |Y F(x̃)| ≤ |Y c| + |Y| rad, Y c exactly (rational arithmetic: Y's rows cancel F's ill-conditioned part)
        Yq = [[Fraction(float(v)) for v in row] for row in Y]
        Yc = np.array([_float_up(sum((a * c for a, c in zip(row, centre, strict=True)), Fraction(0)))
                       for row in Yq])
        s = _up(Yc + _up(aY @ radius, nv + 2), 2)  # ≥ |Y F(x̃)|
        R = np.eye(nv) - Y @ JF
        gam = (nv + 2) * U / (1.0 - (nv + 2) * U)
        M0 = _up(np.abs(R) + gam * (np.eye(nv) + aY @ np.abs(JF)) + aY @ JFerr, 2 * nv + 8)
        ax = np.abs(x)
        dens = [(_frac(hi[2 * i + 1], lo[2 * i + 1]), rad[2 * i + 1]) for i in range(self.neq)]
        dabs = fabs[1::2]
        deg_row = np.maximum(self.polys.poly_deg[0::2], self.polys.poly_deg[1::2])
        for rho in RADII:
            r = rho * ax
            if np.any(s >= 0.5 * r):
                continue  # the residual does not fit this radius: try a larger one
            grow = np.array([_growth(max(int(d) - 1, 0), rho) for d in deg_row])
            M = _up(M0 + aY @ (grow[:, None] * JFabs), nv + 4)
            b = _up(s + M @ r, nv + 2)
            if not np.all(b < r):
                continue
            r_up = r * (1.0 + 4.0 * U)
            if not any(abs(Fraction(xv) - sv) > Fraction(rv) for xv, sv, rv in zip(x, self.star, r_up, strict=True)):
                return None  # X may contain θ*
            if any(pos and not xv > 0 for pos, xv in zip(positive, x, strict=True)):
                return None
            for i, (dval, drad) in enumerate(dens):
                var = _growth(int(self.polys.poly_deg[2 * i + 1]), rho) * dabs[i]
                if not abs(dval) > Fraction(_up(drad + var, 4)):
                    return None  # a denominator may vanish in X
            return r_up
        return None
