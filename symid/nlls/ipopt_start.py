"""One IPOPT solve from one start, as every CasADi estimator runs it; never raises on solver failure."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from symid.interrupt import native_interrupts

__all__ = ["IPOPT_SUCCESS", "solve_from"]

IPOPT_SUCCESS = frozenset({"Solve_Succeeded", "Solved_To_Acceptable_Level"})
"""IPOPT return statuses counted as converged."""


def solve_from(solver: Any, z0: np.ndarray, lbx: np.ndarray, ubx: np.ndarray
               ) -> tuple[np.ndarray, str, int, bool, float]:
    """Run a CasADi ``nlpsol`` from ``z0`` within the bounds.

    Returns
    -------
    (z, status, iterations, converged, seconds)
        The solution (``z0`` when CasADi raised, e.g. on NaN in a linear solve), IPOPT's
        return status (or ``"IPOPT failed: ..."``), its iteration count, whether the
        status is in :data:`IPOPT_SUCCESS`, and the wall time.

    Examples
    --------
    >>> import casadi as ca
    >>> import numpy as np
    >>> from symid.nlls.ipopt_start import solve_from
    >>> x = ca.MX.sym("x")
    >>> nlp = ca.nlpsol("s", "ipopt", {"x": x, "f": (x - 2) ** 2}, {"print_time": 0, "ipopt.print_level": 0})
    >>> z, status, _, ok, _ = solve_from(nlp, np.zeros(1), np.full(1, -np.inf), np.full(1, np.inf))
    >>> round(float(z[0]), 6), status, ok
    (2.0, 'Solve_Succeeded', True)
    """
    t0 = time.perf_counter()
    try:
        # CasADi turns Ctrl-C into a failed start and goes on; this raises it after the solve
        with native_interrupts(raise_now=True):
            sol = solver(x0=z0, lbx=lbx, ubx=ubx)
        stats = solver.stats()
        z = np.asarray(sol["x"]).reshape(-1)
        status = str(stats.get("return_status", "unknown"))
        iters = int(stats.get("iter_count", 0))
    except RuntimeError as exc:  # CasADi evaluation errors (NaN in the linear solve)
        return np.array(z0, dtype=float), f"IPOPT failed: {exc}", 0, False, time.perf_counter() - t0
    return z, status, iters, status in IPOPT_SUCCESS, time.perf_counter() - t0
