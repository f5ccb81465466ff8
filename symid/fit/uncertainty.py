"""Covariance, standard errors and confidence intervals of θ from the Fisher information at the estimate.

Every data kind's misfit is a weighted least-squares criterion ‖r(θ)‖², r the data minus
the model, each entry weighed as the method's misfit weighs it. For independent Gaussian
noise with Var(rᵢ) = vᵢ, the Fisher information at the estimate is

    F = Jᵀ V⁻¹ J,          J = ∂r/∂θ at θ̂,  V = diag(vᵢ)

(the Gauss–Newton matrix; Ljung, *System Identification*, 2nd ed., §9.2, (9.17)–(9.18);
Pintelon & Schoukens, *System Identification: A Frequency Domain Approach*, 2nd ed.,
§9.11 for frequency-domain data). The covariance of the estimate that minimises ‖r‖² is

    cov(θ̂) ≈ (JᵀJ)⁻¹ Jᵀ V J (JᵀJ)⁻¹,

which is F⁻¹ when the misfit weighs every entry by its noise (V ∝ I); otherwise the
"sandwich" form is the right one (White, *Econometrica* 48, 1980). The noise is

- **estimated from the residuals** (default): Vᵢ = σ_c² sᵢ² with a known shape sᵢ per
  entry and one level σ_c per channel c (an output), σ̂_c from the part of the
  standardised residual that the estimation error cannot reach (:func:`_noise_levels`;
  RSS / (N − k) for a misfit that weighs every entry by its noise). The shape is the data
  kind's noise model: constant per output for time series (σ in data units),
  **relative** for frequency responses and spectra (sᵢ ∝ the model's |H| or |Φyy|
  there, σ a relative level, as ``si.simulate_frf(..., noise=ε)`` adds); intervals are
  θ̂ ± t₀.₉₇₅(N − k)·SE;
- **given** (``si.identify(..., noise_std=...)``): the standard deviation of every
  measured value in data units (a complex value's E|e|² = std²), intervals
  θ̂ ± 1.96·SE, and ``residual_ratio`` = rms of the residual in units of the given noise
  (≈ 1 when the given noise is right).

Nuisance unknowns (estimated initial states) are in J and marginalised: the θ block of
the covariance is reported (one the residual does not depend on at all, an initial
position of a model measured in velocity, is left out). The covariance is that of the least-squares estimate of the
method's misfit, evaluated at θ̂: exact to first order for the methods that minimise that
misfit (``ipopt``, ``oe``); for the others (``scr``, ``ls``, ``als``, ``gb``, an
equation-error objective) it holds as far as their estimate agrees with that minimiser,
and ``note`` says so (``polish=True`` reaches it). For every method, one Gauss–Newton
step from θ̂ measures how far the least-squares estimate lies (``shift``, in standard
errors): beyond ``SHIFT_LIMIT`` the intervals centred on θ̂ are withheld (NaN) with the
reason. A method that minimises the misfit can stop short of the minimum too: the
frequency-response ``auto`` accepts a fit within the noise, and on a new user's DC motor
(1 % noise) it ended with the friction rate b/J at 5e-7 /s where the least-squares
estimate, which IPOPT reached from the same start, has 4.8 /s: 3.4 standard errors away
(one Gauss–Newton step puts it at 0.97, enough to withhold the intervals).

A Fisher information that is near-singular means the data hardly determine some
combination of the parameters — practically non-identifiable even when structurally
identifiable: the flag ``near_singular`` is set when the smallest eigenvalue of θ's
information with the nuisance unknowns (initial states, offsets) profiled out,
F_θθ − F_θn F_nn⁺ F_nθ, scaled by θ's own diagonal of F, is below 1e-8 of its largest;
the weakest direction is reported. (Two nearly collinear nuisance columns alone no longer
set it; a parameter that trades off against a nuisance unknown still does:
``tests/test_uncertainty.py``.) Where F is singular (to 1e-15), a parameter whose unit vector lies
in the row space of J is still determined to first order and gets the standard error of
the pseudo-inverse; one with a part in the null space gets ``inf`` (before, every
parameter got ``inf``, the well-determined ones too).

An estimator offers this by inheriting :class:`FisherInformation` (declared, never
probed for); :func:`symid.identify` then fills ``result.uncertainty``.
"""

from __future__ import annotations

import abc
import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from symid.errors import DataError

__all__ = ["BOUND_PULL_LIMIT", "BOUND_REJECT", "NEAR_SINGULAR", "POSITIVITY_ZERO", "ROUNDING_SHIFT", "SHIFT_LIMIT",
           "FisherInformation", "Uncertainty", "broadcast_noise", "fisher_uncertainty"]

NEAR_SINGULAR = 1e-8
"""Smallest/largest eigenvalue of the correlation-scaled Fisher information below which it is near-singular."""

_NULL_PART = 1e-6
"""A parameter whose unit vector (scaled) has more than this part in the null space of J is not determined."""

SHIFT_LIMIT = 0.5
"""Largest distance (in standard errors) from θ̂ to the least-squares estimate at which intervals centred on θ̂
are reported: shifted by 0.5 SE, a 95 % interval still holds the truth 93 % of the time (1 SE: 83 %)."""

ROUNDING_SHIFT = 1e-9
"""A Gauss–Newton step from θ̂ no larger than this relative to every parameter is rounding: the intervals are kept
however many standard errors it spans (a noise-free fit's are at rounding too: exact data gave NaN intervals)."""

BOUND_PULL_LIMIT = 3.0
"""Largest distance, in its own standard errors, by which a bound may hold a parameter back from the least-squares
estimate for the other parameters' intervals to be given (:func:`_with_shift`): beyond it the data reject the bound
(with the truth on the bound, the least-squares estimate lies beyond it by less than this in 99.9 % of records)."""

POSITIVITY_ZERO = 1e-3
"""A parameter declared positive within this fraction of its own standard error of 0 sits on the bound 0 that
keeps it positive, for the intervals (:func:`_with_shift`): the data cannot tell it from 0."""

BOUND_REJECT = 1e-6
"""The probability, with the model right and the truth within its bounds, that a fit on its bounds is said not to fit
(:meth:`Uncertainty.bounds_rejected`)."""

_Z975 = 1.959963984540054  # the 0.975 quantile of the standard normal


@dataclass(frozen=True)
class Uncertainty:
    """Covariance of θ̂ from the Fisher information, with standard errors and 95 % confidence intervals.

    Attributes
    ----------
    parameter_names : tuple of str
    covariance : numpy.ndarray
        (l, l) covariance of θ̂ (``inf`` where the Fisher information is singular).
    standard_errors : numpy.ndarray
        Square roots of its diagonal.
    intervals : numpy.ndarray
        (l, 2) lower and upper ends of the 95 % confidence intervals.
    noise_std : numpy.ndarray
        Noise level per channel (output): estimated from the residuals, in ``noise_units``;
        with given noise, the rms of the given standard deviations (data units).
    noise_units : str
        ``"data units"`` or ``"relative"`` (a fraction of the model's value at each point).
    noise_source : str
        ``"residuals"`` or ``"given"``.
    dof : int or None
        Degrees of freedom N − k of the residual (``None`` with given noise: normal quantile).
    condition : float
        Largest over smallest eigenvalue of the correlation-scaled Fisher information.
    near_singular : bool
        ``condition`` above 1 / NEAR_SINGULAR: some parameter combination is practically
        non-identifiable from these data.
    weakest : dict of str to float
        The (unit) direction of θ the data determine least, by parameter name.
    weakest_relative : dict of str to float or None
        The same direction in relative changes δθᵢ/θ̂ᵢ (a unit vector; 0 for a parameter at 0): what
        ``summary()`` shows, since in absolute units parameters of small magnitude (an inertia of 2e-4 beside a
        stiffness of 3) read as 0 in it whatever their part (a new user's motor: a common scaling of all seven
        parameters was shown as "ks and Kt").
    residual_ratio : float or None
        With given noise: rms of the residual in units of the given noise (≈ 1 when it is right).
    note : str
        What the covariance describes when the method does not minimise this misfit, and
        why the intervals are withheld when they are.
    shift : float or None
        The distance from θ̂ to the least-squares estimate of the misfit (one Gauss–Newton
        step), in standard errors, √(δᵀ cov⁻¹ δ): for every method, since one that
        minimises the misfit can stop short of its minimum too (a fit accepted within the
        noise, a parameter held at its bound). Above ``SHIFT_LIMIT`` the intervals
        (centred on θ̂) would not hold and are NaN, and ``note`` says why. ``None`` for a
        method whose sensitivity to the noise is known (``estimate_sensitivity``).
    beyond_bounds : dict of str to float or None
        The parameters on a bound that the data pull beyond it by more than ``BOUND_PULL_LIMIT``
        of their own standard errors (or with the others then not at their least-squares
        estimate), with how far the Gauss–Newton step takes each, in its standard errors
        (signed); None when there is none. :meth:`bounds_rejected` says whether the data
        reject the bounds.
    """

    parameter_names: tuple[str, ...]
    covariance: np.ndarray
    standard_errors: np.ndarray
    intervals: np.ndarray
    noise_std: np.ndarray
    dof: int | None
    condition: float
    near_singular: bool
    weakest: dict[str, float]
    noise_units: str = "data units"
    noise_source: str = "residuals"
    residual_ratio: float | None = None
    note: str = ""
    shift: float | None = None
    weakest_relative: dict[str, float] | None = None
    beyond_bounds: dict[str, float] | None = None

    def bounds_rejected(self) -> str | None:
        """Why the data reject the model within its bounds at θ̂, or None.

        ``shift``² is then the score statistic of the active bounds (the squared length of the residual's
        projection on the sensitivities, in noise units: how much the misfit would fall, to first order, just
        beyond them); with the model right and the truth within the bounds it exceeds ``χ²(l)`` at 1 − 10⁻⁶
        (:data:`BOUND_REJECT`, l parameters) once in a million records. Beyond that the estimate does not fit the
        data: the model within its bounds cannot explain them (a frequency response in Hz read as rad/s pulled a
        resistance 12 standard errors below 0), or the solver stopped on a bound short of the fit.

        Examples
        --------
        >>> import numpy as np
        >>> from symid.fit.uncertainty import Uncertainty
        >>> unc = Uncertainty(("R", "L"), np.eye(2), np.ones(2), np.full((2, 2), np.nan), np.ones(1), 100, 1.0,
        ...                   False, {}, shift=12.4, beyond_bounds={"R": -12.0})
        >>> unc.bounds_rejected().startswith("the data pull R 12 standard errors beyond its bound")
        True
        >>> Uncertainty(("R", "L"), np.eye(2), np.ones(2), np.zeros((2, 2)), np.ones(1), 100, 1.0, False, {},
        ...             shift=4.0, beyond_bounds={"R": -4.0}).bounds_rejected() is None
        True
        """
        if not self.beyond_bounds or self.shift is None or not np.isfinite(self.shift):
            return None
        from scipy.stats import chi2

        limit = float(np.sqrt(chi2.isf(BOUND_REJECT, len(self.parameter_names))))
        if self.shift <= limit:
            return None
        pulls = ", ".join(f"{name} {abs(z):.3g} standard errors" for name, z in self.beyond_bounds.items())
        which = "its bound" if len(self.beyond_bounds) == 1 else "their bounds"
        return (f"the data pull {pulls} beyond {which} (the least-squares estimate lies {self.shift:.3g} standard "
                f"errors away, more than noise explains: {limit:.3g} at probability {BOUND_REJECT:g}), so within "
                f"the bounds the model does not fit these data: check the model and the data's units (a frequency "
                f"in Hz read as rad/s, a time in ms read as s), or widen the bounds if the physics allows")

    @property
    def correlation(self) -> np.ndarray:
        """Correlation matrix of θ̂ (NaN where a standard error is 0 or infinite)."""
        se = self.standard_errors
        with np.errstate(divide="ignore", invalid="ignore"):
            return self.covariance / np.outer(se, se)

    def interval(self, name: str) -> tuple[float, float]:
        """The 95 % confidence interval (low, high) of the parameter called ``name`` (NaN where the intervals are
        withheld: ``note`` says why).

        Raises
        ------
        DataError
            When ``name`` is no parameter of the estimate (the message lists them).

        Examples
        --------
        >>> import numpy as np
        >>> import symid as si
        >>> m, c, k = si.parameters("m c k", positive=True)
        >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
        >>> frf = si.simulate_frf(model, [2.0, 0.5, 3.0], np.linspace(0.5, 2.0, 40), noise=0.01, seed=0)
        >>> unc = si.identify(model, frf, x0=[2.0, 0.5, 3.0], identifiability_check=False).uncertainty
        >>> low, high = unc.interval("k")
        >>> bool(low < 3.0 < high)
        True
        """
        if name not in self.parameter_names:
            raise DataError(f"{name!r} is not a parameter of this estimate; its parameters are "
                            f"{', '.join(self.parameter_names)}")
        low, high = self.intervals[self.parameter_names.index(name)]
        return float(low), float(high)

    def summary(self) -> str:
        """One line per fact, for :meth:`IdentificationResult.summary`."""
        if self.noise_source == "given":
            noise = (f"noise given per value (rms {', '.join(f'{s:.3g}' for s in self.noise_std)}), residual/noise "
                     f"rms {self.residual_ratio:.3g}")
        elif self.noise_units == "relative":
            noise = "relative noise " + ", ".join(f"{100 * s:.3g} %" for s in self.noise_std) + " from the residuals"
        elif self.noise_units == "data units":
            noise = "noise std " + ", ".join(f"{s:.3g}" for s in self.noise_std) + " from the residuals"
        else:
            noise = ("noise std " + ", ".join(f"{s:.3g}" for s in self.noise_std) + f" {self.noise_units} from the "
                     "residuals")
        dof = "normal quantile" if self.dof is None else f"{self.dof} dof"
        text = f"uncertainty: Fisher information at the estimate, {noise}, {dof}; condition {self.condition:.2e}"
        if self.note:
            text += f"\n  note: {self.note}"
            if self.shift is not None and self.shift <= SHIFT_LIMIT:
                text += f" (θ̂ lies {self.shift:.2g} standard errors from the least-squares estimate)"
        if self.near_singular:
            rel = self.weakest_relative is not None and any(self.weakest_relative.values())
            vec = self.weakest_relative if rel else self.weakest
            big = max((abs(v) for v in vec.values()), default=0.0)
            top = sorted(((k, v) for k, v in vec.items() if abs(v) >= 0.2 * big), key=lambda kv: -abs(kv[1]))
            shown = " ".join(f"{v:+.2f}·{'δ' + k + '/' + k if rel else k}" for k, v in top[:8])
            more = f" and {len(top) - 8} more" if len(top) > 8 else ""
            text += ("\n  NEAR-SINGULAR Fisher information: the data hardly determine the direction "
                     + shown + more + (" (relative changes)" if rel else "") + " (practically non-identifiable)")
        return text

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python form, suitable for JSON (non-finite entries as ``None``)."""
        return {"parameter_names": list(self.parameter_names), "covariance": _plain(self.covariance),
                "standard_errors": _plain(self.standard_errors), "intervals": _plain(self.intervals),
                "noise_std": _plain(self.noise_std), "noise_units": self.noise_units,
                "noise_source": self.noise_source, "dof": self.dof, "condition": _plain(self.condition),
                "near_singular": self.near_singular, "weakest": dict(self.weakest),
                "weakest_relative": None if self.weakest_relative is None else dict(self.weakest_relative),
                "residual_ratio": self.residual_ratio, "note": self.note,
                "shift": None if self.shift is None else float(self.shift)}


def _plain(a: Any) -> Any:
    """Lists of floats, ``None`` for non-finite entries (JSON has no infinity)."""
    arr = np.asarray(a, dtype=float)
    return np.where(np.isfinite(arr), arr, None).tolist()


class FisherInformation(abc.ABC):
    """What an estimator supplies for :func:`fisher_uncertainty`: residuals, their Jacobian and noise shape.

    ``noise_units`` says what the residual-estimated noise level measures (``"data units"``
    or ``"relative"``).
    """

    noise_units: ClassVar[str] = "data units"

    @abc.abstractmethod
    def jacobian(self, theta: Any) -> tuple[np.ndarray, np.ndarray]:
        """Residual vector r (N,) of the misfit (``cost ∝ ‖r‖²``) and its Jacobian (N, k), θ first, then
        any nuisance unknowns."""

    @abc.abstractmethod
    def residual_channels(self) -> np.ndarray:
        """Channel (0 … c−1, an output) of every entry of r."""

    @abc.abstractmethod
    def noise_shape(self, theta: Any) -> np.ndarray:
        """sᵢ ≥ 0 per entry of r with Var(rᵢ) = σ_c² sᵢ² under the data kind's noise model (0: no noise there)."""

    @abc.abstractmethod
    def given_noise(self, noise_std: Any) -> tuple[np.ndarray, np.ndarray]:
        """The standard deviation of every entry of r for a user's ``noise_std`` (data units, per measured
        value), and the given standard deviations themselves (flattened) for the report."""

    def uncertainty_note(self) -> str:
        """What the covariance describes for this method ('' when the method minimises the misfit)."""
        return ""

    def residual_correlation(self, theta: Any) -> Any:
        """The correlation (N, N) of the entries of r, dense or sparse, where they are not independent; ``None``
        (default): independent."""
        return None

    def estimate_sensitivity(self, theta: Any) -> np.ndarray | None:
        """For a method that does not minimise ‖r‖²: G (l, N) with dθ̂ = G e to first order for noise e on
        the entries of r; ``None`` (default) for a least-squares minimiser of ‖r‖²."""
        return None

    def uncertainty(self, theta: Any, parameter_names: tuple[str, ...], noise_std: Any = None) -> Uncertainty:
        """The :class:`Uncertainty` of the estimate ``theta`` (noise from the residuals, or ``noise_std``)."""
        theta = np.asarray(theta, dtype=float)
        r, J = self.jacobian(theta)
        channels = self.residual_channels()
        G = self.estimate_sensitivity(theta)
        note = self.uncertainty_note()
        correlation = self.residual_correlation(theta)
        if noise_std is None:
            unc = fisher_uncertainty(theta, parameter_names, r, J, channels, shape=self.noise_shape(theta),
                                     units=self.noise_units, sensitivity=G, note=note, correlation=correlation)
        else:
            std, given = self.given_noise(noise_std)
            unc = fisher_uncertainty(theta, parameter_names, r, J, channels, given_std=std, given_values=given,
                                     sensitivity=G, note=note, correlation=correlation)
        if G is not None:
            return unc
        lower, upper = getattr(self, "lower", None), getattr(self, "upper", None)
        bounds = None if lower is None or upper is None else (np.asarray(lower, float), np.asarray(upper, float))
        sides = self._bound_sides(theta)
        at_zero = self._at_positivity_bound(theta, unc)
        if at_zero.any():  # the 0 that keeps them positive holds them as a bound does
            sides = np.where(at_zero, -1, np.zeros(theta.size, int) if sides is None else sides)
            lo, hi = (np.full(theta.size, -np.inf), np.full(theta.size, np.inf)) if bounds is None else bounds
            bounds = (np.where(at_zero, 0.0, lo), hi)
        return _with_shift(unc, r, J, sides, bounds, at_zero)

    def _at_positivity_bound(self, theta: np.ndarray, unc: Uncertainty) -> np.ndarray:
        """The parameters declared positive that sit at 0 as far as the data can tell: within
        :data:`POSITIVITY_ZERO` of their own standard error (a new user's motor: the frictions ended at 1e-10
        where their standard errors are 1e-3, and the shift of that held zero withheld every interval)."""
        positive = np.asarray(getattr(getattr(self, "model", None), "positive", np.zeros(theta.size, bool)), bool)
        if positive.shape != theta.shape:
            return np.zeros(theta.size, bool)
        se = np.sqrt(np.abs(np.diag(np.asarray(unc.covariance, dtype=float))))
        return positive & np.isfinite(se) & (se > 0) & (np.abs(theta) <= POSITIVITY_ZERO * se)

    def _bound_sides(self, theta: np.ndarray) -> np.ndarray | None:
        """Per parameter: −1 on its lower bound, +1 on its upper, 0 inside (None for a method without bounds).
        The 0 that keeps a parameter declared positive positive does not count."""
        lower, upper = getattr(self, "lower", None), getattr(self, "upper", None)
        if lower is None or upper is None or np.shape(lower) != theta.shape:
            return None
        from symid.fit.bounded import bound_sides

        positive = np.asarray(getattr(getattr(self, "model", None), "positive", np.zeros(theta.size, bool)), bool)
        return bound_sides(theta, np.asarray(lower, dtype=float), np.asarray(upper, dtype=float), positive)



def _with_shift(unc: Uncertainty, r: np.ndarray, J: np.ndarray, sides: np.ndarray | None = None,
                bounds: tuple[np.ndarray, np.ndarray] | None = None, at_zero: np.ndarray | None = None
                ) -> Uncertainty:
    """Add the distance from θ̂ to the least-squares estimate (one Gauss–Newton step on ‖r + J δ‖²); beyond
    ``SHIFT_LIMIT`` standard errors the intervals become NaN and the note says why (that the step leaves the
    bounds where θ̂ sits on one, ``sides``: −1 on a lower bound, +1 on an upper, 0 inside). Where the step
    leaves bounds by less than ``BOUND_PULL_LIMIT`` of each such parameter's own standard error and θ̂ is the
    least-squares estimate with those parameters held on their bounds, only their intervals are NaN (one
    slightly active bound does not withhold every interval). Within ``SHIFT_LIMIT``, the interval of a
    parameter on a bound is cut at it (``bounds``: (lower, upper)), and the note says so. ``at_zero`` marks the
    lower bounds that are the 0 of a parameter declared positive (named so)."""
    import dataclasses

    def side(k: int) -> str:
        if at_zero is not None and at_zero[k]:
            return "at 0, the bound of a parameter declared positive"
        return "lower" if sides[k] < 0 else "upper"

    l = unc.covariance.shape[0]
    if not np.all(np.isfinite(unc.covariance)) or not np.all(np.isfinite(J)):
        return unc
    delta = -np.linalg.lstsq(J, r, rcond=None)[0][:l]
    try:
        shift = float(np.sqrt(max(float(delta @ np.linalg.solve(unc.covariance, delta)), 0.0)))
    except np.linalg.LinAlgError:
        return unc
    centre = np.mean(np.asarray(unc.intervals, dtype=float), axis=1)
    if shift > SHIFT_LIMIT and np.all(np.abs(delta) <= ROUNDING_SHIFT * np.maximum(np.abs(centre),
                                                                                  np.finfo(float).tiny)):
        # a fit to rounding: θ̂ is the least-squares estimate to rounding, many of its (rounding-sized) standard
        # errors away only because they are that small
        note = (f"{unc.note + '. ' if unc.note else ''}a fit to rounding: θ̂ is the least-squares estimate to "
                f"{ROUNDING_SHIFT:g} relatively ({shift:.3g} of its rounding-sized standard errors away), and the "
                f"intervals are as narrow as the data's rounding")
        return dataclasses.replace(unc, shift=shift, note=note)
    if shift <= SHIFT_LIMIT:
        on = [] if sides is None or bounds is None else [k for k in range(l) if sides[k]]
        if not on:
            return dataclasses.replace(unc, shift=shift)
        intervals = np.array(unc.intervals, dtype=float, copy=True)
        cut = []
        for k in on:
            lo, hi = intervals[k]
            intervals[k] = np.clip(intervals[k], bounds[0][k], bounds[1][k])
            if (lo, hi) != tuple(intervals[k]):
                cut.append(f"{unc.parameter_names[k]} ({side(k)}; the data alone "
                           f"would reach {lo if sides[k] < 0 else hi:.6g})")
        if not cut:
            return dataclasses.replace(unc, shift=shift)
        note = (f"{unc.note + '. ' if unc.note else ''}θ̂ sits on its bounds, where the data hardly pull it "
                f"({shift:.3g} standard errors from the least-squares estimate): the intervals of {', '.join(cut)} "
                f"are cut at the bound")
        return dataclasses.replace(unc, shift=shift, note=note, intervals=intervals)
    pushed = [] if sides is None else [k for k in range(l) if sides[k] and sides[k] * delta[k] > 0]
    se = np.sqrt(np.abs(np.diag(unc.covariance)))
    slight = bool(pushed) and all(abs(delta[k]) <= BOUND_PULL_LIMIT * se[k] for k in pushed)
    held = _held_shift(unc, r, J, pushed) if slight else None
    if held is not None and held <= SHIFT_LIMIT:
        # each bound holds its parameter back by less than BOUND_PULL_LIMIT of its own standard errors (the data do not
        # reject the bound), and with them held θ̂ is the least-squares estimate: the others' intervals hold
        names = ", ".join(f"{unc.parameter_names[k]} ({side(k)})" for k in pushed)
        intervals = np.array(unc.intervals, dtype=float, copy=True)
        intervals[pushed] = np.nan
        note = (f"{unc.note + '. ' if unc.note else ''}θ̂ sits on its bounds where the data pull it slightly "
                f"beyond them (within {BOUND_PULL_LIMIT:g} of its own standard errors): {names}, which get no interval "
                f"(NaN); with them held there θ̂ is the least-squares estimate "
                f"({held:.3g} standard errors away), and the other intervals are those of the free fit around it "
                f"(they allow the held parameters to move, so they are wider, not narrower, than with them fixed)")
        return dataclasses.replace(unc, shift=shift, note=note, intervals=intervals)
    if pushed:
        beyond = {unc.parameter_names[k]: float(delta[k] / se[k]) if se[k] > 0 else math.inf for k in pushed}
        unc = dataclasses.replace(unc, beyond_bounds=beyond)
        names = ", ".join(f"{unc.parameter_names[k]} ({side(k)})" for k in pushed)
        note = (f"{unc.note + '. ' if unc.note else ''}θ̂ sits on its bounds where the data pull it beyond them: "
                f"{names}; the least-squares estimate of these data lies {shift:.3g} standard errors away, outside "
                f"the bounds, so intervals around θ̂ would not hold and none are given (NaN); widen the bounds if "
                f"the physics allows, or check the model and the units")
    else:
        note = (f"{unc.note + '. ' if unc.note else ''}θ̂ lies {shift:.3g} standard errors from the least-squares "
                f"estimate of these data (more than {SHIFT_LIMIT}): intervals around θ̂ would not hold, so none are "
                f"given (NaN); polish=True refines θ̂ to that estimate where the method has a polisher")
    return dataclasses.replace(unc, shift=shift, note=note, intervals=np.full((l, 2), np.nan))


def _held_shift(unc: Uncertainty, r: np.ndarray, J: np.ndarray, held: list[int]) -> float | None:
    """The distance, in standard errors of the other parameters, from θ̂ to the least-squares estimate with
    the parameters ``held`` fixed at θ̂ (a Gauss–Newton step without their columns; nuisance unknowns stay
    free); None where it cannot be computed."""
    l = unc.covariance.shape[0]
    free = [k for k in range(l) if k not in held]
    if not free:
        return 0.0
    cols = free + list(range(l, J.shape[1]))
    try:
        delta = -np.linalg.lstsq(J[:, cols], r, rcond=None)[0][:len(free)]
        info = np.linalg.inv(unc.covariance)[np.ix_(free, free)]  # the Fisher information of the free ones
        value = float(delta @ info @ delta)
    except np.linalg.LinAlgError:
        return None
    return float(np.sqrt(max(value, 0.0))) if np.isfinite(value) else None


def broadcast_noise(noise_std: Any, shape: tuple[int, ...], what: str, *, name: str = "noise_std",
                    check: bool = True, error: type[Exception] = DataError) -> np.ndarray:
    """``noise_std`` as a float array of ``shape``: a number, or an array that broadcasts (its leading axes
    matching); every value finite and > 0 (``check``), else an ``error`` (:class:`~symid.errors.DataError`
    by default) naming ``what``; ``name`` is the option's name in the messages. Complex values are refused.

    Examples
    --------
    >>> from symid.fit.uncertainty import broadcast_noise
    >>> broadcast_noise([0.1, 0.2], (2, 1, 1), "H").ravel().tolist()
    [0.1, 0.2]
    """
    try:
        raw = np.asarray(noise_std)
    except (TypeError, ValueError):  # ragged
        raw = np.asarray([], dtype=object)
    if raw.dtype.kind == "c":
        raise error(f"{name} holds complex numbers; it is real and > 0 (data units)")
    try:
        if raw.dtype.kind not in "iuf":  # text, booleans, objects, ragged lists: no variance or standard deviation
            raise TypeError(name)
        arr = raw.astype(float)
    except (TypeError, ValueError):
        raise error(f"{name} must be a number or an array of numbers (data units); got "
                    f"{_short_repr(noise_std)}") from None
    if arr.ndim > len(shape):
        raise error(f"{name} has shape {arr.shape}; {what} has shape {shape}")
    arr = arr.reshape(arr.shape + (1,) * (len(shape) - arr.ndim))
    try:
        out = np.broadcast_to(arr, shape).astype(float)
    except ValueError:
        per_output = f", one per output (1, {shape[1]})" if len(shape) == 2 else ""
        raise error(f"{name} of shape {np.shape(noise_std)} does not fit {what} of shape {shape}: give one "
                    f"number, one per {'frequency' if 'H' in what or 'Phi' in what else 'sample'} "
                    f"({shape[0]},){per_output}, or the full shape") from None
    if check and (not np.all(np.isfinite(out)) or np.any(out <= 0)):
        raise error(f"{name} must be finite and > 0 everywhere (a standard deviation in data units)")
    return out


def _short_repr(value: Any, limit: int = 60) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[:limit] + "..."


def _noise_levels(r: np.ndarray, J: np.ndarray, channels: np.ndarray, s: np.ndarray, p: int) -> np.ndarray:
    """Noise levels σ_c from the residual, free of the estimation error.

    To first order r = e − J δ (δ = θ̂ − θ). Standardised by the noise, r̃ = V^-½ r and
    J̃ = V^-½ J, the part of r̃ orthogonal to the columns of J̃ is (I − P̃) ẽ: it does not
    depend on δ, and E Σ_{i∈c} ((I − P̃) ẽ)ᵢ² = Σ_{i∈c} (1 − P̃ᵢᵢ). Matching the two per
    channel gives σ_c (V holds the σ_c, so three rounds from σ = 1; one suffices for one
    channel). For a fit that weighs every entry by its noise this is the textbook
    RSS / (N − k); for one that does not (an unweighted misfit of relative noise), the
    plain residual would mix in δ, and with it the very error the intervals are for.
    """
    level = np.ones(p)
    present = np.array([np.any(channels == c) for c in range(p)])
    for _ in range(1 if p == 1 else 3):
        sd = level[channels] * s
        live = sd > 0  # a channel whose residual is exactly 0 (a fit to rounding) has level 0: no noise to scale by
        if not np.any(live):
            break
        Jt, rt, ch = J[live] / sd[live, None], r[live] / sd[live], channels[live]
        d = np.linalg.norm(Jt, axis=0)
        U, sv, _ = np.linalg.svd(Jt / np.where(d > 0, d, 1.0)[None, :], full_matrices=False)
        U = U[:, sv > sv.max() * 1e-12] if sv.size and sv.max() > 0 else U[:, :0]
        e = rt - U @ (U.T @ rt)
        lev = np.sum(U**2, axis=1)
        for c in range(p):
            rows = ch == c
            if present[c] and level[c] > 0:
                level[c] *= np.sqrt(float(np.sum(e[rows] ** 2)) / max(float(np.sum(1 - lev[rows])), 1e-300))
    return level


def fisher_uncertainty(theta: np.ndarray, parameter_names: tuple[str, ...], r: np.ndarray, J: np.ndarray,
                       channels: np.ndarray, *, shape: np.ndarray | None = None, units: str = "data units",
                       given_std: np.ndarray | None = None, given_values: np.ndarray | None = None,
                       sensitivity: np.ndarray | None = None, note: str = "", correlation: Any = None
                       ) -> Uncertainty:
    """Covariance (JᵀJ)⁻¹ JᵀVJ (JᵀJ)⁻¹ with V from the residuals or given (module text).

    The first ``len(theta)`` columns of J are θ; entries with zero noise shape (or given
    standard deviation) carry no noise and are left out. ``sensitivity`` (l, N), when
    given, is the method's own first-order map from the noise on the entries of r to
    θ̂ (dθ̂ = G e), for a method that does not minimise ‖r‖²; the covariance is then G V Gᵀ.
    ``correlation`` (N, N), dense or sparse, when given, is the correlation of the entries
    of r (1 on its diagonal): V = D R D with D the standard deviations (the sandwich's
    middle; the Fisher information's conditioning stays that of independent entries). It
    is used where every entry carries noise.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.uncertainty import fisher_uncertainty
    >>> t = np.linspace(0, 1, 50)
    >>> J = -np.column_stack([np.ones(50), t])            # r = y − (a + b t)
    >>> y = 1 + 2 * t + 0.1 * np.sin(37 * t)
    >>> ab, *_ = np.linalg.lstsq(-J, y, rcond=None)
    >>> r = y + J @ ab                                     # the least-squares residual
    >>> u = fisher_uncertainty(ab, ("a", "b"), r, J, np.zeros(50, int))
    >>> bool(np.allclose(u.covariance, np.linalg.inv(J.T @ J) * (r @ r) / 48))
    True
    """
    from scipy.stats import t as student_t

    theta = np.asarray(theta, dtype=float)
    l = theta.size
    r = np.asarray(r, dtype=float).reshape(-1)
    J = np.asarray(J, dtype=float)
    channels = np.asarray(channels, dtype=int).reshape(-1)
    names = tuple(parameter_names)
    s = np.ones(r.size) if shape is None else np.asarray(shape, dtype=float).reshape(-1)
    if given_std is not None:
        s = np.asarray(given_std, dtype=float).reshape(-1)
    keep = s > 0
    if not np.all(keep):
        correlation = None  # given for every entry: not for a subset
    r, J, channels, s = r[keep], J[keep], channels[keep], s[keep]
    Gm = None if sensitivity is None else np.asarray(sensitivity, dtype=float)[:, keep]
    if J.shape[1] > l:  # a nuisance unknown the residual does not depend on at all (an estimated initial position
        # of a model measured in velocity) is no direction the data fail to determine: left out, not flagged
        felt = np.any(J[:, l:] != 0, axis=0)
        J = np.hstack([J[:, :l], J[:, l:][:, felt]])
    N, k = J.shape
    p = int(channels.max()) + 1 if channels.size else 1
    level = np.zeros(p)
    ratio = None
    if given_std is None:
        dof: int | None = max(N - k, 1)
        # residuals or sensitivities that are not finite (an estimate where the model blows up) tell nothing
        finite = bool(np.all(np.isfinite(r)) and np.all(np.isfinite(J)))
        level = _noise_levels(r, J, channels, s, p) if finite else np.full(p, np.nan)
        var = (level[channels] * s) ** 2
        quantile = float(student_t.ppf(0.975, dof))
    else:
        dof = None
        var = s**2
        ratio = float(np.sqrt(np.mean((r / s) ** 2))) if N else float("nan")
        g = np.asarray(given_values, dtype=float).reshape(-1) if given_values is not None else s
        level = np.array([float(np.sqrt(np.mean(g**2)))])
        quantile = _Z975

    def singular(cond: float = float("inf")) -> Uncertainty:
        inf = np.full((l, l), np.inf)
        return Uncertainty(names, inf, np.full(l, np.inf), np.column_stack([theta - np.inf, theta + np.inf]),
                           level, dof, cond, True, {}, units, "residuals" if given_std is None else "given",
                           ratio, note)

    # residuals exactly 0 (a fit to rounding of noise-free data): the noise level estimated from them is 0, so
    # is the covariance; the information's shape (conditioning, weakest direction) is that of unit noise
    silent = given_std is None and N > 0 and bool(np.all(var == 0)) and bool(np.all(s > 0))
    if given_std is None and not finite:
        result = singular()
        return Uncertainty(names, result.covariance, result.standard_errors, result.intervals, level, dof,
                           float("inf"), False, {}, units, "residuals", ratio,
                           (note + "; " if note else "") + "the residuals or their sensitivities are not finite at "
                           "the estimate")
    if silent:
        var = s**2
    if N == 0 or not np.any(var > 0) or not np.all(np.isfinite(J)) or not np.all(np.isfinite(var)):
        return singular()
    # Fisher information F = Jᵀ V⁻¹ J; entries with no noise estimate (var = 0) carry no information here
    noisy = var > 0
    if not np.all(noisy):
        correlation = None
    Jn, vn = J[noisy], var[noisy]

    def middle(X: np.ndarray) -> np.ndarray:
        """Xᵀ V X for the entries' covariance V (diagonal, or with ``correlation``)."""
        if correlation is None:
            return X.T @ (X * vn[:, None])
        Xs = X * np.sqrt(vn)[:, None]
        return Xs.T @ np.asarray(correlation @ Xs)

    F = Jn.T @ (Jn / vn[:, None])
    d = np.sqrt(np.clip(np.diag(F), 0, None))
    safe = np.where(d > 0, d, 1.0)
    # the conditioning and the weakest direction are θ's, with the nuisance unknowns (initial states, offsets)
    # profiled out: the information about θ once they are estimated too, F_θθ − F_θn F_nn⁺ F_nθ (the whole F's
    # smallest eigenvalue could be two nuisance unknowns the records hardly tell apart, and the summary then says the
    # data do not determine every parameter)
    Fp = F[:l, :l]
    if F.shape[0] > l:
        Fn = F[l:, l:] / np.outer(safe[l:], safe[l:])
        cross = F[:l, l:] / safe[None, l:]
        Fp = Fp - cross @ np.linalg.pinv(Fn, rcond=1e-12, hermitian=True) @ cross.T
        Fp = 0.5 * (Fp + Fp.T)
    # scaled by θ's own information (unprofiled): what a nuisance unknown takes from a parameter shows as a small
    # eigenvalue, as it did in the whole F
    ev, vec = np.linalg.eigh(Fp / np.outer(safe[:l], safe[:l]))
    cond = float(ev[-1] / ev[0]) if ev[0] > 0 else float("inf")
    near = not (ev[0] > NEAR_SINGULAR * ev[-1]) or bool(np.any(d[:l] == 0))
    w = vec[:, 0] / safe[:l]
    w = w / (np.linalg.norm(w) or 1.0)
    weakest = dict(zip(names, np.round(w, 6).tolist(), strict=True))
    with np.errstate(divide="ignore", invalid="ignore"):
        wr = np.where(np.abs(theta) > 0, w / np.where(np.abs(theta) > 0, theta, 1.0), 0.0)
    wr = wr / (np.linalg.norm(wr) or 1.0) if np.all(np.isfinite(wr)) else np.zeros(l)
    weakest_relative = dict(zip(names, np.round(wr, 6).tolist(), strict=True))
    # sandwich (JᵀJ)⁻¹ JᵀVJ (JᵀJ)⁻¹, columns scaled like F (the same null space)
    Js = Jn / safe[None, :]
    G = Js.T @ Js
    gev, gvec = np.linalg.eigh(G)
    if not np.any(d == 0) and gev[0] > gev[-1] * 1e-15 and ev[0] > ev[-1] * 1e-15:
        if Gm is not None and np.all(np.isfinite(Gm)):
            cov = middle(Gm.T) if correlation is not None else (Gm * var[None, :]) @ Gm.T
        else:
            Ginv = (gvec / gev) @ gvec.T
            cov_all = Ginv @ middle(Js) @ Ginv / np.outer(safe, safe)
            cov = cov_all[:l, :l]
        cov = 0.5 * (cov + cov.T)
    else:
        # singular: a parameter whose unit vector has no part in the null space of J (scaled) is still
        # determined to first order, its variance that of the pseudo-inverse; the others are not (inf)
        null = gev <= gev[-1] * 1e-15
        if not np.any(~null):
            result = singular(cond)
            return Uncertainty(names, result.covariance, result.standard_errors, result.intervals, level, dof,
                               cond, True, weakest, units, result.noise_source, ratio, note,
                               weakest_relative=weakest_relative)
        Gpinv = (gvec[:, ~null] / gev[~null]) @ gvec[:, ~null].T
        cov_all = Gpinv @ middle(Js) @ Gpinv / np.outer(safe, safe)
        free = np.linalg.norm(gvec[:, null], axis=1) > _NULL_PART
        cov = 0.5 * (cov_all + cov_all.T)[:l, :l]
        cov[free[:l], :] = np.inf
        cov[:, free[:l]] = np.inf
        near = True
    if silent:
        cov = np.where(np.isinf(cov), cov, 0.0)
    se = np.sqrt(np.clip(np.diag(cov), 0, None))
    ci = np.column_stack([theta - quantile * se, theta + quantile * se])
    return Uncertainty(names, cov, se, ci, level, dof, cond, near, weakest, units,
                       "residuals" if given_std is None else "given", ratio, note, weakest_relative=weakest_relative)
