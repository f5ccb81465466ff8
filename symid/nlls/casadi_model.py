"""Model matrices and frequency responses as CasADi expressions of θ (real arithmetic)."""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

__all__ = ["casadi_frf", "casadi_matrices"]


def casadi_matrices(model: Any, theta: ca.MX) -> dict[str, ca.MX]:
    """Every affine matrix X(θ) = X0 + Σ θi Xi as a CasADi expression."""
    out = {}
    for name, amap in model.maps.items():
        X = ca.MX(ca.DM(amap.X0))
        for k in amap.depends_on:
            X = X + theta[k] * ca.DM(amap.Xi[k])
        out[name] = X
    return out


def casadi_frf(model: Any, theta: ca.MX, w: np.ndarray) -> tuple[list[ca.MX], list[ca.MX]]:
    """Real and imaginary parts of H(ωᵢ, θ), one (p, m) expression per frequency.

    A state-space model solves (jωI − A) X = B in the real form
    [[−A, −ωI], [ωI, −A]] [Xr; Xi] = [B; 0]; a second-order model solves
    (K − ω²M + jωV) X = B as [[K − ω²M, −ωV], [ωV, K − ω²M]] [Xr; Xi] = [B; 0], then
    multiplies by jω or −ω² for velocity or acceleration outputs.
    """
    mats = casadi_matrices(model, theta)
    Hr, Hi = [], []
    if "M" in mats:
        M, V, K, B, C = (mats[k] for k in "MVKBC")
        n, m = model.n_dof, model.n_inputs
        for wi in w:
            R = K - wi**2 * M
            S = wi * V
            big = ca.vertcat(ca.horzcat(R, -S), ca.horzcat(S, R))
            X = ca.solve(big, ca.vertcat(B, ca.MX(n, m)))
            hr, hi = C @ X[:n, :], C @ X[n:, :]
            if model.output == "velocity":
                hr, hi = -wi * hi, wi * hr
            elif model.output == "acceleration":
                hr, hi = -(wi**2) * hr, -(wi**2) * hi
            Hr.append(hr)
            Hi.append(hi)
    else:
        A, B, C, D = (mats[k] for k in "ABCD")
        n, m = model.n_states, model.n_inputs
        eye = ca.DM.eye(n)
        for wi in w:
            big = ca.vertcat(ca.horzcat(-A, -wi * eye), ca.horzcat(wi * eye, -A))
            X = ca.solve(big, ca.vertcat(B, ca.MX(n, m)))
            Hr.append(C @ X[:n, :] + D)
            Hi.append(C @ X[n:, :])
    return Hr, Hi
