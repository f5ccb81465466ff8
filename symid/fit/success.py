"""When an estimate counts as a success: the estimate fits the data.

One rule for every method and data kind, whether the solver finished or was stopped by
its budget (``finished`` reports that beside ``success``). A solver's own verdict (IPOPT's
``Solve_Succeeded``, SCR's "converged") says that its iteration stopped where its
stopping rule is met, not that the model reproduces the measurements: IPOPT stops at
local minima, SCR at a stationary point of its relaxation. So :func:`fit_test` also
compares the estimate's data misfit ``cost`` with what noise alone would leave, in this
order:

1. **exact fit** — ``cost ≤ 1e-10`` (a relative rms residual of 1e-5): the data are
   reproduced to the precision of noise-free data.
2. **given noise floor** φ (``noise_floor=``, the relative misfit that noise alone gives
   at the true parameters, e.g. ε² for relative noise of level ε) — the least-squares
   estimate leaves about φ·(N − l)/N, where N is the number of real data values and l
   the number of parameters; the estimate fits when ``cost ≤ φ · χ²₀.₉₉₉(N − l)/N``
   (exceeded by chance once in a thousand records).
3. **whiteness** (no φ given; frequency-ordered residuals available) — the
   residual left by a correct model is noise, which does not repeat from one frequency
   to the next, while the residual of a wrong estimate (a local minimum) is a smooth
   function of frequency. The estimate fits when the residual is white — the
   self-normalised lag-one autocorrelation of :func:`whiteness`, about N(0, 1) for
   independent noise of any level at each frequency, is ≤ 3 (a correct fit fails this by
   chance about once in 700 records) — and the relative rms residual is at most 10 %
   (``cost ≤ 0.01``). Above that, up to 50 % (``NOISY_CEILING``), measured samples fit
   when their residual is also independent of every input (the residual–input test of
   :func:`symid.fit.validation.validate` at 99.9 %) and one Gauss–Newton step does not
   predict half of the misfit away: a new user's two tanks, levels logged as deviations
   of 1.6 cm rms with 2 mm sensor noise (a 13 % residual), were refused with every
   parameter within 1.2 % and the intervals withheld; a wrong model leaves the inputs'
   imprint in its residual, and a wrong unit or a local minimum a residual that is not
   white (``benchmarks/timeseries_loud_noise.py``: a resonance at 12–45 % noise, the right
   model's fit counts on 40 of 40 records, a first-order model's on 0 of 40). The
   residuals are taken **in the weighting of the misfit** the estimate minimises (for a
   frequency response (Hᵢ − H(ωᵢ, θ))/‖H‖, noise weights included). Dividing each line
   by its own level instead, as this rule once did, tests a criterion the estimate did
   not minimise: with noise proportional to |H| over a few
   decades the least-squares estimate, set by the resonances, leaves at the weak lines a
   relative residual that is a smooth function of frequency, and that rule refused the
   least-squares estimate itself (IPOPT started at the truth) on 14 of the 32 noisy
   problems of ``benchmarks/population.py`` and 136 of the 415 logged estimates whose
   misfit is within a likelihood-ratio bound (χ²₀.₉₉₉(l)/N) of it; in the misfit's
   weighting it refuses none of them.
   When a few resonance lines dominate the misfit, the statistic has little power (a
   sum of few products), so where no black box bounds the misfit (output spectra) a
   whiteness fit is also refused when one Gauss–Newton step from it predicts to remove
   more than half of its misfit (``LOCAL_GAIN_LIMIT``): it is then no minimum of the
   misfit. Found by a new user: a 3-mass chain, all positions measured, output spectra
   with 1 % noise, the truth with one spring 0.2 % off (misfit 38 times the truth's, one
   step predicts 98 % lower) passed as white (−2.3); the least-squares estimate predicts
   1e-15, the truth about 26 %, an SCR estimate of the quarter car 16 %.
   A white verdict also needs a test that could have said otherwise: the statistic is at
   most √(k·nₑ) (:func:`whiteness_reach`; nₑ products carry the sum, k = 2 for complex
   residuals), so where that reach is below ``WHITENESS_POWER`` = 6 (twice the limit)
   the test cannot judge the residual (too few values, or a few large ones, carry it): the
   fit then counts only when the black box below backs it or, with none, when one
   Gauss–Newton step finds it a minimum of the
   misfit (the step above); with neither it is refused. A local minimum passes that step
   too, so the fit text says the test was weak and asks for ``noise_floor=``. For a
   residual of independent noise the reach is about 0.64·√N for N real values and
   1.1·√N for N complex lines, so a time series of about 90 samples or more (a frequency
   response of 30 lines, when noise of one level carries them) is judged by its whiteness
   alone. Found on a single-bolus two-compartment decay, 15 noise-free samples: its
   residuals are carried by a few early samples, the reach is 1.8 to 3.2, and estimates
   up to 100 % off passed as white (k21 doubled: misfit 8.5e-3, statistic 2.5); one
   Gauss–Newton step from them predicts 98 % to 100 % lower. On the 1 % noisy frequency
   responses of ``benchmarks/population.py`` the reach is below 6 for 140 of the logged
   estimates (a few resonance lines carry the misfit), and every one has a black box: no
   verdict of ``benchmarks/success_rule.py`` changed.
4. Otherwise (a black box as data, no floor given): only an exact fit counts.

A fit that is not exact and that rule 2 or 3 accepted is refused when **a black box of
the model's order fits the data better than noise explains** (``black_box=``; for a
frequency response, a vector fit with as many poles as the model has states, Gustavsen
& Semlyen 1999). The black box, with b parameters, leaves about φ·(N − b)/N of noise of
level φ, against a correct estimate's φ·(N − l)/N, so a correct fit is within a factor
(N − l)/(N − b) of it; the fit is refused above ``BLACK_BOX_MARGIN`` = 2 times that. The
rule is applied only when b ≤ N/2 (the factor at most 2), since with fewer data the
black box fits the noise itself. The vector fit weighs each line's error relative to its
level: with noise proportional to |H|, a black box fitted in the judged (absolute)
misfit can chase the noise of the few resonance lines that dominate it (its b
parameters against few effective data) and land far below what a grey box of that order
reaches, which would refuse correct fits; relative weights do not do that, and make the
black box's misfit no tight floor either: the least-squares estimates of the 32 noisy
problems lie between 0.23 and 1.43 times it, hence the margin 2. On noise-free data
the whiteness rule alone accepted estimates at misfits of 2e-9 to 2e-3 and parameter
errors of 100 % to 1e6 % (8-mass chains, with one or two sensors; gains models); a
vector fit reaches 1e-27 on such data and refuses them.
``benchmarks/success_rule.py`` judges every estimate that benchmark logged with this rule
and the one before it (relative residuals, a black box ten times better), and prints
how many right estimates each calls a failure and how many wrong ones a success.

The floor used and the statistic are reported in the outcome's ``fit`` text.

A fit is not enough: an estimate the model's own declarations rule out is never a
success either (:func:`physical_check`, applied to every method's outcome by
:meth:`symid.fit.base.Estimator.outcome`):

* a parameter declared ``positive=True`` that came out negative;
* negative mass, damping or stiffness: in a second-order model, a symmetric M, V or K
  whose parameters are all declared positive, with a negative eigenvalue at the
  estimate (for V, negative damping: the model creates energy);
* unstable poles (an eigenvalue of A with a positive real part) in a model whose
  parameters are all declared positive: such a model describes a passive or
  compartmental system, stable for every admissible θ. A model meant to be unstable
  for positive values declares some parameter without ``positive=True``.

The tolerances are relative (1e-9 of the largest |θ|, and for M, V, K of what such a
change of θ can do to them or of ‖X‖₂; 1e-8 of the largest |pole|), so that rounding
at an active bound θ = 0 or a rigid-body mode (a pole at 0) does not count.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["BLACK_BOX_MARGIN", "CEILING", "EXACT_FIT", "LOCAL_GAIN_LIMIT", "NOISY_CEILING", "WHITENESS_LIMIT",
           "WHITENESS_POWER", "FitTest", "black_box_ratio", "chi2_bound", "fit_test", "physical_check", "whiteness",
           "whiteness_reach"]

EXACT_FIT = 1e-10
"""A relative misfit at or below this reproduces the data as noise-free data are reproduced."""

CEILING = 1e-2
"""Largest relative misfit accepted without a given noise floor (10 % rms residual) by the whiteness rule alone."""

NOISY_CEILING = 0.25
"""Largest relative misfit (50 % rms) a residual white and independent of the inputs is accepted at (rule 3): above
it, the model explains under three quarters of the data's power, and a model predicting little is not told apart
from one that fits."""

WHITENESS_LIMIT = 3.0
"""Largest scaled lag-one autocorrelation of the residual across frequency taken for noise."""

LOCAL_GAIN_LIMIT = 0.5
"""Without a black box, a whiteness fit is refused when one Gauss–Newton step predicts to remove more than this
fraction of its misfit (it is then not near a minimum of the misfit)."""

WHITENESS_POWER = 2.0 * WHITENESS_LIMIT
"""A white residual counts only where the statistic could reach this (:func:`whiteness_reach`): twice the limit, so
that a residual smooth enough to have a lag-one correlation of one half would be refused."""

BLACK_BOX_MARGIN = 2.0
"""A fit that is not exact is refused when its misfit exceeds this margin times the black box's misfit
scaled by (N − l)/(N − b), what a correct fit is expected to leave against it."""


@dataclass(frozen=True)
class FitTest:
    """Whether an estimate fits the data, and why.

    Attributes
    ----------
    fits : bool
    rule : str
        ``"exact"``, ``"noise floor"``, ``"whiteness"``, ``"weak whiteness"`` (a white residual too weakly tested for
        the test to have refused it, backed by a black box or one Gauss–Newton step), ``"local step"``,
        ``"black box"`` or ``"none"`` (which test decided).
    text : str
        One line for a summary: the misfit against the bound it was held to.
    """

    fits: bool
    rule: str
    text: str


def whiteness_reach(residuals: np.ndarray) -> float:
    """The largest value :func:`whiteness` can take on residuals of these magnitudes: its power.

    The statistic is Re Σ pₖ / √(Σ |pₖ|² / k) (k = 2 for complex residuals, 1 for real),
    at most Σ |pₖ| / √(Σ |pₖ|² / k) = √(k · nₑ), nₑ = (Σ |pₖ|)² / Σ |pₖ|² the number of
    products that carry the sum: reached when every product has the same sign, a residual
    as smooth as can be. With few data, or a residual carried by a few lines, even that is
    not far above ``WHITENESS_LIMIT``, so a white verdict then says nothing
    (``WHITENESS_POWER``).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.success import whiteness_reach
    >>> round(whiteness_reach(np.ones(15)), 3)             # 14 equal products: sqrt(14)
    3.742
    >>> bool(whiteness_reach(np.random.default_rng(0).standard_normal(400)) > 10)   # noise: about 0.64 sqrt(s)
    True
    """
    k = 2.0 if np.iscomplexobj(residuals) else 1.0
    r = np.nan_to_num(np.asarray(residuals, dtype=complex))
    s = r.shape[0]
    if s < 3:
        return 0.0
    r = r.reshape(s, -1)
    mag = np.abs(np.conj(r[:-1]) * r[1:]).reshape(-1)
    ss = float(np.sum(mag**2))
    return 0.0 if ss == 0.0 else float(np.sum(mag) / np.sqrt(ss / k))


def whiteness(residuals: np.ndarray) -> float:
    """Self-normalised lag-one autocorrelation of residuals ordered by frequency (or time), about N(0, 1) for noise.

    With r of shape (s, c) (c channels per frequency) and products pₖ꜀ = r̄ₖ꜀·rₖ₊₁,꜀, the
    statistic is Re Σ pₖ꜀ / √(Σ |pₖ꜀|² / 2) for complex residuals (Σ pₖ꜀ / √Σ pₖ꜀² for
    real ones). For independent zero-mean noise, Re pₖ꜀ has mean 0 and variance
    E|rₖ꜀|²·E|rₖ₊₁,꜀|² / 2, which the denominator estimates term by term, so the
    statistic is about N(0, 1) **whatever the noise level at each frequency**: the
    residuals can be given in the weighting of the misfit (dominated by a few resonance
    lines) without dividing by a noise level nobody knows. A residual that is a smooth
    function of frequency (a local minimum) makes it large and positive; when a few lines
    dominate, |statistic| ≤ √(2·(number of dominant products)), so the test then has
    little power and does not refuse a correct fit.

    Parameters
    ----------
    residuals : numpy.ndarray, shape (s, ...)
        Complex or real residuals, frequency first, in the weighting of the misfit that
        the estimate minimises. Non-finite entries count as 0.

    Returns
    -------
    float
        About N(0, 1) for independent noise; large and positive when the residual is a
        smooth function of frequency. ``0.0`` for fewer than 3 frequencies or a zero residual.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.success import whiteness
    >>> rng = np.random.default_rng(0)
    >>> bool(abs(whiteness(rng.standard_normal(400))) < 3)          # noise
    True
    >>> level = np.logspace(-3, 3, 400)                              # noise of very unequal size
    >>> bool(abs(whiteness(level * rng.standard_normal(400))) < 3)
    True
    >>> bool(whiteness(np.sin(np.linspace(0, 3, 400))) > 10)        # a smooth misfit
    True
    """
    is_complex = np.iscomplexobj(residuals)
    r = np.nan_to_num(np.asarray(residuals, dtype=complex))
    s = r.shape[0]
    if s < 3:
        return 0.0
    r = r.reshape(s, -1)
    peak = float(np.max(np.abs(r)))
    if peak > 0:  # the statistic does not change with the residuals' scale; residuals near overflow do not overflow
        r = r / peak
    prod = np.conj(r[:-1]) * r[1:]
    var = float(np.sum(np.abs(prod) ** 2)) / (2.0 if is_complex else 1.0)
    if var == 0.0:
        return 0.0
    return float(np.sum(prod.real) / np.sqrt(var))


_NEGATIVE_RTOL = 1e-9
"""A declared-positive θₖ (or an eigenvalue of M, V, K) below −1e-9 × the largest |θ| (‖X‖₂) is negative."""

_UNSTABLE_RTOL = 1e-8
"""A pole with real part above 1e-8 × the largest |pole| is unstable."""


def physical_check(model: Any, theta: Any) -> str | None:
    """Why an estimate contradicts what the model declares, or ``None`` when it does not.

    The rules (module notes): declared-positive parameters not negative; in a
    second-order model, symmetric M, V, K whose parameters are all declared positive
    positive semidefinite; in a model whose parameters are all declared positive, no
    unstable pole. Every estimator's outcome is held to it; a method may call it itself.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
        Any symid model with ``positive``, ``parameter_names``, ``maps`` and ``state_space``.
    theta : array_like
        The estimate, in ``model.parameter_names`` order.

    Returns
    -------
    str or None
        One line naming what is wrong (for the outcome's ``fit`` text), or ``None``.

    Examples
    --------
    >>> import symid as si
    >>> from symid.fit.success import physical_check
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> physical_check(model, [2.0, 0.5, 3.0]) is None
    True
    >>> physical_check(model, [2.0, -0.5, 3.0])
    'parameters declared positive are negative: c = -0.5'
    """
    th = np.asarray(theta, dtype=float).reshape(-1)
    names = tuple(getattr(model, "parameter_names", ()))
    positive = tuple(getattr(model, "positive", ()))
    if th.size != len(names) or len(positive) != len(names) or not np.all(np.isfinite(th)):
        return None  # nothing to judge (a non-finite estimate fails the fit test already)
    big = float(np.max(np.abs(th), initial=0.0))
    neg = [f"{n} = {v:.6g}" for n, pos, v in zip(names, positive, th, strict=True)
           if pos and v < -_NEGATIVE_RTOL * big]
    if neg:
        return f"parameters declared positive are negative: {', '.join(neg)}"
    maps = getattr(model, "maps", {})
    if all(k in maps for k in "MVK"):
        what = {"M": "mass", "V": "damping", "K": "stiffness"}
        for name in "MVK":
            amap = maps[name]
            dep = amap.depends_on
            if not dep or not all(positive[i] for i in dep):
                continue
            if not (np.allclose(amap.X0, amap.X0.T) and np.allclose(amap.Xi, np.swapaxes(amap.Xi, 1, 2))):
                continue
            X = amap(th)
            lam = np.linalg.eigvalsh(0.5 * (X + X.T))
            # as much as rounding θ at the parameter tolerance can move it, or 1e-9 of ‖X‖₂
            coef = max(float(np.linalg.norm(amap.Xi[i], 2)) for i in dep)
            if lam[0] < -_NEGATIVE_RTOL * max(float(np.abs(lam).max()), big * coef, np.finfo(float).tiny):
                return (f"negative {what[name]}: {name}(θ) has eigenvalue {lam[0]:.6g} although its parameters "
                        f"are declared positive")
    if names and all(positive):
        try:
            A = np.asarray(model.state_space(th).A, dtype=float)
            poles = np.linalg.eigvals(A) if A.size else np.zeros(0)
        except (ValueError, ArithmeticError, np.linalg.LinAlgError):
            return None  # a singular M: the misfit is infinite and the fit test fails already
        if poles.size and np.all(np.isfinite(poles)):
            top = float(np.abs(poles).max())
            bad = poles[poles.real > _UNSTABLE_RTOL * top]
            if bad.size:
                return (f"unstable: pole {bad[np.argmax(bad.real)]:.6g} in the right half-plane although every "
                        "parameter is declared positive (a passive or compartmental model is stable)")
    return None


def chi2_bound(n_data: int, n_parameters: int) -> float:
    """The χ² 99.9 % quantile with n_data − n_parameters degrees of freedom, over n_data: how far above its noise
    floor a misfit of independent Gaussian noise may lie (the factor :func:`fit_test` applies to a noise floor)."""
    from scipy.stats import chi2

    dof = max(n_data - n_parameters, 1)
    return float(chi2.ppf(0.999, dof) / max(n_data, 1))


def fit_test(cost: float, *, n_data: int, n_parameters: int, residuals: np.ndarray | None = None,
             noise_floor: float | None = None,
             black_box: Callable[[], tuple[float, int] | None] | None = None,
             local_gain: Callable[[], float | None] | None = None,
             independent: Callable[[], bool | None] | None = None) -> FitTest:
    """Does a data misfit ``cost`` (relative, squared) fit the data? See the module text for the rule.

    Parameters
    ----------
    cost : float
        The estimate's relative data misfit.
    n_data : int
        Number of real data values (2 per complex entry).
    n_parameters : int
    residuals : numpy.ndarray, optional
        Relative residuals ordered by frequency (for the whiteness test).
    noise_floor : float, optional
        The relative misfit noise alone leaves at the true parameters.
    black_box : callable, optional
        Called (only when a fit that is not exact would otherwise be accepted) for
        ``(misfit, b)``: the same misfit of a black box of the model's order, and its
        number of real parameters b; or ``None`` when there is none.
    local_gain : callable, optional
        Called (only for a whiteness fit when no black box is available, or a weak one
        the black box cannot back) for the fraction of the misfit one Gauss–Newton step
        from the estimate predicts to remove, or ``None``; above ``LOCAL_GAIN_LIMIT`` the
        estimate is not a fit, and a weak whiteness fit without it is not one either.
    independent : callable, optional
        Called (only for a residual above ``CEILING`` and at most ``NOISY_CEILING`` that the
        whiteness test, with power, finds white) for whether the residual is independent of
        every input (measured samples: :func:`symid.fit.validation.independence_pvalues`);
        True lets such a fit count (module notes, rule 3).

    Returns
    -------
    FitTest

    Examples
    --------
    >>> from symid.fit.success import fit_test
    >>> fit_test(1e-12, n_data=60, n_parameters=4).rule
    'exact'
    >>> fit_test(1.1e-4, n_data=60, n_parameters=4, noise_floor=1e-4).fits
    True
    >>> fit_test(0.48, n_data=60, n_parameters=4, noise_floor=1e-4).fits
    False
    >>> fit_test(1.1e-4, n_data=60, n_parameters=4, noise_floor=1e-4, black_box=lambda: (1e-9, 10)).rule
    'black box'
    """
    test = _fit_test(cost, n_data=n_data, n_parameters=n_parameters, residuals=residuals, noise_floor=noise_floor)
    if (not test.fits and independent is not None and noise_floor is None and residuals is not None
            and CEILING < cost <= NOISY_CEILING):
        loud = _loud_noise(cost, residuals, independent, local_gain)
        if loud is not None:
            return loud
    if not test.fits or test.rule == "exact":
        return test
    bb = None if black_box is None else black_box()
    weak = test.rule == "weak whiteness"
    if bb is None or (weak and black_box_ratio(bb, n_data=n_data, n_parameters=n_parameters) is None):
        gain = local_gain() if local_gain is not None and test.rule in ("whiteness", "weak whiteness") else None
        if gain is not None and gain > LOCAL_GAIN_LIMIT:
            return FitTest(False, "local step", f"misfit {cost:.2e} with a white residual, but one Gauss–Newton step "
                                                f"from the estimate predicts a misfit {100 * gain:.0f} % lower: not "
                                                f"a minimum of the misfit ({test.text})")
        if weak and gain is None:
            return FitTest(False, "whiteness", f"{test.text}; no black box to compare with and no Gauss–Newton step "
                                               f"to check: pass noise_floor= to judge this fit")
        if weak:
            return FitTest(True, "weak whiteness", f"{test.text}; a minimum of the misfit (one Gauss–Newton step "
                                                   f"predicts {100 * gain:.0f} % lower), which a local minimum is "
                                                   f"too: pass noise_floor= for a sharper test")
        return test
    ratio = black_box_ratio(bb, n_data=n_data, n_parameters=n_parameters)
    if ratio is None or cost <= ratio * bb[0]:
        return test
    floor, b = bb
    return FitTest(False, "black box", f"misfit {cost:.2e} > {ratio:.3g} × {floor:.2e}, the misfit of a black box "
                                       f"of the model's order ({b} parameters; {BLACK_BOX_MARGIN:g} × (N − l)/(N − b) "
                                       f"with N = {n_data} data, l = {n_parameters}): the data are cleaner than this "
                                       f"fit ({test.text})")


def _loud_noise(cost: float, residuals: np.ndarray, independent: Callable[[], bool | None],
                local_gain: Callable[[], float | None] | None) -> FitTest | None:
    """Rule 3's second half (module notes): a residual above ``CEILING`` that is white with power, independent of
    every input, and no step from a minimum, fits as noise of its own level; else None."""
    with np.errstate(over="ignore", invalid="ignore"):
        z = whiteness(residuals)
        reach = whiteness_reach(residuals)
    if not (np.isfinite(z) and z <= WHITENESS_LIMIT and reach >= WHITENESS_POWER):
        return None
    if independent() is not True:
        return None
    gain = local_gain() if local_gain is not None else None
    if gain is not None and gain > LOCAL_GAIN_LIMIT:
        return None
    return FitTest(True, "whiteness and independence",
                   f"misfit {cost:.2e} ({100 * np.sqrt(cost):.0f} % rms, above {CEILING:g}) with a residual white "
                   f"(lag-1 statistic {z:.1f} ≤ {WHITENESS_LIMIT:g}) and independent of every input: noise of that "
                   f"level; give noise_std= (your sensors') to judge it against theirs")


def black_box_ratio(black_box: tuple[float, int] | None, *, n_data: int, n_parameters: int) -> float | None:
    """How many times the misfit of a black box of the model's order a fit may have before the data are cleaner
    than the fit: ``BLACK_BOX_MARGIN`` (N − l)/(N − b), N data, l parameters, b the black box's (see
    :func:`fit_test`); ``None`` when there is no black box to compare with (or it has more than N/2
    parameters, or no finite misfit).

    Examples
    --------
    >>> from symid.fit.success import black_box_ratio
    >>> round(black_box_ratio((1e-9, 10), n_data=60, n_parameters=4), 3)
    2.24
    >>> black_box_ratio(None, n_data=60, n_parameters=4) is None
    True
    """
    if black_box is None:
        return None
    floor, b = black_box
    if b > n_data / 2 or not np.isfinite(floor):
        return None
    return BLACK_BOX_MARGIN * max(n_data - n_parameters, 1) / (n_data - b)


def _fit_test(cost: float, *, n_data: int, n_parameters: int, residuals: np.ndarray | None,
              noise_floor: float | None) -> FitTest:
    """Rules 1-4 of the module text (without the black box)."""
    if not np.isfinite(cost):
        return FitTest(False, "none", "the model cannot be evaluated at the estimate")
    if cost <= EXACT_FIT:
        return FitTest(True, "exact", f"misfit {cost:.2e} ≤ {EXACT_FIT:g} (exact fit)")
    if noise_floor is not None:
        bound = noise_floor * chi2_bound(n_data, n_parameters)
        ok = cost <= bound
        return FitTest(ok, "noise floor", f"misfit {cost:.2e} {'≤' if ok else '>'} {bound:.2e} "
                                          f"(noise floor {noise_floor:.2e} × χ² 99.9 % bound)")
    if residuals is not None:
        z = whiteness(residuals)
        ok = z <= WHITENESS_LIMIT
        if cost > CEILING:
            # still refused without a noise level, but a white residual is what noise that large would leave: say so
            with np.errstate(over="ignore", invalid="ignore"):  # residuals of a diverged estimate overflow there
                white = (f"; its residual is white (lag-1 statistic {z:.1f} ≤ {WHITENESS_LIMIT:g}), as noise of "
                         f"{100 * np.sqrt(cost):.0f} % rms would leave it"
                         if ok and np.isfinite(cost) and whiteness_reach(residuals) >= WHITENESS_POWER else "")
            return FitTest(False, "whiteness", f"misfit {cost:.2e} > {CEILING:g} (over 10 % rms) and no noise "
                                               f"floor given{white}")
        reach = whiteness_reach(residuals)
        if ok and reach < WHITENESS_POWER:  # a verdict a black box or a Gauss–Newton step must back (fit_test)
            # "too short" read oddly for 400 values (a new user's): a few large values carry the statistic
            return FitTest(True, "weak whiteness", f"misfit {cost:.2e} with a residual the whiteness test cannot "
                                                   f"judge (a few large values carry it: the lag-1 statistic, "
                                                   f"{z:.1f}, reaches at most {reach:.1f} for residuals of these "
                                                   f"sizes, below {WHITENESS_POWER:g}); no noise floor given")
        return FitTest(ok, "whiteness", f"misfit {cost:.2e} with {'white' if ok else 'structured'} residual "
                                        f"(lag-1 statistic {z:.1f} {'≤' if ok else '>'} {WHITENESS_LIMIT:g}); "
                                        f"no noise floor given")
    return FitTest(False, "none", f"misfit {cost:.2e} > {EXACT_FIT:g} and no noise floor given "
                                  f"(pass noise_floor= to judge a noisy fit)")
