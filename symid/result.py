"""Result types shared by every estimation method, so methods compare like for like."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["IdentificationResult", "StartOutcome"]


def _best_index(starts: tuple[StartOutcome, ...] | list[StartOutcome]) -> int:
    """Index of the lowest data misfit (non-finite costs rank last; the first on ties)."""
    return int(np.argmin([s.cost if np.isfinite(s.cost) else np.inf for s in starts]))


@dataclass(frozen=True)
class StartOutcome:
    """What one start of one method produced.

    Attributes
    ----------
    start : numpy.ndarray
        The initial parameter vector (in ``parameter_names`` order).
    theta : numpy.ndarray
        The estimate.
    cost : float
        Relative data misfit of the estimate (see :func:`symid.misfit.relative_misfit`).
    converged : bool
        Whether the solver reported convergence.
    iterations : int
        Solver iterations.
    wall_time : float
        Seconds spent on this start.
    message : str
        The solver's final word.
    history : tuple of dict
        Per-iteration records, when the method keeps them (SCR does).
    """

    start: np.ndarray
    theta: np.ndarray
    cost: float
    converged: bool
    iterations: int
    wall_time: float
    message: str = ""
    history: tuple[dict[str, Any], ...] = field(default=(), repr=False)

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python form (lists and floats), suitable for JSON."""
        return {"start": np.asarray(self.start).tolist(), "theta": np.asarray(self.theta).tolist(),
                "cost": float(self.cost), "converged": bool(self.converged), "iterations": int(self.iterations),
                "wall_time": float(self.wall_time), "message": self.message}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> StartOutcome:
        """Rebuild an outcome written by :meth:`to_dict` (the history is not kept there).

        A cost written as ``None`` (JSON has no NaN or infinity) reads back as ``inf``.
        """
        cost = d.get("cost")
        return cls(start=np.asarray(d["start"], dtype=float), theta=np.asarray(d["theta"], dtype=float),
                   cost=float("inf") if cost is None else float(cost), converged=bool(d["converged"]),
                   iterations=int(d["iterations"]), wall_time=float(d["wall_time"]),
                   message=str(d.get("message", "")))


@dataclass(frozen=True)
class IdentificationResult:
    """The outcome of :func:`symid.identify`: the best start, and every start's outcome.

    Attributes
    ----------
    method : str
        ``"scr"``, ``"ipopt"``, ``"ls"``, ...
    parameter_names : tuple of str
        The order of θ.
    theta : dict of str to float
        Best estimate (lowest misfit over the starts).
    theta_vector : numpy.ndarray
        The same as a vector.
    cost : float
        Relative data misfit of ``theta``.
    success : bool
        Whether the solver converged on the best start.
    iterations : int
        Iterations of the best start.
    wall_time : float
        Total seconds over all starts.
    message : str
        The solver's final word on the best start.
    starts : tuple of StartOutcome
        Every start's outcome, in the order they ran.
    polished : IdentificationResult or None
        With ``polish=True``: SCR followed by a local refinement, reported separately.
    options : dict
        The options the method ran with.
    """

    method: str
    parameter_names: tuple[str, ...]
    theta: dict[str, float]
    theta_vector: np.ndarray
    cost: float
    success: bool
    iterations: int
    wall_time: float
    message: str
    starts: tuple[StartOutcome, ...]
    polished: IdentificationResult | None = None
    options: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def from_starts(cls, method: str, parameter_names: tuple[str, ...], starts: list[StartOutcome],
                    options: dict[str, Any] | None = None,
                    polished: IdentificationResult | None = None) -> IdentificationResult:
        """Pick the best start by data misfit (non-finite costs rank last)."""
        if not starts:
            raise ValueError("no start outcome to report")
        best = starts[_best_index(starts)]
        return cls(method=method, parameter_names=tuple(parameter_names),
                   theta=dict(zip(parameter_names, np.asarray(best.theta, dtype=float).tolist(), strict=True)),
                   theta_vector=np.asarray(best.theta, dtype=float), cost=float(best.cost),
                   success=bool(best.converged), iterations=int(best.iterations),
                   wall_time=float(sum(s.wall_time for s in starts)), message=best.message,
                   starts=tuple(starts), polished=polished, options=dict(options or {}))

    @property
    def best_start(self) -> StartOutcome:
        """The start whose outcome is reported (lowest data misfit)."""
        return self.starts[_best_index(self.starts)]

    @property
    def n_starts(self) -> int:
        """Number of starts run."""
        return len(self.starts)

    def summary(self, truth: dict[str, float] | None = None) -> str:
        """A readable table of the estimate (against ``truth`` when given)."""
        lines = [f"method: {self.method}   starts: {self.n_starts}   "
                 f"converged: {sum(s.converged for s in self.starts)}/{self.n_starts}",
                 f"best: cost {self.cost:.3e}   success {self.success}   iterations {self.iterations}   "
                 f"total time {self.wall_time:.3f} s",
                 f"message: {self.message}"]
        head = f"{'parameter':>12s} {'estimate':>14s}"
        if truth is not None:
            head += f" {'truth':>14s} {'rel. error':>11s}"
        lines.append(head)
        for name in self.parameter_names:
            row = f"{name:>12s} {self.theta[name]:>14.6g}"
            if truth is not None and name in truth:
                t = float(truth[name])
                err = abs(self.theta[name] - t) / (abs(t) if t != 0 else 1.0)
                row += f" {t:>14.6g} {err:>11.2e}"
            lines.append(row)
        if self.polished is not None:
            lines.append("")
            lines.append("after polish:")
            lines.append(self.polished.summary(truth))
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.summary()

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python form, suitable for JSON."""
        return {"method": self.method, "parameter_names": list(self.parameter_names), "theta": dict(self.theta),
                "cost": float(self.cost), "success": bool(self.success), "iterations": int(self.iterations),
                "wall_time": float(self.wall_time), "message": self.message,
                "starts": [s.to_dict() for s in self.starts],
                "polished": None if self.polished is None else self.polished.to_dict(),
                "options": {k: (v if isinstance(v, (int, float, str, bool, type(None))) else repr(v))
                            for k, v in self.options.items()}}
