"""Output error restarted until the estimate fits: the default for time series.

Output-error fitting (:mod:`symid.fit.timeseries.oe`) from a start a factor of a few off
often ends in a local minimum: on generated models with physical values, one run from a
start within a factor 10 of typical values missed the success rule from 9 of 16 such
starts (misfits of 2e-3 to 1, parameters 6 to 10⁷ times off, on chains, chains with
gains, compartment and state-space models). ``auto`` runs output error from the start, and while
the estimate does not fit the samples (the success rule of :mod:`symid.fit.success`) it
restarts from points drawn log-uniformly within a factor ``spread`` of the start — every
other one within that factor of the typical values ``scale`` when they are given — until
one fits, ``restarts`` passes are spent, or ``time_limit`` (the start's whole budget) is
reached. The outcome is the best fit found; every pass's time counts in the start's.
A restart is drawn again (up to ``DRAW_TRIES`` times) until the model's response to the
records is finite there: no solver can start where the simulation overflows, and for a
first-order network with symmetric couplings (``benchmarks/timeseries_population.py``'s
state-space class) 8 % of the draws within a factor 3 of a start whose couplings exceed
its rates were stable, so every restart of one such start failed at once
("Invalid_Number_Detected"); with finite draws it fitted after 4 passes.

A start from a black box (``black_box_start``, :mod:`symid.fit.timeseries.bbstart`): on one
uniformly sampled record, the model fitted by the frequency-response ``auto`` to the
continuous-time response of an N4SID black box of the model's order is the start of one
more pass. On noise-free records (the black box predicts them to ``CLEAN_RECORD``) it is
the first pass, unless the start already fits exactly, and the pass from the start comes
second unless the first fits to rounding. On noisy records the pass from the start comes
first, and the black box's start is sought only when that pass does not predict the
samples as well as the black box itself does: a new user's room model (three thermal
nodes, a record over days) had a black box predicting to 3.6e-5 and a pass from the start
to 9.1e-6, and the response fit spent 10.9 s of a 13.6 s start for nothing (now 1.2 s).
Both passes run otherwise (the first fit may be a worse minimum that the whiteness rule
accepts), so the order changes no estimate there. A start that predicts the samples
worse than zero does (relative misfit ≥ 1) is no start: the black box's then comes
first (a new user's sampled quarter car: the pass from a start at misfit 324 crawled for
the whole 120 s, and the black box's start was "not run: the budget was spent"; first,
it brought every parameter within 0.9 %). Measured on ``benchmarks/timeseries_population.py``
(chains, chains with gains, compartment and state-space models, n = 2 and 3, one informed
and one uninformed start each, noise-free and 1 %, 60 s per start): ``auto`` met the
success rule from 29 of 32 starts with it (noise-free 16/16, 1 % 13/16), 24 of 32
without (noise-free 12/16), in a median 8.1 s per start against 13.8 s. The frequency-response
fit is what ``auto`` does best (continuation over frequency, chain starts), and the black
box of noise-free records is the model's own response: every noise-free start met the
rule, where without it output error's restarts had ended at near-fits within the budget
on four (3-mass chains, a chain with gains, a 3-state network).

Why not the black-box route as the estimate (N4SID, exact ``d2c``, then a similarity
formulation), the default before: on the same problems it met the success rule from 5
starts, one output-error run from 18; it refused 14 (acceleration outputs, parameters in
B, a sampled model with no real logarithm), and it cannot take a model whose realisation
is not minimal or non-uniform sample times. A black box of noisy records can misplace a
weakly observable mode (a 3-mass chain at 1 %: 594 rad/s for 188), which is why its fit is
a start judged by output error on the samples, never the estimate.
Also measured and not kept: skipping the pass from the start after a fit from the black box
that predicts the samples within 1 + b/N of the black box's own misfit (b its real
parameters, N the values; a new user's 4000-sample motor: 28 → 5.6 s, the same estimate).
On the time-series population (``--out timeseries_skip_confirm.json``,
``benchmarks/results/timeseries_skip_confirm.json``) it lost 3 of 12 noisy successes (fits
within that margin but 0.05 % above the least-squares misfit: a 3-mass chain, a
5-compartment model from both starts) for noisy starts 270 → 200 s in all.
Also measured and not kept: confirming a noisy fit by more restarts (until a second pass
ends at its misfit, or 4 passes after the first fit, as the frequency-response ``auto``
does): on the time-series population at 1 % (n = 2, 3, two informed and two uninformed
starts per problem, 60 s each) 15 of 16 informed and 14 of 16 uninformed starts met the
success rule against 14 and 14 without; the one gained was a 3-mass chain whose misfit fell
just below the reference's at 47 times its parameter error (the rule's misfit clause on a
sloppy problem, not a better estimate), and the median time per chain start grew from 7.7
to 16.5 s. Restarts drawn around the start did not reach the least-squares estimate where
the first pass stopped short of it (a 2-mass chain driven by a band-limited multisine: four
more passes, none below the first fit).
Also measured and not kept: a frequency response estimated from the record (Welch,
:func:`symid.estimate_frf`) fitted by the frequency-response ``auto`` as a start for
output error — the estimate's bias from the zero-order hold and its coarse resolution of
lightly damped modes left it 4 to 10⁶ relative error off on 2- and 3-mass chains.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any, ClassVar

import numpy as np

from symid.fit.bounded import clip_into, on_bounds
from symid.fit.options import check_bool, check_float, check_int, check_seed, check_time_limit, moved_onto_bounds
from symid.fit.result import StartOutcome
from symid.fit.success import EXACT_FIT
from symid.fit.timeseries.bbstart import CLEAN_RECORD, BlackBoxResponse, black_box_response, black_box_start
from symid.fit.timeseries.oe import OutputError

__all__ = ["AutoOutputError"]


class AutoOutputError(OutputError):
    """Output error from the start, restarted around it until the estimate fits the samples.

    Parameters
    ----------
    model, data, initial_state, positivity, bounds, variance, hold, solver, hessian, max_iter, tol, callback, verbose
        As for :class:`~symid.fit.timeseries.oe.OutputError` (each pass is one output-error run;
        ``solver="trf"`` by default: 30 of 32 starts of the time-series population met the
        success rule against 28 with IPOPT's passes, in a median 2.1 s against 7.0 s).
    scale : array_like, optional
        Typical magnitude of each parameter: every other restart is drawn around it (and
        each pass scales its unknowns by it, as ``OutputError`` does). Default: restarts
        around the start only.
    restarts : int, optional
        Passes from random restarts after the pass from the start (and the one from the
        black box, ``black_box_start``), at most (default 10).
    spread : float, optional
        Restarts are drawn log-uniformly within this factor of the start (or of ``scale``);
        parameters that may be negative get the start ± spread × their magnitude (1
        where it is 0). Default 10.
    seed : int, optional
        Seed of the restarts (with the start itself: the same start gives the same passes).
    time_limit : float, optional
        Wall-time budget of the whole start in seconds, every pass included (default 120).
    black_box_start : bool, optional
        On one uniformly sampled record, one more pass starts from the model fitted to
        an N4SID black box's response (:mod:`symid.fit.timeseries.bbstart`; that fit is
        counted in passes, with half the budget as a safety). Noise-free records: the
        first pass, unless the start already fits exactly and no worse; the start gets the
        second unless the first fits to rounding. Noisy records: the second, and only when
        the pass from the start does not predict the samples as well as the black box does
        (default True).
    black_box_decimation : bool, optional
        Estimate that black box also on the record decimated, when the input leaves most
        of the band empty (a multisine up to 0.4 of the Nyquist frequency), where N4SID's
        projection is ill-conditioned and noise misplaces every mode
        (:func:`symid.fit.timeseries.bbstart.input_decimation`; the black box predicting
        the record best is kept). Default False: measured on the time-series population
        driven by such an input it lost noisy starts on chains (module notes of
        :mod:`symid.fit.timeseries.bbstart`); a poor black box on such an input names it
        in the start's note.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> u = np.random.default_rng(0).standard_normal(600)
    >>> io = si.simulate_io(model, {"m": 2.0, "c": 0.8, "k": 50.0}, u, dt=0.05)
    >>> res = si.identify(model, io, x0={"m": 1.0, "c": 1.0, "k": 10.0}, identifiability_check=False)
    >>> res.method, [round(v, 6) for v in res.theta.values()], res.success
    ('auto', [2.0, 0.8, 50.0], True)
    """

    method: ClassVar[str] = "auto"
    DRAW_TRIES: ClassVar[int] = 100
    """Draws tried for a restart at which the model's response is finite (module notes)."""
    BLACK_BOX_SHARE: ClassVar[float] = 0.5
    """The share of the start's budget after which the black-box start's response fit stops (a safety: its passes
    are counted, so that the start does not depend on the machine's load)."""

    def __init__(self, model: Any, data: Any, *, initial_state: Any = None, scale: Any = None,
                 positivity: bool = True, hessian: str = "auto", max_iter: int = 500, tol: float = 1e-12,
                 time_limit: float | None = 120.0, callback: Any = None, verbose: bool = False,
                 restarts: int = 10, spread: float = 10.0, seed: int = 0, black_box_start: bool = True,
                 solver: str = "trf", bounds: Any = None, variance: Any = None, hold: Any = "zoh",
                 black_box_decimation: bool = False):
        budget = check_time_limit("time_limit", time_limit)
        super().__init__(model, data, initial_state=initial_state, scale=scale, positivity=positivity,
                         hessian=hessian, max_iter=max_iter, tol=tol, time_limit=budget, callback=callback,
                         verbose=verbose, solver=solver, bounds=bounds, variance=variance, hold=hold)
        self._budget = budget
        self._restarts = check_int("restarts", restarts, low=0, high=10**6)
        self._spread = check_float("spread", spread, low=1.0)
        self._seed = check_seed("seed", seed)
        self._verbose_passes = bool(verbose)
        self._black_box_start = check_bool("black_box_start", black_box_start)
        self._decimate = check_bool("black_box_decimation", black_box_decimation)
        self._bb_response: BlackBoxResponse | None = None  # black_box_response's answer, computed once
        self._positive = np.asarray(model.positive, dtype=bool) & self._positivity
        self.options = {**self.options, "time_limit": budget, "restarts": self._restarts, "spread": self._spread,
                        "seed": self._seed, "black_box_start": self._black_box_start,
                        "black_box_decimation": self._decimate}

    def _draw(self, rng: np.random.Generator, centre: np.ndarray) -> np.ndarray:
        half = math.log(self._spread)
        mag = np.where(np.abs(centre) > 0, np.abs(centre), 1.0)
        positive = centre * np.exp(rng.uniform(-half, half, centre.size))
        positive = np.where(np.abs(centre) > 0, positive, np.exp(rng.uniform(-half, half, centre.size)))
        free = centre + self._spread * mag * rng.uniform(-1.0, 1.0, centre.size)
        return np.where(self._positive, positive, free)

    def _finite_draw(self, rng: np.random.Generator, centre: np.ndarray) -> np.ndarray:
        """A restart drawn around ``centre`` at which the model can be simulated (finite misfit): the first of at most
        ``DRAW_TRIES`` draws, else the last (its pass then fails at once: no solver can start from it)."""
        theta = self._draw(rng, centre)
        for _ in range(self.DRAW_TRIES - 1):
            if np.isfinite(self.misfit(theta)):
                break
            theta = self._draw(rng, centre)
        return theta

    def _black_box_special(self, start: np.ndarray, first: StartOutcome | None,
                           t0: float) -> tuple[np.ndarray | None, str]:
        """The start read off the black box (module notes), or None and why; none is sought when the pass from the
        start fits and predicts the samples at least as well as the black box itself does."""
        limit = None if self._budget is None else self.BLACK_BOX_SHARE * self._budget
        if self._bb_response is None:  # the black box's response is the records', the same for every start
            self._bb_response = black_box_response(self.model, self.data, self._decimate)
        floor = self._bb_response.record_misfit
        if first is not None and self._bb_response.frf is not None and first.success and math.isfinite(floor):
            plain = self._plain_misfit(first.theta)
            if plain <= floor:
                return None, (f"no black-box start sought: the pass from the start predicts the samples at least as "
                              f"well as the N4SID black box of the model's order (misfit {plain:.2e}, the black "
                              f"box's {floor:.2e})")
        if self._verbose_passes:
            print("auto: fitting the model to an N4SID black box's response", flush=True)
        found = black_box_start(self.model, self.data, start, scale=self.scale, time_limit=limit,
                                response=self._bb_response, decimate=self._decimate)
        if self._verbose_passes:
            print(f"auto: {found.note}, {time.perf_counter() - t0:.2f} s", flush=True)
        if found.theta is None:
            return None, found.note
        at_bb = self.misfit(found.theta)
        if not np.isfinite(at_bb):
            return None, "no black-box start: the model cannot be simulated at its response fit"
        if at_bb >= 1:  # the relative misfit of predicting zero: a pass from there would start from nothing
            return None, (f"no black-box start: its response fit predicts the samples no better than zero "
                          f"(misfit {at_bb:.3g})")
        return found.theta, found.note

    def _plain_misfit(self, theta: np.ndarray) -> float:
        """Σ (ŷ − y)² / Σ y² over every output and record, unweighted: the measure of the black box's own misfit."""
        try:
            with np.errstate(all="ignore"):
                sims = self.simulate(theta)
                pairs = list(zip(self.records, sims, self.observed, strict=True))  # measured values only
                err = sum(float(np.sum(np.where(o, s - r.y, 0.0) ** 2)) for r, s, o in pairs)
                power = sum(float(np.sum(np.where(o, r.y, 0.0) ** 2)) for r, _, o in pairs)
        except (np.linalg.LinAlgError, ValueError):
            return math.inf
        return err / power if power > 0 and math.isfinite(err) else math.inf

    def run(self, x0: np.ndarray) -> StartOutcome:
        """Output-error passes from ``x0`` and restarts around it until the estimate fits or the budget is spent."""
        t0 = time.perf_counter()
        start = np.asarray(x0, dtype=float).reshape(-1)
        moved = ""
        if self._bounded:  # a drawn start outside the bounds begins on them (a user's own was refused)
            moved = moved_onto_bounds(start, self.lower, self.upper, self.model.parameter_names)
        given, start = start, clip_into(start, self.lower, self.upper) if moved else start
        deadline = None if self._budget is None else t0 + self._budget
        rng = np.random.default_rng([self._seed, *np.frombuffer(start.tobytes(), dtype=np.uint32)])
        best: StartOutcome | None = None
        visited: list[StartOutcome] = []
        iterations, passes, status = 0, 0, "max_restarts"

        def spent() -> bool:
            return deadline is not None and time.perf_counter() >= deadline

        def one_pass(theta0: np.ndarray, label: str) -> StartOutcome:
            nonlocal best, iterations, passes
            self._time_limit = None if deadline is None else max(deadline - time.perf_counter(), 1e-3)
            try:
                cand = OutputError.run(self, theta0)
            finally:
                self._time_limit = self._budget
            passes += 1
            iterations += cand.iterations
            visited.append(cand)
            if best is None or cand.cost < best.cost:
                best = cand
            if self._verbose_passes:
                print(f"auto pass {passes - 1} ({label}): misfit {cand.cost:.3e}, "
                      f"{'fits' if cand.success else 'does not fit'}, {time.perf_counter() - t0:.2f} s", flush=True)
            return cand

        def exact() -> bool:
            return best is not None and best.success and best.cost <= EXACT_FIT

        bb_pass, bb_note = None, ""
        clean = False
        if self._black_box_start:
            if self._bb_response is None:  # the black box's response is the records', the same for every start
                self._bb_response = black_box_response(self.model, self.data, self._decimate)
            clean = self._bb_response.frf is not None and self._bb_response.record_misfit <= CLEAN_RECORD
        if clean:
            # noise-free records: the black box's response is the model's, and its fit is usually the truth; its
            # pass first, unless the start already fits exactly and no worse, and the start's unless one fits to
            # rounding
            theta_bb, bb_note = self._black_box_special(start, None, t0)
            order: list[tuple[np.ndarray, str]] = [(start, "from the start")]
            if theta_bb is not None:
                at_start = self.misfit(start)
                bb_first = not (at_start <= EXACT_FIT and at_start <= self.misfit(theta_bb))
                order.insert(0 if bb_first else 1, (theta_bb, "from the black box"))
            for k, (theta0, label) in enumerate(order):
                if k > 0 and (exact() or spent()):
                    if label == "from the black box":
                        bb_note += ", not run: " + ("the budget was spent" if spent() else
                                                    "the pass from the start fitted to rounding")
                    break
                if label == "from the black box":
                    bb_pass = passes
                one_pass(theta0, label)
        else:
            # noisy records (or none N4SID takes): the pass from the start first; the black box's start is sought
            # only when that pass does not predict the samples as well as the black box does (a new user's room
            # model: its response fit took 10.9 s of a 13.6 s start whose own pass, 0.3 s, predicted better)
            at_start = self.misfit(start)
            if self._black_box_start and not at_start < 1:
                # a start that predicts the samples worse than zero does is no start: the black box's first (a new
                # user's quarter car, sampled: the pass from a start at misfit 324 crawled for the whole budget,
                # and the black box's start, fitted already, was "not run: the budget was spent")
                theta_bb, bb_note = self._black_box_special(start, None, t0)
                if theta_bb is not None:
                    bb_pass = passes
                    bb_note += f" (run first: the start predicts the samples worse than zero, misfit {at_start:.3g})"
                    one_pass(theta_bb, "from the black box")
                if best is None or not (exact() or spent()):
                    one_pass(start, "from the start")
            else:
                one_pass(start, "from the start")
                if self._black_box_start and not exact():
                    first = visited[0]
                    theta_bb, bb_note = self._black_box_special(start, first, t0)
                    if theta_bb is not None:
                        if spent():
                            bb_note += ", not run: the budget was spent"
                        else:
                            bb_pass = passes
                            one_pass(theta_bb, "from the black box")
        # random restarts until one fits
        if best.success:
            status = "fits"
        else:
            for j in range(1, self._restarts + 1):
                if spent():
                    status = "time_limit"
                    break
                # the first random restart is drawn around the typical values
                around = self.scale if (self.scale is not None and j % 2 == 1) else start
                if one_pass(self._finite_draw(rng, np.asarray(around, dtype=float)), f"restart {j}").success:
                    status = "fits"
                    break
        assert best is not None
        note = f"; {bb_note}" if bb_pass is None and bb_note else (
            f"; pass {bb_pass} from {bb_note}" if bb_pass is not None else "")
        what = {"fits": f"a fit after {passes} output-error pass(es)",
                "max_restarts": f"no fit in {passes} output-error pass(es) (restarts={self._restarts})",
                "time_limit": f"time limit of {self._budget:g} s reached after {passes} pass(es)"}[status]
        bounds_note = on_bounds(best.theta, self.lower, self.upper, self.model.parameter_names,
                                self._positive) if self._bounded else ""
        out = self.outcome(given, best.theta, finished=status != "time_limit", status=status,
                           message=f"{what}; best pass: {best.status}{note}{moved}{bounds_note}",
                           iterations=iterations,
                           wall_time=time.perf_counter() - t0)
        others = tuple(c for c in visited if c is not best)
        return dataclasses.replace(out, passes=others) if others else out
