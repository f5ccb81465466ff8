"""IPOPT through CasADi: model matrices as CasADi expressions, and one bounded NLP solved from many starts.

Every IPOPT estimator of :mod:`symid.fit` poses min f(z) subject to bounds on z, with
z = θ / scale (and, for the similarity formulation, vec T), and solves it from one
start per call of :meth:`IpoptSolver.solve`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from symid.interrupt import native_interrupts

__all__ = ["HESSIANS", "IPOPT_SUCCESS", "IpoptIteration", "IpoptRun", "IpoptSolver", "ScaledIpopt", "casadi_affine",
           "casadi_frf", "casadi_matrices", "iteration_reporter", "positivity_bounds", "print_iteration", "start_scale"]

HESSIANS = ("exact", "limited-memory")
"""IPOPT's Hessian choices: exact (CasADi's automatic differentiation) or L-BFGS."""

GAUSS_NEWTON = "gauss-newton"
"""The Hessian choice of a least-squares objective f = ‖r‖² given with its residual's Jacobian
(:class:`ScaledIpopt`'s ``residual_jacobian=``): 2 JᵀJ, J = ∂r/∂θ, first derivatives only."""

IPOPT_SUCCESS = frozenset({"Solve_Succeeded", "Solved_To_Acceptable_Level"})
"""IPOPT return statuses counted as finished (its stopping rule was met)."""


def casadi_affine(amap: Any, theta: ca.MX) -> ca.MX:
    """An affine matrix X(θ) = X0 + Σ θi Xi (an :class:`~symid.model.affine.AffineMap`) as a CasADi expression."""
    X = ca.MX(ca.DM(amap.X0))
    for k in amap.depends_on:
        X = X + theta[k] * ca.DM(amap.Xi[k])
    return X


def casadi_matrices(model: Any, theta: ca.MX) -> dict[str, ca.MX]:
    """Every affine matrix X(θ) = X0 + Σ θi Xi of a model as a CasADi expression."""
    return {name: casadi_affine(amap, theta) for name, amap in model.maps.items()}


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
            if model.output != "position":  # each row times (jω)ᵈ, d its derivative order
                rows_r, rows_i = [], []
                for i, d in enumerate(model.output_orders):
                    r_, i_ = hr[i, :], hi[i, :]
                    if d == 1:
                        r_, i_ = -wi * i_, wi * r_
                    elif d == 2:
                        r_, i_ = -(wi**2) * r_, -(wi**2) * i_
                    rows_r.append(r_)
                    rows_i.append(i_)
                hr, hi = ca.vertcat(*rows_r), ca.vertcat(*rows_i)
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
    """One IPOPT solve: the solution, IPOPT's status, its iterations, whether it finished, the seconds, and a
    note on what was done beyond IPOPT's own run ('' when nothing was)."""

    z: np.ndarray
    status: str
    iterations: int
    finished: bool
    seconds: float
    note: str = ""


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
                "error_on_fail": False, "show_eval_warnings": False,
                "calc_lam_p": False}
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


def start_scale(theta0: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Typical magnitude of every parameter for a start: |θ₀| where it is not zero, else the largest
    finite non-zero bound, else 1.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.engine.ipopt import start_scale
    >>> inf = np.inf
    >>> start_scale(np.array([-2e3, 0.0, 0.0]), np.array([-inf, 0.0, 0.0]), np.array([inf, 50.0, inf])).tolist()
    [2000.0, 50.0, 1.0]
    """
    theta0 = np.asarray(theta0, dtype=float)
    bound = np.fmax(np.where(np.isfinite(lower), np.abs(lower), 0.0), np.where(np.isfinite(upper), np.abs(upper), 0.0))
    fallback = np.where(bound > 0, bound, 1.0)
    mag = np.abs(theta0)
    return np.where(np.isfinite(mag) & (mag > 0), mag, fallback)


@dataclass(frozen=True)
class IpoptIteration:
    """One IPOPT iteration of :class:`ScaledIpopt`, as ``callback`` receives it.

    Attributes
    ----------
    iteration : int
        0 (the start), 1, 2, …
    objective : float
        The objective f(θ) at the iterate, in the caller's units (e.g. the relative misfit).
    elapsed : float
        Seconds since the solve began.
    theta : numpy.ndarray
        The iterate.
    """

    iteration: int
    objective: float
    elapsed: float
    theta: np.ndarray = field(repr=False)


def print_iteration(info: IpoptIteration, label: str = "ipopt") -> None:
    """One line per IPOPT iteration (iteration, objective, elapsed seconds): what ``verbose=True`` prints; ``label``
    names the solver (another that reports the same way, e.g. ``"trf"``)."""
    print(f"{label:6s} iteration {info.iteration:5d}  objective {info.objective:.6e}  {info.elapsed:9.2f} s",
          flush=True)


def iteration_reporter(callback: Callable[[IpoptIteration], Any] | None, verbose: bool, label: str = "ipopt"
                       ) -> Callable[[IpoptIteration], bool] | None:
    """The per-iteration callback of :class:`ScaledIpopt` from a user's ``callback`` and ``verbose``
    (``None`` when neither is asked for: the solver then runs without one); ``label`` as for
    :func:`print_iteration`.

    Examples
    --------
    >>> from symid.engine.ipopt import IpoptIteration, iteration_reporter
    >>> import numpy as np
    >>> report = iteration_reporter(None, True)
    >>> report(IpoptIteration(3, 1.5e-4, 0.25, np.zeros(2)))
    ipopt  iteration     3  objective 1.500000e-04       0.25 s
    False
    """
    if callback is None and not verbose:
        return None

    def report(info: IpoptIteration) -> bool:
        if verbose:
            print_iteration(info, label)
        return bool(callback(info)) if callback is not None else False

    return report


class _IterationCallback(ca.Callback):
    """CasADi's ``iteration_callback``: hands (x, f) of every IPOPT iteration to ``report``; a true return
    value stops the solve (IPOPT status ``User_Requested_Stop``)."""

    def __init__(self, name: str, nx: int, n_p: int, report: Callable[[np.ndarray, float], bool]):
        ca.Callback.__init__(self)
        self.nx, self.n_p, self.report = nx, n_p, report
        self.construct(name, {})

    def get_n_in(self) -> int:
        return ca.nlpsol_n_out()

    def get_n_out(self) -> int:
        return 1

    def get_name_in(self, i: int) -> str:
        return ca.nlpsol_out(i)

    def get_name_out(self, i: int) -> str:
        return "ret"

    def get_sparsity_in(self, i: int) -> Any:
        name = ca.nlpsol_out(i)
        if name == "f":
            return ca.Sparsity.scalar()
        if name in ("x", "lam_x"):
            return ca.Sparsity.dense(self.nx)
        if name == "lam_p":
            return ca.Sparsity.dense(self.n_p)
        return ca.Sparsity(0, 0)

    def eval(self, arg: Any) -> list[int]:
        return [1 if self.report(np.asarray(arg[0], dtype=float).reshape(-1), float(arg[1])) else 0]


_DECADES = 4
"""The objective is scaled up by at most 10⁴: scaled further, the rounding noise of ∇f at an exact fit
(about 1e-13 for a relative misfit) would exceed the tolerance scaled alike; below 1e-4 (fits of noise-free or
nearly noise-free data) the barrier is kept small by μ₀ alone."""

_FROM_BEST = 1e-3
"""IPOPT runs again from its best iterate when its end is above that iterate's objective by more than this
(relative): measured on msd3_psd (thesis §5-6), ends 1e-6 above the best iterate spent a whole second run on
nothing (3000 iterations, 125 s), ends 3 % to 100× above it reached the fit to rounding in a few iterations."""

_TOL_CAP = 1e-6
"""The tolerance divided by the objective's decade stays below this (or the given tolerance, if larger): IPOPT
keeps its barrier parameter above tol / 10, so a tolerance near 1 would hold the barrier at 0.1."""


class ScaledIpopt:
    """min f(θ) subject to lower ≤ θ ≤ upper with IPOPT, scaled so that the result does not depend on units.

    IPOPT works on z = θ / s and on f / c:

    - s is ``scale`` when given, else set per start by :func:`start_scale` (|θ₀| where it
      is not zero), a CasADi parameter, so the solver is built once: every unknown
      starts at ±1 (or 0) whatever the units of θ, and IPOPT's bound push, barrier and
      tolerances act alike on every parameter;
    - c = 10^⌊log₁₀ f(θ₀)⌋ (clipped to [1e-4, 1]), the decade of the start's objective, so
      that f / c starts between 1 and 10; the tolerance is divided by c as well (the same
      stopping point in f; at most 1e-6 or ``tol``);
    - the log barrier of the bounds starts at μ₀ = 0.1 min(1, ‖∇_z (f/c)(z₀)‖∞) (IPOPT's
      default 0.1 from a start the objective pulls away from, less from a start where it
      is nearly stationary), with bound multipliers started at μ₀ / slack. The barrier
      term μ Σ −log(zᵢ − lᵢ) pushes every unknown away from its bound; when it outweighs
      what the objective asks, IPOPT leaves a converged fit: with IPOPT's μ₀ = 0.1 against
      a relative misfit of 1e-2, it walked from a fit of the F-16 ground vibration test
      with lightly damped modes (misfit 0.0102) to another basin (0.034), and it leaves
      sloppy optima of noisy data for hundreds of iterations (measured by
      ``benchmarks/ipopt_barrier.py``).

    One solver is built per (decade, μ₀ decade, iteration cap, time cap) on demand, all
    from one CasADi function of the objective (the second costs a fraction of the first).
    An objective that depends on further numbers fixed per start (``parameters``, e.g.
    the balancing of a matrix exponential) takes them as CasADi parameters too.

    Parameters
    ----------
    name : str
        CasADi name of the solver.
    theta : casadi.MX or casadi.SX
        The parameter symbol (a column of ``l`` entries).
    f : casadi.MX or casadi.SX
        The objective in ``theta`` (normalised by the caller, e.g. by ‖data‖²).
    lower, upper : numpy.ndarray
        Bounds on θ (``-inf``/``inf`` for none).
    max_iter, tol, hessian, time_limit
        As :class:`IpoptSolver`.
    scale : numpy.ndarray, optional
        Fixed typical magnitudes (default: per start).
    callback : callable, optional
        Called with an :class:`IpoptIteration` after every iteration; a true return
        value stops the start (status ``"User_Requested_Stop"``).
    ipopt_options : dict, optional
        Further IPOPT options, for studies of the set-up.
    parameters : casadi.MX or casadi.SX, optional
        A column of further symbols in ``f`` whose values every :meth:`solve` gives
        (``values``); they are not optimised.
    start_scaling, objective_scaling, barrier_from_start : bool
        The three scalings above (default all True; False gives IPOPT's own set-up, for
        comparisons).
    from_best : bool
        When IPOPT ends above the best objective its iterates reached, run it again from
        that iterate with a small barrier and keep the better (default True; see
        :meth:`_from_best`).
    residual_jacobian : casadi.Function, optional
        For ``hessian="gauss-newton"`` (:data:`GAUSS_NEWTON`; required then): (θ, parameters)
        ↦ ∂r/∂θ of the residual r of f = ‖r‖². IPOPT then uses 2 JᵀJ (in z = θ / s), which
        needs first derivatives of r only: cheaper to build than the exact Hessian, and
        exact at a zero-residual fit.

    Examples
    --------
    >>> import casadi as ca
    >>> import numpy as np
    >>> from symid.engine.ipopt import ScaledIpopt
    >>> t = ca.MX.sym("t", 2)
    >>> solver = ScaledIpopt("demo", t, (t[0] - 3e4) ** 2 / 9e8 + (t[1] - 2e-3) ** 2 / 4e-6,
    ...                      lower=np.zeros(2), upper=np.full(2, np.inf), max_iter=100, tol=1e-12,
    ...                      hessian="exact")
    >>> run = solver.solve(np.array([1e4, 1e-3]))
    >>> np.round(run.z / [3e4, 2e-3], 8).tolist(), run.status
    ([1.0, 1.0], 'Solve_Succeeded')
    """

    def __init__(self, name: str, theta: Any, f: Any, *, lower: np.ndarray, upper: np.ndarray, max_iter: int,
                 tol: float, hessian: str, time_limit: float | None = None, scale: np.ndarray | None = None,
                 callback: Callable[[IpoptIteration], Any] | None = None,
                 ipopt_options: dict[str, Any] | None = None, start_scaling: bool = True,
                 objective_scaling: bool = True, barrier_from_start: bool = True, parameters: Any = None,
                 from_best: bool = True, residual_jacobian: Any = None):
        self.name = name
        self.lower = np.asarray(lower, dtype=float)
        self.upper = np.asarray(upper, dtype=float)
        self.l = self.lower.size
        self.scale = None if scale is None else np.asarray(scale, dtype=float)
        self.n_values = 0 if parameters is None else int(parameters.numel())
        q = (ca.MX if isinstance(theta, ca.MX) else ca.SX)(0, 1) if parameters is None else parameters
        self.objective = ca.Function(f"{name}_f", [theta, q], [f])
        self.gradient = ca.Function(f"{name}_g", [theta, q], [ca.gradient(f, theta)]) if barrier_from_start else None
        if hessian == GAUSS_NEWTON and residual_jacobian is None:
            raise ValueError(f"{name}: hessian={GAUSS_NEWTON!r} needs the residual's Jacobian (f = ‖r‖²)")
        self.residual_jacobian = residual_jacobian if hessian == GAUSS_NEWTON else None
        self.max_iter, self.tol, self.hessian, self.time_limit = int(max_iter), float(tol), hessian, time_limit
        self.ipopt_options = dict(ipopt_options or {})
        self.start_scaling, self.objective_scaling = bool(start_scaling), bool(objective_scaling)
        self.from_best = bool(from_best)
        self.callback = callback
        # every iteration is seen: the best iterate is kept (``solve``), and the callback, if any, is called
        self._iter_callback = _IterationCallback(f"{name}_progress", self.l, self.l + self.n_values, self._report)
        self._context: dict[str, Any] = {}
        self._solvers: dict[tuple[int, int, int, float | None], Any] = {}

    # -- the scalings --------------------------------------------------------------------------
    def scale_for(self, theta0: np.ndarray) -> np.ndarray:
        """s of a start: ``scale`` when given, else :func:`start_scale` (ones without start scaling)."""
        if self.scale is not None:
            return self.scale
        if not self.start_scaling:
            return np.ones(self.l)
        return start_scale(theta0, self.lower, self.upper)

    def _values(self, values: Any) -> np.ndarray:
        v = np.zeros(0) if values is None else np.asarray(values, dtype=float).reshape(-1)
        if v.size != self.n_values:
            raise ValueError(f"{self.name}: {self.n_values} parameter value(s) expected, got {v.size}")
        return v

    def decade(self, theta0: np.ndarray, values: Any = None) -> int:
        """⌊log₁₀ f(θ₀)⌋ clipped to [−4, 0] (0 without objective scaling or where f is not finite)."""
        if not self.objective_scaling:
            return 0
        try:
            f0 = float(self.objective(theta0, self._values(values)))
        except RuntimeError:
            return 0
        return int(np.clip(np.floor(np.log10(f0)), -_DECADES, 0)) if np.isfinite(f0) and f0 > 0 else 0

    def barrier_decade(self, theta0: np.ndarray, s: np.ndarray, decade: int, values: Any = None) -> int:
        """log₁₀ μ₀: ⌊log₁₀(0.1 ‖∇_z f(θ₀)‖∞ / c)⌋ clipped to [−10, −1] (−1, IPOPT's μ₀ = 0.1, without it)."""
        if self.gradient is None:
            return -1
        try:
            g = np.asarray(self.gradient(theta0, self._values(values)), dtype=float).reshape(-1) * s / 10.0**decade
        except RuntimeError:
            return -1
        gmax = float(np.max(np.abs(g))) if g.size else 0.0
        if not np.isfinite(gmax):
            return -1
        return int(np.clip(np.floor(np.log10(max(0.1 * gmax, 1e-300))), -10, -1))

    # -- the solvers ---------------------------------------------------------------------------
    def _options(self, decade: int, mu: int, max_iter: int, time_limit: float | None) -> dict[str, Any]:
        tol = min(self.tol / 10.0**decade, max(self.tol, _TOL_CAP))
        opts: dict[str, Any] = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
                                "ipopt.max_iter": max_iter, "ipopt.tol": tol,
                                "ipopt.acceptable_tol": max(tol, 1e-12), "ipopt.acceptable_iter": 25,
                                "error_on_fail": False, "show_eval_warnings": False,
                                "calc_lam_p": False}
        if self.hessian == "limited-memory":
            opts["ipopt.hessian_approximation"] = "limited-memory"
        if time_limit is not None:
            opts["ipopt.max_wall_time"] = float(time_limit)
        if mu < -1:
            opts["ipopt.mu_init"] = 10.0**mu
            opts["ipopt.bound_mult_init_method"] = "mu-based"
        if self._iter_callback is not None:
            opts["iteration_callback"] = self._iter_callback
        opts.update({f"ipopt.{k}": v for k, v in self.ipopt_options.items()})
        return opts

    def _solver(self, decade: int, mu: int, max_iter: int, time_limit: float | None, keep: bool = True) -> Any:
        """The IPOPT solver for these caps, built once and kept (``keep=False``: a one-off cap, built and not
        kept, such as a rerun from the best iterate with the time left)."""
        key = (decade, mu, max_iter, time_limit)
        if key in self._solvers:
            return self._solvers[key]
        z = ca.MX.sym("z", self.l)
        s = ca.MX.sym("s", self.l)
        q = ca.MX.sym("q", self.n_values)
        nlp = {"x": z, "p": ca.vertcat(s, q), "f": self.objective(z * s, q) / 10.0**decade}
        opts = self._options(decade, mu, max_iter, time_limit)
        if self.residual_jacobian is not None:  # 2 JᵀJ in z: first derivatives of r only
            lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", 0)
            Jz = self.residual_jacobian(z * s, q) @ ca.diag(s)
            H = 2 * lam_f / 10.0**decade * (Jz.T @ Jz)
            opts["hess_lag"] = ca.Function(f"{self.name}_hess", [z, ca.vertcat(s, q), lam_f, lam_g], [ca.triu(H)],
                                           ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])
        solver = ca.nlpsol(f"{self.name}_{len(self._solvers)}", "ipopt", nlp, opts)
        if keep:
            self._solvers[key] = solver
        return solver

    def _report(self, z: np.ndarray, f: float) -> bool:
        ctx = self._context
        if np.isfinite(f) and f < ctx["best"][0]:
            ctx["best"] = (f, z.copy())
        ctx["iteration"] += 1
        if self.callback is None:
            return False
        info = IpoptIteration(iteration=ctx["iteration"] - 1, objective=f * ctx["c"],
                              elapsed=time.perf_counter() - ctx["t0"], theta=z * ctx["s"])
        return bool(self.callback(info))

    def solve(self, theta0: np.ndarray, *, max_iter: int | None = None, time_limit: float | None = None,
              scale: np.ndarray | None = None, values: Any = None) -> IpoptRun:
        """Run IPOPT from ``theta0`` (clipped to the bounds); ``IpoptRun.z`` is θ, within the bounds.

        ``max_iter`` and ``time_limit`` cap this solve below the solver's own (e.g. a trial
        polish); ``scale`` replaces s for this solve; ``values`` are those of ``parameters``.
        Never raises on solver failure (as :meth:`IpoptSolver.solve`).
        """
        theta0 = np.clip(np.asarray(theta0, dtype=float), self.lower, self.upper)
        iters = self.max_iter if max_iter is None else min(int(max_iter), self.max_iter)
        limit = self.time_limit
        if time_limit is not None:
            limit = float(time_limit) if limit is None else min(float(time_limit), limit)
        s = self.scale_for(theta0) if scale is None else np.asarray(scale, dtype=float)
        q = self._values(values)
        decade = self.decade(theta0, q)
        t0 = time.perf_counter()
        run = self._run(theta0, s, q, decade, self.barrier_decade(theta0, s, decade, q), iters, limit, t0)
        if self.from_best and run.status == "User_Requested_Stop":
            run = self._stopped_at_best(run, s, q, t0)
        elif self.from_best and not run.status.startswith("IPOPT failed"):
            run = self._from_best(run, s, q, decade, iters, limit, t0)
        return run

    def _stopped_at_best(self, run: IpoptRun, s: np.ndarray, q: np.ndarray, t0: float) -> IpoptRun:
        """A run its callback stopped (the caller's time budget, or a user) ends wherever IPOPT was, which can lie
        far above the best iterate: an output-error start on a 3-mass chain with gains, cut by its 60 s budget
        mid-way, ended at misfit 2.5e11 from a start at 6.6e6. The best iterate is returned instead when it lies
        lower (no rerun: the caller asked to stop), and the note says so."""
        below = self._best_below_end(run, s, q)
        if below is None:
            return run
        best, f_best, f_end = below
        return IpoptRun(best, run.status, run.iterations, False, time.perf_counter() - t0,
                        f"; stopped at objective {f_end:.6g}, above its best iterate's {f_best:.6g}: that iterate kept")

    def _best_below_end(self, run: IpoptRun, s: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, float, float] | None:
        """(best iterate within the bounds, its objective, the end's objective) when the best iterate the last solve
        visited lies below the end by more than ``_FROM_BEST`` (relative), else ``None``."""
        f_best, z_best = self._context["best"]
        if z_best is None:
            return None
        best = np.clip(z_best * s, self.lower, self.upper)
        f_end, f_best = self._f(run.z, q), self._f(best, q)
        return (best, f_best, f_end) if f_best < f_end * (1 - _FROM_BEST) else None

    def _run(self, theta0: np.ndarray, s: np.ndarray, q: np.ndarray, decade: int, mu: int, iters: int,
             limit: float | None, t0: float, first: int = 0,
             left: tuple[int, float | None] | None = None) -> IpoptRun:
        """One IPOPT solve from θ₀, its iterations numbered from ``first`` for the callback (the best iterate it
        visits is left in ``self._context["best"]``); ``left`` = (iterations, seconds) caps it below ``iters``
        and ``limit``, with a solver built for these caps and not kept."""
        solver = self._solver(decade, mu, iters, limit) if left is None else self._solver(decade, mu, *left,
                                                                                          keep=False)
        self._context = {"iteration": first, "c": 10.0**decade, "s": s, "t0": t0, "best": (np.inf, None)}
        try:
            with native_interrupts(raise_now=True):
                sol = solver(x0=theta0 / s, p=np.concatenate([s, q]), lbx=self.lower / s, ubx=self.upper / s)
            stats = solver.stats()
            # IPOPT relaxes the bounds by 1e-8 (bound_relax_factor): the estimate returned lies within them
            theta = np.clip(np.asarray(sol["x"]).reshape(-1) * s, self.lower, self.upper)
            status = str(stats.get("return_status", "unknown"))
            iters_done = int(stats.get("iter_count", 0))
        except RuntimeError as exc:  # CasADi evaluation errors (NaN in the linear solve)
            return IpoptRun(theta0, f"IPOPT failed: {exc}", 0, False, time.perf_counter() - t0)
        return IpoptRun(theta, status, iters_done, status in IPOPT_SUCCESS, time.perf_counter() - t0)

    def _f(self, theta: np.ndarray, q: np.ndarray) -> float:
        try:
            v = float(self.objective(theta, q))
        except RuntimeError:
            return np.inf
        return v if np.isfinite(v) else np.inf

    def _from_best(self, run: IpoptRun, s: np.ndarray, q: np.ndarray, decade: int, iters: int,
                   limit: float | None, t0: float) -> IpoptRun:
        """IPOPT ends where the barrier problem is solved, which can lie above the best objective its iterates
        reached: on a flat direction the log barrier of θ ≥ 0 pushes the iterate away, and the objective there
        is no longer steep enough to pull it back (a quarter car at 1 % noise, from the truth: the unsprung
        mass 1e5 times too large, misfit 3.47e-5 against 3.38e-5 at iteration 8). Then IPOPT runs again from
        that best iterate with a small barrier (μ₀ = 1e-9); the better of the two, or the best iterate itself,
        is kept, and the note says so. The rerun takes at most twice the iterations of the first run (at least
        100) and what is left of the time limit."""
        below = self._best_below_end(run, s, q)
        if below is None:
            return run
        best, f_best, f_end = below
        left = None if limit is None else limit - (time.perf_counter() - t0)
        if left is not None and left <= 0:
            return IpoptRun(best, run.status, run.iterations, False, time.perf_counter() - t0,
                            f"; its best iterate kept (objective {f_best:.6g} against {f_end:.6g} at its end)")
        # the caps of the first run (whole seconds: one solver per cap is built and kept, see _solver); the
        # iterations left and the time left bound what the rerun adds
        # at most twice the iterations the first run took (100 at least), within what is left of both caps
        extra = max(min(iters - run.iterations, max(2 * run.iterations, 100)), 1)
        again = self._run(best, s, q, decade, -9, iters, limit, t0, first=self._context["iteration"],
                          left=(extra, None if left is None else math.ceil(left)))
        f_again = self._f(again.z, q) if not again.status.startswith("IPOPT failed") else np.inf
        how = f"ended at objective {f_end:.6g} above its best iterate's {f_best:.6g}"
        if f_again <= f_best:
            return IpoptRun(again.z, again.status, run.iterations + again.iterations, again.finished,
                            time.perf_counter() - t0, f"; IPOPT {how} and was run again from there "
                                                      f"(μ₀ = 1e-9): objective {f_again:.6g}")
        return IpoptRun(best, run.status, run.iterations + again.iterations, False, time.perf_counter() - t0,
                        f"; IPOPT {how}; its best iterate kept")
