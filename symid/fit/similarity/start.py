"""Initial similarity transforms (T₀, S₀) shared by every similarity method, so starts are identical.

A start of :func:`symid.identify` is a parameter vector x₀. The similarity methods work
on (θ, T) (and SCR also on S, its substitute for T⁻¹); they derive the same (θ₀, T₀, S₀)
from x₀, in one of four ways (``aux_init``):

``"random"`` (no prior knowledge, thesis §6-6-2 and §6-7-1)
    When x₀ already explains the black box — F(x₀, T) ≤ 1e-12 of the energy of its
    terms for the least-squares T of x₀, e.g. the truth on noise-free data — the start is
    kept as ``"model"`` would keep it. Otherwise
    T₀ = α G₁ and S₀ = G₂ / α with G₁, G₂ independent N(0, 1) matrices ("S and T with
    entries drawn from a random distribution"), seeded by ``seed`` and the bytes of x₀,
    so the same x₀ gives the same T₀, S₀ in every method and every run; θ₀ =
    argmin_θ F(θ, T₀), the least squares (C-8). α is the scale the data imply for T
    (:func:`transform_scale`), so that T₀ and S₀ = T₀⁻¹-sized draws are both plausible.
``"model"`` (prior knowledge on θ, thesis §6-7-2)
    θ₀ = x₀, T₀ = argmin_T F(θ₀, T), the least squares (C-7), and S₀ = T₀⁺.
``"zero"``, ``"identity"``
    T₀ = S₀ = 0 or I (thesis §6-6-2 reports that zero fails); θ₀ by (C-8).

F is the similarity misfit (C-1), ‖T𝔸 − A(θ)T‖² + ‖T𝔹 − B(θ)‖² + ‖ℂ − C(θ)T‖²
(+ ‖𝔻 − D(θ)‖² when D holds parameters).
"""

from __future__ import annotations

import zlib
from typing import Any

import numpy as np

from symid.errors import ModelError

__all__ = ["INITS", "initial_point", "least_squares_theta", "least_squares_transform", "random_pair",
           "transform_scale", "unknown_scale"]

INITS = ("random", "model", "zero", "identity")
_EXPLAINS = 1e-12  # relative similarity misfit below which a start explains the black box ("random" keeps it)


def least_squares_transform(maps: dict[str, Any], bb: Any, theta: np.ndarray) -> np.ndarray:
    """T minimising ‖T𝔸 − A(θ)T‖² + ‖T𝔹 − B(θ)‖² + ‖ℂ − C(θ)T‖² for fixed θ (thesis (C-7)).

    Column-major vec: vec(T X) = (Xᵀ ⊗ I) vec T and vec(Y T) = (I ⊗ Y) vec T.
    """
    A, B, C = (maps[k](theta) for k in "ABC")
    n = A.shape[0]
    eye = np.eye(n)
    lhs = np.vstack([np.kron(bb.A.T, eye) - np.kron(eye, A), np.kron(bb.B.T, eye), np.kron(eye, C)])
    rhs = np.concatenate([np.zeros(n * n), B.ravel(order="F"), bb.C.ravel(order="F")])
    return np.linalg.lstsq(lhs, rhs, rcond=None)[0].reshape(n, n, order="F")


def random_pair(n: int, x0: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Two independent N(0, 1) n×n matrices, seeded by ``seed`` and the bytes of the start x₀."""
    key = zlib.crc32(np.ascontiguousarray(x0, dtype=float).tobytes())
    rng = np.random.default_rng([int(seed), key])
    return rng.standard_normal((n, n)), rng.standard_normal((n, n))


def least_squares_theta(maps: dict[str, Any], bb: Any, T: np.ndarray) -> np.ndarray:
    """θ minimising F(θ, T) for fixed T (thesis (C-8)); when not unique, the solution of least norm in
    parameters scaled to unit columns (so that neither the rank decision nor the choice depends on the
    parameters' units)."""
    J, r = theta_system(maps, bb, T)
    cols = np.linalg.norm(J, axis=0)
    cols = np.where((cols > 0) & np.isfinite(cols), cols, 1.0)
    return np.linalg.lstsq(J / cols, r, rcond=None)[0] / cols


def theta_system(maps: dict[str, Any], bb: Any, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(J, r) with F(θ, T) = ‖J θ − r‖² (the residual of (C-1) is affine in θ)."""
    mA, mB, mC = maps["A"], maps["B"], maps["C"]
    cols = [np.concatenate([(Ai @ T).ravel(), Bi.ravel(), (Ci @ T).ravel()]) for Ai, Bi, Ci in
            zip(mA.Xi, mB.Xi, mC.Xi, strict=True)]
    r = np.concatenate([(T @ bb.A - mA.X0 @ T).ravel(), (T @ bb.B - mB.X0).ravel(), (bb.C - mC.X0 @ T).ravel()])
    J = np.array(cols).T.reshape(r.size, len(cols))
    if "D" in maps and not maps["D"].is_constant:
        J = np.vstack([J, maps["D"].Xi.reshape(len(cols), -1).T])
        r = np.concatenate([r, (bb.D - maps["D"].X0).ravel()])
    return J, r


def transform_scale(maps: dict[str, Any], bb: Any) -> float:
    """The scale α of a similarity transform T with T𝔹 = B(θ) and ℂ = C(θ)T, from the known parts.

    If T were α times an orthogonal matrix, ‖B‖ = α‖𝔹‖ and ‖ℂ‖ = α‖C‖. With the
    constant parts B₀, C₀ of the model (the known entries), α₁ = ‖B₀‖/‖𝔹‖ and
    α₂ = ‖ℂ‖/‖C₀‖; α is their geometric mean, the one available, or 1 when both are zero.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> a = si.parameters("a")
    >>> model = si.StateSpaceModel(A=[[-a]], B=[[1]], C=[[1]])
    >>> transform_scale(model.maps, si.BlackBox([[-2.0]], [[0.25]], [[4.0]]))
    4.0
    """
    nb, nc = float(np.linalg.norm(bb.B)), float(np.linalg.norm(bb.C))
    b0, c0 = float(np.linalg.norm(maps["B"].X0)), float(np.linalg.norm(maps["C"].X0))
    est = []
    if b0 > 0 and nb > 0:
        est.append(b0 / nb)
    if c0 > 0 and nc > 0:
        est.append(nc / c0)
    return float(np.sqrt(np.prod(est))) if len(est) == 2 else (est[0] if est else 1.0)


def initial_point(init: str, x0: np.ndarray, seed: int, maps: dict[str, Any], bb: Any
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(θ₀, T₀, S₀) for the start x₀ (see the module notes).

    Parameters
    ----------
    init : {"random", "model", "zero", "identity"}
    x0 : numpy.ndarray
        The start from :func:`symid.fit.starts.make_starts` (θ₀ itself for ``"model"``).
    seed : int
        Seed of the random T₀, S₀.
    maps : dict
        The model's state-space affine maps A, B, C (and D).
    bb : BlackBox
        The black box (𝔸, 𝔹, ℂ, 𝔻).
    """
    x0 = np.asarray(x0, dtype=float)
    n = bb.n_states
    if init == "model":
        T = least_squares_transform(maps, bb, x0)
        return x0, T, np.linalg.pinv(T)
    if init == "random":
        # a start that already explains the black box (to 1e-6 rms) keeps its own T: random T₀ would walk away
        # from it (found on a two-compartment model started at the truth on noise-free records: 'scr' ended at
        # misfit 0.44). The similarity misfit is affine in θ for the least-squares T of the start.
        T = least_squares_transform(maps, bb, x0)
        J, r = theta_system(maps, bb, T)
        resid = J @ x0 - r
        if np.all(np.isfinite(resid)) and float(resid @ resid) <= _EXPLAINS * float(r @ r + (J @ x0) @ (J @ x0)):
            return x0, T, np.linalg.pinv(T)
        alpha = transform_scale(maps, bb)
        G1, G2 = random_pair(n, x0, seed)
        T, S = alpha * G1, G2 / alpha
    elif init == "zero":
        T, S = np.zeros((n, n)), np.zeros((n, n))
    elif init == "identity":
        T, S = np.eye(n), np.eye(n)
    else:
        raise ModelError(f"init must be one of {', '.join(map(repr, INITS))}; got {init!r}")
    return least_squares_theta(maps, bb, T), T, S


def unknown_scale(theta0: np.ndarray, T0: np.ndarray, lower: np.ndarray | None = None) -> np.ndarray:
    """Typical magnitudes of z = (θ, vec T) (row-major) at a start, for methods that work on z / s.

    θ: |θ₀| per parameter (:func:`symid.engine.ipopt.start_scale`: where θ₀ is 0, the
    largest finite bound, else 1), so that a parameter declared in other units is the
    same unknown. T: every entry of row i by ‖T₀ᵢ‖ (row i of T maps into the model's state
    i, whose units it carries; rows of 0 take the largest row norm, a T₀ of 0 takes 1).

    Examples
    --------
    >>> import numpy as np
    >>> from symid.fit.similarity.start import unknown_scale
    >>> unknown_scale(np.array([-2e3, 0.5]), np.array([[3.0, 4.0], [0.0, 0.0]])).tolist()
    [2000.0, 0.5, 5.0, 5.0, 5.0, 5.0]
    """
    from symid.engine.ipopt import start_scale

    theta0 = np.asarray(theta0, dtype=float)
    lower = np.full(theta0.size, -np.inf) if lower is None else np.asarray(lower, dtype=float)
    st = start_scale(theta0, lower, np.full(theta0.size, np.inf))
    rows = np.linalg.norm(np.asarray(T0, dtype=float), axis=1)
    rows = np.where(np.isfinite(rows), rows, 0.0)
    top = float(rows.max(initial=0.0))
    rows = np.where(rows > 0, rows, top if top > 0 else 1.0)
    return np.concatenate([st, np.repeat(rows, rows.size)])
