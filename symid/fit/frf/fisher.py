"""The Fisher information of a frequency-response fit: residuals, exact Jacobian, relative noise.

The misfit of every FRF method is Σᵢ ‖Hᵢ − H(ωᵢ, θ)‖²_F / Σᵢ ‖Hᵢ‖²_F, so the residual
vector is the real and imaginary parts of (Hᵢ − H(ωᵢ, θ)) / ‖H‖ and its Jacobian is
−∂H/∂θ / ‖H‖, exact from the affine maps (:func:`symid.fit.sensitivity.frf_sensitivity`).
Estimated from the residuals, the noise is independent circular complex Gaussian, either
**relative**, E|eᵢ|² = ε_j² |H_j(ωᵢ, θ̂)|² for output j (each part half of it), the model
``si.simulate_frf(..., noise=ε)`` follows and the success rule assumes
(:mod:`symid.fit.success`), or **additive**, E|eᵢ|² = σ_j² on every line of output j, as a
response estimated from a multisine with a flat spectrum has it: whichever the residuals'
Gaussian likelihood prefers (each with its own level per output; :meth:`FrfFisher.additive_noise`).
Taking relative noise for additive noise puts the largest variances at the resonances,
where the information is: a new user's 4-storey frame got standard errors 60 to 150 times
the spread of its estimates. ``noise_std=`` gives the noise per frequency or entry instead.

A noise-weighted fit (``line_weights`` w = 1/σ² per entry, set by an estimator's
``variance=`` option) minimises Σ w|Hᵢ − H(ωᵢ, θ)|² / Σ w|Hᵢ|²: its residual vector is
√w (Hᵢ − H(ωᵢ, θ)) / ‖√w H‖ and the Jacobian likewise, and when the estimator knows the
variance itself (``line_variance``) that is the noise of the uncertainty unless
``noise_std`` is given (Pintelon & Schoukens, §7.2: the maximum-likelihood criterion
with known noise variances; its covariance is the inverse Fisher information).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
import scipy.linalg

from symid.fit.sensitivity import frf_sensitivity
from symid.fit.uncertainty import FisherInformation, Uncertainty, broadcast_noise
from symid.model.secondorder import output_factor

__all__ = ["FrfFisher", "residual_noise_model"]


def residual_noise_model(H: np.ndarray, Hm: np.ndarray) -> str | None:
    """Whether the residual H − Hm is likelier ``"additive"`` noise (one level per output on every line) or
    ``"relative"`` noise (a level per output times |Hm|): the Gaussian likelihoods, each level at its maximum,
    compared; None where either is undefined (a zero or non-finite value).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.frf.fisher import residual_noise_model
    >>> Hm = np.logspace(0, -4, 50).reshape(-1, 1, 1)
    >>> e = np.random.default_rng(0).standard_normal(Hm.shape)
    >>> residual_noise_model(Hm * (1 + 0.01 * e), Hm), residual_noise_model(Hm + 1e-3 * e, Hm)
    ('relative', 'additive')
    """
    r2, m2 = np.abs(H - Hm) ** 2, np.abs(Hm) ** 2
    if not (np.all(np.isfinite(r2)) and np.all(m2 > 0) and np.all(np.isfinite(m2))):
        return None
    nll_add = nll_rel = 0.0
    for j in range(H.shape[1]):  # per output: N log(mean r²/s²) + Σ log s² (s = 1 or |H|)
        rj, mj = r2[:, j].ravel(), m2[:, j].ravel()
        add, rel = float(np.mean(rj)), float(np.mean(rj / mj))
        if not (add > 0 and rel > 0):
            return None
        nll_add += rj.size * np.log(add)
        nll_rel += rj.size * np.log(rel) + float(np.sum(np.log(mj)))
    return "additive" if nll_add < nll_rel else "relative"

_MINIMISERS = ("ipopt", "lm", "auto")


class FrfFisher(FisherInformation):
    """:class:`~symid.fit.uncertainty.FisherInformation` of the FRF misfit (mixed into ``FrfEstimator``).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, [2.0, 0.5, 3.0], np.linspace(0.5, 2.0, 20), noise=0.01, seed=0)
    >>> res = si.identify(model, frf, method="ipopt", x0=[2.0, 0.5, 3.0])
    >>> unc = res.uncertainty
    >>> unc.noise_units, bool(0.005 < unc.noise_std[0] < 0.02), bool(np.all(unc.standard_errors < 0.05))
    ('relative', True, True)
    """

    noise_units: ClassVar[str] = "relative"
    model: Any
    data: Any
    method: ClassVar[str]
    line_weights: np.ndarray | None = None
    line_variance: np.ndarray | None = None
    estimated_variance_dof: float | None = None

    def _sqrt_weights(self) -> np.ndarray:
        """√w per entry of H (ones without noise weighting)."""
        w = self.line_weights
        return np.ones(np.shape(self.data.H)) if w is None else np.sqrt(np.asarray(w, dtype=float))

    def _norm(self) -> float:
        return float(np.sqrt(np.sum((self._sqrt_weights() * np.abs(np.asarray(self.data.H))) ** 2))) or 1.0

    def jacobian(self, theta: Any) -> tuple[np.ndarray, np.ndarray]:
        """Real and imaginary parts of √w (H − H(θ)) / ‖√w H‖ (entry order s, p, m; w = 1 without weights) and
        their Jacobian."""
        H = np.asarray(self.data.H)
        Hm, dH = frf_sensitivity(self.model, theta, self.data.w)
        nrm = self._norm()
        sw = self._sqrt_weights()
        R = sw * (H - Hm) / nrm
        D = -(dH * sw[..., None]).reshape(-1, dH.shape[-1]) / nrm
        return np.concatenate([R.real.ravel(), R.imag.ravel()]), np.vstack([D.real, D.imag])

    def data_shift(self, theta: Any, dH: Any) -> np.ndarray:
        """How far the estimate θ moves, to first order (one Gauss–Newton step), when the data H change by ``dH``
        (an array shaped like H): the bias a systematic error of the data leaves in θ̂ (symid.fit.frf.leakage).
        Exact to first order on data the model fits exactly; with a residual, its curvature term is left out (on an
        oscillator at 1 % noise the refit moved 20 % less in its stiffness than this step)."""
        _, J = self.jacobian(theta)
        d = self._sqrt_weights() * np.asarray(dH) / self._norm()
        step, *_ = np.linalg.lstsq(J, np.concatenate([d.real.ravel(), d.imag.ravel()]), rcond=None)
        return -step[: np.asarray(theta).size]

    def residual_channels(self) -> np.ndarray:
        """The output (row of H) of every residual entry."""
        s, p, m = np.asarray(self.data.H).shape
        ch = np.broadcast_to(np.arange(p)[None, :, None], (s, p, m)).ravel()
        return np.concatenate([ch, ch])

    def additive_noise(self, theta: Any) -> bool:
        """Whether the residuals at ``theta`` are likelier additive noise (one level per output on every line) than
        relative noise (a level per output times |H(ωᵢ, θ)|): the Gaussian likelihoods, each level at its maximum,
        compared. False for a noise-weighted fit (its weights say the noise) or where either is undefined."""
        if self.line_weights is not None:
            return False
        key = np.asarray(theta, dtype=float).tobytes()
        memo = getattr(self, "_additive_memo", None)
        if memo is not None and memo[0] == key:  # uncertainty asks twice at one θ (noise_units, noise_shape)
            return memo[1]
        answer = self._additive_noise(theta)
        self._additive_memo = (key, answer)
        return answer

    def _additive_noise(self, theta: Any) -> bool:
        """:meth:`additive_noise`, computed."""
        H = np.asarray(self.data.H)
        try:
            Hm = np.asarray(self.model.frequency_response(theta, self.data.w))
        except Exception:  # a model that cannot be evaluated there: the default shape
            return False
        return residual_noise_model(H, Hm) == "additive"

    def noise_shape(self, theta: Any) -> np.ndarray:
        """|H(ωᵢ, θ)| / (√2 ‖H‖) per part for relative noise; 1 / (√2 ‖H‖) for additive noise
        (:meth:`additive_noise`)."""
        if self.additive_noise(theta):
            a = np.ones(np.asarray(self.data.H).size) / (np.sqrt(2.0) * self._norm())
            return np.concatenate([a, a])
        Hm = np.asarray(self.model.frequency_response(theta, self.data.w))
        a = (self._sqrt_weights() * np.abs(Hm)).ravel() / (np.sqrt(2.0) * self._norm())
        return np.concatenate([a, a])

    def given_noise(self, noise_std: Any) -> tuple[np.ndarray, np.ndarray]:
        """``noise_std``: a number, one per frequency (s,), or (s, p, m); E|eᵢ|² = std² for each complex entry."""
        H = np.asarray(self.data.H)
        arr = broadcast_noise(noise_std, H.shape, f"the frequency response H (s, p, m) = {H.shape}")
        a = (self._sqrt_weights() * arr).ravel() / (np.sqrt(2.0) * self._norm())
        return np.concatenate([a, a]), arr.ravel()

    def uncertainty(self, theta: Any, parameter_names: tuple[str, ...], noise_std: Any = None) -> Uncertainty:
        """As :meth:`FisherInformation.uncertainty`; a noise-weighted fit whose variance is known
        (``line_variance``) takes σ = √variance as the given noise unless ``noise_std`` is given. A variance the
        data estimated with ν degrees of freedom (``estimated_variance_dof``, from ``si.estimate_frf``) is not
        exact: the covariance is then ν/(ν − 4) times larger
        (:func:`~symid.fit.frf.misfit.estimated_variance_inflation`), and not finite for ν ≤ 4 (NaN, with the
        reason in ``note``)."""
        import dataclasses

        from symid.fit.frf.misfit import estimated_variance_inflation

        inflation, dof = 1.0, None
        if noise_std is None and self.line_variance is not None:
            var = np.asarray(self.line_variance, dtype=float)
            dof = self.estimated_variance_dof
            if dof is not None:
                inflation = estimated_variance_inflation(dof)
            noise_std = np.sqrt(var * inflation) if np.isfinite(inflation) else np.sqrt(var)
        # the level from the residuals measures what the shape says: relative to |H|, or in H's units
        self.noise_units = "data units" if noise_std is None and self.additive_noise(theta) else "relative"
        unc = super().uncertainty(theta, parameter_names, noise_std=noise_std)
        if dof is None:
            return unc
        if np.isfinite(inflation):
            said = (f"the data's variance is an estimate with {dof:g} degrees of freedom: the covariance of the fit "
                    f"weighted by it is {inflation:.3g} times the one that takes it as exact")
            return dataclasses.replace(unc, note=f"{unc.note}; {said}" if unc.note else said)
        nan = np.full_like(np.asarray(unc.covariance, dtype=float), np.nan)
        said = (f"intervals withheld: the data's variance is an estimate with {dof:g} degrees of freedom (2 or 3 "
                f"periods), and a fit weighted by it has no finite covariance (4 periods or more are needed); fit "
                f"with variance=None (equal weights; --option variance=none) for intervals, or measure more periods")
        return dataclasses.replace(unc, covariance=nan, standard_errors=np.full(nan.shape[0], np.nan),
                                   intervals=np.full((nan.shape[0], 2), np.nan), shift=None,
                                   note=f"{unc.note}; {said}" if unc.note else said)

    def estimate_sensitivity(self, theta: Any) -> np.ndarray | None:
        """For ``ls``: the first-order map from the noise on H to θ̂ of the equation-error least squares."""
        case = getattr(self, "case", None)
        if self.method != "ls" or case not in ("sensors", "actuators"):
            return None
        theta = np.asarray(theta, dtype=float)
        whitening = getattr(self, "equation_whitening", None)  # the noise-weighted ls: its weights at θ
        G = _ls_sensitivity(self.model, self.data, theta, case, whitening(theta) if callable(whitening) else None)
        sw = self._sqrt_weights().ravel()  # r = √w (H − H(θ)) / ‖√w H‖, so dH = ‖√w H‖ dr / √w
        return G * (self._norm() / np.concatenate([sw, sw]))[None, :]

    def uncertainty_note(self) -> str:
        """Said for the methods that do not minimise the FRF misfit."""
        if self.method in _MINIMISERS:
            return ""
        if self.method == "ls":
            return ("the equation-error least squares (4-10)/(4-11) is not the least-squares estimate of H: the "
                    "covariance is its own, propagated to first order from the noise on H (its estimate is also "
                    "biased by about the noise variance; polish=True gives the efficient estimate)")
        return (f"method {self.method!r} does not minimise the FRF misfit; this is the covariance of the "
                "least-squares estimate, evaluated at its θ̂ (polish=True reaches that estimate)")


def _ls_sensitivity(model: Any, data: Any, theta: np.ndarray, case: str,
                    whitening: list[np.ndarray] | None = None) -> np.ndarray:
    """G (l, 2spm) with dθ̂ = G [Re dH; Im dH] (entries in (s, p, m) order) for the linear least squares of
    thesis (4-10) (sensors: eᵢ = Zᵢ C⁻¹ Ĥᵢ − B(θ)) or (4-11) (actuators: eᵢ = Ĥᵢ B⁻¹ Zᵢ − C(θ)), Ĥ = H / f(ω),
    Z = K − ω²M + jωV (second order) or jωI − A: dθ̂ = −(JₑᵀJₑ)⁻¹ Jₑᵀ de with de linear in dH (the term in
    e·dJₑ is of second order in the noise). ``whitening`` (one matrix Wᵢ per frequency, acting on its flattened
    equations, ``LinearFRF.equation_whitening``) multiplies the equations of the noise-weighted least squares:
    dθ̂ = −(JₑᴴWᴴWJₑ)⁻¹ JₑᴴWᴴW de (real parts; the change of W with the noise is of second order too)."""
    w = np.asarray(data.w, dtype=float)
    H = np.asarray(data.H, dtype=complex)
    _, p, m = H.shape
    maps = model.maps
    l = model.n_parameters
    f = output_factor(model, w)  # (s, p): each output row times (jω)ᵈ
    th = np.asarray(theta, dtype=float)
    rows_J, blocks = [], []
    for i, wi in enumerate(w):
        if "M" in maps:
            Z0 = maps["K"].X0 - wi**2 * maps["M"].X0 + 1j * wi * maps["V"].X0
            Zk = maps["K"].Xi - wi**2 * maps["M"].Xi + 1j * wi * maps["V"].Xi
        else:
            Z0 = 1j * wi * np.eye(maps["A"].shape[0]) - maps["A"].X0
            Zk = -maps["A"].Xi.astype(complex)
        Z = Z0 + np.tensordot(th, Zk, axes=1)
        Hh = H[i] / f[i][:, None]
        if case == "sensors":
            Ci = np.linalg.inv(maps["C"].X0)
            Je = np.einsum("knr,rm->knm", Zk, Ci @ Hh) - maps["B"].Xi      # (l, n, m)
            K = Z @ Ci / f[i][None, :]                                      # de = K dH   (n × p)
            L = np.einsum("ab,jc->ajbc", K, np.eye(m)).reshape(K.shape[0] * m, p * m)
        else:
            Bi = np.linalg.inv(maps["B"].X0)
            Je = np.einsum("pm,kmn->kpn", Hh @ Bi, Zk) - maps["C"].Xi       # (l, p, n)
            K = Bi @ Z                                                      # de = diag(1/f) dH K   (m × n)
            L = np.einsum("ac,bj->ajcb", np.diag(1 / f[i]), K).reshape(p * K.shape[1], p * m)
        Je = Je.reshape(l, -1).T
        if whitening is not None:
            Je, L = whitening[i] @ Je, whitening[i] @ L
        rows_J.append(Je)
        blocks.append(L)
    Jc = np.vstack(rows_J)
    Je_real = np.vstack([Jc.real, Jc.imag])

    Lc = scipy.linalg.block_diag(*blocks)
    L_real = np.block([[Lc.real, -Lc.imag], [Lc.imag, Lc.real]])
    return -np.linalg.lstsq(Je_real, L_real, rcond=None)[0]
