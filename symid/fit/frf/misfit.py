"""Frequency-response data: the check against the model, and the misfit every FRF method is ranked by."""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from symid.errors import DataError, ModelError, OptionError
from symid.fit.base import Estimator
from symid.fit.frf.fisher import FrfFisher, residual_noise_model

__all__ = ["RELATIVE_NOTE_DECADES", "FrfEstimator", "NoiseWeighted", "check_frf", "estimated_variance_factor",
           "estimated_variance_inflation", "frf_variance", "frf_weights", "misfit_residuals", "relative_misfit",
           "relative_noise_note", "relative_residuals"]

VARIANCE_OPTION_DOC = """variance : "data", "relative", None or array_like, optional
        Noise weighting of the FRF criterion, Σᵢ Σ_jk |Hᵢ,jk − H(ωᵢ, θ)_jk|² / σ²ᵢ,jk
        (the maximum-likelihood criterion for independent complex Gaussian noise on H,
        as frequency-domain toolboxes such as FDIDENT use): ``"data"`` (default) takes
        σ² from the data's per-line variance (``FrequencyData.variance``, e.g. from
        :func:`symid.estimate_frf`) and weighs every line alike when the data have none;
        ``"relative"`` takes σ ∝ |H| at an unknown level (noise of a few % of each
        value, as a response spanning decades often has: every line then counts, not only
        the largest; the level, as without a variance, is judged from the residual): ``lm``
        and ``auto`` weigh by the model's |H(ωᵢ, θ̂)| at their estimate (iterated, unbiased),
        the other methods by the measured |Hᵢ,jk| (biased by about ε² for noise of ε);
        ``None`` weighs every line alike; an array gives σ², one per frequency (s,) or per
        entry (s, p, m)."""


def check_frf(model: Any, data: Any) -> None:
    """Refuse a response of the wrong size, or too few frequencies for the parameters."""
    s, p, m = np.asarray(data.H).shape
    if (p, m) != (model.n_outputs, model.n_inputs):
        raise DataError(f"data H has {p} output(s) × {m} input(s) per frequency; the model has "
                        f"{model.n_outputs} output(s) × {model.n_inputs} input(s)")
    if not np.any(np.asarray(data.H)):
        raise DataError("the frequency response H is zero at every frequency: there is nothing to fit")
    equations = 2 * s * p * m
    if equations < model.n_parameters:
        need = math.ceil(model.n_parameters / (2 * p * m))
        raise DataError(f"{s} frequencies give {equations} real equations for {model.n_parameters} unknown "
                        f"parameters: at least {need} frequencies are needed")


def frf_weights(data: Any, variance: Any = "data") -> np.ndarray | None:
    """Weights 1/σ² of the noise-weighted FRF criterion, one per entry of H, scaled to mean 1.

    Parameters
    ----------
    data : FrequencyData
    variance : "data", "relative", None or array_like
        ``"data"``: the data's per-line variance when it has one; ``"relative"``: σ² ∝
        |Hᵢ,jk|² (every entry nonzero); ``None``: equal weights; an array: σ² per frequency
        (s,) or per entry (s, p, m), finite and > 0.

    Returns
    -------
    numpy.ndarray of shape (s, p, m), or None
        ``None`` means equal weights (the relative misfit Σ‖Hᵢ − H(ωᵢ, θ)‖² / Σ‖Hᵢ‖²).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.frf.misfit import frf_weights
    >>> frf = si.FrequencyData([1.0, 2.0], np.ones(2), variance=[1e-4, 4e-4])
    >>> frf_weights(frf).ravel()
    array([1.6, 0.4])
    >>> frf_weights(frf, None) is None
    True
    >>> frf_weights(si.FrequencyData([1.0, 2.0], [1.0, 0.5]), "relative").ravel()
    array([0.4, 1.6])
    """
    H = np.asarray(data.H)
    if isinstance(variance, str) and variance == "relative":
        with np.errstate(divide="ignore", over="ignore"):
            wts = 1.0 / np.abs(H) ** 2
            total = float(np.sum(wts))
        # a zero, or values so small that 1/|H|² or its sum overflows (a new user's 1e-300: NaN misfits, no reason)
        if not np.isfinite(total):
            idx = tuple(int(i) for i in np.unravel_index(int(np.argmin(np.abs(H))), H.shape))
            raise OptionError(f"variance='relative' weighs each value of H by 1/|H|², but entry {idx} (frequency "
                              f"{float(np.asarray(data.w)[idx[0]]):g} rad/s) is {abs(complex(H[idx])):.3g} in "
                              f"magnitude, too small to weigh so; give the noise variances as an array, or "
                              f"variance=None for equal weights")
        return wts / (total / wts.size)
    if isinstance(variance, str):
        if variance != "data":
            raise OptionError(f"variance must be 'data', 'relative', None or an array of noise variances; got "
                              f"{variance!r}")
        given = getattr(data, "variance", None)
        if given is None:
            return None
        var = np.asarray(given, dtype=float)
        source = "the data's variance"
    elif variance is None:
        return None
    else:
        if np.iscomplexobj(variance):
            raise OptionError("variance holds complex numbers; a noise variance is real and > 0")
        try:
            var = np.asarray(variance, dtype=float)
        except (TypeError, ValueError):
            raise OptionError(f"variance must be 'data', 'relative', None or an array of real noise variances; "
                              f"got {type(variance).__name__}") from None
        if var.shape == ():  # one variance for every value
            var = np.broadcast_to(var, H.shape)
        if var.shape == (H.shape[0],):
            var = np.broadcast_to(var[:, None, None], H.shape)
        if var.shape != H.shape:
            raise OptionError(f"variance must be one number, one value per frequency ({H.shape[0]},) or one per "
                              f"entry of H {H.shape}; got shape {var.shape}")
        source = "variance"
    var = var.reshape(H.shape)
    bad = ~np.isfinite(var) | (var <= 0)
    if np.any(bad):
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise OptionError(f"{source} must be finite and > 0 to weigh the fit by it: entry {idx} (frequency "
                          f"{float(np.asarray(data.w)[idx[0]]):g} rad/s) is {float(var[idx])!r}; give a small positive "
                          f"variance for lines measured without noise, or variance=None for equal weights")
    wts = 1.0 / var
    return wts / float(np.mean(wts))


def frf_variance(data: Any, variance: Any = "data") -> np.ndarray | None:
    """The noise variance σ² per entry of H behind :func:`frf_weights` (checked the same way).

    Parameters
    ----------
    data : FrequencyData
    variance : "data", "relative", None or array_like
        As :func:`frf_weights`.

    Returns
    -------
    numpy.ndarray of shape (s, p, m), or None
        ``None`` when the fit weighs every entry alike, or by ``"relative"`` (whose level
        is not known).

    Examples
    --------
    >>> import symid as si
    >>> from symid.fit.frf.misfit import frf_variance
    >>> frf = si.FrequencyData([1.0, 2.0], [1.0, 1.0], variance=[1e-4, 4e-4])
    >>> frf_variance(frf).ravel().tolist()
    [0.0001, 0.0004]
    """
    if frf_weights(data, variance) is None or (isinstance(variance, str) and variance == "relative"):
        return None
    H = np.asarray(data.H)
    var = np.asarray(data.variance if isinstance(variance, str) else variance, dtype=float)
    if var.shape == ():
        var = np.broadcast_to(var, H.shape)
    if var.shape == (H.shape[0],):
        var = np.broadcast_to(var[:, None, None], H.shape)
    return np.array(var, dtype=float).reshape(H.shape)


def variance_label(variance: Any, weights: np.ndarray | None) -> str | None:
    """How a fit is weighted, for its ``options``: ``"data"``, ``"relative"``, ``"given"``, ``None`` (equal
    weights asked for) or ``"data (none: equal weights)"``."""
    if weights is None:
        return None if variance is None else "data (none: equal weights)"
    return variance if isinstance(variance, str) else "given"


def _model_response(model: Any, data: Any, theta: Any) -> np.ndarray | None:
    try:
        Hm = model.frequency_response(theta, data.w)
    except (ModelError, np.linalg.LinAlgError, FloatingPointError):
        return None
    return Hm if np.all(np.isfinite(Hm)) else None


def _relative(H: np.ndarray, Hm: np.ndarray, weights: np.ndarray | None = None) -> float:
    """Σ w|H − Hm|² / Σ w|H|² (w = 1 without weights), on H / max|H| so that neither sum under- or overflows."""
    scale = float(np.max(np.abs(H)))
    if scale == 0.0 or not np.isfinite(scale):
        return 0.0 if not np.any(Hm) else float("inf")
    wts = 1.0 if weights is None else weights
    den = float(np.sum(wts * np.abs(H / scale) ** 2))
    return float(np.sum(wts * np.abs((H - Hm) / scale) ** 2) / den)


def relative_misfit(model: Any, data: Any, theta: Any, weights: np.ndarray | None = None) -> float:
    """Relative squared misfit Σ‖Hᵢ − H(ωᵢ, θ)‖²_F / Σ‖Hᵢ‖²_F of a frequency response.

    With ``weights`` (:func:`frf_weights`), Σ w|Hᵢ − H(ωᵢ, θ)|² / Σ w|Hᵢ|² entry by entry.
    Returns ``inf`` when the model cannot be evaluated at θ (singular M, a pole on
    the imaginary axis, non-finite values).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.frf.misfit import relative_misfit
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, [2.0, 0.5, 3.0], np.linspace(0.5, 2.0, 5))
    >>> relative_misfit(model, frf, [2.0, 0.5, 3.0])
    0.0
    """
    Hm = _model_response(model, data, theta)
    return float("inf") if Hm is None else _relative(np.asarray(data.H), Hm, weights)


def relative_residuals(model: Any, data: Any, theta: Any) -> np.ndarray | None:
    """(Hᵢ − H(ωᵢ, θ)) / |Hᵢ| entry by entry (0 where Hᵢ = 0), frequency first; ``None`` if not evaluable."""
    H = np.asarray(data.H)
    Hm = _model_response(model, data, theta)
    if Hm is None:
        return None
    mag = np.abs(H)
    return np.where(mag > 0, (H - Hm) / np.where(mag > 0, mag, 1.0), 0.0)


def misfit_residuals(model: Any, data: Any, theta: Any, weights: np.ndarray | None = None) -> np.ndarray | None:
    """The residuals whose sum of squares is :func:`relative_misfit`: √w (Hᵢ − H(ωᵢ, θ)) / ‖√w H‖ entry by
    entry (w = 1 without ``weights``), frequency first; ``None`` if not evaluable. The success rule's
    whiteness test takes these (:func:`symid.fit.success.whiteness`)."""
    H = np.asarray(data.H)
    Hm = _model_response(model, data, theta)
    if Hm is None:
        return None
    sw = np.ones(H.shape) if weights is None else np.sqrt(np.asarray(weights, dtype=float))
    nrm = float(np.sqrt(np.sum((sw * np.abs(H)) ** 2))) or 1.0
    return sw * (H - Hm) / nrm


WEAK_SHARE = 1e-6
"""Lines whose share of Σ‖Hᵢ‖² is below this do not move an equally weighted fit: a 100 % error on all of them
changes the relative misfit by less than a hundredth of what 1 % noise leaves (1e-4)."""
WEAK_MISS = 0.1
"""A relative error above this at a line is a miss (10 %: ten times 1 % noise)."""


def weak_lines_missed(model: Any, data: Any, theta: Any, weights: np.ndarray | None = None) -> str | None:
    """A warning when an equally weighted fit misses a band of weak lines it cannot see, else None.

    Three or more consecutive lines of one entry of H, each missed by more than
    :data:`WEAK_MISS` of its own level and each carrying less than a 1/s-th part of
    :data:`WEAK_SHARE` of Σ‖Hᵢ‖² (s lines): the equal weights of the misfit let the large lines decide, so a resonance
    where |H| is small (a position sensor on a chain with a rigid-body mode: |H| over 8
    decades) can be missed by a fit the success rule accepts, its misfit below the
    truth's. Found by a new user: a drivetrain's load angle, 1 % noise, its second
    resonance missed by 28–90 % at 258–1000 rad/s, J1 11 times too large, ``success``.
    Noise weights (``variance=``) see every line; with them nothing is said.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.frf.misfit import weak_lines_missed
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, {"m": 1.0, "c": 0.1, "k": 1.0}, np.logspace(-1, 4, 60))
    >>> weak_lines_missed(model, frf, [1.0, 0.1, 1.0]) is None
    True
    >>> weak_lines_missed(model, frf, [1.3, 0.1, 1.0])[:50]  # m 30 % off: H = 1/(m s²) above resonance
    'the fit misses the data by 23% or more at 31 lines'
    """
    if weights is not None:
        return None
    H = np.asarray(data.H)
    Hm = _model_response(model, data, theta)
    if Hm is None or H.shape[0] < 3:
        return None
    level = np.abs(H)
    total = float(np.sum(level**2))
    if not total > 0:
        return None
    with np.errstate(divide="ignore", invalid="ignore"):
        miss = np.where(level > 0, np.abs(H - Hm) / level, 0.0)
    w = np.asarray(data.w, dtype=float)
    worst = None
    faint = level**2 < WEAK_SHARE * total / H.shape[0]  # a line carrying less than its share of WEAK_SHARE
    for idx in np.ndindex(*H.shape[1:]):
        bad = (miss[(slice(None), *idx)] > WEAK_MISS) & faint[(slice(None), *idx)]
        start = None
        for i in range(len(bad) + 1):
            if i < len(bad) and bad[i]:
                start = i if start is None else start
                continue
            if start is not None and i - start >= 3:
                band = slice(start, i)
                share = float(np.sum(level[(band, *idx)] ** 2)) / total
                if worst is None or i - start > worst[1] - worst[0]:
                    worst = (start, i, idx, share)
            start = None
    if worst is None:
        return None
    a, b, idx, share = worst
    r = miss[(slice(a, b), *idx)]
    entry = f" of entry {tuple(int(x) for x in idx)}" if H.shape[1:] != (1, 1) else ""
    return (f"the fit misses the data by {np.min(r):.0%} or more at {b - a} lines ({w[a]:.2g} to {w[b - 1]:.2g} "
            f"rad/s{entry}, up to {np.max(r):.0%}) where |H| is small: with equal weights these lines carry "
            f"{share:.0e} of Σ|H|², so the fit does not see them and its success says nothing about them. If the "
            "noise is proportional to |H| (a relative noise level ε, an H1 estimate), give variance='relative' (or "
            "(ε·|H|)² per line), which weighs every line by its own level")


RELATIVE_NOTE_DECADES = 1.0
"""A fit with equal weights whose residual looks like relative noise gets a note naming ``variance="relative"``
when some entry's |H| spans more than this many decades over the lines (there the weights differ most)."""


def relative_noise_note(model: Any, data: Any, theta: Any) -> dict[str, float] | None:
    """``{"level": %, "decades": d}`` when the residual of an equally weighted fit at θ is likelier relative noise
    (a level per output times |H(ωᵢ, θ)|) than additive noise (one level per output), as the uncertainty's noise
    model decides (:func:`~symid.fit.frf.fisher.residual_noise_model`), and some entry's |H| spans more than
    :data:`RELATIVE_NOTE_DECADES` decades; else None.

    With relative noise the maximum-likelihood fit weighs every line by its own level (``variance="relative"``);
    equal weights let the largest lines decide. Measured on the population benchmark's problems at 1 % relative
    noise (``benchmarks/frf_relative_weights.py``): ``lm`` with ``variance="relative"`` started from the equally
    weighted estimate, against that estimate; with additive noise this note never applies there.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.frf.misfit import relative_noise_note
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, {"m": 1.0, "c": 0.1, "k": 1.0}, np.logspace(-1, 2, 60), noise=0.02, seed=0)
    >>> note = relative_noise_note(model, frf, [1.0, 0.1, 1.0])
    >>> round(note["decades"], 1), bool(1.5 < note["level"] < 2.5)
    (4.9, True)
    """
    H = np.asarray(data.H)
    Hm = _model_response(model, data, theta)
    if Hm is None or not np.all(np.abs(H) > 0) or not np.all(np.abs(Hm) > 0):
        return None
    decades = float(np.max(np.log10(np.max(np.abs(H), axis=0) / np.min(np.abs(H), axis=0))))
    if not decades > RELATIVE_NOTE_DECADES:
        return None
    if residual_noise_model(H, Hm) != "relative":
        return None
    return {"level": 100.0 * float(np.sqrt(np.mean(np.abs(H - Hm) ** 2 / np.abs(Hm) ** 2))), "decades": decades}


RELATIVE_COST_KIND = "mean relative FRF misfit (1/N) Σ |Hᵢ − H(ωᵢ, θ)|² / |Hᵢ|² over the N entries of H"
MODEL_RELATIVE_COST_KIND = ("relative FRF misfit weighted by the model at the estimate Σ wᵢ|Hᵢ − H(ωᵢ, θ)|² / "
                            "Σ wᵢ|Hᵢ|², wᵢ = 1/|H(ωᵢ, θ̂)|²")
"""The misfit's name with ``variance="relative"`` once the weights come from the model's response at the estimate
(``lm``, ``auto``: :meth:`NoiseWeighted.reweigh_relative`)."""
"""The misfit's name with ``variance="relative"`` (every entry weighed by 1/|Hᵢ|²)."""
WEIGHTED_COST_KIND = "noise-weighted relative FRF misfit Σ wᵢ|Hᵢ − H(ωᵢ, θ)|² / Σ wᵢ|Hᵢ|², wᵢ = 1/σᵢ²"
"""The misfit's name when the noise variance of every entry weighs it."""


class FrfEstimator(Estimator, FrfFisher):
    """Base of the frequency-response methods: their data misfit (relative, squared), and its Fisher
    information for the uncertainty of θ̂ (:mod:`symid.fit.frf.fisher`)."""

    cost_kind: ClassVar[str] = "relative FRF misfit Σ‖Hᵢ − H(ωᵢ, θ)‖²_F / Σ‖Hᵢ‖²_F"

    line_weights: np.ndarray | None = None
    """Per-entry weights 1/σ² of a noise-weighted fit (:func:`frf_weights`); ``None``: equal weights."""

    def misfit(self, theta: np.ndarray) -> float:
        """:func:`relative_misfit` of the model at θ (noise-weighted when ``line_weights`` is set)."""
        return relative_misfit(self.model, self.data, theta, self.line_weights)

    def residuals(self, theta: np.ndarray) -> np.ndarray | None:
        """:func:`misfit_residuals` at θ (in the misfit's own weighting)."""
        return misfit_residuals(self.model, self.data, theta, self.line_weights)

    def n_data(self) -> int:
        """2·s·p·m real values."""
        return 2 * int(np.asarray(self.data.H).size)

    def black_box(self) -> tuple[float, int] | None:
        """A vector fit of the data with as many poles N as the model has states and a constant term
        (:func:`symid.signal.vectfit.vector_fit`, each line's error relative to its level): its
        :meth:`misfit` and its N + (N + 1)·p·m real parameters; built once per estimator (milliseconds
        to a second at 16 states). ``None`` when it cannot be built (too few frequencies, say)."""
        if not hasattr(self, "_black_box"):
            self._black_box = _vector_fit_floor(self.model, self.data, self.line_weights)
        return self._black_box


def _vector_fit_floor(model: Any, data: Any, weights: np.ndarray | None) -> tuple[float, int] | None:
    from symid.signal.vectfit import vector_fit

    H = np.asarray(data.H)
    n = int(model.n_states)
    try:
        bb = vector_fit(np.asarray(data.w, dtype=float), H, n, weight="relative")
        Hb = np.asarray(bb.response(np.asarray(data.w, dtype=float))).reshape(H.shape)
    except (DataError, OptionError, ModelError, np.linalg.LinAlgError, ValueError, FloatingPointError):
        return None
    cost = _relative(H, Hb, weights)
    if not math.isfinite(cost):
        return None
    return cost, n + (n + 1) * H.shape[1] * H.shape[2]


def estimated_variance_factor(dof: float, n_data: int, n_parameters: int) -> float | None:
    """How much higher the noise floor of a fit weighted by 1/σ̂² is, σ̂² estimated with ``dof`` real degrees of
    freedom ν, than the Σ w σ̂² / Σ w |H|² of a known σ²; None for ν ≤ 2 (no finite mean: no floor).

    Each weighted term |r|²/σ̂² is then an F(2, ν) ratio, not a χ²₂/2 one: its mean is ν/(ν − 2) and its spread
    √(ν/(ν − 4)) times larger. The factor is the mean times the widening of the χ² 99.9 % bound's excess b
    (:func:`symid.fit.success.fit_test` applies that bound to the floor): (1 + b √(ν/(ν − 4))) / (1 + b), with
    a spread of 3 for ν ≤ 4, where the F ratio has no finite variance. Measured (a new user's 4-storey frame,
    periodic multisine): 8 periods (ν = 14) left a misfit 1.229 times the unadjusted floor at the estimate,
    4 periods 1.516; the mean alone is 1.167 and 1.5.

    Examples
    --------
    >>> from symid.fit.frf.misfit import estimated_variance_factor
    >>> round(estimated_variance_factor(14, 1538, 12), 3), estimated_variance_factor(2, 100, 3)
    (1.187, None)
    """
    if dof <= 2:
        return None
    from symid.fit.success import chi2_bound

    b = chi2_bound(n_data, n_parameters) - 1.0
    spread = float(np.sqrt(dof / (dof - 4))) if dof > 4 else 3.0
    return dof / (dof - 2) * (1 + b * spread) / (1 + b)


def estimated_variance_inflation(dof: float) -> float:
    """How much larger the covariance of a fit weighted by 1/σ̂² is, σ̂² estimated with ``dof`` real degrees of
    freedom ν, than the inverse Fisher information that takes σ̂² as the exact variance: ν/(ν − 4); ``inf`` for
    ν ≤ 4, where the covariance is not finite.

    Two factors: the information Σ J²/σ̂² is on average ν/(ν − 2) times Σ J²/σ² (the mean of ν/χ²_ν), and
    weights from a variance estimated over M = ν/2 + 1 periods lose efficiency against the true ones by
    (M − 2)/(M − 3) = (ν − 2)/(ν − 4) (the sample maximum likelihood estimator: Schoukens, Pintelon,
    Vandersteen and Guillaume, *Automatica* 33(6), 1997; Pintelon & Schoukens, *System Identification: A
    Frequency Domain Approach*, 2nd ed., §10.3). Both factors hold when many lines carry the information;
    when a few do (a lightly damped mode's), the weights' noise does not average out, and the factor is
    conservative. Measured (``benchmarks/frf_estimated_variance.py``, 100 records each, a periodic
    multisine, 1 % output noise): on a 3-mass chain (6 parameters) the 95 % intervals held the truth in
    73–83 % of the records per parameter at 4 periods taking σ̂² as exact and 94–99 % with this factor
    (84–94 % and 88–99 % at 8 periods); on two masses (6 parameters) 78–91 % and 95–99 % at 4 periods. On one
    lightly damped mass (``tests/test_frf_weighting.py``) the estimates' spread was 0.67–0.77 of the reported
    standard error at 4 periods: conservative there.

    Examples
    --------
    >>> from symid.fit.frf.misfit import estimated_variance_inflation
    >>> estimated_variance_inflation(6), estimated_variance_inflation(14), estimated_variance_inflation(4)
    (3.0, 1.4, inf)
    """
    return float(dof / (dof - 4)) if dof > 4 else float("inf")


class NoiseWeighted:
    """Mixin of an FRF method with a ``variance=`` option: the weights, the variance, and the noise floor it
    gives, as :class:`~symid.fit.frf.ipopt.IpoptFRF` has them.

    :meth:`set_variance` sets ``line_weights`` (so that ``misfit`` and the success rule are the
    weighted ones) and ``line_variance`` (the given noise of the uncertainty); ``noise_floor``
    is then, unless given, Σ w σ² / Σ w |H|², the weighted relative misfit the declared noise
    alone leaves at the truth, so the fit is judged against that noise.
    Put it before :class:`FrfEstimator` among the bases.
    """

    data: Any
    line_weights: np.ndarray | None = None
    line_variance: np.ndarray | None = None
    estimated_variance_dof: float | None = None
    _noise_floor: float | None = None
    _variance_floor: float | None = None

    def set_variance(self, variance: Any) -> str | None:
        """Weights and variance from the ``variance`` option; returns its label for ``options``."""
        self.line_weights = frf_weights(self.data, variance)
        self.line_variance = frf_variance(self.data, variance) if self.line_weights is not None else None
        # the misfit is then the weighted one, and named so (a new user read the mean relative misfit of
        # variance="relative" under the equally weighted misfit's name)
        self.cost_kind = (type(self).cost_kind if self.line_weights is None else  # type: ignore[misc]
                          RELATIVE_COST_KIND if isinstance(variance, str) and variance == "relative" else
                          WEIGHTED_COST_KIND)
        self._variance_floor = None
        self.estimated_variance_dof = None
        if self.line_variance is not None:
            w = self.line_weights
            self._variance_floor = float(np.sum(w * self.line_variance) /
                                         np.sum(w * np.abs(np.asarray(self.data.H)) ** 2))
            dof = getattr(self.data, "variance_dof", None)
            if isinstance(variance, str) and dof is not None:  # the data's own variance, estimated
                self.estimated_variance_dof = float(dof)
                factor = estimated_variance_factor(dof, 2 * int(np.asarray(self.data.H).size),
                                                   int(self.model.n_parameters))
                self._variance_floor = None if factor is None else self._variance_floor * factor
        return variance_label(variance, self.line_weights)

    def reweigh_relative(self, theta: Any) -> None:
        """With ``variance="relative"``: weigh each entry by 1/|H(ωᵢ, θ)|², the model's response at θ, in place of
        the measured |Hᵢ| (scaled to mean 1; the label and the unknown level stay). Weights from the measured values
        correlate with their noise and bias the fit (symid.fit.frf.lm: a 2-mass chain at 10 % relative noise, the
        masses 0.9 % high, 0.8 standard errors, intervals holding the truth 86–90 % of the time); weights from the
        model at the estimate, iterated, do not. Does nothing for other weightings or where H(θ) has a zero."""
        if self.options.get("variance") != "relative":
            return
        Hm = _model_response(self.model, self.data, theta)
        if Hm is None or not np.all(np.abs(Hm) > 0):
            return
        wts = 1.0 / np.abs(Hm) ** 2
        self.line_weights = wts / float(np.mean(wts))
        self.cost_kind = MODEL_RELATIVE_COST_KIND  # type: ignore[misc]

    @property
    def variance_shape(self) -> np.ndarray | None:
        """σ² per entry of H up to one factor, for methods that weigh their own equations by the noise (SCR, the
        linear least squares): the variance when it is known, 1/w with ``variance="relative"``, else None."""
        if self.line_variance is not None:
            return self.line_variance
        return None if self.line_weights is None else 1.0 / self.line_weights

    @property
    def noise_floor(self) -> float | None:
        """The given ``noise_floor``; else, with a variance, the relative misfit that noise leaves at the truth."""
        return self._noise_floor if self._noise_floor is not None else self._variance_floor

    @noise_floor.setter
    def noise_floor(self, value: float | None) -> None:
        self._noise_floor = value
