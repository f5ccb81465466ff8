"""The similarity misfit (C-1) and its analytic gradients (C-12)–(C-18).

    F(θ, T) = ‖T𝔸 − A(θ)T‖²_F + ‖T𝔹 − B(θ)‖²_F + ‖ℂ − C(θ)T‖²_F  (+ ‖𝔻 − D(θ)‖²_F)

The last term appears only when D holds parameters (the thesis's models have D = 0).
Gradients, with R_A = T𝔸 − A(θ)T, R_B = T𝔹 − B(θ), R_C = ℂ − C(θ)T:

    ∇_T F = 2 (R_A 𝔸ᵀ − A(θ)ᵀ R_A) + 2 R_B 𝔹ᵀ − 2 C(θ)ᵀ R_C                       (C-12)
    ∂F/∂θᵢ = −2 tr(M_Aᵀ Aᵢ) − 2 tr(M_Bᵀ Bᵢ) − 2 tr(M_Cᵀ Cᵢ)                     (C-15)
    M_A = R_A Tᵀ,  M_B = R_B,  M_C = R_C Tᵀ                                     (C-16)–(C-18)

(C-12) expanded is 2(T𝔸𝔸ᵀ − A T𝔸ᵀ − AᵀT𝔸 + AᵀAT) + 2(CᵀCT − Cᵀℂ) + 2(T𝔹𝔹ᵀ − B𝔹ᵀ);
the thesis prints the last bracket as T𝔹ᵀ𝔹 − Bᵀ𝔹, which does not conform for m ≠ n —
a transcription slip; the form above is the derivative of ‖T𝔹 − B‖².
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["SimilarityMisfit"]


class SimilarityMisfit:
    """F(θ, T) of (C-1) for one model and black box, on the stacked vector z = (θ, vec T).

    ``vec T`` is row-major (``T.ravel()``). ``scale`` divides F so that its size does not
    depend on the units of the black box: F / (‖𝔸‖² + ‖𝔹‖² + ‖ℂ‖²).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.similarity.objective import SimilarityMisfit
    >>> a = si.parameters("a")
    >>> model = si.StateSpaceModel(A=[[-a]], B=[[1]], C=[[1]])
    >>> F = SimilarityMisfit(model.maps, si.BlackBox([[-2.0]], [[0.5]], [[2.0]]))
    >>> float(F.value(np.array([2.0]), np.array([[2.0]])))      # T = 2 maps the black box to the model
    0.0
    """

    def __init__(self, maps: dict[str, Any], bb: Any):
        self.maps = maps
        self.bb = bb
        self.n = bb.n_states
        self.l = maps["A"].Xi.shape[0]
        self.with_d = "D" in maps and not maps["D"].is_constant
        self.scale = float(np.sum(bb.A**2) + np.sum(bb.B**2) + np.sum(bb.C**2)) or 1.0

    def split(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(θ, T) from z = (θ, vec T)."""
        return z[: self.l], z[self.l:].reshape(self.n, self.n)

    def join(self, theta: np.ndarray, T: np.ndarray) -> np.ndarray:
        """z = (θ, vec T)."""
        return np.concatenate([np.asarray(theta, dtype=float).reshape(-1), np.asarray(T, dtype=float).ravel()])

    def residuals(self, theta: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, ...]:
        """R_A, R_B, R_C (and R_D) at (θ, T)."""
        m, bb = self.maps, self.bb
        A, B, C = m["A"](theta), m["B"](theta), m["C"](theta)
        out = (T @ bb.A - A @ T, T @ bb.B - B, bb.C - C @ T)
        if self.with_d:
            out = (*out, bb.D - m["D"](theta))
        return out

    def value(self, theta: np.ndarray, T: np.ndarray) -> float:
        """F(θ, T) (unscaled)."""
        return float(sum(np.sum(R**2) for R in self.residuals(theta, T)))

    def relative_residual(self, theta: np.ndarray, T: np.ndarray) -> float:
        """√(F(θ, T) / scale): the residual of the similarity equations relative to the black box's size
        (what ALS, GB and IPOPT report per iteration)."""
        return float(np.sqrt(self.value(theta, T) / self.scale))

    def value_and_grad(self, z: np.ndarray) -> tuple[float, np.ndarray]:
        """F/scale and its gradient in z, from (C-12) and (C-15)."""
        theta, T = self.split(z)
        m, bb = self.maps, self.bb
        A, C = m["A"](theta), m["C"](theta)
        res = self.residuals(theta, T)
        RA, RB, RC = res[:3]
        f = float(sum(np.sum(R**2) for R in res))
        gT = 2 * (RA @ bb.A.T - A.T @ RA) + 2 * RB @ bb.B.T - 2 * C.T @ RC  # (C-12)
        MA, MB, MC = RA @ T.T, RB, RC @ T.T  # (C-16)–(C-18)
        gth = -2 * (np.einsum("ij,kij->k", MA, m["A"].Xi) + np.einsum("ij,kij->k", MB, m["B"].Xi)
                    + np.einsum("ij,kij->k", MC, m["C"].Xi))  # (C-15)
        if self.with_d:
            gth = gth - 2 * np.einsum("ij,kij->k", res[3], m["D"].Xi)
        return f / self.scale, np.concatenate([gth, gT.ravel()]) / self.scale
