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
2. from Z = e D′ / (e + D′) (D′ the sub-chain's own impedance), e − Z = e² / (e + D′) has a
   double zero at s₀ = −k/c: Z(s₀) = 0 and Z′(s₀) = c, i.e. g_S′(s₀) = 0 and
   g_S(s₀) + c s₀ + β_S = 0. With c and β_S fixed by the split, these are two equations in
   one unknown s₀: the numerators G = N′F − N F′ of g_S′ and H = N + (c s + β_S) F
   (g_S = N/F) must have a common root. A split whose G and H share no root on either side
   is impossible.

Both conditions hold on every solution outside a proper subvariety (a zero damper or a
vanishing cofactor), which the solutions for a generic θ* avoid.

How it is computed
------------------
The poles and residues are computed from the exact rational D in 40-digit arithmetic
(``mpmath.polyroots``); every split is then tested in double precision, all splits at
once (numpy): the relative residual min over the roots s₀ of G of
|H(s₀)| / (|N(s₀)| + |(c s₀ + β_S) F(s₀)|), the larger of the two sides'. Any split whose
double residual is below :data:`RECHECK` is recomputed in 40-digit arithmetic, where it
passes below :data:`PASS` and fails above :data:`FAIL`; in between (or when a damper
value c of the split is not clearly nonzero, or the poles are not simple) nothing is
decided. This is a floating-point test with wide margins (on the chains of
``benchmarks/identifiability_models.py`` the passing split is at 1e-40 and the nearest
failing one above 1e-5), not an interval proof.
"""

from __future__ import annotations

from itertools import combinations

import mpmath
import numpy as np
import sympy as sp

__all__ = ["FAIL", "PASS", "RECHECK", "possible_splits"]

DPS = 40
"""Decimal digits of the high-precision steps."""
RECHECK = 1e-4
"""Splits whose double-precision residual is below this are recomputed in 40 digits."""
PASS = 1e-25
"""40-digit residual below which a split passes (a solution could have it)."""
FAIL = 1e-12
"""40-digit residual above which a split fails."""
_C_MIN = 1e-8
"""A damper value c of a split smaller than this (relative to the sum of the magnitudes of its terms) is not clearly
nonzero: condition 2 needs c ≠ 0, so such a split is not decided."""


def _mpc(x: sp.Rational) -> mpmath.mpf:
    return mpmath.mpf(int(x.p)) / int(x.q)


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
    if P.degree() < 2 or P.gcd(P.diff()).degree() > 0:
        return None  # a multiple pole: the partial fractions below do not apply
    with mpmath.workdps(DPS):
        coeffs = [_mpc(c) for c in P.all_coeffs()]
        roots = _roots(coeffs)
        dP = P.diff()
        rho = [mpmath.polyval([_mpc(c) for c in rem.all_coeffs()], z)
               / mpmath.polyval([_mpc(c) for c in dP.all_coeffs()], z) for z in roots]
        al, be = _mpc(alpha), _mpc(beta)
        z = np.array([complex(r) for r in roots])
        rh = np.array([complex(r) for r in rho])
        splits = np.array(list(combinations(range(len(z)), n_right)), dtype=int)
        mask = np.ones((len(splits), len(z)), dtype=bool)
        mask[np.arange(len(splits))[:, None], splits] = False
        rest = np.nonzero(mask)[1].reshape(len(splits), len(z) - n_right)  # the other poles, in increasing order
        res = _residual_double(z, rh, splits, rest, complex(al), complex(be), left_free)
        passing = []
        for k in np.flatnonzero(~(res >= RECHECK)):  # NaN (a degenerate double computation) is rechecked too
            r = _residual_mp(roots, rho, list(splits[k]), list(rest[k]), al, be, left_free)
            if r is None or PASS <= r <= FAIL:
                return None
            if r < PASS:
                passing.append(tuple(complex(roots[i]) for i in splits[k]))
    return passing, [complex(r) for r in roots]


def _roots(coeffs: list) -> list:
    """All roots of a polynomial (mpmath coefficients, highest first) to the working precision.

    numpy's roots refined by Newton's method in working precision (a few ms); when a root
    does not converge or two refined roots coincide, ``mpmath.polyroots`` (a few hundred ms
    at degree 14) instead.
    """
    d = [coeffs[i] * (len(coeffs) - 1 - i) for i in range(len(coeffs) - 1)]
    tol = mpmath.mpf(10) ** (5 - mpmath.mp.dps)
    out = []
    for x0 in np.roots([complex(c) for c in coeffs]):
        x = mpmath.mpc(x0)
        for _ in range(40):
            step = mpmath.polyval(coeffs, x) / mpmath.polyval(d, x)
            x -= step
            if abs(step) <= tol * max(abs(x), 1):
                break
        else:
            return mpmath.polyroots(coeffs, maxsteps=400, extraprec=4 * mpmath.mp.dps)
        out.append(x)
    sep = min((abs(p - q) / max(abs(p), abs(q), 1) for i, p in enumerate(out) for q in out[:i]), default=1)
    if len(out) != len(coeffs) - 1 or sep < mpmath.mpf(10) ** (-mpmath.mp.dps // 2):
        return mpmath.polyroots(coeffs, maxsteps=400, extraprec=4 * mpmath.mp.dps)
    return out


# -- double precision, every split at once ------------------------------------------------------------------------

def _polys(z: np.ndarray, rho: np.ndarray, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """F = Π (s − z_i) and N = Σ ρ_i F / (s − z_i) over each row of idx (coefficients, highest first)."""
    B, k = idx.shape
    F = np.ones((B, 1), dtype=complex)
    for t in range(k):
        zt = z[idx[:, t]][:, None]
        G = np.zeros((B, F.shape[1] + 1), dtype=complex)
        G[:, :-1] += F
        G[:, 1:] -= zt * F
        F = G
    N = np.zeros((B, k), dtype=complex)
    for t in range(k):
        zt = z[idx[:, t]]
        q = np.zeros((B, k), dtype=complex)  # F / (s − z_t) by synthetic division
        acc = np.zeros(B, dtype=complex)
        for i in range(k):
            acc = F[:, i] + zt * acc
            q[:, i] = acc
        N += rho[idx[:, t]][:, None] * q
    return F, N


def _der(p: np.ndarray) -> np.ndarray:
    d = p.shape[1] - 1
    return p[:, :-1] * np.arange(d, 0, -1)


def _mul(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    out = np.zeros((p.shape[0], p.shape[1] + q.shape[1] - 1), dtype=complex)
    for i in range(p.shape[1]):
        out[:, i:i + q.shape[1]] += p[:, i:i + 1] * q
    return out


def _horner(p: np.ndarray, x: np.ndarray) -> np.ndarray:
    out = np.zeros_like(x)
    for i in range(p.shape[1]):
        out = out * x + p[:, i:i + 1]
    return out


def _side_double(z, rho, idx, c, beta) -> np.ndarray:
    F, N = _polys(z, rho, idx)
    G = _mul(_der(N), F) - _mul(N, _der(F))  # both of degree 2k − 2
    lead = G[:, 0]
    with np.errstate(all="ignore"):
        comp = np.zeros((len(G), G.shape[1] - 1, G.shape[1] - 1), dtype=complex)
        comp[:, 0, :] = -G[:, 1:] / lead[:, None]
        if G.shape[1] > 2:
            comp[:, np.arange(1, G.shape[1] - 1), np.arange(G.shape[1] - 2)] = 1
        ok = np.isfinite(comp).all(axis=(1, 2)) & (np.abs(lead) > 1e-10 * np.abs(G).max(axis=1))
        comp[~ok] = 0
        s0 = np.linalg.eigvals(comp)
        Nv, Fv = _horner(N, s0), _horner(F, s0)
        lin = (c[:, None] * s0 + beta[:, None]) * Fv
        res = np.abs(Nv + lin) / (np.abs(Nv) + np.abs(lin))
        out = res.min(axis=1)
    out[~ok] = np.nan  # a degree drop: recomputed in 40 digits
    return out


def _residual_double(z, rho, right, left, al, be, left_free) -> np.ndarray:
    """The larger of the two sides' residuals per split (the side with fewer poles first: a split it fails is not
    tested on the other side, whose polynomials are of higher degree)."""
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

def _pmul(p, q):
    out = [mpmath.mpc(0)] * (len(p) + len(q) - 1)
    for i, x in enumerate(p):
        for j, y in enumerate(q):
            out[i + j] += x * y
    return out


def _pder(p):
    d = len(p) - 1
    return [p[i] * (d - i) for i in range(d)]


def _side_mp(roots, rho, S, c, beta, cscale) -> mpmath.mpf | None:
    if abs(c) < _C_MIN * cscale:
        return None
    F = [mpmath.mpc(1)]
    for i in S:
        F = _pmul(F, [1, -roots[i]])
    N = [mpmath.mpc(0)] * (len(F) - 1)
    for i in S:
        q, acc = [], mpmath.mpc(0)
        for a in F[:-1]:
            acc = a + roots[i] * acc
            q.append(acc)
        N = [x + rho[i] * y for x, y in zip(N, q, strict=True)]
    A, Bq = _pmul(_pder(N), F), _pmul(N, _pder(F))
    A = [mpmath.mpc(0)] * (len(Bq) - len(A)) + A
    G = [x - y for x, y in zip(A, Bq, strict=True)]
    big = max(abs(x) for x in G)
    while len(G) > 1 and abs(G[0]) < mpmath.mpf(10) ** (-DPS // 2) * big:
        G = G[1:]
    if len(G) < 2:
        return None
    best = None
    for s0 in _roots(G):
        Nv, lin = mpmath.polyval(N, s0), (c * s0 + beta) * mpmath.polyval(F, s0)
        r = abs(Nv + lin) / (abs(Nv) + abs(lin))
        best = r if best is None else min(best, r)
    return best


def _residual_mp(roots, rho, right, left, al, be, left_free) -> float | None:
    cR = mpmath.fsum(rho[i] / roots[i] ** 2 for i in right)
    bR = mpmath.fsum(rho[i] / roots[i] for i in right)
    gap = mpmath.mpf(0)
    if left_free:
        cL = mpmath.fsum(rho[i] / roots[i] ** 2 for i in left)
        bL = mpmath.fsum(rho[i] / roots[i] for i in left)
        gap = abs(cL + cR - al) / (abs(cL) + abs(cR) + abs(al)) + abs(bL + bR - be) / (abs(bL) + abs(bR) + abs(be))
    else:
        cL, bL = al - cR, be - bR
    terms = {i: abs(rho[i] / roots[i] ** 2) for i in range(len(roots))}
    sR = mpmath.fsum(terms[i] for i in right)
    sL = mpmath.fsum(terms[i] for i in left) if left_free else sR + abs(al)
    sides = [_side_mp(roots, rho, right, cR, bR, sR), _side_mp(roots, rho, left, cL, bL, sL)]
    if any(x is None for x in sides):
        return None
    return float(max(*sides, gap))
