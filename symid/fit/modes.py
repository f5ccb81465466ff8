"""The modes of an estimate: natural frequency and damping ratio of every pole pair, and the real poles.

A check a person makes at a glance: a frequency axis in Hz read as rad/s moves every mode
by 2π, a time axis in minutes read as seconds every rate by 60, and neither is visible in
the misfit. ``si.identify`` puts the line in ``summary()`` (``res.options["modes"]``),
and ``symid identify`` prints it with the summary.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["estimate_poles", "modes_line"]


def estimate_poles(model: Any, theta: Any) -> np.ndarray | None:
    """The poles of the model at θ (the eigenvalues of its first-order form), or None where it cannot be evaluated.

    A first-order system E x' + F x = B u written as M = E, V = F, K = 0 and measured in velocity has the poles of
    −M⁻¹V: the positions' n integrators are no pole of its response (a new user's LC ladder read "5 poles at 0").

    Examples
    --------
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> sorted(estimate_poles(model, [1.0, 0.2, 100.0]).round(6).tolist(), key=lambda p: p.imag)
    [(-0.1-9.9995j), (-0.1+9.9995j)]
    """
    try:
        A = np.asarray(model.state_space(theta)[0], dtype=float)
        if hasattr(model, "output_orders") and min(model.output_orders) >= 1:
            mats = model.matrices(theta)
            if not np.any(mats["K"]):
                A = -np.linalg.solve(np.asarray(mats["M"], dtype=float), np.asarray(mats["V"], dtype=float))
        return np.linalg.eigvals(A) if A.size and np.all(np.isfinite(A)) else np.array([])
    except Exception:  # an estimate where the model cannot be evaluated
        return None


def modes_line(model: Any, theta: Any, time_unit: str | None) -> str:
    """'modes of the estimate: 87.16 Hz, 547.6 rad/s, ζ 0.0584; real pole -1.5 /s', or '' when the model cannot be
    evaluated at θ.

    Poles at 0 (a rigid-body mode, an integrator) are counted in one item; a natural frequency is given in Hz as well
    when the time unit is the second.

    Examples
    --------
    >>> import symid as si
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> modes_line(model, [1.0, 0.2, 100.0], "s")
    'modes of the estimate: 1.592 Hz, 10 rad/s, ζ 0.01'
    """
    poles = estimate_poles(model, theta)
    if poles is None:  # an estimate where the model cannot be evaluated: nothing to say
        return ""
    unit = time_unit or "s"
    items = []
    zero = np.abs(poles) <= 1e-12 * max(float(np.max(np.abs(poles))), 1e-300) if poles.size else poles
    if np.count_nonzero(zero):  # integrators (a rigid-body mode, positions no output sees): one item, shown as 0
        count = np.count_nonzero(zero)  # (a new user's drivetrain read "real pole 1.359e-11 /s", positive)
        items.append(f"{count} pole{'s' if count > 1 else ''} at 0")
        poles = poles[~zero]
    for p in sorted(poles, key=abs):
        if p.imag > 0:
            wn = abs(p)
            hz = f"{wn / (2 * np.pi):.4g} Hz, " if unit == "s" else ""
            items.append(f"{hz}{wn:.4g} rad/{unit}, ζ {-p.real / wn:.3g}")
        elif p.imag == 0:
            items.append(f"real pole {p.real:.4g} /{unit}")
    return "modes of the estimate: " + "; ".join(items) if items else ""
