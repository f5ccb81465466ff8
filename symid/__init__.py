"""symid: continuous-time grey-box system identification by bilinear optimisation.

The light core (models, data, errors, the zoo) is imported eagerly; the estimators,
simulators and the identifiability report load on first use (PEP 562), so that
``import symid`` costs little more than importing sympy.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from symid.data import BlackBox, FrequencyData, IOData, SpectralData, TimeSeries, read_data
from symid.errors import (
    DataError,
    DataWarning,
    IdentifiabilityWarning,
    ModelError,
    ModelWarning,
    NonAffineError,
    OptionError,
    SolverError,
    SymidError,
)
from symid.fit.result import IdentificationResult, StartOutcome
from symid.model.lti import StateSpaceMatrices
from symid.model.secondorder import SecondOrderModel
from symid.model.statespace import StateSpaceModel
from symid.model.symbols import parameters
from symid.modelfile import ModelFile
from symid.zoo import ZooEntry, list_models, load_model

if TYPE_CHECKING:
    from symid.fit.compare import Comparison, MethodStats, compare
    from symid.fit.identify import identify
    from symid.fit.validation import Validation, validate
    from symid.signal.frf import estimate_coherence, estimate_frf
    from symid.signal.simulate import simulate_frf, simulate_io, simulate_spectra
    from symid.signal.spectra import estimate_spectra
    from symid.signal.subspace import n4sid
    from symid.signal.zoh import d2c
    from symid.structural import IdentifiabilityReport, identifiability

__version__ = "0.1.0"

_LAZY = {
    "Comparison": "symid.fit.compare",
    "MethodStats": "symid.fit.compare",
    "compare": "symid.fit.compare",
    "d2c": "symid.signal.zoh",
    "n4sid": "symid.signal.subspace",
    "identify": "symid.fit.identify",
    "validate": "symid.fit.validation",
    "Validation": "symid.fit.validation",
    "simulate_frf": "symid.signal.simulate",
    "simulate_io": "symid.signal.simulate",
    "simulate_spectra": "symid.signal.simulate",
    "estimate_spectra": "symid.signal.spectra",
    "estimate_frf": "symid.signal.frf",
    "estimate_coherence": "symid.signal.frf",
    "IdentifiabilityReport": "symid.structural",
    "identifiability": "symid.structural",
}


_LAZY_MODULES = {"scr": "symid.engine.scr"}  # ``from symid import scr``: the SCR engine


def __getattr__(name: str) -> Any:
    if name in _LAZY_MODULES:
        value = importlib.import_module(_LAZY_MODULES[name])
        globals()[name] = value
        return value
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'symid' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY) | set(_LAZY_MODULES))


__all__ = [
    "BlackBox",
    "Comparison",
    "DataError",
    "DataWarning",
    "FrequencyData",
    "IOData",
    "IdentifiabilityReport",
    "IdentifiabilityWarning",
    "IdentificationResult",
    "MethodStats",
    "ModelError",
    "ModelFile",
    "ModelWarning",
    "NonAffineError",
    "OptionError",
    "SecondOrderModel",
    "SolverError",
    "SpectralData",
    "StartOutcome",
    "StateSpaceMatrices",
    "StateSpaceModel",
    "SymidError",
    "TimeSeries",
    "Validation",
    "ZooEntry",
    "compare",
    "d2c",
    "estimate_coherence",
    "estimate_frf",
    "estimate_spectra",
    "identifiability",
    "identify",
    "list_models",
    "load_model",
    "n4sid",
    "parameters",
    "read_data",
    "simulate_frf",
    "simulate_io",
    "simulate_spectra",
    "validate",
]
