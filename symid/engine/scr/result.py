"""Result of an SCR run."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["Iteration", "SCRSolution", "ScrProgress", "print_progress"]


@dataclass(frozen=True)
class Iteration:
    """One SCR iteration (one convex sub-problem solved, then Q, R updated).

    Attributes
    ----------
    objective : float
        f(x) at the new iterate.
    relaxation : float
        Optimal value of the sub-problem: f(x) + Σ w_t ||M_t(x)||_* (minus the linear
        term of the truncated nuclear norm), on the normalised terms.
    residuals : tuple of float
        ||A_t(x) P_t B_t(x) − C_t(x)||_F of every user term (unscaled), thesis Fig. 3-2.
    residual : float
        Largest bilinear residual of the normalised, presolved terms: the stopping measure.
    step : float
        ||x_k − x_{k−1}||_∞.
    time : float
        Wall time of the iteration in seconds.
    timing : dict
        Where the wall time went (back-end specific: build, factor, solve, svd, projection,
        bookkeeping), ADMM facts (inner_iterations, residuals, rho) and the process CPU
        time of the iteration (``cpu``; less disturbed than wall time by other jobs).
    """

    objective: float
    relaxation: float
    residuals: tuple[float, ...]
    residual: float
    step: float
    time: float
    timing: dict = field(default_factory=dict, compare=False)

    def to_dict(self) -> dict[str, Any]:
        return {"objective": self.objective, "relaxation": self.relaxation, "residuals": list(self.residuals),
                "residual": self.residual, "step": self.step, "time": self.time, "timing": dict(self.timing)}


@dataclass(frozen=True)
class ScrProgress:
    """One SCR iteration of an estimator's start, as its ``callback`` receives it.

    The similarity methods that are not SCR but iterate on the same equations (ALS and
    GB sweeps, the reweighting rounds of ``ls``; :mod:`symid.fit.similarity`) report
    their iterations in this record too, each with its own ``residual`` (their docstrings
    say which).

    Attributes
    ----------
    iteration : int
        1, 2, …
    residual : float
        Largest normalised bilinear residual after the iteration (SCR's stopping measure).
    misfit : float
        The estimator's data misfit at the iterate's θ (its ``cost``; ``inf`` where the
        model cannot be evaluated). On the N4SID route of I/O records, the misfit to the
        estimated black box (:mod:`symid.fit.timeseries.blackbox`).
    elapsed : float
        Seconds since the start began.
    theta : numpy.ndarray
        The parameter iterate.
    """

    iteration: int
    residual: float
    misfit: float
    elapsed: float
    theta: np.ndarray = field(repr=False)


def print_progress(info: ScrProgress, label: str = "scr") -> None:
    """One line per SCR iteration (iteration, residual, misfit, elapsed seconds): what ``verbose=True`` prints.

    ``label`` names the method at the start of the line (``"als"``, ``"gb"``, … for the
    similarity methods that report in this record).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.engine.scr.result import ScrProgress, print_progress
    >>> print_progress(ScrProgress(12, 3.1e-4, 2.5e-6, 1.25, np.zeros(3)))
    scr    iteration    12  residual 3.100e-04  misfit 2.500000e-06       1.25 s
    """
    print(f"{label:<6} iteration {info.iteration:5d}  residual {info.residual:.3e}  misfit {info.misfit:.6e}  "
          f"{info.elapsed:9.2f} s", flush=True)


def _jsonable(v: Any) -> Any:
    if isinstance(v, np.ndarray):
        if np.iscomplexobj(v):
            return {"real": v.real.tolist(), "imag": v.imag.tolist()}
        return v.tolist()
    if isinstance(v, complex):
        return {"real": v.real, "imag": v.imag}
    return v


@dataclass(frozen=True)
class SCRSolution:
    """Outcome of :func:`symid.engine.scr.solve`, in the spirit of scipy's ``OptimizeResult``.

    Attributes
    ----------
    x : dict
        Final iterate by variable name (float, complex or array).
    iterates : tuple of dict
        One dict per SCR iteration, the first being the first update.
    history : tuple of Iteration
        Per-iteration record: objective, relaxation value, residuals, time.
    status : str
        ``"converged"``, ``"max_iter"``, ``"time_limit"``, ``"stopped"`` (by the callback),
        ``"solver_error"`` or ``"infeasible"``.
    success : bool
        ``status == "converged"``.
    message : str
        Human-readable outcome.
    iterations : int
        Number of SCR iterations done.
    wall_time : float
        Seconds, presolve and compilation included.
    backend : str
        ``"admm"`` or ``"cvxpy"``.
    info : dict
        Presolve and back-end facts (fixed variables, equalities, compile time, ...).
    """

    x: dict[str, Any]
    iterates: tuple[dict[str, Any], ...]
    history: tuple[Iteration, ...]
    status: str
    success: bool
    message: str
    iterations: int
    wall_time: float
    backend: str
    x_vector: np.ndarray = field(repr=False, compare=False, default_factory=lambda: np.zeros(0))
    info: dict = field(default_factory=dict, compare=False)

    @property
    def residual(self) -> float:
        """Final stopping residual (inf if no iteration was done)."""
        return self.history[-1].residual if self.history else float("inf")

    def summary(self) -> str:
        """A readable table of the run."""
        lines = [
            "SCR solution",
            "=" * 60,
            f"status      : {self.status} ({'success' if self.success else 'failure'})",
            f"message     : {self.message}",
            f"backend     : {self.backend}",
            f"iterations  : {self.iterations}",
            f"wall time   : {self.wall_time:.4g} s",
        ]
        if self.history:
            h = self.history[-1]
            lines += [f"objective   : {h.objective:.6g}", f"residual    : {h.residual:.3e}",
                      f"time/iter   : {np.mean([i.time for i in self.history]) * 1e3:.3g} ms"]
        lines += ["-" * 60, f"{'variable':<16}value"]
        for k, v in self.x.items():
            s = np.array2string(np.asarray(v), precision=6) if isinstance(v, np.ndarray) else f"{v:.8g}"
            lines.append(f"{k:<16}{s}")
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python dict (JSON-serialisable) of the result."""
        return {
            "x": {k: _jsonable(v) for k, v in self.x.items()},
            "iterates": [{k: _jsonable(v) for k, v in it.items()} for it in self.iterates],
            "history": [h.to_dict() for h in self.history],
            "status": self.status, "success": self.success, "message": self.message,
            "iterations": self.iterations, "wall_time": self.wall_time, "backend": self.backend,
            "info": {k: _jsonable(v) for k, v in self.info.items()},
        }

    def __str__(self) -> str:
        return self.summary()
