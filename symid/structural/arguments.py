"""The arguments of :func:`~symid.structural.identifiability`, checked in one place before any work.

A problem with the model or with ``known=`` (its names or values) is a
:class:`~symid.errors.ModelError`, as for parameter values elsewhere
(:meth:`symid.model.parametric.ParametricModel.theta_vector`); a bad option value
(``timeout``, ``positive``, ``exact_count``, ``seed``, ``engine``) is an
:class:`~symid.errors.OptionError`. Both derive from ``ValueError``.

Decisions (documented in :func:`~symid.structural.identifiability`):

* ``timeout=inf`` (or a number too large for a float) means no limit, like ``None``;
* ``seed=None`` is refused: the report is a deterministic function of the model and
  the seed (a fresh random point would make two runs disagree silently);
* known values keep their exact value (``Fraction(1, 3)`` stays 1/3; floats go through
  their shortest decimal, :func:`~symid.structural.summary.rational`).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import sympy as sp

from symid.errors import ModelError, OptionError, did_you_mean
from symid.fit.options import check_bool, check_seed
from symid.structural.msolve import msolve_binary
from symid.structural.summary import model_kind, rational

__all__ = ["ENGINES", "Arguments", "checked_arguments", "checked_engine", "checked_known", "checked_seed",
           "checked_timeout"]

ENGINES = ("auto", "sympy", "msolve")
"""Values of ``engine=``."""


@dataclass(frozen=True)
class Arguments:
    """The checked arguments of one identifiability analysis.

    Attributes
    ----------
    known : dict of str to sympy.Rational
        Known parameter values, exact, by name.
    known_values : dict of str to float
        The same values as floats (what the report shows).
    timeout : float or None
        Seconds > 0, or ``None`` for no limit.
    positive : bool or None
    exact_count : bool
    seed : int
        In [0, 2⁶³ − 1].
    msolve : str or None
        The msolve program the global step uses, or None (sympy).
    """

    known: dict[str, sp.Rational]
    known_values: dict[str, float]
    timeout: float | None
    positive: bool | None
    exact_count: bool
    seed: int
    msolve: str | None = None


def _is_real(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def checked_known(model, known: Any, *, require_free: bool = True) -> tuple[dict[str, sp.Rational], dict[str, float]]:
    """``known=`` as exact rationals and as floats, by parameter name; a :class:`ModelError` otherwise.

    Keys are parameter names or the parameters' symbols; values finite real numbers
    (int, float, ``Fraction``, numpy or sympy numbers). ``require_free``: refuse a
    ``known`` that leaves no parameter free, and a model without parameters.

    Examples
    --------
    >>> import symid as si
    >>> from fractions import Fraction
    >>> from symid.structural.arguments import checked_known
    >>> a, b = si.parameters("a b")
    >>> model = si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[1]])
    >>> checked_known(model, {b: Fraction(1, 3)})
    ({'b': 1/3}, {'b': 0.3333333333333333})
    >>> checked_known(model, {"b": float("nan")})
    Traceback (most recent call last):
    ...
    symid.errors.ModelError: known['b'] must be a finite real number; got nan (float)
    """
    model_kind(model)
    if known is None:
        known = {}
    if not isinstance(known, Mapping):
        raise ModelError(f"known must be a dict of parameter name → value; got {type(known).__name__} {known!r:.80}")
    names = model.parameter_names
    exact: dict[str, sp.Rational] = {}
    values: dict[str, float] = {}
    for key, value in known.items():
        name = key.name if isinstance(key, sp.Symbol) else key
        if not isinstance(name, str):
            raise ModelError(f"known= keys must be parameter names or symbols; got {key!r} ({type(key).__name__})")
        if name not in names:
            raise ModelError(f"known= names unknown parameter {name!r}{did_you_mean([name], names)}; the model's "
                             f"parameters are {', '.join(names) or 'none'}")
        if name in exact:
            raise ModelError(f"known= gives {name!r} twice (as a name and as a symbol)")
        if not _is_real(value):
            raise ModelError(f"known[{name!r}] must be a finite real number; got {value!r:.80} "
                             f"({type(value).__name__})")
        try:
            as_float = float(value)
        except OverflowError:
            digits = len(str(abs(int(value))))
            raise ModelError(f"known[{name!r}] must be a finite real number within the float range (about "
                             f"1.8e308); got a number of {digits} digits ({type(value).__name__})") from None
        if not math.isfinite(as_float):
            raise ModelError(f"known[{name!r}] must be a finite real number; got {value!r:.80} "
                             f"({type(value).__name__})")
        declared = dict(zip(names, getattr(model, "positive", ()) or (), strict=False))
        if declared.get(name) and as_float < 0:
            raise ModelError(f"known[{name!r}] = {value!r:.40} is negative, but {name} is declared positive "
                             "(si.parameters(..., positive=True)); give a value > 0, or 0 to leave the element out")
        exact[name] = rational(value)
        values[name] = as_float
    if require_free:
        if not names:
            raise ModelError("the model has no parameter: there is nothing to identify")
        if len(exact) == len(names):
            raise ModelError(f"every parameter ({', '.join(names)}) is given in known=: nothing is left to identify")
    return exact, values


def checked_seed(seed: Any) -> int:
    """The seed of the random points: an integer in [0, 2⁶³ − 1]; ``None`` is refused (deterministic reports).

    Examples
    --------
    >>> from symid.structural.arguments import checked_seed
    >>> checked_seed(7)
    7
    """
    if seed is None:
        raise OptionError("seed must be an integer between 0 and 9223372036854775807; got None: the analysis is a "
                          "deterministic function of the model and the seed, so pass an integer (for another "
                          "random point, e.g. secrets.randbits(32))")
    return check_seed("seed", seed)


def checked_timeout(timeout: Any) -> float | None:
    """Seconds > 0 as a float, or ``None`` (no limit) for ``None``, ``inf`` or a number beyond the float range."""
    if timeout is None:
        return None
    if not _is_real(timeout):
        raise OptionError(f"timeout must be a number of seconds > 0, or None or inf (no limit); got {timeout!r:.80} "
                          f"({type(timeout).__name__})")
    try:
        value = float(timeout)
    except OverflowError:  # an int or Fraction beyond 1.8e308 s: no limit
        value = math.inf if timeout > 0 else -math.inf
    if math.isnan(value) or value <= 0:
        raise OptionError(f"timeout must be a number of seconds > 0, or None or inf (no limit); got {timeout!r}")
    return None if math.isinf(value) else value


def _checked_positive(positive: Any) -> bool | None:
    if positive is None:
        return None
    if not isinstance(positive, (bool, np.bool_)):
        raise OptionError(f"positive must be None (the declarations), True or False; got {positive!r:.80} "
                          f"({type(positive).__name__})")
    return bool(positive)


def checked_engine(engine: Any) -> str | None:
    """The msolve program for ``engine=`` (``"auto"``: msolve when found, else sympy), or None for sympy.

    Examples
    --------
    >>> from symid.structural.arguments import checked_engine
    >>> checked_engine("sympy") is None
    True
    >>> checked_engine("maple")
    Traceback (most recent call last):
    ...
    symid.errors.OptionError: engine must be one of 'auto', 'sympy', 'msolve'; got 'maple' (str)
    """
    if not isinstance(engine, str) or engine not in ENGINES:
        raise OptionError(f"engine must be one of {', '.join(map(repr, ENGINES))}; got {engine!r:.80} "
                          f"({type(engine).__name__})")
    if engine == "sympy":
        return None
    binary = msolve_binary()
    if engine == "msolve" and binary is None:
        raise OptionError("engine='msolve' but no msolve program was found: install it with pip install "
                          "\"symid[msolve]\" (or put msolve on the PATH, or set SYMID_MSOLVE to its path)")
    return binary


def checked_arguments(model, *, known: Any, timeout: Any, positive: Any, exact_count: Any,
                      seed: Any, engine: Any = "auto") -> Arguments:
    """Every argument of :func:`~symid.structural.identifiability`, checked; the first problem raised.

    Raises
    ------
    ModelError
        Not a model, a model without parameters, or a bad ``known`` (not a dict, an
        unknown or repeated name, a value that is not a finite real number, every
        parameter known).
    OptionError
        A bad ``timeout``, ``positive``, ``exact_count``, ``seed`` or ``engine`` (or
        ``engine="msolve"`` without an msolve program, or ``$SYMID_MSOLVE`` naming
        something that is not an executable file).

    Examples
    --------
    >>> import symid as si
    >>> from symid.structural.arguments import checked_arguments
    >>> a, b = si.parameters("a b")
    >>> model = si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[1]])
    >>> args = checked_arguments(model, known={"b": 2}, timeout=float("inf"), positive=None,
    ...                          exact_count=False, seed=0)
    >>> args.known, args.timeout
    ({'b': 2}, None)
    >>> checked_arguments(model, known=None, timeout=5, positive="yes", exact_count=False, seed=0)
    Traceback (most recent call last):
    ...
    symid.errors.OptionError: positive must be None (the declarations), True or False; got 'yes' (str)
    """
    exact, values = checked_known(model, known)
    return Arguments(known=exact, known_values=values, timeout=checked_timeout(timeout),
                     positive=_checked_positive(positive),
                     exact_count=check_bool("exact_count", exact_count), seed=checked_seed(seed),
                     msolve=checked_engine(engine))
