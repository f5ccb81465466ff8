"""Floating-point local identifiability: rank of the frequency-response Jacobian.

A cheap screen for large models (where exact rational arithmetic is too slow) and for
the warning :func:`symid.identify` gives before estimating. At a random parameter point
and a spread of test frequencies, the Jacobian of vec(H(ωᵢ, θ)) (real and imaginary
parts) with respect to θ is formed from the affine maps:

- state space, Z = jωI − A:  ∂H = ∂C Z⁻¹B + C Z⁻¹ ∂A Z⁻¹ B + C Z⁻¹ ∂B + ∂D;
- second order, Z = K − ω²M + jωV, H = f C Z⁻¹ B:  ∂H = f (∂C Z⁻¹B − C Z⁻¹ ∂Z Z⁻¹ B + C Z⁻¹ ∂B).

Columns are scaled to unit norm and the numerical rank is taken with a relative
singular-value threshold. θ_k is flagged when the null space has a component of size
> 1e-6 along it. A floating-point rank is a screen, not a proof: the exact verdict is
:func:`symid.identifiability`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from symid.errors import ModelError
from symid.model.secondorder import output_factor

__all__ = ["NumericLocalResult", "numeric_local_check"]


@dataclass(frozen=True)
class NumericLocalResult:
    """Rank of the frequency-response Jacobian at a random point.

    Attributes
    ----------
    rank : int
        Numerical rank.
    n_parameters : int
        Number of free parameters (columns).
    not_identifiable : tuple of str
        Parameters with a component in the null space.
    singular_values : numpy.ndarray
        Singular values of the column-scaled Jacobian.
    """

    rank: int
    n_parameters: int
    not_identifiable: tuple[str, ...]
    singular_values: np.ndarray


def _jacobian(model: Any, theta: np.ndarray, w: np.ndarray) -> np.ndarray:
    maps = model.maps
    l = model.n_parameters
    rows = []
    if "M" in maps:
        mats = model.matrices(theta)
        M, V, K, B, C = (mats[k] for k in "MVKBC")
        f = output_factor(model, w)  # (s, p): each output row times (jω)ᵈ
        for wi, fi in zip(w, f, strict=True):
            Z = K - wi**2 * M + 1j * wi * V
            ZB = np.linalg.solve(Z, B)
            CZ = np.linalg.solve(Z.T, C.T).T
            dZ = maps["K"].Xi - wi**2 * maps["M"].Xi + 1j * wi * maps["V"].Xi
            d = (np.einsum("kpn,nm->kpm", maps["C"].Xi, ZB) - np.einsum("pn,knr,rm->kpm", CZ, dZ, ZB)
                 + np.einsum("pn,knm->kpm", CZ, maps["B"].Xi))
            rows.append((fi[None, :, None] * d).reshape(l, -1))
    else:
        A, B, C, _ = model.state_space(theta)
        n = A.shape[0]
        for wi in w:
            Z = 1j * wi * np.eye(n) - A
            ZB = np.linalg.solve(Z, B)
            CZ = np.linalg.solve(Z.T, C.T).T
            d = (np.einsum("kpn,nm->kpm", maps["C"].Xi, ZB) + np.einsum("pn,knr,rm->kpm", CZ, maps["A"].Xi, ZB)
                 + np.einsum("pn,knm->kpm", CZ, maps["B"].Xi) + maps["D"].Xi)
            rows.append(d.reshape(l, -1))
    J = np.concatenate(rows, axis=1).T
    return np.vstack([J.real, J.imag])


def numeric_local_check(model: Any, *, known: Mapping[str, float] | None = None, w: Any = None, seed: int = 0,
                        rtol: float = 1e-8) -> NumericLocalResult:
    """Screen a model for locally non-identifiable parameters in floating point.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    known : dict of str to float, optional
        Parameters fixed at these values: their columns are left out.
    w : array_like, optional
        Test frequencies (rad/s); default log-spaced in 0.05–20 rad/s, enough for three
        times as many real equations as parameters and at least 2n + 4 of them.
    seed : int
        Seed of the random point (positive parameters drawn in 0.5–2, others in ±(0.5–2)).
    rtol : float
        Relative singular-value threshold of the numerical rank.

    Returns
    -------
    NumericLocalResult

    Raises
    ------
    ModelError
        When the frequency response is singular or not finite at every one of 10
        random points (a degenerate model).

    Examples
    --------
    >>> import symid as si
    >>> from symid.structural.numeric import numeric_local_check
    >>> a, b, c = si.parameters("a b c", positive=True)
    >>> numeric_local_check(si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[c]])).not_identifiable
    ('b', 'c')
    """
    l = model.n_parameters
    known = dict(known or {})
    free = [k for k, name in enumerate(model.parameter_names) if name not in known]
    if not free:
        return NumericLocalResult(0, 0, (), np.zeros(0))
    rng = np.random.default_rng(seed)
    if w is None:
        per = 2 * model.n_outputs * model.n_inputs
        count = max(2 * model.n_states + 4, -(-3 * l // per) + 4)
        freqs = np.logspace(np.log10(0.05), np.log10(20.0), count)
    else:
        freqs = np.asarray(w, dtype=float)
    fixed = np.array([known.get(name, np.nan) for name in model.parameter_names], dtype=float)
    for _ in range(10):
        theta = rng.uniform(0.5, 2.0, l)
        signs = np.where(np.array(model.positive, dtype=bool), 1.0, rng.choice([-1.0, 1.0], l))
        theta = np.where(np.isnan(fixed), theta * signs, fixed)
        try:
            J = _jacobian(model, theta, freqs)[:, free]
        except np.linalg.LinAlgError:
            continue
        if np.all(np.isfinite(J)):
            break
    else:  # pragma: no cover - degenerate models only; never reported as "nothing identifiable"
        raise ModelError("the frequency response is singular or not finite at 10 random parameter points "
                         f"({freqs.size} test frequencies in {freqs.min():g}–{freqs.max():g} rad/s): no rank to take")
    nf = len(free)
    norms = np.linalg.norm(J, axis=0)
    zero_cols = norms == 0
    Js = J / np.where(zero_cols, 1.0, norms)
    _, s, vt = np.linalg.svd(Js, full_matrices=Js.shape[0] < nf)
    rank = int(np.sum(s > rtol * s[0])) if s.size and s[0] > 0 else 0
    null = vt[rank:]
    flagged = np.any(np.abs(null) > 1e-6, axis=0) | zero_cols if null.size else zero_cols
    names = tuple(model.parameter_names[k] for k, f in zip(free, flagged, strict=True) if f)
    return NumericLocalResult(rank, nf, names, s)
