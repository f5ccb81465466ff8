"""Validation of arrays shared by the data containers and the signal layer (simulation, spectra, d2c).

Every helper raises :class:`symid.errors.DataError` with a message naming the array and
what was expected; none lets a numpy exception through. Arrays returned are fresh,
C-contiguous, read-only copies.

Conventions fixed here:

* Angular frequencies (rad/s) are strictly positive, finite and strictly increasing.
  ω = 0 is refused: a second-order model with a rigid-body mode is singular there,
  and the identification formulations divide by or scale with ω; give a small positive
  frequency instead.
* Hermitian spectra are checked to the tolerance ``HERMITIAN_RTOL`` relative to the
  Frobenius norm of each matrix: ``max |Φ − Φᴴ| <= HERMITIAN_RTOL * ||Φ||_F``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from symid.data import _files
from symid.errors import DataError

__all__ = [
    "HERMITIAN_RTOL",
    "as_array",
    "check_finite",
    "check_hermitian",
    "check_positive_scalar",
    "frequencies",
    "frozen",
    "grid_jump",
    "shape_text",
]

HERMITIAN_RTOL = 1e-8


def frozen(arr: np.ndarray) -> np.ndarray:
    """A read-only, C-contiguous copy of ``arr``."""
    out = np.array(arr, copy=True, order="C")
    out.flags.writeable = False
    return out


def shape_text(shape: tuple[int, ...]) -> str:
    """A shape as ``(3, 1, 1)``, for messages."""
    return "(" + ", ".join(str(int(d)) for d in shape) + ("," if len(shape) == 1 else "") + ")"


def as_array(x: Any, name: str, *, complex_ok: bool) -> np.ndarray:
    """Convert ``x`` to a float (or complex) array, refusing strings, ragged lists and bad dtypes.

    Parameters
    ----------
    x : array_like
        The user's input.
    name : str
        Name of the array in messages.
    complex_ok : bool
        Whether complex values are allowed. The result is ``complex128`` when True and
        ``float64`` when False.
    """
    if x is None:
        raise DataError(f"{name} is missing (got None)")
    try:
        arr = np.asarray(x)
    except (ValueError, TypeError):
        raise DataError(f"{name} must be a numeric array; got a ragged or non-numeric sequence") from None
    if arr.dtype.kind in "US" and arr.size:  # text: name the first entry that does not even read as a number
        bad = next(((idx, v) for idx, v in np.ndenumerate(arr) if not _reads_as_number(str(v))),
                   next(np.ndenumerate(arr)))
        raise DataError(f"{name} must hold numbers; got text, {_files._show(str(bad[1]))} at "
                        f"[{', '.join(map(str, bad[0]))}]")
    if arr.dtype.kind in "USV" or arr.dtype.kind == "M" or arr.dtype.kind == "m":
        raise DataError(f"{name} must hold numbers; got dtype {arr.dtype}")
    if arr.dtype.kind == "b":
        raise DataError(f"{name} must hold numbers; got booleans")
    target = np.complex128 if complex_ok else np.float64
    if arr.dtype.kind == "c" and not complex_ok:
        raise DataError(f"{name} must be real; got complex values")
    if arr.dtype.kind == "O":
        empty = [idx for idx, v in np.ndenumerate(arr) if v is None]
        if empty:  # None would become NaN + NaN·j, and be called complex
            raise DataError(f"{name} holds None at [{', '.join(map(str, empty[0]))}]: a missing value? give a number "
                            f"(or NaN where a time series' output was not measured)")
        try:
            arr = arr.astype(np.complex128)
        except (TypeError, ValueError):
            raise DataError(f"{name} must hold numbers; got {_first_non_number(arr)}") from None
        if not complex_ok:
            if np.any(arr.imag != 0):
                raise DataError(f"{name} must be real; got complex values")
            arr = arr.real
    try:
        return np.array(arr, dtype=target, copy=True, order="C")
    except (TypeError, ValueError, OverflowError):
        raise DataError(f"{name} must hold numbers; got dtype {arr.dtype}") from None


def check_finite(arr: np.ndarray, name: str) -> None:
    """Raise if ``arr`` holds NaN or ±inf, naming the first bad index."""
    bad = ~np.isfinite(arr)
    if np.any(bad):
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        where = ", ".join(map(str, idx))
        val = arr[idx]
        raise DataError(f"{name} must be finite: {name}[{where}] = {val} ({int(bad.sum())} non-finite value(s))")


def frequencies(w: Any, name: str = "w") -> np.ndarray:
    """Validate angular frequencies: real, 1-D, non-empty, finite, > 0, strictly increasing.

    A scalar is accepted as one frequency. Returns a read-only float64 copy.
    """
    arr = as_array(w, name, complex_ok=False)
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise DataError(f"{name} must be 1-D (one angular frequency per sample); got shape {shape_text(arr.shape)}")
    if arr.size == 0:
        raise DataError(f"{name} is empty; at least one frequency is needed")
    check_finite(arr, name)
    nonpos = np.flatnonzero(arr <= 0)
    if nonpos.size:
        i = int(nonpos[0])
        raise DataError(f"{name} must be positive angular frequencies in rad/s: {name}[{i}] = {float(arr[i])!r} "
                        f"(ω = 0 and negative frequencies are not allowed)")
    d = np.diff(arr)
    bad = np.flatnonzero(d <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        kind = "duplicate" if arr[i] == arr[i - 1] else "unsorted"
        raise DataError(f"{name} must be strictly increasing: {name}[{i}] = {float(arr[i])!r} is not greater than "
                        f"{name}[{i - 1}] = {float(arr[i - 1])!r} ({kind})")
    return frozen(arr)


def check_hermitian(Phi: np.ndarray, name: str, rtol: float = HERMITIAN_RTOL) -> None:
    """Raise unless every ``Phi[i]`` (shape (s, k, k)) is Hermitian to ``rtol`` relative to its norm."""
    # each matrix is divided by its largest real or imaginary part first, so that |Φ − Φᴴ| and ||Φ||_F
    # can neither overflow nor underflow; real and imaginary parts are divided separately (a complex
    # division by a subnormal number overflows inside numpy)
    big = np.maximum(np.abs(Phi.real), np.abs(Phi.imag)).max(axis=(-1, -2))
    div = np.where(big > 0, big, 1.0)[..., None, None]
    unit = np.empty(Phi.shape, dtype=np.complex128)
    unit.real, unit.imag = Phi.real / div, Phi.imag / div
    dev = np.abs(unit - np.conj(np.swapaxes(unit, -1, -2))).max(axis=(-1, -2)) * big
    scale = np.linalg.norm(unit, axis=(-1, -2)) * big
    bad = np.flatnonzero(dev > rtol * scale)
    if bad.size:
        i = int(bad[0])
        raise DataError(f"{name}[{i}] is not Hermitian: max |Φ − Φᴴ| = {dev[i]:.3g} exceeds "
                        f"{rtol:g} × ||Φ||_F = {rtol * scale[i]:.3g} ({bad.size} frequency(ies) affected)")


def grid_jump(t: Any, *, even_share: float = 0.9) -> tuple[int, float, int] | None:
    """``(k, typical, jumps)`` for sample times on an even grid with holes: the index k of the largest step
    t[k + 1] − t[k], the typical (median) step, and the number of steps beyond 1.5 typical ones, when at least
    ``even_share`` of the steps are the typical one (to 1e-3 of it); None for uneven times (a dosing schedule) or
    fewer than 3 samples. Callers judge the jump: a table refuses one of 1.5 steps (samples missing), a fit warns of
    one beyond 10.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.data.checks import grid_jump
    >>> grid_jump(np.concatenate([np.arange(10.0), 15.0 + np.arange(10.0)]))
    (9, 1.0, 1)
    >>> grid_jump(np.array([0.0, 0.5, 1, 2, 4, 8])) is None
    True
    """
    t = np.asarray(t, dtype=float)
    if t.size < 3:
        return None
    d = np.diff(t)
    typical = float(np.median(d))
    if not typical > 0 or np.mean(np.abs(d - typical) <= 1e-3 * typical) < even_share:
        return None
    return int(np.argmax(d)), typical, int(np.count_nonzero(d > 1.5 * typical))


def check_positive_scalar(x: Any, name: str) -> float:
    """A finite, strictly positive real scalar (a sample time, for instance)."""
    arr = as_array(x, name, complex_ok=False)
    if arr.size != 1:
        raise DataError(f"{name} must be a scalar; got shape {shape_text(arr.shape)}")
    val = float(arr.reshape(()))
    if not math.isfinite(val) or val <= 0:
        raise DataError(f"{name} must be a finite number > 0; got {val!r}")
    return val


def check_power_diagonal(arr: np.ndarray, name: str) -> None:
    """Refuse a spectrum (s, k, k) with a diagonal entry below −1e-8 times the largest: an auto-spectrum is a
    power, ≥ 0 to rounding however noisy the estimate."""
    diag = np.real(np.diagonal(arr, axis1=1, axis2=2))
    floor = -1e-8 * float(np.max(np.abs(diag))) if diag.size else 0.0
    bad = np.argwhere(diag < floor)
    if bad.size:
        i, j = (int(v) for v in bad[0])
        many = f" ({bad.shape[0]} negative diagonal entries)" if bad.shape[0] > 1 else ""
        raise DataError(f"{name}[{i}, {j}, {j}] = {diag[i, j]:.6g} at frequency line {i}: the diagonal of a power "
                        f"spectrum is a power, ≥ 0{many}")


def _first_non_number(arr: np.ndarray) -> str:
    """Where an object array first holds something that is not a number, and what: ``'abc' at [3]``."""
    for idx, v in np.ndenumerate(arr):
        try:
            complex(v)
        except (TypeError, ValueError):
            text = repr(v) if len(repr(v)) <= 40 else repr(v)[:37] + "..."
            return f"{text} at [{', '.join(map(str, idx))}]"
    return "objects that are not numbers"


def _reads_as_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True

