"""Is the response of reversed polarity? A failed fit tried again with an input or output negated.

A sensor mounted the other way, a current measured backwards or a force cell's sign
convention flips an input or an output: the measured response is the model's times −1 in
those entries. A model whose parameters are physical (positive masses, stiffnesses,
gains) cannot change the sign of its quasi-static response, so no start fits such data,
and the advice of a failed fit ("more starts", "check the units") sends the user the
wrong way (two new users: a frame with one accelerometer flipped, a servo with its
current reversed). The correlation of the failed estimate's response with the data does
not show it reliably (the fit half-adapts: +0.71 for the flipped entry of the frame), so
the test is the fit itself: after a failed fit, the frequency-response ``auto`` is run,
from the user's start (else ``scale=`` or the typical values the data imply) and then
from the failed estimate, on the data with the whole
response negated and, for several outputs or inputs, with each output's row or input's
column negated; a flip whose fit succeeds is reported (``options["polarity"]`` and a NEXT
line in the summary) when the same try on the data as they are does not. A model with
parameters of either sign can negate its response itself and is not tried (the thesis's
belt drive, IPOPT from θ = 0 failed, fitted its response negated). Each try has
``TRY_SECONDS`` and ``RESTARTS``, all of them ``TOTAL_SECONDS``; at most ``1 + p + m``
flips, each from up to two points, and one control on the data as they are.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from symid.data import FrequencyData
from symid.errors import SymidError

__all__ = ["BLACK_BOX_FLOOR", "RESTARTS", "TOTAL_SECONDS", "TRY_SECONDS", "polarity_flip"]

TRY_SECONDS = 10.0
"""The budget of each try (a failed fit already spent its own)."""
TOTAL_SECONDS = 40.0
"""The budget of all tries."""
RESTARTS = 4
"""Restarts of each try (a flip that fits does so from the point tried or soon after)."""
BLACK_BOX_FLOOR = 1e-2
"""The misfit below which a try fits the response of a records' black box (:func:`symid.identify` on samples):
that response is another model's of the same order, so the success rule's black-box test refuses any fit of it
(a vector fit is exact); the flip that is right fits it within 10 % rms (2.5e-8 on a two-mass chain with one
accelerometer reversed, the data as they are 1)."""


def _flips(p: int, m: int) -> list[tuple[str, np.ndarray]]:
    """The sign patterns tried: the whole response, then each output row and each input column (several of them)."""
    out = [("the whole response (every input or every output)", -np.ones((p, m)))]
    if p > 1:
        for i in range(p):
            sign = np.ones((p, m))
            sign[i, :] = -1
            out.append((f"output {i}", sign))
    if m > 1:
        for j in range(m):
            sign = np.ones((p, m))
            sign[:, j] = -1
            out.append((f"input {j}", sign))
    return out


def polarity_flip(model: Any, data: FrequencyData, theta: np.ndarray, *, scale: Any = None, bounds: Any = None,
                  noise_floor: float | None = None, start: np.ndarray | None = None,
                  misfit_below: float | None = None) -> dict[str, Any] | None:
    """The first sign flip of ``data`` that the model fits (module notes), or None; None at once for a model with a
    parameter not declared positive.

    ``misfit_below``: a try fits when its misfit is below this, instead of by the success rule
    (for data that are a black box's response: :data:`BLACK_BOX_FLOOR`).

    Returns
    -------
    dict or None
        ``{"flip": what was negated, "misfit": the fit's misfit, "theta": its estimate}``.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.frf.polarity import polarity_flip
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, [2.0, 0.5, 30.0], np.logspace(0, 1.5, 40))
    >>> flipped = si.FrequencyData(frf.w, -np.asarray(frf.H))      # a sensor mounted the other way
    >>> polarity_flip(model, flipped, np.array([1.0, 1.0, 10.0]))["flip"]
    'the whole response (every input or every output)'
    """
    import time

    from symid.fit.frf.lm import AutoFRF

    if not np.all(np.asarray(model.positive, dtype=bool)):
        return None  # parameters of either sign can negate the response themselves: a flip that fits says nothing
    t0 = time.perf_counter()
    H = np.asarray(data.H)
    _, p, m = H.shape
    variance = getattr(data, "variance", None)

    # from the user's start first (a failed estimate can have a mass collapsed to 0: a new user's frame with its
    # floor-2 accelerometer flipped fitted from the start in 0.5 s, from the failed estimate not in 2.5 s), or
    # without one from the typical values the data imply (|H| is the same flipped or not; a new user's servo, its
    # failed estimate at masses of 1e-10, was not found from there), then from the failed estimate
    first = start
    if first is None:
        from symid.fit.frf.scale import typical_scale

        try:
            first = typical_scale(model, data) if scale is None else np.broadcast_to(
                np.asarray(scale, dtype=float), (model.n_parameters,))
        except (SymidError, ValueError, TypeError, np.linalg.LinAlgError):
            first = None
    points = [np.asarray(theta, dtype=float)] if first is None else [np.asarray(first, dtype=float),
                                                                   np.asarray(theta, dtype=float)]

    def attempt(sign: np.ndarray, at: np.ndarray) -> Any:
        """The try on the data times ``sign`` (entry by entry) from ``at``: its outcome, or None when it could not
        run."""
        left = TOTAL_SECONDS - (time.perf_counter() - t0)
        if left <= 0:
            return None
        flipped = FrequencyData(data.w, H * sign[None], variance=variance)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                est = AutoFRF(model, flipped, scale=scale, bounds=bounds, time_limit=min(TRY_SECONDS, left),
                              restarts=RESTARTS)
                est.noise_floor = noise_floor
                return est.run(at)
        except (SymidError, np.linalg.LinAlgError, ValueError):
            return None

    def fits(out: Any) -> bool:
        return out is not None and (out.success if misfit_below is None else out.cost <= misfit_below)

    for what, sign in _flips(p, m):
        for at in points:
            out = attempt(sign, at)
            if fits(out):
                break
        if fits(out):
            # the same try on the data as they are must fail, or the flip says nothing (it only ran longer)
            control = attempt(np.ones((p, m)), at)
            if fits(control):
                return None
            return {"flip": what, "misfit": float(out.cost), "theta": np.asarray(out.theta, dtype=float).tolist()}
    return None
