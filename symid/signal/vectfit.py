"""Vector fitting: a rational black box of a frequency response, with common poles for every entry.

Relaxed vector fitting (Gustavsen & Semlyen 1999, IEEE Trans. Power Delivery 14(3),
"Rational approximation of frequency domain responses by vector fitting"; the relaxed
normalisation of Gustavsen 2006, IEEE Trans. Power Delivery 21(3)) fits

    H(s) ≈ Σᵢ Rᵢ / (s − aᵢ) + D (+ s E),    s = jω,

with N poles aᵢ shared by every entry of H (p × m) and residue matrices Rᵢ. Each
iteration solves a linear least squares problem for a weighting function
σ(s) = Σᵢ c̃ᵢ / (s − aᵢ) + d̃ with σH rational of the same poles; the zeros of σ become
the next poles (the eigenvalues of A − b c̃ᵀ / d̃ of a real realisation), unstable ones
reflected into the left half plane. With the poles fixed, the residues, D and E are a
linear least squares problem. The entries are coupled only through σ: each entry's
own unknowns are eliminated by a QR factorisation first (the "fast" variant,
Deschrijver, Mrozowski, Dhaene & De Zutter 2008, IEEE Microwave Wireless Comp. Lett.
18(6)). Frequencies are scaled by the largest one inside, so the linear systems are
well conditioned in any unit of time.

Starting poles are complex pairs with imaginary parts spread log-uniformly over the
band and real parts 1 % of them (Gustavsen & Semlyen's recommendation), plus one real
pole at the band's lower edge when N is odd.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from symid.errors import DataError, OptionError

__all__ = ["VectorFit", "modes_of_poles", "vector_fit"]


@dataclass(frozen=True)
class VectorFit:
    """A rational model H(s) = Σᵢ Rᵢ / (s − aᵢ) + D + s E fitted by :func:`vector_fit`.

    Attributes
    ----------
    poles : numpy.ndarray, shape (N,)
        The poles aᵢ (rad/s), every one with Re aᵢ ≤ 0: real poles first, then complex
        pairs (Im > 0 first, its conjugate next), each group sorted by |aᵢ|.
    residues : numpy.ndarray, shape (N, p, m)
        The residue matrix Rᵢ of each pole (conjugate pairs have conjugate residues).
    D, E : numpy.ndarray, shape (p, m)
        Constant and proportional terms (E is zero unless asked for).
    rms : float
        Root-mean-square weighted error of the fit, relative to the weighted data.
    iterations : int
        Pole relocation iterations run.
    """

    poles: np.ndarray
    residues: np.ndarray
    D: np.ndarray
    E: np.ndarray
    rms: float
    iterations: int

    def response(self, w: Any) -> np.ndarray:
        """H(jω) of the rational model at angular frequencies ``w``, shape (s, p, m)."""
        s = 1j * np.asarray(w, dtype=float).reshape(-1)
        terms = 1.0 / (s[:, None] - self.poles[None, :])
        return (np.einsum("ki,ipm->kpm", terms, self.residues) + self.D[None] + s[:, None, None] * self.E[None])

    def modes(self) -> tuple[np.ndarray, np.ndarray]:
        """Natural frequencies (rad/s) and damping ratios of the poles (:func:`modes_of_poles`)."""
        return modes_of_poles(self.poles)


def modes_of_poles(poles: Any) -> tuple[np.ndarray, np.ndarray]:
    """Natural frequency ωₙ and damping ratio ζ of every second-order factor of a set of poles.

    A complex pair a, a* is the factor s² + 2ζωₙ s + ωₙ² with ωₙ = |a|, ζ = −Re a / |a|;
    real poles are paired with their neighbour by magnitude (ωₙ = √(a₁a₂),
    ζ = −(a₁ + a₂) / (2ωₙ) ≥ 1), and a last real pole left alone is reported with ζ = 1
    and ωₙ = |a|.

    Parameters
    ----------
    poles : array_like of complex
        Poles closed under conjugation (a complex pole without its conjugate is an error).

    Returns
    -------
    wn, zeta : numpy.ndarray
        Sorted by ωₙ.

    Examples
    --------
    >>> from symid.signal.vectfit import modes_of_poles
    >>> wn, zeta = modes_of_poles([-0.1 + 9.9995j, -0.1 - 9.9995j, -2.0, -8.0])
    >>> [round(float(v), 4) for v in wn], [round(float(v), 4) for v in zeta]
    ([4.0, 10.0], [1.25, 0.01])
    """
    p = np.asarray(poles, dtype=complex).reshape(-1)
    scale = float(np.max(np.abs(p))) if p.size else 1.0
    real_mask = np.abs(p.imag) <= 1e-12 * max(scale, 1e-300)
    upper = p[(~real_mask) & (p.imag > 0)]
    lower = p[(~real_mask) & (p.imag < 0)]
    if upper.size != lower.size or not np.allclose(np.sort_complex(np.conj(lower)), np.sort_complex(upper),
                                                   rtol=1e-8, atol=1e-12 * scale):
        raise DataError("poles must come in complex-conjugate pairs")
    wn = list(np.abs(upper))
    zeta = list(-upper.real / np.abs(upper))
    reals = np.sort(p[real_mask].real)[::-1]  # by magnitude for stable poles: −0.1, −2, ...
    reals = reals[np.argsort(np.abs(reals))]
    for i in range(0, reals.size - 1, 2):
        a1, a2 = reals[i], reals[i + 1]
        w = math.sqrt(abs(a1 * a2))
        wn.append(w)
        zeta.append(-(a1 + a2) / (2 * w) if w > 0 else 1.0)
    if reals.size % 2:
        wn.append(abs(reals[-1]))
        zeta.append(1.0)
    wn_a, zeta_a = np.array(wn, dtype=float), np.array(zeta, dtype=float)
    order = np.argsort(wn_a, kind="stable")
    return wn_a[order], zeta_a[order]


def _basis(s: np.ndarray, poles: np.ndarray) -> np.ndarray:
    """Real-coefficient basis of partial fractions: 1/(s−a) for a real pole; for a pair a, a*
    the two columns 1/(s−a) + 1/(s−a*) and j/(s−a) − j/(s−a*)."""
    cols = []
    i = 0
    while i < poles.size:
        a = poles[i]
        if a.imag == 0:
            cols.append(1.0 / (s - a))
            i += 1
        else:
            f1, f2 = 1.0 / (s - a), 1.0 / (s - np.conj(a))
            cols.append(f1 + f2)
            cols.append(1j * f1 - 1j * f2)
            i += 2
    return np.stack(cols, axis=1)


def _realisation(poles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Real (A, b) with cᵀ(sI − A)⁻¹b equal to the basis of :func:`_basis` weighted by c."""
    n = poles.size
    A = np.zeros((n, n))
    b = np.zeros(n)
    i = 0
    while i < n:
        a = poles[i]
        if a.imag == 0:
            A[i, i], b[i] = a.real, 1.0
            i += 1
        else:
            A[i:i + 2, i:i + 2] = [[a.real, a.imag], [-a.imag, a.real]]
            b[i] = 2.0
            i += 2
    return A, b


def _ordered(poles: np.ndarray) -> np.ndarray:
    """Stable (reflected), conjugate-closed poles: real ones first, then pairs (Im > 0, conjugate)."""
    p = np.asarray(poles, dtype=complex)
    p = np.where(p.real > 0, -np.conj(p), p)  # reflect unstable poles (Gustavsen & Semlyen 1999)
    scale = max(float(np.max(np.abs(p))), 1e-300)
    real = np.abs(p.imag) <= 1e-10 * scale
    r = np.sort(p[real].real)
    r = r[np.argsort(np.abs(r), kind="stable")].astype(complex)
    up = p[(~real) & (p.imag > 0)]
    up = up[np.argsort(np.abs(up), kind="stable")]
    pairs = np.empty(2 * up.size, dtype=complex)
    pairs[0::2], pairs[1::2] = up, np.conj(up)
    out = np.concatenate([r, pairs])
    if out.size != p.size:  # an unmatched complex pole (rounding): rebuild from the upper half plane only
        raise np.linalg.LinAlgError("poles lost their conjugate structure")
    return out


def _ri(x: np.ndarray) -> np.ndarray:
    return np.concatenate([x.real, x.imag], axis=0)


def vector_fit(w: Any, H: Any, n_poles: int, *, weight: Any = None, n_iter: int = 30, tol: float = 1e-10,
               D: bool = True, E: bool = False, poles: Any = None) -> VectorFit:
    """Fit a rational model with ``n_poles`` common poles to a frequency response (module docstring).

    Parameters
    ----------
    w : array_like, shape (s,)
        Angular frequencies (rad/s), > 0.
    H : array_like, shape (s,), (s, p) or (s, p, m)
        Complex response at ``w``.
    n_poles : int
        Number of poles N (a conjugate pair counts two). The linear systems need at
        least N + 2 frequencies.
    weight : array_like or "relative", optional
        Weight of every entry's error (real, ≥ 0, shaped like ``H``), or ``"relative"``
        for 1/|H| (each line's error relative to its level; a level below 1e-8 of the
        entry's largest is floored there). Default: 1.
    n_iter : int, optional
        Pole relocation iterations at most (default 30).
    tol : float, optional
        Stop once no pole moves by more than ``tol`` times the largest frequency.
    D, E : bool, optional
        Fit the constant term D (default) and the proportional term E (default not).
    poles : array_like, optional
        Starting poles instead of the default spread (module docstring).

    Returns
    -------
    VectorFit

    Raises
    ------
    DataError
        Frequencies that are not positive and finite, a non-finite response, or fewer
        than N + 2 frequencies.
    OptionError
        A bad ``n_poles``, ``weight``, ``n_iter`` or ``poles``.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.signal.vectfit import vector_fit
    >>> w = np.linspace(1.0, 30.0, 200)
    >>> s = 1j * w
    >>> H = 1 / (s**2 + 0.2 * s + 100) + 2 / (s**2 + 0.5 * s + 400)   # modes at 10 and 20 rad/s
    >>> fit = vector_fit(w, H, 4)
    >>> wn, zeta = fit.modes()
    >>> np.round(wn, 6).tolist(), np.round(zeta, 6).tolist()
    ([10.0, 20.0], [0.01, 0.0125])
    """
    w = np.asarray(w, dtype=float).reshape(-1)
    Hc = np.asarray(H, dtype=complex)
    if Hc.ndim == 1:
        Hc = Hc[:, None, None]
    elif Hc.ndim == 2:
        Hc = Hc[:, :, None]
    if Hc.ndim != 3 or Hc.shape[0] != w.size:
        raise DataError(f"H must have shape (s,), (s, p) or (s, p, m) with s = {w.size} frequencies; "
                        f"got {np.shape(H)}")
    if not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise DataError("frequencies must be positive and finite")
    if not np.all(np.isfinite(Hc)):
        raise DataError("the response holds non-finite values")
    if isinstance(n_poles, bool) or not isinstance(n_poles, (int, np.integer)) or n_poles < 1:
        raise OptionError(f"n_poles must be an integer >= 1; got {n_poles!r}")
    n_poles = int(n_poles)
    if isinstance(n_iter, bool) or not isinstance(n_iter, (int, np.integer)) or n_iter < 0:
        raise OptionError(f"n_iter must be an integer >= 0; got {n_iter!r}")
    if w.size < n_poles + 2:
        raise DataError(f"vector fitting with {n_poles} poles needs at least {n_poles + 2} frequencies; "
                        f"the data have {w.size}")
    s_count, p, m = Hc.shape
    F = Hc.reshape(s_count, p * m)
    if weight is None:
        W = np.ones_like(F, dtype=float)
    elif isinstance(weight, str):
        if weight != "relative":
            raise OptionError(f"weight must be an array or 'relative'; got {weight!r}")
        mag = np.abs(F)
        floor = 1e-8 * np.max(mag, axis=0, keepdims=True)
        W = 1.0 / np.maximum(mag, np.where(floor > 0, floor, 1.0))
    else:
        try:
            Wa = np.asarray(weight, dtype=float)
            if Wa.shape == np.shape(H):
                Wa = Wa.reshape(Hc.shape)
            W = np.broadcast_to(Wa, Hc.shape).reshape(s_count, p * m)
        except (TypeError, ValueError):
            raise OptionError(f"weight must be real numbers shaped like H {np.shape(H)}; got shape "
                              f"{np.shape(weight)}") from None
        if not np.all(np.isfinite(W)) or np.any(W < 0):
            raise OptionError("weight must be finite and >= 0")
    wc = float(w.max())
    s = 1j * w / wc  # scaled frequencies

    if poles is None:
        n_pairs = n_poles // 2
        lo, hi = float(w.min()) / wc, 1.0
        beta = np.geomspace(lo, hi, n_pairs) if n_pairs > 1 else np.array([math.sqrt(lo * hi)] * n_pairs)
        start = [complex(-0.01 * b, b) for b in beta]
        a = np.array([v for c in start for v in (c, np.conj(c))] + ([-lo] if n_poles % 2 else []), dtype=complex)
    else:
        a = np.asarray(poles, dtype=complex).reshape(-1) / wc
        if a.size != n_poles or not np.all(np.isfinite(a)):
            raise OptionError(f"poles must be {n_poles} finite values")
    try:
        a = _ordered(a)
    except np.linalg.LinAlgError:
        raise OptionError("poles must be closed under conjugation") from None

    n_ent = F.shape[1]
    iterations = 0
    for it in range(n_iter):
        Phi = _basis(s, a)  # (s, N)
        blocks = []
        for e in range(n_ent):
            We = W[:, e]
            own = [Phi * We[:, None]]
            if D:
                own.append(We[:, None].astype(complex))
            if E:
                own.append((s * We)[:, None])
            own_m = np.concatenate(own, axis=1)
            shared = np.concatenate([-(We * F[:, e])[:, None] * Phi, -(We * F[:, e])[:, None]], axis=1)
            Areal = _ri(np.concatenate([own_m, shared], axis=1))
            R = np.linalg.qr(Areal, mode="r")
            k_own = own_m.shape[1]
            blocks.append(R[k_own:k_own + n_poles + 1, k_own:])
        # the relaxed normalisation: Re Σₖ σ(sₖ) = s_count, weighted like the data
        scale = math.sqrt(float(np.sum(np.abs(W * F) ** 2))) / s_count
        norm_row = scale * np.concatenate([np.sum(Phi, axis=0).real, [s_count]])
        A_sys = np.vstack([*blocks, norm_row[None, :]])
        b_sys = np.zeros(A_sys.shape[0])
        b_sys[-1] = scale * s_count
        col = np.linalg.norm(A_sys, axis=0)
        col[col == 0] = 1.0
        x = np.linalg.lstsq(A_sys / col, b_sys, rcond=None)[0] / col
        c_sig, d_sig = x[:n_poles], x[n_poles]
        if abs(d_sig) < 1e-8:  # the relaxation degenerates: fix d̃ (Gustavsen 2006)
            d_sig = 1e-8 * (1.0 if d_sig >= 0 else -1.0)
            A2 = np.vstack(blocks)
            x2 = np.linalg.lstsq(A2[:, :n_poles], -A2[:, n_poles] * d_sig, rcond=None)[0]
            c_sig = x2
        Ar, br = _realisation(a)
        new = np.linalg.eigvals(Ar - np.outer(br, c_sig) / d_sig)
        try:
            new = _ordered(new)
        except np.linalg.LinAlgError:  # pragma: no cover - eigvals of a real matrix are conjugate-closed
            break
        iterations = it + 1
        moved = float(np.max(np.abs(np.sort_complex(new) - np.sort_complex(a))))
        a = new
        if moved < tol:
            break

    # residues, D, E with the poles fixed: one linear least squares per entry
    Phi = _basis(s, a)
    res_coef = np.zeros((n_poles, n_ent))
    Dv = np.zeros(n_ent)
    Ev = np.zeros(n_ent)
    err2 = 0.0
    for e in range(n_ent):
        We = W[:, e]
        cols = [Phi]
        if D:
            cols.append(np.ones((s_count, 1), dtype=complex))
        if E:
            cols.append(s[:, None])
        Amat = np.concatenate(cols, axis=1)
        Areal = _ri(Amat * We[:, None])
        breal = _ri(We * F[:, e])
        col = np.linalg.norm(Areal, axis=0)
        col[col == 0] = 1.0
        x = np.linalg.lstsq(Areal / col, breal, rcond=None)[0] / col
        res_coef[:, e] = x[:n_poles]
        if D:
            Dv[e] = x[n_poles]
        if E:
            Ev[e] = x[n_poles + int(D)]
        err2 += float(np.sum((Areal @ x - breal) ** 2))
    total = float(np.sum(np.abs(W * F) ** 2))
    rms = math.sqrt(err2 / total) if total > 0 else 0.0
    # complex residues from the real basis coefficients, back in unscaled units
    residues = np.zeros((n_poles, n_ent), dtype=complex)
    i = 0
    while i < n_poles:
        if a[i].imag == 0:
            residues[i] = res_coef[i]
            i += 1
        else:
            r = res_coef[i] + 1j * res_coef[i + 1]
            residues[i], residues[i + 1] = r, np.conj(r)
            i += 2
    return VectorFit(poles=a * wc, residues=(residues * wc).reshape(n_poles, p, m), D=Dv.reshape(p, m),
                     E=(Ev / wc).reshape(p, m), rms=rms, iterations=iterations)
