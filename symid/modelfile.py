"""Model files: a user's model in a Python file, with what the user knows about its parameters.

A model file is a Python file that defines one model, and optionally what is known
about its parameters::

    # chain.py: a symid model file (Python code, run when symid loads it)
    import symid as si

    m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
    model = si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                                K=[[k1 + k2, -k2], [-k2, k2]], B=[[0], [1]], C=[[1, 0]])

    known = {"m1": 0.5}                              # measured: substituted before estimation
    start = {"m2": 1.0, "c1": 0.5, "c2": 0.5, "k1": 100.0, "k2": 100.0}   # a first guess of θ
    scale = {"m2": 1.0, "c1": 0.5, "c2": 0.5, "k1": 100.0, "k2": 100.0}   # typical magnitudes
    bounds = {"k1": (10.0, 1000.0), "k2": (10.0, 1000.0)}                # plausible ranges
    title = "Two masses on springs, force on mass 2, position of mass 1"
    input_units, output_units = "N", "m"             # for plot labels: H in m/N
    initial_state = "estimate"                       # time series: records that do not start at rest
    time_unit = "s"                                  # the time unit the model's rates are written in

Only ``model`` is required (any name works when the file defines exactly one model;
with several, the one to use must be called ``model``). The other names are optional
and read as described in :class:`ModelFile`. The initial state x(0) of a state-space
model is part of the model (``si.StateSpaceModel(..., x0=[...])``).

The zoo's files (``models/``, ``symid models``) are the same format plus three names
that only a simulation study has: ``truth`` (the true values), ``make_data(model, truth,
noise=None, seed=None)`` (the data recipe) and ``recipe`` (that recipe in words); such a
file loads as a :class:`~symid.zoo.ZooEntry`.

Model files are code
--------------------
Loading a model file runs it, with every right of the user who runs symid: only load
files you wrote or trust, as you would only run scripts you trust. (Data files are
different: symid reads them as data and never runs anything in them.)
"""

from __future__ import annotations

import difflib
import importlib.util
import math
import numbers
import sys
import traceback
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import sympy as sp

from symid.errors import ModelError, ModelWarning, SymidError, did_you_mean
from symid.model.secondorder import SecondOrderModel
from symid.model.statespace import StateSpaceModel

__all__ = ["EXAMPLE", "ModelFile", "read_model_file", "substitute_known"]

EXAMPLE = ('    k, c = si.parameters("k c", positive=True)              # after `import symid as si`\n'
           '    model = si.SecondOrderModel(M=[[1.0]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])')
"""The two-line model file quoted by every error about a model file's contents."""

_MODEL_TYPES = (StateSpaceModel, SecondOrderModel)
_OPTIONAL = ("known", "start", "scale", "bounds", "title", "source", "notes", "input_units", "output_units",
             "initial_state", "time_unit")


def _model_error(where: str, what: str) -> ModelError:
    return ModelError(f"{where}: {what}. A model file defines the model, for example:\n{EXAMPLE}")


@dataclass(frozen=True, kw_only=True)
class ModelFile:
    """A model with what its user knows about the parameters, as read from a model file.

    Attributes
    ----------
    name : str
        The file name without ``.py`` (the zoo name for a zoo entry).
    model : StateSpaceModel or SecondOrderModel
        The symbolic model, every parameter free (``known`` is applied by
        :meth:`free_model`).
    title, source, notes : str
        One-line description, where the model comes from, remarks (all optional).
    known : dict of str to float
        Parameters whose values are known: they are substituted into the model before
        estimation (:meth:`free_model`) and passed to :func:`symid.identifiability` as
        ``known=``.
    start : dict of str to float or None
        A first guess of every free parameter: the first start of ``symid identify``.
    scale : dict of str to float
        Typical magnitude of each free parameter (positive), for the estimators that take
        ``scale=`` (the unknowns become θ / scale).
    bounds : dict of str to (float, float)
        Plausible range (low, high) of some free parameters; ``±inf`` leaves a side open.
        ``start`` must lie inside them; ``symid identify`` passes them to the methods that
        take ``bounds=`` (the default ``auto``, ``lm``, ``oe``, ``ipopt``: the estimate stays
        inside), reports an estimate of the other methods outside them and, when every free
        parameter has finite bounds and no start is given, starts at their centre
        (geometric for positive ranges).
    input_units, output_units : tuple of str
        Physical unit of each input and output (labels only: the Bode plot's |H| is in
        output unit per input unit). Empty when not given.
    initial_state : {"estimate", "zero"} or None
        How time-series fits take the initial state (``si.identify``'s option of that name):
        ``"estimate"`` for records that do not start at rest (a room at 18 °C), which a
        second-order model cannot say itself (a state-space model can: ``x0="estimate"``).
        ``symid identify`` passes it on (a method that takes no initial state is told so); in
        Python give it yourself, ``si.identify(spec.free_model(), io,
        initial_state=spec.initial_state)``. ``None`` when not given.
    time_unit : str or None
        The time unit the model's rates, and the file's ``known``, ``start``, ``scale`` and
        ``bounds``, are written in (``"s"``, ``"min"``, ``"h"``, ...; canonical name).
        ``symid identify`` reads a table's times into it (unless ``--time-unit`` says
        otherwise), and :func:`symid.identify` warns when a record's ``time_unit``, or a
        frequency response's rad/s, is another unit: symid converts no rate, so a factor
        between them would go into the estimates unsaid. ``None`` when not given (the CLI
        then reads records in seconds).
    path : str or None
        The file it was read from (``None`` for a model built in Python).

    Examples
    --------
    >>> import os, tempfile
    >>> import symid as si
    >>> path = os.path.join(tempfile.mkdtemp(), "spring.py")
    >>> with open(path, "w") as fh:
    ...     _ = fh.write('import symid as si\\n'
    ...                  'm, c, k = si.parameters("m c k", positive=True)\\n'
    ...                  'model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])\\n'
    ...                  'known = {"m": 2.0}\\n')
    >>> spec = si.load_model(path)
    >>> spec.name, spec.model.parameter_names, spec.free_model().parameter_names
    ('spring', ('m', 'c', 'k'), ('c', 'k'))
    """

    name: str
    model: Any
    title: str = ""
    source: str = ""
    notes: str = ""
    known: dict[str, float] = field(default_factory=dict)
    start: dict[str, float] | None = None
    scale: dict[str, float] = field(default_factory=dict)
    bounds: dict[str, tuple[float, float]] = field(default_factory=dict)
    input_units: tuple[str, ...] = ()
    output_units: tuple[str, ...] = ()
    initial_state: str | None = None
    time_unit: str | None = None
    path: str | None = None

    def free_model(self, known: Mapping[str, float] | None = None) -> Any:
        """The model with the known parameters substituted: θ holds only the free ones.

        Parameters
        ----------
        known : dict of str to float, optional
            Values known beyond (or instead of) the file's ``known``; they win.

        Returns
        -------
        StateSpaceModel or SecondOrderModel
            The model itself when nothing is known.
        """
        return substitute_known(self.model, {**self.known, **dict(known or {})})

    def updated(self, *, known: Mapping[str, float] | None = None, start: Mapping[str, float] | None = None,
                scale: float | Mapping[str, float] | None = None,
                bounds: Mapping[str, tuple[float | None, float | None]] | None = None,
                where: str = "the command line") -> ModelFile:
        """The same declarations with some replaced or extended (the command line's ``--known``, ``--x0`` ...).

        ``known`` and ``bounds`` extend the file's (given names win); ``scale`` replaces it
        when one number, and by name extends it (given names win; a name the file's scale
        lacks must then be given); ``start`` replaces it for the names it gives, the others keep the file's start, else
        their scale, else the centre of their finite bounds. A parameter newly known leaves
        the file's start, scale and bounds.

        Parameters
        ----------
        known, start, scale, bounds
            As the attributes of the same names; ``None`` keeps the file's.
        where : str
            Where the values come from, for messages.

        Returns
        -------
        ModelFile
            Of the same class (a zoo entry stays one), every value checked as when read.
        """
        import dataclasses

        known_ = {**self.known, **_known_values(known or {}, self.model, f"{where}: known")}
        free = [n for n in self.model.parameter_names if n not in known_]
        if isinstance(scale, Mapping):  # by name: the names given win, the others keep the file's (as start)
            scale_ = _scale_values({**{n: v for n, v in self.scale.items() if n in free}, **scale}, free, known_,
                                   where)
        elif scale is not None:
            scale_ = _scale_values(scale, free, known_, where)
        else:
            scale_ = {n: v for n, v in self.scale.items() if n in free} if all(n in self.scale for n in free) else {}
        bounds_ = {n: b for n, b in self.bounds.items() if n in free}
        for n, (lo, hi) in self.bounds.items():  # they drop out with the value made known: said when it lies outside
            if n in known_ and not lo <= known_[n] <= hi:
                import warnings

                from symid.errors import DataWarning

                warnings.warn(f"{where}: {n} is known as {known_[n]:g}, outside the bounds [{lo:g}, {hi:g}] the "
                              f"model file gives for it: check the value or the bounds", DataWarning, stacklevel=2)
        bounds_.update(_bounds_values(bounds or {}, free, known_, where))
        if start is not None:  # a partial start is completed from the file's start, the scale, then the bounds
            given = _check_free(_name_map(start, f"{where}: x0"), free, known_, f"{where}: x0")
            fill = {**_bounds_centres(bounds_), **scale_, **(self.start or {})}
            missing = [n for n in free if n not in given and n not in fill]
            if missing:
                raise ModelError(f"{where}: x0 lacks {', '.join(missing)} and the model file gives no start, scale "
                                 f"or finite bounds for {'it' if len(missing) == 1 else 'them'}: give "
                                 f"{'its' if len(missing) == 1 else 'their'} value(s) too")
            start_ = _start_values({n: given.get(n, fill.get(n)) for n in free}, self.model, free, known_,
                                   f"{where}: x0")
        elif self.start is not None and all(n in self.start for n in free):
            start_ = {n: self.start[n] for n in free}
        else:
            start_ = None
        if start_ is not None:
            bad = {k: v for k, v in start_.items() if k in bounds_ and not bounds_[k][0] <= v <= bounds_[k][1]}
            if bad:
                k, v = next(iter(bad.items()))
                raise ModelError(f"{where}: the start {k} = {v:g} lies outside its bounds {bounds_[k]}; move the "
                                 "start inside or widen the bounds")
        return dataclasses.replace(self, known=known_, start=start_, scale=scale_, bounds=bounds_)

    def bounds_centre(self) -> dict[str, float] | None:
        """The centre of the bounds when every free parameter has finite ones (geometric for 0 < low), else None."""
        free = [n for n in self.model.parameter_names if n not in self.known]
        if not free or any(n not in self.bounds or not all(map(math.isfinite, self.bounds[n])) for n in free):
            return None
        return _bounds_centres({n: self.bounds[n] for n in free})

    def h_unit(self, output: int = 0, input: int = 0) -> str | None:
        """The physical unit of H[output, input] (``"m/N"``), or ``None`` when the units are not given."""
        if not self.input_units or not self.output_units:
            return None
        return f"{self.output_units[output]}/{self.input_units[input]}"

    def outside_bounds(self, theta: Mapping[str, float]) -> dict[str, tuple[float, float, float]]:
        """The parameters of ``theta`` outside their bounds beyond rounding (1e-9 relative): name → (value, low, high).

        An estimate held on a bound by a method can end a rounding error beyond it (the
        log-parameters' exp(log(bound))); that is on the bound, not outside.
        """
        out = {}
        for name, (lo, hi) in self.bounds.items():
            if name not in theta:
                continue
            v = float(theta[name])
            slack = 1e-9 * max(abs(v), 1e-300)
            if not (lo - slack <= v <= hi + slack):
                out[name] = (v, lo, hi)
        return out

    def _spec_lines(self) -> list[str]:
        lines = []
        if self.known:
            lines.append("known (substituted before estimation): "
                         + ", ".join(f"{k} = {v:.6g}" for k, v in self.known.items()))
        if self.start:
            lines.append("start: " + ", ".join(f"{k} = {v:.6g}" for k, v in self.start.items()))
        if self.scale:
            lines.append("scale: " + ", ".join(f"{k} = {v:.6g}" for k, v in self.scale.items()))
        if self.bounds:
            lines.append("bounds: " + ", ".join(f"{lo:.6g} ≤ {k} ≤ {hi:.6g}" for k, (lo, hi) in self.bounds.items()))
        if self.input_units:
            lines.append(f"units: inputs {', '.join(self.input_units)}; outputs {', '.join(self.output_units)}")
        if self.initial_state:
            lines.append(f"initial state: {self.initial_state}")
        if self.time_unit:
            lines.append(f"time unit: {self.time_unit} (rates per {self.time_unit})")
        return lines

    def summary(self) -> str:
        """The model and what the file says about its parameters, as readable text."""
        head = f"{self.name}: {self.title}" if self.title else self.name
        parts = [head]
        if self.source:
            parts.append(f"source: {self.source}")
        parts.append(self.model.summary())
        parts.extend(self._spec_lines())
        if self.notes:
            parts.append(f"notes: {self.notes}")
        return "\n".join(parts)

    def to_dict(self) -> dict[str, Any]:
        """The file's declarations as plain JSON-ready values (the model by its parameters and shape)."""
        return {"name": self.name, "title": self.title, "source": self.source, "path": self.path,
                "model": {"kind": type(self.model).__name__, "parameters": list(self.model.parameter_names),
                          "positive": list(self.model.positive), "n_states": self.model.n_states,
                          "n_inputs": self.model.n_inputs, "n_outputs": self.model.n_outputs},
                "known": dict(self.known), "start": None if self.start is None else dict(self.start),
                "scale": dict(self.scale), "bounds": {k: list(v) for k, v in self.bounds.items()},
                "input_units": list(self.input_units), "output_units": list(self.output_units),
                "initial_state": self.initial_state, "time_unit": self.time_unit}


def substitute_known(model: Any, known: Mapping[str, float]) -> Any:
    """The same model with some parameters replaced by numbers.

    Parameters
    ----------
    model : StateSpaceModel or SecondOrderModel
    known : dict of str to float
        Parameter name → value (finite); the other parameters stay free, in their order.

    Returns
    -------
    StateSpaceModel or SecondOrderModel
        A new model of the same class (the model itself when ``known`` is empty).

    Raises
    ------
    ModelError
        On a name that is not a parameter of the model, or a value that is not a finite number.

    Examples
    --------
    >>> import symid as si
    >>> from symid.modelfile import substitute_known
    >>> m, c, k = si.parameters("m c k", positive=True)
    >>> model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    >>> free = substitute_known(model, {"m": 2.0})
    >>> free.parameter_names, free.matrices({"c": 0.5, "k": 3.0})["M"]
    (('c', 'k'), array([[2.]]))
    """
    known = _known_values(dict(known), model, "known")
    if not known:
        return model
    out = _substituted(model, known)
    out.io_units = dict(getattr(model, "io_units", {}))
    return out


def _substituted(model: Any, known: Mapping[str, float]) -> Any:
    """:func:`substitute_known`'s new model (``known`` checked and not empty)."""
    values = {p: sp.Float(known[p.name]) for p in model.parameters if p.name in known}
    free = [p for p in model.parameters if p.name not in known]
    sym = {k: v.xreplace(values) for k, v in model.symbolic.items()}
    if isinstance(model, SecondOrderModel):
        with warnings.catch_warnings():  # the model's own construction said what there is to say of its matrices
            warnings.simplefilter("ignore", ModelWarning)
            return SecondOrderModel(M=sym["M"], V=sym["V"], K=sym["K"], B=sym["B"], C=sym["C"],
                                    output=model.outputs, parameters=free, name=model.name)
    kind = model.initial_state_kind
    x0: Any = None
    if kind == "estimate":
        x0 = "estimate"
    elif kind != "zero":
        amap = model.initial_state_map
        expr = amap.constant + sum((p * c for p, c in zip(amap.parameters, amap.coefficients, strict=True)),
                                   sp.zeros(*amap.constant.shape))
        x0 = list(expr.xreplace(values))
    return StateSpaceModel(A=sym["A"], B=sym["B"], C=sym["C"], D=sym["D"], x0=x0, parameters=free,
                           name=model.name)


# -- reading a file -----------------------------------------------------------------------------------

def read_model_file(path: str | Path) -> ModelFile:
    """Run a model file and read the model and the optional declarations it makes.

    The file is Python code and runs with the rights of the caller (see the module
    notes): load only files you trust.

    Parameters
    ----------
    path : str or pathlib.Path
        A ``.py`` file.

    Returns
    -------
    ModelFile
        A :class:`~symid.zoo.ZooEntry` when the file also defines ``truth`` and ``make_data``.

    Raises
    ------
    ModelError
        If the file does not exist or is not a ``.py`` file, fails when run (the message
        names the line and the error), defines no model or several, or declares
        ``known``, ``start``, ``scale``, ``bounds`` or units that do not fit the model.

    Examples
    --------
    >>> import os, tempfile
    >>> from symid.modelfile import read_model_file
    >>> path = os.path.join(tempfile.mkdtemp(), "nothing.py")
    >>> _ = open(path, "w").write("x = 1\\n")
    >>> read_model_file(path)
    Traceback (most recent call last):
    ...
    symid.errors.ModelError: model file '...nothing.py': defines no model ...
    """
    text = str(path)
    where = f"model file {text!r}"
    p = Path(text)
    if not p.is_file():
        raise ModelError(f"{where} does not exist" if not p.exists() else f"{where} is not a regular file")
    if p.suffix != ".py":
        raise ModelError(f"{where}: a model file is a Python file ending in .py")
    spec = importlib.util.spec_from_file_location(f"symid_model_file_{abs(hash(str(p.resolve())))}", p)
    if spec is None or spec.loader is None:  # pragma: no cover - a .py file always has a loader
        raise ModelError(f"cannot import {where}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses and pickling inside the file look their module up here
    try:
        spec.loader.exec_module(module)
    except SyntaxError as exc:
        raise ModelError(f"{where}, line {exc.lineno}: syntax error: {exc.msg}") from None
    except SymidError as exc:
        raise ModelError(f"{where}{_line_in(exc, p)}: {type(exc).__name__}: {exc}") from exc
    except Exception as exc:
        raise ModelError(f"{where}{_line_in(exc, p)}: {type(exc).__name__}: {exc} (the file failed when run)") from exc
    finally:
        sys.modules.pop(spec.name, None)
    return from_module(module, name=p.stem, where=where, path=str(p))


def _line_in(exc: BaseException, path: Path) -> str:
    """``, line N`` of the last frame of ``exc`` that ran in ``path`` (empty when none did)."""
    target = str(path.resolve())
    line = None
    for frame in traceback.extract_tb(exc.__traceback__):
        try:
            if str(Path(frame.filename).resolve()) == target:
                line = frame.lineno
        except OSError:  # pragma: no cover - a frame of a file that vanished
            continue
    return "" if line is None else f", line {line}"


def from_module(module: ModuleType, *, name: str, where: str, path: str | None = None) -> ModelFile:
    """The :class:`ModelFile` (or zoo entry) a module that has run defines (used for files and the zoo)."""
    names = vars(module)
    if callable(names.get("entry")) and "model" not in names:
        raise _model_error(where, "defines entry(), the format of older symid versions; define the model at "
                                  "the top level of the file instead (and truth, make_data, recipe for a zoo entry)")
    model = _find_model(names, where)
    _warn_near_names(names, where)
    declared = {k: names[k] for k in _OPTIONAL if k in names}
    known = _known_values(declared.get("known") or {}, model, f"{where}: known")
    free = [n for n in model.parameter_names if n not in known]
    start = None if declared.get("start") is None else _start_values(declared["start"], model, free, known, where)
    scale = _scale_values(declared.get("scale"), free, known, where)
    bounds = _bounds_values(declared.get("bounds") or {}, free, known, where)
    if start is not None:
        bad = {k: v for k, v in start.items() if k in bounds and not bounds[k][0] <= v <= bounds[k][1]}
        if bad:
            k, v = next(iter(bad.items()))
            raise ModelError(f"{where}: start {k} = {v:g} lies outside its bounds {bounds[k]}; move the start "
                             "inside or widen the bounds")
    units_in = _units(declared.get("input_units"), model.n_inputs, "input_units", where)
    units_out = _units(declared.get("output_units"), model.n_outputs, "output_units", where)
    if bool(units_in) != bool(units_out):
        raise ModelError(f"{where}: give both input_units and output_units (the unit of H is their ratio), "
                         "e.g. input_units, output_units = \"N\", \"m\"")
    texts = {k: _text(declared.get(k, ""), k, where) for k in ("title", "source", "notes")}
    initial = declared.get("initial_state")
    if initial is not None and (not isinstance(initial, str) or initial not in ("estimate", "zero")):
        raise ModelError(f"{where}: initial_state is 'estimate' (records that do not start at rest) or 'zero'; got "
                         f"{initial!r}")
    time_unit = _time_unit(declared.get("time_unit"), where)
    io_units: dict[str, tuple[str, ...]] = {}
    if units_in:  # what the data files' stated units are compared with (si.identify)
        io_units.update(input=tuple(units_in), output=tuple(units_out))
    if time_unit is not None:  # and the records' time unit
        io_units["time"] = (time_unit,)
    if io_units:
        model.io_units = io_units
    common = dict(name=name, model=model, known=known, start=start, scale=scale, bounds=bounds,
                  input_units=units_in, output_units=units_out, initial_state=initial, time_unit=time_unit,
                  path=path, **texts)
    zoo_names = [k for k in ("truth", "make_data") if k in names]
    if not zoo_names:
        return ModelFile(**common)
    from symid.zoo import ZooEntry

    if len(zoo_names) == 1:
        missing = "make_data" if zoo_names == ["truth"] else "truth"
        raise ModelError(f"{where} defines {zoo_names[0]} but not {missing}: a simulation study (a zoo entry) "
                         "gives both, the true values and the recipe make_data(model, truth, noise=None, "
                         "seed=None); a model for measured data gives neither")
    truth = _known_values(names["truth"], model, f"{where}: truth")
    missing = [n for n in model.parameter_names if n not in truth]
    if missing:
        raise ModelError(f"{where}: truth lacks {', '.join(missing)}; it gives every parameter's true value")
    if not callable(names["make_data"]):
        raise ModelError(f"{where}: make_data must be a function make_data(model, truth, noise=None, seed=None)")
    recipe = names.get("recipe") or (names["make_data"].__doc__ or "").strip().split("\n")[0]
    extra = names.get("extra", {})
    if not isinstance(extra, Mapping):
        raise ModelError(f"{where}: extra must be a dict; got {type(extra).__name__}")
    return ZooEntry(**common, truth={n: truth[n] for n in model.parameter_names}, recipe=_text(recipe, "recipe", where),
                    make_data=names["make_data"], extra=dict(extra))


_READ = (*_OPTIONAL, "model", "truth", "make_data", "recipe")
"""The top-level names symid reads in a model file (a zoo entry's too)."""


def _warn_near_names(names: Mapping[str, Any], where: str) -> None:
    """A ModelWarning for a top-level value whose name is nearly one symid reads (``bound``, ``Known``,
    ``starts``): symid would pass it over, and the fit run without it."""
    for name, value in names.items():
        if name.startswith("_") or name in _READ or not isinstance(value, (Mapping, list, tuple, str, numbers.Real)):
            continue
        near = [k for k in _READ if k.lower() == name.lower()] or \
            difflib.get_close_matches(name, _READ, n=1, cutoff=0.8)
        if near:
            warnings.warn(f"{where} defines {name!r}, which symid does not read; did you mean {near[0]!r}? (as "
                          f"written it plays no part in the fit)", ModelWarning, stacklevel=4)


def _find_model(names: Mapping[str, Any], where: str) -> Any:
    if "model" in names:
        model = names["model"]
        if not isinstance(model, _MODEL_TYPES):
            raise _model_error(where, f"`model` is a {type(model).__name__}, not a si.StateSpaceModel or "
                                      "si.SecondOrderModel")
        return model
    found = [k for k, v in names.items() if isinstance(v, _MODEL_TYPES) and not k.startswith("_")]
    if not found:
        raise _model_error(where, "defines no model (no si.StateSpaceModel or si.SecondOrderModel at the top "
                                  "level of the file)")
    if len(found) > 1:
        raise _model_error(where, f"defines several models ({', '.join(found)}); name the one to use `model`")
    return names[found[0]]


def _number(value: Any, what: str) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ModelError(f"{what} must be a number; got {value!r}")
    x = float(value)
    if not math.isfinite(x):
        raise ModelError(f"{what} must be finite; got {x!r}")
    return x


def _name_map(value: Any, what: str) -> dict[str, Any]:
    if not isinstance(value, Mapping):
        raise ModelError(f"{what} must be a dict by parameter name, e.g. {{\"k\": 100.0}}; got "
                         f"{type(value).__name__}")
    return {(k.name if isinstance(k, sp.Symbol) else str(k)): v for k, v in value.items()}


def _known_values(value: Any, model: Any, what: str) -> dict[str, float]:
    given = _name_map(value, what)
    unknown = [k for k in given if k not in model.parameter_names]
    if unknown:
        raise ModelError(f"{what} names {', '.join(map(repr, unknown))}, not a parameter of the model"
                         f"{did_you_mean(unknown, model.parameter_names)} ({', '.join(model.parameter_names)})")
    out = {k: _number(v, f"{what} {k}") for k, v in given.items()}
    positive = dict(zip(model.parameter_names, model.positive, strict=True))
    bad = [k for k, v in out.items() if positive[k] and v < 0]
    if bad:
        raise ModelError(f"{what} {bad[0]} = {out[bad[0]]:g}, but {bad[0]} is declared positive; give its value ≥ 0 "
                         f"(or declare it without positive=True)")
    return out


def _equal_number(value: Any, known: float) -> bool:
    """Whether ``value`` is a number equal to ``known`` (to 1e-12 of it)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return False
    return math.isclose(float(value), float(known), rel_tol=1e-12, abs_tol=0.0)


def _check_free(given: Mapping[str, Any], free: Sequence[str], known: Mapping[str, float], what: str
                ) -> dict[str, Any]:
    """``given`` without the known parameters (a ModelWarning names those given another value than the known one,
    which is used); a name that is no parameter at all is a ModelError."""
    # an entry that gives the known value itself is set aside without a word (a new user's file serves the fits
    # with Km known and free alike: start = {..., "Km": 0.08}, known = {"Km": 0.08})
    given = {k: v for k, v in given.items() if not (k in known and _equal_number(v, known[k]))}
    on_known = [k for k in given if k in known]
    if on_known:
        # two new users added `known` to a file whose start named the parameter, and were refused: the known value
        # is what the fit uses, so the entry is set aside, and said
        values = ", ".join(f"{k} = {known[k]:g}" for k in on_known)
        warnings.warn(f"{what} gives {', '.join(on_known)}, declared known ({values}): known parameters are not "
                      f"estimated, so {'this entry is' if len(on_known) == 1 else 'these entries are'} left out",
                      ModelWarning, stacklevel=4)
        given = {k: v for k, v in given.items() if k not in known}
    unknown = [k for k in given if k not in free]
    if unknown:
        raise ModelError(f"{what} names {', '.join(map(repr, unknown))}, not a parameter of the model"
                         f"{did_you_mean(unknown, [*free, *known])} (free parameters: {', '.join(free)})")
    return dict(given)


def _bounds_centres(bounds: Mapping[str, tuple[float, float]]) -> dict[str, float]:
    """The centre of each pair of finite bounds (geometric for 0 < low); names without finite bounds are left out."""
    out = {}
    for n, (lo, hi) in bounds.items():
        if math.isfinite(lo) and math.isfinite(hi):
            out[n] = math.sqrt(lo * hi) if lo > 0 else 0.5 * (lo + hi)
    return out


def _start_values(value: Any, model: Any, free: list[str], known: Mapping[str, float], where: str
                  ) -> dict[str, float]:
    given = _check_free(_name_map(value, f"{where}: start"), free, known, f"{where}: start")
    missing = [k for k in free if k not in given]
    if missing:
        raise ModelError(f"{where}: start lacks {', '.join(missing)}; a start gives every free parameter")
    return {k: _number(given[k], f"{where}: start {k}") for k in free}


def _scale_values(value: Any, free: list[str], known: Mapping[str, float], where: str) -> dict[str, float]:
    if value is None:
        return {}
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        given = dict.fromkeys(free, value)
    else:
        given = _check_free(_name_map(value, f"{where}: scale"), free, known, f"{where}: scale")
        missing = [k for k in free if k not in given]
        if missing:
            raise ModelError(f"{where}: scale lacks {', '.join(missing)}; give one typical magnitude per free "
                             "parameter, or one number for all")
    out = {k: _number(given[k], f"{where}: scale {k}") for k in free}
    bad = [k for k, v in out.items() if v <= 0]
    if bad:
        raise ModelError(f"{where}: scale {bad[0]} = {out[bad[0]]!r}; a typical magnitude is a positive number")
    return out


def _bounds_values(value: Any, free: list[str], known: Mapping[str, float], where: str
                   ) -> dict[str, tuple[float, float]]:
    given = _check_free(_name_map(value, f"{where}: bounds"), free, known, f"{where}: bounds")
    out = {}
    for k in free:
        if k not in given:
            continue
        pair = given[k]
        if isinstance(pair, (str, bytes)) or not isinstance(pair, Sequence) or len(pair) != 2:
            raise ModelError(f"{where}: bounds {k} must be a pair (low, high), e.g. (10.0, 1000.0); got {pair!r}")
        lo = -math.inf if pair[0] is None else pair[0]
        hi = math.inf if pair[1] is None else pair[1]
        for side, x in (("low", lo), ("high", hi)):
            if isinstance(x, (bool, np.bool_)) or not isinstance(x, numbers.Real) or math.isnan(float(x)):
                raise ModelError(f"{where}: bounds {k}: the {side} end must be a number (or None for no bound); "
                                 f"got {x!r}")
        lo, hi = float(lo), float(hi)
        if not lo < hi:
            raise ModelError(f"{where}: bounds {k} = ({lo:g}, {hi:g}); the low end must be below the high end")
        out[k] = (lo, hi)
    return out


def _time_unit(value: Any, where: str) -> str | None:
    """The canonical name of a model file's ``time_unit`` (None when not given), or a ModelError naming it."""
    if value is None:
        return None
    from symid.data.units import canonical_unit
    from symid.errors import DataError

    try:
        return canonical_unit(value, "time", "time_unit")
    except DataError as exc:
        raise ModelError(f"{where}: {exc}") from None


def _units(value: Any, n: int, what: str, where: str) -> tuple[str, ...]:
    if value is None:
        return ()
    items = [value] * n if isinstance(value, str) else value
    if isinstance(items, (bytes, Mapping)) or not isinstance(items, Sequence):
        raise ModelError(f"{where}: {what} must be a unit name or one per channel; got {value!r}")
    items = list(items)
    if len(items) != n:
        raise ModelError(f"{where}: {what} gives {len(items)} unit(s); the model has {n}")
    return tuple(_text(u, what, where) for u in items)


def _text(value: Any, what: str, where: str) -> str:
    if not isinstance(value, str):
        raise ModelError(f"{where}: {what} must be text; got {type(value).__name__}")
    return value
