"""IPOPT on the similarity misfit (6-9): min over θ and T of ‖T𝔸 − A(θ)T‖² + ‖T𝔹 − B(θ)‖² + ‖ℂ − C(θ)T‖²."""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from symid.baselines.objective import SimilarityMisfit
from symid.errors import ModelError
from symid.formulations.similarity_data import SimilarityData, transform_outcome
from symid.formulations.similarity_start import INITS, initial_point
from symid.nlls.casadi_model import casadi_matrices
from symid.nlls.ipopt_start import solve_from
from symid.result import StartOutcome

__all__ = ["IpoptSimilarity"]


class IpoptSimilarity:
    """Nonlinear least squares (6-9) over z = (θ, vec T) with CasADi/IPOPT (exact Hessian).

    The objective is F(θ, T) / (‖𝔸‖² + ‖𝔹‖² + ‖ℂ‖²), the scaled misfit of
    :class:`~symid.baselines.SimilarityMisfit` (+ ‖𝔻 − D(θ)‖² when D holds parameters).
    Like ALS and GB it does not keep T invertible.

    Parameters
    ----------
    model : StateSpaceModel
    data : SimilarityData
    init : {"random", "theta", "zero", "identity"}
    seed : int
    bounds : bool
        Bound parameters declared positive below by 0 (default True).
    max_iter : int
        IPOPT iteration limit (default 3000).
    tol : float
        IPOPT tolerance (default 1e-12).
    """

    method = "ipopt"

    def __init__(self, model: Any, data: SimilarityData, *, init: str = "random", seed: int = 0,
                 bounds: bool = True, max_iter: int = 3000, tol: float = 1e-12):
        if init not in INITS:
            raise ModelError(f"init must be one of {', '.join(map(repr, INITS))}; got {init!r}")
        self.model, self.data, self.frf = model, data, data.frf
        self.init, self.seed = init, int(seed)
        self.misfit = SimilarityMisfit(model.maps, data.blackbox)
        self.options = {"init": init, "seed": int(seed), "bounds": bounds, "max_iter": int(max_iter),
                        "tol": float(tol), "black_box": data.source}
        bb = data.blackbox
        l, n = model.n_parameters, bb.n_states
        z = ca.MX.sym("z", l + n * n)
        theta = z[:l]
        T = ca.reshape(z[l:], n, n).T  # row-major vec T
        mats = casadi_matrices(model, theta)
        f = (ca.sumsqr(T @ ca.DM(bb.A) - mats["A"] @ T) + ca.sumsqr(T @ ca.DM(bb.B) - mats["B"])
             + ca.sumsqr(ca.DM(bb.C) - mats["C"] @ T))
        if self.misfit.with_d:
            f = f + ca.sumsqr(ca.DM(bb.D) - mats["D"])
        opts = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.max_iter": int(max_iter),
                "ipopt.tol": float(tol), "ipopt.acceptable_tol": max(float(tol), 1e-12),
                "ipopt.acceptable_iter": 25, "error_on_fail": False}
        self._solver = ca.nlpsol("symid_ipopt_similarity", "ipopt", {"x": z, "f": f / self.misfit.scale}, opts)
        lb = np.full(l + n * n, -np.inf)
        if bounds:
            lb[:l][np.array(model.positive, dtype=bool)] = 0.0
        self._lb, self._ub = lb, np.full(l + n * n, np.inf)

    def run(self, x0: np.ndarray) -> StartOutcome:
        """Solve from the start x₀; never raises on solver failure."""
        x0 = np.asarray(x0, dtype=float)
        theta0, T0, _ = initial_point(self.init, x0, self.seed, self.model.maps, self.data.blackbox)
        z0 = np.clip(self.misfit.join(theta0, T0), self._lb, self._ub)
        z, status, iters, ok, elapsed = solve_from(self._solver, z0, self._lb, self._ub)
        theta, T = self.misfit.split(z)
        return transform_outcome(self.model, self.data, x0, theta, T, ok, iters, elapsed, f"IPOPT: {status}")
