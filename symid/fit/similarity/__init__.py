"""Estimation from a black box or input/output records by a similarity transform (thesis chapters 6, 7).

Input/output records first become a continuous-time black box of the model's order
(N4SID + exact zero-order-hold ``d2c``, Algorithms 6.1 and 7.1, steps 1–2;
:func:`~symid.fit.similarity.data.similarity_data`).

=================  ==========  =====================================================================
model              method      solver
=================  ==========  =====================================================================
StateSpaceModel    ``scr``     (6-13)/(6-14), Algorithm 6.1 (:mod:`~symid.fit.similarity.scr`)
StateSpaceModel    ``als``     appendix C-1, (C-2)–(C-8) (:mod:`~symid.fit.similarity.als`)
StateSpaceModel    ``gb``      appendix C-2, (C-12)–(C-18) (:mod:`~symid.fit.similarity.gb`)
StateSpaceModel    ``ipopt``   (6-9) with CasADi/IPOPT (:mod:`~symid.fit.similarity.ipopt`)
SecondOrderModel   ``scr``     §7-5-2 linear case when it applies, else (7-10), Algorithm 7.1
SecondOrderModel   ``ls``      §7-5-2 (full set of sensors or actuators)
SecondOrderModel   ``ipopt``   nonlinear least squares on the black box's frequency response
=================  ==========  =====================================================================

Every method is ranked by the same basis-free misfit
(:meth:`~symid.fit.similarity.data.SimilarityData.misfit`). The options ``horizon``
(N4SID), ``allow_unstable`` and ``balance`` configure the black box and are taken by
every method. Every method also takes ``time_limit`` (seconds per start), ``callback``
and ``verbose`` (per-iteration progress: a :class:`symid.engine.scr.ScrProgress` for
SCR, ALS, GB and ``ls``, a :class:`symid.engine.ipopt.IpoptIteration` for IPOPT); when
``"scr"`` runs the linear case instead, these three pass to it.
"""

from __future__ import annotations

from typing import Any

from symid.errors import ModelError, OptionError
from symid.fit.base import Estimator
from symid.fit.options import check_bool, check_known_names
from symid.fit.similarity.data import similarity_data
from symid.model.secondorder import SecondOrderModel

__all__ = ["DATA_OPTIONS", "METHODS", "PROGRESS_OPTIONS", "prepare"]

METHODS = ("scr", "als", "gb", "ipopt", "ls")
DATA_OPTIONS = ("horizon", "allow_unstable", "balance")
PROGRESS_OPTIONS = ("time_limit", "callback", "verbose")


def _estimator_class(model: Any, method: str) -> type[Estimator]:
    if isinstance(model, SecondOrderModel):
        from symid.fit.similarity.ipopt import IpoptSimilarityFRF
        from symid.fit.similarity.second_order import LinearSimilarity2nd, ScrSimilarity2nd

        if method in ("als", "gb"):
            raise ModelError(f"method {method!r} (thesis appendix C) needs a StateSpaceModel, whose matrices are "
                             "affine in θ; for a SecondOrderModel use 'scr', 'ls' or 'ipopt'")
        return {"ls": LinearSimilarity2nd, "ipopt": IpoptSimilarityFRF, "scr": ScrSimilarity2nd}[method]
    if method == "ls":
        raise ModelError("method 'ls' (the linear special cases of thesis §7-5-2) is for SecondOrderModel; for a "
                         "StateSpaceModel with black-box data use 'scr', 'als', 'gb' or 'ipopt'")
    from symid.fit.similarity.als import AlsSimilarity
    from symid.fit.similarity.gb import GbSimilarity
    from symid.fit.similarity.ipopt import IpoptSimilarity
    from symid.fit.similarity.scr import ScrSimilarity

    return {"scr": ScrSimilarity, "als": AlsSimilarity, "gb": GbSimilarity, "ipopt": IpoptSimilarity}[method]


def prepare(model: Any, data: Any, method: str, options: dict[str, Any], *,
            noise_floor: float | None = None) -> Estimator:
    """The estimator of ``method`` for a model and BlackBox or IOData data (see the module table).

    ``"scr"`` on a second-order model with a full set of known sensors or actuators runs
    the exact linear case of §7-5-2 instead (reported as ``"ls"``); ``force_scr=True``
    runs SCR anyway, and SCR options given without it are refused.
    """
    if method not in METHODS:
        raise OptionError(f"unknown method {method!r} for black-box data; choose one of {', '.join(METHODS)}")
    cls = _estimator_class(model, method)
    opts = dict(options)
    force = check_bool("force_scr", opts.pop("force_scr", False)) if method == "scr" else False
    owner = f"method {method!r} ({cls.__name__})"
    extra = ("force_scr",) if method == "scr" else ()
    check_known_names(owner, opts, (*cls.option_names(), *DATA_OPTIONS, *extra))
    data_opts = {k: opts.pop(k) for k in DATA_OPTIONS if k in opts}
    sd = similarity_data(model, data, **data_opts)
    if isinstance(model, SecondOrderModel) and method == "scr" and not force:
        from symid.fit.similarity.second_order import LinearSimilarity2nd, second_order_case

        case = second_order_case(model)
        if case is not None:
            shared = {k: opts.pop(k) for k in PROGRESS_OPTIONS if k in opts}  # ls takes these too
            if opts:
                raise OptionError(f"options {', '.join(sorted(opts))} are SCR options, but the linear special case "
                                  "of §7-5-2 applies and runs instead; pass force_scr=True to run SCR")
            est = LinearSimilarity2nd.create(model, sd, shared, noise_floor=noise_floor)
            est.options["chosen_because"] = f"scr → ls: linear special case of §7-5-2 ({case})"
            return est
    return cls.create(model, sd, opts, noise_floor=noise_floor, owner=owner)
