"""Bounds on θ for the trust-region methods that work on log-parameters (``lm``, ``auto``, ``oe``).

These methods solve for φ, with θₖ = cₖ·exp(φₖ) for a parameter kept positive (cₖ its
start) and θₖ = cₖ + sₖ·φₖ for the others (sₖ its scale). A user's bounds lo ≤ θ ≤ hi
become bounds on φ, which SciPy's trust-region reflective least squares honours
(``scipy.optimize.least_squares(..., bounds=...)``): log(lo/c) ≤ φ ≤ log(hi/c), or
(lo − c)/s ≤ φ ≤ (hi − c)/s. Parameters declared positive already stay positive through
the exponential, so a lower bound of 0 adds nothing; where no parameter has a bound of
its own the solver runs unbounded, as without ``bounds``.

Drawn starts and restarts are moved into the bounds (a start exactly on a bound is
moved strictly inside by the solver); a user's own start outside them is refused
(:func:`symid.fit.options.check_start_bounds`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from symid.errors import OptionError
from symid.fit.options import parameter_bounds

__all__ = ["bound_sides", "bounds_option", "clip_into", "log_box", "named_bounds", "on_bounds", "typical_within"]


def bounds_option(model: Any, bounds: Any, positivity: bool) -> tuple[np.ndarray, np.ndarray, bool]:
    """(lower, upper, given): the bounds of :func:`~symid.fit.options.parameter_bounds`, and whether any
    parameter has one beyond positivity. Refuses equal bounds (a known value, not a bound).

    Examples
    --------
    >>> import symid as si
    >>> from symid.fit.bounded import bounds_option
    >>> m, k = si.parameters("m k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[0.1]], K=[[k]], B=[[1]], C=[[1]])
    >>> lo, hi, given = bounds_option(model, {"k": (10, 100)}, True)
    >>> lo.tolist(), hi.tolist(), given
    ([0.0, 10.0], [inf, 100.0], True)
    >>> bounds_option(model, {"k": (10, 10)}, True)
    Traceback (most recent call last):
    ...
    symid.errors.OptionError: bounds: k has equal bounds [10, 10]: that is a known value; fit model.with_known(...
    """
    lower, upper = parameter_bounds(model, bounds, positivity)
    names = model.parameter_names
    same = np.flatnonzero(lower == upper)
    if same.size:
        k = int(same[0])
        raise OptionError(f"bounds: {names[k]} has equal bounds [{lower[k]:g}, {upper[k]:g}]: that is a known "
                          f"value; fit model.with_known({{{names[k]!r}: {lower[k]:g}}}) instead (a model file: "
                          f"known = {{...}}, or --known on the command line), or leave the bounds apart")
    plain_lower, _ = parameter_bounds(model, None, positivity)
    given = bool(np.any(lower != plain_lower) or np.any(np.isfinite(upper)))
    return lower, upper, given


def named_bounds(names: Sequence[str], lower: np.ndarray, upper: np.ndarray) -> dict[str, list[float]] | None:
    """The bounds by parameter name, for a result's options (None where no parameter has one)."""
    out = {n: [float(lo), float(hi)] for n, lo, hi in zip(names, lower, upper, strict=True)
           if np.isfinite(lo) or np.isfinite(hi)}
    return out or None


def clip_into(x: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """``x`` moved into [lower, upper] entry by entry (NaN bounds are never passed here)."""
    return np.clip(np.asarray(x, dtype=float), lower, upper)


def log_box(lower: np.ndarray, upper: np.ndarray, centre: np.ndarray, unit: np.ndarray, positive: np.ndarray,
            box: float) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on φ for θ = c·exp(φ) (``positive``) or θ = c + s·φ, intersected with |φ| ≤ ``box`` for the
    positive ones (the methods' own limit on how far an estimate moves from its start).

    ``centre`` must lie within [lower, upper] (the start, moved into the bounds first), so φ = 0 is feasible.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.bounded import log_box
    >>> lo, hi = log_box(np.array([0.0, 1.0]), np.array([np.inf, 3.0]), np.array([2.0, 2.0]),
    ...                  np.array([1.0, 0.5]), np.array([True, False]), 10.0)
    >>> lo.tolist(), hi.tolist()
    ([-10.0, -2.0], [10.0, 2.0])
    """
    positive = np.asarray(positive, dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        log_lo = np.where(lower > 0, np.log(np.where(lower > 0, lower, 1.0) / centre), -np.inf)
        log_hi = np.where(np.isfinite(upper), np.log(np.where(upper > 0, upper, 1.0) / centre), np.inf)
        lin_lo = (lower - centre) / unit
        lin_hi = (upper - centre) / unit
    lo = np.where(positive, np.maximum(log_lo, -box), lin_lo)
    hi = np.where(positive, np.minimum(log_hi, box), lin_hi)
    return lo, hi


def typical_within(typical: np.ndarray, lower: np.ndarray, upper: np.ndarray, positive: np.ndarray,
                   user_scale: bool) -> np.ndarray:
    """Typical values for drawing starts, given bounds: the geometric mean of a positive parameter's two
    positive finite bounds (what the user knows of where it lies) unless ``user_scale``; every typical value
    moved into its bounds.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.bounded import typical_within
    >>> typical_within(np.array([5.0, 5.0]), np.array([10.0, 0.0]), np.array([1000.0, 2.0]),
    ...                np.array([True, True]), False).tolist()
    [100.0, 2.0]
    """
    positive = np.asarray(positive, dtype=bool)
    out = np.asarray(typical, dtype=float).copy()
    if not user_scale:
        both = positive & (lower > 0) & np.isfinite(upper)
        with np.errstate(invalid="ignore"):
            out = np.where(both, np.sqrt(np.where(both, lower * upper, 1.0)), out)
    inside = np.clip(out, np.fmax(lower, 0.0), upper)
    return np.where(positive & np.isfinite(out) & (inside > 0), inside, out)


def on_bounds(theta: np.ndarray, lower: np.ndarray, upper: np.ndarray, names: Sequence[str],
              positive: np.ndarray) -> str:
    """``"; on its bounds: k = 60 (lower)"`` for the entries of an estimate that sit on a bound the user gave
    ('' if none; the 0 that keeps a positive parameter positive is not the user's bound). An estimate on a
    bound that does not fit the data says the data want a value outside it.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.bounded import on_bounds
    >>> on_bounds(np.array([60.0, 2.0]), np.array([60.0, 0.0]), np.array([100.0, np.inf]), ["k", "m"],
    ...           np.array([True, True]))
    '; on its bounds: k = 60 (lower)'
    """
    theta = np.asarray(theta, dtype=float)
    if theta.shape != np.shape(lower):
        return ""
    sides = bound_sides(theta, lower, upper, positive)
    parts = [f"{name} = {theta[k]:.6g} ({'lower' if sides[k] < 0 else 'upper'})"
             for k, name in enumerate(names) if sides[k]]
    return "; on its bounds: " + ", ".join(parts) if parts else ""


def bound_sides(theta: np.ndarray, lower: np.ndarray, upper: np.ndarray, positive: np.ndarray) -> np.ndarray:
    """Per entry of ``theta``: −1 on its lower bound, +1 on its upper, 0 inside (to 1e-9 relative, and to a
    quarter of the box for a box narrower than that: the nearer bound). The 0 that keeps a positive
    parameter positive is not a bound the user gave.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.bounded import bound_sides
    >>> bound_sides(np.array([60.0, 2.0, 1.0]), np.array([60.0, 0.0, 1.0]), np.array([100.0, 3.0, 1.0 + 1e-12]),
    ...             np.array([True, True, True])).tolist()
    [-1, 0, -1]
    """
    theta = np.asarray(theta, dtype=float)
    width = np.where(np.isfinite(upper - lower), upper - lower, np.inf)
    tol = np.fmin(1e-9 * np.fmax(1.0, np.abs(theta)), 0.25 * width)
    dlo, dhi = np.abs(theta - lower), np.abs(upper - theta)
    low = np.isfinite(lower) & (dlo <= tol) & ~(positive & (lower == 0))
    high = np.isfinite(upper) & (dhi <= tol)
    both = low & high
    low, high = low & (~both | (dlo <= dhi)), high & (~both | (dhi < dlo))
    return np.where(low, -1, np.where(high, 1, 0))
