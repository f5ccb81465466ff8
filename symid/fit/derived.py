"""Quantities computed from the estimate (a volume from 1/V, a clearance k10·V, a natural frequency √(k/m)), with
standard errors and 95 % intervals by the delta method.

A user parameterises the model so that it is affine (``q = 1/V`` where the concentration is
the amount over V) but reports what the field reports (V, CL = k10·V, a time constant):
a new user's pharmacokinetic fit gave q with an interval and V with none. For a function
f of the parameters, f(θ̂) is the estimate and ∇f Σ ∇fᵀ its variance to first order (Σ the
covariance of θ̂, ∇f by central differences with steps of 1e-6 of each parameter), the
interval f(θ̂) ± q·SE with the quantile q of the parameters' own intervals (Student's t
with their degrees of freedom, or the normal one for a given noise level). First order:
for a strongly nonlinear f over the interval (1/q where q's interval nearly reaches 0) the
interval is symmetric where the truth is not; a note says so when f's real change across
one standard error (along the direction that moves it most) differs from first order's by
more than ``NONLINEAR`` of it. The functions are Python callables the
user writes (code, not text: nothing here parses a string).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from symid.errors import OptionError

__all__ = ["NONLINEAR", "STEP", "DerivedQuantities", "derived_quantities"]

STEP = 1e-6
"""The relative step of the central differences (of each parameter's value; absolute where it is 0)."""
NONLINEAR = 0.1
"""A quantity whose real change across one standard error differs from the first-order one (the standard error) by
more than this share of it is said to be too nonlinear for a symmetric interval."""


@dataclass(frozen=True)
class DerivedQuantities:
    """Quantities computed from an estimate, with their first-order uncertainty (:func:`derived_quantities`).

    Attributes
    ----------
    names : tuple of str
    values : numpy.ndarray
        f(θ̂) for each quantity.
    standard_errors : numpy.ndarray
        √(∇f Σ ∇fᵀ); ``inf`` where f depends on a parameter the data do not determine, NaN where the
        estimate's intervals are withheld (an estimate that does not fit).
    intervals : numpy.ndarray
        (k, 2) 95 % intervals, f(θ̂) ± q·SE.
    notes : tuple of str
    """

    names: tuple[str, ...]
    values: np.ndarray
    standard_errors: np.ndarray
    intervals: np.ndarray
    notes: tuple[str, ...] = field(default=())

    def __getitem__(self, name: str) -> float:
        """The value of the quantity called ``name``."""
        if name not in self.names:
            raise OptionError(f"{name!r} is not a derived quantity here; they are {', '.join(self.names)}")
        return float(self.values[self.names.index(name)])

    def summary(self) -> str:
        """A table: quantity, estimate, standard error and 95 % interval, then the notes."""
        lines = [f"{'quantity':>12s} {'estimate':>14s} {'std. error':>11s} {'95 % interval':>27s}"]
        for name, v, s, (lo, hi) in zip(self.names, self.values, self.standard_errors, self.intervals, strict=True):
            lines.append(f"{name:>12s} {v:>14.6g} {s:>11.3g} {f'[{lo:.6g}, {hi:.6g}]':>27s}")
        lines.extend(f"note: {n}" for n in self.notes)
        return "\n".join(lines)


def derived_quantities(result: Any, quantities: Mapping[str, Callable[[dict[str, float]], float]]
                       ) -> DerivedQuantities:
    """The quantities ``{name: f}`` at the estimate of ``result``, with standard errors and 95 % intervals.

    Parameters
    ----------
    result : IdentificationResult
        An estimate with its uncertainty (``si.identify``'s result).
    quantities : dict of str to callable
        Each callable takes the parameters as a dict by name and returns a number.

    Returns
    -------
    DerivedQuantities

    Raises
    ------
    OptionError
        When ``quantities`` is not a dict of callables, a callable fails or returns something that is not a
        finite number at the estimate.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, [2.0, 0.5, 200.0], np.linspace(5.0, 15.0, 60), noise=0.01, seed=0)
    >>> res = si.identify(model, frf, x0=[2.0, 0.5, 200.0], identifiability_check=False)
    >>> d = res.derived({"wn": lambda th: np.sqrt(th["k"] / th["m"])})
    >>> lo, hi = d.intervals[0]
    >>> bool(lo < 10.0 < hi), round(d["wn"], 2)
    (True, 10.0)
    """
    from scipy.stats import t as student_t

    if not isinstance(quantities, Mapping) or not quantities or not all(
            isinstance(k, str) and callable(f) for k, f in quantities.items()):
        raise OptionError("quantities is a dict of name → function of the parameters (a dict by name), e.g. "
                          "{'V': lambda th: 1 / th['q']}")
    names = tuple(result.parameter_names)
    theta = np.asarray(result.theta_vector, dtype=float)
    unc = result.uncertainty

    def value(name: str, f: Callable[[dict[str, float]], float], at: np.ndarray) -> float:
        try:
            out = f(dict(zip(names, at.tolist(), strict=True)))
            v = float(out)
        except Exception as exc:  # the user's function: its failure named, with the quantity
            raise OptionError(f"quantity {name!r}: the function failed at the estimate: {type(exc).__name__}: "
                              f"{exc}") from None
        if not np.isfinite(v):
            raise OptionError(f"quantity {name!r} is {v} at the estimate")
        return v

    quantile = None
    if unc is not None:
        quantile = 1.959963984540054 if unc.dof is None else float(student_t.ppf(0.975, unc.dof))
    values, ses, notes = [], [], []
    for qname, f in quantities.items():
        v = value(qname, f, theta)
        values.append(v)
        if unc is None or not result.success:
            ses.append(np.nan)
            continue
        grad = np.zeros(theta.size)
        for i in range(theta.size):
            h = STEP * (abs(theta[i]) if theta[i] != 0 else 1.0)
            up, down = theta.copy(), theta.copy()
            up[i] += h
            down[i] -= h
            grad[i] = (value(qname, f, up) - value(qname, f, down)) / (2 * h)
        felt = grad != 0
        cov = np.asarray(unc.covariance, dtype=float)[np.ix_(felt, felt)]
        var = float(grad[felt] @ cov @ grad[felt]) if felt.any() else 0.0
        se = float(np.sqrt(var)) if np.isfinite(var) and var >= 0 else float("inf")
        ses.append(se)
        if np.isfinite(se) and se > 0:
            # how far first order is from the function one standard error along the gradient's direction
            step = cov @ grad[felt] / se
            along = theta.copy()
            along[felt] += step
            try:
                real = value(qname, f, along) - v
            except OptionError:
                real = np.inf
            if not abs(real - se) <= NONLINEAR * se:
                notes.append(f"{qname}: f changes by {real:.3g} across one standard error where first order says "
                             f"{se:.3g}: the interval is symmetric where the truth is not (a profile or a "
                             f"parameterisation in the quantity itself says more)")
    if unc is None:
        notes.append("no uncertainty at this estimate: values only")
    elif not result.success:
        notes.append("the estimate does not fit the data: values only (as its own intervals are withheld)")
    if any(np.isinf(s) for s in ses):
        notes.append("an infinite standard error: the quantity depends on a parameter the data do not determine")
    values_a, ses_a = np.asarray(values), np.asarray(ses)
    q = quantile if quantile is not None else np.nan
    intervals = np.column_stack([values_a - q * ses_a, values_a + q * ses_a])
    return DerivedQuantities(tuple(quantities), values_a, ses_a, intervals, tuple(notes))
