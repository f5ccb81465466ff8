"""``si.identify``: one entry point that picks the formulation from the model and data kinds."""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import numpy as np

from symid.errors import DataError, ModelError
from symid.formulations.frf_ls import LinearFRF, ls_applicable
from symid.interrupt import Interrupted
from symid.nlls.frf import IpoptFRF
from symid.polish import polish_outcome
from symid.progress import progress_bar
from symid.result import IdentificationResult, StartOutcome
from symid.secondorder import SecondOrderModel
from symid.starts import make_starts
from symid.statespace import StateSpaceModel
from symid.structural.analyse import warn_if_not_identifiable

__all__ = ["METHODS", "identify", "prepare"]

METHODS = ("scr", "ipopt", "ls")


def _check_model(model: Any) -> None:
    if not isinstance(model, (StateSpaceModel, SecondOrderModel)):
        raise ModelError(f"model must be a StateSpaceModel or SecondOrderModel; got {type(model).__name__}")
    if model.n_parameters == 0:
        raise ModelError("the model has no free parameter: there is nothing to estimate")


def _check_frf(model: Any, data: Any) -> None:
    s, p, m = np.asarray(data.H).shape
    if (p, m) != (model.n_outputs, model.n_inputs):
        raise DataError(f"data H has {p} output(s) × {m} input(s) per frequency; the model has "
                        f"{model.n_outputs} output(s) × {model.n_inputs} input(s)")
    equations = 2 * s * p * m
    if equations < model.n_parameters:
        need = math.ceil(model.n_parameters / (2 * p * m))
        raise DataError(f"{s} frequencies give {equations} real equations for {model.n_parameters} unknown "
                        f"parameters: at least {need} frequencies are needed")


def _prepare_frf(model: Any, data: Any, method: str, options: dict[str, Any]) -> Any:
    """Solvers for a frequency response (thesis ch. 3 and 4)."""
    _check_frf(model, data)
    if method == "ls":
        return LinearFRF(model, data, **options)
    if method == "ipopt":
        return IpoptFRF(model, data, **options)
    if method == "scr":
        if isinstance(model, SecondOrderModel) and ls_applicable(model) and not options.get("force_scr", False):
            return LinearFRF(model, data)
        from symid.formulations.frf_scr import ScrFRF

        opts = {k: v for k, v in options.items() if k != "force_scr"}
        return ScrFRF(model, data, **opts)
    raise ModelError(f"unknown method {method!r} for frequency-response data; choose one of {', '.join(METHODS)}")


def prepare(model: Any, data: Any, method: str, options: dict[str, Any]) -> Any:
    """Build the method's solver for this model and data once; its ``run(x0)`` solves one start.

    The formulation follows from the two kinds (the table of ``design.md``); each data
    kind has its own ``_prepare_*`` function. A solver has ``method`` (the method that
    actually runs), ``options`` and ``run(x0) -> StartOutcome``.
    """
    from symid.data import BlackBox, FrequencyData, IOData, SpectralData

    _check_model(model)
    if isinstance(data, FrequencyData):
        return _prepare_frf(model, data, method, options)
    if isinstance(data, SpectralData):
        from symid.formulations.psd_prepare import prepare_spectral

        return prepare_spectral(model, data, method, options)
    if isinstance(data, (BlackBox, IOData)):
        from symid.similarity import prepare_similarity

        return prepare_similarity(model, data, method, options)
    raise DataError(f"identify() for {type(model).__name__} does not take {type(data).__name__} data here")


def identify(model: Any, data: Any, method: str = "scr", *, x0: Any = None, starts: int = 1,
             seed: int | None = None, polish: bool = False, progress: bool | None = None,
             identifiability_check: bool = True, **options: Any) -> IdentificationResult:
    """Estimate the parameters of a symbolic model from data.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
        The grey-box model.
    data : FrequencyData, BlackBox or IOData
        The measurements. A black box, or input/output records (then N4SID and an
        exact zero-order-hold ``d2c`` first), go to the similarity-transformation
        formulations of thesis chapters 6 and 7 (:mod:`symid.similarity`), where the
        methods are ``"scr"``, ``"als"``, ``"gb"``, ``"ipopt"`` and ``"ls"``.
    method : {"scr", "ipopt", "ls", "als", "gb"}
        ``"scr"``: sequential convex relaxation (thesis Algorithm 3.1 / (4-8)); for a
        second-order model whose C or B is known, square and invertible the linear
        least squares (4-10)/(4-11) is exact and is used instead (reported as method
        ``"ls"``; pass ``force_scr=True`` to run SCR anyway). ``"ipopt"``: nonlinear
        least squares on the frequency response with CasADi/IPOPT. ``"ls"``: the linear
        least squares; a clear error when it does not apply.
    x0 : dict or sequence, optional
        A start; it becomes the first of ``starts``.
    starts : int
        Number of starts. Default starts: for a state-space model the first is θ = 0
        (thesis ch. 3), for a second-order model all are N(0, 1) draws (thesis ch. 4),
        positive parameters drawn in absolute value. Every method gets the same starts
        for the same ``seed``.
    seed : int, optional
        Seed of the random starts.
    polish : bool
        After SCR, refine the best estimate with IPOPT (kept only when it lowers the
        misfit, :func:`symid.polish.polish_outcome`); reported as its own result in
        ``result.polished`` (method ``"scr+polish"``, time = all SCR starts + polish),
        never mixed into the SCR figures. :func:`symid.compare` polishes every start
        (method ``"scr+polish"``).
    progress : bool, optional
        Show a progress bar over the starts (default: when there is more than one start
        and standard error is a terminal).
    identifiability_check : bool
        Before estimating, run the cheap local identifiability test and emit an
        :class:`~symid.IdentifiabilityWarning` naming the parameters that no data of
        this kind can determine (default True).
    **options
        Passed to the method (e.g. ``backend="admm"``, ``max_iter``, ``tol`` for SCR;
        ``scale``, ``hessian`` for IPOPT).

    Returns
    -------
    IdentificationResult
        The best start by data misfit, and every start's outcome in ``result.starts``.

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
    >>> [round(v, 6) for v in res.theta.values()]
    [2.0, 0.5, 3.0]
    """
    solver = prepare(model, data, method, dict(options))
    if identifiability_check:
        warn_if_not_identifiable(model, stacklevel=2)
    zero_first = isinstance(model, StateSpaceModel)
    x0s = make_starts(model, starts, seed, x0, zero_first=zero_first)
    if solver.method == "ls":
        x0s = x0s[:1]
    outcomes: list[StartOutcome] = []
    label = f"{solver.method} starts"
    options_used = dict(getattr(solver, "options", {}))
    if solver.method != method:
        options_used["chosen_because"] = f"{method} → {solver.method}: linear special case ({solver.case})"
    try:
        for x in progress_bar(x0s, desc=label, enabled=progress):
            outcomes.append(solver.run(x))
    except KeyboardInterrupt:
        if not outcomes:
            raise
        partial = IdentificationResult.from_starts(solver.method, model.parameter_names, outcomes,
                                                   {**options_used, "interrupted": True})
        raise Interrupted(f"identify() interrupted after {len(outcomes)} of {len(x0s)} starts; "
                          f"the finished starts are in the exception's .partial result", partial) from None
    result = IdentificationResult.from_starts(solver.method, model.parameter_names, outcomes, options_used)
    if polish and solver.method == "scr":
        t0 = time.perf_counter()
        polisher = getattr(solver, "polisher", None) or IpoptFRF(model, data)
        out = polish_outcome(polisher, result.best_start)
        # the polished estimate cost every SCR start plus the polish
        out = dataclasses.replace(out, wall_time=result.wall_time + time.perf_counter() - t0)
        polished = IdentificationResult.from_starts("scr+polish", model.parameter_names, [out],
                                                    {"polish": getattr(polisher, "method", "polish")})
        result = dataclasses.replace(result, polished=polished)
    return result
