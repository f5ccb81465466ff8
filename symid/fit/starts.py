"""Initial points for multi-start estimation, identical for every method and tied to parameter names.

Each parameter draws its own stream of values, seeded by ``seed`` and its name: the same
seed gives a parameter the same starting values whatever the order in which the model
declares its parameters, and whatever other parameters it has. Two distributions:

- ``"normal"``: N(0, 1), in absolute value for parameters declared positive (the
  thesis's starts, chapters 3-4);
- ``"scale"``, around typical values s (the user's ``scale=``, or
  :func:`symid.fit.frf.scale.typical_scale` from a frequency response, or
  :func:`symid.fit.timeseries.scale.typical_scale` from time series): s · 3^U(−1, 1)
  for parameters declared positive (log-uniform within a factor 3 of s), s · N(0, 1) for
  the others — starts of the right physical order of magnitude, no wider than the
  typical values are uncertain (the restarts of method ``"auto"`` search wider).
  On a frequency response without a user's start, the first start is the black-box
  start of :func:`symid.fit.frf.modal.black_box_start` (the model's poles placed on
  those of a vector fit of the data) when there is one, and the typical values of the
  further draws are its magnitudes.
"""

from __future__ import annotations

import zlib
from typing import Any

import numpy as np

from symid.errors import OptionError
from symid.fit.options import MAX_STARTS, check_int, check_seed

__all__ = ["DRAWS", "draw_starts", "make_starts"]

DRAWS = ("scale", "normal")
"""How :func:`draw_starts` draws random starts (module docstring)."""


def _name_key(name: str) -> int:
    return zlib.crc32(name.encode("utf-8"))


def make_starts(model: Any, starts: int, seed: int | None, x0: Any = None, *, zero_first: bool = False,
                typical: Any = None, spread: float = 3.0) -> list[np.ndarray]:
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
        initialisation; not with ``typical``).
    typical : array_like, optional
        Typical magnitude of each parameter (> 0): the draws are s · spread^U(−1, 1) for
        parameters declared positive and s · N(0, 1) for the others. Default: N(0, 1)
        draws (module docstring).
    spread : float
        With ``typical``: the factor within which positive parameters are drawn (default 3).

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
    if typical is not None:
        typical = np.asarray(typical, dtype=float).reshape(-1)
        if typical.size != l or not np.all(np.isfinite(typical)) or np.any(typical <= 0):
            raise OptionError(f"typical values must be {l} finite numbers > 0; got {typical!r}")
    out: list[np.ndarray] = []
    if x0 is not None:
        try:
            out.append(model.theta_vector(x0))
        except ValueError as exc:
            raise OptionError(f"x0: {exc}") from None
    elif zero_first and typical is None:
        out.append(np.zeros(l))
    n_draws = starts - len(out)
    if n_draws > 0:
        cols = []
        for j, (name, pos) in enumerate(zip(model.parameter_names, model.positive, strict=True)):
            rng = np.random.default_rng([seed, _name_key(name)])
            if typical is None:
                draws = rng.standard_normal(n_draws)
                cols.append(np.abs(draws) if pos else draws)
            elif pos:
                cols.append(typical[j] * float(spread) ** rng.uniform(-1.0, 1.0, n_draws))
            else:
                cols.append(typical[j] * rng.standard_normal(n_draws))
        table = np.column_stack(cols) if cols else np.zeros((n_draws, 0))
        out.extend(table[k].copy() for k in range(n_draws))
    return out[:starts]


def draw_starts(model: Any, data: Any, starts: int, seed: int | None, x0: Any = None, *, draws: str | None = None,
                scale: Any = None, black_box: bool = True, bounds: Any = None,
                data_typical: np.ndarray | None = None) -> list[np.ndarray]:
    """The starts of :func:`symid.identify` and :func:`symid.compare`: ``x0`` first, then random draws.

    Parameters
    ----------
    model, data
        The model and the data (the data kind picks the default).
    starts, seed, x0
        As in :func:`make_starts`.
    draws : {"scale", "normal"}, optional
        ``"scale"``: within a factor 3 of typical values — ``scale`` when given, else the
        data kind's (:func:`symid.fit.frf.scale.typical_scale` for a frequency response);
        for a frequency response and no ``x0``, the black-box start
        (:func:`symid.fit.frf.modal.black_box_start`) first when there is one, and its
        magnitudes as the typical values unless ``scale`` is given.
        ``"normal"``: N(0, 1), with θ = 0 first for a state-space model (the thesis).
        Default: ``"scale"`` for a frequency response, or when ``scale`` is given, or
        when the data give typical values of their own (time series and spectra, unless
        there is only ``x0`` to return); ``"normal"`` otherwise.
    scale : float or array_like, optional
        The user's typical values (the methods' ``scale=`` option).
    black_box : bool, optional
        Build the black-box start (default ``True``); ``False`` for a method that does not
        use its start (the linear least squares), where it would only cost time.
    bounds : dict or array_like, optional
        The user's bounds (the methods' ``bounds=`` option): a positive parameter with
        two positive finite bounds is drawn around their geometric mean unless ``scale``
        gives its typical value, and every start but the user's ``x0`` is moved into the
        bounds (:mod:`symid.fit.bounded`; a user's start outside them is the method's
        to refuse).
    data_typical : array_like, optional
        The typical values the data kind reads off the data, when the caller has them
        already (an estimator that computed them: not computed again).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.starts import draw_starts
    >>> m, k = si.parameters("m k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[0.5]], K=[[k]], B=[[1]], C=[[1]])
    >>> frf = si.simulate_frf(model, [50.0, 2e5], np.logspace(1, 3, 40))
    >>> x = np.array(draw_starts(model, frf, 20, seed=0))
    >>> bool(np.all((x[:, 1] > 1e3) & (x[:, 1] < 1e7)))      # stiffnesses drawn at the data's scale
    True
    """
    from symid.fit.options import check_choice, check_scale
    from symid.fit.registry import data_kind

    kind = data_kind(data)
    typical = None
    if draws is None:
        if kind.name == "frequency response" or scale is not None:
            draws = "scale"
        elif x0 is None or starts > 1:
            # data that give typical values of their own (time series through their frequency response, spectra
            # through the level they imply): starts at the data's physical scale rather than N(0, 1) (measured:
            # benchmarks/timeseries_defaults.py, benchmarks/psd_units.py)
            typical = kind.typical_scale(model, data) if data_typical is None else np.asarray(data_typical)
            draws = "normal" if typical is None else "scale"
        else:
            draws = "normal"  # the user's start alone
    draws = check_choice("draws", draws, DRAWS)
    lower = upper = None
    if bounds is not None:
        from symid.fit.options import check_bounds

        lower, upper = check_bounds("bounds", bounds, model.parameter_names)
    user_x0 = x0
    if draws == "normal":
        out = make_starts(model, starts, seed, x0, zero_first=type(model).__name__ == "StateSpaceModel")
        return out if lower is None else _into_bounds(out, lower, upper, user_x0 is not None)
    if scale is not None:
        typical = np.abs(check_scale("scale", scale, model.n_parameters))
    elif typical is None:
        typical = kind.typical_scale(model, data) if data_typical is None else np.asarray(data_typical)
        if typical is None:
            raise OptionError(f"draws='scale' needs typical values: give scale= (one value or one per parameter); "
                              f"{kind.name} data give none of their own")
    positive = np.asarray(model.positive, dtype=bool)
    if lower is not None:
        from symid.fit.bounded import typical_within

        typical = typical_within(typical, lower, upper, positive, scale is not None)
    if black_box and x0 is None and kind.name == "frequency response":
        from symid.fit.frf.modal import black_box_start

        found = black_box_start(model, data, typical, seed=0 if seed is None else check_seed("seed", seed))
        if found is not None:
            x0 = found.theta
            if scale is None:
                typical = found.typical if lower is None else typical_within(found.typical, lower, upper, positive,
                                                                             False)
    out = make_starts(model, starts, seed, x0, typical=typical)
    return out if lower is None else _into_bounds(out, lower, upper, user_x0 is not None)


def _into_bounds(starts: list[np.ndarray], lower: np.ndarray, upper: np.ndarray, keep_first: bool
                 ) -> list[np.ndarray]:
    """The starts moved into [lower, upper], but for the user's own start (``keep_first``)."""
    return [x if (i == 0 and keep_first) else np.clip(x, lower, upper) for i, x in enumerate(starts)]
