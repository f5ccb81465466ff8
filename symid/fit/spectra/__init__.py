"""Estimation from output and input power spectra (thesis chapter 5).

=======  ==============================================================  =============================
method   what it solves                                                  module
=======  ==============================================================  =============================
scr      Algorithm 5.1 with M, V, K ⪰ 0 (full set of known sensors)      :mod:`~symid.fit.spectra.scr`
ipopt    nonlinear least squares on (5-13)                               :mod:`~symid.fit.spectra.ipopt`
auto     IPOPT with restarts around the typical values, then SCR         :mod:`~symid.fit.spectra.auto`
=======  ==============================================================  =============================

Spectra have no linear least-squares special case (Φyy = H Φuu Hᴴ is quadratic in H).
"""

from __future__ import annotations

from typing import Any

from symid.errors import ModelError, OptionError
from symid.fit.base import Estimator
from symid.fit.spectra.scale import typical_scale

__all__ = ["MANY_LINES", "METHODS", "prepare", "typical_scale"]

METHODS = ("scr", "ipopt", "auto")

MANY_LINES = 2000
"""Spectra of more lines than this are a ``DataWarning`` for IPOPT and ``auto``: CasADi's graph holds every line, and a
new user's default Welch estimate of 8190 lines (two outputs, 30 minutes at 100 Hz) ran one IPOPT iteration in its
300 s budget."""


def prepare(model: Any, data: Any, method: str, options: dict[str, Any], *,
            noise_floor: float | None = None) -> Estimator:
    """The estimator of ``method`` for a second-order model and spectra, its options checked."""
    if method == "scr":
        from symid.fit.spectra.scr import ScrPSD

        return ScrPSD.create(model, data, options, noise_floor=noise_floor)
    if method in ("ipopt", "auto") and data.n_frequencies > MANY_LINES:
        import warnings

        from symid.errors import DataWarning

        warnings.warn(f"the spectra have {data.n_frequencies} lines: IPOPT's graph holds every one, and each "
                      f"iteration evaluates them all (minutes per start); keep the lines around the modes: "
                      f"si.estimate_spectra(..., band=(w_low, w_high), n_frequencies=500) (each line keeps its "
                      f"averages)", DataWarning, stacklevel=3)
    if method == "ipopt":
        from symid.fit.spectra.ipopt import IpoptPSD

        return IpoptPSD.create(model, data, options, noise_floor=noise_floor)
    if method == "auto":
        from symid.fit.spectra.auto import AutoPSD

        return AutoPSD.create(model, data, options, noise_floor=noise_floor)
    if method == "ls":
        raise ModelError("spectral data have no linear least-squares special case (Φyy = H Φuu Hᴴ is quadratic "
                         "in H); use method='scr' or 'ipopt'")
    raise OptionError(f"unknown method {method!r} for spectral data; choose one of {', '.join(METHODS)}")
