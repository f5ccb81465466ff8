"""Checking estimator options: one error type, messages that name the option.

Every estimator validates its options when it is built (:class:`symid.fit.base.Estimator`),
so a bad value is refused before any work, with an :class:`~symid.errors.OptionError`
that names the option, what it got and what it accepts; an unknown or misspelt name
lists the valid ones.
"""

from __future__ import annotations

import difflib
import numbers
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from symid.errors import OptionError

__all__ = [
    "MAX_SEED",
    "MAX_STARTS",
    "check_bool",
    "check_choice",
    "check_float",
    "check_int",
    "check_known_names",
    "check_scale",
    "check_seed",
    "check_time_limit",
]

MAX_SEED = 2**63 - 1
"""Largest accepted seed (numpy seeds are unbounded, but a seed is also written to JSON and logs)."""

MAX_STARTS = 100_000
"""Largest number of starts of one run (a typo guard: 10⁵ starts are days of work)."""


def _is_int(value: Any) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_))


def check_int(name: str, value: Any, *, low: int, high: int | None = None) -> int:
    """``value`` as an int in [low, high]; booleans and floats are refused.

    Examples
    --------
    >>> from symid.fit.options import check_int
    >>> check_int("max_iter", 50, low=1)
    50
    >>> check_int("max_iter", -3, low=1)
    Traceback (most recent call last):
    ...
    symid.errors.OptionError: max_iter must be an integer ≥ 1; got -3
    """
    span = f"≥ {low}" if high is None else f"between {low} and {high}"
    if not _is_int(value):
        raise OptionError(f"{name} must be an integer {span}; got {value!r} ({type(value).__name__})")
    if value < low or (high is not None and value > high):
        raise OptionError(f"{name} must be an integer {span}; got {value!r}")
    return int(value)


def check_float(name: str, value: Any, *, low: float | None = None, high: float | None = None,
                strict_low: bool = False) -> float:
    """``value`` as a finite float within the bounds (``strict_low``: > low instead of ≥).

    Examples
    --------
    >>> from symid.fit.options import check_float
    >>> check_float("tol", 1e-6, low=0, strict_low=True)
    1e-06
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise OptionError(f"{name} must be a number; got {value!r} ({type(value).__name__})")
    x = float(value)
    bad = not np.isfinite(x)
    if low is not None:
        bad = bad or (x <= low if strict_low else x < low)
    if high is not None:
        bad = bad or x > high
    if bad:
        parts = []
        if low is not None:
            parts.append(f"{'>' if strict_low else '≥'} {low:g}")
        if high is not None:
            parts.append(f"≤ {high:g}")
        want = "a finite number" + (f" {' and '.join(parts)}" if parts else "")
        raise OptionError(f"{name} must be {want}; got {value!r}")
    return x


def check_bool(name: str, value: Any) -> bool:
    """``value`` if it is ``True`` or ``False`` (numpy booleans included); not 0/1 or strings."""
    if not isinstance(value, (bool, np.bool_)):
        raise OptionError(f"{name} must be True or False; got {value!r} ({type(value).__name__})")
    return bool(value)


def check_choice(name: str, value: Any, choices: Sequence[Any]) -> Any:
    """``value`` if it is one of ``choices``; else an error listing them (and the closest match)."""
    try:
        ok = value in choices
    except TypeError:  # an unhashable or incomparable value
        ok = False
    if isinstance(value, (bool, np.bool_)) and not any(isinstance(c, bool) for c in choices):
        ok = False
    if not ok:
        listed = ", ".join(map(repr, choices))
        hint = ""
        if isinstance(value, str):
            close = difflib.get_close_matches(value, [c for c in choices if isinstance(c, str)], n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise OptionError(f"{name} must be one of {listed}; got {value!r}{hint}")
    return value


def check_seed(name: str, value: Any) -> int:
    """A random seed: an integer in [0, 2⁶³ − 1].

    Examples
    --------
    >>> from symid.fit.options import check_seed
    >>> check_seed("seed", 1.5)
    Traceback (most recent call last):
    ...
    symid.errors.OptionError: seed must be an integer between 0 and 9223372036854775807; got 1.5 (float)
    """
    return check_int(name, value, low=0, high=MAX_SEED)


def check_scale(name: str, value: Any, size: int) -> np.ndarray:
    """Positive finite typical magnitudes: one number, or one per parameter (``size``)."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise OptionError(f"{name} must be a positive number or {size} positive numbers (one per parameter); "
                          f"got {value!r}") from None
    if arr.ndim == 0:
        arr = np.full(size, float(arr))
    if arr.shape != (size,):
        raise OptionError(f"{name} must be a positive number or {size} positive numbers (one per parameter); "
                          f"got an array of shape {arr.shape}")
    bad = ~np.isfinite(arr) | (arr <= 0)
    if bad.any():
        k = int(np.argmax(bad))
        raise OptionError(f"{name}[{k}] = {float(arr[k])!r}; every entry must be a positive finite number")
    return arr.copy()


def check_time_limit(name: str, value: Any) -> float | None:
    """A wall-time budget in seconds: ``None`` (no limit) or a finite number > 0.

    Examples
    --------
    >>> from symid.fit.options import check_time_limit
    >>> check_time_limit("time_limit", 30), check_time_limit("time_limit", None)
    (30.0, None)
    """
    return None if value is None else check_float(name, value, low=0, strict_low=True)


def check_known_names(owner: str, given: Mapping[str, Any], valid: Iterable[str]) -> None:
    """Refuse option names that ``owner`` does not take, listing the valid ones.

    Examples
    --------
    >>> from symid.fit.options import check_known_names
    >>> check_known_names("scr", {"max_iters": 5}, ["max_iter", "tol"])
    Traceback (most recent call last):
    ...
    symid.errors.OptionError: scr has no option 'max_iters' (did you mean 'max_iter'?); its options are: max_iter, tol
    """
    valid = sorted(valid)
    unknown = [k for k in given if k not in valid]
    if not unknown:
        return
    parts = []
    for k in unknown:
        close = difflib.get_close_matches(str(k), valid, n=1)
        parts.append(f"{k!r}" + (f" (did you mean {close[0]!r}?)" if close else ""))
    noun = "option" if len(unknown) == 1 else "options"
    raise OptionError(f"{owner} has no {noun} {', '.join(parts)}; its options are: "
                      f"{', '.join(valid) if valid else '(none)'}")
