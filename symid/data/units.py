"""Units symid reads in the user's tables: named explicitly, converted where the data come in, never guessed.

Inside symid, angular frequencies are in rad/s (rad per time unit of the model) and a
frequency response is a complex number; times are in the record's ``time_unit``
(seconds unless chosen otherwise). A table may hold any of the units below; the reader
(:mod:`symid.data.table`) converts them once, where the data come in.

=============  ========================================================  ==========================
role           units                                                     converted to
=============  ========================================================  ==========================
frequency      ``mHz``, ``Hz``, ``kHz``, ``MHz``, ``GHz``, ``rad/s``     rad/s (ω = 2π f for Hz)
magnitude      ``dB`` (20 log10 |H|), ``linear`` (|H| itself)             |H|
phase          ``deg``, ``rad``                                          radians
time, dt       ``s``, ``ms``, ``us``, ``min``, ``h``, ``d``              the record's ``time_unit``
=============  ========================================================  ==========================

Spellings are matched without regard to case (but ``Ms``, mega, is not ``ms``, and ``MHz``,
mega, is not ``mHz``, milli; all capitals, ``MS`` and ``MHZ``, are read as a logger or an
analyzer writes them: ms and MHz), and a few aliases are accepted
(``degrees``, ``µs``, ``sec``, ``hour``, ...); anything else is a
:class:`~symid.errors.DataError` listing the units above.
"""

from __future__ import annotations

import math
import re

from symid.errors import DataError

__all__ = ["DIMENSIONS", "TIME_UNITS", "canonical_unit", "time_factor"]

TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "min": 60.0, "h": 3600.0, "d": 86400.0}
"""Time units and their length in seconds."""

DIMENSIONS = {
    "frequency": {"mHz": 2e-3 * math.pi, "Hz": 2 * math.pi, "kHz": 2e3 * math.pi, "MHz": 2e6 * math.pi,
                  "GHz": 2e9 * math.pi, "rad/s": 1.0},
    "magnitude": {"dB": None, "linear": None},
    "phase": {"deg": math.pi / 180, "rad": 1.0},
    "time": TIME_UNITS,
}
"""Each dimension's units with the factor to symid's unit (``None``: converted by a formula)."""

_ALIASES = {
    "hz": "Hz", "hertz": "Hz", "khz": "kHz", "mhz": "MHz", "ghz": "GHz", "megahertz": "MHz", "gigahertz": "GHz",
    "millihertz": "mHz", "kilohertz": "kHz", "rad/s": "rad/s", "rad/sec": "rad/s", "rad s^-1": "rad/s",
    "db": "dB", "decibel": "dB", "linear": "linear", "lin": "linear", "abs": "linear",
    "deg": "deg", "degree": "deg", "degrees": "deg", "°": "deg", "rad": "rad", "radian": "rad", "radians": "rad",
    "s": "s", "sec": "s", "second": "s", "seconds": "s", "ms": "ms", "millisecond": "ms", "milliseconds": "ms",
    "us": "us", "µs": "us", "μs": "us", "microsecond": "us", "microseconds": "us", "min": "min", "minute": "min",
    "minutes": "min", "h": "h", "hr": "h", "hour": "h", "hours": "h", "d": "d", "day": "d", "days": "d",
    "secs": "s", "msec": "ms", "msecs": "ms", "usec": "us", "usecs": "us", "mins": "min", "hrs": "h",
}


def _alias(text: str) -> str | None:
    """The canonical unit a spelling names, without regard to case but for the case of a prefix: ``Ms`` (mega)
    is not ``ms`` (milli), though ``MS`` (all capitals, as a logger's ``TIME_MS`` writes it) is."""
    key = re.sub(r"\s+", "", text).lower() if "/" in text else text.strip().lower()
    name = _ALIASES.get(key)
    if name == "ms" and text.strip()[:1] == "M" and not text.strip().isupper():
        return None
    if key == "mhz" and text.strip() == "mhz":  # mega or milli, 1e9 apart: not read (canonical_unit says so)
        return None
    if name == "MHz" and text.strip()[:1] == "m":  # milli, as written (an analyzer's MHz is "M")
        return "mHz"
    return name


def canonical_unit(text: str, dimension: str, what: str) -> str:
    """The canonical name of a unit of ``dimension`` (``"hz"`` → ``"Hz"``), or a :class:`DataError`.

    Examples
    --------
    >>> from symid.data.units import canonical_unit
    >>> canonical_unit("hz", "frequency", "units of 'frequency'")
    'Hz'
    >>> canonical_unit("rpm", "frequency", "units of 'frequency'")
    Traceback (most recent call last):
    ...
    symid.errors.DataError: units of 'frequency': unknown unit 'rpm'; symid reads mHz, Hz, kHz, MHz, GHz, rad/s
    """
    if not isinstance(text, str):
        raise DataError(f"{what}: a unit is a name such as {', '.join(DIMENSIONS[dimension])}; got {text!r}")
    name = _alias(text) if len(text) <= 40 else None
    if name is None or name not in DIMENSIONS[dimension]:
        shown = repr(text) if len(text) <= 40 else f"{text[:40]!r}..."
        mega = (" (M is mega: milliseconds are ms)" if name is None and text.strip()[:1] == "M"
                and _ALIASES.get(text.strip().lower()) == "ms" else
                " (mega or milli? write MHz or mHz)" if text.strip() == "mhz" else "")
        raise DataError(f"{what}: unknown unit {shown}{mega}; symid reads {', '.join(DIMENSIONS[dimension])}")
    return name


def time_factor(unit: str, target: str) -> float:
    """The factor that converts a time in ``unit`` to ``target`` (both canonical).

    Examples
    --------
    >>> from symid.data.units import time_factor
    >>> time_factor("ms", "s"), time_factor("min", "h")
    (0.001, 0.016666666666666666)
    """
    return TIME_UNITS[unit] / TIME_UNITS[target]


_AMBIGUOUS = frozenset({"s", "h", "d", "min", "rad", "linear", "lin", "abs"})
"""Words that name a unit but are too common in free text to be read as one there (in a unit's own
place, e.g. ``t [s]``, they are units)."""


def unit_tokens(text: str, *, strict: bool = False) -> list[tuple[str, str]]:
    """The units recognisable in a text, as (dimension, canonical name) pairs.

    ``strict=False`` (free text, a comment line): the words of :data:`_AMBIGUOUS` ("s",
    "h", "min", "rad", ...) are skipped — in prose they are rarely units — but their long
    forms ("seconds", "hours", "radians") count. ``strict=True`` (text known to be a unit,
    e.g. the bracket of ``t [s]``): every unit name counts.

    Examples
    --------
    >>> from symid.data.units import unit_tokens
    >>> unit_tokens("time in seconds, f in Hz")
    [('time', 's'), ('frequency', 'Hz')]
    >>> unit_tokens("s"), unit_tokens("s", strict=True)
    ([], [('time', 's')])
    """
    out = []
    for token in re.findall(r"rad\s*/\s*s(?:ec)?\b|[A-Za-zµμ°]+", text, flags=re.IGNORECASE):
        raw = re.sub(r"\s+", "", token).lower()
        name = _alias(re.sub(r"\s+", "", token))
        if name is None or (not strict and raw in _AMBIGUOUS):
            continue
        dimension = next(d for d, units in DIMENSIONS.items() if name in units)
        out.append((dimension, name))
    return out
