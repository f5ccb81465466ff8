"""The scale output spectra cannot give: what a fit from spectra says of it.

Output spectra determine the response only through Φyy = H Φuu Hᴴ: a model whose response is
a times another's fits the same Φyy with Φuu / a². When some change of the parameters scales
H by a common factor at every frequency — a mechanical model's masses, dampers and springs
together, with B and C fixed — the estimate's scale is therefore the Φuu given, not the
data's: a new user's footbridge (ambient forces, three accelerometers) fitted with a force
intensity 4 times too large came back with every parameter 2.08 times too large, with
``success`` and intervals that missed the truth; with the spectra per rad/s instead of per
Hz, 2.6 times (√(2π)). ``si.identifiability`` analyses the input–output map, where that
direction is fixed by the input, so it said "global". A known value (a weighed mass)
removes the direction; the note is then not given (and a Φuu off by a factor makes the fit
fail instead).

The direction is found at the estimate from the response's exact sensitivities: the least
squares v with Σₖ vₖ ∂H/∂θₖ ≈ H over every line, entry and frequency; when it reproduces H to
:data:`SCALE_RESIDUAL`, H(θ̂ + εv) = (1 + ε) H(θ̂) to first order and the note names the
parameters it moves.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from symid.fit.sensitivity import frf_sensitivity

__all__ = ["SCALE_RESIDUAL", "output_only_scale"]

SCALE_RESIDUAL = 1e-6
"""A change of θ that reproduces H to this relative residual scales the response: the spectra cannot tell it."""


def output_only_scale(model: Any, data: Any, theta: Any) -> dict[str, Any] | None:
    """``{"text", "direction"}`` when a change of θ scales the model's response by a common factor at θ (module
    notes), else None. ``direction`` holds each moved parameter's relative change rₖ per unit relative change of
    the response (−1 for a mass, damper or spring: θₖ × a^(−rₖ) when H × 1/a).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.spectra.outputonly import output_only_scale
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> psd = si.simulate_spectra(model, [2.0, 0.5, 300.0], np.linspace(5.0, 20.0, 30), Phi_uu=1.0)
    >>> output_only_scale(model, psd, [2.0, 0.5, 300.0])["direction"]
    {'m': -1.0, 'c': -1.0, 'k': -1.0}
    >>> output_only_scale(model.with_known({"m": 2.0}), psd, [0.5, 300.0]) is None
    True
    """
    theta = np.asarray(theta, dtype=float)
    try:
        Hm, dH = frf_sensitivity(model, theta, np.asarray(data.w, dtype=float))
    except Exception:  # an estimate where the model cannot be evaluated: nothing to say
        return None
    A = dH.reshape(-1, theta.size)
    h = np.asarray(Hm).reshape(-1)
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(h))) or not np.any(h):
        return None
    rows = np.concatenate([A.real, A.imag])
    target = np.concatenate([h.real, h.imag])
    v, *_ = np.linalg.lstsq(rows, target, rcond=None)
    if np.linalg.norm(rows @ v - target) > SCALE_RESIDUAL * np.linalg.norm(target):
        return None
    with np.errstate(divide="ignore", invalid="ignore"):
        relative = np.where(theta != 0, v / theta, 0.0)
    moved = np.abs(relative) > 1e-6
    if not moved.any():
        return None
    names = list(model.parameter_names)
    direction = {n: round(float(r), 6) for n, r, keep in zip(names, relative, moved, strict=True) if keep}
    if moved.all() and np.allclose(relative, -1.0, rtol=1e-3):
        which = "every parameter a times as large (the response 1/a times)"
    else:
        moves = ", ".join(f"{n} × a^{-r:.3g}" for n, r in direction.items())
        which = f"the response 1/a times as large ({moves})"
    text = (f"from output spectra the response is known only through Φyy = H Φuu Hᴴ: a Φuu a² times as large fits "
            f"these spectra as well with {which}, so the estimate's scale is that of the input spectrum given "
            f"(check its level and units: two-sided, per Hz), not the data's, and the intervals do not include "
            f"it; a known value (a weighed mass: model.with_known) fixes it")
    return {"text": text, "direction": direction}
