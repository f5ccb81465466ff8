"""Covariance, standard errors and confidence intervals of θ from the Fisher information at the estimate.

For a least-squares fit with residuals r = y − ŷ(θ) of independent Gaussian noise of
variance σⱼ² in output channel j, the Fisher information is

    F = Σⱼ Jⱼᵀ Jⱼ / σⱼ²,          Jⱼ = ∂ŷⱼ/∂θ at the estimate

(the Gauss–Newton matrix), and cov(θ̂) ≈ F⁻¹ (Ljung, *System Identification*, 2nd ed.,
§9.2, (9.17)–(9.18); Bates & Watts, *Nonlinear Regression Analysis*, 1988, §2.3). σⱼ² is
estimated from the residuals, σ̂ⱼ² = ‖rⱼ‖² / (Nⱼ − k Nⱼ/N) with k unknowns shared out
over the channels in proportion to their samples. Nuisance unknowns (estimated initial
states) are in F and marginalised: the θ block of F⁻¹ is reported. The 95 % intervals are
θ̂ ± t₀.₉₇₅(N − k) · SE.

A Fisher information that is near-singular means the data hardly determine some
combination of the parameters — practically non-identifiable even when structurally
identifiable: the flag ``near_singular`` is set when the smallest eigenvalue of the
correlation-scaled F (unit diagonal) is below 1e-8 of its largest; the weakest
direction is reported.

An estimator offers this by inheriting :class:`FisherInformation` (declared, never
probed for); :func:`symid.identify` then fills ``result.uncertainty``.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["NEAR_SINGULAR", "FisherInformation", "Uncertainty", "fisher_uncertainty"]

NEAR_SINGULAR = 1e-8
"""Smallest/largest eigenvalue of the correlation-scaled Fisher information below which it is near-singular."""


@dataclass(frozen=True)
class Uncertainty:
    """Covariance of θ̂ from the Fisher information, with standard errors and 95 % confidence intervals.

    Attributes
    ----------
    parameter_names : tuple of str
    covariance : numpy.ndarray
        (l, l) covariance of θ̂ (``inf`` on the diagonal where F is singular).
    standard_errors : numpy.ndarray
        Square roots of its diagonal.
    intervals : numpy.ndarray
        (l, 2) lower and upper ends of the 95 % confidence intervals.
    noise_std : numpy.ndarray
        Estimated noise standard deviation per output channel (data units).
    dof : int
        Degrees of freedom N − k of the residual.
    condition : float
        Largest over smallest eigenvalue of the correlation-scaled Fisher information.
    near_singular : bool
        ``condition`` above 1 / NEAR_SINGULAR: some parameter combination is practically
        non-identifiable from these data.
    weakest : dict of str to float
        The (unit) direction of θ the data determine least, by parameter name.
    """

    parameter_names: tuple[str, ...]
    covariance: np.ndarray
    standard_errors: np.ndarray
    intervals: np.ndarray
    noise_std: np.ndarray
    dof: int
    condition: float
    near_singular: bool
    weakest: dict[str, float]

    def summary(self) -> str:
        """One line per fact, for :meth:`IdentificationResult.summary`."""
        noise = ", ".join(f"{s:.3g}" for s in self.noise_std)
        text = (f"uncertainty: Fisher information (Gauss-Newton), noise std {noise} from the residuals, "
                f"{self.dof} dof; condition {self.condition:.2e}")
        if self.near_singular:
            top = sorted(self.weakest.items(), key=lambda kv: -abs(kv[1]))[:3]
            text += ("\n  NEAR-SINGULAR Fisher information: the data hardly determine the direction "
                     + " ".join(f"{v:+.2f}·{k}" for k, v in top) + " (practically non-identifiable)")
        return text

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python form, suitable for JSON."""
        return {"parameter_names": list(self.parameter_names), "covariance": self.covariance.tolist(),
                "standard_errors": self.standard_errors.tolist(), "intervals": self.intervals.tolist(),
                "noise_std": self.noise_std.tolist(), "dof": self.dof, "condition": self.condition,
                "near_singular": self.near_singular, "weakest": dict(self.weakest)}


class FisherInformation(abc.ABC):
    """What an estimator supplies for :func:`fisher_uncertainty`: residuals, their Jacobian and channels."""

    @abc.abstractmethod
    def jacobian(self, theta: Any) -> tuple[np.ndarray, np.ndarray]:
        """Residual vector r (N,) and its Jacobian (N, k), θ first then any nuisance unknowns."""

    @abc.abstractmethod
    def residual_channels(self) -> np.ndarray:
        """Output channel (0 … p−1) of every entry of r."""

    def uncertainty(self, theta: Any, parameter_names: tuple[str, ...]) -> Uncertainty:
        """The :class:`Uncertainty` of the estimate ``theta``."""
        r, J = self.jacobian(theta)
        return fisher_uncertainty(np.asarray(theta, dtype=float), parameter_names, r, J, self.residual_channels())


def fisher_uncertainty(theta: np.ndarray, parameter_names: tuple[str, ...], r: np.ndarray, J: np.ndarray,
                       channels: np.ndarray) -> Uncertainty:
    """Covariance from F = Σⱼ Jⱼᵀ Jⱼ / σ̂ⱼ² (module text); the first ``len(theta)`` columns of J are θ.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.uncertainty import fisher_uncertainty
    >>> t = np.linspace(0, 1, 50)
    >>> J = -np.column_stack([np.ones(50), t])            # ŷ = a + b t
    >>> r = 0.1 * np.sin(37 * t)                           # some residual
    >>> u = fisher_uncertainty(np.array([1.0, 2.0]), ("a", "b"), r, J, np.zeros(50, int))
    >>> bool(np.allclose(u.covariance, np.linalg.inv(J.T @ J) * (r @ r) / 48))
    True
    """
    from scipy.stats import t as student_t

    l = theta.size
    N, k = J.shape
    dof = max(N - k, 1)
    channels = np.asarray(channels, dtype=int)
    p = int(channels.max()) + 1
    var = np.empty(p)
    F = np.zeros((k, k))
    for j in range(p):
        rows = channels == j
        nj = int(rows.sum())
        var[j] = float(r[rows] @ r[rows]) / max(nj - k * nj / N, 1e-300)
        if var[j] > 0:
            F += J[rows].T @ J[rows] / var[j]
    d = np.sqrt(np.clip(np.diag(F), 0, None))
    names = tuple(parameter_names)
    if np.all(var == 0) or not np.all(np.isfinite(F)):
        inf = np.full((l, l), np.inf)
        return Uncertainty(names, inf, np.full(l, np.inf), np.column_stack([theta - np.inf, theta + np.inf]),
                           np.sqrt(var), dof, float("inf"), True, {})
    safe = np.where(d > 0, d, 1.0)
    Fs = F / np.outer(safe, safe)
    ev, vec = np.linalg.eigh(Fs)
    cond = float(ev[-1] / ev[0]) if ev[0] > 0 else float("inf")
    near = not (ev[0] > NEAR_SINGULAR * ev[-1]) or bool(np.any(d == 0))
    w = vec[:, 0][:l] / safe[:l]
    w = w / (np.linalg.norm(w) or 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv_s = np.where(ev > ev[-1] * 1e-15, 1.0 / ev, np.inf)
        cov_all = (vec * inv_s) @ vec.T / np.outer(safe, safe) if np.all(np.isfinite(inv_s)) else None
    if cov_all is None:
        cov = np.full((l, l), np.inf)
    else:
        cov = cov_all[:l, :l]
    se = np.sqrt(np.clip(np.diag(cov), 0, None))
    q = float(student_t.ppf(0.975, dof))
    ci = np.column_stack([theta - q * se, theta + q * se])
    return Uncertainty(names, cov, se, ci, np.sqrt(var), dof, cond, near,
                       dict(zip(names, np.round(w, 6).tolist(), strict=True)))
