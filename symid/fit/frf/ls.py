"""Linear least squares for frequency responses when a known square matrix can be inverted.

Thesis §4-5-1, (4-10) and (4-11), generalised: the inverted matrix (C or B) must be known
(free of parameters), square and invertible; everything else may hold parameters, and
the problem stays linear in θ.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from symid.errors import ModelError
from symid.fit.frf.misfit import VARIANCE_OPTION_DOC, FrfEstimator, NoiseWeighted
from symid.fit.options import check_bool, check_choice, check_time_limit
from symid.fit.result import StartOutcome
from symid.fit.similarity.data import budget_message
from symid.model.secondorder import output_factor

__all__ = ["LinearFRF", "equation_residual", "ls_applicable"]

_GLS_MAX = 50  # solves of the iterated noise-weighted least squares (class text)


def _known_invertible(amap: Any) -> bool:
    r, c = amap.shape
    if r != c or not amap.is_constant:
        return False
    return bool(np.linalg.matrix_rank(amap.X0) == r and np.linalg.cond(amap.X0) < 1e12)


def ls_applicable(model: Any) -> str | None:
    """Which linear special case applies: ``"sensors"`` (C known, square, invertible),
    ``"actuators"`` (B known, square, invertible) or ``None``."""
    maps = model.maps
    if "D" in maps and not (maps["D"].is_constant and not np.any(maps["D"].X0)):
        return None
    if _known_invertible(maps["C"]):
        return "sensors"
    if _known_invertible(maps["B"]):
        return "actuators"
    return None


def _why_not(model: Any) -> str:
    reasons = []
    for name in ("C", "B"):
        amap = model.maps[name]
        r, c = amap.shape
        if r != c:
            reasons.append(f"{name} is {r}×{c}, not square")
        elif not amap.is_constant:
            reasons.append(f"{name} holds parameters")
        else:
            reasons.append(f"{name} is singular")
    if "D" in model.maps and not (model.maps["D"].is_constant and not np.any(model.maps["D"].X0)):
        reasons.append("D is not zero")
    return "; ".join(reasons)


class LinearFRF(NoiseWeighted, FrfEstimator):
    """The linear least-squares estimate (thesis (4-10)/(4-11) and their state-space analogue).

    For a second-order model, with Z(ω, θ) = K(θ) − ω²M(θ) + jωV(θ) and Ĥ the
    measured response divided by 1, jω or −ω² (position, velocity, acceleration):

    - sensors (C known, invertible): Σᵢ ‖Z(ωᵢ, θ) C⁻¹ Ĥᵢ − B(θ)‖²_F  (4-10)
    - actuators (B known, invertible): Σᵢ ‖Ĥᵢ B⁻¹ Z(ωᵢ, θ) − C(θ)‖²_F  (4-11)

    For a state-space model (D = 0) the same with Z(ω, θ) = jωI − A(θ).
    Both are linear in θ; real and imaginary parts are stacked and solved by
    ``numpy.linalg.lstsq``. Exact on noise-free data.

    Declared positivity is honoured: when the unconstrained solution has a parameter
    declared ``positive=True`` below zero, the bounded least squares θₖ ≥ 0 (for those
    parameters) is solved instead (:func:`scipy.optimize.lsq_linear`, bounded-variable
    least squares on the column-scaled problem), and the message names the bounds that
    are active. Like every method, the result is a success only when it fits the data
    and is physical (:func:`symid.fit.success.physical_check`): a parameter pinned at 0
    that the data wanted negative usually leaves a large misfit, which is then reported
    as a failure, never as a success.

    Noise weighting (``variance``): generalised least squares on the equation error.
    Noise dH on the data enters (4-10) as eᵢ = Zᵢ C⁻¹ dHᵢ / fᵢ and (4-11) as
    eᵢ = dHᵢ B⁻¹ Zᵢ / fᵢ (fᵢ = 1, jωᵢ, −ωᵢ² for position, velocity, acceleration), so
    column k of eᵢ (sensors; input k) has the covariance
    Sᵢₖ = G diag(σ²ᵢ,:,k) Gᴴ / |fᵢ|² with G = Z(ωᵢ, θ) C⁻¹, and row j (actuators;
    output j) the same with G = Z(ωᵢ, θ)ᵀ B⁻ᵀ and σ²ᵢ,j,:. Each column (row) is
    multiplied by S^-½ (to first order in the noise the equation errors are then
    independent, of unit variance: the Gauss–Markov weighting). S depends on θ through
    Z, so θ̂ is iterated: the unweighted solution, then S at the last θ̂, until θ̂ moves by
    less than 1e-12 (relative, on unit-norm columns; at most 50 solves, typically 3–6).
    Weighting by 1/σᵢ alone would not do: the equation error carries Zᵢ dHᵢ, and |Zᵢ|
    ~ 1/|Hᵢ| spans decades across a resonance (tried first, on the one-mass model of
    ``benchmarks/frf_weighting.py`` with σᵢ/|Hᵢ| rising 30-fold over the band: a mean
    squared parameter error 3–6 times that of equal weights, 6 × 50 records; with S:
    about half of it, and about 0.005 of it when the noise steps 30-fold at mid-band,
    ``benchmarks/frf_weighting.py``). It is not the
    maximum-likelihood estimate (the regressors hold the noisy H too; ``polish=True``
    is IPOPT on the same weights). ``misfit``, the success rule (judged against the
    declared noise) and the uncertainty (propagated through the weighted solve, the
    variance as the given noise) use the same variance; the bounded least squares of
    ``positivity`` runs on the weighted equations.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    data : FrequencyData
    case : {"sensors", "actuators"}, optional
        Which known matrix is inverted; default: the one that applies (sensors first).
    positivity : bool, optional
        Keep the parameters declared ``positive=True`` ≥ 0 (default True; bounded least squares).
        ``False`` returns the unconstrained solution, never a success when a declared-positive
        parameter comes out negative.
    {variance}
    time_limit : float, optional
        Wall-time budget of one run in seconds, checked after every solve of the
        noise-weighted iteration (status ``"time_limit"``; the last solve's estimate is
        kept, not weighted to its fixed point, so the run is not finished; it is a success
        only if that estimate fits the data). Default: none (one solve without a variance;
        with one, 3–6 measured, at most 50).
    callback : callable, optional
        Called after every solve with a :class:`symid.engine.scr.ScrProgress` (solve,
        residual ‖Jθ + r₀‖ / ‖|r₀| + |J| |θ|‖ of the (weighted) linear equations relative
        to the size of their terms, data misfit, elapsed seconds, θ); the bounded least
        squares of ``positivity`` is one more solve. A true return value stops the
        noise-weighted iteration (status ``"stopped"``).
    verbose : bool, optional
        Print one line per solve (solve, residual, misfit, elapsed). Default False.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.frf.ls import LinearFRF
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, [2.0, 0.5, 3.0], np.linspace(0.5, 2.0, 5))
    >>> np.round(LinearFRF(model, frf).run().theta, 6).tolist()
    [2.0, 0.5, 3.0]
    """

    method = "ls"

    def __init__(self, model: Any, data: Any, *, case: str | None = None, positivity: bool = True,
                 variance: Any = "data", time_limit: float | None = None, callback: Any = None,
                 verbose: bool = False):
        if case is None:
            case = ls_applicable(model)
        if case is None:
            raise ModelError("the linear least-squares special case needs C or B known (no parameters), square and "
                             f"invertible, and D = 0; here: {_why_not(model)}. Use method='scr' or 'ipopt'.")
        case = check_choice("case", case, ("sensors", "actuators"))
        if case == "sensors" and not _known_invertible(model.maps["C"]):
            raise ModelError(f"case='sensors' needs C known, square and invertible; here: {_why_not(model)}")
        if case == "actuators" and not _known_invertible(model.maps["B"]):
            raise ModelError(f"case='actuators' needs B known, square and invertible; here: {_why_not(model)}")
        self.model, self.data, self.case = model, data, case
        self.positivity = check_bool("positivity", positivity)
        self.time_limit = check_time_limit("time_limit", time_limit)
        self._progress_options(callback, verbose)
        label = self.set_variance(variance)
        self.options = {"case": case, "positivity": self.positivity, "variance": label,
                        "time_limit": self.time_limit, "callback": None if callback is None else "given",
                        "verbose": self._verbose}
        w = np.asarray(data.w, dtype=float)
        H = np.asarray(data.H, dtype=complex)
        second = "M" in model.maps
        out = getattr(model, "output", "position")
        if out != "position" and np.any(w == 0):
            raise ModelError(f"{out} output: H is zero at ω = 0 and cannot be divided back; drop ω = 0")
        factor = output_factor(model, w)  # (s, p): each output row times (jω)ᵈ
        Hh = H / factor[:, :, None]
        maps = model.maps
        l = model.n_parameters
        rows0, rowsJ, self._Z = [], [], []
        for i, wi in enumerate(w):
            if second:
                Z0 = maps["K"].X0 - wi**2 * maps["M"].X0 + 1j * wi * maps["V"].X0
                Zi = maps["K"].Xi - wi**2 * maps["M"].Xi + 1j * wi * maps["V"].Xi
            else:
                n = maps["A"].shape[0]
                Z0 = 1j * wi * np.eye(n) - maps["A"].X0
                Zi = -maps["A"].Xi.astype(complex)
            if case == "sensors":
                G = np.linalg.solve(maps["C"].X0, Hh[i])          # C⁻¹ Ĥ = Γ
                r0 = Z0 @ G - maps["B"].X0
                rJ = Zi @ G - maps["B"].Xi
            else:
                G = Hh[i] @ np.linalg.inv(maps["B"].X0)           # Ĥ B⁻¹ = C Z⁻¹
                r0 = G @ Z0 - maps["C"].X0
                rJ = np.einsum("pn,knm->kpm", G, Zi) - maps["C"].Xi
            self._Z.append((Z0, Zi))
            rows0.append(r0.reshape(-1))
            rowsJ.append(rJ.reshape(l, -1).T)
        self._rows0, self._rowsJ, self._factor = rows0, rowsJ, factor
        r0 = np.concatenate(rows0)
        J = np.vstack(rowsJ)
        self._J = np.vstack([J.real, J.imag])
        self._r0 = np.concatenate([r0.real, r0.imag])
        norms = np.linalg.norm(self._J, axis=0)  # unit-norm columns: the solution does not depend on units
        self._norms = np.where(norms > 0, norms, 1.0)
        rank = np.linalg.matrix_rank(self._J / self._norms)
        if rank < l:
            raise ModelError(f"the linear least-squares problem has rank {rank} < {l} parameters: the data do not "
                             f"determine θ (add frequencies, or check identifiability)")

    def equation_whitening(self, theta: Any) -> list[np.ndarray] | None:
        """Per frequency, the matrix Wᵢ that multiplies the (flattened) equations of ωᵢ in the noise-weighted
        solve at θ: block-diagonal, S^-½ for every column (sensors) or row (actuators) of the equation error
        (class text); ``None`` without a variance."""
        var = self.variance_shape  # the noise up to one factor, which leaves the weighted solve unchanged
        if var is None:
            return None
        th = np.asarray(theta, dtype=float)
        maps = self.model.maps
        out = []
        for i, (Z0, Zi) in enumerate(self._Z):
            Z = Z0 + np.tensordot(th, Zi, axes=1)
            if self.case == "sensors":
                G = Z @ np.linalg.inv(maps["C"].X0) / self._factor[i][None, :]  # e[:, k] = G diag(1/f) dH[:, k]
                S = np.einsum("ap,kp,bp->kab", G, var[i].T, G.conj())
            else:
                G = Z.T @ np.linalg.inv(maps["B"].X0).T                  # e[j, :]ᵀ = G dH[j, :]ᵀ / f_j
                S = np.einsum("am,jm,bm->jab", G, var[i], G.conj()) / (abs(self._factor[i]) ** 2)[:, None, None]
            vals, vecs = np.linalg.eigh(S)
            top = np.max(vals, axis=1, keepdims=True)
            vals = np.maximum(vals, 1e-12 * np.where(top > 0, top, 1.0))  # a singular Z(θ, ωᵢ): no blow-up
            Winv = np.einsum("kab,kb,kcb->kac", vecs, vals**-0.5, vecs.conj())
            q = Winv.shape[0]
            if self.case == "sensors":  # entries (a, k) of e, k-th block
                W = np.einsum("kab,kl->akbl", Winv, np.eye(q))
            else:                       # entries (j, a) of e, j-th block
                W = np.einsum("jab,jl->jalb", Winv, np.eye(q))
            out.append(W.reshape(W.shape[0] * W.shape[1], -1))
        return out

    def _weighted_system(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """J and r0 (real and imaginary parts) of the equations multiplied by their whitening at θ."""
        Ws = self.equation_whitening(theta)
        J = np.vstack([W @ rJ for W, rJ in zip(Ws, self._rowsJ, strict=True)])
        r0 = np.concatenate([W @ r for W, r in zip(Ws, self._rows0, strict=True)])
        return np.vstack([J.real, J.imag]), np.concatenate([r0.real, r0.imag])

    def _gls(self, theta: np.ndarray, report: Any = None, deadline: float | None = None
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, str]:
        """The iterated noise-weighted solution from ``theta`` (the unweighted solution, solve 1; class text):
        θ̂, its J and r0, the solves and the status: ``"solved"`` (θ̂ moved less than 1e-12, or 50 solves),
        ``"stopped"`` (``report`` returned True after a solve) or ``"time_limit"`` (``deadline`` passed after a
        solve with more to do)."""
        norms = self._norms
        solves = 1  # the unweighted solution that started it
        asked = report is not None and report(1, equation_residual(self._J, self._r0, theta), theta)
        J, r0 = self._J, self._r0
        while solves < _GLS_MAX + 1:
            if asked:
                return theta, J, r0, solves, "stopped"
            if deadline is not None and time.perf_counter() >= deadline:
                return theta, J, r0, solves, "time_limit"
            solves += 1
            J, r0 = self._weighted_system(theta)
            cn = np.linalg.norm(J, axis=0)
            cn = np.where(cn > 0, cn, 1.0)
            new = np.linalg.lstsq(J / cn, -r0, rcond=None)[0] / cn
            done = np.linalg.norm((new - theta) * norms) <= 1e-12 * np.linalg.norm(new * norms)
            theta = new
            asked = report is not None and report(solves, equation_residual(J, r0, theta), theta)
            if done:
                break
        return theta, J, r0, solves, "solved"

    def _bounded(self, pos: np.ndarray, J: np.ndarray, r0: np.ndarray) -> tuple[np.ndarray, str]:
        """min ‖Jθ + r0‖ with θₖ ≥ 0 where ``pos``: bounded-variable least squares on unit-norm columns."""
        from scipy.optimize import lsq_linear

        norms = np.linalg.norm(J, axis=0)
        norms = np.where(norms > 0, norms, 1.0)
        lower = np.where(pos, 0.0, -np.inf)
        sol = lsq_linear(J / norms, -r0, bounds=(lower, np.inf), method="bvls")
        theta = sol.x / norms
        theta[pos] = np.maximum(theta[pos], 0.0)
        active = [n for n, a in zip(self.model.parameter_names, sol.active_mask, strict=True) if a != 0]
        how = f"bounded least squares (θ ≥ 0 for declared-positive parameters; at the bound: " \
              f"{', '.join(active) or 'none'})"
        return theta, how

    def run(self, x0: np.ndarray | None = None) -> StartOutcome:
        """Solve the least squares (the start is irrelevant; kept for a uniform signature).

        Without a variance, one solve; with one, the noise-weighted iteration (class text),
        which ``time_limit`` and ``callback`` may stop after any solve (status
        ``"time_limit"`` or ``"stopped"``, not finished; a success only if the estimate
        fits). The bounded least squares of ``positivity`` is applied to the estimate kept
        in every case.
        """
        t0 = time.perf_counter()
        deadline = None if self.time_limit is None else t0 + self.time_limit
        report = self.progress_reporter(t0)
        theta = np.linalg.lstsq(self._J / self._norms, -self._r0, rcond=None)[0] / self._norms
        J, r0, solves, status, asked = self._J, self._r0, 1, "solved", False
        start = np.zeros(self.model.n_parameters) if x0 is None else np.asarray(x0, dtype=float)
        msg = f"linear least squares ({self.case} case)"
        if self.variance_shape is not None:
            theta, J, r0, solves, status = self._gls(theta, report, deadline)
            msg = (f"linear least squares ({self.case} case), noise-weighted: generalised least squares on the "
                   f"equation error, {solves} solves")
            if status == "time_limit":
                msg += "; " + budget_message(self.time_limit, solves, "solve") + " (not weighted to its fixed point)"
            elif status == "stopped":
                msg += f"; stopped by the callback after {solves} solves (not weighted to its fixed point)"
        elif report is not None:  # one solve: nothing left for a stop to cut short
            asked = report(1, equation_residual(J, r0, theta), theta)
        pos = np.array(self.model.positive, dtype=bool)
        negative = [n for n, p, v in zip(self.model.parameter_names, pos, theta, strict=True) if p and v < 0]
        iterations = solves
        if negative and self.positivity:
            theta, how = self._bounded(pos, J, r0)
            iterations += 1
            msg += f"; the unconstrained solution had {', '.join(negative)} < 0: {how}"
            if report is not None and status == "solved" and not asked:
                report(iterations, equation_residual(J, r0, theta), theta)
        elif negative:
            msg += f"; parameters declared positive came out negative: {', '.join(negative)} (positivity=False)"
        return self.outcome(start, theta, finished=status == "solved", status=status, message=msg,
                            iterations=iterations, wall_time=time.perf_counter() - t0)


def equation_residual(J: np.ndarray, r0: np.ndarray, theta: np.ndarray) -> float:
    """‖Jθ + r₀‖ / ‖|r₀| + |J| |θ|‖: the residual of the linear equations Jθ + r₀ = 0 relative to the size of
    their terms (0 when every term is 0).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.frf.ls import equation_residual
    >>> equation_residual(np.array([[1.0]]), np.array([-3.0]), np.array([1.0]))     # |1 − 3| / (3 + 1)
    0.5
    """
    top = float(np.linalg.norm(J @ theta + r0))
    size = float(np.linalg.norm(np.abs(r0) + np.abs(J) @ np.abs(theta)))
    return top / size if size > 0 else 0.0


LinearFRF.__doc__ = (LinearFRF.__doc__ or "").replace("{variance}", VARIANCE_OPTION_DOC)
