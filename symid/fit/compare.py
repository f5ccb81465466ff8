"""``si.compare``: several methods on the same model, data and starts, side by side."""

from __future__ import annotations

import time
import uuid
from collections.abc import Mapping, Sequence
from concurrent.futures import Executor, as_completed
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from symid.errors import DataError, ModelError, OptionError
from symid.fit.options import check_choice, check_float, scale_by_name, without_known
from symid.fit.registry import check_model, data_kind, prepare
from symid.fit.result import IdentificationResult, StartOutcome
from symid.fit.starts import draw_starts
from symid.interrupt import Interrupted
from symid.progress import progress_bar
from symid.runlog import RunLog

__all__ = ["Comparison", "MethodStats", "compare", "largest_relative_error", "relative_parameter_error"]


def relative_parameter_error(theta: np.ndarray, truth: np.ndarray) -> float:
    """‖θ − θ*‖₂ / ‖θ*‖₂ (absolute error when θ* = 0).

    Examples
    --------
    >>> from symid.fit.compare import relative_parameter_error
    >>> relative_parameter_error([1.0, 2.1], [1.0, 2.0]) < 0.05
    True
    """
    theta = np.asarray(theta, dtype=float)
    truth = np.asarray(truth, dtype=float)
    den = float(np.linalg.norm(truth))
    return float(np.linalg.norm(theta - truth) / (den if den > 0 else 1.0))


def largest_relative_error(theta: np.ndarray, truth: np.ndarray) -> float:
    """maxₖ |θₖ − θ*ₖ| / |θ*ₖ| (the absolute error where θ*ₖ = 0): the worst parameter, whatever its units.

    :func:`relative_parameter_error` is dominated by the largest parameters: in SI units
    a spring of 1e4 N/m exact hides a mass 100 % off; this one does not.

    Examples
    --------
    >>> from symid.fit.compare import largest_relative_error, relative_parameter_error
    >>> relative_parameter_error([2.0, 1e4], [1.0, 1e4]) < 1e-3, largest_relative_error([2.0, 1e4], [1.0, 1e4])
    (True, 1.0)
    """
    theta = np.asarray(theta, dtype=float)
    truth = np.asarray(truth, dtype=float)
    den = np.where(truth != 0, np.abs(truth), 1.0)
    return float(np.max(np.abs(theta - truth) / den, initial=0.0))


_ERRORS = {"largest": largest_relative_error, "l2": relative_parameter_error}


@dataclass(frozen=True)
class MethodStats:
    """One method's figures in a comparison.

    Attributes
    ----------
    method : str
        The method asked for (``"scr"``, ``"ipopt"``, ...).
    ran_as : str
        The method that actually ran (``"ls"`` when SCR chose the linear special case).
    n_starts, n_success : int
        Starts run and starts that succeeded (by the comparison's criterion).
    success_rate : float
        ``n_success / n_starts``.
    median_time : float
        Median seconds per start (solver time, setup excluded).
    setup_time : float
        Seconds to build the method's problem once (shared by all starts).
    time_to_solution : float
        (setup + all starts) / successes; ``inf`` without a success.
    best_cost : float
        Lowest data misfit over the starts.
    best_error : float or None
        Parameter error (``param_error`` of :func:`compare`) of the best-cost start, when the truth is known.
    result : IdentificationResult
        Every start's outcome.
    """

    method: str
    ran_as: str
    n_starts: int
    n_success: int
    success_rate: float
    median_time: float
    setup_time: float
    time_to_solution: float
    best_cost: float
    best_error: float | None
    result: IdentificationResult = field(repr=False)

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python form, suitable for JSON."""
        return {"method": self.method, "ran_as": self.ran_as, "n_starts": self.n_starts,
                "n_success": self.n_success, "success_rate": self.success_rate, "median_time": self.median_time,
                "setup_time": self.setup_time, "time_to_solution": self.time_to_solution,
                "best_cost": self.best_cost, "best_error": self.best_error,
                "theta": self.result.theta, "starts": [s.to_dict() for s in self.result.starts]}


@dataclass(frozen=True)
class Comparison:
    """The outcome of :func:`compare`: per method, success rate and time figures.

    A start counts as a success when its parameter error (``param_error``: the largest
    relative error of any parameter, or ‖θ − θ*‖₂/‖θ*‖₂) is ≤ ``param_tol`` if the truth
    is known, otherwise when the start's own ``success``
    holds (the estimate fits the data, :mod:`symid.fit.success`).

    Attributes
    ----------
    stats : tuple of MethodStats
        One row per method, in the order asked (``cmp["scr"]`` picks one by name).
    n_starts : int
        Starts per method (identical for every method).
    seed : int or None
        Seed of the starts.
    criterion : str
        What counted as a success.
    truth : dict or None
        The true parameters, when given.
    """

    stats: tuple[MethodStats, ...]
    n_starts: int
    seed: int | None
    criterion: str
    truth: dict[str, float] | None = None

    def __getitem__(self, method: str) -> MethodStats:
        for s in self.stats:
            if s.method == method:
                return s
        raise KeyError(method)

    def _rows(self) -> list[list[str]]:
        rows = []
        for s in self.stats:
            name = s.method if s.ran_as == s.method else f"{s.method} (as {s.ran_as})"
            rows.append([name, f"{s.n_success}/{s.n_starts}", f"{100 * s.success_rate:.0f}%",
                         f"{1e3 * s.median_time:.1f}", f"{1e3 * s.setup_time:.1f}",
                         "inf" if not np.isfinite(s.time_to_solution) else f"{s.time_to_solution:.3f}",
                         f"{s.best_cost:.2e}", "—" if s.best_error is None else f"{s.best_error:.2e}"])
        return rows

    _HEAD: ClassVar[tuple[str, ...]] = ("method", "successes", "rate", "median ms/start", "setup ms",
                                         "time to solution s", "best cost", "best param. error")

    def table(self) -> str:
        """A plain-text table."""
        rows = [list(self._HEAD), *self._rows()]
        widths = [max(len(r[i]) for r in rows) for i in range(len(self._HEAD))]
        lines = ["  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in rows]
        lines.insert(1, "  ".join("-" * w for w in widths))
        out = [f"{self.n_starts} identical starts (seed {self.seed}); success: {self.criterion}", *lines]
        if (hint := self._noise_hint()) is not None:
            out.append(hint)
        return "\n".join(out)

    def _noise_hint(self) -> str | None:
        """A line for a comparison against the truth where no start is near it but some fit the data."""
        if self.truth is None or any(s.n_success for s in self.stats):
            return None
        fits = sum(st.success for s in self.stats for st in s.result.starts)
        if not fits:
            return None
        return (f"NOTE: no start is within the tolerance of the truth, but {fits} fit the data (their own success "
                "rule): on noisy data the best fit lies off the truth by what the noise allows; compare with a "
                "param_tol near the estimates' standard errors (.result.uncertainty), or without truth=")

    def to_markdown(self) -> str:
        """A Markdown table."""
        lines = ["| " + " | ".join(self._HEAD) + " |", "|" + "---|" * len(self._HEAD)]
        lines += ["| " + " | ".join(r) + " |" for r in self._rows()]
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python form, suitable for JSON."""
        return {"n_starts": self.n_starts, "seed": self.seed, "criterion": self.criterion, "truth": self.truth,
                "methods": [s.to_dict() for s in self.stats]}

    def __str__(self) -> str:
        return self.table()


def _takes(kind: str, method: str, option: str) -> bool:
    """Whether ``method`` of the data kind ``kind`` takes the keyword ``option`` (any of its estimators)."""
    from symid.fit.catalog import estimator_classes

    label = "black box / I/O" if kind == "black box" else kind
    return any(option in cls.option_names() for k, m, cls in estimator_classes()
               if k == label and m.split(" ")[0] == method)


def compare(model: Any, data: Any, methods: tuple[str, ...] | list[str] = ("scr", "ipopt"), *,
            starts: int | Sequence[Any] = 10, seed: int | None = 0, truth: Any = None, x0: Any = None,
            param_tol: float = 1e-3, param_error: str = "largest", progress: bool | None = None,
            options: dict[str, dict[str, Any]] | None = None,
            noise_floor: float | None = None, log: RunLog | None = None, executor: Executor | None = None,
            draws: str | None = None, scale: Any = None) -> Comparison:
    """Run several methods from identical starts and tabulate success and time.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    data : FrequencyData, SpectralData, BlackBox or IOData
    methods : sequence of str
        Methods to compare (see :func:`symid.identify`). ``"<method>+polish"`` runs the
        method and, from every start, its declared polisher
        (:meth:`symid.fit.base.Estimator.polisher`, IPOPT); for frequency responses
        ``"scr+polish"`` hands over as soon as a trial polish from the current SCR
        estimate fits the data (:meth:`symid.fit.frf.scr.ScrFRF.run_polished`). It is
        built and run on its own, so its setup and time per start (method + every
        polish) share nothing with the plain row.
    starts : int or sequence of parameter vectors
        Number of starts (every method gets the same list, :func:`symid.fit.starts.draw_starts`),
        or the starts themselves: a sequence of dicts or vectors in ``parameter_names``
        order (then ``seed``, ``x0`` and ``draws`` play no part).
    seed : int, optional
        Seed of the random starts.
    truth : dict or sequence, optional
        True parameters; success is then a parameter error ≤ ``param_tol``.
    x0 : dict or sequence, optional
        A start put first in the list.
    param_tol : float
        Success threshold on the parameter error, with a truth (default 1e-3).
    param_error : {"largest", "l2"}
        The parameter error: ``"largest"`` (default) maxₖ |θₖ − θ*ₖ|/|θ*ₖ|
        (:func:`largest_relative_error`, meaningful in any units), ``"l2"``
        ‖θ − θ*‖₂/‖θ*‖₂ (:func:`relative_parameter_error`, the thesis's measure; dominated by
        the largest parameters).
    progress : bool, optional
        Progress bar (default: on a terminal).
    options : dict, optional
        Per-method options, e.g. ``{"scr": {"backend": "admm"}}``; ``"scr+polish"``
        uses the options of ``"scr"``.
    noise_floor : float, optional
        As in :func:`symid.identify` (judges each start's own ``success``).
    log : symid.runlog.RunLog, optional
        Record every start as it ends (JSON Lines, flushed); starts already in the log
        are read back instead of run, so an interrupted comparison resumes where it
        stopped. Use :meth:`~symid.runlog.RunLog.scoped` to keep several comparisons in
        one file. A log written with other starts is refused.
    draws : {"scale", "normal"}, optional
        How the random starts are drawn, as in :func:`symid.identify`; with ``"scale"``,
        the typical values are ``scale``, else the first compared method's ``scale=``
        option, else the data's (frequency responses; time series through their frequency
        response).
    scale : float, sequence or dict, optional
        Typical values of the parameters, as :func:`symid.identify`'s ``scale=``: given to
        every compared method that takes ``scale=`` (a method's own ``options`` win) and
        used for the random starts.
    executor : concurrent.futures.Executor, optional
        Run the starts of each method as tasks of this executor: a
        ``concurrent.futures.ProcessPoolExecutor`` on one machine, or a Dask cluster's
        ``distributed.Client(...).get_executor()`` when a study outgrows it. Each worker
        process builds every method's problem once (the model, data and options are sent
        to it) and reuses it for the starts it runs; results are identical to a serial
        run (every start is independent). Default: the starts run one after another in
        this process. Threads (``ThreadPoolExecutor``) gain nothing: the solvers hold
        the GIL for most of their time.

    Returns
    -------
    Comparison

    Raises
    ------
    symid.interrupt.Interrupted
        On Ctrl-C after at least one start finished; its ``partial`` is the comparison
        of the finished starts (an unfinished method's row counts only its finished
        starts).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> truth = {"m": 2.0, "c": 0.5, "k": 3.0}
    >>> frf = si.simulate_frf(model, truth, np.linspace(0.5, 2.0, 5))
    >>> cmp = si.compare(model, frf, methods=("ls", "ipopt"), starts=3, seed=0, truth=truth)
    >>> cmp["ls"].n_success, cmp["ls"].n_starts
    (3, 3)
    """
    check_model(model)
    if isinstance(methods, str) or not methods:
        raise ModelError("compare() needs a sequence of at least one method name")
    methods = tuple(methods)
    if len(set(methods)) != len(methods):
        raise ModelError(f"a method is listed twice in {methods}")
    kind = data_kind(data)
    for m in methods:
        if not isinstance(m, str) or m.removesuffix("+polish") not in kind.methods:
            raise OptionError(f"unknown method {m!r} for {kind.name} data; choose among "
                              f"{', '.join(kind.methods)} (each also as '<method>+polish' where it has a polish step)")
    # a model file's start, scale and bounds name every parameter; with some made known (with_known) they still serve
    known = model.known_values if hasattr(model, "known_values") else {}
    x0 = without_known(x0, known)
    options = {m: ({k: (without_known(v, known) if k in ("scale", "bounds") else v) for k, v in o.items()}
                   if isinstance(o, dict) else o) for m, o in dict(options or {}).items()}
    unknown = set(options) - {m.removesuffix("+polish") for m in methods}
    if unknown:
        raise ModelError(f"options are keyed by method, e.g. options={{'ipopt': {{'time_limit': 10}}}} (a "
                         f"'+polish' method takes its base method's options); these keys are not methods "
                         f"compared here ({', '.join(methods)}): {', '.join(sorted(map(str, unknown)))}")
    if scale is not None:  # shared typical values (a new user's compare(..., scale=...) was a bare TypeError)
        scale = without_known(scale, known)
        for base in {m.removesuffix("+polish") for m in methods}:
            if _takes(kind.name, base, "scale") and not (isinstance(options.get(base), dict)
                                                          and options[base].get("scale") is not None):
                options[base] = {**(options.get(base) or {}), "scale": scale}
    param_tol = check_float("param_tol", param_tol, low=0, strict_low=True)
    error_of = _ERRORS[check_choice("param_error", param_error, tuple(_ERRORS))]
    truth_vec = None if truth is None else model.theta_vector(truth)
    scale = (scale_by_name({"scale": scale}, model.parameter_names)["scale"] if scale is not None else
             next((scale_by_name(o, model.parameter_names)["scale"] for o in options.values()
                   if isinstance(o, dict) and o.get("scale") is not None), None))
    x0s = _start_list(model, data, starts, seed, x0, draws, scale)
    if log is not None and not isinstance(log, RunLog):
        raise ModelError(f"log must be a symid.runlog.RunLog; got {type(log).__name__}")
    if executor is not None and not isinstance(executor, Executor):
        raise ModelError(f"executor must be a concurrent.futures.Executor (a process pool, or a Dask client's "
                         f"get_executor()); got {type(executor).__name__}")
    criterion = ((f"largest relative parameter error <= {param_tol:g}" if param_error == "largest" else
                  f"relative parameter error ‖θ − θ*‖₂/‖θ*‖₂ <= {param_tol:g}") if truth_vec is not None
                 else "the start's own success (the estimate fits the data)")
    stats: list[MethodStats] = []

    def tabulate(method: str, meta: dict[str, Any], outcomes: list[StartOutcome], interrupted: bool = False
                 ) -> MethodStats:
        opts = {**meta.get("options", {}), **({"interrupted": True} if interrupted else {})}
        ran_as = meta.get("ran_as", method)
        res = IdentificationResult.from_starts(ran_as, model.parameter_names, outcomes,
                                               cost_kind=meta.get("cost_kind", ""), options=opts)
        if truth_vec is not None:
            ok = [error_of(o.theta, truth_vec) <= param_tol for o in outcomes]
            best_err = error_of(res.theta_vector, truth_vec)
        else:
            ok = [o.success for o in outcomes]
            best_err = None
        n_ok = int(sum(ok))
        setup = float(meta.get("setup_time", 0.0))
        total = setup + sum(o.wall_time for o in outcomes)
        return MethodStats(method=method, ran_as=ran_as, n_starts=len(outcomes), n_success=n_ok,
                           success_rate=n_ok / len(outcomes),
                           median_time=float(np.median([o.wall_time for o in outcomes])), setup_time=setup,
                           time_to_solution=total / n_ok if n_ok else float("inf"),
                           best_cost=res.cost, best_error=best_err, result=res)

    def partial() -> Comparison:
        return Comparison(stats=tuple(stats), n_starts=len(x0s), seed=seed, criterion=criterion,
                          truth=None if truth is None else model.theta_dict(truth))

    # every method is built (its options and the data checked) before any runs: a method that cannot take these
    # data is refused at once, not after the earlier methods' starts (a new user's comparison lost its finished
    # output-error row to srivc's refusal of the model)
    built: dict[str, tuple[Any, Any, float]] = {}
    for method in methods:
        t0 = time.perf_counter()
        try:
            estimator, polisher = _build(model, data, method, dict(options.get(method.removesuffix("+polish"), {})),
                                         noise_floor)
        except (ModelError, DataError, OptionError) as exc:
            # which method, and that the comparison runs without it (a new user's methods=("lm", "ls") stopped at
            # the linear least squares' own message, naming neither)
            others = [m for m in methods if m != method]
            kind = next(c for c in (OptionError, DataError, ModelError) if isinstance(exc, c))
            raise kind(f"compare(): method {method!r} cannot run here, so nothing ran: {str(exc).rstrip('.')}"
                       + (f". Leave it out (methods={tuple(others)!r})" if others else "")) from None
        built[method] = (estimator, polisher, time.perf_counter() - t0)
    for method in methods:
        outcomes: list[StartOutcome] = []
        meta: dict[str, Any] = {}
        try:
            method_options = dict(options.get(method.removesuffix("+polish"), {}))
            _run_method(model, data, method, method_options, x0s, progress, log, outcomes, meta, noise_floor,
                        executor, built.pop(method))
        except KeyboardInterrupt:
            if outcomes:
                stats.append(tabulate(method, meta, outcomes, interrupted=True))
            if not stats:
                raise
            done = ", ".join(f"{s.method} {s.n_starts}/{len(x0s)}" for s in stats)
            raise Interrupted(f"compare() interrupted (finished starts: {done}); they are in the exception's "
                              f".partial comparison", partial()) from None
        stats.append(tabulate(method, meta, outcomes))
    return partial()


def _start_list(model: Any, data: Any, starts: Any, seed: int | None, x0: Any, draws: str | None, scale: Any
                ) -> list[np.ndarray]:
    """The starts of a comparison: drawn (``starts`` a count) or given (a sequence of starts)."""
    if isinstance(starts, (int, np.integer)) and not isinstance(starts, bool):
        return draw_starts(model, data, int(starts), seed, x0, draws=draws, scale=scale)
    if isinstance(starts, (str, bytes, Mapping)) or not isinstance(starts, (Sequence, np.ndarray)) or len(starts) == 0:
        raise OptionError(f"starts must be a number of starts or a non-empty sequence of starts (dicts or vectors "
                          f"of {model.n_parameters} values); got {type(starts).__name__}")
    if x0 is not None:
        raise OptionError("give either x0 or an explicit list of starts, not both (put x0 in the list)")
    out = []
    for i, st in enumerate(starts):
        try:
            out.append(np.asarray(model.theta_vector(st), dtype=float))
        except ValueError as exc:
            raise OptionError(f"start {i}: {exc}") from None
    return out


# One worker process builds each (comparison, method) estimator once and reuses it for its starts; a few
# recent ones are kept, the oldest dropped. Private to this module; never consulted by the parent process.
_WORKER_ESTIMATORS: dict[str, tuple[Any, Any]] = {}
_WORKER_KEEP = 4


def _worker_start(token: str, model: Any, data: Any, method: str, options: dict[str, Any],
                  noise_floor: float | None, x: np.ndarray) -> StartOutcome:
    """Run one start in an executor's worker (its history comes back with it)."""
    built = _WORKER_ESTIMATORS.get(token)
    if built is None:
        estimator, polisher = _build(model, data, method, options, noise_floor)
        while len(_WORKER_ESTIMATORS) >= _WORKER_KEEP:
            _WORKER_ESTIMATORS.pop(next(iter(_WORKER_ESTIMATORS)))
        built = _WORKER_ESTIMATORS[token] = (estimator, polisher)
    estimator, polisher = built
    return estimator.run(x) if polisher is None else estimator.run_polished(x, polisher)


def _build(model: Any, data: Any, method: str, options: dict[str, Any], noise_floor: float | None
           ) -> tuple[Any, Any]:
    """The estimator of ``method`` and, for ``"<method>+polish"``, its polisher."""
    options = scale_by_name(options, model.parameter_names)  # a dict by name, as x0 may be
    estimator = prepare(model, data, method.removesuffix("+polish"), options, noise_floor=noise_floor)
    polisher = None
    if method.endswith("+polish"):
        polisher = estimator.polisher()
        if polisher is None:
            raise OptionError(f"{method!r}: method {estimator.method!r} has no polish step")
        polisher.noise_floor = estimator.noise_floor  # the polished estimate is judged by the same rule
    return estimator, polisher


def _run_method(model: Any, data: Any, method: str, options: dict[str, Any], x0s: list[np.ndarray],
                progress: bool | None, log: RunLog | None, outcomes: list[StartOutcome], meta: dict[str, Any],
                noise_floor: float | None, executor: Executor | None = None,
                built: tuple[Any, Any, float] | None = None) -> None:
    """Run one method from every start, appending to ``outcomes`` (in start order).

    ``meta`` receives ``ran_as``, ``options``, ``setup_time`` and ``cost_kind`` as soon as
    they are known (so an interrupted row is still labelled). Starts found in ``log`` are
    read back instead of run; each new one is logged as it ends. With an ``executor``
    the starts run as its tasks and are logged as they complete, in any order.
    """
    cached = [None if log is None else log.get(f"{method}/start{i}") for i in range(len(x0s))]
    for i, (rec, x) in enumerate(zip(cached, x0s, strict=True)):
        if rec is not None and not np.allclose(rec["start"], x, rtol=1e-12, atol=0):
            raise DataError(f"the log {log.path} holds start {i} of {method} from another starting point "
                            f"(another seed, x0 or model?); resume with the same arguments or use a new log")
    head = None if log is None else log.get(f"{method}/setup")
    if head is not None and all(rec is not None for rec in cached):  # everything done: nothing to build
        meta.update(ran_as=str(head["ran_as"]), options=dict(head["options"]), setup_time=float(head["setup_time"]),
                    cost_kind=str(head["cost_kind"]))
        outcomes.extend(StartOutcome.from_dict(rec) for rec in cached)
        return
    if built is not None:  # (built by compare, which checks every method before running any)
        estimator, polisher, setup = built
    else:
        t0 = time.perf_counter()
        estimator, polisher = _build(model, data, method, options, noise_floor)  # every row builds its own
        setup = time.perf_counter() - t0
    opts = dict(estimator.options)
    ran_as = estimator.method
    if polisher is not None:
        ran_as = f"{estimator.method}+polish"
        opts["polish"] = polisher.method
    if head is not None:
        setup = float(head["setup_time"])  # the first run's setup is the one the figures count
    elif log is not None:
        log.append(f"{method}/setup", {"ran_as": ran_as, "options": opts, "setup_time": setup,
                                       "cost_kind": estimator.cost_kind})
    meta.update(ran_as=ran_as, options=opts, setup_time=setup, cost_kind=estimator.cost_kind)
    if executor is not None:
        _run_on_executor(executor, model, data, method, options, noise_floor, x0s, cached, progress, log, outcomes)
        return
    for i, x in enumerate(progress_bar(x0s, desc=method, enabled=progress)):
        if cached[i] is not None:
            outcomes.append(StartOutcome.from_dict(cached[i]))
            continue
        out = estimator.run(x) if polisher is None else estimator.run_polished(x, polisher)
        outcomes.append(out)
        if log is not None:
            log.append(f"{method}/start{i}", out.to_dict())


def _run_on_executor(executor: Executor, model: Any, data: Any, method: str, options: dict[str, Any],
                     noise_floor: float | None, x0s: list[np.ndarray], cached: list[Any], progress: bool | None,
                     log: RunLog | None, outcomes: list[StartOutcome]) -> None:
    """The starts not in the log as tasks of ``executor``; ``outcomes`` gets them in start order.

    On Ctrl-C the tasks not started are cancelled, and ``outcomes`` holds the starts
    finished so far (in start order) before the interrupt propagates.
    """
    token = uuid.uuid4().hex
    done: dict[int, StartOutcome] = {i: StartOutcome.from_dict(rec) for i, rec in enumerate(cached) if rec is not None}
    futures = {executor.submit(_worker_start, token, model, data, method, options, noise_floor, x): i
               for i, x in enumerate(x0s) if i not in done}
    try:
        for fut in progress_bar(as_completed(futures), desc=method, enabled=progress, total=len(futures)):
            i = futures[fut]
            out = fut.result()
            done[i] = out
            if log is not None:
                log.append(f"{method}/start{i}", out.to_dict())
    finally:
        for fut in futures:
            fut.cancel()
        outcomes.extend(done[i] for i in sorted(done))
