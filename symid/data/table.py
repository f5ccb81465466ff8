"""Reading the user's own measurements: plain CSV with named columns, pandas DataFrames, MATLAB files, dicts.

symid's own CSV and NPZ files (``to_csv``/``from_csv``, :func:`symid.data.load`) are
the lossless round-trip format. Measurements made elsewhere come in through a *table*
and a declaration of which column plays which role, in which unit:

>>> import numpy as np
>>> from symid.data import FrequencyData
>>> table = {"f": [0.1, 0.2, 0.4], "mag": [0.0, -3.0, -12.0], "ph": [-10.0, -45.0, -80.0]}
>>> frf = FrequencyData.from_table(table, columns={"frequency": "f", "magnitude": "mag", "phase": "ph"},
...                                units={"frequency": "Hz", "magnitude": "dB", "phase": "deg"})
>>> frf.w.round(4)                                   # converted at the door: ω = 2π f
array([0.6283, 1.2566, 2.5133])

A table is one of

* the path of a plain CSV file: one header line of column names (``"quoted"`` names
  are unquoted), then one row of numbers per sample; ``delimiter=`` sets the separator
  (``","`` by default, ``";"`` and tab work too). Lines starting with ``#`` are comments.
  A comment that states units (``# units: Hz, dB``, or per column ``# units: t [s]``,
  ``time=s``) is checked against the declared units, never ignored: a unit it names that
  contradicts the declaration, or any unit stated while ``units`` is not given, is an
  error; a unit inside another column's unit (``mag [dB re 1 (rad/s)/N]``) is that
  column's, not a statement about the frequency. Only the declared columns are
  parsed, so other columns may hold anything (dates, text). At most
  :data:`MAX_TABLE_BYTES`;
* the path of a MATLAB ``.mat`` file (level 5, what ``save`` writes): columns are
  variable names; a 2-D variable holds several channels (its axis whose length is the
  number of samples is the sample axis) and ``name[k]`` picks channel k. Sizes are
  checked before anything is read (:mod:`symid.data._matfile`);
* a pandas ``DataFrame`` (read through its ``columns`` and ``to_numpy``; pandas is not a
  dependency of symid) or any mapping of names to arrays.

Roles and units
---------------
Frequency response (:meth:`FrequencyData.from_table <symid.data.FrequencyData.from_table>`):
``frequency`` with its unit, and H as ``real`` and ``imag`` (no unit), or as
``magnitude`` (unit ``dB`` or ``linear``) and ``phase`` (``deg`` or ``rad``). For a
system with several inputs or outputs, name each entry: ``"real[i][j]"`` (output i,
input j), or give a nested list of names.

Time series (:meth:`IOData.from_table <symid.data.IOData.from_table>`,
:meth:`TimeSeries.from_table <symid.data.TimeSeries.from_table>`): ``input`` and
``output`` (a name or a list of names), and the sample times as a ``time`` column or as
a sample time ``dt=``, either with its unit ``units={"time": ...}``. Times are converted
to ``time_unit`` (seconds by default), which the record keeps and reports.

The units are those of :mod:`symid.data.units`. Every unit that matters must be given:
symid never guesses one.
"""

from __future__ import annotations

import csv
import os
import re
import sys
import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from symid.data import _files, checks
from symid.data.units import DIMENSIONS, canonical_unit, time_factor, unit_tokens
from symid.errors import DataError, DataWarning

__all__ = ["FRF_ROLES", "MAX_TABLE_BYTES", "SERIES_ROLES", "frequency_data_from_table", "outputs_from_table",
           "read_data", "series_from_table"]

MAX_TABLE_BYTES = 2**30
"""Largest plain CSV file read as a table (1 GiB): larger files are refused before they are read."""

FRF_ROLES = ("frequency", "real", "imag", "magnitude", "phase")
"""Column roles of a frequency-response table."""

SERIES_ROLES = ("time", "input", "output")
"""Column roles of a time-series table."""

_UNIT_DIMENSION = {"frequency": "frequency", "magnitude": "magnitude", "phase": "phase", "time": "time"}
_INDEXED = re.compile(r"^(real|imag|magnitude|phase)\[(\d{1,4})\]\[(\d{1,4})\]$")
_CHANNEL = re.compile(r"^(.*)\[(\d{1,6})\]$")

FRF_EXAMPLE = ('    columns={"frequency": "f", "magnitude": "mag", "phase": "ph"}, '
               'units={"frequency": "Hz", "magnitude": "dB", "phase": "deg"}   (Python)\n'
               '    --columns frequency=f magnitude=mag phase=ph --units frequency=Hz magnitude=dB phase=deg   '
               '(command line)')
"""Two lines, Python and command line, quoted by errors about a frequency-response table."""

SERIES_EXAMPLE = ('    columns={"time": "t", "input": "u", "output": "y"}, units={"time": "s"}   (Python)\n'
                  '    --columns time=t input=u output=y --units time=s   (command line)')
"""Two lines, Python and command line, quoted by errors about a time-series table."""


def _fail(where: str, what: str, example: str) -> DataError:
    return DataError(f"{where}: {what}. For example:\n{example}")


# -- sources ------------------------------------------------------------------------------------------

_MISSING_HINT = {"uniform": " (an output not measured at some times: read the table as a TimeSeries, "
                             "TimeSeries.from_table or kind='TimeSeries', --kind TimeSeries on the command line, "
                             "where an empty cell or NaN marks it)"}
"""What to add to an error about a missing or non-finite value, by the source's ``missing_hint``."""


def _looks_like_units(cells: list[str]) -> bool:
    """Every cell of a row is a short text with a letter, %, ° or µ and none is a number: a row of units."""
    def unit(cell: str) -> bool:
        text = cell.strip().strip("[]()")
        try:
            float(text)
            return False
        except ValueError:
            return 0 < len(text) <= 12 and bool(re.search(r"[A-Za-z%°µ]", text))
    return bool(cells) and all(unit(c) for c in cells)


def _other_delimiter(header: list[str], delimiter: str) -> str:
    """A hint when a one-column header holds another delimiter (a new user's ';'-separated file with decimal commas
    was told only its cell counts)."""
    if len(header) != 1:
        return ""
    for other, name in ((";", "';'"), ("\t", "tab ('\\t')"), ("|", "'|'")):
        if other != delimiter and other in header[0]:
            return (f"; the header holds {name}: is that the delimiter? (delimiter={other!r} in Python, "
                    f"--delimiter {other!r} on the command line)")
    return ""


def _caller_level() -> int:
    """The ``stacklevel`` of the first frame outside symid, for a warning of the function that calls this one (a
    table is read through several layers, more from ``read_data`` than from ``from_table``)."""
    package = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    frame, level = sys._getframe(1), 1
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(package + os.sep):
        frame, level = frame.f_back, level + 1
    return level


def _cells(split: Any, line: str) -> list[str]:
    """A line's cells, stripped, a cell in double quotes its text."""
    return [c[1:-1].strip() if len(c) >= 2 and c[0] == c[-1] == '"' else c for c in (c.strip() for c in split(line))]


PREAMBLE_LINES = 50
"""How far down a header is looked for when the first line does not name the columns asked for."""


def _preamble(lines: list[tuple[int, str]], split: Any, names: Sequence[str]) -> int:
    """How many lines precede the header: 0, or (an analyzer's export: "Instrument: …", "Date: …" above the names)
    the index of the first of the first ``PREAMBLE_LINES`` lines whose cells hold every name asked for, when the
    first line's do not and every line above it has fewer cells."""
    wanted = [n for n in names if n]
    if not wanted or not lines or all(n in _cells(split, lines[0][1]) for n in wanted):
        return 0
    for i, (_, line) in enumerate(lines[1:PREAMBLE_LINES], start=1):
        cells = _cells(split, line)
        if all(n in cells for n in wanted):
            return i if all(len(_cells(split, above)) < len(cells) for _, above in lines[:i]) else 0
    return 0


class _Csv:
    """A plain CSV file: header of names, rows of text cells parsed column by column on demand."""

    missing_hint = ""

    def __init__(self, path: _files.PathLike, delimiter: str, names: Sequence[str] = ()):
        if delimiter not in (",", ";", "\t", "|", " "):
            raise DataError(f"delimiter must be one of ',', ';', tab, '|' or ' '; got {delimiter!r}")
        self.delimiter = delimiter
        self.where = repr(os.fspath(path))
        with _files._open_regular(path) as fh:
            size = os.fstat(fh.fileno()).st_size
            if size > MAX_TABLE_BYTES:
                raise DataError(f"{self.where} has {size} bytes, more than the {MAX_TABLE_BYTES} symid reads as a "
                                "CSV table; save the measurements as .npz (numpy) or .mat instead")
            raw = fh.read(MAX_TABLE_BYTES + 1)
        if raw.startswith(_files._ZIP_SIGNATURES) or raw.startswith(_files._NPY_MAGIC):
            raise DataError(f"{self.where} is a zip or .npy file, not a CSV table; symid's own .npz files are read "
                            "without columns (symid.data.load)")
        try:
            text = raw.decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            raise DataError(f"{self.where} is not a UTF-8 text file (byte {exc.start}); save the table as UTF-8 "
                            "CSV") from None
        if text.startswith(_files._CSV_MAGIC):
            raise DataError(f"{self.where} is a symid CSV file: read it without columns and units "
                            "(symid.data.load, or --data alone); its layout is fixed by symid")
        self.comments: list[tuple[int, str]] = []
        self.rows: list[tuple[int, list[str]]] = []
        header = None
        # a cell in double quotes (as spreadsheets export every cell, numbers too) is its text, the delimiter inside
        # it included (a new user's "a, b" and "0,0002" were split at their commas)
        split = (lambda line: line.split()) if delimiter == " " else (
            lambda line: next(csv.reader([line], delimiter=delimiter, quotechar='"', skipinitialspace=True), []))
        lines = []
        for k, line in enumerate(text.splitlines(), start=1):
            if not line.strip():
                continue
            if line.lstrip().startswith("#"):
                self.comments.append((k, line.strip()))
                continue
            lines.append((k, line))
        skip = _preamble(lines, split, names)
        if skip:  # said, and kept with the comments: nothing read as data, nothing lost
            self.comments.extend((k, line.strip()) for k, line in lines[:skip])
            self.comments.sort()
            warnings.warn(f"{self.where}: line{'s' if skip > 1 else ''} {lines[0][0]}"
                          f"{'–' + str(lines[skip - 1][0]) if skip > 1 else ''} read as a preamble above the "
                          f"header (line {lines[skip][0]}, the first to name the columns asked for): "
                          f"{_files._show(lines[0][1].strip())}{' …' if skip > 1 else ''}", DataWarning,
                          stacklevel=_caller_level())
        for k, line in lines[skip:]:
            cells = _cells(split, line)
            if header is None:
                header = cells
                self.header_line = k
                continue
            if len(cells) != len(header):
                wanted = [n for n in names if n]
                other = _other_delimiter(header, delimiter)
                preamble = "" if other or not wanted or len(cells) <= len(header) else (
                    f"; if the lines above are a preamble (an instrument's export), the header is the first line "
                    f"that names every column asked for ({', '.join(map(repr, wanted))}), and none of the first "
                    f"{PREAMBLE_LINES} does")
                raise DataError(f"{self.where}, line {k}: {len(cells)} cells; the header (line {self.header_line}) "
                                f"has {len(header)} column{'s' if len(header) != 1 else ''} (delimiter "
                                f"{delimiter!r})" + other + preamble)
            self.rows.append((k, cells))
        if header is None:
            raise DataError(f"{self.where} holds no header line of column names")
        dup = sorted({c for c in header if header.count(c) > 1})
        if dup:
            raise DataError(f"{self.where}: the header names column {_files._show(dup[0])} twice")
        if not self.rows:
            raise DataError(f"{self.where} holds a header but no data rows")
        self.names = header

    def has(self, name: str) -> bool:
        return name in self.names

    def get(self, name: str, missing_ok: bool = False) -> np.ndarray:
        """A column's numbers; an empty cell or NaN is a missing value (NaN) where ``missing_ok``."""
        c = self.names.index(name)
        out = np.empty(len(self.rows))
        for r, (line, cells) in enumerate(self.rows):
            cell = cells[c]
            if missing_ok and cell.strip().lower() in ("", "nan", "na"):
                out[r] = np.nan
                continue
            if not cell:
                raise DataError(f"{self.where}, line {line}, column {name!r}: the value is missing" +
                                _MISSING_HINT.get(self.missing_hint, ""))
            try:
                if not cell.isascii() or "_" in cell:
                    raise ValueError(cell)
                out[r] = float(cell)
            except ValueError:
                comma = re.fullmatch(r"[+-]?\d*,\d+(?:[eE][+-]?\d+)?", cell.strip())
                # a row of units under the header (a new user's "s,A,rad/s"): said so, with where units go
                units_row = r == 0 and len(self.rows) > 1 and _looks_like_units(cells)
                raise DataError(f"{self.where}, line {line}, column {name!r}: {_files._show(cell)} is not a "
                                "number" + (" (a decimal comma? symid reads '.' as the decimal point: export the "
                                            "file with '.', or replace ',' by '.' in its numbers)" if comma else
                                            f" (a row of units under the header? symid reads units from the header "
                                            f"('{name} [{cell}]') or a '# units:' comment line, and declared ones "
                                            f"(units=, --units): delete that row)" if units_row else "")
                                ) from None
            if not np.isfinite(out[r]):
                raise DataError(f"{self.where}, line {line}, column {name!r}: {cell} is not a finite number; "
                                "drop or fill that row" + _MISSING_HINT.get(self.missing_hint, ""))
        return out

    def check_unit_comments(self, declared: Mapping[str, str], example: str,
                            columns: Mapping[str, str] | None = None, read: Sequence[str] = ()) -> None:
        """A comment that states units must agree with the declared ones (and units must be declared).

        ``columns``: the name of the column of each role that has a unit (``{"t": "time"}``),
        so that ``t [s]`` or ``t=s`` is read as the unit of that column; ``read``: every
        column read, whose stated units (``u [mg/h]``) are then not taken for another
        role's (:func:`_stated_units`).
        """
        roles: dict[str, str | None] = dict.fromkeys(_UNIT_DIMENSION)
        roles.update({_base_name(n): "" for n in (*read, *self.names)})
        roles.update(columns or {})
        for line, comment in self.comments:
            if not re.search(r"\bunits?\b", comment, flags=re.IGNORECASE):
                continue
            if not declared:
                raise _fail(f"{self.where}, line {line}", f"the file states units ({_files._show(comment, 60)}) but "
                            "none were declared; symid never guesses units from a comment: declare them", example)
            for name, role, text in _unread_units(comment, roles):
                dimension = _UNIT_DIMENSION[role]
                mine = sorted({u for r, u in declared.items() if _UNIT_DIMENSION.get(r) == dimension})
                warnings.warn(f"{self.where}, line {line}: the file states {_files._show(text, 30)} for {name!r}, "
                              f"which symid does not read as a {dimension} unit, so it is not checked against the "
                              f"{dimension} unit declared ({', '.join(mine) or 'none'}); make sure that is the "
                              "file's", DataWarning, stacklevel=4)
            for name, dimension, unit in _stated_units(comment, roles):
                mine = {u for role, u in declared.items() if _UNIT_DIMENSION.get(role) == dimension}
                if mine and unit not in mine:
                    what = f"{unit} for {name!r}" if name else unit
                    raise DataError(f"{self.where}, line {line}: the file states {what} ({_files._show(comment, 60)}) "
                                    f"but the {dimension} unit declared is {', '.join(sorted(mine))}; check which "
                                    "is right")


_PAIR = re.compile(r"^([^\s\[\]=:()]+)\s*(?:\[(.*)\]|\((.*)\)|[=:]\s*(.+))$")
"""``name [unit]``, ``name (unit)``, ``name = unit`` or ``name: unit`` in a units comment."""


_ONE_UNIT = re.compile(r"[A-Za-zµμ°]+|rad\s*/\s*s(?:ec)?")
"""A text that can be one unit's name alone (``s``, ``Hz``, ``rad/s``)."""


_NAME_UNIT = re.compile(r"(?:\[\s*([^\[\]]+?)\s*\]|\(\s*([^()]+?)\s*\)|_([^_\s\[\]()]+))\s*$")
"""A unit at the end of a column's name: ``t [s]``, ``f (Hz)``, ``t_ms``."""


def _check_name_units(where: str, declared: Mapping[str, str], columns: Mapping[str, str]) -> None:
    """A column read in a role with a unit whose name ends in a unit (``t_ms``, ``f [Hz]``)
    must agree with the declared unit: the name is the file's own statement of it."""
    for name, role in columns.items():
        base = _base_name(name)
        m = _NAME_UNIT.search(base)
        if role not in declared:
            continue
        dimension = _UNIT_DIMENSION[role]
        if m:
            text = next(g for g in m.groups() if g is not None)
            if re.search(r"[_\s]rad[_\s]s(?:ec)?$", base, flags=re.IGNORECASE):  # freq_rad_s: rad/s, not s
                text = "rad/s"
            found = unit_tokens(text, strict=True) if _ONE_UNIT.fullmatch(text) else []
        else:
            found = []
        if not (len(found) == 1 and found[0][0] == dimension):
            # a unit inside the name, before a channel's suffix (phase_deg_m, mag_dB_load): the one word after
            # the first that names a unit of the role's dimension
            words = re.split(r"[_\s]+", re.sub(r"rad[_\s]s(?:ec)?\b", "rad/s", base, flags=re.IGNORECASE))[1:]
            inner = {u[1]: (dim, u[1]) for w in words if _ONE_UNIT.fullmatch(w)
                     for u in unit_tokens(w, strict=True) for dim in [u[0]] if dim == dimension}
            if len(inner) == 1:
                found = list(inner.values())
                text = found[0][1]
        if len(found) == 1 and found[0][0] == dimension and found[0][1] != declared[role]:
            raise DataError(f"{where}: the {role} column is named {name!r}, which states {found[0][1]}, but the "
                            f"{dimension} unit declared is {declared[role]}; check which is right (if {text!r} "
                            "in the name is not a unit, rename the column)")


def _base_name(name: str) -> str:
    """A column's name without a channel index: ``y[2]`` → ``y``."""
    m = _CHANNEL.match(name)
    return m.group(1) if m else name


def _units_body(comment: str) -> str:
    """What a units comment states after its "units:" (at its start, or after other text: "exported by X;
    units: ..."); the whole text when it has none."""
    text = comment.lstrip("#").strip()
    head = re.match(r"units?\s*[:=]?\s*", text, flags=re.IGNORECASE) or \
        re.search(r"\bunits?\s*[:=]\s*", text, flags=re.IGNORECASE)
    return text[head.end():] if head else text


def _split_items(text: str) -> list[str]:
    """``text`` split at the commas and semicolons outside brackets and parentheses."""
    items, depth, cur = [], 0, []
    for ch in text:
        depth += ch in "[("
        depth -= ch in "])"
        if ch in ",;" and depth <= 0:
            items.append("".join(cur).strip())
            cur = []
        else:
            cur.append(ch)
    items.append("".join(cur).strip())
    return [i for i in items if i]


def _stated_units(comment: str, roles: Mapping[str, str | None]) -> list[tuple[str | None, str, str]]:
    """The units a comment states, as (column or role name or None, dimension, unit) triples.

    The text after ``units:`` is split into items at commas and semicolons. An item
    ``name [unit]`` (or ``name = unit``, ``name: unit``, ``name (unit)``) states the unit
    of that column: where ``name`` is a column read in a role with a unit (``roles``: name
    → role; the role names themselves, e.g. ``time=s``, count too), every unit of the
    role's dimension in the bracket is stated for it, and the others are ignored (``mag
    [dB re 1 (rad/s)/N]`` states dB, not rad/s, for the magnitude). A column without a
    unit role (``roles``: name → ``""``: an input, an output, the real part of H, or a
    column of the file not read) states nothing: ``u [mg/h]`` is the input's unit, not
    the time's. Any other name states its bracket's unit when the bracket is a single
    unit (a unit of a column that does not exist can still contradict the declaration:
    ``t_ms=s`` beside a time column ``t``). An item that is a unit alone (``s``, ``Hz``)
    states it; any other item is free text, where unit words that are also common words
    ("s", "min", "rad") are not read as units.

    Examples
    --------
    >>> from symid.data.table import _stated_units
    >>> _stated_units("# units: f [Hz], mag [dB re 1 (rad/s)/N], ph [deg]", {"f": "frequency",
    ...               "mag": "magnitude", "ph": "phase"})
    [('f', 'frequency', 'Hz'), ('mag', 'magnitude', 'dB'), ('ph', 'phase', 'deg')]
    >>> _stated_units("# units: s", {}), _stated_units("# units: t_ms=s", {"t": "time"})
    ([(None, 'time', 's')], [('t_ms', 'time', 's')])
    >>> _stated_units("# units: t [s], u [mg/h]", {"t": "time", "u": ""})
    [('t', 'time', 's')]
    >>> _stated_units("# exported by X; units: f_Hz [Hz]", {"f_Hz": "frequency"})
    [('f_Hz', 'frequency', 'Hz')]
    """
    body = _units_body(comment)
    out: list[tuple[str | None, str, str]] = []
    for item in _split_items(body):
        pair = _PAIR.match(item)
        if pair:
            name = pair.group(1)
            unit_text = next(g for g in pair.groups()[1:] if g is not None)
            found = unit_tokens(unit_text, strict=True)
            role = roles.get(name) if name in roles else None
            role = role if role is not None else (name if name in _UNIT_DIMENSION else None)
            if role:
                out.extend((name, d, u) for d, u in found if d == _UNIT_DIMENSION[role])
            elif role is None and len(found) == 1 and _ONE_UNIT.fullmatch(unit_text.strip()):
                out.append((name, *found[0]))
            continue
        alone = unit_tokens(item, strict=True)
        if len(alone) == 1 and _ONE_UNIT.fullmatch(item):
            out.append((None, *alone[0]))
        else:
            out.extend((None, d, u) for d, u in unit_tokens(item))
    return out


def _unread_units(comment: str, roles: Mapping[str, str | None]) -> list[tuple[str, str, str]]:
    """The items ``name [text]`` of a units comment whose ``name`` is a column read in a role with a unit (time,
    frequency, magnitude, phase) and whose ``text`` holds no unit of that role's dimension symid knows, as
    (name, role, text): ``t [Std]`` (German hours) cannot be checked.

    Examples
    --------
    >>> from symid.data.table import _unread_units
    >>> _unread_units("# units: t [Std], u [V]", {"t": "time", "u": ""})
    [('t', 'time', 'Std')]
    >>> _unread_units("# units: t [h], u [Std]", {"t": "time", "u": ""})
    []
    """
    out = []
    for item in _split_items(_units_body(comment)):
        pair = _PAIR.match(item)
        if not pair:
            continue
        name = pair.group(1)
        role = roles.get(name)
        if not role or role not in _UNIT_DIMENSION:
            continue
        text = next(g for g in pair.groups()[1:] if g is not None).strip()
        if not any(d == _UNIT_DIMENSION[role] for d, _ in unit_tokens(text, strict=True)):
            out.append((name, role, text))
    return out


def stated_column_units(path: Any, delimiter: str = ",") -> dict[str, str]:
    """The unit a CSV file's ``# units:`` comments state for each named column (``dose [mg/h]`` → ``{"dose":
    "mg/h"}``), as written; {} for a file without such comments. For checks beyond the time and frequency units
    (the command line compares the input and output units with a model file's).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from symid.data.table import stated_column_units
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "pk.csv"
    >>> _ = path.write_text("# units: t [h], dose [mg/h], conc [mg/L]\\nt,dose,conc\\n0,1,0\\n1,0,1\\n")
    >>> stated_column_units(path)
    {'t': 'h', 'dose': 'mg/h', 'conc': 'mg/L'}
    """
    return _column_units(_Csv(path, delimiter))


_BRACKETED_UNIT = re.compile(r"^.*\S\s*[\[(]\s*([^\[\]()]*[A-Za-zµμ°%][^\[\]()]*?)\s*[\])]\s*$")
"""A unit at the end of a column's own name: ``h2 [mm]``, ``T (degC)``."""


def _name_unit(name: str) -> str | None:
    """The unit a column's name ends with in brackets or parentheses (``h2 [mm]`` → ``mm``), or None.

    Examples
    --------
    >>> from symid.data.table import _name_unit
    >>> _name_unit("h2 [mm]"), _name_unit("T (degC)"), _name_unit("u[1]"), _name_unit("h2")
    ('mm', 'degC', None, None)
    """
    m = _BRACKETED_UNIT.match(str(name))
    return m.group(1) if m else None


_UNIT_SUFFIX = re.compile(r"^(.+?)\s*(?:\[[^\[\]]*\]|\([^()]*\)|_[^_\s\[\]()]+)\s*$")
"""A column's name and a unit it ends in (``q_W``, ``h2 [mm]``, ``T (degC)``): group 1 the name without it."""


def _column_units(src: _Csv) -> dict[str, str]:
    """:func:`stated_column_units` of a file already read."""
    out: dict[str, str] = {}
    for _, comment in src.comments:
        if not re.search(r"\bunits?\b", comment, flags=re.IGNORECASE):
            continue
        for item in _split_items(_units_body(comment)):
            pair = _PAIR.match(item)
            if pair:
                out[pair.group(1)] = next(g for g in pair.groups()[1:] if g is not None).strip()
    return out


class _Arrays:
    """Named arrays: a dict, a DataFrame's columns, or the variables of a .mat file."""

    missing_hint = ""

    def __init__(self, arrays: Mapping[str, Any], where: str):
        self.where = where
        self.arrays = arrays
        self.names = list(arrays)

    def has(self, name: str) -> bool:
        return name in self.arrays

    def get(self, name: str, missing_ok: bool = False) -> np.ndarray:
        """A column's numbers; NaN is a missing value where ``missing_ok``."""
        arr = checks.as_array(self.arrays[name], f"{self.where} column {name!r}", complex_ok=True)
        if np.any(arr.imag != 0):
            raise DataError(f"{self.where}: column {name!r} holds complex numbers; give H as real and imag columns")
        arr = arr.real.copy()
        if arr.ndim > 2:
            raise DataError(f"{self.where}: column {name!r} has {arr.ndim} dimensions; a column is 1-D or "
                            "samples × channels")
        bad = np.argwhere(np.isinf(arr) if missing_ok else ~np.isfinite(arr))
        if bad.size:
            raise DataError(f"{self.where}: column {name!r} is not finite at index {tuple(int(i) for i in bad[0])}"
                            + _MISSING_HINT.get(self.missing_hint, ""))
        return arr


def _frame(table: Any) -> dict[str, Any] | None:
    """A DataFrame-like object's columns by name (duck-typed: ``columns`` and ``__getitem__`` with ``to_numpy``)."""
    cols = getattr(table, "columns", None)
    if cols is None or not hasattr(table, "__getitem__") or isinstance(table, Mapping):
        return None
    labels = list(cols)
    names = [str(c) for c in labels]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise DataError(f"the DataFrame has two columns named {dup[0]!r}")
    out = {}
    for label, name in zip(labels, names, strict=True):
        column = table[label]
        out[name] = column.to_numpy() if hasattr(column, "to_numpy") else np.asarray(column)
    return out


def _source(table: Any, names: Sequence[str], delimiter: str) -> _Csv | _Arrays:
    if isinstance(table, (str, os.PathLike)):
        path = os.fspath(table)
        if str(path).lower().endswith(".mat"):
            from symid.data._matfile import read_mat_variables

            # MATLAB names cannot hold brackets: "acc[0]" is channel 0 of the variable acc
            wanted = sorted({_CHANNEL.match(n).group(1) if _CHANNEL.match(n) else n for n in names})
            return _Arrays(read_mat_variables(path, wanted), repr(path))
        return _Csv(path, delimiter, names)
    frame = _frame(table)
    if frame is not None:
        return _Arrays(frame, "the DataFrame")
    if isinstance(table, Mapping):
        return _Arrays({str(k): v for k, v in table.items()}, "the table")
    raise DataError(f"a table is a CSV or .mat file path, a pandas DataFrame or a dict of arrays; got "
                    f"{type(table).__name__}")


# -- columns ------------------------------------------------------------------------------------------

class _Columns:
    """Resolves column names to 1-D arrays of one common length N, expanding 2-D arrays into channels."""

    def __init__(self, src: _Csv | _Arrays, example: str):
        self.src = src
        self.example = example
        self.n: int | None = None

    def _missing(self, name: str) -> DataError:
        shown = ", ".join(self.src.names[:30]) + (" ..." if len(self.src.names) > 30 else "")
        hint = ""
        used = getattr(self.src, "delimiter", None)
        if used is not None:
            other = next((sep for sep in (";", "\t", ",", "|") if sep != used
                          and any(sep in n for n in self.src.names)), None)
            if other is not None:
                shown_sep = "tab" if other == "\t" else other
                hint = (f"; the header looks {shown_sep!r}-separated, not {used!r}: read it with "
                        f"delimiter={other!r} (--delimiter {shown_sep!r} on the command line)")
        return _fail(self.src.where, f"no column named {name!r} (it has: {shown or 'none'}){hint}; declare the "
                     "columns the table holds", self.example)

    def _length(self, name: str, n: int) -> None:
        if self.n is None:
            self.n = n
        elif n != self.n:
            raise DataError(f"{self.src.where}: column {name!r} has {n} samples, the columns before it {self.n}")

    def vector(self, name: str) -> np.ndarray:
        """One column as a 1-D array."""
        chans = self.channels(name)
        if chans.shape[1] != 1:
            raise DataError(f"{self.src.where}: {name!r} holds {chans.shape[1]} channels where one column is "
                            f"expected; pick one with {name}[k]")
        return chans[:, 0]

    def channels(self, name: str, missing_ok: bool = False) -> np.ndarray:
        """A column, or a 2-D array's channels, as (N, channels); ``missing_ok``: empty cells and NaN are NaN."""
        if not isinstance(name, str):
            raise DataError(f"column names are text; got {name!r}")
        if self.src.has(name):
            arr = self.src.get(name, missing_ok)
            index = None
        else:
            match = _CHANNEL.match(name)
            if not match or not isinstance(self.src, _Arrays) or not self.src.has(match.group(1)):
                raise self._missing(name)
            arr = self.src.get(match.group(1), missing_ok)
            index = int(match.group(2))
        if arr.ndim == 0:
            raise DataError(f"{self.src.where}: {name!r} is a single number, not a column of samples")
        if arr.ndim == 1:
            arr = arr.reshape(-1, 1)
        elif 1 in arr.shape:
            arr = arr.reshape(-1, 1)
        else:
            rows, cols = arr.shape
            if self.n is None:
                raise DataError(f"{self.src.where}: cannot tell samples from channels in {name!r} of shape "
                                f"{checks.shape_text(arr.shape)}: list a 1-D column (the time or frequency) first")
            if rows == cols:
                raise DataError(f"{self.src.where}: {name!r} is square ({rows} × {cols}): samples and channels "
                                "cannot be told apart")
            if cols == self.n:
                arr = arr.T
            elif rows != self.n:
                raise DataError(f"{self.src.where}: {name!r} has shape {checks.shape_text(arr.shape)}; neither "
                                f"axis has the {self.n} samples of the other columns")
        if index is not None:
            if index >= arr.shape[1]:
                raise DataError(f"{self.src.where}: {name!r}: channel {index} does not exist ({arr.shape[1]} "
                                "channel(s), counted from 0)")
            arr = arr[:, index:index + 1]
        self._length(name, arr.shape[0])
        return arr


def _role_map(columns: Any, roles: Sequence[str], where: str, example: str) -> dict[str, Any]:
    if not isinstance(columns, Mapping) or not columns:
        raise _fail(where, "columns= must be a dict from role to column name", example)
    out = {}
    for role, name in columns.items():
        base = _INDEXED.match(str(role)).group(1) if _INDEXED.match(str(role)) else role
        if base not in roles:
            raise _fail(where, f"unknown column role {role!r}; the roles here are {', '.join(roles)}", example)
        out[str(role)] = name
    return out


def _units(units: Any, needed: Sequence[str], where: str, example: str) -> dict[str, str]:
    given = {} if units is None else units
    if not isinstance(given, Mapping):
        raise _fail(where, "units= must be a dict from role to unit", example)
    out = {}
    for role, unit in given.items():
        if role not in _UNIT_DIMENSION:
            raise _fail(where, f"units for {role!r}: only frequency, magnitude, phase and time carry units",
                        example)
        if role not in needed:
            raise _fail(where, f"units for {role!r}, but the table has no {role} column", example)
        out[role] = canonical_unit(unit, _UNIT_DIMENSION[role], f"{where}: units of {role!r}")
    for role in needed:
        if role not in out:
            options = ", ".join(DIMENSIONS[_UNIT_DIMENSION[role]])
            raise _fail(where, f"the unit of {role!r} is missing ({options}); symid never guesses units", example)
    return out


# -- frequency response -------------------------------------------------------------------------------

def _entry_names(roles: Mapping[str, Any], role: str, where: str) -> dict[tuple[int, int], str]:
    """{(i, j): column} for one part of H, from "role": name / nested list, or "role[i][j]": name."""
    out: dict[tuple[int, int], str] = {}
    if role in roles:
        value = roles[role]
        if isinstance(value, str):
            out[(0, 0)] = value
        else:
            rows = list(value) if isinstance(value, Sequence) else None
            if not rows or any(isinstance(r, str) or not isinstance(r, Sequence) for r in rows):
                raise DataError(f"{where}: columns[{role!r}] is a column name, or a nested list of names "
                                "[[H00, H01], [H10, H11]] (outputs × inputs)")
            for i, r in enumerate(rows):
                for j, name in enumerate(r):
                    out[(i, j)] = name
    for key, name in roles.items():
        m = _INDEXED.match(key)
        if m and m.group(1) == role:
            ij = (int(m.group(2)), int(m.group(3)))
            if ij in out:
                raise DataError(f"{where}: H entry {ij} of {role} is named twice")
            out[ij] = name
    return out


def frequency_data_from_table(table: Any, *, columns: Mapping[str, Any], units: Mapping[str, str] | None = None,
                              delimiter: str = ",") -> Any:
    """A :class:`~symid.data.FrequencyData` from a table (module notes); see ``FrequencyData.from_table``."""
    from symid.data.frequency import FrequencyData

    where = repr(os.fspath(table)) if isinstance(table, (str, os.PathLike)) else "the table"
    roles = _role_map(columns, FRF_ROLES, where, FRF_EXAMPLE)
    if "frequency" not in roles:
        raise _fail(where, "no frequency column declared", FRF_EXAMPLE)
    parts = {r: _entry_names(roles, r, where) for r in ("real", "imag", "magnitude", "phase")}
    cartesian, polar = bool(parts["real"] or parts["imag"]), bool(parts["magnitude"] or parts["phase"])
    if cartesian == polar:
        raise _fail(where, "declare H either as real and imag columns or as magnitude and phase columns"
                    if not cartesian else "H is declared both as real/imag and as magnitude/phase: choose one",
                    FRF_EXAMPLE)
    a, b = ("real", "imag") if cartesian else ("magnitude", "phase")
    if set(parts[a]) != set(parts[b]):
        odd = sorted(set(parts[a]) ^ set(parts[b]))[0]
        raise _fail(where, f"H entry {odd} has a {a if odd in parts[a] else b} column but no "
                    f"{b if odd in parts[a] else a} column", FRF_EXAMPLE)
    p = 1 + max(i for i, _ in parts[a])
    m = 1 + max(j for _, j in parts[a])
    if len(parts[a]) != p * m:
        missing = sorted({(i, j) for i in range(p) for j in range(m)} - set(parts[a]))
        raise _fail(where, f"H is {p} × {m} but entry {missing[0]} has no column", FRF_EXAMPLE)
    needed = ["frequency"] + ([] if cartesian else ["magnitude", "phase"])
    names = [roles["frequency"], *parts[a].values(), *parts[b].values()]
    src = _source(table, [n for n in names if isinstance(n, str)], delimiter)
    if isinstance(src, _Csv) and not units:
        src.check_unit_comments({}, FRF_EXAMPLE)  # a file that states units, read without any declared
    declared = _units(units, needed, where, FRF_EXAMPLE)
    if isinstance(src, _Csv):
        src.check_unit_comments(declared, FRF_EXAMPLE, _unit_columns(roles, parts),
                                read=[n for n in names if isinstance(n, str)])
    _check_name_units(where, declared, _unit_columns(roles, parts))
    cols = _Columns(src, FRF_EXAMPLE)
    w = cols.vector(roles["frequency"]) * DIMENSIONS["frequency"][declared["frequency"]]
    H = np.empty((w.size, p, m), dtype=np.complex128)
    for (i, j), name in parts[a].items():
        x, y = cols.vector(name), cols.vector(parts[b][(i, j)])
        if cartesian:
            H[:, i, j] = _files.complex_from_parts(x, y)
            continue
        if declared["magnitude"] == "linear" and np.any(x < 0):
            k = int(np.argmax(x < 0))
            raise DataError(f"{src.where}: magnitude {name!r} is negative at sample {k} ({x[k]:g}); a linear "
                            "magnitude is |H| ≥ 0 (is it in dB?)")
        if declared["phase"] == "rad" and (said := _degrees_as_radians(y)) is not None:
            warnings.warn(f"{src.where}: phase {parts[b][(i, j)]!r} is declared in rad but {said}: is it in "
                          f"degrees? (units phase=deg; it is read as rad)", DataWarning, stacklevel=_caller_level())
        mag = 10.0 ** (x / 20.0) if declared["magnitude"] == "dB" else x
        H[:, i, j] = mag * np.exp(1j * y * DIMENSIONS["phase"][declared["phase"]])
    with _naming(src.where):
        return FrequencyData(w, H)


DEGREE_STEP = 0.3
"""The step (rad, wrapped) between neighbouring lines that a quarter of the steps of a phase declared in rad and
beyond 2π must exceed for it to be said to look like degrees."""


def _degrees_as_radians(phase: np.ndarray) -> str | None:
    """What makes a phase declared in rad look like degrees, or None: values beyond ±2π (a wrapped phase in rad
    lies within ±π) that also jump between neighbouring lines (a degree read as a radian: a smooth curve in degrees,
    about 57 times as steep; a new user's file in degrees declared rad, phases up to 91, ended in a generic failed
    fit)."""
    phase = np.asarray(phase, dtype=float)
    top = float(np.max(np.abs(phase))) if phase.size else 0.0
    if phase.size < 3 or top <= 2 * np.pi:
        return None
    # the upper quartile: a phase in degrees is flat away from its modes, and steep (57 times, read as rad) near them
    step = float(np.quantile(np.abs(np.angle(np.exp(1j * np.diff(phase)))), 0.75))
    if step <= DEGREE_STEP:
        return None
    return f"reaches {top:.4g} and a quarter of its steps between neighbouring lines exceed {step:.2g} rad"


def _unit_columns(roles: Mapping[str, Any], parts: Mapping[str, Mapping[Any, Any]]) -> dict[str, str]:
    """Column name → role for the columns of a frequency table whose role has a unit."""
    out = {roles["frequency"]: "frequency"} if isinstance(roles["frequency"], str) else {}
    for role in ("magnitude", "phase"):
        out.update({n: role for n in parts[role].values() if isinstance(n, str)})
    return out


# -- time series --------------------------------------------------------------------------------------

def _name_list(value: Any, role: str, where: str) -> list[str]:
    names = [value] if isinstance(value, str) else value
    if not isinstance(names, Sequence) or isinstance(names, str) or not names or \
            not all(isinstance(n, str) for n in names):
        raise _fail(where, f"columns[{role!r}] is a column name or a list of names", SERIES_EXAMPLE)
    return list(names)


def outputs_from_table(table: Any, *, columns: Mapping[str, Any], units: Mapping[str, str] | None = None,
                       dt: float | None = None, time_unit: str = "s", delimiter: str = ",") -> tuple[np.ndarray, float]:
    """``(y, dt)``: the equally spaced output records of a table without an input column (output-only data, ambient
    excitation), read and checked as :meth:`IOData.from_table <symid.data.IOData.from_table>` reads a record, for
    :func:`symid.estimate_spectra` with the input spectrum given.

    Examples
    --------
    >>> import numpy as np
    >>> from symid.data.table import outputs_from_table
    >>> table = {"t_ms": np.arange(5) * 10.0, "a1": np.arange(5.0), "a2": np.ones(5)}
    >>> y, dt = outputs_from_table(table, columns={"time": "t_ms", "output": ["a1", "a2"]}, units={"time": "ms"})
    >>> y.shape, dt
    ((5, 2), 0.01)
    """
    return series_from_table(table, columns=columns, units=units, dt=dt, time_unit=time_unit, delimiter=delimiter,
                             outputs_only=True)


def series_from_table(table: Any, *, columns: Mapping[str, Any], units: Mapping[str, str] | None = None,
                      dt: float | None = None, time_unit: str = "s", uniform: bool = True,
                      delimiter: str = ",", outputs_only: bool = False) -> Any:
    """An :class:`~symid.data.IOData` (``uniform``) or :class:`~symid.data.TimeSeries` from a table (module notes);
    with ``outputs_only``, ``(y, dt)`` of a table without inputs (:func:`outputs_from_table`)."""
    from symid.data.iodata import IOData
    from symid.data.timeseries import TimeSeries

    where = repr(os.fspath(table)) if isinstance(table, (str, os.PathLike)) else "the table"
    roles = _role_map(columns, SERIES_ROLES, where, SERIES_EXAMPLE)
    for role in ("output",) if outputs_only else ("input", "output"):
        if role not in roles:
            raise _fail(where, f"no {role} column declared", SERIES_EXAMPLE)
    if outputs_only and "input" in roles:
        raise _fail(where, "an input column is declared for output-only records: leave it out (the input spectrum "
                           "is given instead)", SERIES_EXAMPLE)
    inputs = [] if outputs_only else _name_list(roles["input"], "input", where)
    outputs = _name_list(roles["output"], "output", where)
    has_time = "time" in roles
    if has_time and dt is not None:
        raise _fail(where, "both a time column and dt= are given: give one", SERIES_EXAMPLE)
    if not has_time and (dt is None or not uniform):
        raise _fail(where, "no time column declared" + ("" if uniform else " (a TimeSeries needs one)")
                    + ("" if not uniform else " and no dt= given"), SERIES_EXAMPLE)
    target = canonical_unit(time_unit, "time", "time_unit")
    names = ([roles["time"]] if has_time else []) + inputs + outputs
    src = _source(table, names, delimiter)
    if isinstance(src, _Csv) and not units:
        src.check_unit_comments({}, SERIES_EXAMPLE)
    declared = _units(units, ["time"], where, SERIES_EXAMPLE)
    if isinstance(src, _Csv):
        src.check_unit_comments(declared, SERIES_EXAMPLE, {roles["time"]: "time"} if has_time else None,
                                read=names)
    if has_time:
        _check_name_units(where, declared, {roles["time"]: "time"})
    cols = _Columns(src, SERIES_EXAMPLE)
    factor = time_factor(declared["time"], target)
    if has_time:
        raw = cols.vector(roles["time"])
        _check_time_order(raw, src, roles["time"], declared["time"])
    t = raw * factor if has_time else None
    if uniform:  # an output missing in a uniform record: say how to read it (a TimeSeries takes NaN outputs)
        src.missing_hint = "uniform"
    y = np.hstack([cols.channels(n, missing_ok=not uniform) for n in outputs])
    if outputs_only:
        if t is None:
            return y, checks.check_positive_scalar(dt, "dt") * factor
        _check_gaps(raw, src, roles["time"], declared["time"])
        return y, _uniform_step(raw, src.where) * factor
    u = np.hstack([cols.channels(n) for n in inputs])
    with _naming(src.where):
        if not uniform:
            record: TimeSeries | IOData = TimeSeries(t, u, y, time_unit=target)
        else:
            if t is None:
                step = checks.check_positive_scalar(dt, "dt") * factor
            else:
                _check_gaps(raw, src, roles["time"], declared["time"])
                step = _uniform_step(raw, src.where) * factor  # the times as written: their digits are rounding
            record = IOData(u, y, step, time_unit=target)
    if isinstance(src, _Csv):  # the columns read and the units the file states for them (a CSV column: a channel)
        stated = _column_units(src)
        # a comment may name a column without the unit its name ends in ("q [W]" over "q_W"), as it may the time
        # column's ("t [min]" over "t_min"): a new user's input in W was not checked against the model's kW
        stem = {n: m.group(1) for n in src.names if (m := _UNIT_SUFFIX.match(n))}
        stray = [n for n in stated if n not in src.names and n not in stem.values() and n not in _UNIT_DIMENSION]
        if stray:
            warnings.warn(f"{src.where}: the units comment names {', '.join(map(repr, stray))}, which "
                          f"{'is no column' if len(stray) == 1 else 'are no columns'} of the file (its columns: "
                          f"{', '.join(src.names)}): the unit stated there is not checked against the model's; "
                          "name the columns as in the header", DataWarning, stacklevel=3)
        for n in (*inputs, *outputs):
            said, named = stated.get(n) or stated.get(stem.get(n, n)), _name_unit(n)
            if said and named and said != named:
                warnings.warn(f"{src.where}: column {n!r} is named in {named} but the units comment states {said} "
                              "for it: the comment's is checked against the model's; make them agree",
                              DataWarning, stacklevel=3)
        units: dict = {role: tuple((n, stated.get(n) or stated.get(stem.get(n, n)) or _name_unit(n)) for n in names)
                       for role, names in (("input", inputs), ("output", outputs))}
        units["file"] = src.where  # which file says so, for messages about several
        object.__setattr__(record, "stated_units", units)  # on the object read: metadata, not a field
    return record


def _missing(n: int) -> str:
    """'about 1 sample is missing', 'about 3 samples are missing'."""
    return f"about {n} sample is missing" if n == 1 else f"about {n} samples are missing"


def _check_time_order(t: np.ndarray, src: _Csv | _Arrays, name: str, unit: str) -> None:
    """Refuse times that repeat or go back, naming the file's lines (or the table's rows), the column and the unit."""
    step = np.diff(t)
    bad = np.flatnonzero(step <= 0)
    if not bad.size:
        return
    k = int(bad[0])
    if isinstance(src, _Csv):
        place = f"{src.where}, lines {src.rows[k][0]} and {src.rows[k + 1][0]}, column {name!r}"
    else:
        place = f"{src.where}, rows {k} and {k + 1}, column {name!r}"
    if step[k] == 0:
        raise DataError(f"{place}: both times are {t[k]:.9g} {unit}: a duplicated sample time; average the two "
                        "samples or drop one")
    raise DataError(f"{place}: the time {t[k + 1]:.9g} {unit} comes after {t[k]:.9g} {unit}: sample times must "
                    "increase; sort the rows by time")


def _check_gaps(t: np.ndarray, src: _Csv | _Arrays, name: str, unit: str) -> None:
    """For an equally spaced record: refuse a jump between two rows of more than 1.5 typical steps where nearly
    every other step (90 %) is the typical one (samples missing from an even grid), naming the file's lines, the
    times in the file's unit and how many samples are missing (a new user's record with 10 minutes missing was
    told its sample 1000 lay 7.66 sample times off an even grid, in seconds of a file in hours)."""
    jump = checks.grid_jump(t)  # a grid with holes: nearly every step is the typical one
    if jump is None:
        return
    k, typical, gaps = jump
    d = np.diff(t)
    if not d[k] > 1.5 * typical:
        return
    if isinstance(src, _Csv):
        place = f"{src.where}, lines {src.rows[k][0]} and {src.rows[k + 1][0]}, column {name!r}"
    else:
        place = f"{src.where}, rows {k} and {k + 1}, column {name!r}"
    more = f" ({gaps} such gaps in all)" if gaps > 1 else ""
    raise DataError(f"{place}: the times jump from {t[k]:.9g} to {t[k + 1]:.9g} {unit}, {d[k] / typical:.3g} steps "
                    f"of {typical:.6g} {unit}: {_missing(round(d[k] / typical) - 1)}{more}. An "
                    "equally spaced record has none: read the table as a TimeSeries (TimeSeries.from_table, or "
                    "kind='TimeSeries'; --kind TimeSeries), which takes the times as they are and the input as held "
                    "from one row to the next across the gap (an input that changed inside it is then wrong there: "
                    "split the record at the gap instead)")


PRINTED_JITTER = 0.1
"""Times written with few digits (a logger's 119.667 h for 119.6667) are read as an even grid when every time is
within half a unit of its last printed digit of the grid, and that is at most this fraction of a sample."""


def _printed_half_unit(t: np.ndarray) -> list[np.ndarray]:
    """Half a unit of the last digit each time was written with, under the two ways tables are written: a fixed
    number of decimals (``%.3f``) and of significant digits (``%.6g``); the fewest digits that reproduce every time
    (read from at most 2000 of them), one array per way."""
    sample = t if t.size <= 2000 else t[np.linspace(0, t.size - 1, 2000).astype(int)]
    out = []
    for q in range(16):  # decimals
        if all(float(f"{v:.{q}f}") == v for v in sample):
            out.append(np.full(t.size, 0.5 * 10.0 ** -q))
            break
    for d in range(1, 17):  # significant digits
        if all(float(f"{v:.{d}g}") == v for v in sample):
            with np.errstate(divide="ignore"):
                exponent = np.floor(np.log10(np.where(t != 0, np.abs(t), 1.0)))
            out.append(0.5 * 10.0 ** (exponent - d + 1))
            break
    return out


def _uniform_step(t: np.ndarray, where: str) -> float:
    """The sample time of equally spaced times: jitter up to 0.1 % of a sample is rounding, and so is up to half a
    unit of the times' last printed digit (:data:`PRINTED_JITTER`); more is refused."""
    if t.size < 2:
        raise DataError(f"{where}: a record needs at least 2 samples; got {t.size}")
    step = (t[-1] - t[0]) / (t.size - 1)
    if not step > 0:
        raise DataError(f"{where}: the times do not increase (first {t[0]:g}, last {t[-1]:g})")
    dev = np.abs(t - (t[0] + step * np.arange(t.size)))
    k = int(np.argmax(dev))
    if dev[k] > 1e-3 * step and dev[k] <= PRINTED_JITTER * step:
        # a new user's 10-minute samples in hours, written with 6 digits (119.667), were 0.004 of a sample off the
        # grid: the grid fitted to every time (its ends are rounded too) is within the rounding of each, twice half
        # a unit of the last digit at most (its own, and the grid's). Each time weighs by its digits: with 6
        # significant digits 0.0833333 pins the grid where 239.083 cannot, and an unweighted grid, pulled by the
        # coarse times, missed the fine ones (another user's 5 s samples in minutes: 1.1 half-units off)
        idx = np.arange(t.size, dtype=float)
        for half in _printed_half_unit(t):
            slope, offset = np.polyfit(idx, t, 1, w=1.0 / half)
            fitted = np.abs(t - (offset + slope * idx))
            if slope > 0 and np.all(fitted <= 2 * half * (1 + 1e-9) + 4 * np.spacing(np.abs(t))):
                return float(slope)
    if dev[k] > 1e-3 * step:
        raise DataError(f"{where}: the samples are not equally spaced: sample {k} is at {t[k]:.9g}, "
                        f"{dev[k] / step:.3g} sample times away from an even grid of step {step:.6g}; read "
                        "the table as a TimeSeries (TimeSeries.from_table, or kind='TimeSeries'; --kind TimeSeries "
                        "on the command line) for uneven times; or, if the times are even but were rounded when "
                        "written, leave the time column out and give the sample time (dt=, or --dt)")
    return float(step)


class _naming:
    """Prefix the constructor's DataError with the table it came from."""

    def __init__(self, where: str):
        self.where = where

    def __enter__(self) -> None:
        return None

    def __exit__(self, kind, exc, tb) -> bool:
        if isinstance(exc, DataError) and not str(exc).startswith(self.where):
            raise DataError(f"{self.where}: {exc}") from None
        return False


# -- one entry point ----------------------------------------------------------------------------------

def read_data(source: Any, *, columns: Mapping[str, Any] | None = None, units: Mapping[str, str] | None = None,
              kind: str | None = None, dt: float | None = None, time_unit: str = "s", delimiter: str = ",") -> Any:
    """Read measurements: a symid data file as it is, or the user's own table with declared columns and units.

    Parameters
    ----------
    source : str, os.PathLike, pandas.DataFrame or dict
        A symid CSV/NPZ file (without ``columns``), or a table (module notes): a plain
        CSV file, a MATLAB ``.mat`` file, a DataFrame or a dict of arrays.
    columns : dict, optional
        Role → column name (:data:`FRF_ROLES`, :data:`SERIES_ROLES`); required for a table.
    units : dict, optional
        Role → unit (:mod:`symid.data.units`) for the frequency, magnitude, phase and time.
    kind : {"FrequencyData", "IOData", "TimeSeries"}, optional
        What to build from a table; by default ``FrequencyData`` when a frequency column is
        declared, else ``IOData`` (equally spaced samples; ``TimeSeries`` for uneven ones).
    dt : float, optional
        Sample time of a time series without a time column, in ``units["time"]``.
    time_unit : str
        The time unit of the record built (default ``"s"``).
    delimiter : str
        Separator of a CSV table (default ``","``).

    Returns
    -------
    FrequencyData, SpectralData, IOData, TimeSeries or BlackBox

    Raises
    ------
    DataError
        On a file that is neither, columns that do not match the table, missing or
        unknown units, or values that fail the data's checks.

    Examples
    --------
    >>> import numpy as np
    >>> import symid as si
    >>> table = {"t_ms": np.arange(5) * 10.0, "u": np.ones(5), "y": np.linspace(0, 1, 5)}
    >>> si.read_data(table, columns={"time": "t_ms", "input": "u", "output": "y"}, units={"time": "ms"})
    IOData(5 samples, dt = 0.01 s, 1 input(s), 1 output(s))
    """
    if columns is None:
        if units is not None or dt is not None or kind is not None:
            raise DataError("units=, dt= and kind= describe a table: give columns= too (a symid file carries its own)")
        if not isinstance(source, (str, os.PathLike)):
            raise DataError("a DataFrame or dict is read as a table: give columns= and units=")
        from symid.data import load

        if str(os.fspath(source)).lower().endswith(".mat"):
            raise _fail(repr(os.fspath(source)), "a MATLAB file is read as a table: declare its columns and units",
                        SERIES_EXAMPLE)
        try:
            return load(source)
        except DataError as exc:
            if "is not a symid CSV file" in str(exc) or "not a UTF-8" in str(exc):
                raise DataError(f"{exc}. A plain table is read with its columns and units declared, e.g.\n"
                                f"{FRF_EXAMPLE}\n{SERIES_EXAMPLE}") from None
            raise
    if kind is None:
        kind = "FrequencyData" if isinstance(columns, Mapping) and "frequency" in columns else "IOData"
    if kind == "FrequencyData":
        if dt is not None:
            raise DataError("dt= belongs to a time series, not to a frequency response")
        return frequency_data_from_table(source, columns=columns, units=units, delimiter=delimiter)
    if kind in ("IOData", "TimeSeries"):
        return series_from_table(source, columns=columns, units=units, dt=dt, time_unit=time_unit,
                                 uniform=kind == "IOData", delimiter=delimiter)
    raise DataError(f"kind must be 'FrequencyData', 'IOData' or 'TimeSeries' for a table; got {kind!r}")
