"""Which splits of a driving-point impedance's poles between the two halves of a chain are possible.

A mass chain driven and measured at an interior mass j has the dynamic stiffness

    D(s) = m_j s² + Z_L(s) + Z_R(s),

Z_L and Z_R the impedances of the sub-chains on either side as seen from mass j, each
through the element e(s) = c s + k that ties it to j. The poles of D are those of Z_L and
of Z_R, so every solution θ of D(θ) = D(θ*) splits the 2n − 2 poles of D into 2a
of Z_L and 2b of Z_R (a, b masses on each side). This module tests every split against
two necessary conditions, so that only the splits some solution could have remain.

The conditions
--------------
Write D − m_j s² = α s + β + Σ_r ρ_r / (s − r) (partial fractions over the simple poles r)
and, for a split S of the poles, g_S(s) = Σ_{r ∈ S} ρ_r / (s − r). A side's impedance is
Z = c s + β_S + g_S (its polynomial part is c s + β_S because every mass is nonzero), and

1. *a free sub-chain* (no element to the ground) moves as a rigid body at s = 0: its own
   impedance is O(s²) there, so Z(0) = Z′(0) = 0, which gives c = Σ_S ρ_r / r² and
   β_S = Σ_S ρ_r / r. A grounded side gets c and β_S from the other side (the sums are α
   and β);
2. from Z = e D′ / (e + D′), e − Z = e² / (e + D′) has a double zero at s₀ = −k/c:
   Z(s₀) = 0 and Z′(s₀) = c, i.e. h(s₀) = 0 for h = Z = c s + β_S + g_S, and
   g_S′(s₀) = 0. With c and β_S fixed by the split, these are two equations in one unknown
   s₀: some root of h must be a critical point of g_S. A split for which no root of h is
   one, on either side, is impossible.

Both conditions hold on every solution outside a proper subvariety (a zero damper or a
vanishing cofactor), which the solutions for a generic θ* avoid.

How it is computed
------------------
The poles and residues are computed from the exact rational D in 40-digit arithmetic
(numpy's roots refined by Newton's method). For each split and side, the roots of h are
the eigenvalues of an arrowhead matrix built from the poles and residues (no polynomial
in the monomial basis is formed, so poles of very different sizes cost no accuracy),
and the residual is min over them of |Σ ρ_r/(s − r)²| / Σ |ρ_r/(s − r)²| (the relative size
of g′ there); a split's residual is the larger of its two sides'. All splits are tested
at once in double precision (numpy, in blocks); any split whose residual is below :data:`RECHECK`
(or within 1e4 of the smallest one, which shows the double computation's error on this
D) is recomputed in 40 digits (the eigenvalues refined by Newton's method on h), where it
passes below :data:`PASS` and fails above :data:`FAIL`. In between, or when a damper
value c of the split is not clearly nonzero, a root does not refine, the poles are not
simple or there are more than :data:`MAX_SPLITS` splits (10 masses and more), nothing is
decided. This is a floating-point test with wide margins, not an interval proof: on the
chains of ``benchmarks/identifiability_models.py`` driven at the middle mass (3–8
masses, five random points each; ``benchmarks/pole_split_margins.py``) θ*'s split is at
6e-35 or below and every other one at 1.7e-5 or above.
"""

from __future__ import annotations

import math
import threading
from itertools import combinations

import mpmath
import numpy as np
import sympy as sp

__all__ = ["FAIL", "MAX_SPLITS", "PASS", "RECHECK", "possible_splits", "split_residuals"]

DPS = 40
"""Decimal digits of the high-precision steps."""
RECHECK = 1e-4
"""Splits whose double-precision residual is below this are recomputed in 40 digits."""
PASS = 1e-25
"""40-digit residual below which a split passes (a solution could have it)."""
FAIL = 1e-12
"""40-digit residual above which a split fails."""
MAX_SPLITS = 20_000
"""More splits than this (10 masses and more; 3003 at 8 masses, 12 870 at 9) are not tried: nothing is decided."""
_CHUNK = 2048
"""Splits tested at once in double precision (bounds the memory: ~40 MB at 9 masses)."""
_C_MIN = 1e-8
"""A damper value c of a split smaller than this (relative to the sum of the magnitudes of its terms) is not clearly
nonzero: condition 2 needs c ≠ 0, so such a split is not decided."""


class _PerThread(threading.local):
    """mpmath's global context (its precision) is shared by every thread, and the confirmation at θ** runs this
    module in a thread beside the step at θ*: each thread computes in a context of its own."""

    def __init__(self):
        self.ctx = mpmath.MPContext()


_THREAD = _PerThread()


def _mpc(x: sp.Rational) -> mpmath.mpf:
    mp = _THREAD.ctx
    return mp.mpf(int(x.p)) / int(x.q)


def split_residuals(P: sp.Poly, rem: sp.Poly, alpha: sp.Rational, beta: sp.Rational, n_right: int,
                    left_free: bool) -> tuple[list, np.ndarray, np.ndarray, dict] | None:
    """Every split's residual (module notes): the arguments of :func:`possible_splits`.

    Returns
    -------
    (roots, splits, double, fine) or None
        The poles (40 digits), the splits (rows of pole indices given to Z_R), each
        split's double-precision residual, and ``{row: 40-digit residual or None}`` for
        the rows below :data:`RECHECK` (None: a damper value not clearly nonzero, or no
        root to test). None when the poles are not simple or there are more than
        :data:`MAX_SPLITS` splits.
    """
    mp = _THREAD.ctx
    if P.degree() < 2 or P.gcd(P.diff()).degree() > 0:
        return None  # a multiple pole: the partial fractions below do not apply
    if math.comb(P.degree(), n_right) > MAX_SPLITS:
        return None
    with mp.workdps(DPS):
        coeffs = [_mpc(c) for c in P.all_coeffs()]
        roots = _roots(coeffs)
        dP = P.diff()
        rho = [mp.polyval([_mpc(c) for c in rem.all_coeffs()], z)
               / mp.polyval([_mpc(c) for c in dP.all_coeffs()], z) for z in roots]
        al, be = _mpc(alpha), _mpc(beta)
        # in units of the poles' geometric mean size (the residuals are invariant under s → s/w: ρ → ρ/w,
        # α → α w), so that the double computation works on numbers near 1
        w = mp.exp(mp.fsum(mp.log(abs(r)) for r in roots) / len(roots)) if all(roots) else 1
        z = np.array([complex(r / w) for r in roots])
        rh = np.array([complex(r / w) for r in rho])
        splits = np.array(list(combinations(range(len(z)), n_right)), dtype=int)
        mask = np.ones((len(splits), len(z)), dtype=bool)
        mask[np.arange(len(splits))[:, None], splits] = False
        rest = np.nonzero(mask)[1].reshape(len(splits), len(z) - n_right)  # the other poles, in increasing order
        res = np.concatenate([_residual_double(z, rh, splits[i:i + _CHUNK], rest[i:i + _CHUNK], complex(al * w),
                                               complex(be), left_free) for i in range(0, len(splits), _CHUNK)])
        # the smallest double residual (θ*'s split, normally) shows the double computation's error on this D:
        # anything within 1e4 of it is rechecked, and NaN (a degenerate double computation) too
        limit = max(RECHECK, 1e4 * float(np.nanmin(res, initial=np.inf)))
        fine = {int(k): _residual_mp(roots, rho, list(splits[k]), list(rest[k]), al, be, left_free)
                for k in np.flatnonzero(~(res >= limit))}
    return roots, splits, res, fine


def possible_splits(P: sp.Poly, rem: sp.Poly, alpha: sp.Rational, beta: sp.Rational, n_right: int,
                    left_free: bool) -> tuple[list[tuple[complex, ...]], list[complex]] | None:
    """The pole splits that pass both necessary conditions (module notes), or None when undecided.

    Parameters
    ----------
    P : sympy.Poly
        Monic denominator of D (exact, rational), degree 2a + 2b.
    rem : sympy.Poly
        Remainder of D's numerator divided by P (so D − m s² − α s − β = rem / P).
    alpha, beta : sympy.Rational
        The polynomial part α s + β of D − m s².
    n_right : int
        2b, the number of poles of the free side Z_R.
    left_free : bool
        Whether the other side is free too (else grounded: its c and β_S are α − c_R, β − β_R).

    Returns
    -------
    (passing, roots) or None
        ``passing``: for every passing split, the poles given to Z_R (40-digit values as
        Python complex); ``roots``: all the poles. None when the poles are not simple or a
        split could not be decided.
    """
    found = split_residuals(P, rem, alpha, beta, n_right, left_free)
    if found is None:
        return None
    roots, splits, _, fine = found
    if any(r is None or PASS <= r <= FAIL for r in fine.values()):
        return None
    passing = [tuple(complex(roots[i]) for i in splits[k]) for k, r in fine.items() if r < PASS]
    return passing, [complex(r) for r in roots]


def _roots(coeffs: list) -> list:
    """All roots of a polynomial (mpmath coefficients, highest first) to the working precision.

    numpy's roots refined by Newton's method in working precision (a few ms); when a root
    does not converge or two refined roots coincide, ``mpmath.polyroots`` (a few hundred ms
    at degree 14) instead.
    """
    mp = _THREAD.ctx
    d = [coeffs[i] * (len(coeffs) - 1 - i) for i in range(len(coeffs) - 1)]
    tol = mp.mpf(10) ** (5 - mp.dps)
    out = []
    for x0 in np.roots([complex(c) for c in coeffs]):
        x = mp.mpc(x0)
        for _ in range(40):
            step = mp.polyval(coeffs, x) / mp.polyval(d, x)
            x -= step
            if abs(step) <= tol * max(abs(x), 1):
                break
        else:
            return mp.polyroots(coeffs, maxsteps=400, extraprec=4 * mp.dps)
        out.append(x)
    sep = min((abs(p - q) / max(abs(p), abs(q), 1) for i, p in enumerate(out) for q in out[:i]), default=1)
    if len(out) != len(coeffs) - 1 or sep < mp.mpf(10) ** (-mp.dps // 2):
        return mp.polyroots(coeffs, maxsteps=400, extraprec=4 * mp.dps)
    return out


# -- double precision, every split at once ------------------------------------------------------------------------

def _side_double(z, rho, idx, c, beta) -> np.ndarray:
    """Per row of ``idx``: min over the roots s of h = c s + β + Σ ρ_i/(s − z_i) of the relative size of g′(s).

    The roots of h are the eigenvalues of the arrowhead matrix [[−β/c, uᵀ], [v, diag(z)]]
    with u_i v_i = −ρ_i / c (its characteristic polynomial is (s + β/c + Σ ρ_i / (c (s − z_i)))
    Π (s − z_i)); no polynomial in the monomial basis is formed, so poles of very different
    sizes cost no accuracy.
    """
    B, k = idx.shape
    with np.errstate(all="ignore"):
        A = np.zeros((B, k + 1, k + 1), dtype=complex)
        A[:, 0, 0] = -beta / c
        A[:, 0, 1:] = 1.0
        A[:, 1:, 0] = -rho[idx] / c[:, None]
        A[:, np.arange(1, k + 1), np.arange(1, k + 1)] = z[idx]
        ok = np.isfinite(A).all(axis=(1, 2))
        A[~ok] = 0
        s0 = np.linalg.eigvals(A)  # (B, k + 1)
        terms = rho[idx][:, None, :] / (s0[:, :, None] - z[idx][:, None, :]) ** 2
        res = np.abs(terms.sum(axis=2)) / np.abs(terms).sum(axis=2)
        out = res.min(axis=1)
    out[~ok] = np.nan  # c = 0 or overflow: recomputed in 40 digits
    return out


def _residual_double(z, rho, right, left, al, be, left_free) -> np.ndarray:
    """The larger of the two sides' residuals per split (the side with fewer poles first: a split it fails is not
    tested on the other side)."""
    cR = (rho[right] / z[right] ** 2).sum(axis=1)
    bR = (rho[right] / z[right]).sum(axis=1)
    if left_free:
        cL = (rho[left] / z[left] ** 2).sum(axis=1)
        bL = (rho[left] / z[left]).sum(axis=1)
        out = np.abs(cL + cR - al) / (np.abs(cL) + np.abs(cR) + abs(al)) \
            + np.abs(bL + bR - be) / (np.abs(bL) + np.abs(bR) + abs(be))
    else:
        cL, bL, out = al - cR, be - bR, np.zeros(len(right))
    cL, bL = np.broadcast_to(cL, cR.shape), np.broadcast_to(bL, bR.shape)
    sides = [(left, cL, bL), (right, cR, bR)]
    sides.sort(key=lambda t: t[0].shape[1])
    for idx, c, b in sides:
        todo = np.flatnonzero(~(out >= RECHECK))
        if len(todo):
            r = _side_double(z, rho, idx[todo], c[todo], b[todo])
            out[todo] = np.where(np.isnan(r), np.nan, np.maximum(out[todo], r))  # NaN: rechecked in 40 digits
    return out


# -- 40 digits, one split ---------------------------------------------------------------------------------------

def _side_mp(roots, rho, S, c, beta, cscale, free: bool) -> mpmath.mpf | None:
    """:func:`_side_double` for one split in working precision: the double eigenvalues refined by Newton's method
    on h (partial fractions); None when c is not clearly nonzero or a root does not refine to a distinct one.

    On a free side c and β make h = Z vanish to second order at 0 (condition 1), a double
    root at which g′(0) = −c ≠ 0: the two eigenvalues nearest 0 are that root and are left out.
    """
    mp = _THREAD.ctx
    if abs(c) < _C_MIN * cscale:
        return None
    z = [roots[i] for i in S]
    r = [rho[i] for i in S]
    k = len(S)
    A = np.zeros((k + 1, k + 1), dtype=complex)
    A[0, 0] = complex(-beta / c)
    A[0, 1:] = 1.0
    A[1:, 0] = [complex(-x / c) for x in r]
    A[np.arange(1, k + 1), np.arange(1, k + 1)] = [complex(x) for x in z]
    if not np.isfinite(A).all():
        return None
    tol = mp.mpf(10) ** (5 - mp.dps)
    found = []
    eig = sorted(np.linalg.eigvals(A), key=abs)
    if free:  # the double root splits into two eigenvalues ~ sqrt(u) from 0: they must stand apart from the rest
        if len(eig) < 3 or abs(eig[1]) > 1e-3 * abs(eig[2]):
            return None
        eig = eig[2:]
    for x0 in eig:
        x = mp.mpc(x0)
        for _ in range(60):
            h = c * x + beta + mp.fsum(ri / (x - zi) for ri, zi in zip(r, z, strict=True))
            dh = c - mp.fsum(ri / (x - zi) ** 2 for ri, zi in zip(r, z, strict=True))
            step = h / dh
            x -= step
            if abs(step) <= tol * max(abs(x), 1):
                break
        else:
            return None
        found.append(x)
    sep = min((abs(p - q) / max(abs(p), abs(q), 1) for i, p in enumerate(found) for q in found[:i]), default=1)
    if sep < mp.mpf(10) ** (-mp.dps // 2):
        return None  # two eigenvalues refined to one root: one may be missed
    best = None
    for x in found:
        terms = [ri / (x - zi) ** 2 for ri, zi in zip(r, z, strict=True)]
        v = abs(mp.fsum(terms)) / mp.fsum(abs(t) for t in terms)
        best = v if best is None else min(best, v)
    return best


def _residual_mp(roots, rho, right, left, al, be, left_free) -> float | None:
    mp = _THREAD.ctx
    cR = mp.fsum(rho[i] / roots[i] ** 2 for i in right)
    bR = mp.fsum(rho[i] / roots[i] for i in right)
    gap = mp.mpf(0)
    if left_free:
        cL = mp.fsum(rho[i] / roots[i] ** 2 for i in left)
        bL = mp.fsum(rho[i] / roots[i] for i in left)
        gap = abs(cL + cR - al) / (abs(cL) + abs(cR) + abs(al)) + abs(bL + bR - be) / (abs(bL) + abs(bR) + abs(be))
    else:
        cL, bL = al - cR, be - bR
    terms = {i: abs(rho[i] / roots[i] ** 2) for i in range(len(roots))}
    sR = mp.fsum(terms[i] for i in right)
    sL = mp.fsum(terms[i] for i in left) if left_free else sR + abs(al)
    sides = [_side_mp(roots, rho, right, cR, bR, sR, True), _side_mp(roots, rho, left, cL, bL, sL, left_free)]
    if any(x is None for x in sides):
        return None
    return float(max(*sides, gap))
