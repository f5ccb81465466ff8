"""Solvers for black-box and input/output data: the similarity-transformation rows of the design table.

:func:`prepare_similarity` is what :func:`symid.identify` and :func:`symid.compare` call for
:class:`~symid.data.BlackBox` and :class:`~symid.data.IOData` data. Input/output records
first become a continuous-time black box of the model's order (N4SID + exact ZOH
``d2c``, Algorithms 6.1 and 7.1, steps 1–2).

=================  ==========================================  =====================================
model              method                                      solver
=================  ==========================================  =====================================
StateSpaceModel    ``"scr"``                                   (6-13)/(6-14), Algorithm 6.1
StateSpaceModel    ``"als"``, ``"gb"``                         appendix C: (C-2)–(C-8), (C-12)–(C-18)
StateSpaceModel    ``"ipopt"``                                 (6-9) with CasADi/IPOPT
SecondOrderModel   ``"scr"``                                   §7-5-2 linear case when it applies,
                                                               else (7-10), Algorithm 7.1
SecondOrderModel   ``"ls"``                                    §7-5-2 (full sensors / actuators)
SecondOrderModel   ``"ipopt"``                                 NLLS on the black box's frequency
                                                               response
=================  ==========================================  =====================================

Every solver ranks its estimate by the same basis-free misfit
(:meth:`~symid.formulations.similarity_data.SimilarityData.misfit`).
"""

from __future__ import annotations

from typing import Any

from symid.errors import ModelError
from symid.formulations.similarity_data import SimilarityData, similarity_data
from symid.result import StartOutcome
from symid.secondorder import SecondOrderModel

__all__ = ["SIMILARITY_METHODS", "prepare_similarity"]

SIMILARITY_METHODS = ("scr", "als", "gb", "ipopt", "ls")
_DATA_OPTIONS = ("horizon", "allow_unstable", "balance")


class _RankedBySimilarity:
    """A frequency-response solver on the black box's response, its outcomes ranked by the black-box misfit."""

    def __init__(self, inner: Any, model: Any, data: SimilarityData):
        self.inner, self.model, self.data, self.frf = inner, model, data, data.frf
        self.method = inner.method
        self.options = {**inner.options, "black_box": data.source, "data": "black-box frequency response"}

    def run(self, x0: Any) -> StartOutcome:
        out = self.inner.run(x0)
        return StartOutcome(**{**out.__dict__, "cost": self.data.misfit(self.model, out.theta)})


def _polisher(model: Any, data: SimilarityData) -> Any:
    from symid.nlls.similarity import IpoptSimilarity

    return IpoptSimilarity(model, data, init="theta")


def prepare_similarity(model: Any, data: Any, method: str, options: dict[str, Any]) -> Any:
    """The solver of ``method`` for a model and BlackBox or IOData data (see the module table).

    Options ``horizon`` (N4SID), ``allow_unstable`` and ``balance`` configure the black box (see
    :func:`~symid.formulations.similarity_data.similarity_data`); the rest
    go to the solver. SCR solvers carry a ``polisher`` that ``identify(..., polish=True)``
    runs from the SCR estimate: IPOPT on (6-9) (T from (C-7)) for a state-space model,
    NLLS on the black box's frequency response for a second-order model.
    """
    opts = dict(options)
    data_opts = {k: opts.pop(k) for k in _DATA_OPTIONS if k in opts}
    if method not in SIMILARITY_METHODS:
        raise ModelError(f"unknown method {method!r} for black-box data; choose one of {', '.join(SIMILARITY_METHODS)}")
    sd = similarity_data(model, data, **data_opts)
    if isinstance(model, SecondOrderModel):
        from symid.formulations.similarity_2nd import LinearSimilarity2nd, ScrSimilarity2nd, second_order_case

        if method in ("als", "gb"):
            raise ModelError(f"method {method!r} (thesis appendix C) needs a StateSpaceModel, whose matrices are "
                             "affine in θ; for a SecondOrderModel use 'scr', 'ls' or 'ipopt'")
        if method == "ls":
            return LinearSimilarity2nd(model, sd, **opts)
        if method == "ipopt":
            from symid.nlls.frf import IpoptFRF

            return _RankedBySimilarity(IpoptFRF(model, sd.frf, **opts), model, sd)
        force = opts.pop("force_scr", False)
        if not force and second_order_case(model) is not None:
            if opts:
                raise ModelError(f"options {', '.join(sorted(opts))} are SCR options, but the linear special case "
                                 "of §7-5-2 applies and runs instead; pass force_scr=True to run SCR")
            return LinearSimilarity2nd(model, sd)
        from symid.nlls.frf import IpoptFRF

        solver = ScrSimilarity2nd(model, sd, **opts)
        solver.polisher = _RankedBySimilarity(IpoptFRF(model, sd.frf), model, sd)
        return solver
    if method == "ls":
        raise ModelError("method 'ls' (the linear special cases of thesis §7-5-2) is for SecondOrderModel; for a "
                         "StateSpaceModel with black-box data use 'scr', 'als', 'gb' or 'ipopt'")
    if method == "scr":
        from symid.formulations.similarity_scr import ScrSimilarity

        solver = ScrSimilarity(model, sd, **opts)
        solver.polisher = _polisher(model, sd)
        return solver
    if method == "als":
        from symid.baselines.als import AlsSimilarity

        return AlsSimilarity(model, sd, **opts)
    if method == "gb":
        from symid.baselines.gb import GbSimilarity

        return GbSimilarity(model, sd, **opts)
    from symid.nlls.similarity import IpoptSimilarity

    return IpoptSimilarity(model, sd, **opts)
