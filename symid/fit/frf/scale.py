"""Typical parameter values from a frequency response by dimensional analysis: starts at physical scale.

A user who gives no start still knows the data: the band of frequencies measured and the
level of the response. Each parameter's role follows from the matrix it sits in, and
its order of magnitude from two numbers of the data:

- ω₀ = √(ω_min ω_max), the centre of the measured band (rad/s);
- a level L (force per displacement), chosen so that the model's response at the
  typical values has the data's level: the one-dimensional least squares
  min over log L of Σᵢ (log |H(ωᵢ, θ(L))| − log |Hᵢ|)², solved by a bounded scalar search.

Second-order models M q̈ + V q̇ + K q = B u: a parameter in K is a stiffness, L; in V a
damping, 2ζ₀ L / ω₀ (ζ₀ = 0.05, a lightly damped structure); in M a mass, L / ω₀²; in B or C
a gain, 1. State-space models ẋ = A x + B u, y = C x + D u: a parameter in A is a rate, ω₀;
in B, C or D a gain, L (of the level of H · ω₀ when both B and C hold one). A parameter in
several matrices takes the role of the first in the order M, V, K, A, B, C, D.

A second-order model with a known entry in M, V or K (a known mass, say) and gains
(parameters in B, C or D) is different: the known entry fixes what L means, and the
level of |H| belongs to the gains. There L is chosen so that the model's natural
frequencies at the typical values centre on ω₀ (their geometric mean is ω₀, as they are
when every entry is a parameter), and each gain from the level of the entries it
reaches: when every entry of H is a monomial in the gains (checked numerically), the
log gains are the least-squares fit of the data's log |H| to the response at gains 1
(otherwise the rule above). Before, all gains took one common value, and where they
reach the entries to different powers (an actuator gain b on every row, a sensor gain
g on one: b and b·g) the analysis fell back to gains of 1 with the level in the
springs: on 12 problems drawn from the gains class of ``benchmarks/population_models.py``
(n = 2, 3, 5, 8) springs and dampers were up to 3.8 decades off, gains up to 1.8; now
every value is within 1.3 decades (``benchmarks/typical_scale.py``). Earlier still, before
L centred the natural frequencies, the stiffnesses took
the level of |H| and the modes left the band (the F-16 modal model of
``examples/f16_gvt.py``, M = I: every k = 1.3e6, modes at 185 Hz for a band of 2–15 Hz;
now k = 1.2e3, 5.5 Hz).

A second-order model with known entries in M, V or K and no gains can have no level
that fits: a DC motor written as L q̈ + R q̇ + K ω = u, J ω̇ + b ω − K q̇ = 0 with L and R
known (K, J, b in the damping and mass matrices) has, at the ratios ζ₀ sets, a response
whose misfit falls as the level goes to 0 and then stays flat, and the search ended on
that plateau, at e^−77.5, with J = 2e-38 (a new user's model, the fit staying there:
every parameter 1e-35 of the truth, reported as a fit). Where the misfit is as low at the
search's edge as at its minimum, the level is instead the one the known entries imply (a
known mass m: m ω₀²; a damper c: c ω₀/(2ζ₀); a spring: itself; their geometric mean):
J = 0.03, K = b = 0.32 for that motor (truth 1e-4, 0.05, 1e-5).

These typical values are where :func:`symid.fit.frf.modal.black_box_start` starts, and
what :func:`symid.fit.starts.draw_starts` draws around (log-uniformly within a factor 3)
when there is no black-box start: a start of the right order of magnitude, not an
estimate.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.optimize import minimize_scalar

from symid.errors import ModelError

__all__ = ["ZETA0", "parameter_roles", "typical_scale"]

ZETA0 = 0.05
"""Damping ratio assumed for the typical damping values."""

_ORDER = ("M", "V", "K", "A", "B", "C", "D")


def parameter_roles(model: Any) -> tuple[str, ...]:
    """The matrix each parameter is read from: the first of M, V, K, A, B, C, D it appears in.

    Examples
    --------
    >>> import symid as si
    >>> from symid.fit.frf.scale import parameter_roles
    >>> m, c, k, b = si.parameters("m c k b", positive=True)
    >>> parameter_roles(si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[b]], C=[[1]]))
    ('M', 'V', 'K', 'B')
    """
    maps = model.maps
    roles = []
    for j in range(model.n_parameters):
        role = next((name for name in _ORDER if name in maps and maps[name].Xi.size
                     and np.any(maps[name].Xi[j] != 0)), None)
        if role is None:  # pragma: no cover - every parameter appears in some matrix (the model checks it)
            raise ModelError(f"parameter {model.parameter_names[j]!r} appears in no matrix")
        roles.append(role)
    return tuple(roles)


def typical_scale(model: Any, data: Any) -> np.ndarray:
    """Typical magnitude of every parameter from a frequency response (module docstring).

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    data : FrequencyData

    Returns
    -------
    numpy.ndarray
        One positive value per parameter, in ``parameter_names`` order.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.frf.scale import typical_scale
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, [20.0, 40.0, 5e5], np.logspace(1.5, 3, 50))   # 158 rad/s, ζ = 0.006
    >>> scale = typical_scale(model, frf)
    >>> bool(np.all(np.abs(np.log10(scale / [20.0, 40.0, 5e5])) < 1))   # each within a factor 10
    True
    """
    w = np.asarray(data.w, dtype=float)
    H = np.asarray(data.H)
    w0 = math.sqrt(float(w[0]) * float(w[-1]))
    roles = parameter_roles(model)
    second = "M" in model.maps
    gain_b = any(r == "B" for r in roles)
    gain_c = any(r in ("C", "D") for r in roles)

    def theta(log_level: float) -> np.ndarray:
        level = math.exp(log_level)
        if second:
            table = {"M": level / w0**2, "V": 2 * ZETA0 * level / w0, "K": level, "B": 1.0, "C": 1.0, "D": 1.0}
        else:
            gain = math.sqrt(level) if (gain_b and gain_c) else level
            table = {"A": w0, "B": gain, "C": gain, "D": level}
        return np.array([table[r] for r in roles])

    mask = np.abs(H) > 0
    logH = np.log(np.abs(H[mask]))

    def misfit(log_level: float) -> float:
        try:
            with np.errstate(all="ignore"):
                Hm = np.asarray(model.frequency_response(theta(log_level), w))
        except (ModelError, np.linalg.LinAlgError):
            return float("inf")
        mag = np.abs(Hm[mask])
        if not np.all(np.isfinite(mag)) or np.any(mag == 0):
            return float("inf")
        return float(np.sum((np.log(mag) - logH) ** 2))

    level = _search(misfit)
    if level is None:
        return np.abs(theta(0.0))
    if second and (gain_b or gain_c) and _pinned(model):
        gains = _gain_level(model, w, mask, logH, theta, roles)
        if gains is not None:
            level, log_gain = gains
            out = theta(level)
            out[[r in ("B", "C", "D") for r in roles]] = np.exp(log_gain)
            return np.abs(out)
    if second and _pinned(model) and min(misfit(-_EDGE), misfit(_EDGE)) <= misfit(level) * (1 + 1e-6):
        level = math.log(_known_level(model, w0))  # the data do not fix the level: the misfit is as low at the edge
    return np.abs(theta(level))


_EDGE = 80.0
"""The search's outermost log-level (module notes: e^±80 covers any unit system)."""


def _known_level(model: Any, w0: float) -> float:
    """The level the known nonzero entries of M, V and K imply (a mass m: m ω₀², a damper c: c ω₀ / (2ζ₀), a spring:
    itself), their geometric mean: for a model whose response no common level fits (module notes)."""
    per = {"M": w0**2, "V": w0 / (2 * ZETA0), "K": 1.0}
    logs = [math.log(abs(float(x)) * f) for name, f in per.items()
            for x in np.asarray(model.maps[name].X0, dtype=float).ravel() if x != 0]
    return math.exp(sum(logs) / len(logs))


def _search(misfit: Any) -> float | None:
    """The minimiser of a function of one log-level: a coarse grid, then a bounded search in its bracket."""
    # the level enters H as 1/L (second order) or L (state space, through the gains): a 1-D search over
    # 2 × 80 natural-log units covers any unit system; the grid picks the bracket, the bounded search refines
    grid = np.linspace(-_EDGE, _EDGE, 81)
    values = np.array([misfit(g) for g in grid])
    if not np.any(np.isfinite(values)):
        return None
    k = int(np.nanargmin(np.where(np.isfinite(values), values, np.inf)))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
    best = minimize_scalar(misfit, bounds=(lo, hi), method="bounded", options={"xatol": 1e-3})
    return float(best.x) if np.isfinite(best.fun) and best.fun <= values[k] else float(grid[k])


def _pinned(model: Any) -> bool:
    """M, V or K holds a known nonzero entry: the mechanical level is fixed against it, not free."""
    return any(np.any(np.asarray(model.maps[n].X0) != 0) for n in ("M", "V", "K"))


def _gain_level(model: Any, w: np.ndarray, mask: np.ndarray, logH: np.ndarray, theta: Any,
                roles: tuple[str, ...]) -> tuple[float, np.ndarray] | None:
    """Level L and the log of every gain, for a second-order model with a known entry in M, V or K and gains.

    With a mass (say) known, the stiffness level L is what places the resonances, and
    the gains (parameters of B, C, D) set the response level. L is chosen so that the
    model's natural frequencies at the typical values centre on ω₀ (their geometric mean
    is ω₀, as for a model made of parameters only). When every entry of H is a monomial
    in the gains, log |Hᵢⱼ| = log |Hᵢⱼ(L, 1)| + Σₚ κᵢⱼₚ log gₚ (checked numerically at a second
    point; otherwise ``None``), the log gains are the least-squares solution of that
    system over every line and entry (the smallest one where only products of gains
    show, e.g. b·g). One common gain, as before, cannot fit a gain b in B and a sensor
    gain g on one output only (b on one row of H, b·g on the other): module notes.
    """
    w0 = math.sqrt(float(w[0]) * float(w[-1]))
    is_gain = np.array([r in ("B", "C", "D") for r in roles])
    n_gain = int(is_gain.sum())

    def response(log_level: float, log_gain: np.ndarray) -> np.ndarray | None:
        th = theta(log_level)
        th[is_gain] = np.exp(log_gain)
        try:
            with np.errstate(all="ignore"):
                Hm = np.asarray(model.frequency_response(th, w))
        except (ModelError, np.linalg.LinAlgError):
            return None
        mag = np.abs(Hm[mask])
        if not np.all(np.isfinite(mag)) or np.any(mag == 0):
            return None
        return np.log(mag)

    def centre(log_level: float) -> float:
        try:
            with np.errstate(all="ignore"):
                lam = np.abs(np.linalg.eigvals(model.state_space(theta(log_level)).A))
        except (ModelError, np.linalg.LinAlgError, ValueError):
            return float("inf")
        lam = lam[np.isfinite(lam) & (lam > 0)]
        return float((np.mean(np.log(lam)) - math.log(w0)) ** 2) if lam.size else float("inf")

    found = _search(centre)
    if found is None:
        return None
    h0 = response(found, np.zeros(n_gain))
    steps = [response(found, np.eye(n_gain)[p]) for p in range(n_gain)]
    check = response(found, np.linspace(0.5, 1.5, n_gain))
    if h0 is None or check is None or any(h is None for h in steps):
        return None
    K = np.column_stack([h - h0 for h in steps])  # κ per entry and gain
    if np.max(np.abs(h0 + K @ np.linspace(0.5, 1.5, n_gain) - check)) > 1e-6 * max(1.0, float(np.abs(K).max())):
        return None  # an entry is not a monomial in the gains
    if not np.any(np.abs(K) > 0.5):
        return None  # the gains do not reach the response
    log_gain, *_ = np.linalg.lstsq(K, logH - h0, rcond=None)
    return found, log_gain
