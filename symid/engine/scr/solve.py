"""Algorithm 2.1 (Sequential Convex Relaxation) driving either back end."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from symid.engine.scr.backend_admm import ADMMBackend, ADMMOptions
from symid.engine.scr.blocks import TermGroup
from symid.engine.scr.compiled import INCONSISTENT_TOL, CompiledProblem
from symid.engine.scr.compiled import compile as _compile
from symid.engine.scr.presolve import Reduced
from symid.engine.scr.problem import BilinearProblem
from symid.engine.scr.result import Iteration, SCRSolution
from symid.errors import ModelError

__all__ = ["solve"]

_BACKENDS = ("admm", "cvxpy")
_HEURISTICS = ("nuclear", "truncated")
_STALL_DECREASE = 0.01
_STEP_ACCURACY = 0.1


def _relaxation(red: Reduced, groups: list[TermGroup], built: list[tuple[np.ndarray, np.ndarray]],
                W: list[np.ndarray] | None, z: np.ndarray) -> float:
    val = red.objective(z)
    for k, g in enumerate(groups):
        m0, G = built[k]
        M = m0 + np.einsum("spu,su->sp", G, g.gather(z)).reshape(m0.shape)
        sv = np.linalg.svd(M, compute_uv=False)
        val += float(g.weight @ sv.sum(axis=1))
        if W is not None:
            val -= float(g.weight @ np.einsum("sij,sij->s", W[k], M))
    return val


def _truncation(groups: list[TermGroup], ranks: list[np.ndarray], Q_old: list[np.ndarray],
                R_old: list[np.ndarray], Q: list[np.ndarray], R: list[np.ndarray], z: np.ndarray) -> list[np.ndarray]:
    """W_t = U V^T for the truncated nuclear norm (Hu et al. 2012).

    U_r, V_r are the leading rank(P_t) singular vectors of the last sub-problem's optimal
    M_t(x; Q_old, R_old) (Hu et al.'s X_l), carried to the new Q, R by the identity
    M(x; Q', R') = [[I, Q'−Q], [0, I]] M(x; Q, R) [[I, 0], [R'−R, I]].
    """
    out = []
    for k, g in enumerate(groups):
        j, _, _, m = g.dims
        m0, G = g.build(Q_old[k], R_old[k])
        M = m0 + np.einsum("spu,su->sp", G, g.gather(z)).reshape(m0.shape)
        U, _, Vt = np.linalg.svd(M, full_matrices=False)
        r = int(ranks[k].max())
        U, V = U[:, :, :r], Vt[:, :r, :].transpose(0, 2, 1)
        U = U.copy()
        U[:, :j] += (Q[k] - Q_old[k]) @ U[:, j:]
        V = V.copy()
        V[:, :m] += (R[k] - R_old[k]).transpose(0, 2, 1) @ V[:, m:]
        U, _ = np.linalg.qr(U)
        V, _ = np.linalg.qr(V)
        out.append(U @ V.transpose(0, 2, 1))
    return out


def solve(prob: BilinearProblem | CompiledProblem, x0: Mapping[Any, Any] | None = None, *, backend: str = "admm",
          max_iter: int = 100, tol: float = 1e-6, step_tol: float | None = None, heuristic: str = "nuclear",
          truncate_after: int = 0, presolve: bool | None = None, normalize: bool | None = None,
          admm: ADMMOptions | None = None, solver_options: dict | None = None,
          callback: Callable[[int, dict[str, Any]], bool] | None = None,
          time_limit: float | None = None, stationary: int | None = 3,
          monitor: Callable[[int, dict[str, Any], Iteration, float], bool] | None = None) -> SCRSolution:
    """Solve a bilinear problem by Sequential Convex Relaxation (thesis Algorithm 2.1).

    Every iteration minimises f(x) + Σ_t λ_t ||M_t(x; Q_t, R_t)||_* subject to the
    linear equalities and LMIs, with M of (2-6), then sets Q_t := −A_t(x), R_t := −B_t(x).
    Q, R start at −A(x0), −B(x0).

    Parameters
    ----------
    prob : BilinearProblem or CompiledProblem
        A problem, or one prepared by :func:`symid.engine.scr.compile` for many solves
        (multi-start): its presolve, blocks and compiled SDP are then reused, with the
        same iterates as a solve of the bare problem.
    x0 : dict, optional
        Starting values by variable name, sympy symbol or Variable; missing variables
        start at 0. Unknown names and non-finite values raise :class:`ModelError`.
    backend : {"admm", "cvxpy"}
        ``"admm"``: numpy ADMM with singular value thresholding and PSD projection
        (fast, inexact). ``"cvxpy"``: the SDP (2-9) with Clarabel, compiled once.
    max_iter : int
        Maximum number of SCR iterations.
    tol : float
        Stop when the largest bilinear residual of the normalised, presolved terms is
        ≤ ``tol`` and the step ||x_k − x_{k−1}||_∞ is ≤ ``step_tol``.
    step_tol : float, optional
        Default ``max(10 * tol, 1e-8) * max(1, ||x||_∞)``.
    heuristic : {"nuclear", "truncated"}
        Rank surrogate. ``"truncated"`` is the truncated nuclear norm (Hu et al. 2012;
        thesis §6-7-1): after ``truncate_after`` plain iterations (at least one), each
        sub-problem minimises ||M||_* − <U_r V_rᵀ, M> with U_r, V_r the leading rank(P)
        singular vectors of the previous sub-problem's optimal M, carried to the new Q, R.
        Groups of terms share the largest rank(P) of the group.
    truncate_after : int
        Plain nuclear-norm iterations before the truncated ones start.
    presolve : bool, optional
        Move the affine rows/columns of the bilinear terms to linear equalities and
        eliminate variables they determine (default ``True``); see :mod:`symid.engine.scr.presolve`.
        For a :class:`CompiledProblem` it is fixed at compilation (leave it ``None``).
    normalize : bool, optional
        Equilibrate each term so one λ means the same across problems (default ``True``):
        P scaled to unit spectral norm, each row of the equation by its largest coefficient
        in A and C, each column by its largest coefficient in B and C; complex terms get
        half the weight in the real representation (2-8). See :mod:`symid.scr`.
        For a :class:`CompiledProblem` it is fixed at compilation (leave it ``None``).
    admm : ADMMOptions, optional
        Options of the ADMM back end.
    solver_options : dict, optional
        Extra keyword arguments for ``cvxpy.Problem.solve`` (cvxpy back end).
    callback : callable, optional
        ``callback(k, x)`` is called after every SCR iteration k = 1, 2, … that did not
        meet the stopping rule, with the iterate ``x`` by variable name; a true return
        stops SCR (status ``"stopped"``). Its time counts in ``wall_time``. Used, e.g.,
        to hand over to a local solver once SCR has reached a good basin.
    time_limit : float, optional
        Wall-time budget in seconds, presolve included (status ``"time_limit"``): no new
        iteration starts once it is spent, and the iteration under way is cut short — the
        ADMM back end checks the clock every ``check_every`` inner iterations and keeps its
        inexact iterate, Clarabel gets the remaining time as its ``time_limit`` and its
        unfinished solve is discarded (the last iterate is kept). What cannot be cut is
        cvxpy's one-off compilation of the SDP (first iteration of a solve) and one
        ADMM factorisation. Default: no limit.
    stationary : int or None, optional
        Stop (status ``"stationary"``) after this many consecutive iterations whose step
        met ``step_tol`` while the residual, still above ``tol``, fell by less than 1 %
        each: the iterate has stopped moving where the equalities cannot all hold
        (noisy data: measured on the 2-DOF problem of thesis §4-6-2 with 1 % noise, ADMM
        stops after 41–134 iterations instead of running to ``max_iter``). Default 3;
        ``None`` runs to ``max_iter``.
    monitor : callable, optional
        ``monitor(k, x, iteration, elapsed)`` after every iteration k = 1, 2, … (the last
        one included), with the iterate ``x`` by variable name, its :class:`Iteration`
        record and the seconds since the solve began: progress reports. A true return
        stops SCR (status ``"stopped"``) unless that iteration met the stopping rule.

    Returns
    -------
    SCRSolution
        ``success`` is ``True`` only when the stopping rule was met; a back-end failure
        gives ``status="solver_error"`` and keeps the last good iterate; a stop asked by
        ``callback`` gives ``status="stopped"``; an iterate that stopped moving short of
        ``tol`` gives ``status="stationary"`` (``info["stationary"]`` is then true).

    Examples
    --------
    Rosenbrock, thesis Algorithm 2.3 with λ = 0.1 from (−1.9, 2):

    >>> import sympy as sp
    >>> from symid import scr
    >>> x, y, a = sp.symbols("x y a")
    >>> prob = scr.BilinearProblem(
    ...     variables=[x, y, a],
    ...     bilinear=[scr.Bilinear(A=[[x]], P=[[1]], B=[[x]], C=[[y - a]], weight=0.1)],
    ...     objective=100 * a**2 + (1 - x)**2)
    >>> sol = scr.solve(prob, x0={x: -1.9, y: 2}, backend="cvxpy", max_iter=6)
    >>> round(sol.iterates[0]["x"], 3), round(sol.iterates[0]["y"], 3)
    (0.9, -6.03)
    >>> abs(sol.x["x"] - 1) < 1e-3 and abs(sol.x["y"] - 1) < 1e-3
    True
    """
    t_start = time.perf_counter()
    deadline = None if time_limit is None else t_start + float(time_limit)
    if isinstance(prob, CompiledProblem):
        for name, given, fixed in (("presolve", presolve, prob.presolve), ("normalize", normalize, prob.normalize)):
            if given is not None and bool(given) != fixed:
                raise ModelError(f"{name}={given!r} differs from the compiled problem's {name}={fixed}; "
                                 f"compile the problem again with {name}={given!r}")
        compiled = prob
    elif isinstance(prob, BilinearProblem):
        compiled = None
    else:
        raise ModelError(f"solve() needs a BilinearProblem or a CompiledProblem, got {type(prob).__name__}")
    if backend not in _BACKENDS:
        raise ModelError(f"unknown backend {backend!r}; choose one of {_BACKENDS}")
    if heuristic not in _HEURISTICS:
        raise ModelError(f"unknown heuristic {heuristic!r}; choose one of {_HEURISTICS}")
    if int(max_iter) < 1:
        raise ModelError(f"max_iter must be ≥ 1, got {max_iter}")
    if not (np.isfinite(tol) and tol > 0):
        raise ModelError(f"tol must be finite and > 0, got {tol}")
    if step_tol is not None and not (np.isfinite(step_tol) and step_tol >= 0):
        raise ModelError(f"step_tol must be finite and ≥ 0, got {step_tol}")
    if stationary is not None and (isinstance(stationary, bool) or not isinstance(stationary, (int, np.integer))
                                   or stationary < 1):
        raise ModelError(f"stationary must be an integer ≥ 1 or None, got {stationary!r}")
    if int(truncate_after) < 0:
        raise ModelError(f"truncate_after must be ≥ 0, got {truncate_after}")
    if admm is not None and not isinstance(admm, ADMMOptions):
        raise ModelError(f"admm must be an scr.ADMMOptions, got {type(admm).__name__}")
    if solver_options is not None and not isinstance(solver_options, Mapping):
        raise ModelError(f"solver_options must be a dict, got {type(solver_options).__name__}")
    if callback is not None and not callable(callback):
        raise ModelError(f"callback must be callable, got {type(callback).__name__}")
    if monitor is not None and not callable(monitor):
        raise ModelError(f"monitor must be callable, got {type(monitor).__name__}")
    if time_limit is not None and not (isinstance(time_limit, (int, float)) and not isinstance(time_limit, bool)
                                       and time_limit > 0):
        raise ModelError(f"time_limit must be a number of seconds > 0 or None, got {time_limit!r}")
    lay = (compiled.problem if compiled is not None else prob).layout
    x_start = lay.pack(x0)
    if compiled is None:
        compiled = _compile(prob, presolve=True if presolve is None else presolve,
                            normalize=True if normalize is None else normalize)
    prob = compiled.problem
    red, groups, lgroups = compiled.reduced, compiled.groups, compiled.lmi_groups
    t_pre = time.perf_counter() - t_start
    info: dict[str, Any] = dict(red.info)
    info["presolve_time"] = t_pre  # ~0 when a compiled problem is reused
    info["presolve_first_time"] = compiled.prepare_time  # what compiling the problem cost
    if red.inconsistent > INCONSISTENT_TOL:
        return SCRSolution(lay.unpack(x_start), (), (), "infeasible", False,
                           f"the linear equalities (given and split off the bilinear terms) are inconsistent: "
                           f"residual {red.inconsistent:.3e}", 0, time.perf_counter() - t_start, backend,
                           x_start, info)
    info["groups"] = [dict(zip(("j", "k", "l", "m"), g.dims, strict=True)) | {"s": g.s, "u": g.idx.shape[1]}
                      for g in groups]
    z = x_start[red.free].copy()
    t0 = time.perf_counter()
    if backend == "admm":
        be = ADMMBackend(red, groups, lgroups, admm or ADMMOptions())
        info["rho"] = be.rho
    else:
        be = compiled.cvxpy_backend(solver_options)
        compilations0, compile_time0 = be.compilations, be.compile_time
        info["is_dpp"] = bool(be.problem.is_dpp())
    info["setup_time"] = time.perf_counter() - t0
    Q = [-g.A(z) for g in groups]
    R = [-g.B(z) for g in groups]
    ranks = [np.linalg.matrix_rank(g.P) for g in groups]
    Q_prev, R_prev = Q, R
    x_prev = red.lift(z)
    history: list[Iteration] = []
    xs: list[np.ndarray] = []
    status, message = "max_iter", ""
    cut = cut_kept = False
    last_res = np.inf
    last_step = np.inf
    still = 0  # consecutive iterations that met the step rule without reducing the residual
    stol = np.inf
    n_iter = max_iter if groups else 1
    for k in range(n_iter):
        t_it, c_it = time.perf_counter(), time.process_time()
        W = None
        if heuristic == "truncated" and k >= max(truncate_after, 1) and groups:
            W = _truncation(groups, ranks, Q_prev, R_prev, Q, R, z)
        t_b = time.perf_counter()
        built = [g.build(q, r) for g, q, r in zip(groups, Q, R, strict=True)]
        t_build = time.perf_counter() - t_b
        # the sub-problem as accurate as the last residual or, once the iterate barely moves (noisy data,
        # residual stuck), a tenth of the last step: otherwise inexact ADMM steps jitter at the accuracy
        # they are solved to and never settle (measured: 2-DOF, 1 % noise, scaled unknowns, 500 iterations)
        z_new, ok, msg, timing = be.step(built, W, z, min(last_res, _STEP_ACCURACY * last_step), deadline)
        cut = bool(timing.get("time_limit", False))  # the back end stopped at the deadline
        cut_kept = cut and ok  # its inexact iterate kept (ADMM) or discarded (Clarabel)
        if not ok:
            status, message = ("time_limit", msg) if cut else ("solver_error", msg)
            break
        t_b = time.perf_counter()
        relax = _relaxation(red, groups, built, W, z_new)
        z = z_new
        x = red.lift(z)
        res_terms = tuple(float(v) for v in prob.residuals(x))
        res = max((float(g.residual(z).max()) for g in groups), default=0.0)
        step = float(np.max(np.abs(x - x_prev), initial=0.0))
        Q_prev, R_prev = Q, R
        Q = [-g.A(z) for g in groups]
        R = [-g.B(z) for g in groups]
        timing = dict(timing)
        timing["build"] = timing.get("build", 0.0) + t_build
        timing["bookkeeping"] = time.perf_counter() - t_b
        timing["cpu"] = time.process_time() - c_it
        history.append(Iteration(red.objective(z), relax, res_terms, res, step, time.perf_counter() - t_it, timing))
        xs.append(x)
        if msg:
            message = msg
        asked = monitor is not None and bool(monitor(k + 1, lay.unpack(x), history[-1],
                                                      time.perf_counter() - t_start))
        stol = (step_tol if step_tol is not None else max(10 * tol, 1e-8)) * max(1.0, float(np.abs(x).max(initial=0)))
        if res <= tol and step <= stol:
            status = "converged"
            break
        if cut:
            status, message = "time_limit", msg
            break
        if asked:
            status = "stopped"
            break
        still = still + 1 if step <= stol and res >= (1 - _STALL_DECREASE) * last_res else 0
        if stationary is not None and still >= stationary:
            status = "stationary"
            break
        if not groups:  # convex after presolve: one exact (or capped ADMM) solve
            status = "max_iter" if msg and backend == "admm" else "converged"
            break
        if callback is not None and callback(k + 1, lay.unpack(x)):
            status = "stopped"
            break
        if time_limit is not None and time.perf_counter() - t_start >= time_limit and k + 1 < n_iter:
            status = "time_limit"
            break
        if res >= 0.99 * last_res:
            be.on_stall()
        last_res = res
        last_step = step
        x_prev = x
    if backend == "cvxpy":
        info["compilations"] = be.compilations - compilations0
        info["compile_time"] = be.compile_time - compile_time0
    else:
        info["inner_iterations"] = list(be.iterations)
        info["rho_final"] = be.rho
    x_final = red.lift(z)
    iterates = tuple(lay.unpack(xk) for xk in xs)
    # stationary: the last step met the step rule (converged, or stuck at a residual it cannot reduce)
    info["stationary"] = bool(history) and status in ("converged", "stationary", "max_iter", "time_limit") and \
        history[-1].step <= stol
    if status == "converged":
        lsq = float(red.info.get("equality_residual", 0.0))
        if groups:
            message = f"bilinear residual {history[-1].residual:.3e} ≤ tol = {tol:g} after {len(history)} iterations"
        elif lsq > INCONSISTENT_TOL:
            message = ("no bilinear term left after presolve: solved in one step, the linear equalities in the "
                       f"least-squares sense (relative residual {lsq:.3e}; noisy data)")
        else:
            message = "solved exactly: no bilinear term left after presolve"
        if msg:
            message += f" (last sub-problem: {msg})"
    elif status == "time_limit":
        inside = f" (iteration {len(history) + (not cut_kept)} cut short: {message})" if cut else ""
        if history:
            message = (f"time limit of {time_limit:g} s reached after {len(history)} iterations{inside}; bilinear "
                       f"residual {history[-1].residual:.3e}, last step {history[-1].step:.3e}")
        else:
            message = f"time limit of {time_limit:g} s reached in the first iteration{inside}; the start is kept"
    elif status == "max_iter" and not groups:
        message = f"the convex problem left after presolve was not solved to tolerance: {msg}"
    elif status == "stationary":
        last = history[-1]
        message = (f"stationary after {len(history)} iterations: {stationary} steps in a row ≤ {stol:.3e} (last "
                   f"{last.step:.3e}) without lowering the bilinear residual {last.residual:.3e} > tol = {tol:g} by "
                   f"{_STALL_DECREASE:.0%}: the equalities cannot all hold here (noisy or inconsistent data, or a "
                   "local minimum of the residual)")
    elif status == "stopped":
        message = (f"stopped by the callback after {len(history)} iterations; bilinear residual "
                   f"{history[-1].residual:.3e}")
    elif status == "max_iter":
        last = history[-1]
        if last.residual > tol and last.step <= stol:
            why = (f"the iterate is stationary (last step {last.step:.3e} ≤ {stol:.3e}) but the bilinear residual "
                   f"{last.residual:.3e} > tol = {tol:g}: the equalities cannot all hold here (inconsistent or "
                   "noisy data, or a local minimum of the residual)")
        elif last.residual <= tol:
            why = (f"the bilinear residual {last.residual:.3e} ≤ tol = {tol:g} but the last step {last.step:.3e} "
                   f"> {stol:.3e}")
        else:
            why = f"bilinear residual {last.residual:.3e} > tol = {tol:g}, last step {last.step:.3e} > {stol:.3e}"
        message = f"maximum number of iterations ({max_iter}) reached; {why}"
    return SCRSolution(lay.unpack(x_final), iterates, tuple(history), status, status == "converged", message,
                       len(history), time.perf_counter() - t_start, backend, x_final, info)
