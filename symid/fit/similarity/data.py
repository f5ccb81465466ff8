"""The black box a similarity-transformation formulation works on, checked, and its misfit.

Thesis chapters 6 and 7 start from a continuous-time black box (𝔸, 𝔹, ℂ, 𝔻) in an
unknown state basis. It is given (:class:`~symid.data.BlackBox`) or estimated from
input/output records (:class:`~symid.data.IOData`) by N4SID and the exact zero-order-hold
``d2c`` (steps 1–2 of Algorithms 6.1 and 7.1), with the model's order.

Every similarity method (SCR, ALS, GB, IPOPT) is ranked by one basis-free number, the
mean relative frequency-response misfit of the grey box against the black box,

    (1/s) Σᵢ ‖H_bb(ωᵢ) − H(ωᵢ, θ)‖²_F / ‖H_bb(ωᵢ)‖²_F,

on s = 200 log-spaced frequencies from a tenth of the slowest to ten times the fastest
pole magnitude of the black box. It is zero exactly when the grey box has the black
box's transfer function (6-7), whatever T a method found. Each frequency is weighed
relative to its own gain: with one normalisation for the whole grid (as the FRF
misfit of :func:`symid.fit.frf.misfit.relative_misfit`) the low-frequency gain dominates, and on
the e-nose a grey box 10× off in its parameters scored 2e-9.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from symid.data import BlackBox, FrequencyData, IOData
from symid.errors import DataError, ModelError, OptionError
from symid.fit.base import Estimator
from symid.fit.options import check_bool, check_int
from symid.fit.result import ScrIteration, StartOutcome
from symid.signal.realisation import balanced_realisation, not_minimal

__all__ = ["SimilarityData", "SimilarityEstimator", "budget_message", "similarity_data"]

_GRID_POINTS = 200


@dataclass(frozen=True, eq=False)
class SimilarityData:
    """A checked continuous-time black box, with the frequency grid its misfit is measured on.

    Attributes
    ----------
    blackbox : BlackBox
        (𝔸, 𝔹, ℂ, 𝔻), continuous time, the model's order, in the basis the methods work
        in: the balanced realisation when the black box is stable (``basis``).
    frf : FrequencyData
        The black box's frequency response on the misfit grid.
    subspace : DiscreteStateSpace or None
        The N4SID estimate when the data were input/output records.
    source : str
        ``"blackbox"`` or ``"io"``.
    basis : str
        ``"balanced"`` or ``"given"``.
    to_basis : numpy.ndarray
        P with blackbox = (P 𝔸ₒ P⁻¹, P 𝔹ₒ, ℂₒ P⁻¹) for the given (or estimated) black box
        (𝔸ₒ, 𝔹ₒ, ℂₒ): a transform T found for ``blackbox`` is T P for the original.
    """

    blackbox: BlackBox
    frf: FrequencyData
    subspace: Any = None
    source: str = "blackbox"
    basis: str = "given"
    to_basis: Any = None

    def misfit(self, model: Any, theta: np.ndarray) -> float:
        """Mean relative frequency-response misfit of the grey box at θ against the black box (``inf`` if
        the grey box cannot be evaluated)."""
        H = np.asarray(self.frf.H)
        try:
            Hm = model.frequency_response(theta, self.frf.w)
        except (ModelError, np.linalg.LinAlgError, FloatingPointError):
            return float("inf")
        if not np.all(np.isfinite(Hm)):
            return float("inf")
        scale = np.max(np.abs(H), axis=(1, 2), keepdims=True)  # per frequency: no under- or overflow
        scale = np.where(scale > 0, scale, 1.0)
        den = np.maximum(np.sum(np.abs(H / scale) ** 2, axis=(1, 2)), 1e-300)
        return float(np.mean(np.sum(np.abs((H - Hm) / scale) ** 2, axis=(1, 2)) / den))


def model_has_feedthrough(model: Any) -> bool:
    """Whether the model has a direct feedthrough for some θ (a D that is not the constant 0, or an acceleration
    output of a second-order model): N4SID then estimates D too."""
    maps = model.maps
    if "D" in maps:
        return not (maps["D"].is_constant and not np.any(maps["D"].X0))
    return "acceleration" in getattr(model, "outputs", ())


def _check_sizes(model: Any, n: int, m: int, p: int, what: str) -> None:
    if (p, m) != (model.n_outputs, model.n_inputs):
        raise DataError(f"{what} has {p} output(s) and {m} input(s); the model has {model.n_outputs} output(s) and "
                        f"{model.n_inputs} input(s)")
    if n != model.n_states:
        raise DataError(f"{what} has {n} states but the model has {model.n_states}: a similarity transform needs a "
                        f"black box of the model's order (estimate it again with order {model.n_states})")


def _grid(poles: np.ndarray) -> np.ndarray:
    mag = np.abs(poles)
    mag = mag[mag > 1e-9 * max(1.0, mag.max(initial=0.0))]
    lo, hi = (mag.min() / 10, mag.max() * 10) if mag.size else (1e-2, 1e2)
    return np.logspace(np.log10(lo), np.log10(hi), _GRID_POINTS)


def similarity_data(model: Any, data: Any, *, horizon: int | None = None, allow_unstable: bool = False,
                    balance: bool = True) -> SimilarityData:
    """Check a black box against the model (or estimate one from I/O records) and set up its misfit.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    data : BlackBox or IOData
        A continuous-time black box, or records that N4SID (order = the model's) and
        the exact zero-order-hold ``d2c`` turn into one.
    horizon : int, optional
        N4SID horizon (see :func:`symid.n4sid`).
    allow_unstable : bool
        Accept a black box with poles in the closed right half-plane. The similarity
        transformation does not need stability (the driver belt of thesis §6-7-2 is
        unstable), but an unstable estimate from records usually means a wrong order or
        bad data, so it is refused unless asked for.
    balance : bool
        Put a stable black box in its balanced realisation (default). The basis of a
        black box is arbitrary (an N4SID estimate's is an accident of the algorithm),
        but no similarity method is basis-invariant: SCR, ALS, GB and IPOPT all work on
        T, whose size and conditioning depend on it. The balanced basis makes the
        problem depend on the system only; on the 3-D mass-spring-damper of §7-6-1 it
        turns cond(T) from 4e3 (N4SID basis) into 6.

    Raises
    ------
    DataError
        Wrong order or sizes, an unstable black box (without ``allow_unstable``), a
        non-minimal black box, or records that N4SID refuses (too short, not exciting).
    """
    allow_unstable, balance = check_bool("allow_unstable", allow_unstable), check_bool("balance", balance)
    if horizon is not None:
        horizon = check_int("horizon", horizon, low=1)
    if isinstance(data, IOData):
        from symid.signal.subspace import n4sid

        _check_sizes(model, model.n_states, data.n_inputs, data.n_outputs, "the I/O data")
        dss = n4sid(data, model.n_states, horizon=horizon, feedthrough=model_has_feedthrough(model))
        bb, source = dss.to_continuous(), "io"
        where = f"the black box estimated from the I/O data (N4SID order {model.n_states} + d2c)"
    elif isinstance(data, BlackBox):
        if horizon is not None:
            raise OptionError("horizon is an N4SID option; it does not apply to BlackBox data")
        dss, bb, source = None, data, "blackbox"
        where = "the black box"
    else:
        raise DataError(f"similarity formulations take BlackBox or IOData; got {type(data).__name__}")
    _check_sizes(model, bb.n_states, bb.n_inputs, bb.n_outputs, where)
    _check_feedthrough(model, bb, where)
    poles = bb.poles
    if not allow_unstable and np.any(poles.real >= -1e-12 * max(1.0, np.abs(poles).max())):
        bad = poles[np.argmax(poles.real)]
        raise DataError(f"{where} is not stable (pole {bad:.4g} in the closed right half-plane). The similarity "
                        "transformation does not need stability; pass allow_unstable=True if this is intended "
                        "(e.g. the driver belt of thesis §6-7-2), otherwise check the order and the data")
    why = not_minimal(bb.A, bb.B, bb.C)
    if why is not None:
        raise DataError(f"{where} is not minimal: {why}. A similarity transform to a structured model of the same "
                        "order is then not unique; use a minimal realisation (lower order)")
    w = _grid(poles)
    try:
        H = bb.frequency_response(w)
    except ModelError:
        w = w * (1 + 1e-3)
        H = bb.frequency_response(w)
    basis, P = "given", np.eye(bb.n_states)
    if balance and np.all(poles.real < 0):
        P, Pinv = balanced_realisation(bb.A, bb.B, bb.C)
        bb = BlackBox(P @ bb.A @ Pinv, P @ bb.B, bb.C @ Pinv, bb.D)
        basis = "balanced"
    return SimilarityData(blackbox=bb, frf=FrequencyData(w, H), subspace=dss, source=source, basis=basis,
                          to_basis=P)


def _check_feedthrough(model: Any, bb: Any, where: str) -> None:
    """A model whose feedthrough D holds no parameter must have the black box's: a similarity transform does not
    change D (found by a new user: SCR refused D = 0.3 against a fixed 0, ALS, GB and IPOPT ran on to misfits of
    0.7-0.8)."""
    Dmap = getattr(model, "maps", {}).get("D")
    if Dmap is None or not Dmap.is_constant:
        return
    D0, Db = np.asarray(Dmap.X0, dtype=float), np.asarray(bb.D, dtype=float)
    if D0.shape == Db.shape and not np.allclose(D0, Db, rtol=1e-9, atol=1e-12 * max(1.0, float(np.abs(Db).max()))):
        raise DataError(f"the model's feedthrough D is fixed at {D0.tolist()} but {where} has D = {Db.tolist()}; "
                        "a similarity transform does not change D (give D parameters, or remove the feedthrough)")


def budget_message(limit: float, iterations: int, unit: str = "iteration") -> str:
    """What a start stopped by its ``time_limit`` reports (as the SCR engine words it).

    Examples
    --------
    >>> from symid.fit.similarity.data import budget_message
    >>> budget_message(0.5, 3, "sweep")
    'time limit of 0.5 s reached after 3 sweeps; the last estimate is kept'
    """
    plural = "" if iterations == 1 else "s"
    return f"time limit of {limit:g} s reached after {iterations} {unit}{plural}; the last estimate is kept"


class SimilarityEstimator(Estimator):
    """Base of the similarity-transformation methods: the basis-free black-box misfit.

    No whiteness test applies (the residual against a black box is not measurement
    noise), so a fit counts as a success only when it is exact or within a given
    ``noise_floor`` (:mod:`symid.fit.success`).
    """

    cost_kind = "mean relative FRF misfit against the black box, (1/s) Σᵢ ‖H_bb − H(θ)‖²_F / ‖H_bb‖²_F"

    def misfit(self, theta: np.ndarray) -> float:
        """:meth:`SimilarityData.misfit` of the model at θ."""
        return self.data.misfit(self.model, theta)

    def n_data(self) -> int:
        """2·s·p·m real values of the black box's response on the misfit grid."""
        return 2 * int(np.asarray(self.data.frf.H).size)

    def transform_outcome(self, x0: np.ndarray, theta: np.ndarray, T: np.ndarray, *, finished: bool, status: str,
                          message: str, iterations: int, wall_time: float,
                          history: tuple[ScrIteration, ...] = ()) -> StartOutcome:
        """The outcome of a method that estimated (θ, T), with cond(T) in the message."""
        finite = bool(np.all(np.isfinite(theta)) and np.all(np.isfinite(T)))
        cond = float(np.linalg.cond(T)) if finite else float("inf")
        return self.outcome(x0, theta, finished=finished, status=status, message=f"{message}; cond(T) = {cond:.3g}",
                            iterations=iterations, wall_time=wall_time, history=history)
