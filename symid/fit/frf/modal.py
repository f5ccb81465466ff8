"""A start from a black box of the frequency response: the model's poles placed on the measured ones.

A grey box's frequency response is a landscape of narrow ridges around its resonances;
a start whose modes sit beside the measured ones is where local methods get lost. The
modes themselves are easy to measure without the grey box: a rational black box of the
data has them. The start is built in four steps, for any model structure (state space or
second order, any parameterisation):

1. **Black box.** Vector fitting (:func:`symid.signal.vectfit.vector_fit`, Gustavsen &
   Semlyen 1999) with as many poles as the model has states (2n for n degrees of
   freedom), errors relative to each line's level. Its poles aᵢ are the measured modes:
   natural frequencies, damping ratios, and the overdamped or out-of-band pairs that
   stand for what lies outside the band.
2. **Poles.** The parameters of the dynamics (those in M, V, K, or in A) solve a small
   least squares problem that puts the model's poles on the aᵢ: the residuals are the
   model's characteristic polynomial at each aᵢ, det(aᵢ²M + aᵢV + K) / det M (or
   det(aᵢI − A)), divided by Πⱼ≠ᵢ (aᵢ − aⱼ) and by the half-bandwidth max(|Re aᵢ|,
   1e-3 |aᵢ|) — near a match, the distance of the nearest model pole in units of the
   mode's bandwidth — with magnitudes compressed to log(1 + |r|). The polynomial is
   smooth in θ: no sorting or pairing of eigenvalues, which jump as modes cross or
   become overdamped. A weak pull (0.05 per natural-log unit) towards the typical
   values of :func:`symid.fit.frf.scale.typical_scale` settles the directions the poles
   do not fix. Positive parameters move on a log scale. It runs from the typical values
   and from four seeded draws within a factor 3 of them: the poles rarely fix every
   parameter, and the draws land on different points with the same poles.
3. **Levels.** From each of those points, the other parameters (gains in B, C, D) —
   and, for a second-order model whose M, V, K are made of parameters only, a common
   factor of M, V and K, which leaves the poles unchanged — solve the least squares
   problem of the response relative to each line's level, (H(θ) − Hᵢ) / |Hᵢ|.
4. **Everything.** The three best points by the log-H error below (the best one only
   for a model of more than 30 parameters, where this step's cost grows as l²) fit every
   parameter to the data, log H(ωᵢ, θ) − log Hᵢ (the first criterion of
   :mod:`symid.fit.frf.lm`, each line alike, exact Jacobian), with the pole residuals of
   step 2 beside it (they keep the modes on the measured ones while the zeros and
   levels settle) and a pull of 1e-3 towards the point; 100 iterations at most: a
   start, not an estimate.

The best result is kept only when it fits the data better than the typical values do,
in the mean squared error of log H (phase wrapped, :func:`log_misfit`); otherwise (or
when the data have fewer than N + 2 lines for N states, or the black box fails) there
is no black-box start, and :func:`symid.fit.starts.draw_starts` draws around the typical
values alone.

Measured on the generated population of ``benchmarks/population_models.py``
(``benchmarks/frf_starts.py``; numbers in the README) and on the F-16 ground vibration
test (``examples/f16_gvt.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from symid.errors import DataError, ModelError, OptionError
from symid.fit.frf.scale import typical_scale

__all__ = ["BlackBoxStart", "black_box_start", "log_misfit"]

_PRIOR = 0.05  # pull towards the typical values, per natural-log unit: resolves what the poles leave open
_HOLD = 1e-3  # pull of the last step towards where it starts: resolves only what the data leave open
_POLE_WEIGHT = 1.0  # weight of the pole match beside the mean squared log-H error in the last step
_DRAWS = 4  # extra starts of the pole match, within a factor 3 of the typical values
_CANDIDATES = 3  # points of step 3 refined by step 4
_MANY = 30  # with more parameters than this, step 4 refines only the best point (its cost grows as l²)
_JOINT_ITER = 100  # iterations of the last step: a start, not an estimate
_MATCH_ITER = 100  # iterations of each pole match


@dataclass(frozen=True)
class BlackBoxStart:
    """A start for a grey box from a black box of its frequency response (:func:`black_box_start`).

    Attributes
    ----------
    theta : numpy.ndarray
        The start, in ``parameter_names`` order.
    typical : numpy.ndarray
        Typical magnitudes for further draws: |θ| where it is not zero, else the typical
        value of :func:`~symid.fit.frf.scale.typical_scale`.
    poles : numpy.ndarray
        The black box's poles (rad/s).
    black_box_error : float
        Relative rms error of the black box (vector fitting).
    misfit, typical_misfit : float
        Mean squared error of log H at the start and at the typical values.
    """

    theta: np.ndarray
    typical: np.ndarray
    poles: np.ndarray
    black_box_error: float
    misfit: float
    typical_misfit: float


def log_misfit(model: Any, data: Any, theta: Any) -> float:
    """Mean of |log(H(ωᵢ, θ) / Hᵢ)|² over the lines and entries where Hᵢ ≠ 0 (phase wrapped to (−π, π]).

    Returns ``inf`` where the model cannot be evaluated or is zero at a measured line.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.frf.modal import log_misfit
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, [1.0, 0.2, 100.0], np.linspace(5, 15, 30))
    >>> round(log_misfit(model, frf, [1.0, 0.2, 100.0]), 12), round(log_misfit(model, frf, [2.0, 0.4, 200.0]), 4)
    (0.0, 0.4805)
    """
    H = np.asarray(data.H)
    mask = H != 0
    try:
        with np.errstate(all="ignore"):
            Hm = np.asarray(model.frequency_response(theta, data.w))
    except (ModelError, np.linalg.LinAlgError):
        return float("inf")
    with np.errstate(all="ignore"):
        r = np.log(Hm[mask] / H[mask])
    if not np.all(np.isfinite(r)):
        return float("inf")
    return float(np.mean(np.abs(r) ** 2))


def _dynamic(model: Any) -> np.ndarray:
    """Which parameters enter the dynamics (M, V, K or A)."""
    names = ("M", "V", "K") if "M" in model.maps else ("A",)
    out = np.zeros(model.n_parameters, dtype=bool)
    for name in names:
        Xi = np.asarray(model.maps[name].Xi)
        if Xi.size:
            out |= np.any(Xi.reshape(model.n_parameters, -1) != 0, axis=1)
    return out


def _common_factor(model: Any, dyn: np.ndarray) -> bool:
    """True when scaling every parameter of M, V, K by one factor scales M, V, K (the poles stay)."""
    if "M" not in model.maps:
        return False
    if any(np.any(np.asarray(model.maps[n].X0) != 0) for n in ("M", "V", "K")):
        return False
    for n in ("B", "C"):
        Xi = np.asarray(model.maps[n].Xi)
        if Xi.size and np.any(Xi.reshape(model.n_parameters, -1)[dyn] != 0):
            return False  # a parameter of the dynamics also sits in B or C
    return True


def _targets(poles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The black box's poles once each (one of every conjugate pair) and log of their normalisers
    |Πⱼ≠ᵢ (aᵢ − aⱼ)| · dᵢ, dᵢ = max(|Re aᵢ|, 1e-3 |aᵢ|) (module docstring, step 2)."""
    keep = poles.imag >= 0
    a = poles[keep]
    norm = np.empty(a.size)
    for i, ai in enumerate(a):
        others = np.delete(poles, np.flatnonzero(keep)[i])
        d = max(abs(ai.real), 1e-3 * abs(ai))
        norm[i] = float(np.sum(np.log(np.abs(ai - others)))) + math.log(d)
    return a, norm


def _pole_residual(coef: dict[str, tuple[np.ndarray, np.ndarray]], theta: np.ndarray, a: np.ndarray,
                   norm: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Step 2's residuals and their exact derivative with respect to θ (``None`` where undefined).

    With P(s) = K + sV + s²M (or sI − A) and Lᵢ = log det P(aᵢ) − log det M − log normaliserᵢ
    (complex: ℓᵢ + jφᵢ), the residual is rᵢ = e^{jφᵢ} log(1 + e^{ℓᵢ}) — the characteristic
    polynomial at aᵢ over the normaliser, its magnitude compressed — and
    ∂Lᵢ/∂θₖ = tr(P(aᵢ)⁻¹ ∂P/∂θₖ) − tr(M⁻¹ ∂M/∂θₖ) (Jacobi's formula). Real and imaginary parts
    are stacked: shapes (2T,) and (2T, l).
    """
    mats = {n: X0 + np.tensordot(theta, Xi, axes=1) for n, (X0, Xi) in coef.items()}
    second = "M" in mats
    try:
        with np.errstate(all="ignore"):
            if second:
                sign_m, log_m = np.linalg.slogdet(mats["M"])
                if sign_m == 0 or not np.isfinite(log_m):
                    return None
                dlog_m = np.einsum("rc,kcr->k", np.linalg.inv(mats["M"]), coef["M"][1])
            else:
                sign_m, log_m, dlog_m = 1.0, 0.0, 0.0
            r = np.empty(a.size, dtype=complex)
            J = np.empty((a.size, theta.size), dtype=complex)
            for i, ai in enumerate(a):
                if second:
                    P = mats["K"] + ai * mats["V"] + ai * ai * mats["M"]
                    dP = coef["K"][1] + ai * coef["V"][1] + ai * ai * coef["M"][1]
                else:
                    P = ai * np.eye(mats["A"].shape[0]) - mats["A"]
                    dP = -coef["A"][1]
                sign, logabs = np.linalg.slogdet(P)
                if sign == 0 or not np.isfinite(logabs):  # a model pole exactly on aᵢ: r = 0, flat
                    r[i], J[i] = 0.0, 0.0
                    continue
                ell = min(logabs - log_m - norm[i], 700.0)
                phase = sign / sign_m
                g = math.log1p(math.exp(ell)) if ell < 700.0 else ell
                dg = 1.0 / (1.0 + math.exp(-ell)) if ell > -700.0 else 0.0
                dL = np.einsum("rc,kcr->k", np.linalg.inv(P), dP) - dlog_m
                r[i] = phase * g
                J[i] = phase * (dg * dL.real + 1j * g * dL.imag)
    except (np.linalg.LinAlgError, ValueError, OverflowError):
        return None
    out = np.concatenate([r.real, r.imag])
    jac = np.vstack([J.real, J.imag])
    if not (np.all(np.isfinite(out)) and np.all(np.isfinite(jac))):
        return None
    return out, jac


class _Map:
    """θ from unknowns φ: positive parameters θ₀·exp φ, others θ₀ + s·φ."""

    def __init__(self, theta0: np.ndarray, scale: np.ndarray, positive: np.ndarray, which: np.ndarray):
        self.theta0, self.scale, self.positive, self.which = theta0, scale, positive, np.flatnonzero(which)

    def __call__(self, phi: np.ndarray) -> np.ndarray:
        th = self.theta0.copy()
        for i, j in enumerate(self.which):
            th[j] = self.theta0[j] * math.exp(phi[i]) if self.positive[j] else self.theta0[j] + self.scale[j] * phi[i]
        return th


def black_box_start(model: Any, data: Any, typical: Any = None, *, seed: int = 0) -> BlackBoxStart | None:
    """A start whose poles are the black box's poles (module docstring), or ``None`` if there is none.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    data : FrequencyData
    typical : array_like, optional
        Typical magnitude of every parameter (default:
        :func:`symid.fit.frf.scale.typical_scale`).
    seed : int, optional
        Seed of the extra starts of the pole match.

    Returns
    -------
    BlackBoxStart or None
        ``None`` when the data have fewer than N + 2 lines for a model of N states, when
        the black box or the model cannot be evaluated, or when the start does not fit
        the data better than the typical values.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.frf.modal import black_box_start
    >>> m1, m2, c, k1, k2 = si.parameters("m1 m2 c k1 k2", positive=True)
    >>> model = si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c, 0], [0, c]],
    ...                             K=[[k1 + k2, -k2], [-k2, k2]], B=[[0], [1]], C=[[1, 0]])
    >>> truth = [2.0, 0.5, 1.5, 3e4, 1e4]
    >>> frf = si.simulate_frf(model, truth, np.logspace(1.5, 3, 80))
    >>> start = black_box_start(model, frf)
    >>> bool(start.misfit < 1e-3 * start.typical_misfit)          # on the measured modes
    True
    """
    w = np.asarray(data.w, dtype=float)
    H = np.asarray(data.H)
    N = int(model.n_states)
    if N == 0 or w.size < N + 2 or not np.any(H != 0):
        return None
    if typical is None:
        typical = typical_scale(model, data)
    typical = np.asarray(typical, dtype=float).reshape(-1)
    try:
        from symid.signal.vectfit import vector_fit

        bb = vector_fit(w, H, N, weight="relative")
    except (DataError, OptionError, np.linalg.LinAlgError):
        return None
    target, norm = _targets(bb.poles)
    positive = np.asarray(model.positive, dtype=bool)
    dyn = _dynamic(model)
    t_mis = log_misfit(model, data, typical)
    ctx = _Context(model, w, H, typical, positive, dyn, target, norm)
    leveled = []
    for cand in ctx.match_poles(seed):
        th = ctx.levels(cand)
        if not any(np.allclose(th, other, rtol=1e-6) for _, other in leveled):
            leveled.append((log_misfit(model, data, th), th))
    leveled.sort(key=lambda c: c[0])
    best_mis, best = math.inf, None
    for _, cand in leveled[:_CANDIDATES if model.n_parameters <= _MANY else 1]:
        theta = ctx.joint(cand)
        mis = log_misfit(model, data, theta)
        if mis < best_mis:
            best_mis, best = mis, theta
    if best is None or not (np.isfinite(best_mis) and best_mis < t_mis):
        return None
    mag = np.abs(best)
    refined = np.where(mag > 1e-6 * typical, mag, typical)
    return BlackBoxStart(theta=best, typical=refined, poles=bb.poles, black_box_error=bb.rms, misfit=best_mis,
                         typical_misfit=t_mis)


class _Context:
    """The data, the model and the black box's poles shared by the steps of :func:`black_box_start`."""

    def __init__(self, model: Any, w: np.ndarray, H: np.ndarray, typical: np.ndarray, positive: np.ndarray,
                 dyn: np.ndarray, target: np.ndarray, norm: np.ndarray):
        self.model, self.w, self.H, self.typical = model, w, H, typical
        self.positive, self.dyn, self.target, self.norm = positive, dyn, target, norm
        self.mask = np.abs(H) > 0
        self.n_res = 2 * target.size
        names = ("M", "V", "K") if "M" in model.maps else ("A",)
        self.coef = {n: (np.asarray(model.maps[n].X0, dtype=float), np.asarray(model.maps[n].Xi, dtype=float)
                         .reshape(model.n_parameters, *model.maps[n].shape)) for n in names}

    def pole_residual(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """Step 2's residual at θ and its derivative (``None`` where the model cannot be evaluated)."""
        return _pole_residual(self.coef, theta, self.target, self.norm)

    def response(self, theta: np.ndarray) -> np.ndarray | None:
        try:
            with np.errstate(all="ignore"):
                Hm = np.asarray(self.model.frequency_response(theta, self.w))
        except (ModelError, np.linalg.LinAlgError):
            return None
        return Hm if np.all(np.isfinite(Hm)) else None

    def match_poles(self, seed: int) -> list[np.ndarray]:
        """Step 2 from the typical values and from draws around them; the results, best first."""
        typical, positive, dyn = self.typical, self.positive, self.dyn
        if not np.any(dyn):
            return [typical.copy()]
        rng = np.random.default_rng([int(seed), 611953])
        k = int(dyn.sum())
        found = []
        for draw in range(_DRAWS + 1):
            start = typical.copy()
            if draw:
                start[dyn] = np.where(positive[dyn], typical[dyn] * 3.0 ** rng.uniform(-1, 1, k),
                                      typical[dyn] * rng.uniform(0.5, 1.5, k))
            pmap = _Map(start, np.abs(typical), positive, dyn)
            shift = np.where(positive[dyn], np.log(start[dyn] / typical[dyn]),
                             (start[dyn] - typical[dyn]) / np.abs(typical[dyn]))

            def resid(phi: np.ndarray, pmap: _Map = pmap, shift: np.ndarray = shift) -> np.ndarray:
                rj = self.pole_residual(pmap(phi))
                if rj is None:
                    return np.full(self.n_res + k, 1e3)
                return np.concatenate([rj[0], _PRIOR * (phi + shift)])

            def jac(phi: np.ndarray, pmap: _Map = pmap) -> np.ndarray:
                th = pmap(phi)
                rj = self.pole_residual(th)
                if rj is None:
                    return np.vstack([np.zeros((self.n_res, k)), _PRIOR * np.eye(k)])
                scale = np.where(positive[dyn], th[dyn], np.abs(typical[dyn]))  # dθ/dφ
                return np.vstack([rj[1][:, dyn] * scale, _PRIOR * np.eye(k)])

            sol = least_squares(resid, np.zeros(k), jac=jac, method="trf", max_nfev=_MATCH_ITER)
            found.append((sol.cost, pmap(sol.x)))
        found.sort(key=lambda c: c[0])
        return [th for _, th in found]

    def levels(self, theta: np.ndarray) -> np.ndarray:
        """Step 3: gains (and a common factor of M, V, K) on the response relative to each line's level."""
        model, positive, dyn = self.model, self.positive, self.dyn
        level = ~dyn
        factor = _common_factor(model, dyn)
        if not (np.any(level) or factor):
            return theta
        lmap = _Map(theta.copy(), np.abs(self.typical), positive, level)
        n_level = int(level.sum())
        H, mask = self.H, self.mask
        Hmag = np.abs(H[mask])

        def full(x: np.ndarray) -> np.ndarray:
            th = lmap(x[:n_level])
            if factor:
                th[dyn] = th[dyn] * math.exp(x[n_level])
            return th

        def resid(x: np.ndarray) -> np.ndarray:
            Hm = self.response(full(x))
            if Hm is None:
                return np.full(2 * Hmag.size + x.size, 1e3)
            r = (Hm[mask] - H[mask]) / Hmag
            return np.concatenate([r.real, r.imag, _PRIOR * x])

        sol = least_squares(resid, np.zeros(n_level + int(factor)), method="trf", max_nfev=100 * (n_level + 2))
        return full(sol.x)

    def joint(self, theta: np.ndarray) -> np.ndarray:
        """Step 4: every parameter on log H, the poles held on the black box's (exact Jacobian of log H)."""
        from symid.fit.sensitivity import frf_sensitivity

        model, H, mask, w = self.model, self.H, self.mask, self.w
        l = model.n_parameters
        jmap = _Map(theta.copy(), np.abs(self.typical), self.positive, np.ones(l, dtype=bool))
        root = math.sqrt(int(mask.sum()))
        size = 2 * int(mask.sum()) + self.n_res + l
        cache: dict[bytes, Any] = {}

        def evaluate(x: np.ndarray, derivative: bool = False) -> Any:
            key = x.tobytes()
            if key not in cache or (derivative and cache[key][2] is None):
                th = jmap(x)
                try:
                    with np.errstate(all="ignore"):
                        if derivative:
                            Hm, dH = frf_sensitivity(model, th, w)
                        else:
                            Hm, dH = np.asarray(model.frequency_response(th, w)), None
                        rh = np.log(Hm[mask] / H[mask]) / root
                except (ModelError, np.linalg.LinAlgError):
                    Hm, dH, rh = None, None, None
                rpj = self.pole_residual(th)
                cache.clear()
                cache[key] = (th, Hm, dH, rh, rpj)
            return cache[key]

        def resid(x: np.ndarray) -> np.ndarray:
            _, Hm, _, rh, rpj = evaluate(x)
            if Hm is None or rpj is None:
                return np.full(size, 1e3)
            out = np.concatenate([rh.real, rh.imag, _POLE_WEIGHT * rpj[0], _HOLD * x])
            return np.where(np.isfinite(out), out, 1e3)

        def jac(x: np.ndarray) -> np.ndarray:
            th, Hm, dH, _, rpj = evaluate(x, derivative=True)
            if Hm is None or dH is None or rpj is None:
                return np.eye(size, l)
            dtheta = np.where(self.positive, th, np.abs(self.typical))  # dθ/dx
            with np.errstate(all="ignore"):
                dlog = dH[mask] / Hm[mask][:, None] * (dtheta / root)[None, :]
            out = np.vstack([dlog.real, dlog.imag, _POLE_WEIGHT * rpj[1] * dtheta[None, :], _HOLD * np.eye(l)])
            return np.where(np.isfinite(out), out, 0.0)

        x0 = np.zeros(l)
        sol = least_squares(resid, x0, jac=jac, method="trf", max_nfev=_JOINT_ITER)
        return jmap(sol.x) if sol.cost < 0.5 * float(np.sum(resid(x0) ** 2)) else theta
