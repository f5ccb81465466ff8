"""The solvers ``si.identify`` and ``si.compare`` use for spectral data (thesis ch. 5)."""

from __future__ import annotations

from typing import Any

from symid.errors import ModelError

__all__ = ["SPECTRAL_METHODS", "prepare_spectral"]

SPECTRAL_METHODS = ("scr", "ipopt")


def prepare_spectral(model: Any, data: Any, method: str, options: dict[str, Any]) -> Any:
    """Build the solver of ``method`` for a second-order model and spectra.

    ``"scr"``: Algorithm 5.1 (:class:`~symid.formulations.psd_scr.ScrPSD`); ``"ipopt"``:
    nonlinear least squares on (5-13) (:class:`~symid.nlls.psd.IpoptPSD`). Spectra have
    no linear special case: ``"ls"`` is refused.
    """
    if method == "scr":
        from symid.formulations.psd_scr import ScrPSD

        return ScrPSD(model, data, **options)
    if method == "ipopt":
        from symid.nlls.psd import IpoptPSD

        return IpoptPSD(model, data, **options)
    if method == "ls":
        raise ModelError("spectral data have no linear least-squares special case (Φyy = H Φuu Hᴴ is quadratic "
                         "in H); use method='scr' or 'ipopt'")
    raise ModelError(f"unknown method {method!r} for spectral data; choose one of {', '.join(SPECTRAL_METHODS)}")
