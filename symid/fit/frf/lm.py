"""Trust-region least squares on log-parameters with restarts: the default for frequency responses.

The frequency response of a lightly damped structure is a landscape of narrow ridges in
θ: a resonance of the model that sits beside the measured one leaves a misfit that
barely changes until the two meet. These choices make a local method reliable on models
in physical units, whatever their scale (measured on the generated population of
``benchmarks/population.py`` and in probes on its chains; numbers in the README):

1. **Unknowns of order one.** A parameter declared positive is θₖ = sₖ·exp(φₖ), with
   sₖ its start (or its ``scale`` where the start is 0): a factor of ten is the same step
   for a mass of 0.5 kg and a stiffness of 1e5 N/m, θ stays positive without bounds, and
   the estimate in other units is the same estimate converted (tested over 1e-6…1e6).
   Other parameters are θₖ = x0ₖ + sₖ·φₖ, with sₖ = ``scale``, or |x0ₖ|, or 1.
2. **A smooth criterion first.** Stage 1 fits log(H(ωᵢ, θ) / Hᵢ) (log-magnitude and
   wrapped phase error of each line), which weighs every line alike instead of letting
   the resonance peaks dominate; then the relative error (H(ωᵢ, θ) − Hᵢ)/|Hᵢ|; stage 2
   minimises the criterion the result is judged by, Σ w |Hᵢ − H(ωᵢ, θ)|² / Σ w |Hᵢ|²
   (w = 1/σ² with ``variance``), from there, with ten times the evaluations (on noisy
   data of a sloppy model its minimum lies at the end of a long valley). All use the
   exact Jacobian from the affine maps (:func:`symid.fit.sensitivity.frf_sensitivity`)
   in SciPy's trust-region reflective least squares (Branch, Coleman & Li 1999,
   ``scipy.optimize.least_squares``).
3. **Continuation over frequency** (``bands``). Stage 1 first fits the lowest 1/``bands``
   of the lines, then 2/``bands``, …: the low band fixes the static compliance and the
   first modes before the higher ones pull. Each band stage carries a weak prior
   0.1·(φ − φ₀) towards the pass's start, so that what a partial band cannot see stays
   put instead of drifting to the edge of the box. Measured in a probe (5-mass chains,
   10 passes per start): 0/5 starts without continuation, 2/5 with 4 bands, 3/5 with 8.
4. **Restarts around the start.** When the estimate does not fit the data (the success
   rule of :mod:`symid.fit.success`), a new pass starts from a point drawn
   log-uniformly within a factor ``spread`` of the start — every other one (passes 1,
   3, 5, …) within that factor of the typical values ``scale`` when they are given —
   until a pass fits (a fit that is exact only at the 1e-10 level on data that look
   noise-free gets three more passes: it can be a near-solution in a sloppy direction;
   before them, one pass goes on from that estimate itself, which is often a point the
   pass stopped at short of the fit to rounding: on a user's 3-mass chain, 3 of 4
   starts within a factor 3 of the truth had returned such a fit 3–12 % off, and all 4
   now reach the truth, tests/test_lm_auto.py),
   three passes end at the same best misfit (a confirmed minimum, e.g. on noisy data
   whose residual the whiteness rule rejects; not when a black box of the model's order
   fits the data better than noise explains, item 5: then the minimum found again is a
   local one, and the restarts go on), ``restarts`` passes are spent, or
   ``time_limit`` is reached. The outcome is the best fit found; every pass's time
   counts in the start's. Why the typical values: a start a decade from them on the
   other side of the truth is up to two decades from the truth, and restarts within a
   factor 10 of it rarely land near the truth in every parameter at once; ``scale`` is
   what the user knows of where the truth lies.
5. **A fit a black box beats is no fit.** A fit that is not exact (misfit above
   1e-10: the whiteness or noise-floor rule accepted it) counts as no fit, and the restarts go
   on, while a vector fit of the data with as many poles as the model has states fits them
   better than noise explains (the success rule of :mod:`symid.fit.success`, for every
   method; :meth:`~symid.fit.frf.misfit.FrfEstimator.black_box`). On noise-free data the
   whiteness rule alone accepted misfits of 2e-9 on an 8-mass chain with two sensors (the
   population benchmark's chain_sensors-n8-1, three of four starts, parameters 280 % to
   6600 % off) and 2.3e-6 on a 5-mass chain (50 000 % off), and ``auto`` stopped there; the
   black box fits such data to rounding. On noisy data it is no better than the noise
   allows, so a correct fit is not refused (tests/test_lm_auto.py: on 1 % noise of a 5-mass
   chain, between 0.2 and 1 times the misfit at the truth).

6. **A chain's own values first** (``chain_start``, ``auto`` only). A chain of masses driven
   and measured at one mass is a continued fraction of its elements (two of them, one per
   side, for an interior mass), so its masses,
   dampers and springs can be read off the measured response node by node
   (:func:`symid.fit.frf.chain.chain_start`, tens of milliseconds). The first pass starts
   from them (from the start only when it already fits exactly and no worse), the second
   from the other unless the first fits to rounding. On noise-free data of chains whose
   grid resolves the tolerance, one pass from them reaches the truth in 129 of 133 draws up
   to eight masses, and ``auto`` reaches it from 42 of 44 uninformed starts in 69 s in all,
   against 34 of 44 in 373 s without them; at 1 % noise the deeper elements come out far
   off (the peeling amplifies the noise), and the pass is only a start like any other
   (``benchmarks/chain_start.py``; numbers in the README).

7. **A noisy fit is confirmed** (``confirm``, ``auto`` only). A fit that only the noise
   rule accepts (misfit above 1e-10) can be a local minimum above the least-squares one:
   the whiteness test cannot tell two fits apart that are both as good as the truth's.
   The restarts go on until a second pass ends at the best misfit, or 4 passes after the
   first fit. On the population benchmark's noisy problems (1 %, 27 problems, n = 2 to 8,
   two informed and two uninformed starts each, 45 s per start; ``OMP_NUM_THREADS=1
   OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/auto_confirm.py``, confirm 0 and 4
   side by side, ``benchmarks/results/auto_confirm.jsonl``), 51 of 54 uninformed starts
   met its rule against 49 with the first fit (a 5-compartment model and an 8-mass chain
   with gains, each at the reference's misfit instead of 1.2 % and 4.3 times above it),
   54 of 54 informed either way, no start lost; the median time per start grew from 0.61
   to 0.97 s uninformed (0.32 to 0.42 s informed), the mean from 3.5 to 6.5 s.

8. **A near-singular noisy fit looks elsewhere** (``auto`` only). A fit that only the
   noise rule accepts, where the Fisher information is near-singular
   (:data:`~symid.fit.uncertainty.NEAR_SINGULAR`: the data hardly determine some
   combination of the parameters), is often a limit the passes ran into rather than the
   least-squares estimate: a new user's half car started at 1000 times its values ended
   with the rear spring and damper 1000 times their size (a rigid axle) at misfit
   1.031e-4, where the least-squares estimate of the same data has 8.761e-5. Such a fit
   gets one more start, from the black box's poles
   (:func:`~symid.fit.frf.modal.black_box_start`), with its own restarts and the time
   left; the better of the two is kept (there: 8.761e-5 in 3.5 s).
9. **Parameters the response does not feel are moved** (``auto`` only). Where a fit that
   only the noise rule accepts is, after choice 8, still near-singular with some
   positive parameters saturated (their column of the log-scaled Jacobian below
   :data:`SATURATED` of the largest: a spring and a damper so stiff the axle is rigid,
   or so soft it is free), or has parameters run to the solver's limit (1e6 times their
   start), or more than :data:`FAR` times above or below the typical values given as
   ``scale=``, no local step brings them back, and the
   black box's poles may start there too. One pass each starts from the estimate with
   those parameters multiplied by 0.1, 10, 0.01, 100, 0.001 and 1000 (:data:`JUMPS`; a
   parameter at the limit from its own start times the factor, one far from its typical
   value from that value times the factor), the others kept; the best is kept. On the same half car
   the black box's start had the rear spring 8 times its size, already rigid, and its
   passes ended at 1.031e-4 too (or not, by rounding: the derivatives computed in
   another order, 1e-14 apart, decided it); from the starts 10, 30, 100, 1000 and 0.001
   times the truth one of the six passes reached 8.761e-5. FRF population (auto rerun
   at every size): it ran on 19 of 128 noisy starts and was kept on 3; 1 % uninformed
   at n = 8 went from 3 to 4 of 6 successes, no count fell. A parameter left at the
   limit is named in the message. The move of a parameter far from its typical value
   (:data:`FAR`) turned the 8-mass gains model's uninformed miss (1.226e-4, c7 21 000
   times its value, neither unfelt nor at the limit) into a fit at the least-squares
   misfit, 2.872e-5; the noisy population rerun at every size lost no success (n = 8: 6
   and 5 of 6 informed and uninformed, from 5 and 4).

Measured on generated 5-mass chains the population benchmark does not use (noise-free,
uninformed starts, 45 s each; ``OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 .venv/bin/python
benchmarks/auto_restarts.py``): the truth from 4 of 8 starts with every restart around
the start, 5/8 with every other one around the typical values, 6/8 with the black-box rule of choice 5 too
(one start settled for a whiteness fit at misfit 2e-6, 500-fold off; with the rule it
went on to the truth in 8 s). On the population benchmark's own n = 5 and 8 problems
(README), run again after the sensitivities became 4–6 times cheaper at 8 masses: every
noise-free start at n = 5 (8/8 uninformed, was 7/8); at n = 8 2 of 6 uninformed, the
misses 8-mass chains whose 5–11 passes of 3–9 s ended at near-solutions (misfits 2e-9 to
1e-5, parameters 180 % to 67 000 % off) that rule 5 refuses. With choice 6 every noise-free
start of the benchmark reaches the truth, n = 8 included (6 of 6 uninformed, a median
0.04 s per start); at 1 % noise 7 of 8 uninformed at n = 5 and 4 of 6 at n = 8.

Also tried and not kept: a pass from the black-box start of
:func:`symid.fit.frf.modal.black_box_start` (the model's poles placed on a vector fit's)
when the pass from the start does not fit. It is cheap (0.6 s to build at 5 masses, 1.2 s
at 8, median) but rarely near enough: on exact data of generated chains, chains with two
sensors and chains with gains the benchmark does not use, one ``auto`` pass from it reached
the truth on 3 of 8 problems at n = 5 and 1 of 5 at n = 8 (a median 15–17 % of its
parameters more than a factor 10 off; ``benchmarks/black_box_pass.py``).

Also tried in earlier probes and not kept: basin hopping around the best point so far (worse
than restarts around the start: 0/5 against 3/5 on a 3-mass chain), and a homotopy that
shifts the evaluation contour from Re s = σ > 0 to the imaginary axis (needs the
response off the axis, i.e. a black-box fit first; it helped some chains and hurt
others).

``method="lm"`` is one pass (no restarts, no continuation), ``method="auto"`` the
restarted one with 8 bands.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np
from scipy.optimize import least_squares

from symid.errors import ModelError, OptionError
from symid.fit.bounded import bounds_option, clip_into, log_box, named_bounds, on_bounds
from symid.fit.frf.misfit import (
    RELATIVE_COST_KIND,
    VARIANCE_OPTION_DOC,
    FrfEstimator,
    NoiseWeighted,
    frf_weights,
)
from symid.fit.options import (
    check_bool,
    check_float,
    check_int,
    check_scale,
    check_seed,
    check_start_bounds,
    check_time_limit,
    moved_onto_bounds,
)
from symid.fit.result import StartOutcome
from symid.fit.sensitivity import frf_sensitivity
from symid.fit.success import EXACT_FIT, black_box_ratio

__all__ = ["AutoFRF", "LmFRF"]

_LOG_BOX = math.log(1e6)  # |φₖ| ≤ log 1e6 for positive parameters: no estimate beyond a factor 1e6 of the start
_EXACT_STOP = 1e-20  # a misfit at rounding level: no further pass can do better
_EXTRA_PASSES = 3  # passes tried after a fit that is exact only at the 1e-10 level
_PRIOR = 0.1  # weight of φ − φ_pass-start in the band stages: what a partial band cannot see stays put
SATURATED = 1e-3
"""A positive parameter whose log-scaled Jacobian column is below this fraction of the largest is one the response
does not feel at the estimate (choice 9)."""

FAR = 100.0
"""A positive parameter more than this factor from its typical value at a noisy fit is moved too (choice 9)."""

JUMPS = (0.1, 10.0, 0.01, 100.0, 0.001, 1000.0)
"""The factors the saturated parameters are multiplied by, one pass each (choice 9)."""

RELATIVE_ROUNDS = 3
"""With ``variance="relative"``: at most this many passes reweighted by the model's response at the estimate."""

_REPEATS = 3  # restarts stop once this many passes have ended at the best misfit (to 1e-6): a confirmed minimum


class _Budget(Exception):
    """Raised inside a residual evaluation once the time budget is spent."""


class LmFRF(NoiseWeighted, FrfEstimator):
    """Levenberg–Marquardt (trust-region reflective) on log-parameters, optionally restarted.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    data : FrequencyData
    scale : array_like, optional
        Typical magnitude of each parameter (one number or one per parameter): the unit
        of φ for parameters of either sign, the centre of every other restart of the
        parameters declared positive, and of all restarts for a parameter whose start is
        0. Default: the start itself (|x0ₖ|, or 1 where x0ₖ = 0).
    restarts : int, optional
        Further passes from random points when the estimate does not fit the data
        (default 0 for ``"lm"``, 30 for ``"auto"``).
    spread : float, optional
        Restart points are drawn log-uniformly within a factor ``spread`` of the start,
        every other one of ``scale`` when it is given (default 10: two decades around it).
    bands : int, optional
        Continuation over frequency: stage 1 first fits the lowest 1/``bands`` of the
        lines, then 2/``bands``, ..., then all of them (default 1, no continuation, for
        ``"lm"``; 8 for ``"auto"``).
    max_iter : int, optional
        Function evaluations (iterations of the trust-region method) per stage of a pass
        (default 300; ten times that for the last stage, the judged criterion).
    positivity : bool, optional
        Parameters declared positive are θₖ = sₖ·exp(φₖ), so they stay positive (default
        ``True``); ``False`` treats them as the others (θₖ = x0ₖ + sₖ·φₖ).
    tol : float, optional
        Relative tolerance on the criterion and the step (SciPy's ``ftol``, ``xtol``;
        default 1e-12).
    time_limit : float, optional
        Wall-time budget of one start in seconds, restarts included (default: none for
        ``"lm"``, 120 for ``"auto"``).
    seed : int, optional
        Seed of the restart points (combined with the start, so every start draws its own).
    verbose : bool, optional
        Print one line per pass (misfit, fit, elapsed).
    callback : callable, optional
        ``callback(pass_index, info)`` after every pass, with ``info`` holding ``theta``,
        ``misfit``, ``fits``, ``elapsed``; a true return stops the restarts.
    confirm : int, optional
        Further passes after a fit that only the noise rule accepts (misfit above
        1e-10): restarts go on until a second pass ends at the best misfit (a confirmed
        minimum) or ``confirm`` passes have been spent since the first fit; the outcome is
        the best (default 0 for ``"lm"``, 4 for ``"auto"``).
    bounds : dict or array_like, optional
        Lower and upper bounds per parameter: a dict by name of (low, high) pairs (None or
        ±inf for an open side), or an (l, 2) array. The passes stay within them (bounds on
        the log-parameters, :mod:`symid.fit.bounded`), restarts and the chain's values are
        moved into them, and a start outside them is refused. Parameters declared
        positive stay positive without a bound. Default: none.
    chain_start : bool, optional
        For a chain of masses driven and measured at one mass, one pass starts from the
        chain's values read off the response by continued fractions
        (:func:`symid.fit.frf.chain.chain_start`): the first pass, unless the start
        already fits the data exactly and no worse; the other start gets the second pass
        unless the first fits to rounding (default ``True`` for ``"auto"``, ``False`` for
        ``"lm"``). Other models are not affected.
    {variance}

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, {{"m": 2.0, "c": 0.5, "k": 3e4}}, np.logspace(1, 3, 40))
    >>> res = si.identify(model, frf, method="auto", x0={{"m": 20.0, "c": 0.05, "k": 1e3}}, seed=0)
    >>> res.success, [float(f"{{v:.6g}}") for v in res.theta.values()]
    (True, [2.0, 0.5, 30000.0])
    """

    method: ClassVar[str] = "lm"
    default_restarts: ClassVar[int] = 0
    default_bands: ClassVar[int] = 1
    default_time_limit: ClassVar[float | None] = None
    default_chain_start: ClassVar[bool] = False
    default_confirm: ClassVar[int] = 0
    _loose_fits_matter: bool = True  # a fit exact only at the 1e-10 level gets more passes (choice 4)
    _rescue: ClassVar[bool] = False  # a near-singular noisy fit gets one pass from the black box's poles (auto)

    def __init__(self, model: Any, data: Any, *, scale: Any = None, restarts: int | None = None,
                 spread: float = 10.0, max_iter: int = 300, positivity: bool = True, tol: float = 1e-12,
                 time_limit: float | None = None, bands: int | None = None, seed: int = 0,
                 variance: Any = "data", verbose: bool = False,
                 callback: Callable[[int, dict[str, Any]], Any] | None = None, chain_start: bool | None = None,
                 confirm: int | None = None, bounds: Any = None):
        self.model, self.data = model, data
        l = model.n_parameters
        self.scale = None if scale is None else check_scale("scale", scale, l)
        restarts = self.default_restarts if restarts is None else check_int("restarts", restarts, low=0,
                                                                            high=10**6)
        spread = check_float("spread", spread, low=1.0)
        bands = self.default_bands if bands is None else check_int("bands", bands, low=1, high=10**4)
        max_iter = check_int("max_iter", max_iter, low=1, high=10**7)
        positivity = check_bool("positivity", positivity)
        tol = check_float("tol", tol, low=0, strict_low=True)
        if time_limit is None:
            time_limit = self.default_time_limit
        time_limit = check_time_limit("time_limit", time_limit)
        seed = check_seed("seed", seed)
        verbose = check_bool("verbose", verbose)
        chain_start = self.default_chain_start if chain_start is None else check_bool("chain_start", chain_start)
        confirm = self.default_confirm if confirm is None else check_int("confirm", confirm, low=0, high=10**6)
        if callback is not None and not callable(callback):
            raise OptionError(f"callback must be callable (pass_index, info) -> bool; got {type(callback).__name__}")
        self.lower, self.upper, self._bounded = bounds_option(model, bounds, positivity)
        label = self.set_variance(variance)  # weights, the given noise and the noise floor it declares
        self._variance = variance
        self.callback = callback
        self.options = {"scale": None if self.scale is None else self.scale.tolist(),
                        "bounds": named_bounds(model.parameter_names, self.lower, self.upper)
                        if self._bounded else None, "restarts": restarts,
                        "bands": bands,
                        "spread": spread, "max_iter": max_iter,
                        "positivity": positivity, "tol": tol, "time_limit": time_limit, "seed": seed,
                        "variance": label,
                        "verbose": verbose, "chain_start": chain_start, "confirm": confirm}
        H = np.asarray(data.H)
        self._H = H
        self._mask = np.abs(H) > 0
        self._weights_changed()
        self._positive = np.asarray(model.positive, dtype=bool) & positivity
        self._w = np.asarray(data.w, dtype=float)
        self._chain: Any = None  # the chain's values (chain_start), read once per estimator
        self._chain_read = False
        self._box: tuple[np.ndarray, np.ndarray] | None = None  # bounds on φ of the start under way (bounds)
        self._bb_theta: np.ndarray | None = None  # the black-box start (_black_box_theta), read once
        self._bb_read = False
        self._rescuing = False  # within the start from the black box's poles of a near-singular fit

    def _weights_changed(self) -> None:
        """The pass's √w and ‖√w H‖ from ``line_weights``."""
        wts = np.ones(self._H.shape) if self.line_weights is None else self.line_weights
        self._sqrtw = np.sqrt(wts)
        self._hnorm = float(np.sqrt(np.sum(wts * np.abs(self._H) ** 2)))

    def reweigh_relative(self, theta: Any) -> None:
        """As :meth:`NoiseWeighted.reweigh_relative`, for the passes too."""
        super().reweigh_relative(theta)
        self._weights_changed()

    def _relative_rounds(self, best: StartOutcome, start: np.ndarray, centre: np.ndarray, unit: np.ndarray,
                         deadline: float | None, t0: float, nfev: int) -> tuple[StartOutcome, int, int]:
        """With ``variance="relative"``: passes from the estimate with the weights from the model's response there
        (:meth:`reweigh_relative`), until the estimate moves by under 1e-6 of itself (at most
        :data:`RELATIVE_ROUNDS`); (the last outcome, passes, evaluations)."""
        rounds = used = 0
        theta = best.theta
        for _ in range(RELATIVE_ROUNDS):
            if deadline is not None and time.perf_counter() >= deadline:
                break
            self.reweigh_relative(theta)
            new, count, spent = self._pass(self._phi(theta, centre, unit), centre, unit, deadline)
            rounds, used = rounds + 1, used + count
            moved = float(np.max(np.abs(new - theta) / np.maximum(np.abs(theta), 1e-300)))
            theta = new
            if spent or moved < 1e-6:
                break
        if not rounds:
            return best, 0, 0
        self.reweigh_relative(theta)  # the weights the outcome (and the uncertainty) are judged in
        out = self.outcome(start, theta, finished=True, status="converged", message="", iterations=nfev + used,
                           wall_time=time.perf_counter() - t0)
        return out, rounds, used

    # -- parametrisation ------------------------------------------------------------------------
    def _units(self, x0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(centre c, unit s): θ = c·exp(φ) for positive parameters, θ = c + s·φ for the others."""
        mag = np.abs(x0)
        typical = self.scale if self.scale is not None else np.where(mag > 0, mag, 1.0)
        centre = np.where(self._positive, np.where(x0 > 0, x0, typical), x0)
        return centre, typical

    def _phi(self, theta: np.ndarray, centre: np.ndarray, unit: np.ndarray) -> np.ndarray:
        """φ of θ (the inverse of :meth:`_theta`; a positive parameter at or below 0 goes to the box's edge)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(self._positive, theta / centre, 1.0)
            logs = np.log(np.where(ratio > 0, ratio, math.exp(-_LOG_BOX)))
        return self._clip(np.where(self._positive, logs, (theta - centre) / unit))

    def _theta(self, phi: np.ndarray, centre: np.ndarray, unit: np.ndarray) -> np.ndarray:
        theta = np.where(self._positive, centre * np.exp(np.clip(phi, -_LOG_BOX, _LOG_BOX)), centre + unit * phi)
        # on a bound exactly, not a rounding error of exp(log(bound / centre)) beyond it
        return np.clip(theta, self.lower, self.upper) if self._bounded else theta

    def _dtheta(self, phi: np.ndarray, centre: np.ndarray, unit: np.ndarray) -> np.ndarray:
        inside = np.abs(phi) < _LOG_BOX
        return np.where(self._positive, np.where(inside, centre * np.exp(np.clip(phi, -_LOG_BOX, _LOG_BOX)), 0.0),
                        unit)

    # -- one pass ---------------------------------------------------------------------------------
    def _residual(self, kind: str, centre: np.ndarray, unit: np.ndarray, deadline: float | None, lines: int
                  ) -> Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]:
        """Residual and Jacobian in φ of criterion ``kind`` over the first ``lines`` frequencies."""
        H, mask = self._H[:lines], self._mask[:lines]
        sqrtw, w = self._sqrtw[:lines], self._w[:lines]
        big = 1e3 * math.sqrt(H.size)

        def fun(phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            if deadline is not None and time.perf_counter() > deadline:
                raise _Budget
            th = self._theta(phi, centre, unit)
            try:
                with np.errstate(all="ignore"):
                    Hm, dH = frf_sensitivity(self.model, th, w)
            except (ModelError, np.linalg.LinAlgError):
                Hm = None
            if Hm is None or not (np.all(np.isfinite(Hm)) and np.all(np.isfinite(dH))):
                r = np.full(2 * H.size, big)
                return r, np.zeros((r.size, phi.size))
            dH = dH * self._dtheta(phi, centre, unit)  # chain rule to φ, last axis
            if kind in ("log", "rel"):
                ok = mask & (np.abs(Hm) > 0)
                with np.errstate(all="ignore"):
                    if kind == "log":  # log(Hm / H): the phase error wrapped to (−π, π], never 2π off
                        r = np.where(ok, np.log(np.where(ok, Hm, 1.0) / np.where(mask, H, 1.0)), 0.0)
                        J = np.where(ok[..., None], dH / np.where(ok, Hm, 1.0)[..., None], 0.0)
                    else:
                        absH = np.where(mask, np.abs(H), 1.0)
                        r = np.where(mask, (Hm - H) / absH, 0.0)
                        J = np.where(mask[..., None], dH / absH[..., None], 0.0)
                r = r * sqrtw
                J = J * sqrtw[..., None]
            else:
                r = sqrtw * (Hm - H) / self._hnorm
                J = dH * (sqrtw / self._hnorm)[..., None]
            r = r.ravel()
            J = J.reshape(-1, phi.size)
            out_r = np.concatenate([r.real, r.imag])
            out_J = np.vstack([J.real, J.imag])
            if not (np.all(np.isfinite(out_r)) and np.all(np.isfinite(out_J))):
                out_r = np.full(2 * H.size, big)
                out_J = np.zeros((out_r.size, phi.size))
            return out_r, out_J

        return fun

    def _stage(self, kind: str, phi: np.ndarray, centre: np.ndarray, unit: np.ndarray, deadline: float | None,
               lines: int | None = None, anchor: np.ndarray | None = None) -> tuple[np.ndarray, int]:
        """One least-squares stage from φ; with ``anchor``, plus the prior term _PRIOR·(φ − anchor)."""
        fun = self._residual(kind, centre, unit, deadline, self._w.size if lines is None else lines)
        memo: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}
        eye = _PRIOR * np.eye(phi.size)

        def value(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            key = p.tobytes()
            if key not in memo:
                memo.clear()
                r, J = fun(p)
                if anchor is not None:
                    r, J = np.concatenate([r, _PRIOR * (p - anchor)]), np.vstack([J, eye])
                memo[key] = (r, J)
            return memo[key]

        # stage 1 only has to bring the estimate into the basin: a looser tolerance (measured: the
        # tight one spends most passes' time creeping along the log criterion)
        tol = max(self.options["tol"], 1e-8) if kind == "log" else self.options["tol"]
        # the judged criterion gets ten times the evaluations: on noisy data of a sloppy model its minimum
        # lies at the end of a long valley (measured: 250-850 evaluations on a 2-mass chain at 1 % noise)
        nfev = self.options["max_iter"] * (10 if kind == "abs" else 1)
        box = (-np.inf, np.inf) if self._box is None else self._box
        sol = least_squares(lambda p: value(p)[0], self._clip(phi), jac=lambda p: value(p)[1], method="trf",
                            x_scale=1.0, max_nfev=nfev, ftol=tol, xtol=tol, gtol=min(tol, 1e-10), bounds=box)
        return self._clip(sol.x), int(sol.nfev)

    def _clip(self, phi: np.ndarray) -> np.ndarray:
        phi = np.where(self._positive, np.clip(phi, -_LOG_BOX, _LOG_BOX), phi)
        return phi if self._box is None else np.clip(phi, *self._box)

    def _pass(self, phi: np.ndarray, centre: np.ndarray, unit: np.ndarray, deadline: float | None
              ) -> tuple[np.ndarray, int, bool]:
        """Stage 1 (log H, then the relative error of each line) and stage 2 (the judged criterion);
        (θ, evaluations, budget spent)."""
        nfev = 0
        s = self._w.size
        bands = self.options["bands"]
        try:
            anchor = phi.copy()
            for b in range(1, bands):  # the log criterion on a growing band of the lowest frequencies
                phi, k = self._stage("log", phi, centre, unit, deadline, max(3, math.ceil(b * s / bands)), anchor)
                nfev += k
            for kind in ("log", "rel", "abs"):
                phi, k = self._stage(kind, phi, centre, unit, deadline)
                nfev += k
            # a pass never ends worse, by the judged criterion, than it began: lines whose noise is as large as
            # the response (beyond a mode, a flat multisine's) make the log and relative criteria noise there,
            # and stage 1 walked from the truth itself to a misfit 4e4 times the truth's (a one-mass model, 1 %
            # output noise, lines up to 10 times the mode; 2 of 60 records). Then stage 2 runs from the start too
            judged = self._residual("abs", centre, unit, deadline, s)
            nfev += 2
            if float(np.sum(judged(anchor)[0] ** 2)) < float(np.sum(judged(phi)[0] ** 2)):
                again, k = self._stage("abs", anchor, centre, unit, deadline)
                nfev += k + 1
                if float(np.sum(judged(again)[0] ** 2)) < float(np.sum(judged(phi)[0] ** 2)):
                    phi = again
        except _Budget:
            return self._theta(phi, centre, unit), nfev, True
        return self._theta(phi, centre, unit), nfev, False

    # -- a start ------------------------------------------------------------------------------
    def check_start(self, x0: np.ndarray) -> None:
        """Refuse a start of the wrong length, or negative in a parameter kept positive (an :class:`OptionError`
        naming it): θₖ = sₖ·exp(φₖ) cannot start below 0. A start of 0 takes the parameter's ``scale``."""
        x = np.asarray(x0, dtype=float).reshape(-1)
        names = self.model.parameter_names
        if x.size != len(names):
            raise OptionError(f"the start has {x.size} values; the model has {len(names)} parameters "
                              f"({', '.join(names)})")
        bad = [k for k in range(x.size) if self._positive[k] and x[k] < 0]
        if bad:
            k = bad[0]
            raise OptionError(f"the start {names[k]} = {x[k]:g} is negative, but {names[k]} is declared positive and "
                              f"{self.method!r} keeps it so; give a positive start (0 takes its scale), or "
                              f"positivity=False")
        check_start_bounds(x, self.lower, self.upper, names)

    def _chain_theta(self, x0: np.ndarray) -> np.ndarray | None:
        """x0 with the chain's values read off the response (chain_start), or None where there are none."""
        if not self._chain_read:
            from symid.fit.frf.chain import chain_start

            self._chain, self._chain_read = chain_start(self.model, self.data), True
        if self._chain is None:
            return None
        theta = x0.copy()
        for k, name in enumerate(self.model.parameter_names):
            v = self._chain.values.get(name)
            if v is not None and np.isfinite(v) and (v > 0 or not self._positive[k]):
                theta[k] = v
        return theta

    def run(self, x0: np.ndarray) -> StartOutcome:
        """Passes from ``x0`` (and restarts around it) until the estimate fits or the budget is spent."""
        t0 = time.perf_counter()
        x0 = np.asarray(x0, dtype=float).reshape(-1)
        if x0.size != self.model.n_parameters or not np.all(np.isfinite(x0)):
            raise OptionError(f"the start must hold {self.model.n_parameters} finite values; got {x0!r}")
        opts = self.options
        limit = opts["time_limit"]
        deadline = None if limit is None else t0 + limit
        moved, start = "", x0
        if self._bounded:  # a drawn start outside the bounds begins on them (a user's own was refused)
            moved = moved_onto_bounds(x0, self.lower, self.upper, self.model.parameter_names)
            x0 = clip_into(x0, self.lower, self.upper)
        centre, unit = self._units(x0)
        if self.options["variance"] == "relative":  # every start from the measured |H|'s weights
            self.line_weights = frf_weights(self.data, "relative")
            self.cost_kind = RELATIVE_COST_KIND  # type: ignore[misc]
            self._weights_changed()
        self._box = None
        if self._bounded:
            self._box = log_box(self.lower, self.upper, centre, unit, self._positive, _LOG_BOX)
        rng = np.random.default_rng([opts["seed"], *np.frombuffer(x0.tobytes(), dtype=np.uint32)])
        best: StartOutcome | None = None
        total_nfev = 0
        status = "max_restarts"
        passes = 0
        phi = np.zeros(x0.size)
        first_fit = opts["restarts"] + 1
        repeats = 0
        polished = math.nan  # the misfit of the last loose fit a pass was continued from
        visited: list[StartOutcome] = []  # every pass's outcome: other local solutions for alternatives()
        chain_note = ""
        # with the chain's values (chain_start), passes 0 and 1 start from them and from x0: from x0 first only
        # when it fits exactly and no worse than they do (a start at the truth stays there); the misfit of the
        # values is no guide otherwise (an 8-mass chain whose deepest spring came out 3500 times too large
        # fitted worse than the start, yet one pass from them reached the truth). The second pass is skipped
        # only when the first fits to rounding (noisy data: the first fit may be a worse minimum that the
        # whiteness rule accepts; measured on an 8-mass chain at 1 % noise)
        pending, pending_note = None, ""
        specials = 1  # passes before the random restarts: from x0, and from the chain's values
        chain = self._chain_theta(x0) if opts["chain_start"] else None
        if chain is not None:
            specials = 2
            chain_phi = self._phi(chain, centre, unit)
            at_start = self.misfit(x0)
            if not (at_start <= EXACT_FIT and at_start <= self.misfit(chain)):
                phi, pending, chain_note = chain_phi, phi.copy(), "; pass 0 from the chain's continued fraction"
            else:
                pending, pending_note = chain_phi, "; pass 1 from the chain's continued fraction"
            if opts["verbose"]:
                print(f"{self.method}: the chain's values read off the response "
                      f"(pass {1 if pending_note else 0} starts there)", flush=True)
        for k in range(opts["restarts"] + 1):
            if k == 1 and pending is not None:
                if deadline is not None and time.perf_counter() >= deadline:
                    status = "time_limit"
                    break
                phi, pending = pending, None
                chain_note = f"{chain_note}, pass 1 from the start" if chain_note else pending_note
            elif k > 0:
                if deadline is not None and time.perf_counter() >= deadline:
                    status = "time_limit"
                    break
                half = math.log(opts["spread"])
                phi = np.where(self._positive, rng.uniform(-half, half, x0.size), rng.uniform(-1.0, 1.0, x0.size))
                if (k - specials) % 2 == 0 and self.scale is not None:  # every other restart around the typical values
                    phi = phi + np.where(self._positive, np.log(self.scale / centre), 0.0)
            theta, nfev, spent = self._pass(phi, centre, unit, deadline)
            total_nfev += nfev
            passes += 1
            cand = self.outcome(start, theta, finished=not spent, status="time_limit" if spent else "converged",
                                message="", iterations=total_nfev, wall_time=time.perf_counter() - t0)
            visited.append(cand)
            if best is None or cand.cost < best.cost * (1 - 1e-6):
                best, repeats = cand, 1
            elif cand.cost <= best.cost * (1 + 1e-6):
                repeats += 1
                if cand.cost < best.cost:
                    best = cand
            info = {"theta": dict(zip(self.model.parameter_names, theta.tolist(), strict=True)), "misfit": cand.cost,
                    "fits": cand.success, "elapsed": time.perf_counter() - t0}
            if opts["verbose"]:
                print(f"{self.method} pass {k}: misfit {cand.cost:.3e}, {'fits' if cand.success else 'does not fit'}"
                      f", {info['elapsed']:.2f} s", flush=True)
            if self.callback is not None and self.callback(k, info):
                status = "stopped"
                break
            loose_fit = self._loose_fits_matter and _EXACT_STOP < best.cost <= EXACT_FIT
            if best.success and loose_fit and best.cost != polished and not spent:
                # a fit exact only at the 1e-10 level is often a point the pass stopped at, short of a fit to
                # rounding along a sloppy direction: one more pass from the estimate itself goes on from there
                polished = best.cost
                theta, nfev, spent = self._pass(self._phi(best.theta, centre, unit), centre, unit, deadline)
                total_nfev += nfev
                passes += 1
                cand = self.outcome(start, theta, finished=not spent, status="time_limit" if spent else "converged",
                                    message="", iterations=total_nfev, wall_time=time.perf_counter() - t0)
                visited.append(cand)
                if cand.cost < best.cost:
                    best = cand
                if opts["verbose"]:
                    print(f"{self.method} pass {k} continued from its estimate: misfit {cand.cost:.3e}, "
                          f"{time.perf_counter() - t0:.2f} s", flush=True)
            if best.success:
                # an exact fit only at the 1e-10 level on data that look noise-free can be a near-solution
                # in a sloppy direction (measured: chains of 5 masses, misfit 4e-15 at 47 % parameter error):
                # a few more passes look for a fit to rounding before settling for it
                first_fit = min(first_fit, k)
                loose = self._loose_fits_matter and _EXACT_STOP < best.cost <= EXACT_FIT
                settled = not loose or k >= first_fit + _EXTRA_PASSES
                if best.cost > EXACT_FIT:  # accepted by the noise rule: confirmed, or `confirm` passes spent
                    settled = repeats >= 2 or k >= first_fit + opts["confirm"]
                if settled and (pending is None or best.cost <= EXACT_FIT):
                    status = "fits"
                    break
            if spent:
                status = "time_limit"
                break
            if repeats >= _REPEATS and not self._cleaner_than(best):
                # the same minimum from several points: no restart is likely to beat it
                status = "repeated"
                break
        assert best is not None
        rescue = ""
        noisy_fit = (self._rescue and not self._rescuing and best.success and best.cost > EXACT_FIT
                     and status not in ("time_limit", "stopped"))
        if (noisy_fit and (deadline is None or time.perf_counter() < deadline)
                and self._near_singular(best.theta)):
            # a fit only the noise rule accepts, where the data hardly determine some combination of the parameters:
            # often a limit the passes ran into (a stiffness and a damper 1000 times their size: a rigid axle), not
            # the least-squares estimate; a start from the black box's poles (symid.fit.frf.modal), with its own
            # restarts, looks elsewhere (choice 8)
            found = self._black_box_theta()
            if found is not None:
                self._rescuing = True  # the start from the black box's poles, with its own restarts, once
                saved = opts["time_limit"]
                try:
                    if deadline is not None:
                        opts["time_limit"] = max(deadline - time.perf_counter(), 1e-3)
                    other = self.run(found)
                finally:
                    self._rescuing = False
                    opts["time_limit"] = saved
                total_nfev += other.iterations
                passes += 1 + len(other.passes)
                cand = self.outcome(start, other.theta, finished=other.finished, status="converged", message="",
                                    iterations=total_nfev, wall_time=time.perf_counter() - t0)
                visited.extend((cand, *other.passes))
                rescue = (f"; the fit was near-singular: a start from the black box's poles ({1 + len(other.passes)} "
                          f"pass(es)) ended at misfit {cand.cost:.3e}")
                if cand.cost < best.cost * (1 - 1e-6):
                    best = cand
                    rescue += ", kept"
        jumped = self._jump_saturated(best, start, centre, unit, deadline, t0, total_nfev) if noisy_fit else None
        if jumped is not None:
            note, tried, used = jumped
            total_nfev += used
            passes += len(tried)
            visited.extend(tried)
            top = min(tried, key=lambda c: c.cost)
            rescue += note + f"{top.cost:.3e}"
            if top.cost < best.cost * (1 - 1e-6):
                best = top
                rescue += ", kept"
        if self.options["variance"] == "relative" and np.all(np.isfinite(best.theta)):
            # weights from the model's response at the estimate, not the measured one's (reweigh_relative)
            best, rounds, used = self._relative_rounds(best, start, centre, unit, deadline, t0, total_nfev)
            total_nfev += used
            passes += rounds
            if rounds:
                rescue += f"; {rounds} pass(es) weighted by the model's |H| at the estimate (variance='relative')"
        if status == "max_restarts" and best.success:
            status = "fits"
        wall = time.perf_counter() - t0
        what = {"fits": f"a fit after {passes} pass(es)",
                "max_restarts": f"no fit in {passes} pass(es) (restarts={opts['restarts']})",
                "time_limit": f"time limit of {limit:g} s reached after {passes} pass(es)" if limit else "",
                "stopped": f"stopped by the callback after {passes} pass(es)",
                "repeated": f"{_REPEATS} of {passes} passes ended at the same best misfit"}[status]
        out = self.outcome(start, best.theta, finished=status not in ("time_limit", "stopped"), status=status,
                           message=f"{what}; {total_nfev} evaluations; best misfit {best.cost:.3e}{chain_note}"
                                   f"{rescue}{moved}{self._on_bounds(best.theta)}"
                                   f"{self._at_edge(best.theta, centre, unit)}",
                           iterations=total_nfev, wall_time=wall)
        others = tuple(c for c in visited if c is not best)
        return dataclasses.replace(out, passes=others) if others else out

    def _near_singular(self, theta: np.ndarray) -> bool:
        """Whether the Fisher information at θ is near-singular (:data:`~symid.fit.uncertainty.NEAR_SINGULAR`)."""
        try:
            unc = self.uncertainty(theta, self.model.parameter_names)
        except (ModelError, np.linalg.LinAlgError, ValueError):
            return False
        return bool(unc.near_singular)

    def _edge(self, theta: np.ndarray, centre: np.ndarray, unit: np.ndarray) -> np.ndarray:
        """The positive parameters θ has run to the solver's limit, 1e6 times their start (not a user's bound)."""
        edge = self._positive & (np.abs(self._phi(theta, centre, unit)) >= _LOG_BOX * (1 - 1e-9))
        if self._bounded:  # an edge of the user's bounds is theirs (on_bounds), not a parameter run off
            edge &= ~(np.isclose(theta, self.lower, rtol=1e-9, atol=0)
                      | np.isclose(theta, self.upper, rtol=1e-9, atol=0))
        return edge

    def _at_edge(self, theta: np.ndarray, centre: np.ndarray, unit: np.ndarray) -> str:
        """The message's warning for parameters at the solver's limit ('' if none)."""
        edge = self._edge(theta, centre, unit)
        if not edge.any():
            return ""
        phi = self._phi(theta, centre, unit)
        sides = []
        for factor, side in (("1e-6", phi < 0), ("1e6", phi > 0)):
            names = ", ".join(n for n, e, d in zip(self.model.parameter_names, edge, side, strict=True) if e and d)
            if names:
                sides.append(f"{names} stopped at {factor} times the start")
        return (f"; {' and '.join(sides)}, the solver's limit: a limit the passes ran into rather than a minimum "
                f"(a parameter the data hardly feel, or a start far from the typical values: x0= or scale= may fit "
                f"better)")

    def _saturated(self, theta: np.ndarray) -> np.ndarray:
        """The positive parameters the response does not feel at θ (choice 9): their column of the Jacobian
        scaled by θ below :data:`SATURATED` of the largest."""
        none = np.zeros(theta.size, dtype=bool)
        try:
            _, J = self.jacobian(theta)
        except (ModelError, np.linalg.LinAlgError, ValueError):
            return none
        size = np.linalg.norm(J[:, :theta.size] * np.where(self._positive, theta, 0.0), axis=0)
        if not np.all(np.isfinite(size)) or not size.max() > 0:
            return none
        return self._positive & (size < SATURATED * size.max())

    def _jump_saturated(self, best: StartOutcome, start: np.ndarray, centre: np.ndarray, unit: np.ndarray,
                        deadline: float | None, t0: float, nfev: int) -> tuple[str, list[StartOutcome], int] | None:
        """Choice 9: one pass from ``best`` with its saturated parameters multiplied by each of :data:`JUMPS`;
        (the note's text, the passes' outcomes, their evaluations) or None when nothing is saturated (or no time
        is left). ``nfev``: the evaluations so far, for the outcomes' counts."""
        if deadline is not None and time.perf_counter() >= deadline:
            return None
        edge = self._edge(best.theta, centre, unit)  # run to 1e6 × their start
        far = self._far(best.theta, unit) & ~edge
        unfelt = np.zeros_like(edge)
        if self._near_singular(best.theta):
            unfelt = self._saturated(best.theta) & ~edge & ~far
        which = edge | far | unfelt
        if not which.any():
            return None
        tried, used = [], 0
        for factor in JUMPS:
            if deadline is not None and time.perf_counter() >= deadline:
                break
            # an unfelt parameter moves from where it is; one run to the edge starts again from its own start, one
            # far from the typical values from them
            moved = np.where(edge, centre * factor,
                             np.where(far, unit * factor, np.where(unfelt, best.theta * factor, best.theta)))
            if self._bounded:
                moved = clip_into(moved, self.lower, self.upper)
            theta, count, spent = self._pass(self._phi(moved, centre, unit), centre, unit, deadline)
            used += count
            tried.append(self.outcome(start, theta, finished=not spent, status="converged", message="",
                                      iterations=nfev + used, wall_time=time.perf_counter() - t0))
        if not tried:
            return None
        groups = []
        for mask, what in ((unfelt, "unfelt by the response"), (edge, "run 1e6 times from the start"),
                           (far, f"more than {FAR:g} times from the typical values")):
            names = ", ".join(n for n, w in zip(self.model.parameter_names, mask, strict=True) if w)
            if names:
                groups.append(f"{names} {what}")
        return (f"; {'; '.join(groups)}: {len(tried)} pass(es) with them × 0.1 … 1000 ended at best misfit ",
                tried, used)

    def _far(self, theta: np.ndarray, unit: np.ndarray) -> np.ndarray:
        """The positive parameters more than :data:`FAR` times above or below their typical values (``scale=``; none
        without it: a fit far from a start that was only a guess is no sign of a limit): choice 9."""
        if self.scale is None:
            return np.zeros(theta.size, dtype=bool)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.abs(np.log(np.abs(theta) / unit))
        return self._positive & ~(ratio <= math.log(FAR))

    def _black_box_theta(self) -> np.ndarray | None:
        """The black-box start of :func:`~symid.fit.frf.modal.black_box_start` (read once), or None."""
        if not self._bb_read:
            from symid.fit.frf.modal import black_box_start

            self._bb_read = True
            try:
                found = black_box_start(self.model, self.data, self.scale, seed=self.options["seed"])
            except (ModelError, np.linalg.LinAlgError, ValueError):
                found = None
            self._bb_theta = None if found is None else np.asarray(found.theta, dtype=float)
        return self._bb_theta

    def _on_bounds(self, theta: np.ndarray) -> str:
        """Which entries of the estimate sit on the user's bounds ('' without bounds)."""
        if not self._bounded:
            return ""
        return on_bounds(theta, self.lower, self.upper, self.model.parameter_names, self._positive)

    def _cleaner_than(self, best: StartOutcome) -> bool:
        """Whether the data are cleaner than ``best``, a fit the success rule refuses: a black box of the model's
        order fits them more than :func:`~symid.fit.success.black_box_ratio` times better. The minimum found
        again is then a local one (measured: 3 passes of a 3-mass chain measured away from the driven mass ended at
        misfit 2.1e-8 on exact data, 120 % off, and the restarts stopped there after 3 s of a 45 s budget)."""
        if best.success:
            return False
        bb = self.black_box()
        ratio = black_box_ratio(bb, n_data=self.n_data(), n_parameters=self.model.n_parameters)
        return ratio is not None and best.cost > ratio * bb[0]

    def polisher(self) -> Any:
        """IPOPT on the same frequency response, noise weighting and bounds (:class:`~symid.fit.frf.ipopt.IpoptFRF`)."""
        from symid.fit.frf.ipopt import IpoptFRF

        bounds = np.column_stack([self.lower, self.upper]) if self._bounded else None
        return IpoptFRF(self.model, self.data, variance=self._variance, bounds=bounds,
                        positivity=self.options["positivity"])


class AutoFRF(LmFRF):
    __doc__ = (LmFRF.__doc__ or "").replace("Levenberg–Marquardt (trust-region reflective) on log-parameters, "
                                            "optionally restarted.",
                                            "The default: Levenberg–Marquardt on log-parameters, restarted around "
                                            "the start until the estimate fits.")
    method: ClassVar[str] = "auto"
    default_restarts: ClassVar[int] = 30
    default_bands: ClassVar[int] = 8
    default_time_limit: ClassVar[float | None] = 120.0
    default_chain_start: ClassVar[bool] = True
    default_confirm: ClassVar[int] = 4
    _rescue: ClassVar[bool] = True


LmFRF.__doc__ = (LmFRF.__doc__ or "").format(variance=VARIANCE_OPTION_DOC)
AutoFRF.__doc__ = (AutoFRF.__doc__ or "").format(variance=VARIANCE_OPTION_DOC)
