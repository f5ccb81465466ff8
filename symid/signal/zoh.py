"""Exact zero-order-hold conversion of a discrete-time state-space model to continuous time.

The zero-order-hold (ZOH) discretisation of ``x' = A x + B u`` over a sample time dt is
``Ad = e^{A dt}``, ``Bd = ∫₀^dt e^{Aτ} dτ B``, or in one block exponential

    expm([[A, B], [0, 0]] dt) = [[Ad, Bd], [0, I]]

(:func:`symid.signal.simulate.zoh_discretize`). The inverse is the matrix logarithm of the
same block matrix, ``[[A, B], [0, 0]] = logm([[Ad, Bd], [0, I]]) / dt`` (the method of
MATLAB's ``d2c``). We use :func:`scipy.linalg.logm` (inverse scaling and squaring,
Al-Mohy & Higham 2012) on the augmented matrix: it is exact up to rounding and keeps
B consistent with A, which inverting Bd = A⁻¹(Ad − I)B would not for singular A.
Before the logarithm the augmented matrix is balanced, ``big = S bal S⁻¹`` with S a
diagonal of powers of two (:func:`scipy.linalg.matrix_balance`, the LAPACK ``gebal``
scaling without permutation, so S is applied exactly), and ``logm(big) = S logm(bal) S⁻¹``.
On states of very different scale (1e±3) the unbalanced logarithm loses up to seven
digits; the balanced one keeps the round trip to about 1e-13
(``benchmarks/signal_layer.py`` measures both).
python-control offers ``c2d`` (``sample_system``) but no ``d2c``, and harold's
``undiscretize`` has had a bug on this very step, so a well-kept library function
does not exist; the scipy primitive does the work.

A real continuous-time model exists only when the principal logarithm of Ad is real:
no eigenvalue of Ad may lie on the closed negative real axis (an eigenvalue ≤ 0 means
the sampling aliases a mode to the Nyquist frequency or the model is not a sampled
continuous-time system). That case raises :class:`~symid.errors.DataError`, unless
such modes are dropped first: ``band=(w_low, w_high)`` keeps only the modes whose
continuous-time natural frequency |s| = |ln z| / dt lies in the band. A mode on the
negative real axis has |s| ≥ π/dt (the Nyquist frequency), so any ``w_high`` below π/dt
drops it, and a band of interest drops the fast (or slow) modes a black box fitted
to noise. The modes are separated exactly: an ordered real Schur form puts the kept
eigenvalues first, and a Sylvester equation decouples them from the others
(Golub & Van Loan, *Matrix Computations*, 4th ed., §7.6), so the kept modes keep
their poles and residues; the dropped modes' contribution (their static gain
included) is removed, not moved into D.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import scipy.linalg

from symid.data import BlackBox, checks
from symid.errors import DataError

__all__ = ["d2c"]

#: Eigenvalues of Ad closer than this (relative to ‖Ad‖) to the closed negative real axis
#: have no usable real logarithm.
_AXIS_TOL = 1e-10
#: Largest accepted relative error of expm(logm(·)) on the augmented matrix.
_ROUND_TRIP_TOL = 1e-8


def _matrix(x: Any, name: str, *, row: bool = False) -> np.ndarray:
    """A finite real matrix; a 1-D array is a column (or a row with ``row=True``)."""
    arr = checks.as_array(x, name, complex_ok=False)
    if arr.ndim == 1:
        arr = arr.reshape(1, -1) if row else arr.reshape(-1, 1)
    if arr.ndim != 2:
        raise DataError(f"{name} must be a matrix; got shape {checks.shape_text(arr.shape)}")
    checks.check_finite(arr, name)
    return arr.astype(float)


def _balanced_logm(big: np.ndarray) -> np.ndarray:
    """Real principal logarithm of ``big`` computed on its balanced form, checked by a round trip."""
    bal, (scaling, _) = scipy.linalg.matrix_balance(big, permute=False, separate=True)
    with warnings.catch_warnings():
        # logm warns from an error estimate of ~1e-13; we check the round trip ourselves below
        warnings.filterwarnings("ignore", message="logm result may be inaccurate", category=RuntimeWarning)
        L = scipy.linalg.logm(bal)
    if np.iscomplexobj(L):
        # logm returns complex only when the principal logarithm is not real; rounding gives tiny parts
        if np.abs(L.imag).max() > 1e-8 * max(1.0, float(np.abs(L.real).max())):
            raise DataError("no real continuous-time model: the principal logarithm of the discrete A is complex")
        L = L.real
    back = np.linalg.norm(scipy.linalg.expm(L) - bal, 1) / np.linalg.norm(bal, 1)
    if not back <= _ROUND_TRIP_TOL:
        raise DataError(f"d2c is inaccurate for this model: expm(logm(·)) reproduces the (balanced) discrete model "
                        f"only to {back:.1e} (relative); Ad is too close to singular or defective")
    # bal = S⁻¹ big S with S = diag(scaling), powers of two: undoing it is exact
    return (L * scaling[:, None]) / scaling[None, :]


def _band(band: Any, dt: float) -> tuple[float, float]:
    try:
        lo, hi = (float(b) for b in band)
    except (TypeError, ValueError):
        raise DataError(f"band must be a pair (w_low, w_high) of angular frequencies in rad/s; got {band!r}") from None
    if not (0 <= lo < hi) or np.isnan(hi):
        raise DataError(f"band must be (w_low, w_high) in rad/s with 0 <= w_low < w_high; got {band!r}")
    return lo, hi


def _keep_modes(Ad: np.ndarray, Bd: np.ndarray, Cd: np.ndarray, dt: float, band: tuple[float, float]
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The subsystem of the modes with |ln z|/dt in ``band`` (ordered real Schur form + Sylvester decoupling)."""
    lo, hi = band

    def natural(z: complex) -> float:
        return float("inf") if z == 0 else abs(np.log(complex(z))) / dt

    def keep(x: float, y: float = 0.0) -> bool:
        return lo <= natural(complex(x, y)) <= hi

    ev = np.linalg.eigvals(Ad)
    kept = [keep(z.real, z.imag) for z in ev]
    if all(kept):
        return Ad, Bd, Cd
    if not any(kept):
        freqs = ", ".join(f"{natural(z):.4g}" for z in ev)
        raise DataError(f"no mode of the discrete model has its natural frequency in band {band!r} rad/s "
                        f"(modes at {freqs} rad/s)")
    T, Z, k = scipy.linalg.schur(Ad, output="real", sort=keep)
    T11, T12, T22 = T[:k, :k], T[:k, k:], T[k:, k:]
    X = scipy.linalg.solve_sylvester(T11, -T22, -T12)  # T11 X − X T22 = −T12 decouples the blocks
    ZB, CZ = Z.T @ Bd, Cd @ Z
    return T11, ZB[:k] - X @ ZB[k:], CZ[:, :k]


def d2c(A: Any, B: Any, C: Any, D: Any = None, dt: Any = None, *, band: Any = None) -> BlackBox:
    """Continuous-time model whose zero-order-hold sampling at ``dt`` is the given discrete model.

    Parameters
    ----------
    A : array_like, shape (n, n)
        Discrete-time state matrix Ad.
    B : array_like, shape (n, m)
        Discrete-time input matrix Bd.
    C : array_like, shape (p, n)
        Output matrix (unchanged by the hold).
    D : array_like, shape (p, m), optional
        Feedthrough (unchanged); zero when omitted.
    dt : float
        Sample time in seconds.
    band : (float, float), optional
        Keep only the modes whose natural frequency |ln z| / dt (rad/s) lies in
        [w_low, w_high] (module notes); with ``w_high`` < π/dt this drops a mode at the
        Nyquist frequency, which has no real continuous-time equivalent. Default: every
        mode.

    Returns
    -------
    BlackBox
        The continuous-time (A, B, C, D) with ``expm([[A, B], [0, 0]] dt) = [[Ad, Bd], [0, I]]``
        (for the kept modes, with ``band``).

    Raises
    ------
    DataError
        When ``dt`` is missing or not a positive number, on inconsistent shapes or
        non-finite entries, a malformed band or one that keeps no mode, or when no real
        logarithm exists: an eigenvalue of Ad on the closed negative real axis (zero
        included); the message then gives the ``band`` that drops it.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> bb = si.d2c([[np.exp(-0.5)]], [[1 - np.exp(-0.5)]], [[1.0]], dt=0.5)   # sampled 1/(s + 1)
    >>> np.round([bb.A[0, 0], bb.B[0, 0]], 12)
    array([-1.,  1.])
    """
    if dt is None:
        raise DataError("d2c needs the sample time dt (seconds) of the discrete-time model; got none")
    dt_ = checks.check_positive_scalar(dt, "dt")
    Ad = _matrix(A, "A")
    n = Ad.shape[0]
    if Ad.shape != (n, n):
        raise DataError(f"A must be square; got shape {checks.shape_text(Ad.shape)}")
    Bd = _matrix(B, "B")
    if Bd.shape[0] != n:
        raise DataError(f"B must have {n} rows to match A; got shape {checks.shape_text(Bd.shape)}")
    Cd = _matrix(C, "C", row=True)
    if Cd.shape[1] != n:
        raise DataError(f"C must have {n} columns to match A; got shape {checks.shape_text(Cd.shape)}")
    if band is not None:
        Ad, Bd, Cd = _keep_modes(Ad, Bd, Cd, dt_, _band(band, dt_))
        n = Ad.shape[0]
    ev = np.linalg.eigvals(Ad)
    scale = max(1.0, float(np.abs(ev).max(initial=0.0)))
    bad = ev[(ev.real <= _AXIS_TOL * scale) & (np.abs(ev.imag) <= _AXIS_TOL * scale)]
    if bad.size:
        fix = (f"drop that mode with band=(0, w_high), w_high below the Nyquist frequency π/dt = "
               f"{np.pi / dt_:.6g} rad/s (keeps the modes in the band of interest)" if band is None else
               "narrow the band")
        raise DataError(f"no real continuous-time model: the discrete A has eigenvalue {bad[0].real:.6g} on the "
                        "closed negative real axis, whose logarithm is not real (a mode at the Nyquist frequency, "
                        f"or a model that is not a sampled continuous-time system); {fix}, sample faster or check "
                        "the model")
    m = Bd.shape[1]
    big = np.zeros((n + m, n + m))
    big[:n, :n] = Ad
    big[:n, n:] = Bd
    big[n:, n:] = np.eye(m)
    L = _balanced_logm(big)
    L = L / dt_
    if D is None:
        D_ = np.zeros((Cd.shape[0], m))
    else:
        D_ = _matrix(D, "D")
        if D_.shape != (Cd.shape[0], m):
            raise DataError(f"D must have shape (p, m) = ({Cd.shape[0]}, {m}); got shape "
                            f"{checks.shape_text(D_.shape)}")
    return BlackBox(L[:n, :n], L[:n, n:], Cd, D_)
