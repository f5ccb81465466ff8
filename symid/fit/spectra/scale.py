"""Typical parameter values from power spectra: the response level they imply, then dimensional analysis.

Spectra Φyy = H Φuu Hᴴ carry the magnitude of the response but not its phase: with
uncorrelated inputs, Φyyᵢᵢ(ω) = Σⱼ |Hᵢⱼ(ω)|² Φuuⱼⱼ(ω). Reading every input as carrying an
equal share of each output's power, |Hᵢⱼ(ω)| ≈ √(Φyyᵢᵢ(ω) / (m Φuuⱼⱼ(ω))), a response of the
right level over the measured band; :func:`symid.fit.frf.scale.typical_scale` needs no
more (the band centre and the level of |H|). As for time series, the result is an order
of magnitude to draw starts around (:func:`symid.fit.starts.draw_starts`), never a start:
without it, spectra of a model in SI units were started from N(0, 1) draws (a new user's
3-storey building, masses of 2e4 kg and stiffnesses of 3e7 N/m, ended after 181 s with
masses of 1.3 kg and misfit 2.2e5).

There are none (``None``; the starts are then N(0, 1) draws, as before) when the input
spectrum is zero on some channel at every frequency, or the output spectra hold no
power.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from symid.data import FrequencyData
from symid.errors import ModelError

__all__ = ["typical_scale"]


def typical_scale(model: Any, data: Any) -> np.ndarray | None:
    """Typical magnitude of every parameter from spectra (module docstring), or ``None``.

    Parameters
    ----------
    model : SecondOrderModel
    data : SpectralData

    Returns
    -------
    numpy.ndarray or None
        One positive value per parameter, in ``parameter_names`` order.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.spectra.scale import typical_scale
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> spec = si.simulate_spectra(model, [20.0, 40.0, 5e5], np.logspace(1.5, 3, 50), 1.0)   # white force, 158 rad/s
    >>> scale = typical_scale(model, spec)
    >>> bool(np.all(np.abs(np.log10(scale / [20.0, 40.0, 5e5])) < 1))   # each within a factor 10
    True
    """
    from symid.fit.frf.scale import typical_scale as frf_typical_scale

    w = np.asarray(data.w, dtype=float)
    out_power = np.real(np.diagonal(np.asarray(data.Phi_yy), axis1=1, axis2=2))  # (s, p)
    in_power = np.real(np.diagonal(np.asarray(data.Phi_uu), axis1=1, axis2=2))  # (s, m)
    m = in_power.shape[1]
    if not np.all(np.any(in_power > 0, axis=0)) or not np.any(out_power > 0):
        return None
    with np.errstate(divide="ignore", invalid="ignore"):
        level = np.sqrt(np.clip(out_power, 0.0, None)[:, :, None] / (m * in_power[:, None, :]))
    level = np.where(np.isfinite(level), level, 0.0)
    if not np.any(level > 0):
        return None
    try:
        scale = np.asarray(frf_typical_scale(model, FrequencyData(w, level.astype(complex))), dtype=float)
    except (ModelError, ValueError, np.linalg.LinAlgError):
        return None
    if scale.size != model.n_parameters or not np.all(np.isfinite(scale)) or np.any(scale <= 0):
        return None
    return scale
