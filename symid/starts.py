"""Initial points for multi-start estimation, identical for every method."""

from __future__ import annotations

from typing import Any

import numpy as np

from symid.errors import ModelError

__all__ = ["make_starts"]


def make_starts(model: Any, starts: int, seed: int | None, x0: Any = None, *, zero_first: bool = False
                ) -> list[np.ndarray]:
    """The list of initial parameter vectors.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    starts : int
        How many starts (≥ 1).
    seed : int or None
        Seed of the N(0, 1) draws.
    x0 : dict or sequence, optional
        A user start; it becomes the first start.
    zero_first : bool
        Make the first start θ = 0 when ``x0`` is not given (the thesis's chapter-3
        initialisation).

    Returns
    -------
    list of numpy.ndarray
        ``starts`` vectors: ``x0`` (or zeros) first when asked, then seeded N(0, 1) draws.
        Draws for parameters declared positive are taken in absolute value.
    """
    if isinstance(starts, bool) or not isinstance(starts, (int, np.integer)) or starts < 1:
        raise ModelError(f"starts must be a positive integer; got {starts!r}")
    rng = np.random.default_rng(seed)
    l = model.n_parameters
    positive = np.array(model.positive, dtype=bool)
    out: list[np.ndarray] = []
    if x0 is not None:
        out.append(model.theta_vector(x0))
    elif zero_first:
        out.append(np.zeros(l))
    while len(out) < starts:
        draw = rng.standard_normal(l)
        draw[positive] = np.abs(draw[positive])
        out.append(draw)
    return out[:starts]
