"""Which package estimates from which data: the small registry :func:`symid.identify` dispatches through.

Each data kind is one package of :mod:`symid.fit` with a ``METHODS`` tuple and a
``prepare(model, data, method, options, noise_floor=...)`` function. The command line
and :func:`symid.compare` build their method lists from here.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any

from symid.errors import DataError, ModelError
from symid.fit.base import Estimator

__all__ = ["DataKind", "all_methods", "check_model", "data_kind", "data_kinds", "prepare"]


@dataclass(frozen=True)
class DataKind:
    """One data kind: its name, the data types it takes, its package and methods.

    Attributes
    ----------
    name : str
        ``"frequency response"``, ``"spectra"``, ``"time series"``, ``"black box"``.
    data_types : tuple of str
        Names of the :mod:`symid.data` classes it takes.
    package : str
        The :mod:`symid.fit` package.
    default_method : str
        What :func:`symid.identify` runs when no method is named: ``"auto"`` for a
        frequency response (measured on ``benchmarks/population.py``), for time
        series (``benchmarks/timeseries_population.py``) and for spectra
        (``benchmarks/psd_auto.py``), ``"scr"`` for black boxes.
    """

    name: str
    data_types: tuple[str, ...]
    package: str
    default_method: str = "scr"

    @property
    def methods(self) -> tuple[str, ...]:
        """The method names of this kind."""
        return tuple(importlib.import_module(self.package).METHODS)

    def typical_scale(self, model: Any, data: Any) -> Any:
        """Typical parameter values from the data (the package's ``typical_scale``), or ``None`` if it has none."""
        fn = getattr(importlib.import_module(self.package), "typical_scale", None)
        return None if fn is None else fn(model, data)

    def prepare(self, model: Any, data: Any, method: str, options: dict[str, Any], *,
                noise_floor: float | None = None) -> Estimator:
        """Build the estimator of ``method`` (options validated)."""
        return importlib.import_module(self.package).prepare(model, data, method, options, noise_floor=noise_floor)


_KINDS = (
    DataKind("frequency response", ("FrequencyData",), "symid.fit.frf", default_method="auto"),
    DataKind("spectra", ("SpectralData",), "symid.fit.spectra", default_method="auto"),
    DataKind("time series", ("IOData", "TimeSeries"), "symid.fit.timeseries", default_method="auto"),
    DataKind("black box", ("BlackBox",), "symid.fit.similarity"),
)


def data_kinds() -> tuple[DataKind, ...]:
    """Every data kind symid estimates from."""
    return _KINDS


def data_kind(data: Any) -> DataKind:
    """The kind of a data object (a :class:`DataError` for anything else).

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> from symid.fit.registry import data_kind
    >>> data_kind(si.FrequencyData([1.0, 2.0], np.ones(2))).methods
    ('scr', 'ipopt', 'ls', 'lm', 'auto')
    """
    if isinstance(data, (list, tuple)) and data:  # several experiments: every record a time series
        names = {type(d).__name__ for d in data}
        if names <= {"IOData", "TimeSeries"} and all(type(d).__module__.startswith("symid.data") for d in data):
            return _KINDS[2]
        raise DataError(f"a list of data is read as several experiments and must hold only IOData or TimeSeries "
                        f"records; got {', '.join(sorted(names))}")
    name = type(data).__name__
    for kind in _KINDS:
        if name in kind.data_types and type(data).__module__.startswith("symid.data"):
            return kind
    known = ", ".join(t for k in _KINDS for t in k.data_types)
    raise DataError(f"symid estimates from {known}; got {name}")


def all_methods() -> tuple[str, ...]:
    """Every method name of every kind, in a stable order."""
    out: list[str] = []
    for kind in _KINDS:
        out.extend(m for m in kind.methods if m not in out)
    return tuple(out)


def check_model(model: Any) -> None:
    """Refuse anything but a StateSpaceModel or SecondOrderModel, with the step to take for a model file or a zoo
    entry (a :class:`~symid.errors.ModelError`).

    Examples
    --------
    >>> from symid.fit.registry import check_model
    >>> check_model("m s^2 + k")
    Traceback (most recent call last):
    ...
    symid.errors.ModelError: model must be a StateSpaceModel or SecondOrderModel; got str
    """
    from symid.model.secondorder import SecondOrderModel
    from symid.model.statespace import StateSpaceModel

    if isinstance(model, (StateSpaceModel, SecondOrderModel)):
        return
    kind = type(model).__name__
    if any(c.__name__ == "ModelFile" for c in type(model).__mro__):
        raise ModelError(f"model is a {kind} (what si.load_model returns), not a model: pass spec.free_model() "
                         "(the model with the file's known values substituted), and the file's start, scale and "
                         "bounds as x0=spec.start, scale=spec.scale, bounds=spec.bounds where you want them")
    raise ModelError(f"model must be a StateSpaceModel or SecondOrderModel; got {kind}")


def prepare(model: Any, data: Any, method: str, options: dict[str, Any], *,
            noise_floor: float | None = None) -> Estimator:
    """The estimator of ``method`` for this model and data, its options validated."""
    check_model(model)
    if model.n_parameters == 0:
        raise ModelError("the model has no free parameter: there is nothing to estimate")
    if not isinstance(method, str):
        raise ModelError(f"method must be a name (str); got {method!r}")
    # the kind's package refuses an unknown method, with advice where a known one does not apply
    return data_kind(data).prepare(model, data, method, dict(options), noise_floor=noise_floor)
