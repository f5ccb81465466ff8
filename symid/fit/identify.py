"""``si.identify``: one entry point; the data kind picks the package, the method the estimator."""

from __future__ import annotations

import dataclasses
import math
import re
import time
import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np

from symid.errors import DataWarning, IdentifiabilityWarning, OptionError, SymidError
from symid.fit.frf.misfit import FrfEstimator, relative_noise_note, weak_lines_missed
from symid.fit.modes import modes_line
from symid.fit.options import check_bool, scale_by_name, without_known
from symid.fit.registry import check_model, prepare
from symid.fit.result import IdentificationResult, StartOutcome
from symid.fit.starts import draw_starts
from symid.fit.success import EXACT_FIT
from symid.fit.uncertainty import FisherInformation
from symid.interrupt import Interrupted
from symid.progress import Heartbeat, progress_bar

__all__ = ["identify", "unit_mismatches"]


_SEVERAL_INTERVALS = (
    "other parameter values give the same response (NOT UNIQUE (structure)): these intervals describe this "
    "solution's neighbourhood only, and hold less often than they say when another solution lies within a few "
    "standard errors; fit model.with_known({...}) with a parameter whose value is known for intervals that hold")
# measured by benchmarks/interval_coverage.py: a half car at 1 % noise, the other solution 1.9 to 10.6 standard errors
# away, 95 % intervals held the truth in 68 to 98 % of 40 records, 85 to 100 % with its body mass known
"""The uncertainty's note for an estimate of a model with several solutions (:func:`identify`)."""


MERGED = 1e-3
"""Another solution at the estimate within this relative difference in every parameter is the estimate itself: two
solutions meet there (:func:`identify`'s uncertainty note says so)."""


WORSE_THAN_ZERO = 1.0
"""An output whose relative misfit exceeds this is predicted worse than by zero."""


def _misfit_per_output(estimator: Any, theta: np.ndarray, records: list[Any]) -> dict[str, Any] | None:
    """``{"names": [...], "misfit": [...], "worse_than_zero": [...]}``: each output's relative misfit
    ‖yⱼ − ŷⱼ‖² / ‖yⱼ‖² over the records at θ, by the table's column names when read from one; None when the
    simulation fails."""
    try:
        with np.errstate(all="ignore"):
            sims = estimator.simulate(theta)
    except (SymidError, ValueError, np.linalg.LinAlgError):
        return None
    p = sims[0].shape[1]
    num, den, cross, model = np.zeros(p), np.zeros(p), np.zeros(p), np.zeros(p)
    for r, s, o in zip(estimator.records, sims, estimator.observed, strict=True):
        y = np.where(o, r.y, 0.0)
        sim = np.where(o, s, 0.0)
        num += np.sum(np.where(o, (r.y - s) ** 2, 0.0), axis=0)
        den += np.sum(y**2, axis=0)
        cross += np.sum(y * sim, axis=0)
        model += np.sum(sim**2, axis=0)
    if not np.all(np.isfinite(num)):
        return None
    misfit = np.where(den > 0, num / np.where(den > 0, den, 1.0), np.inf)
    # each output's least-squares factor on the model's prediction, and the misfit it leaves: an output in another
    # unit than the model's (degrees against radians) is the model's shape times a factor
    with np.errstate(all="ignore"):
        factor = np.where(model > 0, cross / np.where(model > 0, model, 1.0), np.nan)
        scaled = np.where((den > 0) & (model > 0), 1.0 - cross**2 / (den * np.where(model > 0, model, 1.0)), np.inf)
    columns = (getattr(records[0], "stated_units", None) or {}).get("output", ())
    names = [str(columns[j][0]) if len(columns) == p else str(j) for j in range(p)]
    worse = [names[j] for j in range(p) if misfit[j] > WORSE_THAN_ZERO]
    return {"names": names, "misfit": misfit.tolist(), "worse_than_zero": worse, "factor": factor.tolist(),
            "scaled_misfit": np.clip(scaled, 0.0, None).tolist()}


def _offset_explains_most(offset: dict[str, Any] | None) -> bool:
    """Whether an initial state, offsets or a drift (``OutputError.initial_offset``) take at least half the misfit
    away: then they, not a sensor's sign, are what a failed fit's NEXT names.

    Examples
    --------
    >>> _offset_explains_most({"kind": "initial_state", "misfit": 0.628, "after": 0.564})  # a 3-mass chain's 10 %
    False
    >>> _offset_explains_most({"kind": "offset", "misfit": 4.8e-4, "after": 1e-5}), _offset_explains_most(None)
    (True, False)
    """
    if not offset or offset.get("after") is None or not offset.get("misfit"):
        return bool(offset)  # a level or a first sample, with no share measured: taken as the explanation
    return float(offset["after"]) <= 0.5 * float(offset["misfit"])


TIME_SCALE_MARGIN = 20.0
"""A start's modes are said to be out of the records' reach when every one lies more than this factor above their
Nyquist frequency (or the fastest moves by under 1/(10·this) over the longest record): the shake-table frame's
times in ms read as s (its lowest mode 28 times the Nyquist frequency then) is caught, a start 10 times off in its
parameters is not (on the time-series population's problems, n = 2, 3, 5, white and multisine inputs, the truth
and two informed and two uninformed starts each: 0 of 120 flagged; at a factor 1, 2 uninformed starts whose modes
lay 2-5 times above the Nyquist frequency were)."""


def _time_scale_mismatch(model: Any, records: list[Any], x0: Any) -> str | None:
    """A sentence when the user's start has no mode the records can show, else None: every mode far above their
    Nyquist frequency, or the fastest so slow that it barely moves over the longest record
    (:data:`TIME_SCALE_MARGIN`).

    A time column in ms read as s puts a structure's modes (3–10 Hz) far above the records' Nyquist frequency
    (0.1 Hz at dt = 5 s): a new user's shake-table record failed after 30 s with advice about starts and units in
    general. A record's time unit is the one thing about it no data test can check; the start's modes can.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> io = si.IOData(np.ones(100), np.zeros(100), dt=5.0)                 # 5 ms samples read as s
    >>> _time_scale_mismatch(model, [io], [1.0, 1.0, 3947.8])[:63]
    "every mode of the start (10 Hz) lies above the records' Nyquist"
    >>> _time_scale_mismatch(model, [si.IOData(np.ones(100), np.zeros(100), dt=0.005)], [1.0, 1.0, 3947.8]) is None
    True
    """
    from symid.fit.modes import estimate_poles

    poles = estimate_poles(model, np.asarray(x0, dtype=float))
    if poles is None:
        return None
    size = np.abs(poles)
    size = size[size > 1e-12 * max(float(size.max(initial=0.0)), 1e-300)]
    dts = [float(r.dt) for r in records if getattr(r, "dt", None)]
    if not size.size or not dts:
        return None
    nyquist = np.pi / min(dts)
    span = max(float(np.ptp(np.asarray(r.t, dtype=float))) for r in records)
    unit = getattr(records[0], "time_unit", None) or "s"
    hz = "Hz" if unit == "s" else f"cycles/{unit}"

    def f(w: float) -> str:
        return f"{w / (2 * np.pi):.3g} {hz}"

    modes = f(size.min()) if size.size == 1 or np.isclose(size.min(), size.max()) else \
        f"{f(size.min())} … {f(size.max())}"
    if size.min() > TIME_SCALE_MARGIN * nyquist:
        return (f"every mode of the start ({modes}) lies above the records' Nyquist frequency ({f(nyquist)}, "
                f"samples {min(dts):.4g} {unit} apart): the records cannot show them. Are the times in the unit "
                f"declared (milliseconds read as seconds make every sample interval 1000 times too long)? Else "
                f"the start is far from the system")
    if span > 0 and size.max() * span < 1.0 / (10 * TIME_SCALE_MARGIN):
        return (f"every mode of the start ({modes}) is so slow that it moves by under 0.5 % over the records "
                f"({span:.4g} {unit}): are the times in the unit declared (seconds read as milliseconds or hours "
                f"make the record 1000 or 1/3600 times as long)? Else the start is far from the system")
    return None


def _idle_input_parameters(model: Any, records: list[Any]) -> str | None:
    """'b2 multiplies input 'heater_kW' alone, which is zero in every record: …' for the parameters found only in
    the columns of B (and D) of inputs that are zero throughout the records, or None."""
    u = np.vstack([np.asarray(r.u, dtype=float) for r in records])
    zero = [j for j in range(u.shape[1]) if not np.any(u[:, j])]
    if not zero:
        return None
    maps = model.maps
    idle = []
    for k, name in enumerate(model.parameter_names):
        elsewhere = False
        for key, amap in maps.items():
            coef = np.asarray(amap.Xi[k])
            if key in ("B", "D"):
                coef = np.delete(coef, zero, axis=1)
            if np.any(coef):
                elsewhere = True
                break
        if not elsewhere:
            idle.append(name)
    if not idle:
        return None
    stated = getattr(records[0], "stated_units", None) or {}
    columns = stated.get("input", ())
    named = [repr(columns[j][0]) if len(columns) == u.shape[1] else str(j) for j in zero]
    which = f"input {named[0]}" if len(zero) == 1 else f"inputs {', '.join(named)}"
    return (f"{', '.join(idle)} {'multiplies' if len(idle) == 1 else 'multiply'} only {which}, zero in every "
            f"record: the data do not determine {'it' if len(idle) == 1 else 'them'} (the estimate is arbitrary, "
            f"its standard error infinite); drive that input in a record, or make {idle[0]} known")


def _within(solution: dict[str, float], bounds: dict[str, list[float]] | None) -> bool:
    """Does a solution lie within the fit's bounds (with the 1e-9 relative slack of rounding)?"""
    for name, (lo, hi) in (bounds or {}).items():
        v, slack = solution[name], 1e-9 * max(abs(solution[name]), 1e-300)
        if v < lo - slack or v > hi + slack:
            return False
    return True


def _outside_text(outside: list[dict[str, float]], bounds: dict[str, list[float]], names: list[str]) -> str:
    """'the other parameter values with this estimate's response (m = 620.4, …) have kr = 3e+05 above its upper
    bound 2e+05' (the reason the estimate is unique within the bounds)."""
    sol = outside[0]
    beyond = []
    for name, (lo, hi) in bounds.items():
        if sol[name] < lo:
            beyond.append(f"{name} = {sol[name]:.6g} below its lower bound {lo:g}")
        elif sol[name] > hi:
            beyond.append(f"{name} = {sol[name]:.6g} above its upper bound {hi:g}")
    values = ", ".join(f"{n} = {sol[n]:.6g}" for n in names)
    more = f" ({len(outside) - 1} more, outside them too)" if len(outside) > 1 else ""
    return f"the other parameter values with this estimate's response ({values}) have {'; '.join(beyond)}{more}"


def _nearest(others: list[dict[str, float]] | None, theta: np.ndarray, unc: Any) -> str:
    """'; at this estimate the other solution is m = 620.4, … (5.6 standard errors away in kr, the farthest)'
    for the solution nearest θ̂ in that measure ('' if none)."""
    if not others:
        return ""
    names = list(unc.parameter_names)
    se = np.asarray(unc.standard_errors, dtype=float)

    def far(sol: dict[str, float]) -> tuple[float, str]:
        return max((abs(sol[n] - c) / s if s > 0 and np.isfinite(s) else np.inf, n)
                   for n, c, s in zip(names, theta, se, strict=True))

    def apart(sol: dict[str, float]) -> tuple[float, str]:  # the largest relative difference from θ̂
        return max((abs(sol[n] - c) / abs(c) if c else abs(sol[n]), n) for n, c in zip(names, theta, strict=True))

    close = min(others, key=lambda sol: apart(sol)[0])
    rel, which = apart(close)
    if rel < MERGED:
        # a new user's oral dose (ka at a disposition rate: the flip-flop's two solutions meet there): "the other
        # solution is ka = 0.893804, …", the estimate itself, beside intervals that were all infinite
        return (f"; at this estimate another solution coincides with it (to {rel:.1g} relative, in {which}): the "
                f"estimate sits where two solutions meet, where the response cannot tell them apart to first order "
                f"(the Fisher information is singular there, so intervals through it are not finite); a value known "
                f"or bounds that keep one of the two (one rate above another) make the estimate a point of one "
                f"branch")
    best = min(others, key=lambda sol: far(sol)[0])
    dist, name = far(best)
    values = ", ".join(f"{n} = {best[n]:.6g}" for n in names)
    how = f" ({dist:.3g} standard errors away in {name}, the farthest)" if np.isfinite(dist) else ""
    more = f"; {len(others) - 1} more in options['solutions_at_estimate']" if len(others) > 1 else ""
    return f"; at this estimate the other solution is {values}{how}{more}"


def _same_unit(a: str, b: str) -> bool:
    """Two spellings of one unit: equal but for spaces, µ written u (``mg / h`` is ``mg/h``, ``µg`` is ``ug``), the
    degree sign written deg (``°C`` is ``degC``, ``°`` is ``deg``) and the case of an angle's name (``DEG`` is
    ``deg``); otherwise case counts (``Mg`` is not ``mg``)."""
    norm = [re.sub(r"\s+", "", x).replace("µ", "u").replace("μ", "u").replace("°", "deg") for x in (a, b)]
    return norm[0] == norm[1] or (norm[0].lower() == norm[1].lower() and norm[0].lower() in _CASELESS)


_CASELESS = frozenset({"deg", "rad", "degree", "degrees", "radian", "radians"})


def _temperature(unit: str) -> str | None:
    """The temperature scale a unit names: "K", "C" or "F" (any spelling: °C, degC, kelvin), else None."""
    u = unit.strip().replace("°", "").replace("deg", "").replace(" ", "").lower()
    return {"k": "K", "kelvin": "K", "c": "C", "celsius": "C", "f": "F", "fahrenheit": "F"}.get(u)


def unit_mismatches(model: Any, data: Any) -> list[str]:
    """What a data file's stated input and output units (``data.stated_units``) say against the model's declared
    ones (``model.io_units``, from a model file): one sentence per channel whose units differ; [] when either
    side states none. A model file's ``time_unit`` (``model.io_units["time"]``) is compared with a record's
    ``time_unit`` and with the rad/s of a frequency response or spectra.

    symid converts neither, so a factor between them goes into the estimates without a word: a new user's
    encoder angles in degrees fitted a model in radians with ``success=True`` and every inertia off by π/180.

    Examples
    --------
    >>> import symid as si
    >>> k, g = si.parameters("k g", positive=True)
    >>> model = si.StateSpaceModel(A=[[-k]], B=[[g]], C=[[1]])
    >>> model.io_units = {"input": ("A",), "output": ("rad",)}
    >>> io = si.IOData([[1.0], [0.0], [0.0]], [[0.0], [1.0], [0.5]], 0.1)
    >>> object.__setattr__(io, "stated_units", {"input": (("i", "A"),), "output": (("theta", "deg"),)})
    >>> unit_mismatches(model, io)[0][:68]
    "the file states deg for output 'theta'; the model file's output unit"
    """
    declared = getattr(model, "io_units", None) or {}
    records = data if isinstance(data, (list, tuple)) else [data]
    out: list[str] = []
    for record in records:
        stated = getattr(record, "stated_units", None) or {}
        for role in ("input", "output"):
            for (column, have), want in zip(stated.get(role, ()), declared.get(role, ()), strict=False):
                if have and want and not _same_unit(have, want):
                    where = f" (in {stated['file']})" if len(records) > 1 and stated.get("file") else ""
                    # kelvin against degrees Celsius (or Fahrenheit) is an offset, not a factor (a new user's
                    # temperatures in K beside a model in °C were told of a factor)
                    offset = {_temperature(have), _temperature(want)} in ({"K", "C"}, {"K", "F"}, {"C", "F"})
                    what = ("an offset between them (and for °F a factor) goes into the estimates and the initial "
                            "state" if offset else "a factor between them goes into the estimates")
                    text = (f"the file states {have} for {role} {column!r}; the model file's {role} unit is {want}: "
                            f"symid converts neither, so {what}; convert the data or the model{where}")
                    if text not in out:
                        out.append(text)
        time_unit = getattr(record, "time_unit", None) if hasattr(record, "t") else None
        model_time = (declared.get("time") or (None,))[0]
        implied = model_time is None and bool(declared.get("input"))
        if implied:  # a model file that states its units but no time_unit: its rates are per second (README)
            model_time = "s"
        on_omega = time_unit is None and type(record).__name__ in ("FrequencyData", "SpectralData")
        if model_time is not None and (time_unit or ("s" if on_omega else model_time)) != model_time:
            # a new user's rates per minute on a record read in seconds: success=True, every rate 60 times off
            text = (("the model file states no time_unit, so its rates are per s (its default), but the "
                     if implied else f"the model file's time unit is {model_time} (its rates are per {model_time}), "
                                     f"but the ")
                    + (f"record's is {time_unit}: read the record in {model_time} (time_unit={model_time!r}; "
                       f"--time-unit {model_time})" if not on_omega else
                       f"frequencies are in rad/s: give ω in rad/{model_time} (times the seconds in one {model_time})")
                    + f" or write the model's rates per {time_unit or 's'}"
                    + (f" (if they are: time_unit = {time_unit!r} in the model file)" if implied and time_unit else "")
                    + ": symid converts no rate, so a factor between them goes into the estimates")
            if text not in out:
                out.append(text)
        for role in ("input", "output"):
            for want in declared.get(role, ()):
                per = _per_time(want)
                if per is not None and time_unit is not None and per != time_unit:
                    # a new user's accelerations in m/s^2 with the record read in ms: no fit, and a generic message
                    text = (f"the model file's {role} unit {want} is per {per}, but the record's time unit (the "
                            f"model's time axis) is {time_unit}: read the record in {per} (time_unit={per!r}; "
                            f"--time-unit {per}) or state the unit per {time_unit}")
                    if text not in out:
                        out.append(text)
    return out


_PER_TIME = re.compile(r"/\s*\(?\s*(s|sec|ms|us|µs|min|h|hr|d)\b")
"""A time unit after a slash in a unit (m/s^2, rad/s, mg/h, cm³/(s·%))."""


def _per_time(unit: str) -> str | None:
    """The canonical time unit a unit is per (``m/s^2`` → ``s``, ``mg/h`` → ``h``), or None.

    Examples
    --------
    >>> from symid.fit.identify import _per_time
    >>> _per_time("m/s^2"), _per_time("mg/h"), _per_time("cm³/(s·%)"), _per_time("N m"), _per_time("rad/s")
    ('s', 'h', 's', None, 's')
    """
    from symid.data.units import canonical_unit
    from symid.errors import DataError

    m = _PER_TIME.search(str(unit))
    if m is None:
        return None
    try:
        return canonical_unit(m.group(1).replace("µ", "u"), "time", "unit")
    except DataError:
        return None


def identify(model: Any, data: Any, method: str | None = None, *, x0: Any = None, starts: int = 1,
             seed: int | None = None, polish: bool = False, progress: bool | None = None,
             identifiability_check: bool = True, noise_floor: float | None = None,
             noise_std: Any = None, draws: str | None = None, **options: Any) -> IdentificationResult:
    """Estimate the parameters of a symbolic model from data.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
        The grey-box model.
    data : FrequencyData, SpectralData, BlackBox or IOData
        The measurements. The data kind picks the formulation (:mod:`symid.fit.registry`):
        a frequency response goes to :mod:`symid.fit.frf` (thesis ch. 3, 4), spectra to
        :mod:`symid.fit.spectra` (ch. 5), input/output records (``IOData``, ``TimeSeries``)
        to :mod:`symid.fit.timeseries` (output error on the samples; its ``"scr"``,
        ``"als"`` and ``"gb"`` run N4SID and an exact zero-order-hold ``d2c`` first and
        then the similarity formulations) and a black box to :mod:`symid.fit.similarity`
        (ch. 6, 7).
    method : str, optional
        Default: the data kind's default (:attr:`symid.fit.registry.DataKind.default_method`):
        ``"auto"`` for a frequency response (:mod:`symid.fit.frf.lm`: least squares on
        log-parameters, restarted around the start until the estimate fits; the most
        reliable method on the generated population of ``benchmarks/population.py``) and
        for input/output records (:mod:`symid.fit.timeseries.auto`: output error on the
        samples, restarted, with a start from an N4SID black box; measured on
        ``benchmarks/timeseries_population.py``) and for spectra (:mod:`symid.fit.spectra.auto`:
        IPOPT restarted around the typical values, then SCR; ``benchmarks/psd_auto.py``), ``"scr"``
        for black boxes.
        Others: ``"scr"`` (sequential convex relaxation), ``"ipopt"`` (nonlinear least
        squares with CasADi/IPOPT), ``"ls"`` (a linear special case, where it applies),
        ``"lm"`` (one least-squares run, frequency response), for black-box data and
        records ``"als"``, ``"gb"``, and for records ``"oe"`` (output error from the
        start), ``"srivc"`` and ``"svf"`` (each data kind's ``methods``:
        :func:`symid.fit.registry.data_kinds`). ``"scr"`` on a second-order model whose C or
        B is known, square and invertible runs the exact linear least squares instead
        (reported as method ``"ls"``; ``force_scr=True`` runs SCR anyway). ``"<method>+polish"``
        (as :func:`symid.compare` names it) is ``method`` with ``polish=True``.
    x0 : dict or sequence, optional
        A start; it becomes the first of ``starts``.
    starts : int
        Number of starts (1 … 100 000): ``x0`` first when given, then seeded draws per
        parameter name (:func:`symid.fit.starts.draw_starts`); every method gets the
        same starts for the same ``seed``.
    draws : {"scale", "normal"}, optional
        How the random starts are drawn. ``"scale"`` (default for a frequency response):
        log-uniformly within a factor 3 of each parameter's typical value — the
        ``scale=`` option when given, else read off the data by dimensional analysis
        (:func:`symid.fit.frf.scale.typical_scale`: band centre and response level).
        On a frequency response without ``x0``, the first start is the black-box start
        (:func:`symid.fit.frf.modal.black_box_start`: the model's poles placed on those
        of a vector fit of the data), and the draws are around its magnitudes.
        On time series the draws are ``"scale"`` too by default when there are typical
        values: ``scale=``, else those read off the records' frequency response
        (:func:`symid.fit.timeseries.scale.typical_scale`: Welch H1, then the same
        dimensional analysis; none for non-uniform samples or a zero input), and on spectra
        (:func:`symid.fit.spectra.scale.typical_scale`: the response level Φyy / Φuu implies).
        ``"normal"`` (default for other data, and for time series without typical
        values): N(0, 1), positive parameters in absolute value, and θ = 0 first for a
        state-space model, as in the thesis (ch. 3-4).
    seed : int, optional
        Seed of the random starts (``None``: a fresh one).
    polish : bool
        After the method, refine the best estimate with the method's declared polisher
        (:meth:`symid.fit.base.Estimator.polisher`, IPOPT; kept only when it lowers the
        misfit); reported as its own result in ``result.polished`` (method
        ``"<method>+polish"``, time = all starts + polish). An :class:`OptionError` for a
        method without one.
    progress : bool, optional
        Show a progress bar over the starts (default: when there is more than one start
        and standard error is a terminal or a notebook's; elsewhere a line at most every
        30 s; one start says "still estimating" after 10 s, then every 20 s). ``False``:
        nothing.
    identifiability_check : bool
        Before estimating, run the cheap local identifiability test and emit an
        :class:`~symid.IdentifiabilityWarning` naming the parameters that no data of
        this kind can determine (default True); after an estimate that fits, the global
        test within 3 s (:func:`symid.structural.analyse.global_check`, cached per model
        structure; one that does not decide is said in ``summary()``, ``options["global_undecided"]``):
        where other parameter values give the same response
        (a flip-flop of two rate constants), a warning says so, and ``summary()`` too,
        with the other values at the estimate (``options["solutions_at_estimate"]``).
        Where every one of them lies outside the fit's ``bounds``, the estimate is unique
        within them: no warning, and ``options["unique_within_bounds"]`` says why.
    noise_floor : float, optional
        The relative misfit noise alone leaves at the true parameters (ε² for relative
        noise of level ε); used to judge ``success`` (:mod:`symid.fit.success`). Default:
        the misfit ``noise_std`` leaves when it is given, else estimated from the residual
        where the data kind allows it.
    noise_std : float or array_like, optional
        Standard deviation of the measurement noise of every measured value, in data
        units (a number, one per frequency or sample, or the data's full shape), for the
        uncertainty in ``result.uncertainty`` and, unless ``noise_floor`` is given, the noise
        floor that judges ``success``; default: estimated from the residuals
        (:mod:`symid.fit.uncertainty`).
    **options
        The method's options (see each estimator's docstring and the options table in
        :mod:`symid.fit.base`); an unknown name or a bad value is an
        :class:`~symid.errors.OptionError` before anything runs. A ``time_limit`` is each
        start's budget: the call also spends time outside the starts (typical values from the
        data, the identifiability checks, the covariance at the estimate, a polish; seconds on
        records of thousands of samples), reported as ``options["identify_s"]`` beside the
        starts' ``wall_time``.

    Returns
    -------
    IdentificationResult
        The best start by data misfit, and every start's outcome in ``result.starts``.
        ``success`` means the estimate fits the data (the solver's own verdict is ``status``).

    Warns
    -----
    IdentifiabilityWarning
        Before estimating, when the local test finds parameters no data of this kind can
        determine (``identifiability_check``); after, when other starts fit the data as well
        with different parameters (:meth:`IdentificationResult.alternatives`: several exact
        solutions, or parameters the data do not pin down).

    Raises
    ------
    symid.interrupt.Interrupted
        On Ctrl-C after at least one start finished (a ``KeyboardInterrupt``, so a
        script stops); its ``partial`` is the result of the finished starts, with
        ``options["interrupted"] = True``. Ctrl-C stops a running start at once (IPOPT
        and Clarabel within one iteration).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, {"m": 2.0, "c": 0.5, "k": 3.0}, np.linspace(0.5, 2.0, 5))
    >>> res = si.identify(model, frf, method="ls")
    >>> [round(v, 6) for v in res.theta.values()], res.success
    ([2.0, 0.5, 3.0], True)
    """
    t_call = time.perf_counter()
    if method is None:
        from symid.fit.registry import data_kind

        method = data_kind(data).default_method
    polish = check_bool("polish", polish)
    if isinstance(method, str) and method.endswith("+polish"):  # as si.compare names it: the method, polished
        method, polish = method.removesuffix("+polish"), True
    identifiability_check = check_bool("identifiability_check", identifiability_check)
    if progress is not None:
        progress = check_bool("progress", progress)
    check_model(model)
    # a model file's start, scale and bounds name every parameter; with some made known (with_known) they still serve
    known = model.known_values if hasattr(model, "known_values") else {}
    for text in _known_outside(known, options.get("bounds")):
        warnings.warn(text, DataWarning, stacklevel=2)
    x0 = without_known(x0, known)
    options = {k: (without_known(v, known) if k in ("scale", "bounds") else v) for k, v in options.items()}
    options = scale_by_name(options, model.parameter_names)  # a dict by name, as x0 may be
    estimator = prepare(model, data, method, options, noise_floor=noise_floor)
    for text in unit_mismatches(model, data):
        warnings.warn(text, DataWarning, stacklevel=2)
    if noise_std is not None and not isinstance(estimator, FisherInformation):
        raise OptionError(f"noise_std is for the uncertainty of the estimate, which method {estimator.method!r} "
                          "on this data kind does not give")
    if noise_std is not None and estimator.noise_floor is None:
        # the noise the user declared also judges the fit: the misfit it alone leaves at the truth, Σ of the squared
        # standard deviations of the misfit's weighted residual (a new user's tank levels as deviations, 0.2 cm noise
        # on a ±1.5 cm signal: a white residual at misfit 1.9e-2 was refused as "over 10 % rms")
        std, _ = estimator.given_noise(noise_std)
        estimator.noise_floor = float(np.sum(np.asarray(std, dtype=float) ** 2))
    polisher = estimator.polisher() if polish else None
    if polish and polisher is None:
        raise OptionError(f"method {estimator.method!r} has no polish step (polish=True applies to SCR)")
    if polisher is not None:
        polisher.noise_floor = estimator.noise_floor  # the polished estimate is judged by the same rule
    # linear least squares (and SRIVC from its own least-squares start): the start plays no part
    linear = estimator.method in ("ls", "svf") or (estimator.method == "srivc" and estimator.options["init"] == "ls")
    x0s = draw_starts(model, data, starts, seed, x0, draws=draws, scale=options.get("scale"), black_box=not linear,
                      bounds=options.get("bounds"), data_typical=getattr(estimator, "data_typical", None))
    if x0 is not None:
        estimator.check_start(x0s[0])  # the user's own start: refused with a reason (e.g. outside the bounds)
    records = data if isinstance(data, (list, tuple)) else [data]
    time_scale = (_time_scale_mismatch(model, records, x0s[0]) if x0 is not None and hasattr(records[0], "t")
                  else None)
    if time_scale is not None:  # said before the fit (the records' time unit, or a start far off), and in summary()
        warnings.warn(time_scale, DataWarning, stacklevel=2)
    gap = None
    if hasattr(records[0], "t"):
        from symid.fit.timeseries.records import sampling_gap

        if (gap := sampling_gap(records)) is not None:  # before the fit, and in summary()
            warnings.warn(gap, DataWarning, stacklevel=2)
    check_s, not_local = None, ()
    if identifiability_check:
        from symid.structural.analyse import warn_if_not_identifiable

        t_check = time.perf_counter()
        not_local = warn_if_not_identifiable(model, stacklevel=2)
        check_s = time.perf_counter() - t_check
    if linear:  # one start says it all
        x0s = x0s[:1]
    options_used = dict(estimator.options)
    if check_s is not None:  # reported beside the starts' time (summary), not in it
        options_used["identifiability_check_s"] = check_s
    outcomes: list[StartOutcome] = []
    try:
        # one start shows no bar: by default a line after 10 s, then every 20 s, says a long one is alive
        with Heartbeat(f"{estimator.method}, 1 start", enabled=progress is None and len(x0s) == 1):
            for x in progress_bar(x0s, desc=f"{estimator.method} starts", enabled=progress):
                outcomes.append(estimator.run(x))
    except KeyboardInterrupt:
        if not outcomes:
            raise
        partial = IdentificationResult.from_starts(estimator.method, model.parameter_names, outcomes,
                                                   cost_kind=estimator.cost_kind,
                                                   options={**options_used, "interrupted": True})
        raise Interrupted(f"identify() interrupted after {len(outcomes)} of {len(x0s)} starts; "
                          f"the finished starts are in the exception's .partial result", partial) from None
    result = IdentificationResult.from_starts(estimator.method, model.parameter_names, outcomes,
                                              cost_kind=estimator.cost_kind, options=options_used)
    reweighs = estimator.method in ("lm", "auto") or estimator.options.get("weighting") == "variance"
    if reweighs and hasattr(estimator, "reweigh_relative") and np.all(np.isfinite(result.theta_vector)):
        # variance="relative" (weighting="variance" on spectra): the weights of the best start's own estimate
        estimator.reweigh_relative(result.theta_vector)
    if (isinstance(estimator, FisherInformation) and np.all(np.isfinite(result.theta_vector))
            and np.isfinite(result.cost)):  # not where the model cannot be evaluated (e.g. a mass on its bound 0)
        # declared by the estimator (symid.fit.uncertainty): covariance of θ̂ at the best estimate
        result = _bounds_reject(dataclasses.replace(result, uncertainty=estimator.uncertainty(
            result.theta_vector, model.parameter_names, noise_std=noise_std)))
    if polisher is not None:
        from symid.fit.polish import polish_outcome

        t0 = time.perf_counter()
        out = polish_outcome(polisher, result.best_start)
        # the polished estimate cost every start plus the polish
        out = dataclasses.replace(out, wall_time=result.wall_time + time.perf_counter() - t0)
        polished = IdentificationResult.from_starts(f"{estimator.method}+polish", model.parameter_names, [out],
                                                    cost_kind=estimator.cost_kind,
                                                    options={"polish": polisher.method})
        if (isinstance(polisher, FisherInformation) and np.all(np.isfinite(polished.theta_vector))
                and np.isfinite(polished.cost)):
            polished = _bounds_reject(dataclasses.replace(polished, uncertainty=polisher.uncertainty(
                polished.theta_vector, model.parameter_names, noise_std=noise_std)))
        result = dataclasses.replace(result, polished=polished)
    extra: dict[str, Any] = {}
    if (result.options.get("initial_state") == "estimate" and hasattr(estimator, "initial_states")
            and np.all(np.isfinite(result.theta_vector))):
        # the initial states estimated with θ (the least-squares ones at θ̂), one per record
        extra["initial_states"] = [np.asarray(x, dtype=float).tolist()
                                   for x in estimator.initial_states(result.theta_vector)]
    if not result.success and hasattr(estimator, "initial_offset") and np.all(np.isfinite(result.theta_vector)):
        # a record that does not start where the model does: the likeliest reason a time-series fit fails
        offset = estimator.initial_offset(result.theta_vector)
        if offset is not None:
            columns = (getattr(records[0], "stated_units", None) or {}).get("output", ())
            if len(columns) == model.n_outputs:
                offset = {**offset, "output_names": [str(c[0]) for c in columns]}
            extra["initial_offset"] = offset
    if time_scale is not None:
        extra["time_scale"] = time_scale
    if gap is not None:
        extra["sampling_gap"] = gap
    if hasattr(records[0], "t") and (idle := _idle_input_parameters(model, records)) is not None:
        # a parameter that multiplies only an input the records hold at zero: its estimate is arbitrary (a new
        # user's heater column left at 0: b2 = 3.8e-12, success, said only as a near-singular direction)
        extra["not_determined"] = idle
        warnings.warn(idle, DataWarning, stacklevel=2)
    if (not result.success and hasattr(records[0], "t") and hasattr(estimator, "simulate")
            and hasattr(estimator, "observed") and model.n_outputs > 1 and np.all(np.isfinite(result.theta_vector))):
        # which output the misfit is in (a new user's building, one accelerometer reversed: nothing said which)
        per = _misfit_per_output(estimator, result.theta_vector, records)
        if per is not None:
            extra["misfit_per_output"] = per
    if not result.success and hasattr(records[0], "t"):
        # the columns read the wrong way round: no start or offset fixes that (symid.fit.timeseries.roles)
        from symid.fit.timeseries.roles import swapped_roles

        roles = swapped_roles(records)
        if roles is not None:
            extra["swapped_roles"] = roles
    if hasattr(records[0], "t") and getattr(records[0], "time_unit", None):  # what the rates are per
        extra["time_unit"] = records[0].time_unit
    # the estimate's modes, in summary(): a frequency axis in Hz read as rad/s moves every one by 2π (a new user's
    # servo: the command line printed them, the Python result held them nowhere)
    if np.all(np.isfinite(result.theta_vector)) and (modes := modes_line(model, result.theta_vector,
                                                                        extra.get("time_unit"))):
        extra["modes"] = modes
    if result.polished is not None and np.all(np.isfinite(result.polished.theta_vector)) and (
            modes := modes_line(model, result.polished.theta_vector, extra.get("time_unit"))):
        result = dataclasses.replace(result, polished=dataclasses.replace(
            result.polished, options={**result.polished.options, "modes": modes}))
    if not_local:  # said in the summary too (the warning alone went to a terminal, not to summary.txt)
        extra["not_identifiable"] = {"parameters": list(not_local),
                                     "from_rest_only": getattr(model, "initial_state_kind", "zero") in ("known",
                                                                                                       "affine")}
    if identifiability_check and not not_local and result.success:
        from symid.structural.analyse import GLOBAL_CHECK_BUDGET, global_check

        t_check = time.perf_counter()
        several, decided = global_check(model)
        extra["identifiability_check_s"] = (check_s or 0.0) + time.perf_counter() - t_check
        if not decided:  # said, not left silent: the answer must not depend on the machine's load (a new user's
            # LC ladder came back as its mirror image, warned in 1 of 4 runs)
            extra["global_undecided"] = (
                f"whether other parameter values give this estimate's response was not decided within "
                f"{GLOBAL_CHECK_BUDGET:g} s (si.identifiability(model) decides it, without a time limit: "
                f"timeout=None): a structure with several solutions (a ladder's mirror image, a flip-flop) fits "
                f"as well from another start")
        if several is not None:
            extra["several_solutions"] = several
            from symid.structural.analyse import solutions_at

            t_at = time.perf_counter()
            others = solutions_at(model, result.theta_vector)
            extra["identifiability_check_s"] += time.perf_counter() - t_at
            bounds = result.options.get("bounds")
            outside = [s for s in others or [] if not _within(s, bounds)]
            others = None if others is None else [s for s in others if _within(s, bounds)]
            if others:
                extra["solutions_at_estimate"] = others
            if outside:
                extra["solutions_outside_bounds"] = outside
            if others == [] and outside:  # every other solution at θ̂ is excluded by the bounds the user gave
                extra["unique_within_bounds"] = _outside_text(outside, bounds, list(model.parameter_names))
            else:
                warnings.warn(several, IdentifiabilityWarning, stacklevel=2)
            if result.uncertainty is not None and "unique_within_bounds" not in extra:
                unc = result.uncertainty
                nearest = _nearest(others, result.theta_vector, unc)
                note = f"{unc.note + '. ' if unc.note else ''}{_SEVERAL_INTERVALS}{nearest}"
                result = dataclasses.replace(result, uncertainty=dataclasses.replace(unc, note=note))
    result = dataclasses.replace(result, options={**result.options, **extra})
    ambiguity = result.ambiguity()
    # warned where the estimate fits or nearly does; far from a fit (over 10 % rms, the success rule's "far") the
    # summary still says it, beside the NEXT line that matters more (a new user's room at misfit 0.82 was warned)
    if ambiguity is not None and (result.success or result.cost <= 1e-2):
        warnings.warn(ambiguity, IdentifiabilityWarning, stacklevel=2)
    if (isinstance(estimator, FrfEstimator) and not result.success and np.all(np.isfinite(result.theta_vector))
            and not result.options.get("interrupted") and not result.on_bounds
            and not result.fit.startswith("pulled beyond")):  # a fit the bounds explain is not tried again
        # a failed fit tried again with an input or output negated (symid.fit.frf.polarity): reversed polarity is
        # what "more starts" and "check the units" never find
        from symid.fit.frf.polarity import polarity_flip

        with Heartbeat("the failed fit tried with the response negated: a reversed sensor?",
                       enabled=progress is not False):
            flip = polarity_flip(model, estimator.data, result.theta_vector, scale=options.get("scale"),
                                 bounds=options.get("bounds"), noise_floor=estimator.noise_floor,
                                 start=x0s[0] if x0 is not None else None)
        if flip is not None:
            result = dataclasses.replace(result, options={**result.options, "polarity": flip})
    explained = (result.success or not np.all(np.isfinite(result.theta_vector)) or result.options.get("interrupted")
                 or result.on_bounds or result.fit.startswith("pulled beyond")
                 or any(result.options.get(k) for k in ("swapped_roles", "not_determined", "time_scale"))
                 or _offset_explains_most(result.options.get("initial_offset")))
    if (hasattr(records[0], "t") and not explained and estimator.method in ("oe", "auto") and "hold" not in options
            and estimator.options.get("hold") == "zoh"):
        # the default hold on a measured input (a new user's shake-table record: 161 s, failed, parameters 1-10 %
        # off; with hold="bandlimited" within 0.1 %): tried once from the failed estimate (symid.fit.timeseries.
        # holdprobe), and said first when it fits
        from symid.fit.timeseries.holdprobe import hold_probe

        with Heartbeat("the failed fit tried with the input band-limited between samples: a measured input?",
                       enabled=progress is not False):
            probe = hold_probe(model, data, result.theta_vector, options, noise_floor=estimator.noise_floor,
                               spent=result.wall_time)
        if probe is not None:
            result = dataclasses.replace(result, options={**result.options, "hold_probe": probe})
    if (hasattr(data, "t") and not explained and np.all(np.asarray(model.positive, dtype=bool))
            and not result.options.get("hold_probe")):
        # one record of samples, unless what its set-up says explains the failure: the same flips, tried on the
        # response of an N4SID black box of the record (sign-agnostic, fast to fit; a new user's building with one
        # accelerometer reversed was told "more starts"; on a 3-mass chain with a position sensor reversed, an
        # initial state explaining 10 % of the misfit had kept the try from running)
        from symid.fit.frf.polarity import BLACK_BOX_FLOOR, polarity_flip
        from symid.fit.timeseries.bbstart import black_box_response

        with Heartbeat("the failed fit tried on the records' black-box response with outputs negated: a reversed "
                       "sensor?", enabled=progress is not False):
            bb = black_box_response(model, data)
            flip = None if bb.frf is None else polarity_flip(
                model, bb.frf, result.theta_vector, scale=options.get("scale"), bounds=options.get("bounds"),
                start=x0s[0] if x0 is not None else None, misfit_below=BLACK_BOX_FLOOR)
        if flip is not None:
            result = dataclasses.replace(result, options={**result.options, "polarity": {
                **flip, "via": "the response of a black box of the records"}})
    if hasattr(data, "Phi_yy") and np.all(np.isfinite(result.theta_vector)):
        # output spectra fix H only up to Φuu's scale (symid.fit.spectra.outputonly): a new user's footbridge with a
        # force intensity 4 times too large came back with every parameter 2.08 times too large, with success
        from symid.fit.spectra.outputonly import output_only_scale

        scale_note = output_only_scale(model, data, result.theta_vector)
        if scale_note is not None:
            result = dataclasses.replace(result, options={**result.options, "output_only_scale": scale_note})
            warnings.warn(scale_note["text"], DataWarning, stacklevel=2)
        if getattr(estimator, "sensor_noise", False) and (nu := estimator.sensor_noise_at(result.theta_vector)) \
                is not None:  # the nuisance fitted beside the model (symid.fit.spectra.welch): what it took
            result = dataclasses.replace(result, options={**result.options, "sensor_noise_levels": nu.tolist()})
    made = getattr(data, "estimated_from", None) or {}
    if (hasattr(estimator, "data_shift") and made.get("nperseg") and np.all(np.isfinite(result.theta_vector))
            and result.uncertainty is not None):
        # a Welch estimate whose lines are too coarse for a fitted mode's bandwidth (symid.fit.frf.leakage): a new
        # user's shake-table frame, c3 11.6 % high at 5.2 standard errors, with success
        from symid.fit.frf.leakage import leakage_note

        leak = leakage_note(estimator, data, result.theta_vector, result.uncertainty.standard_errors)
        if leak is not None:
            result = dataclasses.replace(result, options={**result.options, "leakage": leak})
            warnings.warn(leak["text"], DataWarning, stacklevel=2)
    if isinstance(estimator, FrfEstimator) and not result.success and made and made.get("hold") is None:
        # a response estimated from held records without hold=: the sampled system's, not H(jω) (two new users'
        # acceleration records, told "units, local minimum"); said beside the other advice (summary)
        result = dataclasses.replace(result, options={**result.options, "sampled_response": (
            f"this response was estimated from sampled records (si.estimate_frf, dt = {made['dt']:.4g} s) without "
            f"hold=: if the input was held between samples (a DAC, a controller, si.simulate_io), it is the sampled "
            f"system's response, off H(jω) by the hold's half-sample delay and sinc and by aliasing (most with an "
            f"acceleration output); estimate it with hold='zoh', or fit the records as samples (si.identify(model, "
            f"io): output error models the hold exactly)")})
    if isinstance(estimator, FrfEstimator) and estimator.line_weights is None \
            and np.all(np.isfinite(result.theta_vector)):
        # of a fit the success rule accepted (a failed one misses every line: a new user's start at 1.0 was told
        # "266 weak lines missed")
        weak = weak_lines_missed(model, estimator.data, result.theta_vector) if result.success else None
        if weak is not None:
            result = dataclasses.replace(result, options={**result.options, "weak_lines_missed": weak})
            warnings.warn(weak, DataWarning, stacklevel=2)
        # a fit's residual is noise, a failed one's is not (the note would say nothing true of it)
        relative = (None if result.cost <= EXACT_FIT or not result.success else
                    relative_noise_note(model, estimator.data, result.theta_vector))
        if relative is not None:  # said in the summary (a new user's load angle over 5 decades: Jm on its bound)
            result = dataclasses.replace(result, options={**result.options, "relative_noise": relative})
    far = _far_from_start(result, x0s[0] if x0 is not None else None, options.get("scale"), model)
    if far is not None:  # said in the summary too (a new user's time column in s read as h: success, C1 3600× off)
        result = dataclasses.replace(result, options={**result.options, "far_from_start": far})
        warnings.warn(far["text"], DataWarning, stacklevel=2)
    if noise_std is not None and result.uncertainty is not None:
        # the declared noise judges the fit (noise floor): a residual improbably smaller than it says the noise_std
        # is too large, and then a wrong model fits (a new user's k2 5 % off, noise_std 3 times the noise's: success,
        # residual/noise rms 0.55, said nowhere but in the summary's uncertainty line)
        text = too_small_residual(result.uncertainty.residual_ratio, estimator.n_data(), model.n_parameters)
        if text is not None:
            warnings.warn(text, DataWarning, stacklevel=2)
    result = _withhold_intervals(result)
    # the whole call (setup, typical values, the checks, the starts, uncertainty, polish and the tries after a failed
    # fit), beside the starts' time (a new user's shake-table record: "the whole call 120 s" for 161 s, the try with
    # outputs negated left out)
    return dataclasses.replace(result, options={**result.options, "identify_s": time.perf_counter() - t_call})


FAILED_FIT_NOTE = ("the estimate does not fit the data: no confidence interval is given around it (the covariance "
                   "is the Fisher information's at the estimate)")
"""The uncertainty's note of an estimate that does not fit (its intervals are NaN)."""


def _withhold_intervals(result: IdentificationResult) -> IdentificationResult:
    """The result with NaN intervals around an estimate (or polished estimate) that does not fit the data.

    Intervals describe an estimate that fits; around one that does not they mean nothing, and a script that read
    them got them (a new user's shake-table record fitted with the wrong hold: none of 8 intervals held the truth;
    the summary said "not shown")."""

    def withheld(res: IdentificationResult) -> IdentificationResult:
        unc = res.uncertainty
        if res.success or unc is None or not np.any(np.isfinite(unc.intervals)):
            return res
        note = f"{unc.note}. {FAILED_FIT_NOTE}" if unc.note else FAILED_FIT_NOTE
        return dataclasses.replace(res, uncertainty=dataclasses.replace(
            unc, intervals=np.full(np.shape(unc.intervals), np.nan), note=note))

    result = withheld(result)
    if result.polished is not None:
        result = dataclasses.replace(result, polished=withheld(result.polished))
    return result


FAR_FROM_START = 30.0
"""A successful estimate whose parameters lie, in the median, more than this factor from the user's own start (or
typical values) gets a note: the data's units are the likelier cause (:func:`_far_from_start`). Measured on the 2301
right fits the population benchmark logged (``benchmarks/far_from_start.py``): 0 flagged at 30, 59 at 20, 119 at 10;
a time in min read as s (60 times) is caught at 30, not at 100."""


def _far_from_start(result: IdentificationResult, x0: Any, scale: Any, model: Any) -> dict[str, Any] | None:
    """A note when a fit lies far from what the user said of the parameters, else None.

    A time column in seconds read as hours makes every rate 3600 times another's and the model fits as well (a new
    user's thermal network: success, capacitances 3600 times the model file's start), as milliseconds read as
    seconds do by 1000; only the user's own start (``x0``), else typical values (``scale``), can tell. The median
    over the nonzero parameters of |log₁₀(θ̂ / reference)| above log₁₀ :data:`FAR_FROM_START` says so (a typical
    value 34 times off on a right fit, a new user's loudspeaker, is one parameter, not the median). Taken per role
    (the springs alone, which a frequency in Hz read as rad/s moves by 40 while the masses of an acceleration
    response stay) it would flag 256 of the population's 2301 right fits at 30: not done.
    """
    if not result.success:
        return None
    theta = np.asarray(result.theta_vector, dtype=float)
    if x0 is not None:
        ref, what = np.asarray(x0, dtype=float).reshape(-1), "your start (x0)"
    elif scale is not None:
        ref, what = np.asarray(scale, dtype=float).reshape(-1), "your typical values (scale=)"
        ref = np.full(theta.shape, ref[0]) if ref.size == 1 else ref
    else:
        return None
    if ref.shape != theta.shape:
        return None
    use = np.isfinite(theta) & np.isfinite(ref) & (theta != 0) & (ref != 0)
    if np.count_nonzero(use) < 2:
        return None
    logs = np.log10(np.abs(theta[use]) / np.abs(ref[use]))
    median = float(np.median(np.abs(logs)))
    if median <= math.log10(FAR_FROM_START):
        return None
    names = [n for n, u in zip(model.parameter_names, use, strict=True) if u]
    k = int(np.argmax(np.abs(logs)))
    off = int(np.count_nonzero(np.abs(logs) > math.log10(FAR_FROM_START)))
    text = (f"the estimate fits, but lies far from {what}: {off} of {len(names)} parameters more than "
            f"{FAR_FROM_START:g} times off (median factor {10 ** median:.3g}; {names[k]} {10 ** logs[k]:.3g} times "
            f"its value there). If {what} is right, check the data's units: a time column in s read as h makes every "
            f"rate 3600 times off, ms read as s 1000 times, a frequency in Hz read as rad/s 2π; an input or output "
            f"in other units than the model's (kW for W, mm for m, degrees for radians) moves the parameters that "
            f"scale it by that factor")
    return {"median_factor": 10 ** median, "parameters_off": off, "text": text}


def _bounds_reject(result: IdentificationResult) -> IdentificationResult:
    """A fit whose uncertainty says the data reject the bounds it sits on (:meth:`Uncertainty.bounds_rejected`) does
    not fit the data: ``success`` False, and the fit line says why (a new user's frequency response in Hz read as
    rad/s was a success with a resistance pulled 12 standard errors below 0)."""
    unc = result.uncertainty
    reason = unc.bounds_rejected() if result.success and unc is not None else None
    if reason is None:
        return result
    fit = f"pulled beyond the bounds: {reason}"
    starts = list(result.starts)
    best = result.best_start
    k = next(i for i, s in enumerate(starts) if s is best)
    starts[k] = dataclasses.replace(starts[k], success=False, fit=fit)
    return dataclasses.replace(result, success=False, fit=fit, starts=tuple(starts))


def _known_outside(known: Mapping[str, float], bounds: Any) -> list[str]:
    """A value made known (with_known, --known) outside the bounds given for it: said, since the bounds then drop
    out (a new user's k2 = 5 against the model file's [10, 1000], and the fit's advice named another bound)."""
    if not known or not isinstance(bounds, Mapping):
        return []
    out = []
    for name, value in known.items():
        b = bounds.get(name)
        if b is None or np.ndim(b) != 1 or len(b) != 2:
            continue
        lo, hi = (-np.inf if v is None else float(v) for v in b)
        if not lo <= value <= hi:
            out.append(f"{name} is known as {value:g}, outside the bounds [{lo:g}, {hi:g}] given for it: check the "
                       f"value or the bounds")
    return out


def too_small_residual(ratio: float | None, n_data: int, n_parameters: int) -> str | None:
    """What a residual smaller than the given noise says: ``ratio`` the residual's rms over the given noise's, whose
    square is about χ²(N − l)/N for noise of that level; below its 0.1 % quantile the noise given is too large.

    Examples
    --------
    >>> from symid.fit.identify import too_small_residual
    >>> too_small_residual(0.55, 4000, 4)[:58]
    'the residual is 0.55 times the noise_std given (rms): far '
    >>> too_small_residual(0.99, 4000, 4) is None
    True
    """
    from scipy.stats import chi2

    if ratio is None or not np.isfinite(ratio) or n_data <= n_parameters:
        return None
    dof = n_data - n_parameters
    if ratio**2 >= chi2.ppf(0.001, dof) / n_data:
        return None
    return (f"the residual is {ratio:.2g} times the noise_std given (rms): far less than noise of that level leaves "
            f"(below {np.sqrt(chi2.ppf(0.001, dof) / n_data):.3g} in 99.9 % of records). The noise_std is too large, "
            f"and the fit was judged against a noise floor too lenient for it: a wrong model can pass. Give the "
            f"data's noise level, or leave noise_std out (the level is then estimated from the residual)")
