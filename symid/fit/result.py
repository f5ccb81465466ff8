"""Result types shared by every estimation method, so methods compare like for like.

``success`` means the same thing everywhere: the estimate fits the data and nothing the
model declares rules it out (:mod:`symid.fit.success`). Whether the solver reached its
own stopping rule is reported beside it, in ``finished``, ``status`` and ``message``,
never instead of it: a start stopped by its budget whose estimate fits is a success.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["IdentificationResult", "ScrIteration", "StartOutcome"]


def _relative_difference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """|a − b| / max(|a|, |b|) per entry (0 where both are 0): at most 2, and 1 when one of them is 0."""
    top = np.maximum(np.abs(a), np.abs(b))
    return np.divide(np.abs(a - b), top, out=np.zeros_like(top), where=top > 0)


_NEXT_STEPS = (
    ("pulled beyond the bounds", "the data want values beyond the bounds the estimate sits on (the fit line names "
                                 "them): check the data's units first (a frequency in Hz read as rad/s, a time in ms "
                                 "read as s) and the model's structure; widen the bounds only if the physics allows"),
    ("not physical", "the estimate breaks what the model declares (the fit line says what): try other starts "
                     "(starts=20) or bounds that keep it admissible"),
    ("black box", "a model of this order fits the data far better than this estimate, which is a local minimum or "
                  "stopped short: try more starts (starts=20), method='auto' with scale= your typical values, or "
                  "polish=True"),
    ("Gauss–Newton", "the estimate is not at a minimum of the misfit (a local step would lower it much): "
                     "polish=True, or method='ipopt' started from it"),
    ("structured", "the residual is smooth across frequency: a local minimum, or noise that grows with |H|; with "
                   "noisy data give variance= (si.estimate_frf returns it) or noise_floor= (1e-4 for 1 % noise), "
                   "otherwise try more starts or method='auto' with scale=, and check that the model describes the "
                   "data (its matrices, the data's units). A statistic just above the limit can "
                   "be chance: the least-squares estimate of a true model exceeded it in 1 of 300 records at 1 % "
                   "noise (a 3-storey building, at 3.1)"),
    ("residual is white", "the residual looks like noise, not like a wrong model: if the data are that noisy, "
                          "give noise_floor= the misfit such noise leaves (about this misfit; variance= for noise "
                          "that varies), and the fit is judged against it; if they are not, try more starts "
                          "(starts=20) and check the model's structure and the data's units"),
    ("over 10 %", "far from a fit: try more starts (starts=20), method='auto' with scale= your typical values, and "
                  "check the model's structure and the data's units; if the data are that noisy (over 10 % rms), "
                  "give noise_floor= (0.01 for 10 % noise) so that the fit is judged against the noise"),
    ("χ²", "the misfit exceeds what the declared noise explains: a local minimum (more starts, "
           "method='auto'), a noise_floor/variance smaller than the data's noise, or a model that does not "
           "describe the data (check its matrices, and how the data were made: units, a sampled input taken as "
           "held)"),
    ("pass noise_floor=", "without a noise level only an exact fit counts: give noise_floor= (the relative misfit "
                          "the noise leaves, 1e-4 for 1 % noise) to judge a fit of noisy data"),
)


_FRF_ONLY = {  # advice that only a frequency response can follow, and what to say for other data instead
    "method='auto' with scale= your typical values": "other methods (si.compare) or starts nearer your typical values",
    "method='auto' with scale=": "other methods (si.compare)",
    "method='auto'": "other methods",
    "give variance= (si.estimate_frf returns it) or noise_floor=": "give noise_floor=",
}


_IN_TIME = {  # the advice for residuals ordered in time (measured samples) rather than frequency
    "smooth across frequency": "smooth in time",
    "noise that grows with |H|": "noise that is not white (coloured, or growing with the signal)",
    # a new user's quarter car, its road input measured at 500 Hz and fitted as held: misfit 11 times the noise's,
    # parameters 3-12 % off, and no word of the hold
    "the data's units)": "the data's units, and the input between samples: one measured (sampled, band-limited) "
                         "rather than held by a DAC needs hold='bandlimited')",
    # a new user's concentrations with 10 % proportional noise, 12 samples: the noise level alone said nothing of
    # noise that grows with the value
    "give noise_floor= (0.01 for 10 % noise)": "give noise_floor= (0.01 for 10 % noise), or the noise's error "
                                               "model (variance={\"proportional\": 0.1} for 10 % of each value)",
}


def _offset_advice(offset: Mapping[str, Any]) -> str:
    """The NEXT line for a time-series misfit that a free initial state or a constant offset explains
    (:meth:`symid.fit.timeseries.oe.OutputError.initial_offset`).

    Examples
    --------
    >>> from symid.fit.result import _offset_advice
    >>> _offset_advice({"kind": "offset", "record": 0, "output": 0, "mean": 0.1, "misfit": 4.8e-4,
    ...                 "after": 4.0e-4})[:67]
    'the residual is in part (17% of the misfit) a constant offset (outp'
    >>> _offset_advice({"kind": "offset", "record": 0, "output": 0, "mean": 0.1, "misfit": 4.8e-4,
    ...                 "after": 1e-5})[:45]
    'the residual is mostly a constant offset (out'
    """
    where = f"record {offset['record']}, " if offset["record"] else ""
    names = offset.get("output_names") or ()

    def name(k: int) -> str:  # the table's column name when read from one (a new user read "output 1" as h1)
        return f"{names[k]!r}" if k < len(names) else str(k)

    drop = ("" if offset.get("after") is None else
            f"this estimate's misfit would fall from {offset['misfit']:.3g} to {offset['after']:.3g}")
    if offset.get("kind", "initial_state") == "initial_state":
        text = (f"the record does not start where the model does ({where}output {name(offset['output'])} is "
                f"{offset['measured']:.6g} at its first sample, the model's {offset['model']:.6g}"
                f"{'; with the initial state estimated ' + drop if drop else ''}): estimate the initial state "
                f"(initial_state=\"estimate\"; --option initial_state=estimate) or remove the offset from the data")
        if (level := offset.get("level")) is not None:
            text += (f". Output {name(level['output'])} also sits at a level (mean {level['mean']:.6g}, standard "
                     f"deviation {level['std']:.3g}): if the record lies around an operating point that the model's "
                     f"inputs do not produce, the initial state alone will not fit it; subtract the operating point "
                     f"(deviation variables) or model it (guide: records around an operating point)")
        return text
    if offset.get("kind") == "drift":
        return (f"the residual drifts ({where}output {name(offset['output'])}: {offset['slope']:.3g} per "
                f"{offset.get('time_unit', 's')}, mean residual {offset['mean']:.3g}; with an offset and a ramp on "
                f"each output removed {drop}): a sensor that drifts or a slow disturbance the model does not hold. "
                f"Model it: two inputs, a column of ones and a column of time (a ramp), each with a gain that is a "
                f"parameter on that output, the initial state estimated (guide: records around an operating point)")
    if offset.get("kind") == "level":
        return (f"{where}output {name(offset['output'])} sits at a level (mean {offset['mean']:.6g}, standard "
                f"deviation {offset['std']:.3g}): if the record lies around an operating point (absolute levels, "
                f"temperatures, positions), subtract the operating point from the inputs and outputs (deviation "
                f"variables), or model it: a constant input (a column of ones) whose gain is a parameter, with the "
                f"initial state estimated (guide: records around an operating point)")
    share = (None if offset.get("after") is None or not offset.get("misfit") else
             1.0 - float(offset["after"]) / float(offset["misfit"]))
    # "mostly" only where the offset explains most of the misfit (a new user's record: 16 % of it was "mostly")
    amount = "mostly" if share is None or share >= 0.5 else f"in part ({share:.0%} of the misfit)"
    return (f"the residual is {amount} a constant offset ({where}output {name(offset['output'])}: mean residual "
            f"{offset['mean']:.6g}; with each output's mean residual removed {drop}): the record lies around an "
            f"operating point. Subtract the operating point from the inputs and outputs (deviation variables), or "
            f"model it: a constant input (a column of ones) whose gain is a parameter, with the initial state "
            f"estimated (guide: records around an operating point)")


ONE_OUTPUT_FITS = 0.1
"""The other outputs' misfits below which one output predicted worse than by zero is named alone in NEXT."""


def _one_output_off(per: Mapping[str, Any] | None) -> str | None:
    """The NEXT line when one output is predicted worse than by zero and the others nearly fit (a sensor of reversed
    polarity, or of the wrong unit or kind on that row), else None.

    Examples
    --------
    >>> from symid.fit.result import _one_output_off
    >>> _one_output_off({"names": ["a1", "a2"], "misfit": [0.004, 3.9], "worse_than_zero": ["a2"]})[:45]
    'output a2 is predicted worse than by zero (mi'
    """
    if not per or len(per["worse_than_zero"]) != 1:
        return None
    bad = per["worse_than_zero"][0]
    others = [m for n, m in zip(per["names"], per["misfit"], strict=True) if n != bad]
    if not others or max(others) >= ONE_OUTPUT_FITS:
        return None
    worst = per["misfit"][per["names"].index(bad)]
    return (f"output {bad} is predicted worse than by zero (misfit {worst:.3g}) while the others come within "
            f"{max(others):.2g}: a sensor of reversed polarity on that row (negate its column and fit again), or the "
            f"wrong unit or output kind for it (outputs are counted from 0 in the order of C's rows)")


UNIT_FACTORS = {"degrees read as radians": 180 / math.pi, "radians read as degrees": math.pi / 180,
                "mm read as m (or g as kg, ms as s)": 1e3, "m read as mm (or kg as g)": 1e-3,
                "g read as m/s²": 1 / 9.80665, "m/s² read as g": 9.80665, "rpm read as rad/s": 60 / (2 * math.pi),
                "rad/s read as rpm": 2 * math.pi / 60, "Hz read as rad/s": 1 / (2 * math.pi),
                "rad/s read as Hz": 2 * math.pi, "km/h read as m/s": 3.6, "m/s read as km/h": 1 / 3.6,
                "percent read as a fraction": 100.0, "a fraction read as percent": 0.01}
"""Factors between units a column is often logged in and the model's, named when an output is that factor times the
model's prediction (within 10 %)."""


def _one_output_scaled(per: Mapping[str, Any] | None) -> str | None:
    """The NEXT line when an output is predicted badly (relative misfit above 0.5) but is, to a tenth of that misfit,
    the model's prediction times a factor away from 1 (beyond 2 either way): a unit or a sensor gain (a new user's
    encoder in degrees against a model in radians, told of the initial state); else None.

    Examples
    --------
    >>> from symid.fit.result import _one_output_scaled
    >>> _one_output_scaled({"names": ["angle", "speed"], "misfit": [0.964, 0.002], "factor": [57.1, 1.0],
    ...                     "scaled_misfit": [0.004, 0.002]})[:86]
    "output angle is 57.1 times the model's prediction (misfit 0.964; scaled by that factor"
    """
    if not per or "factor" not in per:
        return None
    rows = [(n, m, f, sm) for n, m, f, sm in zip(per["names"], per["misfit"], per["factor"], per["scaled_misfit"],
                                                 strict=True)
            if f and np.isfinite(f) and m > 0.5 and sm < 0.1 * m and abs(math.log(abs(f))) > math.log(2)]
    if not rows:
        return None
    name, misfit, factor, scaled = max(rows, key=lambda r: r[1])
    known = min(UNIT_FACTORS.items(), key=lambda kv: abs(math.log(abs(factor) / kv[1])))
    unit = (f" (near {known[1]:.4g}: {known[0]}?)" if abs(math.log(abs(factor) / known[1])) < math.log(1.1)
            else "")  # the failed fit's compromise leaves the factor a few % off (53.2 for degrees)
    sign = "; negative: also of reversed polarity" if factor < 0 else ""
    return (f"output {name} is {factor:.3g} times the model's prediction (misfit {misfit:.3g}; scaled by that factor "
            f"{scaled:.2g}){sign}: its unit is not the model's{unit}, or a sensor gain the model does not hold. "
            f"Convert the column (or state its unit: a '# units:' line, --units) or give the output's gain a "
            f"parameter")


def next_step(fit: str, frf: bool = True, time: bool = False) -> str | None:
    """What to try when an estimate does not fit, from its ``fit`` text (``None`` when there is no advice);
    ``frf=False`` for data other than a frequency response (no ``method='auto'``, no ``variance=``);
    ``time=True`` for residuals ordered in time (measured samples).

    Examples
    --------
    >>> from symid.fit.result import next_step
    >>> next_step("misfit 9.87e-01 > 0.01 (over 10 % rms) and no noise floor given").startswith("far from a fit")
    True
    >>> "auto" in next_step("misfit 9.87e-01 > 0.01 (over 10 % rms) and no noise floor given", frf=False)
    False
    >>> next_step("structured residual (lag-1 statistic 5.1 > 3)", frf=False, time=True).startswith(
    ...     "the residual is smooth in time")
    True
    >>> "hold='bandlimited'" in next_step("structured residual (lag-1 statistic 5.1 > 3)", frf=False, time=True)
    True
    >>> 'variance={"proportional": 0.1}' in next_step("misfit 2.84e-02 > 0.01 (over 10 % rms) and no noise floor "
    ...                                                "given", frf=False, time=True)
    True
    """
    for key, advice in _NEXT_STEPS:
        if key in fit:
            if not frf:
                for text, other in _FRF_ONLY.items():
                    advice = advice.replace(text, other)
            if time:
                for text, other in _IN_TIME.items():
                    advice = advice.replace(text, other)
            return advice
    return None


def _plain(value: Any) -> Any:
    """An option's value as plain JSON-ready Python: numbers, strings, lists and dicts of them kept (numpy's as
    Python's; NaN and ±inf, an open bound, as None), anything else as its ``repr``."""
    if isinstance(value, float):
        return value if np.isfinite(value) else None
    if isinstance(value, (bool, int, str, type(None))):
        return value
    if isinstance(value, np.generic):
        return _plain(value.item())
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, dict) and all(isinstance(k, str) for k in value):
        return {k: _plain(v) for k, v in value.items()}
    return repr(value)


def _best_index(starts: tuple[StartOutcome, ...] | list[StartOutcome]) -> int:
    """Index of the lowest data misfit (non-finite costs rank last; the first on ties)."""
    return int(np.argmin([s.cost if np.isfinite(s.cost) else np.inf for s in starts]))


@dataclass(frozen=True)
class ScrIteration:
    """One SCR iteration of one start, as the estimators record it.

    Attributes
    ----------
    iteration : int
        1, 2, …
    residual : float
        Largest normalised bilinear residual after the iteration (the engine's stopping measure).
    objective : float
        The convex objective f(x) (0 without one).
    relaxation : float
        The value of the relaxed sub-problem's objective.
    time : float
        Seconds spent on the iteration.
    theta : numpy.ndarray or None
        The parameter iterate, when the formulation estimates θ directly.
    families : dict of str to float or None
        Summed residual per constraint family (thesis Figure 3-2), when the formulation has them.
    """

    iteration: int
    residual: float
    objective: float
    relaxation: float
    time: float
    theta: np.ndarray | None = field(default=None, repr=False)
    families: dict[str, float] | None = field(default=None, repr=False)

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python form, suitable for JSON."""
        return {"iteration": self.iteration, "residual": self.residual, "objective": self.objective,
                "relaxation": self.relaxation, "time": self.time,
                "theta": None if self.theta is None else np.asarray(self.theta, dtype=float).tolist(),
                "families": None if self.families is None else dict(self.families)}


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
        The data misfit of the estimate; what it measures depends on the data kind
        (``IdentificationResult.cost_kind``).
    success : bool
        The estimate fits the data (:mod:`symid.fit.success`), whether or not the solver finished.
    finished : bool
        The solver reached its own stopping rule (converged, or stationary), not a budget or a callback.
    status : str
        The solver's own status word (IPOPT's return status, SCR's ``"converged"``,
        ``"max_iter"``, ...).
    iterations : int
        Solver iterations.
    wall_time : float
        Seconds spent on this start.
    message : str
        The solver's final word.
    fit : str
        How the misfit compares with the noise floor (why it fits or not).
    history : tuple of ScrIteration
        Per-iteration records, when the method keeps them (SCR does).
    passes : tuple of StartOutcome
        The local solutions a restarted method reached within this start besides the one it
        reports (``auto``'s passes), each with its own estimate and misfit; empty for methods
        that run once. :meth:`IdentificationResult.alternatives` looks at them too, so one
        start can show that the data do not single out one estimate.
    """

    start: np.ndarray
    theta: np.ndarray
    cost: float
    success: bool
    finished: bool
    status: str
    iterations: int
    wall_time: float
    message: str = ""
    fit: str = ""
    history: tuple[ScrIteration, ...] = field(default=(), repr=False)
    passes: tuple[StartOutcome, ...] = field(default=(), repr=False)

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python form (lists and floats), suitable for JSON (the history is left out)."""
        out = {"start": np.asarray(self.start).tolist(), "theta": np.asarray(self.theta).tolist(),
               "cost": float(self.cost), "success": bool(self.success), "finished": bool(self.finished),
               "status": self.status, "iterations": int(self.iterations), "wall_time": float(self.wall_time),
               "message": self.message, "fit": self.fit}
        if self.passes:
            out["passes"] = [p.to_dict() for p in self.passes]
        return out

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> StartOutcome:
        """Rebuild an outcome written by :meth:`to_dict` (without its history).

        A cost written as ``None`` (JSON has no NaN or infinity) reads back as ``inf``.

        Examples
        --------
        >>> import numpy as np
        >>> from symid.fit.result import StartOutcome
        >>> out = StartOutcome(np.zeros(2), np.ones(2), 1e-12, True, True, "converged", 3, 0.1)
        >>> StartOutcome.from_dict(out.to_dict()).status
        'converged'
        """
        cost = d.get("cost")
        return cls(start=np.asarray(d["start"], dtype=float), theta=np.asarray(d["theta"], dtype=float),
                   cost=float("inf") if cost is None else float(cost), success=bool(d["success"]),
                   finished=bool(d["finished"]), status=str(d["status"]), iterations=int(d["iterations"]),
                   wall_time=float(d["wall_time"]), message=str(d.get("message", "")), fit=str(d.get("fit", "")),
                   passes=tuple(cls.from_dict(p) for p in d.get("passes", ())))


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
        Data misfit of ``theta``.
    cost_kind : str
        What ``cost`` measures for this data kind (e.g. the relative FRF misfit).
    success : bool
        The best start's estimate fits the data (its solver's own verdict is ``status``).
    status : str
        The solver's own status on the best start.
    iterations : int
        Iterations of the best start.
    wall_time : float
        Total seconds over all starts.
    message : str
        The solver's final word on the best start.
    fit : str
        The noise-floor test on the best start (why it fits or not).
    starts : tuple of StartOutcome
        Every start's outcome, in the order they ran.
    polished : IdentificationResult or None
        With ``polish=True``: SCR followed by a local refinement, reported separately.
    options : dict
        The options the method ran with.
    uncertainty : Uncertainty or None
        Covariance, standard errors and 95 % confidence intervals of θ from the Fisher
        information, for methods that offer it (:mod:`symid.fit.uncertainty`).
    """

    method: str
    parameter_names: tuple[str, ...]
    theta: dict[str, float]
    theta_vector: np.ndarray
    cost: float
    cost_kind: str
    success: bool
    status: str
    iterations: int
    wall_time: float
    message: str
    fit: str
    starts: tuple[StartOutcome, ...]
    polished: IdentificationResult | None = None
    options: dict[str, Any] = field(default_factory=dict)
    uncertainty: Any = None

    @classmethod
    def from_starts(cls, method: str, parameter_names: tuple[str, ...], starts: list[StartOutcome], *,
                    cost_kind: str, options: dict[str, Any] | None = None,
                    polished: IdentificationResult | None = None) -> IdentificationResult:
        """Pick the best start by data misfit (non-finite costs rank last)."""
        if not starts:
            raise ValueError("no start outcome to report")
        best = starts[_best_index(starts)]
        return cls(method=method, parameter_names=tuple(parameter_names),
                   theta=dict(zip(parameter_names, np.asarray(best.theta, dtype=float).tolist(), strict=True)),
                   theta_vector=np.asarray(best.theta, dtype=float), cost=float(best.cost), cost_kind=cost_kind,
                   success=bool(best.success), status=best.status, iterations=int(best.iterations),
                   wall_time=float(sum(s.wall_time for s in starts)), message=best.message, fit=best.fit,
                   starts=tuple(starts), polished=polished, options=dict(options or {}))

    @property
    def best_start(self) -> StartOutcome:
        """The start whose outcome is reported (lowest data misfit)."""
        return self.starts[_best_index(self.starts)]

    @property
    def n_starts(self) -> int:
        """Number of starts run."""
        return len(self.starts)

    def alternatives(self, *, cost_rtol: float = 0.01, theta_rtol: float = 0.01) -> list[StartOutcome]:
        """Other starts (or passes of a restarted start) whose estimates fit the data as well as
        the best one but lie elsewhere.

        A start counts when its misfit is within ``cost_rtol`` (relative) of the best one's
        and some parameter differs from the best estimate by more than ``theta_rtol``
        relative to the larger of the two values — and, where that parameter has a finite
        standard error, by more than three of them. Whether either estimate passes the fit
        test does not matter: two estimates at the same misfit are equally supported by the
        data. Such starts mean the data do not single out one estimate: the model may have
        several exact solutions (only locally
        identifiable, see :func:`symid.identifiability`), or the data may not pin some
        parameters down. :meth:`summary` and :func:`symid.identify` say so.

        Examples
        --------
        >>> import numpy as np
        >>> from symid.fit.result import IdentificationResult, StartOutcome
        >>> def start(theta, cost):
        ...     return StartOutcome(start=np.ones(2), theta=np.array(theta), cost=cost, success=True,
        ...                         finished=True, status="ok", iterations=1, wall_time=0.1)
        >>> res = IdentificationResult.from_starts("lm", ("a", "b"), [start([1.0, 2.0], 1e-20),
        ...                                        start([1.0, 5.0], 2e-20)], cost_kind="misfit")
        >>> [s.theta.tolist() for s in res.alternatives()]
        [[1.0, 5.0]]
        """
        best = self.best_start
        ref = np.asarray(best.theta, dtype=float)
        if not (np.all(np.isfinite(ref)) and np.isfinite(best.cost)):
            return []
        se = getattr(self.uncertainty, "standard_errors", None)
        se = np.asarray(se, dtype=float) if se is not None else np.zeros_like(ref)
        se = np.where(np.isfinite(se), se, 0.0)  # no finite standard error: the relative rule alone
        found = []
        for s in (c for start in self.starts for c in (start, *start.passes)):
            th = np.asarray(s.theta, dtype=float)
            if s is best or not np.all(np.isfinite(th)) or th.shape != ref.shape:
                continue
            if not s.cost <= best.cost * (1 + cost_rtol) + 1e-14:
                continue
            if any(np.all(_relative_difference(th, np.asarray(f.theta, dtype=float)) <= theta_rtol) for f in found):
                continue  # the same estimate again (a start and its own pass)
            if np.any((_relative_difference(th, ref) > theta_rtol) & (np.abs(th - ref) > 3 * se)):
                found.append(s)
        return found

    def ambiguity(self) -> str | None:
        """One sentence on :meth:`alternatives` (``None`` when there are none)."""
        alts = self.alternatives()
        if not alts:
            return None
        ref = np.asarray(self.best_start.theta, dtype=float)
        rel = np.max([_relative_difference(np.asarray(s.theta, dtype=float), ref) for s in alts], axis=0)
        k = int(np.argmax(rel))
        head = f"{len(alts)} other estimate(s) from other starts or restarts"
        differ = f"with different parameters (up to {100 * rel[k]:.3g} % in {self.parameter_names[k]})"
        if not self.success:  # equally good is not good: neither a fit nor a question of identifiability yet
            return (f"{head} end at the best estimate's misfit ({self.best_start.cost:.3g}, which does not fit the "
                    f"data) {differ}: whether the data single out one estimate is a question once an estimate fits "
                    "(NEXT in the summary says what to try); .alternatives() lists them")
        return (f"{head} fit the data as well {differ}: the data do not single out "
                "one estimate. The model may have several exact solutions (symid.identifiability gives the global "
                "verdict) or the data may not pin these parameters down; compare them in .alternatives(), or fix "
                "known parameters")

    def summary(self, truth: dict[str, float] | None = None) -> str:
        """A readable table of the estimate (against ``truth`` when given)."""
        n_ok = sum(s.success for s in self.starts)
        # a fit whose parameters the data hardly determine says so beside success (a new user's roof-only shake-table
        # record: success True, masses 4 times the truth, said only in the uncertainty's lines below)
        loose = (" (the data fit, but do not determine every parameter: NEAR-SINGULAR below)" if self.success
                 and self.uncertainty is not None and self.uncertainty.near_singular else "")
        lines = [f"method: {self.method}   starts: {self.n_starts}   successful: {n_ok}/{self.n_starts}",
                 f"best: success {self.success}{loose}   cost {self.cost:.3e} ({self.cost_kind})",
                 f"  fit: {self.fit}",
                 f"  solver: {self.status}, {self.iterations} iterations; {self.message}",
                 f"total time {self.wall_time:.3f} s" + (
                     f" (and {self.options['identifiability_check_s']:.2f} s for the identifiability checks)"
                     if self.options.get("identifiability_check_s") is not None else "") + (
                     f"; the whole call {self.options['identify_s']:.3f} s (setup, typical values, check, starts, "
                     f"uncertainty, polish)" if self.options.get("identify_s") is not None else "")]
        if self.options.get("interrupted"):
            lines.append("INTERRUPTED: only the finished starts are reported")
        if not self.success:
            if (scale := self.options.get("time_scale")) is not None:
                # before anything else: no start, hold or sign fixes a record read in the wrong time unit
                lines.append(f"NEXT: {scale}")
            elif (probe := self.options.get("hold_probe")) is not None:
                # before anything else: no start or unit fixes an input taken as held that was measured
                lines.append(f"NEXT: the records fit with the input band-limited between samples (misfit "
                             f"{probe['misfit']:.3g}, against {self.cost:.3g} with it held): an input that was "
                             f"measured (sampled from a continuous signal: a shake table, a road profile, a sensor) "
                             f"rather than held by a DAC or a controller? Fit with hold='bandlimited' (--option "
                             f"hold=bandlimited)"
                             + (", or with one hold per input where some were held by a controller and others "
                                "measured (hold=['zoh', 'bandlimited', …] in the records' input order; --option "
                                "hold=zoh,bandlimited)" if probe.get("inputs", 1) > 1 else "")
                             + "; .options['hold_probe'] holds that fit's estimate")
            elif (flip := self.options.get("polarity")) is not None:
                # before anything else: no start, bound or unit fixes a response of reversed polarity
                what = (f"{flip['via']} fits with {flip['flip']} negated (misfit {flip['misfit']:.3g}; the records "
                        f"as they are, {self.cost:.3g})" if flip.get("via") else
                        f"the data fit with {flip['flip']} negated (misfit {flip['misfit']:.3g}, against "
                        f"{self.cost:.3g} as they are)")
                lines.append(f"NEXT: {what}: an input or output of reversed polarity (a sensor mounted the other "
                             f"way, a current measured backwards)? Negate it in the data and fit again "
                             f"(.options['polarity'] holds that fit's estimate; outputs and inputs are counted "
                             f"from 0)")
            elif (roles := self.options.get("swapped_roles")) is not None:
                # before an offset or a bound, which swapped columns also produce (a new user's two tanks)
                lines.append(f"NEXT: {roles}")
            elif (row := _one_output_scaled(self.options.get("misfit_per_output"))) is not None:
                lines.append(f"NEXT: {row}")
            elif (row := _one_output_off(self.options.get("misfit_per_output"))) is not None:
                lines.append(f"NEXT: {row}")
            elif self.polished is not None and self.polished.success:
                lines.append("NEXT: the polished estimate fits the data: use .polished (below)")
            elif self.on_bounds:  # before the signs of an offset, which then follow: a new user's concentrations
                # in ug/L against a model in mg/L, every parameter on a bound, were told of the initial state alone
                sides = ", ".join(f"{n} ({side})" for n, side in self.on_bounds.items())
                lines.append(f"NEXT: the estimate sits on its bounds ({sides}) and does not fit: the data want values "
                             f"beyond them; widen those bounds if the physics allows, else check the model's "
                             f"structure and the data's units")
                if (offset := self.options.get("initial_offset")) is not None:
                    lines.append("NEXT (also): " + _offset_advice(offset))
            elif (offset := self.options.get("initial_offset")) is not None:
                lines.append("NEXT: " + _offset_advice(offset))
            elif self.options.get("leakage") is not None:
                # before the noise advice, which would accept the biased fit (a new user's footbridge from a 20 s
                # record: told to give noise_floor= at a misfit the window's smoothing explains)
                lines.append(f"NEXT: {self.options['leakage']['text']}")
            elif self.method == "scr" and self.polished is None and not self.fit.startswith("pulled beyond"):
                # SCR solves the bilinear equations, not the misfit: its polish is the remedy measured first (a new
                # user's building from output spectra: misfit 0.098 from every start, 3.6e-4 and a fit polished)
                lines.append("NEXT: SCR solves the bilinear equations (an equation error), not the misfit, and noise "
                             "or a local minimum leaves its estimate off the least-squares fit: polish=True refines "
                             "it by IPOPT on the misfit (kept when lower); then more starts (starts=20)")
            elif (advice := next_step(self.fit, frf="FRF" in self.cost_kind,
                                      time="samples" in self.cost_kind)) is not None:
                lines.append(f"NEXT: {advice}")
        if (gap := self.options.get("sampling_gap")) is not None:  # of a fit or not: what the records hide
            lines.append(f"{'GAP' if self.success else 'NEXT (also)'}: {gap}")
        if (scale := self.options.get("output_only_scale")) is not None:  # of a fit or not: what spectra cannot say
            lines.append(f"SCALE: {scale['text']}")
        if (nu := self.options.get("sensor_noise_levels")) is not None:
            lines.append("sensor noise (white, fitted beside the model's spectra): "
                         + ", ".join(f"output {j + 1} {v:.3g}" for j, v in enumerate(nu)) + " (spectral density)")
        if (leak := self.options.get("leakage")) is not None and not any(leak["text"] in x for x in lines):
            lines.append(f"{'LEAKAGE' if self.success else 'NEXT (also)'}: {leak['text']}")  # the data's own bias
        if not self.success and (sampled := self.options.get("sampled_response")) is not None:
            # beside the other advice, not instead of it: a new user's steering in degrees, from a sampled (not held)
            # input, was told only of the hold
            lines.append(f"NEXT (also): {sampled}")
        if self.success and self.on_bounds:
            sides = ", ".join(f"{n} ({side})" for n, side in self.on_bounds.items())
            unc = self.uncertainty
            if unc is not None and "bounds" in (unc.note or ""):
                pull = "the uncertainty's note (below) says whether the data pull the estimate beyond them"
            else:  # no finite covariance (a near-singular Fisher information), or no uncertainty: nothing to say it
                pull = ("nothing here says whether the data pull the estimate beyond them (the Fisher information "
                        "gives no finite covariance there): make a parameter known, or check the model and the units")
            lines.append(f"ON BOUNDS: {sides}; the fit is accepted, but {pull} (and if they do, widen those bounds "
                         f"if the physics allows)")
        if self.options.get("weak_lines_missed"):  # a fit the success rule cannot judge there (symid.fit.frf.misfit)
            lines.append(f"WEAK LINES MISSED: {self.options['weak_lines_missed']}")
        if (relative := self.options.get("relative_noise")) is not None:
            lines.append(f"NOTE: the residual looks like noise relative to |H| ({relative['level']:.3g} %, likelier "
                         f"than noise of one level on every line), and |H| spans {relative['decades']:.1f} decades: "
                         f"with equal weights the largest lines decide. variance='relative' weighs every line by its "
                         f"own level, the maximum-likelihood fit for such noise")
        if (far := self.options.get("far_from_start")) is not None:
            lines.append(f"NOTE: {far['text']}")
        if (per := self.options.get("misfit_per_output")) is not None and not self.success:
            lines.append("MISFIT PER OUTPUT: " + ", ".join(f"{n} {m:.3g}" for n, m in zip(per["names"],
                                                                                       per["misfit"], strict=True))
                         + (" (predicted worse than by zero: " + ", ".join(per["worse_than_zero"]) + ")"
                            if per["worse_than_zero"] else ""))
        if self.options.get("not_determined"):
            lines.append(f"NOT DETERMINED BY THESE DATA: {self.options['not_determined']}")
        if (bad := self.options.get("not_identifiable")) is not None:
            names = ", ".join(bad["parameters"])
            lines.append(f"NOT IDENTIFIABLE (structure): {names} cannot be determined from "
                         + ("the input-output map from rest (the model's nonzero initial state may determine them: "
                            "check their standard errors)" if bad.get("from_rest_only") else
                            "data of this kind: infinitely many values fit equally well, and these estimates are "
                            "one of them. Fix some of them (known values) or reparameterise; "
                            "si.identifiability(model) lists the combinations the data determine"))
        ambiguity = self.ambiguity()
        if ambiguity is not None:
            lines.append(f"NOT UNIQUE: {ambiguity}")
        if self.options.get("global_undecided"):
            lines.append(f"UNIQUENESS NOT CHECKED (structure): {self.options['global_undecided']}")
        if self.options.get("unique_within_bounds"):
            lines.append(f"UNIQUE WITHIN THE BOUNDS (structure): {self.options['unique_within_bounds']}")
        elif self.options.get("several_solutions"):
            lines.append(f"NOT UNIQUE (structure): {self.options['several_solutions']}")
        unc = self.uncertainty
        if unc is not None and not self.success:
            # intervals describe an estimate that fits the data; around one that does not they mean nothing
            lines.append("uncertainty: not shown, the estimate does not fit the data (.uncertainty holds the "
                         "Fisher information at it, its intervals NaN)")
            unc = None
        if unc is not None:
            lines.append(unc.summary())
        if (unit := self.options.get("time_unit")) not in (None, "s"):  # a record in minutes: rates per minute
            lines.append(f"rates per {unit} (the record's time unit)")
        if self.options.get("modes"):
            lines.append(self.options["modes"])
        head = f"{'parameter':>12s} {'estimate':>14s}"
        if unc is not None:
            head += f" {'std. error':>11s} {'95 % interval':>27s}"
        if truth is not None:
            head += f" {'truth':>14s} {'rel. error':>11s}"
        lines.append(head)
        for i, name in enumerate(self.parameter_names):
            row = f"{name:>12s} {self.theta[name]:>14.6g}"
            if unc is not None:
                lo, hi = unc.intervals[i]
                row += f" {unc.standard_errors[i]:>11.3g} {f'[{lo:.6g}, {hi:.6g}]':>27s}"
            if truth is not None and name in truth:
                t = float(truth[name])
                err = abs(self.theta[name] - t) / (abs(t) if t != 0 else 1.0)
                row += f" {t:>14.6g} {err:>11.2e}"
            lines.append(row)
        states = self.options.get("initial_states")
        if states:
            # at an estimate that does not fit, the least-squares initial state absorbs the misfit (a new user's room
            # model: -2302 °C): said so, as the intervals are withheld
            head = ("initial state x(t₀), estimated with θ (least squares at the estimate): " if self.success else
                    "initial state x(t₀) at an estimate that does not fit the data (it absorbs the misfit: no "
                    "measure of the true start): ")
            lines.append(head + "; ".join(
                (f"record {e}: " if len(states) > 1 else "") + "[" + ", ".join(f"{v:.6g}" for v in x) + "]"
                for e, x in enumerate(states)))
        if self.polished is not None:
            lines.append("")
            lines.append("after polish:")
            lines.append(self.polished.summary(truth))
        return "\n".join(lines)

    def derived(self, quantities: Mapping[str, Any]) -> Any:
        """Quantities computed from the estimate, with standard errors and 95 % intervals by the delta method
        (:func:`symid.fit.derived.derived_quantities`): ``res.derived({"V": lambda th: 1 / th["q"]})``.

        Parameters
        ----------
        quantities : dict of str to callable
            Each callable takes the parameters as a dict by name and returns a number.

        Returns
        -------
        symid.fit.derived.DerivedQuantities
            With ``summary()``, ``values``, ``standard_errors`` and ``intervals``.
        """
        from symid.fit.derived import derived_quantities

        return derived_quantities(self, quantities)

    @property
    def determined(self) -> bool:
        """Whether the data determine every parameter: no structural non-identifiability found, no parameter that
        multiplies only an input the records hold at zero, and a Fisher information that is not near-singular.
        ``success`` says the estimate fits the data; a fit can succeed with parameters the data leave free (a new
        user's drive with its motor constant free: success, every parameter 1.44 times the truth, exit status 0),
        and scripts read this beside it (``"determined"`` in the command line's JSON).

        Examples
        --------
        >>> import numpy as np
        >>> import symid as si
        >>> m, c, k, g = si.parameters("m c k g", positive=True)
        >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[g]], C=[[1]])   # g scales with m, c, k
        >>> frf = si.simulate_frf(model, [2.0, 0.8, 50.0, 1.0], np.linspace(1, 10, 30))
        >>> res = si.identify(model, frf, x0=[1.0, 1.0, 30.0, 1.0])
        >>> bool(res.success), res.determined
        (True, False)
        """
        unc = self.uncertainty
        return not (self.options.get("not_identifiable") or self.options.get("not_determined")
                    or (unc is not None and bool(unc.near_singular)))

    @property
    def on_bounds(self) -> dict[str, str]:
        """The parameters whose estimate sits on a bound the user gave (``options["bounds"]``), by name:
        ``"lower"`` or ``"upper"`` (empty without bounds; the 0 that keeps a positive parameter positive is
        not a bound the user gave).

        Examples
        --------
        >>> import numpy as np
        >>> from symid.fit.result import IdentificationResult, StartOutcome
        >>> out = StartOutcome(np.ones(2), np.array([100.0, 2.0]), 1e-3, False, True, "ok", 3, 0.1)
        >>> res = IdentificationResult.from_starts("lm", ("k", "m"), [out], cost_kind="misfit",
        ...                                        options={"bounds": {"k": [10.0, 100.0], "m": [0.0, np.inf]}})
        >>> res.on_bounds
        {'k': 'upper'}
        """
        bounds = self.options.get("bounds") or {}
        out = {}
        for name, (lo, hi) in bounds.items():
            value = self.theta.get(name)
            if value is None or not np.isfinite(value):
                continue
            tol = min(1e-9 * max(1.0, abs(value)), 0.25 * (hi - lo))
            near_lo = lo != 0 and np.isfinite(lo) and abs(value - lo) <= tol
            near_hi = np.isfinite(hi) and abs(value - hi) <= tol
            if near_lo or near_hi:
                out[name] = "lower" if near_lo and (not near_hi or value - lo <= hi - value) else "upper"
        return out

    def __str__(self) -> str:
        return self.summary()

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python form, suitable for JSON."""
        return {"method": self.method, "parameter_names": list(self.parameter_names), "theta": dict(self.theta),
                "cost": float(self.cost), "cost_kind": self.cost_kind, "success": bool(self.success),
                "status": self.status, "iterations": int(self.iterations), "wall_time": float(self.wall_time),
                "message": self.message, "fit": self.fit, "starts": [s.to_dict() for s in self.starts],
                "polished": None if self.polished is None else self.polished.to_dict(),
                "uncertainty": None if self.uncertainty is None else self.uncertainty.to_dict(),
                "on_bounds": self.on_bounds,
                "options": {k: _plain(v) for k, v in self.options.items()}}
