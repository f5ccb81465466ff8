"""Estimation from measured time series: directly on the samples, or through a black box.

=================  ==========  =====================================================================
data               method      what it fits
=================  ==========  =====================================================================
IOData, TimeSeries ``auto``    the default: ``oe`` restarted around the start until the estimate fits
or a list of them              the samples, with one pass from the model fitted to an N4SID black box's
                               response on one IOData (:mod:`~symid.fit.timeseries.auto`,
                               :mod:`~symid.fit.timeseries.bbstart`)
IOData, TimeSeries ``oe``      output error: the model simulated exactly on the sample times from
or a list of them              its initial state, against the measured samples
                               (:mod:`~symid.fit.timeseries.oe`, CasADi/IPOPT)
one IOData         ``scr``,    the black box of N4SID + exact ``d2c`` (thesis Algorithms 6.1, 7.1;
                   ``als``,    :mod:`symid.fit.similarity`): these fit the black box, not the
                   ``gb``,     samples; their ``cost``, ``success`` and uncertainty are judged on
                   ``ipopt``,  the samples all the same (:mod:`~symid.fit.timeseries.blackbox`),
                   ``ls``      the black-box misfit is in ``message``
IOData, TimeSeries ``svf``     least squares on state-variable-filtered derivatives, for models whose
or a list of them              states are all measured (:mod:`~symid.fit.timeseries.svf`); judged on
                               the samples like the N4SID route
IOData, TimeSeries ``srivc``   simplified refined instrumental variables: the input-output equation
or a list of them              D(s, θ) y = N(s, θ) u prefiltered by the model's own 1/D(s, θ̂),
                               iterated, for models whose transfer-function coefficients are affine
                               in θ (:mod:`~symid.fit.timeseries.srivc`); judged on the samples
=================  ==========  =====================================================================

``oe`` takes non-uniform sample times, several experiments, free responses (u ≡ 0) and
inputs that are not persistently exciting, none of which the N4SID route can use.
"""

from __future__ import annotations

from typing import Any

from symid.data import IOData
from symid.errors import DataError, OptionError
from symid.fit.base import Estimator
from symid.fit.timeseries.scale import typical_scale

__all__ = ["BLACK_BOX_METHODS", "METHODS", "prepare", "typical_scale"]

BLACK_BOX_METHODS = ("scr", "als", "gb", "ipopt", "ls")
METHODS = ("auto", "oe", "svf", "srivc", *BLACK_BOX_METHODS)


def prepare(model: Any, data: Any, method: str, options: dict[str, Any], *,
            noise_floor: float | None = None) -> Estimator:
    """The estimator of ``method`` for time-series data (see the module table)."""
    if method not in METHODS:
        from symid.fit.registry import all_methods

        what = (f"method {method!r} does not take time-series data (it is another data kind's)"
                if method in all_methods() else f"unknown method {method!r} for time-series data")
        raise OptionError(f"{what}; choose one of {', '.join(METHODS)}")
    if method == "oe":
        from symid.fit.timeseries.oe import OutputError

        return OutputError.create(model, data, options, noise_floor=noise_floor)
    if method == "auto":
        from symid.fit.timeseries.auto import AutoOutputError

        return AutoOutputError.create(model, data, options, noise_floor=noise_floor)
    if method == "svf":
        from symid.fit.timeseries.svf import StateVariableFilter

        return StateVariableFilter.create(model, data, options, noise_floor=noise_floor)
    if method == "srivc":
        from symid.fit.timeseries.srivc import SimplifiedRIVC

        return SimplifiedRIVC.create(model, data, options, noise_floor=noise_floor)
    if not isinstance(data, IOData):
        raise DataError(f"method {method!r} goes through N4SID, which needs one uniformly sampled record (IOData); "
                        "for several records or non-uniform sample times use method='oe'")
    from symid.fit.similarity import prepare as similarity_prepare
    from symid.fit.timeseries.blackbox import ThroughBlackBox
    from symid.fit.timeseries.oe import OutputError

    try:
        inner = similarity_prepare(model, data, method, options, noise_floor=noise_floor)
    except DataError as exc:
        if "band=(0, w_high)" in str(exc):  # d2c's advice, an option of si.d2c that identify() does not take
            raise DataError(f"{exc}. Through si.identify: method='auto' (the default) or 'oe' fits the samples and "
                            f"needs no black box; or build the black box yourself (si.n4sid, then si.d2c(..., "
                            f"band=...)) and identify from it") from None
        if "the order is too high" in str(exc):  # N4SID at the model's order; the model itself may be non-minimal
            raise DataError(f"{exc}. Method {method!r} fits an N4SID black box of the model's order "
                            f"({model.n_states} states), which the samples can only determine if the model's "
                            f"realisation is minimal (a free rigid-body mode measured in velocity, for one, leaves "
                            f"its position unseen); method='auto' (the default) or 'oe' fits the samples directly "
                            f"and needs no such order") from None
        if "persistently exciting" not in str(exc):
            raise
        raise DataError(f"{exc}. Method {method!r} goes through N4SID, which needs such an input; method='oe' "
                        "fits the samples directly and does not (a single dose or step will do)") from None
    samples = OutputError(model, data)
    samples.noise_floor = noise_floor
    return ThroughBlackBox(inner, samples)
