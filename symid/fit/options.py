"""Checking estimator options: one error type, messages that name the option.

Every estimator validates its options when it is built (:class:`symid.fit.base.Estimator`),
so a bad value is refused before any work, with an :class:`~symid.errors.OptionError`
that names the option, what it got and what it accepts; an unknown or misspelt name
lists the valid ones.
"""

from __future__ import annotations

import difflib
import math
import numbers
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from symid.errors import OptionError

__all__ = [
    "MAX_SEED",
    "MAX_STARTS",
    "check_bool",
    "check_bounds",
    "check_callback",
    "check_choice",
    "check_float",
    "check_int",
    "check_known_names",
    "check_scale",
    "check_seed",
    "check_start_bounds",
    "check_time_limit",
    "moved_onto_bounds",
    "parameter_bounds",
    "scale_by_name",
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


def without_known(value: Any, known: Mapping[str, float]) -> Any:
    """A dict by parameter name less the names ``known`` holds (a model's :attr:`known_values`): a model file's start,
    scale or bounds, written for every parameter, serve the same model with some values known. Anything that is
    not a dict is returned as it is.

    Examples
    --------
    >>> from symid.fit.options import without_known
    >>> without_known({"m": 300.0, "k": 2e4}, {"m": 320.0})
    {'k': 20000.0}
    """
    if not isinstance(value, Mapping) or not known:
        return value
    return {k: v for k, v in value.items() if str(k) not in known}


def scale_by_name(options: Mapping[str, Any], parameter_names: Sequence[str]) -> dict[str, Any]:
    """``options`` with a ``scale`` given as a dict by parameter name (as ``x0`` and ``bounds`` may be) turned
    into one value per parameter, in θ order; every parameter must be named, and only those.

    Examples
    --------
    >>> from symid.fit.options import scale_by_name
    >>> scale_by_name({"scale": {"k": 1e4, "m": 2.0}}, ["m", "k"])
    {'scale': [2.0, 10000.0]}
    >>> scale_by_name({"scale": {"m": 2.0}}, ["m", "k"])
    Traceback (most recent call last):
    ...
    symid.errors.OptionError: scale by name needs every parameter; missing: k (parameters whose values are known ...)
    """
    value = options.get("scale")
    if not isinstance(value, Mapping):
        return dict(options)
    names = list(parameter_names)
    unknown = [k for k in value if k not in names]
    if unknown:
        parts = []
        for k in unknown:
            close = difflib.get_close_matches(str(k), names, n=1)
            parts.append(f"{k!r}" + (f" (did you mean {close[0]!r}?)" if close else ""))
        raise OptionError(f"scale names {', '.join(parts)}, not a parameter of the model ({', '.join(names)})")
    missing = [n for n in names if n not in value]
    if missing:
        raise OptionError(f"scale by name needs every parameter; missing: {', '.join(missing)} (parameters whose "
                          f"values are known leave the model first: a model file's through ModelFile.free_model())")
    out = [value[n] for n in names]
    try:
        out = [float(v) for v in out]
    except (TypeError, ValueError):
        raise OptionError(f"scale must hold numbers; got {value!r}") from None
    for n, v in zip(names, out, strict=True):  # named here: check_scale later knows positions only
        if not (math.isfinite(v) and v > 0):
            raise OptionError(f"scale {n} = {v!r}; every entry must be a positive finite number")
    return {**options, "scale": out}


def check_bounds(name: str, value: Any, parameter_names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds per parameter: a dict by name of (low, high), or an (l, 2) array.

    A side given as ``None`` or ±inf is open; parameters a dict leaves out are unbounded.
    An unknown name, a wrong shape, NaN, or low > high is an :class:`OptionError` naming it.

    Examples
    --------
    >>> from symid.fit.options import check_bounds
    >>> lo, hi = check_bounds("bounds", {"k": (10, None)}, ["m", "k"])
    >>> lo.tolist(), hi.tolist()
    ([-inf, 10.0], [inf, inf])
    >>> check_bounds("bounds", {"k": (5, 1)}, ["m", "k"])
    Traceback (most recent call last):
    ...
    symid.errors.OptionError: bounds: k has lower bound 5 > upper bound 1
    """
    names = list(parameter_names)
    l = len(names)
    lower, upper = np.full(l, -np.inf), np.full(l, np.inf)

    def side(v: Any, what: str, key: str) -> float:
        if v is None:
            return -np.inf if what == "lower" else np.inf
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
            raise OptionError(f"{name}: the {what} bound of {key} must be a number or None; got {v!r}")
        x = float(v)
        if np.isnan(x):
            raise OptionError(f"{name}: the {what} bound of {key} is NaN")
        return x

    if isinstance(value, Mapping):
        for key, pair in value.items():
            if key not in names:
                close = difflib.get_close_matches(str(key), names, n=1)
                hint = f" (did you mean {close[0]!r}?)" if close else ""
                raise OptionError(f"{name}: {key!r} is not a parameter of the model{hint}; its parameters are: "
                                  f"{', '.join(names)}")
            if isinstance(pair, (str, bytes)) or not isinstance(pair, Sequence) or len(pair) != 2:
                raise OptionError(f"{name}: {key} needs a pair (low, high); got {pair!r}")
            k = names.index(key)
            lower[k], upper[k] = side(pair[0], "lower", key), side(pair[1], "upper", key)
    else:
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise OptionError(f"{name} must be a dict of (low, high) by parameter name or an array of shape "
                              f"({l}, 2); got {type(value).__name__}") from None
        if arr.shape != (l, 2):
            raise OptionError(f"{name} must be a dict of (low, high) by parameter name or an array of shape "
                              f"({l}, 2) (one row per parameter: {', '.join(names)}); got shape {arr.shape}")
        if np.isnan(arr).any():
            k = int(np.argwhere(np.isnan(arr))[0][0])
            raise OptionError(f"{name}: the bounds of {names[k]} contain NaN (use ±inf for an open side)")
        lower, upper = arr[:, 0].copy(), arr[:, 1].copy()
    bad = lower > upper
    if bad.any():
        k = int(np.argmax(bad))
        raise OptionError(f"{name}: {names[k]} has lower bound {lower[k]:g} > upper bound {upper[k]:g}")
    return lower, upper


def check_time_limit(name: str, value: Any) -> float | None:
    """A wall-time budget in seconds: ``None`` (no limit) or a finite number > 0.

    Examples
    --------
    >>> from symid.fit.options import check_time_limit
    >>> check_time_limit("time_limit", 30), check_time_limit("time_limit", None)
    (30.0, None)
    """
    return None if value is None else check_float(name, value, low=0, strict_low=True)


def check_callback(name: str, value: Any, record: str) -> Any:
    """A progress callback: ``None`` or a function of one ``record`` (the name of the type it receives).

    Examples
    --------
    >>> from symid.fit.options import check_callback
    >>> check_callback("callback", print, "ScrProgress") is print
    True
    >>> check_callback("callback", 3, "ScrProgress")
    Traceback (most recent call last):
    ...
    symid.errors.OptionError: callback must be a function of one ScrProgress (or None); got int
    """
    if value is not None and not callable(value):
        raise OptionError(f"{name} must be a function of one {record} (or None); got {type(value).__name__}")
    return value


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


def parameter_bounds(model: Any, bounds: Any, positivity: bool) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds on θ: ``bounds`` (:func:`check_bounds`) and, with
    ``positivity``, θₖ ≥ 0 for parameters declared positive; an :class:`OptionError` when they leave a
    parameter no admissible value.

    Examples
    --------
    >>> import symid as si
    >>> from symid.fit.options import parameter_bounds
    >>> m, k = si.parameters("m k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[0.1]], K=[[k]], B=[[1]], C=[[1]])
    >>> [b.tolist() for b in parameter_bounds(model, {"k": (10, 100)}, True)]
    [[0.0, 10.0], [inf, 100.0]]
    """
    names = list(model.parameter_names)
    if bounds is None:
        lower, upper = np.full(len(names), -np.inf), np.full(len(names), np.inf)
    else:
        lower, upper = check_bounds("bounds", bounds, names)
    if positivity:
        pos = np.asarray(model.positive, dtype=bool)
        lower = np.where(pos, np.fmax(lower, 0.0), lower)
        bad = pos & (upper < 0)
        if bad.any():
            k = int(np.argmax(bad))
            raise OptionError(f"bounds: {names[k]} is declared positive, but its upper bound {upper[k]:g} is below "
                              "0: no value is admissible (raise the bound, or pass positivity=False)")
    return lower, upper


def _outside(x0: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> list[int]:
    """Indices of the entries of x0 outside [lower, upper] beyond rounding."""
    slack = 1e-12 * np.fmax(1.0, np.abs(x0))
    with np.errstate(invalid="ignore"):
        bad = (x0 < lower - slack) | (x0 > upper + slack)
    return [int(k) for k in np.flatnonzero(bad)]


def check_start_bounds(x0: Any, lower: np.ndarray, upper: np.ndarray, names: Sequence[str]) -> None:
    """Refuse a start of the wrong length or outside [lower, upper] (an :class:`OptionError` naming the parameter).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.options import check_start_bounds
    >>> check_start_bounds([5.0, 1.0], np.array([10.0, 0.0]), np.array([100.0, np.inf]), ["k", "m"])
    Traceback (most recent call last):
    ...
    symid.errors.OptionError: the start k = 5 lies outside its bounds [10, 100]; move the start inside or ...
    >>> check_start_bounds([50.0, -1.0], np.array([10.0, 0.0]), np.array([100.0, np.inf]), ["k", "m"])
    Traceback (most recent call last):
    ...
    symid.errors.OptionError: the start m = -1 is negative, and m is kept ≥ 0 (declared positive, or a lower bound ...
    """
    x = np.asarray(x0, dtype=float).reshape(-1)
    if x.size != len(names):
        raise OptionError(f"the start has {x.size} values; the model has {len(names)} parameters ({', '.join(names)})")
    out = _outside(x, lower, upper)
    if out:
        k = out[0]
        if lower[k] == 0 and upper[k] == np.inf and x[k] < 0:  # the 0 of a parameter declared positive
            raise OptionError(f"the start {names[k]} = {x[k]:g} is negative, and {names[k]} is kept ≥ 0 (declared "
                              f"positive, or a lower bound 0): start it above 0, or declare it without "
                              f"positive=True if it may be negative")
        raise OptionError(f"the start {names[k]} = {x[k]:g} lies outside its bounds [{lower[k]:g}, {upper[k]:g}]; "
                          "move the start inside or widen the bounds")


def moved_onto_bounds(x0: np.ndarray, lower: np.ndarray, upper: np.ndarray, names: Sequence[str]) -> str:
    """``"; start moved onto the bounds: k 5 → 10"`` for the entries of a start outside them ('' if none).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.options import moved_onto_bounds
    >>> moved_onto_bounds(np.array([5.0, 1.0]), np.array([10.0, 0.0]), np.array([100.0, np.inf]), ["k", "m"])
    '; start moved onto the bounds: k 5 → 10'
    """
    x = np.asarray(x0, dtype=float).reshape(-1)
    if x.shape != np.shape(lower):
        return ""
    out = _outside(x, lower, upper)
    if not out:
        return ""
    return "; start moved onto the bounds: " + ", ".join(
        f"{names[k]} {x[k]:.4g} → {float(np.clip(x[k], lower[k], upper[k])):.4g}" for k in out)
