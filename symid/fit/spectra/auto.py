"""``method="auto"`` on spectra: IPOPT on (5-13) with restarts around the typical values, then SCR when none fits.

Why this order (measured on shear buildings in SI units, ``benchmarks/psd_units.py``):
IPOPT on the output-spectrum misfit reaches the truth from most starts in a fraction of a
second (15 of 18 exact, 18 of 18 at 2 % noise, 0.23 s a start), SCR with its ADMM back end
from more exact starts but fewer noisy ones and at 4.6 s a start (17 and 15 of 18). A pass
of IPOPT that does not fit is followed by others from draws log-uniform within a factor
``spread`` of the typical values (``scale=``, else the spectra's own,
:func:`symid.fit.spectra.scale.typical_scale`), each drawn from the start's own stream; the
first that fits ends the start. When none does and Algorithm 5.1 applies (a full set of
known sensors, B known), SCR runs once (the ADMM back end) and IPOPT polishes its estimate:
the relaxation does not depend on a start, which is what the restarts lack. Every pass
counts against ``time_limit``, and the best pass is reported with the others in
``passes``. It is the default on spectra: on the buildings of ``benchmarks/psd_auto.py``
(2 to 4 storeys in SI units, measured in position, in acceleration and in both; 18 problems,
three starts each, exact and 2 % noise; 30 s a start) it met the success rule from 54 of 54
exact and 53 of 54 noisy starts (the miss: its 30 s spent), IPOPT alone from 39 and 42, SCR
(ADMM) from 51 and 21; median 0.36 s a start (IPOPT 0.28, SCR 4.4), time to solution 2.2 s
(IPOPT 1.7, SCR 15).
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from typing import Any, ClassVar

import numpy as np

from symid.errors import ModelError, SymidError
from symid.fit.options import (
    check_bool,
    check_choice,
    check_float,
    check_int,
    check_scale,
    check_seed,
    check_time_limit,
)
from symid.fit.result import StartOutcome
from symid.fit.spectra.equations import SpectraEstimator, check_spectral
from symid.fit.spectra.welch import VARIANCE_ROUNDS, data_weights, spectra_averages

__all__ = ["AutoPSD"]


class AutoPSD(SpectraEstimator):
    """IPOPT with restarts, then SCR, on spectra (module notes).

    Parameters
    ----------
    model : SecondOrderModel
    data : SpectralData
    scale : array_like, optional
        Typical magnitude of each parameter: where restarts are drawn, and IPOPT's scaling.
        Default: the spectra's typical values.
    bounds : dict or array_like, optional
        As IPOPT's (held by every pass; SCR's estimate is clipped into them before its polish).
    positivity : bool
        θₖ ≥ 0 for parameters declared positive (default True).
    restarts : int
        IPOPT passes after the first, from draws around the typical values (default 8).
    spread : float
        Draws lie log-uniformly within this factor of the typical values (default 10).
    scr : bool
        Run SCR (ADMM back end) when no IPOPT pass fits and Algorithm 5.1 applies (default True).
    seed : int
        Seeds the draws (with the start, so every start draws its own).
    weighting : {"auto", "none", "variance"}
        The misfit's weights (as IPOPT's, :class:`~symid.fit.spectra.ipopt.IpoptPSD`):
        ``"variance"`` weighs each entry by its scatter in a Welch estimate and judges the
        fit against the noise of the averages; the passes run in the measured
        auto-spectra's weights, the best is then reweighted at its estimate
        (:mod:`symid.fit.spectra.welch`). ``"auto"`` (default): ``"variance"`` where the
        number of averages is known (``averages=``, or the spectra estimated by
        :func:`symid.estimate_spectra` from output records with a given input spectrum),
        else ``"none"``, the equal weights of (5-13).
    averages : float, optional
        The independent averages behind each line (as IPOPT's).
    sensor_noise : {"auto", True, False}
        Fit a white noise on each output's auto-spectrum beside the model's (as IPOPT's);
        ``"auto"`` (default): with ``weighting="variance"``, whose weights let the lines
        where sensor noise dominates carry the fit otherwise.
    pass_iter : int
        IPOPT's iteration limit in each pass (default 500; IPOPT's own default for one
        run is 3000).
    time_limit : float, optional
        Wall-time budget of one start, every pass included, in seconds (default 300).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.spectra.auto import AutoPSD
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> spec = si.simulate_spectra(model, [1.0, 0.5, 4.0], np.linspace(0.5, 3, 8), Phi_uu=1.0)
    >>> out = AutoPSD(model, spec).run(np.array([30.0, 0.01, 0.1]))
    >>> bool(out.success), np.round(out.theta, 4)
    (True, array([1. , 0.5, 4. ]))
    """

    method: ClassVar[str] = "auto"

    def __init__(self, model: Any, data: Any, *, scale: Any = None, bounds: Any = None, positivity: bool = True,
                 restarts: int = 8, spread: float = 10.0, scr: bool = True, seed: int = 0, weighting: str = "auto",
                 averages: float | None = None, sensor_noise: Any = "auto", pass_iter: int = 500,
                 time_limit: float | None = 300.0):
        from symid.fit.spectra.ipopt import IpoptPSD

        check_spectral(model, data)
        self.model, self.data = model, data
        l = model.n_parameters
        self.scale = None if scale is None else check_scale("scale", scale, l)
        self.restarts = check_int("restarts", restarts, low=0, high=10_000)
        self.spread = check_float("spread", spread, low=1.0)
        self.use_scr = check_bool("scr", scr)
        self.seed = check_seed("seed", seed)
        self.time_limit = check_time_limit("time_limit", time_limit)
        self.pass_iter = check_int("pass_iter", pass_iter, low=1, high=10**7)
        weighting = check_choice("weighting", weighting, ("auto", "none", "variance"))
        if averages is not None:
            averages = check_float("averages", averages, low=1.0)
        known = averages if averages is not None else spectra_averages(data)
        if weighting == "auto":
            weighting = "variance" if known is not None else "none"
        if isinstance(sensor_noise, str):
            sensor_noise = check_choice("sensor_noise", sensor_noise, ("auto",)) and weighting == "variance"
        self._ipopt = IpoptPSD(model, data, scale=self.scale, bounds=bounds, positivity=positivity,
                               max_iter=self.pass_iter, weighting=weighting, averages=averages,
                               sensor_noise=check_bool("sensor_noise", sensor_noise))
        self.averages, self.sensor_noise = self._ipopt.averages, self._ipopt.sensor_noise
        # weighted by the scatter, each pass first runs with each frequency's term divided by its own measured
        # ‖Φyyᵢ‖² (IPOPT's weighting="frequency", no sensor noise): from a start within a factor 3 of a footbridge's
        # truth (30 % sensor noise) the passes in the scatter's weights, with or without the noise, and the equal
        # weights all ended in another basin (m1 75-100 % low, c2 at 0 or doubled); per frequency, at the truth's
        self._plain = (IpoptPSD(model, data, scale=self.scale, bounds=bounds, positivity=positivity,
                                max_iter=self.pass_iter, weighting="frequency")
                       if weighting == "variance" else None)
        self.lower, self.upper = self._ipopt.lower, self._ipopt.upper
        self.options = {"scale": None if self.scale is None else self.scale.tolist(),
                        "bounds": self._ipopt.options["bounds"], "positivity": positivity,
                        "restarts": self.restarts, "spread": self.spread, "scr": self.use_scr, "seed": self.seed,
                        "weighting": weighting, "averages": self.averages, "sensor_noise": self.sensor_noise,
                        "pass_iter": self.pass_iter,
                        "time_limit": self.time_limit}
        self._typical: np.ndarray | None = self.scale
        self._scr_estimator: Any = None
        self._share_weights()

    def _share_weights(self) -> None:
        """This estimator's misfit (and success rule, and uncertainty) in the weights its IPOPT passes have."""
        self.set_entry_weights(self._ipopt.entry_weights)

    def reweigh_relative(self, theta: Any) -> None:
        """With ``weighting="variance"``: the weights of the model's spectra at θ, here and in the passes."""
        self._ipopt.reweigh_relative(theta)
        self._share_weights()

    def check_start(self, x0: Any) -> None:
        """Refuse a start outside the bounds (an :class:`OptionError` naming the parameter)."""
        self._ipopt.check_start(x0)

    def _typical_values(self, x0: np.ndarray) -> np.ndarray:
        """Where the restarts are drawn: ``scale``, else the spectra's typical values, else |x0| (1 where 0)."""
        if self._typical is None:
            from symid.fit.spectra.scale import typical_scale

            try:
                self._typical = typical_scale(self.model, self.data)
            except (SymidError, ValueError, np.linalg.LinAlgError):
                self._typical = None
        if self._typical is not None:
            return np.asarray(self._typical, dtype=float)
        return np.where(np.abs(x0) > 0, np.abs(x0), 1.0)

    def _scr(self, time_limit: float | None) -> Any:
        """SCR's estimator (ADMM back end) with this budget, or None where Algorithm 5.1 does not apply."""
        if self._scr_estimator is False:
            return None
        from symid.fit.spectra.scr import ScrPSD

        try:
            return ScrPSD(self.model, self.data, backend="admm", positivity=self.options["positivity"],
                          time_limit=time_limit)
        except ModelError:
            self._scr_estimator = False  # not applicable to this model: not asked again
            return None

    def run(self, x0: np.ndarray) -> StartOutcome:
        """IPOPT from ``x0``, then from draws, then SCR and a polish, until one pass fits (module notes)."""
        t0 = time.perf_counter()
        x0 = np.asarray(x0, dtype=float)
        passes: list[StartOutcome] = []
        words: list[str] = []

        def left() -> float | None:
            return None if self.time_limit is None else self.time_limit - (time.perf_counter() - t0)

        def spent() -> bool:
            rest = left()
            return rest is not None and rest <= 0

        def ipopt_from(start: np.ndarray, rounds: int = 0) -> StartOutcome:
            start = np.clip(start, self.lower, self.upper)
            rest = left()  # a pass begun with the budget nearly spent (a polish after SCR) still gets a second
            if self._plain is not None and not rounds:  # per frequency first (see __init__)
                first = self._plain.run(start, time_limit=None if rest is None else max(rest, 1.0), rounds=0)
                if np.all(np.isfinite(first.theta)):
                    start = np.clip(first.theta, self.lower, self.upper)
                rest = left()
            return self._ipopt.run(start, time_limit=None if rest is None else max(rest, 1.0), rounds=rounds)

        variance = self.options["weighting"] == "variance"
        if variance:  # every start from the measured auto-spectra's weights
            self._ipopt.set_entry_weights(data_weights(self.data))
            self._share_weights()
        out = ipopt_from(x0)
        passes.append(out)
        words.append("pass 0 from the start")
        if not out.success and self.restarts and not spent():
            typical = self._typical_values(x0)
            # the start's own stream: the same start draws the same restarts whatever else runs
            digest = np.frombuffer(np.round(x0, 12).tobytes(), dtype=np.uint32)
            rng = np.random.default_rng([self.seed, *digest.tolist()])
            for k in range(1, self.restarts + 1):
                if spent():
                    words.append("time limit")
                    break
                draw = typical * np.exp(rng.uniform(-np.log(self.spread), np.log(self.spread), typical.size))
                out = ipopt_from(draw)
                passes.append(out)
                if out.success:
                    words.append(f"pass {k} from a draw around the typical values")
                    break
        if (not any(p.success for p in passes) and self.use_scr and not spent()
                and (scr := self._scr(None if left() is None else max(left(), 1.0))) is not None):
            with warnings.catch_warnings():  # its own warnings (many lines for Clarabel) are not this method's
                warnings.simplefilter("ignore")
                relaxed = scr.run(min(passes, key=lambda p: p.cost).theta)
            if variance:  # SCR's own misfit is the unweighted one: compared with the passes in theirs
                relaxed = self.outcome(relaxed.start, relaxed.theta, finished=relaxed.finished, status=relaxed.status,
                                       message=relaxed.message, iterations=relaxed.iterations,
                                       wall_time=relaxed.wall_time)
            polished = ipopt_from(relaxed.theta) if np.all(np.isfinite(relaxed.theta)) else relaxed
            passes.extend([relaxed, polished])
            words.append("SCR (ADMM) and IPOPT from its estimate")
        best = next((p for p in passes if p.success), None) or min(passes, key=lambda p: p.cost)
        if variance and np.all(np.isfinite(best.theta)) and not spent():
            # weights from the model's spectra at the best estimate, not the measured ones (symid.fit.spectra.welch)
            # it replaces the pass it started from: that estimate, in other weights, is no alternative to it
            reweighted = ipopt_from(best.theta, rounds=VARIANCE_ROUNDS)
            passes[next(i for i, p in enumerate(passes) if p is best)] = reweighted
            best = reweighted
            words.append("the best reweighted by the model's spectra at its estimate")
            self._share_weights()
        others = tuple(p for p in passes if p is not best)
        message = (f"{len(passes)} pass(es); " + "; ".join(words) + f"; best: {best.status}")
        result = self.outcome(x0, best.theta, finished=best.finished, status=best.status, message=message,
                              iterations=sum(p.iterations for p in passes), wall_time=time.perf_counter() - t0)
        return dataclasses.replace(result, passes=others)

    def polisher(self) -> Any:
        """IPOPT on (5-13), as the passes."""
        return self._ipopt
