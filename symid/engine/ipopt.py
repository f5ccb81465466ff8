"""IPOPT through CasADi: model matrices as CasADi expressions, and one bounded NLP solved from many starts.

Every IPOPT estimator of :mod:`symid.fit` poses min f(z) subject to bounds on z, with
z = θ / scale (and, for the similarity formulation, vec T), and solves it from one
start per call of :meth:`IpoptSolver.solve`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from symid.interrupt import native_interrupts

__all__ = ["HESSIANS", "IPOPT_SUCCESS", "IpoptRun", "IpoptSolver", "casadi_frf", "casadi_matrices",
           "positivity_bounds"]

HESSIANS = ("exact", "limited-memory")
"""IPOPT's Hessian choices: exact (CasADi's automatic differentiation) or L-BFGS."""

IPOPT_SUCCESS = frozenset({"Solve_Succeeded", "Solved_To_Acceptable_Level"})
"""IPOPT return statuses counted as finished (its stopping rule was met)."""


def casadi_matrices(model: Any, theta: ca.MX) -> dict[str, ca.MX]:
    """Every affine matrix X(θ) = X0 + Σ θi Xi of a model as a CasADi expression."""
    out = {}
    for name, amap in model.maps.items():
        X = ca.MX(ca.DM(amap.X0))
        for k in amap.depends_on:
            X = X + theta[k] * ca.DM(amap.Xi[k])
        out[name] = X
    return out


def casadi_frf(model: Any, theta: ca.MX, w: np.ndarray) -> tuple[list[ca.MX], list[ca.MX]]:
    """Real and imaginary parts of H(ωᵢ, θ), one (p, m) expression per frequency.

    A state-space model solves (jωI − A) X = B in the real form
    [[−A, −ωI], [ωI, −A]] [Xr; Xi] = [B; 0]; a second-order model solves
    (K − ω²M + jωV) X = B as [[K − ω²M, −ωV], [ωV, K − ω²M]] [Xr; Xi] = [B; 0], then
    multiplies by jω or −ω² for velocity or acceleration outputs.
    """
    mats = casadi_matrices(model, theta)
    Hr, Hi = [], []
    if "M" in mats:
        M, V, K, B, C = (mats[k] for k in "MVKBC")
        n, m = model.n_dof, model.n_inputs
        for wi in w:
            R = K - wi**2 * M
            S = wi * V
            big = ca.vertcat(ca.horzcat(R, -S), ca.horzcat(S, R))
            X = ca.solve(big, ca.vertcat(B, ca.MX(n, m)))
            hr, hi = C @ X[:n, :], C @ X[n:, :]
            if model.output == "velocity":
                hr, hi = -wi * hi, wi * hr
            elif model.output == "acceleration":
                hr, hi = -(wi**2) * hr, -(wi**2) * hi
            Hr.append(hr)
            Hi.append(hi)
    else:
        A, B, C, D = (mats[k] for k in "ABCD")
        n, m = model.n_states, model.n_inputs
        eye = ca.DM.eye(n)
        for wi in w:
            big = ca.vertcat(ca.horzcat(-A, -wi * eye), ca.horzcat(wi * eye, -A))
            X = ca.solve(big, ca.vertcat(B, ca.MX(n, m)))
            Hr.append(C @ X[:n, :] + D)
            Hi.append(C @ X[n:, :])
    return Hr, Hi


def positivity_bounds(positive: Any, positivity: bool, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on z = θ / scale: 0 below where ``positive`` (a boolean per parameter) when ``positivity``.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.engine.ipopt import positivity_bounds
    >>> positivity_bounds([True, False], True, np.ones(2))[0].tolist()
    [0.0, -inf]
    """
    positive = np.asarray(positive, dtype=bool)
    lb = np.full(positive.size, -np.inf)
    if positivity:
        lb[positive] = 0.0
    return lb / scale, np.full(positive.size, np.inf)


@dataclass(frozen=True)
class IpoptRun:
    """One IPOPT solve: the solution, IPOPT's status, its iterations, whether it finished, the seconds."""

    z: np.ndarray
    status: str
    iterations: int
    finished: bool
    seconds: float


class IpoptSolver:
    """min f(z) subject to lbz ≤ z ≤ ubz with IPOPT (exact or L-BFGS Hessian), built once.

    Parameters
    ----------
    name : str
        CasADi name of the solver.
    z : casadi.MX
        The unknowns.
    f : casadi.MX
        The objective (scaled by the caller to be of order one).
    lbz, ubz : numpy.ndarray
        Bounds (``-inf``/``inf`` for none).
    max_iter : int
    tol : float
    hessian : {"exact", "limited-memory"}
    time_limit : float, optional
        Wall-time budget of one solve in seconds (IPOPT's ``max_wall_time``; status
        ``"Maximum_WallTime_Exceeded"``). Default: no limit.

    Examples
    --------
    >>> import casadi as ca
    >>> import numpy as np
    >>> from symid.engine.ipopt import IpoptSolver
    >>> x = ca.MX.sym("x")
    >>> solver = IpoptSolver("demo", x, (x - 2) ** 2, lbz=np.array([-np.inf]), ubz=np.array([np.inf]),
    ...                      max_iter=100, tol=1e-12, hessian="exact")
    >>> run = solver.solve(np.zeros(1))
    >>> round(float(run.z[0]), 6), run.status, run.finished
    (2.0, 'Solve_Succeeded', True)
    """

    def __init__(self, name: str, z: Any, f: Any, *, lbz: np.ndarray, ubz: np.ndarray, max_iter: int, tol: float,
                 hessian: str, time_limit: float | None = None):
        opts = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
                "ipopt.max_iter": int(max_iter), "ipopt.tol": float(tol),
                "ipopt.acceptable_tol": max(float(tol), 1e-12), "ipopt.acceptable_iter": 25,
                "error_on_fail": False}
        if hessian == "limited-memory":
            opts["ipopt.hessian_approximation"] = "limited-memory"
        if time_limit is not None:
            opts["ipopt.max_wall_time"] = float(time_limit)
        self._solver = ca.nlpsol(name, "ipopt", {"x": z, "f": f}, opts)
        self.lbz = np.asarray(lbz, dtype=float)
        self.ubz = np.asarray(ubz, dtype=float)

    def solve(self, z0: np.ndarray) -> IpoptRun:
        """Run IPOPT from ``z0`` (clipped to the bounds); never raises on solver failure.

        On a CasADi error (e.g. NaN in a linear solve) ``z`` is the clipped start and the
        status says what failed. Ctrl-C stops the solve at once and is raised after it
        (CasADi would otherwise report it as a failed start).
        """
        z0 = np.clip(np.asarray(z0, dtype=float), self.lbz, self.ubz)
        t0 = time.perf_counter()
        try:
            with native_interrupts(raise_now=True):
                sol = self._solver(x0=z0, lbx=self.lbz, ubx=self.ubz)
            stats = self._solver.stats()
            z = np.asarray(sol["x"]).reshape(-1)
            status = str(stats.get("return_status", "unknown"))
            iters = int(stats.get("iter_count", 0))
        except RuntimeError as exc:  # CasADi evaluation errors (NaN in the linear solve)
            return IpoptRun(z0, f"IPOPT failed: {exc}", 0, False, time.perf_counter() - t0)
        return IpoptRun(z, status, iters, status in IPOPT_SUCCESS, time.perf_counter() - t0)
