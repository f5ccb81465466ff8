"""Initial points for multi-start estimation, identical for every method and tied to parameter names.

Each parameter draws its own stream of N(0, 1) values, seeded by ``seed`` and its
name: the same seed gives a parameter the same starting values whatever the order in
which the model declares its parameters, and whatever other parameters it has.
"""

from __future__ import annotations

import zlib
from typing import Any

import numpy as np

from symid.errors import OptionError
from symid.fit.options import MAX_STARTS, check_int, check_seed

__all__ = ["make_starts"]


def _name_key(name: str) -> int:
    return zlib.crc32(name.encode("utf-8"))


def make_starts(model: Any, starts: int, seed: int | None, x0: Any = None, *, zero_first: bool = False
                ) -> list[np.ndarray]:
    """The list of initial parameter vectors.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    starts : int
        How many starts (1 … 100 000).
    seed : int or None
        Seed of the draws (``None``: fresh entropy, different every call).
    x0 : dict or sequence, optional
        A user start; it becomes the first start.
    zero_first : bool
        Make the first start θ = 0 when ``x0`` is not given (the thesis's chapter-3
        initialisation).

    Returns
    -------
    list of numpy.ndarray
        ``starts`` vectors in ``parameter_names`` order: ``x0`` (or zeros) first when
        asked, then draws. Draw k of a parameter is the k-th N(0, 1) value of the stream
        seeded by (``seed``, the parameter's name); parameters declared positive take it
        in absolute value.

    Examples
    --------
    >>> import symid as si
    >>> from symid.fit.starts import make_starts
    >>> m, k = si.parameters("m k", positive=True)
    >>> a = si.SecondOrderModel(M=[[m]], V=[[0.1]], K=[[k]], B=[[1]], C=[[1]], parameters=[m, k])
    >>> b = si.SecondOrderModel(M=[[m]], V=[[0.1]], K=[[k]], B=[[1]], C=[[1]], parameters=[k, m])
    >>> sa, sb = make_starts(a, 2, seed=0), make_starts(b, 2, seed=0)
    >>> bool(sa[1][0] == sb[1][1] and sa[1][1] == sb[1][0])   # m and k keep their values
    True
    """
    starts = check_int("starts", starts, low=1, high=MAX_STARTS)
    if seed is None:
        seed = int(np.random.SeedSequence().generate_state(1, dtype=np.uint64)[0] >> np.uint64(1))
    seed = check_seed("seed", seed)
    l = model.n_parameters
    out: list[np.ndarray] = []
    if x0 is not None:
        try:
            out.append(model.theta_vector(x0))
        except ValueError as exc:
            raise OptionError(f"x0: {exc}") from None
    elif zero_first:
        out.append(np.zeros(l))
    n_draws = starts - len(out)
    if n_draws > 0:
        cols = []
        for name, pos in zip(model.parameter_names, model.positive, strict=True):
            draws = np.random.default_rng([seed, _name_key(name)]).standard_normal(n_draws)
            cols.append(np.abs(draws) if pos else draws)
        table = np.column_stack(cols) if cols else np.zeros((n_draws, 0))
        out.extend(table[k].copy() for k in range(n_draws))
    return out[:starts]
