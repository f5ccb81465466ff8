"""Output-error fit of a continuous-time state-space model directly to measured samples (SciPy's trf, or IPOPT).

The model ``x' = A(θ) x + B(θ) u, y = C(θ) x + D(θ) u`` is simulated exactly on each
record's sample times (zero-order-hold input, :mod:`symid.fit.timeseries.response`)
from its initial state — the model's ``x0`` (zero, known, affine in θ) or, with
``x0="estimate"``, one unknown initial state per record — and θ minimises the relative
output misfit over all records

    cost(θ) = (1/p) Σⱼ Σₑ ‖yₑⱼ − ŷₑⱼ(θ)‖² / Σₑ ‖yₑⱼ‖²,

each output channel j weighed by its own energy so that outputs in different units count
alike. This is the output-error / prediction-error criterion of MATLAB's ``greyest`` with
a noise model K = 0 (Ljung, *System Identification*, 2nd ed., §4.2, §7.2); no black box
or persistent excitation is needed: a single bolus dose identifies a two-compartment
model.

Two solvers (``solver``). The default, ``"trf"``: SciPy's trust-region reflective least
squares on log-parameters, with the residual's exact Jacobian from the sensitivity
recursion in numpy (:mod:`symid.fit.timeseries.sensitivity`), so nothing is built before
the first step. ``"ipopt"``: IPOPT with gradient and Hessian from CasADi's automatic
differentiation through the exact discretisation, a graph whose build takes seconds to a
minute on long records and cannot be interrupted. Measured on
``benchmarks/timeseries_population.py`` (chains, chains with gains, compartment and
state-space models, n = 2, 3; noise-free and 1 %; one informed and one uninformed start
each; 60 s per start; ``--methods oe,oe-trf,auto,auto-trf``): the time-series ``auto``
met the success rule from 30 of 32 starts with trf passes against 28 of 32 with IPOPT's,
in a median 2.1 s per start against 7.0 s; one output-error run from 19 against 18, in
2.2 s against 6.4 s (trf lost 3 chain starts and won 4 on the other classes). At n = 5
(``benchmarks/timeseries_hessian.py --variants auto,trf``, one uninformed start per
problem and noise level): 6 of 8 fits against 4 of 8, each success in 3.7 to 51 s.

Nothing in the set-up depends on units (issue 14): the cost is relative to each channel's
energy; trf works on log(θ / θ₀) for every parameter kept positive; IPOPT works on θ / |θ₀|
per start (and on every estimated initial state over the state's rms along the start's
response), on the cost over its start's decade, with a barrier no stronger than the cost's
pull at the start (:class:`symid.engine.ipopt.ScaledIpopt`); and the matrix exponential is
balanced before its Taylor polynomial (:func:`symid.fit.timeseries.response.balancing`), so
that a time axis or a state in other units does not change its rounding.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any, ClassVar

import casadi as ca
import numpy as np
from scipy.optimize import least_squares

from symid.data.timeseries import TimeSeries
from symid.engine.ipopt import (
    GAUSS_NEWTON,
    HESSIANS,
    IpoptIteration,
    ScaledIpopt,
    iteration_reporter,
    positivity_bounds,
    start_scale,
)
from symid.errors import DataError, ModelError, OptionError, SymidError
from symid.fit.base import Estimator
from symid.fit.bounded import bounds_option, clip_into, log_box, named_bounds, on_bounds
from symid.fit.options import (
    check_bool,
    check_callback,
    check_choice,
    check_float,
    check_int,
    check_scale,
    check_start_bounds,
    check_time_limit,
    moved_onto_bounds,
)
from symid.fit.result import StartOutcome
from symid.fit.timeseries.records import as_records, band_limited
from symid.fit.timeseries.response import balancing, casadi_output, simulate_output, squarings, state_transitions
from symid.fit.timeseries.sensitivity import output_sensitivity, state_space_derivatives
from symid.fit.uncertainty import FisherInformation, broadcast_noise

__all__ = ["ERROR_MODEL_WEIGHTS", "EXACT_BUILD_RATE", "HOLDS", "REWEIGHTS", "REWEIGHT_TOL", "SOLVERS",
           "SQUARING_MARGIN", "WEIGHTED_COST_KIND", "OutputError", "error_model_parts", "error_model_variance",
           "parse_hold"]

SOLVERS = ("ipopt", "trf")
"""The ``solver`` choices of :class:`OutputError`."""

WEIGHTED_COST_KIND = ("weighted relative output misfit to the measured samples Σ (y − ŷ)²/σ² / Σ y²/σ², σ² the given "
                      "variance")
"""The misfit's name when ``variance=`` weighs every output value."""

_LOG_BOX = math.log(1e8)  # "trf": |φₖ| ≤ log 1e8 for a parameter kept positive, no estimate beyond 1e8 × its start

SQUARING_MARGIN = 2
"""Squarings of the matrix exponential added to what a start needs, so that one graph (and solver) serves the
estimates it leads to (:meth:`OutputError._graph_for`)."""

EXACT_BUILD_RATE = 5.5e-6
"""Seconds per (graph node × unknown) CasADi takes to build the exact Hessian of the output-error cost, for
``hessian="auto"``: measured 3.5e-6 to 5.9e-6 on 7 problems of the time-series population, from 24 k nodes × 6
unknowns (0.5 s) to 857 k × 12 (59 s), on the project's 2-core machine. A size rule, not a clock: the same
problem and time limit choose the same Hessian on any machine."""


def _sx_matrix(amap: Any, theta: Any) -> Any:
    X = ca.SX(ca.DM(amap.X0))
    for k in amap.depends_on:
        X = X + theta[k] * ca.DM(amap.Xi[k])
    return X


def _sx_state_space(model: Any, theta: Any) -> tuple[Any, Any, Any, Any]:
    """(A, B, C, D) as CasADi expressions: the affine maps of a state-space model, or the first-order form
    of a second-order model (x = [q; q'], thesis (7-2)) through M⁻¹."""
    maps = model.maps
    if "M" not in maps:
        return tuple(_sx_matrix(maps[k], theta) for k in "ABCD")
    M, V, K, B, C = (_sx_matrix(maps[k], theta) for k in "MVKBC")
    n, m = model.n_dof, model.n_inputs
    MiK, MiV, MiB = ca.solve(M, K), ca.solve(M, V), ca.solve(M, B)
    A = ca.vertcat(ca.horzcat(ca.SX(n, n), ca.SX.eye(n)), ca.horzcat(-MiK, -MiV))
    Bss = ca.vertcat(ca.SX(n, m), MiB)
    rows, drows = [], []
    for i, kind in enumerate(model.outputs):  # row by row: an output's kind is its own
        Ci = C[i, :]
        if kind == "position":
            rows.append(ca.horzcat(Ci, ca.SX(1, n)))
            drows.append(ca.SX(1, m))
        elif kind == "velocity":
            rows.append(ca.horzcat(ca.SX(1, n), Ci))
            drows.append(ca.SX(1, m))
        else:
            rows.append(ca.horzcat(-ca.mtimes(Ci, MiK), -ca.mtimes(Ci, MiV)))
            drows.append(ca.mtimes(Ci, MiB))
    return A, Bss, ca.vertcat(*rows), ca.vertcat(*drows)


def _initial_state_mode(model: Any, initial_state: Any) -> tuple[str, Any]:
    """``("model" | "zero" | "estimate" | "known", known values)`` from the ``initial_state`` option."""
    if initial_state is None:
        kind = getattr(model, "initial_state_kind", "zero")
        return {"zero": "zero", "estimate": "estimate"}.get(kind, "model"), None
    if isinstance(initial_state, str):
        if initial_state != "estimate":
            raise OptionError(f"initial_state must be None (the model's), 'estimate' or numbers (n,) = "
                              f"({model.n_states},) per record; got {initial_state!r}")
        return "estimate", None
    return "known", initial_state


def _known_states(value: Any, n: int, n_records: int) -> list[np.ndarray]:
    """Known initial states: one (n,) array for every record, or a list of one per record."""
    items = value if isinstance(value, (list, tuple)) and n_records > 1 and len(value) == n_records \
        and all(np.ndim(v) == 1 for v in value) else [value] * n_records
    out = []
    for v in items:
        try:
            x = np.asarray(v, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise OptionError(f"initial_state must be numbers; got {v!r}") from None
        if x.size != n or not np.all(np.isfinite(x)):
            raise OptionError(f"initial_state must hold {n} finite numbers (the model's state"
                              f"{' [q; dq/dt]' if n % 2 == 0 else ''}) per record; got {np.shape(v)}")
        out.append(x)
    return out


HOLDS = ("zoh", "foh", "bandlimited")
"""How the input moves between samples (``hold=``): held, linear, or band-limited (:func:`band_limited`)."""


def parse_hold(hold: Any, n_inputs: int) -> str | tuple[str, ...]:
    """``hold=`` as one of :data:`HOLDS` for every input, or a tuple of one per input where they differ.

    A list or tuple gives one per input, in the records' input order; a string may join them with commas
    (``"zoh,foh"``, as the command line passes it). A new user's room model (heater power switched by a controller,
    outdoor temperature measured): with the one hold of all inputs, the intervals of two conductances held the truth
    in 1 and 4 of 12 records with ``success`` (held, the temperature's ramps between samples were steps; linear or
    band-limited, the heater's steps were ramps, and the fit failed).

    Examples
    --------
    >>> from symid.fit.timeseries.oe import parse_hold
    >>> parse_hold("zoh,foh", 2), parse_hold(["foh", "foh"], 2), parse_hold("bandlimited", 3)
    (('zoh', 'foh'), 'foh', 'bandlimited')
    """
    if isinstance(hold, str) and "," in hold:
        hold = [h.strip() for h in hold.split(",")]
    if isinstance(hold, (list, tuple)):
        if len(hold) != n_inputs:
            raise OptionError(f"hold gives {len(hold)} hold(s) for {n_inputs} input(s): one per input, in the "
                              f"records' order (each one of {', '.join(map(repr, HOLDS))}), or one for all")
        kinds = tuple(check_choice(f"hold[{j}]", h, HOLDS) for j, h in enumerate(hold))
        return kinds[0] if len(set(kinds)) == 1 else kinds
    return check_choice("hold", hold, HOLDS)

_HOLD_WORDS = {"foh": "linear between samples", "bandlimited": "band-limited between samples"}

ERROR_MODEL_WEIGHTS = ("prediction", "measured")
"""Where an error model's σ² = (a·y)² + b² takes y from (the ``"weights"`` key of ``variance=``)."""

REWEIGHTS = 6
"""Refits of one start at most when an error model's weights come from the prediction (:meth:`OutputError.run`):
each from the last estimate, with σ² from its prediction, until θ changes by less than :data:`REWEIGHT_TOL`
relatively. On the three-compartment model of ``benchmarks/timeseries_weighting.py`` each refit cuts the change
10 to 30 times: 3–4 refits at 5 % proportional noise, 4–6 at 20 % (8 records each)."""

REWEIGHT_TOL = 1e-5
"""The largest relative change of any parameter between two refits at which the reweighting has settled (far
below the estimate's own uncertainty, a few % there)."""

OFFSET_SHARE = 0.1
"""The share of a failed fit's misfit that estimated initial states or constant offsets must explain before its NEXT
line names them (:meth:`OutputError.initial_offset`): a record cut from a run of a quarter car, 16 % (4.8e-4 →
4.0e-4, the misfit of the fit with the initial state estimated)."""

_PREDICTION_FLOOR = 1e-3
"""With weights from the prediction and no additive part, a predicted value below this fraction of its output's
largest predicted value counts as that fraction (an exact 0, e.g. at t = 0 from rest, would have no noise)."""


def error_model_parts(model: dict[str, Any]) -> tuple[dict[str, float], str]:
    """The checked parts of an error model ``{"proportional": a, "additive": b, "weights": ...}``: ``({"proportional":
    a, "additive": b}, weights)``, ``weights`` one of :data:`ERROR_MODEL_WEIGHTS` (default ``"prediction"``).

    Raises
    ------
    OptionError
        On other keys, values that are not finite numbers ≥ 0, or both parts 0.

    Examples
    --------
    >>> from symid.fit.timeseries.oe import error_model_parts
    >>> error_model_parts({"proportional": 0.1})
    ({'proportional': 0.1, 'additive': 0.0}, 'prediction')
    """
    unknown = sorted(set(model) - {"proportional", "additive", "weights"})
    if unknown:
        raise OptionError(f"variance: an error model has the keys 'proportional' and 'additive' (σ² = (a·y)² + b²) "
                          f"and 'weights' (where y comes from: {' or '.join(map(repr, ERROR_MODEL_WEIGHTS))}); "
                          f"got {unknown[0]!r}")
    weights = model.get("weights", "prediction")
    if not isinstance(weights, str) or weights not in ERROR_MODEL_WEIGHTS:
        raise OptionError(f"variance: an error model's 'weights' is {' or '.join(map(repr, ERROR_MODEL_WEIGHTS))} "
                          f"(σ² from the model's prediction or from the measured values); got {weights!r}")
    parts = {}
    for key in ("proportional", "additive"):
        value = model.get(key, 0.0)
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
                or not math.isfinite(float(value)) or float(value) < 0:
            raise OptionError(f"variance: {key} must be a finite number ≥ 0 (a relative or an absolute standard "
                              f"deviation); got {value!r}")
        parts[key] = float(value)
    if parts["proportional"] == 0 and parts["additive"] == 0:
        raise OptionError("variance: an error model with proportional = additive = 0 has no noise; give one of them")
    return parts, weights


def error_model_variance(model: dict[str, Any], y: np.ndarray) -> np.ndarray:
    """The variance of every measured value of ``y`` under an error model ``{"proportional": a, "additive": b}``:
    σ² = (a·y)² + b², the combined error model of pharmacokinetics (either part may be left out).

    :class:`OutputError` uses it on the measured values for its first fit, and then, unless the model says
    ``"weights": "measured"``, on the model's prediction (:meth:`OutputError.run`); for that first fit a
    proportional model alone takes a value below :data:`_PREDICTION_FLOOR` of its output's largest as that
    fraction (a concentration measured as 0 before the dose).

    Raises
    ------
    OptionError
        On other keys, values that are not finite numbers ≥ 0, both parts 0, or a proportional-only model
        with ``"weights": "measured"`` where a measured value is 0 (its variance would be 0: add an additive
        part).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.timeseries.oe import error_model_variance
    >>> error_model_variance({"proportional": 0.1, "additive": 0.5}, np.array([[10.0], [0.0]])).ravel().tolist()
    [1.25, 0.25]
    """
    parts, weights = error_model_parts(model)
    if weights == "prediction" and parts["additive"] == 0:
        # these σ² only weigh the first fit, before the prediction's: a value measured as 0 (a concentration
        # before the dose) counts as the prediction floor, as a predicted 0 does
        with np.errstate(all="ignore"):
            top = np.nanmax(np.abs(y), axis=0) if np.any(np.isfinite(y)) else np.zeros(y.shape[1:])
        y = np.maximum(np.abs(y), _PREDICTION_FLOOR * np.nan_to_num(top))
    var = (parts["proportional"] * y) ** 2 + parts["additive"] ** 2
    if parts["additive"] == 0 and np.any(var == 0):
        k, j = (int(i) for i in np.argwhere(var == 0)[0])
        raise OptionError(f"variance: the measured value for sample {k}, output {j} is 0, so a proportional error "
                          f"model alone gives it no noise; add an additive part, e.g. {{'proportional': "
                          f"{parts['proportional']:g}, 'additive': …}} in the output's units, or mark the value NaN "
                          f"if it was not measured")
    return var


LEVEL = 3.0
"""An output whose mean over a record exceeds this many of its standard deviations sits at a level (an operating
point, an absolute temperature), which a failed fit's NEXT line names (:meth:`OutputError.initial_offset`)."""


def _level(rows: list, misfit: float) -> dict[str, Any] | None:
    """The record and output most above :data:`LEVEL` (mean over standard deviation of its measured values), as an
    ``initial_offset`` dict of kind ``"level"``, or None."""
    best, where = LEVEL, None
    for e, (r, _, o, *_) in enumerate(rows):
        for j in range(o.shape[1]):
            y = r.y[o[:, j], j]
            if y.size < 3:
                continue
            sd = float(np.std(y))
            ratio = abs(float(np.mean(y))) / sd if sd > 0 else math.inf
            if ratio > best:
                best, where = ratio, (e, j, float(np.mean(y)), sd)
    if where is None:
        return None
    e, j, mean, sd = where
    r, s, o = rows[e][:3]
    k = int(np.flatnonzero(o[:, j])[0])
    return {"kind": "level", "record": e, "output": j, "misfit": misfit, "after": None, "sample": k,
            "measured": float(r.y[k, j]), "model": float(s[k, j]), "mean": mean, "std": sd}


def _projected_out(res: np.ndarray, X: np.ndarray) -> np.ndarray:
    """The residual ``res`` (N, p) less its least-squares fit by the columns of X (N·p, k), same shape."""
    coef, *_ = np.linalg.lstsq(X, res.reshape(-1), rcond=None)
    return res - (X @ coef).reshape(res.shape)


class OutputError(Estimator, FisherInformation):
    """Output-error estimation on sampled records: trust-region least squares (default) or IPOPT, per start.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
        A state-space model's ``x0=`` gives its initial state (zero when omitted;
        ``"estimate"`` adds one unknown initial state per record); a second-order model
        starts at rest (x = [q; q'] = 0) unless ``initial_state`` says otherwise.
    data : IOData, TimeSeries, or a list of them
        One record per experiment; sample times need not be uniform.
    initial_state : None, "estimate" or array_like, optional
        ``None`` (default): the model's. ``"estimate"``: one unknown initial state per
        record. Numbers (n,), or a list of them per record: known initial states.
    scale : array_like, optional
        Typical magnitude of each parameter; the unknowns are θ / scale (IPOPT) or
        log(θ / θ₀) with scale standing in for a start of 0 (trf). Default: each
        start's own magnitudes |θ₀| (where θ₀ is 0: 1), so that the estimate does not
        depend on the units of θ.
    positivity : bool, optional
        Bound parameters declared ``positive=True`` below by 0. Default True.
    bounds : dict or array_like, optional
        Lower and upper bounds per parameter: a dict by name of (low, high) pairs (None or
        ±inf for an open side), or an (l, 2) array. Both solvers stay within them (trf on
        the log-parameters, :mod:`symid.fit.bounded`); a start outside them is refused,
        a drawn one moved onto them (the message says so). Default: none.
    hessian : {"auto", "exact", "gauss-newton", "limited-memory"}, optional
        For ``solver="ipopt"``, IPOPT's Hessian: CasADi's exact one, Gauss–Newton 2 JᵀJ from the residual's
        Jacobian J (first derivatives only), or L-BFGS. ``"auto"`` (default): exact,
        unless building it would take more than a quarter of ``time_limit``
        (:data:`EXACT_BUILD_RATE` × graph nodes × unknowns; 9 s for 2300 samples of a
        3-mass chain with gains, 59 s for 3900 samples of 5 masses, and the build cannot
        be interrupted), then Gauss–Newton (3 s and 16 s to build there). The exact
        Hessian converges from more starts (time-series population, n = 2, 3: one
        output-error run 18 of 32 against 12 of 32), Gauss–Newton fits in the budget.
    variance : float, array_like or dict, optional
        The noise variance σ² of every measured output value, in the output's units squared: a
        number, one per sample (N,), one per output (1, p), (N, p), or a list of such, one per
        record; or an error model ``{"proportional": a, "additive": b}``, σ² = (a·y)² + b² from
        the measured values (:func:`error_model_variance`; on the command line
        ``--option 'variance={"proportional": 0.05}'``). The fit then minimises Σ (y − ŷ)²/σ² (relative to
        Σ y²/σ²), the maximum-likelihood criterion for independent Gaussian noise: noise that
        grows with the signal (a concentration measured to 5 %) weighs the small values as the
        large ones. Only the shape matters to the estimate. An error model takes y from the
        model's prediction (refits from the estimate until its weights settle: :meth:`run`), or
        from the measured values with ``"weights": "measured"`` (biased where the noise is large:
        a sample measured low gets too much weight). The level judges the fit: unless
        ``noise_floor`` is given, the fit succeeds when its weighted misfit is within what noise
        of this variance leaves (Σ σ²/σ² over Σ y²/σ², χ² 99.9 % bound), as for a frequency
        response's ``variance``. For the intervals the level is estimated from the residuals (in
        units of the given σ) unless ``noise_std`` is given to :func:`symid.identify`. Default:
        each output weighted by its energy.
    solver : {"ipopt", "trf"}, optional
        ``"trf"`` (default): SciPy's trust-region reflective least squares
        (``scipy.optimize.least_squares``) on log-parameters (θₖ = sₖ·exp(φₖ) for a
        parameter kept positive, sₖ its start or ``scale``; the others and estimated
        initial states in units of their scale), with the exact residual Jacobian of the
        sensitivity recursion in numpy (:mod:`symid.fit.timeseries.sensitivity`): no
        graph to build, so a start begins at once whatever the record's length;
        ``hessian`` does not apply. ``"ipopt"``: IPOPT on CasADi's graph of the cost,
        with the Hessian ``hessian`` says (module notes: trf met the success rule from
        more starts of the time-series population, three times faster).
    hold : {"zoh", "foh", "bandlimited"}, optional
        How the input moves between samples: held (``"zoh"``, default: as
        :class:`~symid.data.IOData` defines a record, a DAC or digital controller drives a
        plant), linear (``"foh"``) or band-limited (``"bandlimited"``: an input that was only
        sampled, a shaker's measured force, a road profile; its band-limited interpolation at
        4 points per sample interval, linear between them with an emphasis that cancels
        linear interpolation's (ωh)²/12, :func:`~symid.fit.timeseries.records.band_limited`,
        the outputs measured at the samples), exactly in the simulation and its sensitivities
        (solver ``"trf"``). Sines up to 12 rad/s through a 10 rad/s oscillator at 25 samples a
        second, 2 % noise: taken as held, a misfit 37 times the noise's (success False, c 3.4 %
        off); linear, the noise's, with k/m and c/m within 0.3 % and a common gain 1.3 % low
        (linear interpolation attenuates a band-limited input by about (ω dt)²/12), 22 standard
        errors; band-limited, within 0.035 %, 0.6 standard errors at most, and a residual
        white and independent of the input (``tests/test_timeseries_fit.py``). Equally spaced
        samples only; four times the work of ``"foh"``. One per input (a list, or the names
        joined by commas, ``"zoh,foh"``) where the inputs differ: a heater switched by a
        controller (held) beside a measured outdoor temperature (linear or band-limited)
        (:func:`parse_hold`).
    max_iter : int, optional
        IPOPT iteration limit, or residual evaluations of ``"trf"`` (default 500).
    tol : float, optional
        Tolerance, default 1e-12: for trf SciPy's ``ftol`` and ``xtol``; for IPOPT on the
        relative objective (the two-compartment study fits noise-free samples to 2e-11
        in θ; 1e-14 stops noisy fits with "Search_Direction_Becomes_Too_Small" at the
        optimum), divided by the start's decade of the objective as
        :class:`~symid.engine.ipopt.ScaledIpopt` does.
    time_limit : float, optional
        Wall-time budget of one start in seconds, building its solver included (the
        first start builds it), checked after every iteration (status
        ``"Maximum_WallTime_Exceeded"``; ``"time_limit"`` for ``"trf"``, checked at every
        evaluation). Default: none.
    callback : callable, optional
        Called after every IPOPT iteration (``"trf"``: every evaluation that lowers the
        misfit) with a :class:`~symid.engine.ipopt.IpoptIteration` (iteration, relative
        misfit, elapsed seconds, θ); a true return value stops the start (status
        ``"User_Requested_Stop"``; ``"stopped"`` for ``"trf"``).
    verbose : bool, optional
        Print one line per iteration (``"trf"``: per evaluation that lowers the misfit;
        iteration, misfit, elapsed). Default False.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.timeseries.oe import OutputError
    >>> k, d = si.parameters("k d", positive=True)
    >>> model = si.StateSpaceModel(A=[[-k]], B=[[0]], C=[[1]], x0=[d])   # a decay from an unknown level
    >>> io = si.simulate_io(model, {"k": 0.5, "d": 3.0}, np.zeros(20), dt=0.25)
    >>> out = OutputError(model, io).run(np.array([1.0, 1.0]))
    >>> np.round(out.theta, 8).tolist(), out.success
    ([0.5, 3.0], True)

    With :func:`symid.identify` the result also carries the covariance of θ̂ from the
    Fisher information (:mod:`symid.fit.uncertainty`), ``res.uncertainty``.
    """

    method: ClassVar[str] = "oe"
    cost_kind: ClassVar[str] = "relative output misfit to the measured samples (1/p) Σⱼ ‖yⱼ − ŷⱼ‖² / ‖yⱼ‖²"
    _noise_floor_given: float | None = None
    _variance_floor: float | None = None

    def __init__(self, model: Any, data: Any, *, initial_state: Any = None, scale: Any = None,
                 positivity: bool = True, hessian: str = "auto", max_iter: int = 500, tol: float = 1e-12,
                 time_limit: float | None = None, callback: Any = None, verbose: bool = False,
                 solver: str = "trf", bounds: Any = None, variance: Any = None, hold: Any = "zoh"):
        self._x0_mode, self._x0_known = _initial_state_mode(model, initial_state)
        self.records = as_records(model, data, estimate_x0=self._x0_mode == "estimate")
        # outputs not measured (NaN in a TimeSeries) are left out of the misfit: weight 0, the value 0 in their place
        self._observed = [~np.isnan(r.y) for r in self.records]
        self.n_missing = sum(int(np.count_nonzero(~o)) for o in self._observed)
        self.hold = parse_hold(hold, self.records[0].n_inputs)
        kinds = self.hold if isinstance(self.hold, tuple) else (self.hold,)
        self._upsampled = "bandlimited" in kinds  # the input at points between the samples, where no output is
        self._held = (np.array([k == "zoh" for k in kinds]) if isinstance(self.hold, tuple) else None)
        self._sample_counts = [r.n_samples for r in self.records]  # the user's, before any points between them
        if self._upsampled:  # measured
            self.records = tuple(band_limited(r, f"record {e}" if len(self.records) > 1 else "the record",
                                              holds=self.hold if isinstance(self.hold, tuple) else None)
                                 for e, r in enumerate(self.records))
            self._observed = [~np.isnan(r.y) for r in self.records]
        if any(not np.all(o) for o in self._observed):
            self.records = tuple(TimeSeries(r.t, r.u, np.where(o, r.y, 0.0), r.time_unit)
                                 for r, o in zip(self.records, self._observed, strict=True))
        if self._x0_mode == "known":
            self._x0_known = _known_states(self._x0_known, model.n_states, len(self.records))
        at_rest = self._x0_mode == "zero" or (self._x0_mode == "known" and not any(np.any(x) for x in self._x0_known))
        if at_rest and not any(np.any(r.u) for r in self.records):
            # a new user's zero input ran 11 passes to misfit 1, told to give noise_floor=
            raise DataError("every input is zero throughout the record" + ("s" if len(self.records) > 1 else "") +
                            " and the model starts at rest (initial state 0): its output is 0 for every θ, so the "
                            "samples say nothing of the parameters; give the input that drove the system, or, for a "
                            "free response from a state that is not 0, initial_state='estimate' (or the model's "
                            "own x0)")
        self.model, self.data = model, data
        l = model.n_parameters
        self.scale = None if scale is None else check_scale("scale", scale, l)
        self._positivity = check_bool("positivity", positivity)
        self.lower, self.upper, self._bounded = bounds_option(model, bounds, self._positivity)
        self._hessian = check_choice("hessian", hessian, ("auto", *HESSIANS, GAUSS_NEWTON))
        self._solver_kind = check_choice("solver", solver, SOLVERS)
        self._hold = "zoh" if self.hold == "zoh" else "foh"  # the simulation's: linear between the (fine) points
        if self._hold == "foh" and self._solver_kind != "trf":
            words = (_HOLD_WORDS[self.hold] if isinstance(self.hold, str) else
                     "not held throughout: " + ", ".join(f"input {j} {k}" for j, k in enumerate(self.hold)))
            raise OptionError(f"hold={self.hold!r} (the input {words}) is simulated by "
                              "solver='trf' only; IPOPT's graph holds the input: leave solver out")
        if self._solver_kind == "trf" and self._hessian != "auto":
            raise OptionError(f"hessian={self._hessian!r} is IPOPT's; solver='trf' builds no Hessian (its steps use "
                              f"the residual's Jacobian): leave hessian out, or use solver='ipopt'")
        self._hessian_note: dict[int, str] = {}  # per number of squarings: why "auto" chose Gauss–Newton
        self._max_iter = check_int("max_iter", max_iter, low=1, high=10**7)
        self._tol = check_float("tol", tol, low=0, strict_low=True)
        self._time_limit = check_time_limit("time_limit", time_limit)
        self._hessian_budget = self._time_limit  # the start's whole budget, for hessian="auto" (not the time left)
        verbose = check_bool("verbose", verbose)
        check_callback("callback", callback, "IpoptIteration")
        self._report = iteration_reporter(callback, verbose, label=self._solver_kind)
        self._iterations_before = 0  # of earlier rounds of the same start (run), for the callback's count
        self._deadline: float | None = None  # of the start under way (time_limit), checked every iteration
        self._timed_out = False
        self.options = {"scale": "start" if self.scale is None else self.scale.tolist(),
                        "bounds": named_bounds(model.parameter_names, self.lower, self.upper)
                        if self._bounded else None,
                        "positivity": self._positivity, "solver": self._solver_kind, "hessian": self._hessian,
                        "max_iter": self._max_iter, "tol": self._tol, "time_limit": self._time_limit,
                        "callback": None if callback is None else "given", "verbose": verbose,
                        "records": len(self.records),
                        "hold": list(self.hold) if isinstance(self.hold, tuple) else self.hold,
                        "initial_state": self._x0_mode if self._x0_mode != "model" else model.initial_state_kind}
        self._energy = sum(np.sum(r.y**2, axis=0) for r in self.records)
        self._rms = np.sqrt(self._energy / sum(np.sum(o, axis=0) for o in self._observed))
        # an error model {"proportional": a, "additive": b}: σ² from the prediction unless "weights": "measured"
        self._error_model, self._weights_from = error_model_parts(variance) if isinstance(variance, dict) \
            else (None, None)
        self._anchor_key: bytes | None = None  # the θ whose prediction set the weights (weights from the prediction)
        self._anchor_sims: list[np.ndarray] | None = None  # that prediction, for the misfit at the same θ
        self._base_variance = None if variance is None else self._sample_variance(variance)
        self._set_variance(self._base_variance)
        if variance is not None:
            self.cost_kind = WEIGHTED_COST_KIND  # type: ignore[misc]
        self.options["variance"] = None if variance is None else (
            "given" if self._error_model is None else {**self._error_model, "weights": self._weights_from})
        self._estimate_x0 = self._x0_mode == "estimate"
        values = self.n_data()
        if values < self.n_unknowns():
            x0_part = (f" and {model.n_states} initial-state value(s) per record × {len(self.records)}"
                       if self._estimate_x0 else "")
            raise DataError(f"the record(s) hold {values} output value(s) for {self.n_unknowns()} unknowns "
                            f"({l} parameter(s){x0_part}): too few to fix them; use longer or more records"
                            + (", or give the initial state (x0= numbers or an expression in θ)"
                               if self._estimate_x0 else ""))
        self._x0_scale = np.array([max(float(np.abs(r.y).max()), 1e-300) for r in self.records])
        self._h_max = max(float(np.diff(r.t).max()) for r in self.records)
        self._lower = positivity_bounds(model.positive, self._positivity, np.ones(l))[0]
        self._solvers: dict[int, ScaledIpopt] = {}
        self._jacobian_fns: dict[int, Any] = {}
        self._graphs: dict[int, tuple[Any, Any, Any]] = {}  # (v, q, r) per number of squarings, built once

    def _set_variance(self, variance: list[np.ndarray] | None) -> None:
        """The weights of the misfit from σ² (one (N, p) array per record), or by each output's energy (None)."""
        self._variance = variance
        if variance is None:  # per output channel: cost = Σ_j ‖r_j‖² / (p ‖y_j‖²)
            weights = 1.0 / (self.model.n_outputs * self._energy)
            self._w = [np.broadcast_to(weights, r.y.shape) * o for r, o in zip(self.records, self._observed,
                                                                                strict=True)]
            self._variance_floor = None
        else:  # per value: cost = Σ r² / σ² over Σ y² / σ² (still 1 for ŷ = 0)
            scaled = sum(float(np.sum(r.y**2 / v)) for r, v in zip(self.records, variance, strict=True))
            self._w = [o / (v * scaled) for v, o in zip(variance, self._observed, strict=True)]
            # the weighted misfit that noise of the given variance leaves at the truth, Σ w σ² (= values / scaled)
            self._variance_floor = sum(float(np.sum(w * v)) for w, v in zip(self._w, variance, strict=True))
        self._sw = [np.sqrt(w) for w in self._w]
        for cache in ("_graphs", "_solvers", "_jacobian_fns"):  # CasADi's graphs hold the weights: built again
            if getattr(self, cache, None):
                getattr(self, cache).clear()

    def _anchor(self, theta: Any) -> None:
        """With an error model's weights from the prediction: σ² = (a·ŷ)² + b² from the prediction ŷ at θ (the
        measured values' σ² where the model cannot be simulated there). Nothing otherwise."""
        if self._weights_from != "prediction":
            return
        theta = np.asarray(theta, dtype=float).reshape(-1)[: self.model.n_parameters]
        key = theta.tobytes()
        if key == self._anchor_key:
            return
        self._anchor_key = key
        try:
            with np.errstate(all="ignore"):
                sims = self.simulate(theta) if np.all(np.isfinite(theta)) else None
        except (ModelError, np.linalg.LinAlgError, ValueError):
            sims = None
        self._anchor_sims = sims
        if sims is None or not all(np.all(np.isfinite(s[o])) for s, o in zip(sims, self._observed, strict=True)):
            self._set_variance(self._base_variance)
            return
        assert self._error_model is not None
        a, b = self._error_model["proportional"], self._error_model["additive"]
        variance = []
        for s, o in zip(sims, self._observed, strict=True):
            top = np.max(np.where(o, np.abs(s), 0.0), axis=0) if b == 0 else 0.0  # per output
            v = (a * np.maximum(np.abs(s), _PREDICTION_FLOOR * top)) ** 2 + b**2
            if not np.all(v[o] > 0):  # a prediction of 0 throughout an output, with no additive part
                self._set_variance(self._base_variance)
                return
            variance.append(np.where(o, v, 1.0))
        self._set_variance(variance)

    @property
    def observed(self) -> list[np.ndarray]:
        """Per record, (N, p) booleans: True where the output was measured (False where it was NaN; ``records``
        hold 0 there, with weight 0)."""
        return list(self._observed)

    @property
    def noise_floor(self) -> float | None:  # type: ignore[override]
        """The given ``noise_floor``; else, with a ``variance``, the weighted misfit that noise of that variance
        leaves at the truth, Σ w σ², so that the fit is judged against the noise the user declared (as the
        frequency response's ``variance=`` is)."""
        return self._noise_floor_given if self._noise_floor_given is not None else self._variance_floor

    @noise_floor.setter
    def noise_floor(self, value: float | None) -> None:
        self._noise_floor_given = value

    # -- the data kind's part ------------------------------------------------------------------
    def _matrices(self, theta: np.ndarray) -> tuple[np.ndarray, ...]:
        return tuple(self.model.state_space(theta))

    def _sample_variance(self, variance: Any) -> list[np.ndarray]:
        """``variance`` as one (N, p) array per record: a number, an array (N,) per sample, (1, p) per output or
        (N, p), or a list of such, one per record, or an error model (:func:`error_model_variance`); every
        value finite and > 0."""
        dict_made = isinstance(variance, dict)
        if isinstance(variance, dict):
            arrays = []
            for e, (r, o) in enumerate(zip(self.records, self._observed, strict=True)):
                try:
                    arrays.append(error_model_variance(variance, np.where(o, r.y, np.nan)))
                except OptionError as exc:  # which record, when there are several
                    if len(self.records) == 1:
                        raise
                    raise OptionError(f"record {e} (of {len(self.records)}, in the order given): {exc}") from None
            variance = arrays
            if len(variance) == 1:
                variance = variance[0]
        items = variance if isinstance(variance, (list, tuple)) and len(self.records) > 1 else None
        if items is not None and len(items) != len(self.records):
            raise OptionError(f"variance is a list of {len(items)}; there are {len(self.records)} records")
        if items is None and len(self.records) > 1 and isinstance(variance, np.ndarray) and variance.ndim \
                and variance.shape[0] > 1:
            raise OptionError(f"variance has {variance.shape[0]} values per output (one per sample of one record); "
                              f"there are {len(self.records)} records: give a list of arrays, one per record (a "
                              f"number, or one per output as (1, p), is shared by every record)")
        out = []
        for e, r in enumerate(self.records):
            where = f"the output y of record {e}" if len(self.records) > 1 else "the output y"
            given = variance if items is None else items[e]
            fine = dict_made  # an error model's arrays are the points' already
            arr = broadcast_noise(given, (r.n_samples if fine else self._sample_counts[e], r.n_outputs), where,
                                  name="variance", check=False, error=OptionError)
            arr = arr if fine else self._on_points(arr, e)
            bad = ~(np.isfinite(arr) & (arr > 0)) & self._observed[e]  # a missing value needs no variance
            arr = np.where(self._observed[e], arr, 1.0)
            if bad.any():
                k, j = (int(i) for i in np.argwhere(bad)[0])
                rec = "" if items is None else f" of record {e}"
                raise OptionError(f"variance: the value for sample {k}, output {j}{rec} is {float(arr[k, j])!r}; every "
                                  "variance must be finite and > 0")
            out.append(np.array(arr, dtype=float))
        return out

    def _on_points(self, value: Any, e: int) -> Any:
        """A per-sample array given for record ``e`` (its first axis the record's samples) placed on the points of
        ``hold="bandlimited"`` (1 between the samples, where nothing is measured); anything else as it is."""
        if not self._upsampled or isinstance(value, dict):
            return value
        arr = np.asarray(value, dtype=float) if not isinstance(value, (list, tuple)) or np.ndim(value) else value
        n = self._sample_counts[e]
        if not isinstance(arr, np.ndarray) or arr.ndim == 0 or arr.shape[0] != n or n < 2:
            return value
        step = (self.records[e].n_samples - 1) // (n - 1)
        out = np.ones((self.records[e].n_samples, *arr.shape[1:]))
        out[::step] = arr
        return out

    def initial_states(self, theta: Any) -> list[np.ndarray]:
        """x(t₀) of every record at θ: the model's, or (``x0="estimate"``) the least-squares one.

        The output is linear in the initial state, so for a given θ the best x0 of a record
        solves one linear least-squares problem (weighted as the cost).
        """
        theta = self.model.theta_vector(theta)
        if self._x0_mode == "known":
            return [x.copy() for x in self._x0_known]
        if self._x0_mode == "zero":
            return [np.zeros(self.model.n_states) for _ in self.records]
        if not self._estimate_x0:
            x0 = self.model.initial_state(theta)
            return [x0.copy() for _ in self.records]
        A, B, C, D = self._matrices(theta)
        out = []
        for r, sw in zip(self.records, self._sw, strict=True):
            forced = simulate_output(A, B, C, D, r.t, r.u, np.zeros(A.shape[0]), hold=self._hold,
                                     held=self._held)
            Phi = state_transitions(A, r.t)  # (N, n, n)
            O = np.einsum("pn,knr->kpr", C, Phi) * sw[:, :, None]
            rhs = (r.y - forced) * sw
            x0, *_ = np.linalg.lstsq(O.reshape(-1, A.shape[0]), rhs.reshape(-1), rcond=None)
            out.append(x0)
        return out

    def simulate(self, theta: Any) -> list[np.ndarray]:
        """ŷ of every record at θ (exact for the input held, or linear with ``hold="foh"``; initial states by
        :meth:`initial_states`)."""
        theta = self.model.theta_vector(theta)
        A, B, C, D = self._matrices(theta)
        return [simulate_output(A, B, C, D, r.t, r.u, x0, hold=self._hold, held=self._held)
                for r, x0 in zip(self.records, self.initial_states(theta), strict=True)]

    def initial_offset(self, theta: Any) -> dict[str, Any] | None:
        """What the misfit at θ mostly is, when it is something the data's set-up explains.

        ``"kind": "initial_state"``: a start away from the model's, when the least-squares
        initial state of each record explains a share of the misfit (:meth:`_explains`:
        ``OFFSET_SHARE`` of it, and more than noise would; not asked with the initial state
        estimated). ``"offset"``: a constant on each output (with the initial state) explains a
        share likewise, beyond what the initial state alone does (a record around an
        operating point). Failing both, ``"drift"``: a constant and a ramp on each output
        explain a share likewise, the ramp beyond what noise would (a sensor that drifts;
        ``slope`` per the record's time unit). Failing that, ``"level"``: an output whose mean exceeds
        :data:`LEVEL` of its standard deviations (absolute values around an operating
        point, which a fit can absorb in its gains). Else, without a feedthrough, a first
        measured output beyond a fifth of its range from the model's (an estimate that
        chased an offset, a fast mode whose gain matches the level, need not show either).
        ``after`` is None for these two. ``None`` otherwise: a wrong
        input scale, swapped columns or a local minimum explain no such share. The dict
        names the record and output with the largest share, ``misfit`` and ``after`` (the
        misfit with the initial states or the offsets taken out), the first measured value
        and the model's there (``measured``, ``model``) and that output's mean residual
        (``mean``).
        """
        theta = self.model.theta_vector(theta)
        n, p = self.model.n_states, self.model.n_outputs
        try:
            with np.errstate(all="ignore"):
                A, _, C, D = self._matrices(theta)
                sims = self.simulate(theta)
                rows = []
                for r, s, sw, o in zip(self.records, sims, self._sw, self._observed, strict=True):
                    res = (r.y - s) * sw  # the misfit's weighted residual, 0 where a value is missing
                    if not np.all(np.isfinite(res)):
                        return None
                    # regressors of the weighted residual: a change of the initial state (its free response), and
                    # a constant on each output
                    O = (np.einsum("pn,knr->kpr", C, state_transitions(A, r.t)) * sw[:, :, None]).reshape(-1, n)
                    const = (np.eye(p)[None, :, :] * sw[:, :, None]).reshape(-1, p)
                    span = max(float(r.t[-1] - r.t[0]), 1e-300)
                    ramp = ((r.t - r.t[0])[:, None, None] / span * np.eye(p)[None, :, :]
                            * sw[:, :, None]).reshape(-1, p)
                    free = None if self._estimate_x0 else _projected_out(res, O)
                    joint = _projected_out(res, np.hstack([O, const]))
                    trend = _projected_out(res, np.hstack([O, const, ramp]))
                    rows.append((r, s, o, res, free, joint, trend))
        except (ModelError, np.linalg.LinAlgError, ValueError):
            return None
        misfit = sum(float(np.sum(row[3] ** 2)) for row in rows)
        if not (math.isfinite(misfit) and misfit > 0):
            return None
        n_values = sum(int(np.sum(row[2])) for row in rows)
        E = len(rows)
        with_x0 = None if self._estimate_x0 else sum(float(np.sum(row[4] ** 2)) for row in rows)
        with_both = sum(float(np.sum(row[5] ** 2)) for row in rows)
        x0_explains = with_x0 is not None and self._explains(misfit, with_x0, n_values, n * E)
        # the offsets on top of what an initial state explains (with it estimated already, on top of the fit)
        if x0_explains:
            ref, extra = with_x0, p * E
        else:
            ref, extra = misfit, p * E + (0 if self._estimate_x0 else n * E)
        offset_explains = self._explains(ref, with_both, n_values, extra)
        # a drift (a sensor's, a slow disturbance's) on top of the offsets: a ramp on each output (a new user's
        # temperature sensor, 0.4 K and 0.15 K/h: "try more starts", k4 in the slow mode 5 times off)
        with_trend = sum(float(np.sum(row[6] ** 2)) for row in rows)
        drift_explains = (self._explains(ref, with_trend, n_values, extra + p * E)
                          and self._explains(with_both, with_trend, n_values, p * E, share=0.0))
        # a ramp that explains at least half of what the offsets leave is named as a drift, not as an offset (a new
        # user's encoder with an offset and a drift, its initial state estimated: told of "a constant offset" with
        # a mean residual of -1.8e-14)
        drift_first = drift_explains and with_trend < 0.5 * with_both
        if x0_explains:
            # the model starts at rest and the record does not: estimating the initial state is the first remedy,
            # even where offsets on top of it explain more (a new user's room at 18 °C fitted from rest: told to
            # subtract an operating point from a model in absolute temperatures; the level is said beside it)
            kind, after, shares = "initial_state", with_x0, [np.sum(row[3] ** 2 - row[4] ** 2, axis=0)
                                                               for row in rows]
        elif offset_explains and not drift_first:
            kind, after, shares = "offset", with_both, [np.sum(row[3] ** 2 - row[5] ** 2, axis=0) for row in rows]
        elif drift_explains:  # after the two above: a start away from rest also leaves a slope in the residual
            kind, after, shares = "drift", with_trend, [np.sum(row[3] ** 2 - row[6] ** 2, axis=0) for row in rows]
        elif (level := _level(rows, misfit)) is not None:
            # an estimate whose gains absorbed the level (a linear model through the origin fitted to absolute
            # levels around an operating point: a new user's tanks, misfit 3.7e-4 with the initial state estimated)
            # leaves no constant in its residual; the data's own level still tells
            return level
        elif not self._estimate_x0 and not np.any(D):
            # at an estimate that chased the offset (a fast mode whose gain matches the level) neither explains the
            # misfit; the first sample still tells, where it depends on the initial state alone (no feedthrough:
            # with one, an input in the wrong scale moves it too)
            return self._first_sample_gap(rows, misfit)
        else:
            return None
        e = int(np.argmax([float(np.max(v)) for v in shares]))
        j = int(np.argmax(shares[e]))
        r, s, o = rows[e][:3]
        first = np.flatnonzero(o[:, j])
        k = int(first[0]) if first.size else 0
        raw = np.where(o[:, j], r.y[:, j] - s[:, j], 0.0)
        out = {"kind": kind, "record": e, "output": j, "misfit": misfit, "after": after, "sample": k,
               "measured": float(r.y[k, j]), "model": float(s[k, j]),
               "mean": float(raw.sum() / max(int(o[:, j].sum()), 1))}
        if kind == "drift":  # the residual's slope on that output, per the record's time unit
            keep = o[:, j]
            out["slope"] = float(np.polyfit(r.t[keep] - r.t[0], raw[keep], 1)[0]) if np.count_nonzero(keep) > 1 \
                else 0.0
            out["time_unit"] = getattr(r, "time_unit", "s")
        if kind == "initial_state" and (level := _level(rows, misfit)) is not None:
            # a record at a level also starts away from a model at rest; estimating the initial state alone does
            # not fit it (a new user's absolute temperatures: 0.0286 → 0.0112, no fit), so both are said
            out["level"] = {key: level[key] for key in ("record", "output", "mean", "std")}
        return out

    def _explains(self, misfit: float, after: float, n_values: int, extra: int, share: float = OFFSET_SHARE) -> bool:
        """Whether ``extra`` more unknowns (initial states, offsets) that lower the misfit to ``after`` explain a
        share of it: at least ``OFFSET_SHARE`` of it, and more than noise would (the likelihood-ratio statistic
        (misfit − after) / (after / dof) beyond the χ² 99.9 % quantile of ``extra`` degrees of freedom; on a failed
        fit the residual is not noise, so the share is what decides)."""
        from scipy.stats import chi2

        if not (math.isfinite(after) and after < (1 - share) * misfit):
            return False
        dof = max(n_values - self.model.n_parameters - extra, 1)
        return after <= 0 or (misfit - after) / (after / dof) > float(chi2.ppf(0.999, extra))

    @staticmethod
    def _first_sample_gap(rows: list, misfit: float) -> dict[str, Any] | None:
        """:meth:`initial_offset`'s last test: the first measured output, at the record's first time, beyond a fifth
        of that output's range over the record (and 1e-9 of its largest value) from the model's."""
        for e, (r, s, o, *_) in enumerate(rows):
            first = np.flatnonzero(np.all(o, axis=1))
            if not first.size or not np.all(np.isfinite(s[first[0]])) or r.t[first[0]] != r.t[0]:
                # measured later than the record starts, the model's output there is its response to the input
                # so far, not its initial state (a new user's infusion records, an empty cell at t = 0: a noisy
                # first sample 0.5 h in was called "the record does not start where the model does")
                continue
            k = int(first[0])
            y = np.where(o, r.y, np.nan)
            spread = np.nanmax(y, axis=0) - np.nanmin(y, axis=0)
            gap = np.abs(r.y[k] - s[k])
            far = (gap > 0.2 * spread) & (gap > 1e-9 * np.nanmax(np.abs(y), axis=0))
            if np.any(far):
                j = int(np.argmax(np.where(far, gap / np.where(spread > 0, spread, 1.0), -np.inf)))
                return {"kind": "initial_state", "record": e, "output": j, "misfit": misfit, "after": None,
                        "sample": k, "measured": float(r.y[k, j]), "model": float(s[k, j]),
                        "mean": float(np.nanmean(np.where(o[:, j], r.y[:, j] - s[:, j], np.nan)))}
        return None

    def uncertainty_note(self) -> str:
        """With ``hold="foh"``: the intervals do not include the bias of taking a band-limited input as linear
        between samples (a gain low by about (ω dt)²/12 at the input's frequencies)."""
        if "foh" not in (self.hold if isinstance(self.hold, tuple) else (self.hold,)):
            return ""
        linear = [] if not isinstance(self.hold, tuple) else [str(j) for j, k in enumerate(self.hold) if k == "foh"]
        which = ("the input is" if not linear else f"input {linear[0]} is" if len(linear) == 1
                 else f"inputs {', '.join(linear)} are")
        return (f"{which} taken as linear between samples: a band-limited input's interpolation lowers the gain "
                "by about (ω dt)²/12 at frequency ω, a bias the intervals do not include (a gain 1.3 % low with "
                "sines up to ω dt = 0.48: tests/test_timeseries_fit.py); hold='bandlimited' removes it for a "
                "sampled band-limited input")

    def noise_variance(self, theta: Any) -> list[np.ndarray] | None:
        """σ² of every measured value at θ, one (N, p) array per record, from the ``variance`` option (an error
        model's from the prediction at θ unless it says ``"weights": "measured"``); ``None`` without one."""
        self._anchor(self.model.theta_vector(theta))
        return None if self._variance is None else [np.array(v) for v in self._variance]

    def misfit(self, theta: np.ndarray) -> float:
        """The relative output misfit to the measured samples; ``inf`` where the model overflows.

        With an error model whose weights come from the prediction, σ² is that of θ's own prediction (the
        weights the fit from θ would end with: :meth:`run`)."""
        self._anchor(theta)
        sims = self._anchor_sims if self._anchor_sims is not None and self._anchor_key == np.asarray(
            theta, dtype=float).reshape(-1)[: self.model.n_parameters].tobytes() else None
        if sims is None:  # (the prediction that set the weights is this one: not simulated again)
            try:
                with np.errstate(over="ignore", invalid="ignore"):  # an exponential that overflows: inf, said below
                    sims = self.simulate(theta)
            except (np.linalg.LinAlgError, ValueError):
                return float("inf")
        with np.errstate(over="ignore", invalid="ignore"):  # a diverged θ: inf, said by the cost, not by numpy
            total = sum(float(np.sum(w * (r.y - s) ** 2)) for r, s, w in zip(self.records, sims, self._w, strict=True))
        return total if np.isfinite(total) else float("inf")

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        """Residuals y − ŷ in time order (records one after the other), each channel divided by its rms (by σ of
        each value with ``variance``); a sample time where an output is missing is left out."""
        self._anchor(theta)
        sims = self.simulate(theta)
        if self._variance is not None:
            out = [(r.y - s) / np.sqrt(v) for r, s, v in zip(self.records, sims, self._variance, strict=True)]
        else:
            out = [(r.y - s) / self._rms for r, s in zip(self.records, sims, strict=True)]
        # the sample times where every output was measured (a missing value has no residual)
        return np.vstack([x[np.all(o, axis=1)] for x, o in zip(out, self._observed, strict=True)])

    def residual_independent(self, theta: Any) -> bool | None:
        """Whether the residual (as the misfit weighs it, at the sample times where every output was measured) is
        independent of every non-constant input at 99.9 % (:func:`symid.fit.validation.independence_pvalues`), for
        the success rule above its 10 % ceiling (:mod:`symid.fit.success`, rule 3); None where it cannot tell."""
        from symid.fit.validation import independence_pvalues

        try:
            sims = self.simulate(self.model.theta_vector(theta) if isinstance(theta, dict) else theta)
        except (SymidError, ValueError, ArithmeticError, np.linalg.LinAlgError):
            return None
        res, us = [], []
        for e, (r, s, o) in enumerate(zip(self.records, sims, self._observed, strict=True)):
            scale = np.sqrt(self._variance[e]) if self._variance is not None else self._rms
            keep = np.all(o, axis=1)
            res.append(((r.y - s) / scale)[keep])
            us.append(r.u[keep])
        if not all(np.all(np.isfinite(x)) for x in res) or min(x.shape[0] for x in res) < 8:
            return None
        with np.errstate(all="ignore"):
            pv = independence_pvalues(res, us)
        pv = pv[np.isfinite(pv)]
        return None if pv.size == 0 else bool(np.all(pv >= 1e-3))

    def n_data(self) -> int:
        """Number of measured output values (missing ones not counted)."""
        return int(sum(np.count_nonzero(o) for o in self._observed))

    def n_unknowns(self) -> int:
        """θ plus the estimated initial states."""
        return self.model.n_parameters + (self.model.n_states * len(self.records) if self._estimate_x0 else 0)

    # -- CasADi ----------------------------------------------------------------------------------
    def _symbolic(self, s_max: int) -> tuple[Any, Any, Any]:
        """Unknowns v = (θ, estimated initial states) in their own units, the balancing q = (d, e) of the
        exponential (:func:`~symid.fit.timeseries.response.balancing`) and the weighted residual vector
        r(v, q) (cost = ‖r‖²); built once per ``s_max``, shared by the solver and its Gauss–Newton Hessian."""
        if s_max not in self._graphs:
            self._graphs[s_max] = self._build_symbolic(s_max)
        return self._graphs[s_max]

    def _build_symbolic(self, s_max: int) -> tuple[Any, Any, Any]:
        l, n, m = self.model.n_parameters, self.model.n_states, self.model.n_inputs
        E = len(self.records)
        v = ca.SX.sym("v", l + (n * E if self._estimate_x0 else 0))
        q = ca.SX.sym("q", n + m)
        theta = v[:l]
        A, B, C, D = _sx_state_space(self.model, theta)
        x0_map = self.model.initial_state_map if self._x0_mode == "model" else None
        res = []
        for e, r in enumerate(self.records):
            if self._estimate_x0:
                x0 = v[l + n * e: l + n * (e + 1)]
            elif self._x0_mode == "known":
                x0 = ca.SX(ca.DM(self._x0_known[e]))
            elif x0_map is None:
                x0 = ca.SX.zeros(n, 1)
            else:
                x0 = _sx_matrix(x0_map, theta)
            Y = casadi_output(A, B, C, D, r.t, r.u, x0, s_max, (q[:n], q[n:]))
            R = (ca.DM(r.y) - Y) * ca.DM(np.ascontiguousarray(self._sw[e]))
            res.append(ca.vec(R))
        return v, q, ca.vertcat(*res)

    def _jacobian_function(self, s_max: int) -> Any:
        """CasADi function (v, q) ↦ ∂r/∂v for ``s_max`` squarings, for the Gauss–Newton Hessian (built once;
        :meth:`jacobian` computes the same numbers by a recursion in numpy, with no graph to build)."""
        if s_max not in self._jacobian_fns:
            v, q, r = self._symbolic(s_max)
            self._jacobian_fns[s_max] = ca.Function("symid_oe_jacobian", [v, q], [ca.jacobian(r, v)])
        return self._jacobian_fns[s_max]

    def _hessian_for(self, v: Any, q: Any, r: Any, s_max: int) -> str:
        """The Hessian the solver for ``s_max`` squarings uses: the option, or for ``"auto"`` exact unless its
        predicted build time exceeds a quarter of ``time_limit`` (the note of :meth:`run` then says so)."""
        if self._hessian != "auto":
            return self._hessian
        if self._hessian_budget is None:
            return "exact"
        size = ca.Function("symid_oe_size", [v, q], [r]).n_nodes() * v.numel()
        if EXACT_BUILD_RATE * size <= self._hessian_budget / 4:
            return "exact"
        self._hessian_note[s_max] = (f"; Gauss–Newton Hessian (hessian='auto': the exact one's build, "
                                     f"{size:.3g} graph nodes × unknowns, would take more than a quarter of the "
                                     f"time limit)")
        return GAUSS_NEWTON

    def _solver(self, s_max: int) -> ScaledIpopt:
        """IPOPT on ‖r‖² for ``s_max`` squarings, scaled per start (built once)."""
        if s_max not in self._solvers:
            v, q, r = self._symbolic(s_max)
            extra = v.numel() - self.lower.size
            lower = np.concatenate([self.lower, np.full(extra, -np.inf)])
            upper = np.concatenate([self.upper, np.full(extra, np.inf)])
            hessian = self._hessian_for(v, q, r, s_max)
            self._solvers[s_max] = ScaledIpopt(f"symid_oe_{s_max}", v, ca.sumsqr(r), lower=lower,
                                               upper=upper, max_iter=self._max_iter,
                                               tol=self._tol, hessian=hessian, parameters=q,
                                               residual_jacobian=self._jacobian_function(s_max)
                                               if hessian == GAUSS_NEWTON else None,
                                               callback=None if self._report is None and self._time_limit is None
                                               else self._progress)
        return self._solvers[s_max]

    def _progress(self, info: IpoptIteration) -> bool:
        """Every IPOPT iteration: the user's callback (θ alone, iterations counted over the rounds of one start),
        then the start's time budget (one for all rounds, so IPOPT's own per-solve limit is not used)."""
        stop = False
        if self._report is not None:
            stop = bool(self._report(IpoptIteration(info.iteration + self._iterations_before, info.objective,
                                                    info.elapsed, info.theta[: self.model.n_parameters].copy())))
        if self._deadline is not None and time.perf_counter() > self._deadline:
            self._timed_out = True
            return True
        return stop

    def _balance(self, theta: np.ndarray) -> np.ndarray:
        """q = (d, e): the balancing of the exponential at θ (ones where the model is not finite there)."""
        try:
            A, B, _, _ = self._matrices(theta)
        except (np.linalg.LinAlgError, ValueError):
            return np.ones(self.model.n_states + self.model.n_inputs)
        return np.concatenate(balancing(A, B, self._h_max))

    def _squarings(self, theta: np.ndarray, q: np.ndarray) -> int:
        A, B, _, _ = self._matrices(theta)
        n = self.model.n_states
        return squarings(A, B, self._h_max, (q[:n], q[n:]))

    def _graph_for(self, need: int) -> int:
        """The squarings of the graph to use where θ needs ``need``: the fewest of a graph already built that has
        at least that many (more squarings are only more accurate), else ``need + SQUARING_MARGIN``.

        Each number of squarings is a graph of its own, with its Jacobian and solver: 15 s to build for 2500
        samples of a 5-mass chain, uninterruptible, and a second one (an estimate whose ‖A‖ grew past the
        start's squarings) took a third of a 60 s budget. The squarings themselves cost almost nothing in the
        graph (one exponential per distinct sample interval), so the margin lets ‖A Δt‖ grow 4 times first.
        """
        built = [k for k in self._graphs if k >= need]
        return min(built) if built else need + SQUARING_MARGIN

    def _unknowns(self, theta: np.ndarray) -> np.ndarray:
        """v at θ: θ, then (``x0="estimate"``) the least-squares initial state of every record."""
        if not self._estimate_x0:
            return theta.copy()
        try:
            x0s = self.initial_states(theta)
        except (np.linalg.LinAlgError, ValueError):
            x0s = [np.zeros(self.model.n_states) for _ in self.records]
        return np.concatenate([theta, *(np.nan_to_num(x0) for x0 in x0s)])

    def _unknown_scale(self, v0: np.ndarray) -> np.ndarray:
        """Typical magnitudes of v for a start: ``scale`` or |θ₀| (:func:`~symid.engine.ipopt.start_scale`);
        for an estimated initial state, the rms of each state along the start's response of its record
        (the largest |y| of the record where that is 0 or not finite)."""
        l, n = self.model.n_parameters, self.model.n_states
        theta = v0[:l]
        out = [start_scale(theta, self._lower, np.full(l, np.inf)) if self.scale is None else self.scale]
        if not self._estimate_x0:
            return out[0]
        try:
            A, B, _, _ = self._matrices(theta)
            eye, none = np.eye(n), np.zeros((n, self.model.n_inputs))
            with np.errstate(over="ignore", invalid="ignore"):
                rms = [np.sqrt(np.mean(simulate_output(A, B, eye, none, r.t, r.u, v0[l + n * e: l + n * (e + 1)])
                                       ** 2, axis=0)) for e, r in enumerate(self.records)]
        except (np.linalg.LinAlgError, ValueError):
            rms = [np.zeros(n) for _ in self.records]
        for x, fallback in zip(rms, self._x0_scale, strict=True):
            out.append(np.where(np.isfinite(x) & (x > 0), x, fallback))
        return np.concatenate(out)

    def run(self, x0: np.ndarray) -> StartOutcome:
        """Solve from the start ``x0`` (parameter vector); never raises on solver failure.

        The exponential's balancing and squarings are set for the start; when the estimate
        needs more squarings, IPOPT runs again from it with the larger number (at most
        three rounds), with the start's scaling.

        With an error model ``variance={"proportional": a, "additive": b}`` (weights from the
        prediction, the default), the first fit weighs the measured values by σ² = (a·y)² + b²;
        then, at most :data:`REWEIGHTS` times, σ² is taken from the estimate's prediction ŷ and
        the fit is run again from the estimate, until no parameter moves by more than
        :data:`REWEIGHT_TOL` relatively (iteratively reweighted least squares; all within the
        start's ``time_limit``). Weights from the measured values favour the samples whose noise
        happened to be negative; weights from the prediction do not (three-compartment model,
        20 % proportional noise, 200 records: median errors 1.6–1.9 times smaller, the 95 %
        intervals held the truth 93.5–97.5 % of the time against 75–90 %, as with the true σ²;
        ``benchmarks/timeseries_weighting.py``).
        """
        if self._weights_from != "prediction":
            return self._run_start(x0)
        t0 = time.perf_counter()
        limit = self._time_limit
        self._set_variance(self._base_variance)  # every start's first fit: σ² from the measured values
        self._anchor_key = None
        out = self._run_start(x0)
        given, iterations, refits, change = out.start, out.iterations, 0, math.inf
        try:
            for _ in range(REWEIGHTS):
                theta = out.theta
                if not (np.all(np.isfinite(theta)) and np.isfinite(out.cost)):
                    break
                left = None if limit is None else limit - (time.perf_counter() - t0)
                if left is not None and left <= 0:
                    break
                self._anchor(theta)  # σ² from this estimate's prediction
                self._time_limit = left
                out = self._run_start(theta)
                refits += 1
                iterations += out.iterations
                scale = np.maximum(np.abs(theta), np.finfo(float).tiny)
                change = float(np.max(np.abs(out.theta - theta) / scale)) if np.all(np.isfinite(out.theta)) \
                    else math.inf
                if change < REWEIGHT_TOL:
                    break
        finally:
            self._time_limit = limit
        settled = "" if change < REWEIGHT_TOL else (
            f", not settled (the last refit moved a parameter by {change:.1e} of its value)" if refits else
            ", none run")
        return dataclasses.replace(out, start=given, iterations=iterations, wall_time=time.perf_counter() - t0,
                                   message=f"{out.message}; σ² from the prediction, {refits} refit(s){settled}")

    def _run_start(self, x0: np.ndarray) -> StartOutcome:
        """One fit from ``x0`` with the weights as they are (see :meth:`run`)."""
        given = np.asarray(x0, dtype=float)
        moved = ""
        if self._bounded:  # a drawn start outside the bounds begins on them (a user's own was refused)
            moved = moved_onto_bounds(given, self.lower, self.upper, self.model.parameter_names)
            x0 = clip_into(given, self.lower, self.upper)
        if self._solver_kind == "trf":
            out = self._run_trf(np.asarray(x0, dtype=float))
        else:
            out = self._run_ipopt(np.asarray(x0, dtype=float))
        if self._bounded:
            moved += on_bounds(out.theta, self.lower, self.upper, self.model.parameter_names,
                               np.asarray(self.model.positive, dtype=bool) & self._positivity)
        return dataclasses.replace(out, start=given, message=out.message + moved) if moved else out

    def check_start(self, x0: np.ndarray) -> None:
        """Refuse a start of the wrong length or outside the bounds (an :class:`OptionError` naming it)."""
        check_start_bounds(x0, self.lower, self.upper, self.model.parameter_names)

    def _run_ipopt(self, start: np.ndarray) -> StartOutcome:
        """``solver="ipopt"``: IPOPT on CasADi's graph (see :meth:`run`)."""
        t0 = time.perf_counter()
        l = self.model.n_parameters
        q = self._balance(start) if np.all(np.isfinite(start)) else np.ones(self.model.n_states
                                                                            + self.model.n_inputs)
        try:
            s = self._graph_for(self._squarings(start, q))
        except (np.linalg.LinAlgError, ValueError):
            s = self._graph_for(0)
        v = self._unknowns(start)
        scale = self._unknown_scale(v)
        theta, iters, status, finished, note = start, 0, "not run", False, ""
        self._deadline = None if self._time_limit is None else t0 + self._time_limit  # building counts
        self._timed_out = False
        for _ in range(3):
            self._iterations_before = iters  # a new round starts where the last ended: the same iterate, number
            solver = self._solver(s)
            run = solver.solve(v, scale=scale, values=q)
            iters += run.iterations
            status, finished, note = run.status, run.finished, run.note + self._hessian_note.get(s, "")
            if self._timed_out:
                status, finished = "Maximum_WallTime_Exceeded", False
            v = run.z
            theta = v[:l]
            try:
                need = self._squarings(theta, q) if np.all(np.isfinite(theta)) else s
            except (np.linalg.LinAlgError, ValueError):  # e.g. M(θ) singular: IPOPT stopped on the bound m = 0
                need = s
            if need <= s or self._timed_out or status == "User_Requested_Stop":
                break
            s = self._graph_for(need)
        return self.outcome(start, theta, finished=finished, status=status, message=status + note, iterations=iters,
                            wall_time=time.perf_counter() - t0)

    def _run_trf(self, start: np.ndarray) -> StartOutcome:
        """``solver="trf"``: trust-region least squares on φ with the exact Jacobian (see ``solver``)."""
        t0 = time.perf_counter()
        deadline = None if self._time_limit is None else t0 + self._time_limit
        l = self.model.n_parameters
        v0 = self._unknowns(start)
        unit = self._unknown_scale(v0)
        positive = np.zeros(v0.size, dtype=bool)
        positive[:l] = np.isfinite(self._lower) & (self._lower >= 0)  # kept positive (positivity)
        centre = np.where(positive, np.where(v0 > 0, v0, unit), v0)
        if self._bounded:  # a start at 0 is centred on its typical value, moved into the bounds (φ = 0 inside them)
            centre[:l] = np.where(positive[:l], np.clip(centre[:l], self.lower, self.upper), centre[:l])
        big = 1e3 * math.sqrt(self.n_data())
        best = {"cost": math.inf, "v": v0.copy(), "evals": 0, "refused": 0}
        costs: dict[bytes, float] = {}  # every finite evaluation's misfit, by φ

        class _Spent(Exception):
            pass

        lower = np.concatenate([self.lower, np.full(v0.size - l, -np.inf)])
        upper = np.concatenate([self.upper, np.full(v0.size - l, np.inf)])

        def v_of(phi: np.ndarray) -> np.ndarray:
            v = np.where(positive, centre * np.exp(np.clip(phi, -_LOG_BOX, _LOG_BOX)), centre + unit * phi)
            # on a bound exactly, not a rounding error of exp(log(bound / centre)) beyond it
            return np.clip(v, lower, upper) if self._bounded else v

        memo: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

        def value(phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            key = phi.tobytes()
            if key in memo:
                return memo[key]
            if deadline is not None and time.perf_counter() > deadline:
                raise _Spent
            v = v_of(phi)
            try:
                with np.errstate(all="ignore"):
                    r, J = self._residual_and_jacobian(v)
                ok = bool(np.all(np.isfinite(r)) and np.all(np.isfinite(J)))
            except (ModelError, np.linalg.LinAlgError, ValueError):
                ok = False
            if not ok:
                best["refused"] += 1
                r, J = np.full(self.n_data(), big), np.zeros((self.n_data(), v.size))
            else:
                inside = np.abs(phi) < _LOG_BOX
                J = J * np.where(positive, np.where(inside, v, 0.0), unit)[None, :]  # chain rule to φ
                cost = float(r @ r)
                costs[key] = cost
                best["evals"] += 1
                if cost < best["cost"]:
                    best["cost"], best["v"] = cost, v
                    if self._report is not None and self._report(IpoptIteration(
                            best["evals"], cost, time.perf_counter() - t0, v[:l].copy())):
                        raise _Spent
            memo.clear()
            memo[key] = (r, J)
            return r, J

        phi0 = np.zeros(v0.size)  # the start
        box: Any = (-np.inf, np.inf)
        if self._bounded:  # θ's bounds on its φ; the initial states unbounded
            lo, hi = log_box(self.lower, self.upper, centre[:l], unit[:l], positive[:l], _LOG_BOX)
            free = np.full(v0.size - l, np.inf)
            box = (np.concatenate([lo, -free]), np.concatenate([hi, free]))
        status, finished = "not run", False
        try:
            with np.errstate(all="ignore"):  # steps into overflow are refused above, not printed by SciPy
                sol = least_squares(lambda p: value(p)[0], phi0, jac=lambda p: value(p)[1], method="trf",
                                    x_scale=1.0, max_nfev=self._max_iter, ftol=self._tol, xtol=self._tol,
                                    gtol=min(self._tol, 1e-10), bounds=box)
            # SciPy's last point, unless an evaluation it did not keep was better (or its own was refused)
            end_cost = costs.get(sol.x.tobytes(), math.inf)
            v_end = v_of(sol.x) if end_cost <= best["cost"] else best["v"]
            status = {-1: "improper_input", 0: "max_nfev", 1: "gtol", 2: "ftol", 3: "xtol", 4: "ftol_xtol"
                      }.get(int(sol.status), str(sol.status))
            finished = sol.status > 0
        except _Spent:
            v_end = best["v"]
            timed = deadline is not None and time.perf_counter() > deadline
            status = "time_limit" if timed else "stopped"
        message = f"trf: {status}; {best['evals']} evaluation{'s' if best['evals'] != 1 else ''}"
        if not math.isfinite(best["cost"]) and status not in ("time_limit", "stopped"):
            # not one finite evaluation (the budget did not stop it first): the start itself cannot be simulated
            status, finished = "invalid_start", False
            message = ("trf: invalid_start; the model's response at the start is not finite (or the model cannot be "
                       "evaluated there), so no step could be taken")
        elif best["refused"] and np.array_equal(v_end, v0):
            status, finished = "no_step", False
            message += (f"; every step from the start was refused ({best['refused']} where the model's response is "
                        f"not finite or the model cannot be evaluated): the estimate is the start")
        return self.outcome(start, v_end[:l], finished=finished, status=status, message=message,
                            iterations=best["evals"], wall_time=time.perf_counter() - t0)

    def _residual_and_jacobian(self, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Weighted residual r(v) and ∂r/∂v at the unknowns v = (θ, estimated initial states), in numpy."""
        l, n = self.model.n_parameters, self.model.n_states
        theta = v[:l]
        mats, dmats = state_space_derivatives(self.model, theta)
        rs, Js = [], []
        if self._estimate_x0:
            x0s = [v[l + n * e: l + n * (e + 1)] for e in range(len(self.records))]
        else:
            x0s = self.initial_states(theta)
        for e, (r, x0) in enumerate(zip(self.records, x0s, strict=True)):
            dx0 = np.zeros((n, v.size))
            if self._estimate_x0:
                dx0[:, l + n * e: l + n * (e + 1)] = np.eye(n)
            elif self._x0_mode == "model" and self.model.initial_state_map is not None:
                dx0[:, :l] = self.model.initial_state_map.Xi[:, :, 0].T
            Y, dY = output_sensitivity(mats, dmats, r.t, r.u, x0, dx0, hold=self._hold, held=self._held)
            sw = self._sw[e]
            rs.append(((r.y - Y) * sw).T.reshape(-1))
            Js.append((-dY * sw[:, :, None]).transpose(1, 0, 2).reshape(-1, v.size))
        return np.concatenate(rs), np.vstack(Js)

    def residual_channels(self) -> np.ndarray:
        """Output channel of every entry of the residual vector of :meth:`jacobian`."""
        p = self.model.n_outputs
        return np.concatenate([np.repeat(np.arange(p), r.n_samples) for r in self.records])

    @property
    def noise_units(self) -> str:  # type: ignore[override]
        """What the noise level estimated from the residuals measures: data units, or units of the given σ."""
        return "data units" if self._variance is None else "× the given √variance"

    def noise_shape(self, theta: Any) -> np.ndarray:
        """√w per entry: the residual is √w (y − ŷ), noise of one level per output (data units); with
        ``variance``, σ√w (a noise of one level in units of the given σ)."""
        self._anchor(theta)
        if self._variance is not None:
            return np.concatenate([(sw * np.sqrt(v)).T.reshape(-1) for sw, v in zip(self._sw, self._variance,
                                                                                     strict=True)])
        return np.concatenate([sw.T.reshape(-1) for sw in self._sw])

    def given_noise(self, noise_std: Any) -> tuple[np.ndarray, np.ndarray]:
        """Per entry of r, √wⱼ × the given standard deviation; ``noise_std`` is a number, an array (N,) per
        sample, (1, p) per output or (N, p), or a list of such, one per record."""
        items = noise_std if isinstance(noise_std, (list, tuple)) and len(self.records) > 1 else None
        if items is not None and len(items) != len(self.records):
            raise DataError(f"noise_std is a list of {len(items)}; there are {len(self.records)} records")
        std, given = [], []
        for e, r in enumerate(self.records):
            arr = broadcast_noise(noise_std if items is None else items[e], (self._sample_counts[e], r.n_outputs),
                                  f"the output y of record {e}" if len(self.records) > 1 else "the output y",
                                  check=False)
            arr = np.where(self._observed[e], self._on_points(arr, e), 1.0)  # a missing value needs no noise level
            if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
                raise DataError("noise_std must be finite and > 0 everywhere (a standard deviation in data units)")
            std.append((arr * self._sw[e]).T.reshape(-1))  # channel by channel, as the residual
            # the values given for what was measured (a new user's record with a missing value was told the noise
            # given had rms 0.012 for 0.002: the 1 in its place counted)
            given.append(arr[self._observed[e]].reshape(-1))
        return np.concatenate(std), np.concatenate(given)

    def jacobian(self, theta: Any) -> tuple[np.ndarray, np.ndarray]:
        """Weighted residual vector r and its Jacobian with respect to (θ, estimated x0) in natural units.

        ``cost = ‖r‖²``; the columns are ∂r/∂θ (and ∂r/∂x0 per record for ``x0="estimate"``),
        the rows channel by channel of each record (:meth:`residual_channels`). Computed by the
        sensitivity recursion in numpy (:mod:`symid.fit.timeseries.sensitivity`): no symbolic graph
        is built, so the covariance after a start costs milliseconds, not the seconds of a
        CasADi Jacobian (12 s for 2500 samples of a 5-mass chain).
        """
        theta = self.model.theta_vector(theta)
        self._anchor(theta)
        return self._residual_and_jacobian(self._unknowns(theta))
