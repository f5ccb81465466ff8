"""Local polish: a Gauss–Newton-type refinement (IPOPT) started from another method's estimate.

SCR reaches the basin of the solution in tens of iterations but its tail is slow (and
inexact with the ADMM back end); IPOPT started there converges in a few Newton steps.
The polished outcome is reported on its own (method ``"scr+polish"``), never mixed into
the SCR figures.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from symid.fit.result import StartOutcome

__all__ = ["polish_outcome"]


def polish_outcome(polisher: Any, outcome: StartOutcome) -> StartOutcome:
    """Refine one start's outcome with ``polisher.run(outcome.theta)``.

    The returned outcome keeps the original start, adds the polish's iterations and
    time to those of ``outcome``, and keeps the better of the two estimates by data
    misfit: a refinement that makes the fit worse (it left the basin) is rejected, and
    the message says so.

    Parameters
    ----------
    polisher : Estimator
        Usually the data kind's IPOPT estimator (:meth:`symid.fit.base.Estimator.polisher`).
    outcome : StartOutcome
        What the first method produced from one start.

    Returns
    -------
    StartOutcome

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.frf.ipopt import IpoptFRF
    >>> from symid.fit.polish import polish_outcome
    >>> from symid.fit.result import StartOutcome
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, [2.0, 0.5, 3.0], np.linspace(0.5, 2.0, 5))
    >>> rough = StartOutcome(start=np.ones(3), theta=np.array([2.1, 0.4, 3.2]), cost=1e-2, success=False,
    ...                      finished=False, status="max_iter", iterations=3, wall_time=0.0)
    >>> out = polish_outcome(IpoptFRF(model, frf), rough)
    >>> np.round(out.theta, 6).tolist(), out.success, out.iterations > 3
    ([2.0, 0.5, 3.0], True, True)
    """
    if not np.all(np.isfinite(outcome.theta)):
        return dataclasses.replace(outcome, success=False,
                                   message=f"{outcome.message}; not polished (non-finite estimate)")
    name = polisher.method
    pol = polisher.run(np.asarray(outcome.theta, dtype=float))
    better = np.isfinite(pol.cost) and (not np.isfinite(outcome.cost) or pol.cost <= outcome.cost)
    best = pol if better else outcome
    verdict = (f"polished by {name}: {pol.message}" if better else
               f"polish by {name} rejected (misfit {pol.cost:.3e} > {outcome.cost:.3e}): {pol.message}")
    return dataclasses.replace(best, start=outcome.start, iterations=outcome.iterations + pol.iterations,
                               wall_time=outcome.wall_time + pol.wall_time,
                               message=f"{outcome.message}; {verdict}", history=outcome.history)
