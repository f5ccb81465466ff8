"""IPOPT on the frequency-response misfit Σᵢ ‖Hᵢ − H(ωᵢ, θ)‖²_F."""

from __future__ import annotations

from typing import Any, ClassVar

import casadi as ca
import numpy as np

from symid.engine.ipopt import HESSIANS, IpoptSolver, casadi_frf, positivity_bounds
from symid.fit.frf.misfit import FrfEstimator
from symid.fit.options import check_bool, check_choice, check_float, check_int, check_scale, check_time_limit
from symid.fit.result import StartOutcome

__all__ = ["IpoptFRF"]


class IpoptFRF(FrfEstimator):
    """Nonlinear least squares on a frequency response with CasADi/IPOPT, built once, run per start.

    The objective is the relative misfit Σᵢ ‖Hᵢ − H(ωᵢ, θ)‖²_F / Σᵢ ‖Hᵢ‖²_F (real and
    imaginary parts), so its scale does not depend on the units of H (an objective of
    size 1e-8 makes IPOPT stop early). Exact first and second derivatives come from
    CasADi's automatic differentiation.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    data : FrequencyData
    scale : array_like, optional
        Typical magnitude of each parameter (one number or one per parameter); IPOPT
        works on θ / scale. Default 1.
    positivity : bool, optional
        Bound parameters declared ``positive=True`` below by 0. Default True.
    hessian : {"exact", "limited-memory"}, optional
        Exact Hessian (default) or L-BFGS.
    max_iter : int, optional
        IPOPT iteration limit (default 3000).
    tol : float, optional
        IPOPT convergence tolerance (default 1e-12 on the relative objective).
    time_limit : float, optional
        Wall-time budget of one start in seconds (IPOPT's ``max_wall_time``). Default: none.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.frf.ipopt import IpoptFRF
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, [2.0, 0.5, 3.0], np.linspace(0.5, 2.0, 5))
    >>> out = IpoptFRF(model, frf).run(np.array([1.5, 0.4, 2.0]))
    >>> np.round(out.theta, 6).tolist(), out.success, out.status
    ([2.0, 0.5, 3.0], True, 'Solve_Succeeded')
    """

    method: ClassVar[str] = "ipopt"

    def __init__(self, model: Any, data: Any, *, scale: Any = None, positivity: bool = True,
                 hessian: str = "exact", max_iter: int = 3000, tol: float = 1e-12, time_limit: float | None = None):
        self.model, self.data = model, data
        l = model.n_parameters
        self.scale = np.ones(l) if scale is None else check_scale("scale", scale, l)
        positivity = check_bool("positivity", positivity)
        hessian = check_choice("hessian", hessian, HESSIANS)
        max_iter = check_int("max_iter", max_iter, low=1, high=10**7)
        tol = check_float("tol", tol, low=0, strict_low=True)
        time_limit = check_time_limit("time_limit", time_limit)
        self.options = {"scale": self.scale.tolist(), "positivity": positivity, "hessian": hessian,
                        "max_iter": max_iter, "tol": tol, "time_limit": time_limit}
        z = ca.MX.sym("z", l)
        theta = z * ca.DM(self.scale)
        Hr, Hi = casadi_frf(model, theta, np.asarray(data.w))
        H = np.asarray(data.H)
        norm2 = float(np.sum(np.abs(H) ** 2)) or 1.0
        f = 0
        for i in range(len(Hr)):
            f = f + ca.sumsqr(Hr[i] - ca.DM(H[i].real)) + ca.sumsqr(Hi[i] - ca.DM(H[i].imag))
        lbz, ubz = positivity_bounds(model.positive, positivity, self.scale)
        self._solver = IpoptSolver("symid_ipopt_frf", z, f / norm2, lbz=lbz, ubz=ubz, max_iter=max_iter, tol=tol,
                                   hessian=hessian, time_limit=time_limit)

    def run(self, x0: np.ndarray) -> StartOutcome:
        """Solve from the start ``x0`` (parameter vector); never raises on solver failure."""
        x0 = np.asarray(x0, dtype=float)
        run = self._solver.solve(x0 / self.scale)
        return self.outcome(x0, run.z * self.scale, finished=run.finished, status=run.status, message=run.status,
                            iterations=run.iterations, wall_time=run.seconds)
