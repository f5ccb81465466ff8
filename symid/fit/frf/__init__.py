"""Estimation from a frequency response (thesis chapters 3 and 4).

=======  ==============================================================  ==========================
method   what it solves                                                  module
=======  ==============================================================  ==========================
scr      Algorithm 3.1 (state space) / (4-8) with M, V, K ⪰ 0 (second    :mod:`~symid.fit.frf.scr`
         order); the linear case below when it applies
ipopt    nonlinear least squares on the relative FRF misfit              :mod:`~symid.fit.frf.ipopt`
ls       the linear least squares (4-10)/(4-11) (C or B known, square)   :mod:`~symid.fit.frf.ls`
lm       Levenberg–Marquardt on log-parameters, log-H then H criterion    :mod:`~symid.fit.frf.lm`
auto     ``lm`` restarted around the start until the estimate fits       :mod:`~symid.fit.frf.lm`
=======  ==============================================================  ==========================
"""

from __future__ import annotations

from typing import Any

from symid.errors import OptionError
from symid.fit.base import Estimator
from symid.fit.frf.misfit import check_frf
from symid.fit.frf.scale import typical_scale
from symid.fit.options import check_bool, check_known_names

__all__ = ["METHODS", "SHARED_OPTIONS", "prepare", "typical_scale"]

METHODS = ("scr", "ipopt", "ls", "lm", "auto")
SHARED_OPTIONS = ("variance", "time_limit", "callback", "verbose")
"""Options of ``"scr"`` that pass to ``"ls"`` when the linear case runs instead (both take them, alike)."""


def prepare(model: Any, data: Any, method: str, options: dict[str, Any], *,
            noise_floor: float | None = None) -> Estimator:
    """The estimator of ``method`` for a frequency response, its options checked.

    ``"scr"`` on a second-order model whose C or B is known, square and invertible runs
    the exact linear least squares instead (reported as method ``"ls"``, with the reason
    in ``options["chosen_because"]``); ``force_scr=True`` runs SCR anyway, and SCR
    options given without it are refused (they would be ignored), except those both take:
    ``variance``, ``time_limit``, ``callback`` and ``verbose`` (:data:`SHARED_OPTIONS`).
    """
    from symid.fit.frf.ipopt import IpoptFRF
    from symid.fit.frf.lm import AutoFRF, LmFRF
    from symid.fit.frf.ls import LinearFRF, ls_applicable
    from symid.fit.frf.scr import ScrFRF
    from symid.model.secondorder import SecondOrderModel

    check_frf(model, data)
    if method == "ls":
        return LinearFRF.create(model, data, options, noise_floor=noise_floor)
    if method == "ipopt":
        return IpoptFRF.create(model, data, options, noise_floor=noise_floor)
    if method == "lm":
        return LmFRF.create(model, data, options, noise_floor=noise_floor)
    if method == "auto":
        return AutoFRF.create(model, data, options, noise_floor=noise_floor)
    if method != "scr":
        raise OptionError(f"unknown method {method!r} for frequency-response data; choose one of "
                          f"{', '.join(METHODS)}")
    opts = dict(options)
    force = check_bool("force_scr", opts.pop("force_scr", False))
    check_known_names("method 'scr' (frequency response)", opts, (*ScrFRF.option_names(), "force_scr"))
    case = ls_applicable(model) if isinstance(model, SecondOrderModel) else None
    if case is not None and not force:
        shared = {k: opts.pop(k) for k in SHARED_OPTIONS if k in opts}
        if opts:
            raise OptionError(f"options {', '.join(sorted(opts))} are SCR options, but the linear least squares "
                              f"({case} case, thesis (4-10)/(4-11)) applies and runs instead; pass force_scr=True "
                              "to run SCR")
        est = LinearFRF.create(model, data, {"case": case, **shared}, noise_floor=noise_floor)
        est.options["chosen_because"] = f"scr → ls: linear special case ({case})"
        return est
    return ScrFRF.create(model, data, opts, noise_floor=noise_floor)
