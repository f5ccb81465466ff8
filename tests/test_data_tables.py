"""The user's own measurements (symid.data.table): plain CSV, MATLAB .mat, pandas DataFrames, dicts.

Units are declared and converted where the data come in; a unit stated in a file is checked, never
ignored; columns that do not match the declaration, missing or unknown units are named errors with a
two-line example. Reference values: the conversions' definitions (ω = 2π f, |H| = 10^(dB/20)).
"""

from __future__ import annotations

import os
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
import scipy.io

import symid as si
from symid.cli import main
from symid.data import FrequencyData, IOData, TimeSeries, read_data
from symid.data.table import FRF_EXAMPLE, MAX_TABLE_BYTES, SERIES_EXAMPLE

F_HZ = np.array([0.1, 0.2, 0.5, 1.0, 2.0])
H_TRUE = 1.0 / (1.0 - (2 * np.pi * F_HZ) ** 2 * 0.01 + 0.02j * 2 * np.pi * F_HZ)  # a lightly damped mode


def write_csv(path: Path, lines: list[str]) -> Path:
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


@pytest.fixture
def polar_csv(tmp_path):
    """An FRF as measuring equipment exports it: Hz, dB, degrees, extra text column, a comment."""
    lines = ["# exported by analyser X", "freq_Hz,mag_dB,phase_deg,comment"]
    for f, h in zip(F_HZ, H_TRUE, strict=True):
        lines.append(f"{float(f)!r},{float(20 * np.log10(abs(h)))!r},{float(np.degrees(np.angle(h)))!r},ok; fine")
    return write_csv(tmp_path / "frf.csv", lines)


POLAR = {"frequency": "freq_Hz", "magnitude": "mag_dB", "phase": "phase_deg"}
POLAR_UNITS = {"frequency": "Hz", "magnitude": "dB", "phase": "deg"}


def test_magnitude_phase_in_hz_db_degrees(polar_csv):
    frf = FrequencyData.from_table(polar_csv, columns=POLAR, units=POLAR_UNITS)
    np.testing.assert_allclose(frf.w, 2 * np.pi * F_HZ, rtol=1e-15)  # ω = 2π f
    np.testing.assert_allclose(frf.H[:, 0, 0], H_TRUE, rtol=1e-12)  # |H| = 10^(dB/20), phase in degrees
    assert si.read_data(polar_csv, columns=POLAR, units=POLAR_UNITS) == frf


def test_real_imaginary_in_rad_per_s_with_semicolons(tmp_path):
    w = 2 * np.pi * F_HZ
    lines = ['"w";"Re H";"Im H"'] + [f"{float(a)!r};{float(h.real)!r};{float(h.imag)!r}"
                                     for a, h in zip(w, H_TRUE, strict=True)]
    path = write_csv(tmp_path / "frf.csv", lines)
    frf = FrequencyData.from_table(path, columns={"frequency": "w", "real": "Re H", "imag": "Im H"},
                                   units={"frequency": "rad/s"}, delimiter=";")
    np.testing.assert_array_equal(frf.w, w)  # rad/s: no conversion, bit for bit
    np.testing.assert_array_equal(frf.H[:, 0, 0], H_TRUE)


def test_mimo_entries_by_index_and_by_nested_list():
    H = np.arange(1, 13, dtype=float).reshape(3, 2, 2) * (1 - 0.5j)
    table = {"f": [1.0, 2.0, 3.0]}
    for i in range(2):
        for j in range(2):
            table[f"re{i}{j}"], table[f"im{i}{j}"] = H[:, i, j].real, H[:, i, j].imag
    indexed = {"frequency": "f", **{f"real[{i}][{j}]": f"re{i}{j}" for i in range(2) for j in range(2)},
               **{f"imag[{i}][{j}]": f"im{i}{j}" for i in range(2) for j in range(2)}}
    nested = {"frequency": "f", "real": [["re00", "re01"], ["re10", "re11"]],
              "imag": [["im00", "im01"], ["im10", "im11"]]}
    a = FrequencyData.from_table(table, columns=indexed, units={"frequency": "rad/s"})
    b = FrequencyData.from_table(table, columns=nested, units={"frequency": "rad/s"})
    assert a == b and a.shape == (3, 2, 2)
    np.testing.assert_array_equal(a.H, H)


def test_linear_magnitude_and_radians():
    mag, ph = np.abs(H_TRUE), np.angle(H_TRUE)
    frf = FrequencyData.from_table({"f": F_HZ, "m": mag, "p": ph},
                                   columns={"frequency": "f", "magnitude": "m", "phase": "p"},
                                   units={"frequency": "kHz", "magnitude": "linear", "phase": "rad"})
    np.testing.assert_allclose(frf.w, 2e3 * np.pi * F_HZ, rtol=1e-15)
    np.testing.assert_allclose(frf.H[:, 0, 0], H_TRUE, rtol=1e-14)


def test_io_record_with_time_in_ms_converted_to_seconds(tmp_path):
    lines = ["t_ms,force,position"] + [f"{k * 2.5},{float(np.sin(k))!r},{float(np.cos(k))!r}" for k in range(50)]
    path = write_csv(tmp_path / "io.csv", lines)
    io = IOData.from_table(path, columns={"time": "t_ms", "input": "force", "output": "position"},
                           units={"time": "ms"})
    assert io.dt == pytest.approx(2.5e-3, rel=1e-12) and io.time_unit == "s"
    np.testing.assert_array_equal(io.u[:, 0], np.sin(np.arange(50)))
    assert "dt          : 0.0025 s" in io.summary()
    hours = IOData.from_table(path, columns={"time": "t_ms", "input": "force", "output": "position"},
                              units={"time": "ms"}, time_unit="h")
    assert hours.time_unit == "h" and hours.dt == pytest.approx(2.5e-3 / 3600, rel=1e-12)
    assert "dt          : 6.94444e-07 h (duration" in hours.summary()


def test_io_record_from_dt_and_several_channels():
    table = {"u1": np.ones(6), "u2": np.zeros(6), "y": np.arange(6.0)}
    io = read_data(table, columns={"input": ["u1", "u2"], "output": "y"}, units={"time": "min"}, dt=0.5)
    assert io.n_inputs == 2 and io.dt == 30.0  # 0.5 min


def test_even_times_written_with_few_digits_are_an_even_grid(tmp_path):
    """A new user's 10-minute samples in hours written by "%.6g" (119.667 for 119.66667) were refused as 0.004 of a
    sample off the grid; times within the rounding of their printed digits are read as the even grid they are, and
    jitter beyond that rounding is still refused."""
    t = np.arange(720) / 6.0  # hours
    u, y = np.ones(720), np.linspace(0.0, 1.0, 720)
    cols = {"time": "t_h", "input": "P", "output": "T"}
    for fmt in ("%.6g", "%.3f"):  # significant digits, fixed decimals
        path = tmp_path / "room.csv"
        np.savetxt(path, np.column_stack([t, u, y]), delimiter=",", header="t_h,P,T", comments="", fmt=fmt)
        io = IOData.from_table(path, columns=cols, units={"time": "h"}, time_unit="h")
        assert io.n_samples == 720
        np.testing.assert_allclose(io.dt, 1 / 6, rtol=1e-7)  # the grid fitted to 720 times rounded to 5e-4 h
    # another user's 5 s samples over 4 h in minutes by "%.6g" (0.0833333 … 239.917): the grid fitted without
    # weights, pulled by the coarse late times, missed the fine early ones by 1.1 half-units
    minutes = np.arange(2881) * 5 / 60
    path = tmp_path / "tanks.csv"
    np.savetxt(path, np.column_stack([minutes, np.ones(2881), np.zeros(2881)]), delimiter=",", header="t,P,T",
               comments="", fmt="%.6g")
    io = IOData.from_table(path, columns={"time": "t", "input": "P", "output": "T"}, units={"time": "min"},
                           time_unit="min")
    np.testing.assert_allclose(io.dt, 5 / 60, rtol=1e-7)  # 0.0833333 is 4e-7 from 1/12
    jittered = t + 0.004 / 6 * np.sin(np.arange(720))  # up to 0.4 % of a sample, written at full precision
    path = tmp_path / "jitter.csv"
    np.savetxt(path, np.column_stack([jittered, u, y]), delimiter=",", header="t_h,P,T", comments="", fmt="%.17g")
    with pytest.raises(si.DataError, match=r"not equally spaced"):
        IOData.from_table(path, columns=cols, units={"time": "h"})


def test_uneven_times_are_refused_for_iodata_and_read_as_time_series():
    table = {"t": [0.0, 0.5, 1.0, 2.0, 4.0], "u": np.zeros(5), "c": [1.0, 0.8, 0.6, 0.4, 0.2]}
    cols = {"time": "t", "input": "u", "output": "c"}
    with pytest.raises(si.DataError, match=r"not equally spaced.*TimeSeries.*rounded when written, leave the time "
                                           r"column out and give the sample time \(dt=, or --dt\)"):
        IOData.from_table(table, columns=cols, units={"time": "h"})
    ts = TimeSeries.from_table(table, columns=cols, units={"time": "h"}, time_unit="h")
    np.testing.assert_array_equal(ts.t, table["t"])
    assert ts.time_unit == "h" and "over 0 … 4 h" in ts.summary()
    assert read_data(table, columns=cols, units={"time": "h"}, kind="TimeSeries") == TimeSeries.from_table(
        table, columns=cols, units={"time": "h"})


def test_rounded_times_are_still_even():
    t = np.round(np.arange(1000) * 0.001, 3)  # printed with 3 decimals
    io = IOData.from_table({"t": t, "u": np.ones(1000), "y": np.ones(1000)},
                           columns={"time": "t", "input": "u", "output": "y"}, units={"time": "s"})
    assert io.dt == pytest.approx(1e-3, rel=1e-12)


# -- units in the file are never ignored ----------------------------------------------------------------

def test_a_units_comment_that_agrees_is_accepted(tmp_path, polar_csv):
    text = polar_csv.read_text().replace("# exported by analyser X", "# units: Hz, dB, degrees")
    path = tmp_path / "agree.csv"
    path.write_text(text)
    assert FrequencyData.from_table(path, columns=POLAR, units=POLAR_UNITS) == FrequencyData.from_table(
        polar_csv, columns=POLAR, units=POLAR_UNITS)


def test_a_units_comment_that_contradicts_is_an_error(tmp_path, polar_csv):
    path = tmp_path / "contradict.csv"
    path.write_text(polar_csv.read_text().replace("# exported by analyser X", "# units: Hz"))
    with pytest.raises(si.DataError, match=r"line 1: the file states Hz .* the frequency unit declared is rad/s"):
        FrequencyData.from_table(path, columns=POLAR, units={**POLAR_UNITS, "frequency": "rad/s"})


@pytest.mark.parametrize("comment", ["# units: s", "# units: time=s", "# units: t [s], u [N m], y [rad/s]",
                                     "# units: seconds", "# units: t_ms=s", "# units: time in seconds"])
def test_a_time_unit_in_a_units_comment_is_checked(tmp_path, comment):
    """A file that says its times are in seconds, read as milliseconds: a 1000-fold error otherwise silent."""
    path = write_csv(tmp_path / "series.csv", [comment, "t,u,y", "0.000,1,0", "0.001,0,1", "0.002,1,1"])
    with pytest.raises(si.DataError, match=r"line 1: the file states s\b.*the time unit declared is ms"):
        IOData.from_table(path, columns={"time": "t", "input": "u", "output": "y"}, units={"time": "ms"})


def test_a_unit_inside_another_columns_unit_is_not_read_as_its_own(tmp_path):
    """rad/s in the unit of the response is not a statement about the frequency column (a user's file)."""
    path = write_csv(tmp_path / "frf.csv", ["# units: f [Hz], mag [dB re 1 (rad/s)/(N m)], ph [deg]", "f,mag,ph",
                                            "1.0,-20,-90", "2.0,-26,-95"])
    frf = FrequencyData.from_table(path, columns={"frequency": "f", "magnitude": "mag", "phase": "ph"},
                                   units={"frequency": "Hz", "magnitude": "dB", "phase": "deg"})
    np.testing.assert_allclose(frf.w, [2 * np.pi, 4 * np.pi], rtol=1e-15)
    # the same file read with the frequency in rad/s contradicts its own f [Hz]
    with pytest.raises(si.DataError, match=r"states Hz for 'f'.*frequency unit declared is rad/s"):
        FrequencyData.from_table(path, columns={"frequency": "f", "magnitude": "mag", "phase": "ph"},
                                 units={"frequency": "rad/s", "magnitude": "dB", "phase": "deg"})


@pytest.mark.parametrize("comment", ["# units: t [s], u [mg/h], y [mg/L]", "# units: t [s], u [L/s], y [m]",
                                     "# units: t [s], dose_time [min], y [mg/L]"])
def test_the_units_of_inputs_outputs_and_other_columns_are_not_read_as_the_time_unit(tmp_path, comment):
    """A correct pharmacokinetic file (a new user's trial): mg/h is the input's unit, not a statement of hours."""
    path = write_csv(tmp_path / "pk.csv", [comment, "t,u,y,dose_time", "0,1,0,0", "1,0,1,0", "2,1,1,0"])
    io = IOData.from_table(path, columns={"time": "t", "input": "u", "output": "y"}, units={"time": "s"})
    assert io.dt == pytest.approx(1.0, rel=1e-15)


def test_the_units_of_the_real_and_imaginary_parts_are_not_read_as_the_frequency_unit(tmp_path):
    path = write_csv(tmp_path / "frf.csv", ["# units: f [Hz], re [(rad/s)/(N m)], im [(rad/s)/(N m)]", "f,re,im",
                                            "1.0,0.5,-0.5", "2.0,0.2,-0.4"])
    frf = FrequencyData.from_table(path, columns={"frequency": "f", "real": "re", "imag": "im"},
                                   units={"frequency": "Hz"})
    np.testing.assert_allclose(frf.w, [2 * np.pi, 4 * np.pi], rtol=1e-15)


@pytest.mark.parametrize(("name", "declared", "stated"), [("t [s]", "ms", "s"), ("t_ms", "s", "ms"),
                                                          ("time (h)", "s", "h")])
def test_a_unit_in_the_time_columns_name_is_checked(tmp_path, name, declared, stated):
    """A header ``t [s]`` read as milliseconds: the name is the file's own statement of the unit."""
    path = write_csv(tmp_path / "io.csv", [f"{name},u,y", "0,1,0", "1,0,1", "2,1,1"])
    columns = {"time": name, "input": "u", "output": "y"}
    with pytest.raises(si.DataError, match=rf"the time column is named '{re.escape(name)}', which states "
                                           rf"{stated}, but the time unit declared is {declared}"):
        IOData.from_table(path, columns=columns, units={"time": declared})
    assert IOData.from_table(path, columns=columns, units={"time": stated}).time_unit == "s"
    # a DataFrame-like dict's column names are checked the same way
    with pytest.raises(si.DataError, match="which states"):
        IOData.from_table({name: np.arange(3.0), "u": np.ones(3), "y": np.ones(3)}, columns=columns,
                          units={"time": declared})


def test_a_unit_in_a_frequency_tables_names_is_checked(tmp_path):
    path = write_csv(tmp_path / "frf.csv", ["f_rad/s,mag_dB,ph_deg", "1,-20,-90", "2,-26,-95"])
    columns = {"frequency": "f_rad/s", "magnitude": "mag_dB", "phase": "ph_deg"}
    frf = FrequencyData.from_table(path, columns=columns, units={"frequency": "rad/s", "magnitude": "dB",
                                                                  "phase": "deg"})
    np.testing.assert_allclose(frf.w, [1.0, 2.0], rtol=1e-15)
    renamed = write_csv(tmp_path / "frf2.csv", ["freq_rad_s,mag_dB,ph_deg", "1,-20,-90", "2,-26,-95"])
    with pytest.raises(si.DataError, match="named 'freq_rad_s', which states rad/s, but the frequency unit declared "
                                           "is Hz"):
        FrequencyData.from_table(renamed, columns={**columns, "frequency": "freq_rad_s"},
                                 units={"frequency": "Hz", "magnitude": "dB", "phase": "deg"})
    with pytest.raises(si.DataError, match="named 'mag_dB', which states dB, but the magnitude unit declared is "
                                           "linear"):
        FrequencyData.from_table(path, columns=columns, units={"frequency": "rad/s", "magnitude": "linear",
                                                               "phase": "deg"})


def test_a_unit_inside_a_columns_name_before_a_channel_suffix_is_checked(tmp_path):
    """A new user's trial: ``phase_deg_m`` and ``phase_deg_l`` (motor and load) read as radians, accepted (misfit
    0.92), where ``phase_deg`` was refused. The one word after the first that names a unit of the column's
    dimension is the name's statement; ``m`` (a length) is not a phase's."""
    path = write_csv(tmp_path / "frf.csv", ["f_Hz,mag_dB_m,phase_deg_m,t_ms_meas", "1,-20,-90,0", "2,-26,-95,1"])
    columns = {"frequency": "f_Hz", "magnitude": "mag_dB_m", "phase": "phase_deg_m"}
    ok = {"frequency": "Hz", "magnitude": "dB", "phase": "deg"}
    FrequencyData.from_table(path, columns=columns, units=ok)
    with pytest.raises(si.DataError, match="named 'phase_deg_m', which states deg, but the phase unit declared is rad"):
        FrequencyData.from_table(path, columns=columns, units={**ok, "phase": "rad"})
    with pytest.raises(si.DataError, match="named 'mag_dB_m', which states dB, but the magnitude unit declared is "
                                           "linear"):
        FrequencyData.from_table(path, columns=columns, units={**ok, "magnitude": "linear"})
    with pytest.raises(si.DataError, match="named 't_ms_meas', which states ms, but the time unit declared is s"):
        IOData.from_table(path, columns={"time": "t_ms_meas", "input": "f_Hz", "output": "mag_dB_m"},
                          units={"time": "s"})


def test_a_units_comment_without_declared_units_is_an_error(tmp_path):
    path = write_csv(tmp_path / "plain.csv", ["# units: Hz", "f,re,im", "1.0,0.5,-0.5", "2.0,0.2,-0.4"])
    with pytest.raises(si.DataError) as info:
        FrequencyData.from_table(path, columns={"frequency": "f", "real": "re", "imag": "im"})
    assert "states units ('# units: Hz') but none were declared" in str(info.value)
    assert str(info.value).endswith(FRF_EXAMPLE)


def test_units_metadata_in_a_symid_csv_file_is_refused_not_ignored(tmp_path):
    path = tmp_path / "frf.csv"
    FrequencyData([1.0, 2.0], [0.5 - 0.5j, 0.2 - 0.4j]).to_csv(path)
    lines = path.read_text().splitlines()
    path.write_text("\n".join([lines[0], "# units: Hz", *lines[1:]]) + "\n")
    with pytest.raises(si.DataError, match=r"line 2: unknown metadata '# units'.*would be ignored"):
        FrequencyData.from_csv(path)
    with pytest.raises(si.DataError, match="unknown metadata"):
        si.data.load(path)


# -- bad declarations: named errors with a two-line example -----------------------------------------------

BAD_DECLARATIONS = {
    "missing frequency unit": (dict(columns=POLAR, units={"magnitude": "dB", "phase": "deg"}),
                               "the unit of 'frequency' is missing (mHz, Hz, kHz, MHz, GHz, rad/s); symid never "
                               "guesses", True),
    "no units at all": (dict(columns=POLAR, units=None), "the unit of 'frequency' is missing", True),
    "unknown unit": (dict(columns=POLAR, units={**POLAR_UNITS, "frequency": "rpm"}),
                     "unknown unit 'rpm'; symid reads mHz, Hz, kHz, MHz, GHz, rad/s", False),
    "column not in file": (dict(columns={**POLAR, "phase": "phase"}, units=POLAR_UNITS),
                           "no column named 'phase' (it has: freq_Hz, mag_dB, phase_deg, comment)", True),
    "unknown role": (dict(columns={**POLAR, "freq": "freq_Hz"}, units=POLAR_UNITS),
                     "unknown column role 'freq'", True),
    "magnitude without phase": (dict(columns={"frequency": "freq_Hz", "magnitude": "mag_dB"},
                                     units={"frequency": "Hz", "magnitude": "dB"}),
                                "has a magnitude column but no phase column", True),
    "both forms": (dict(columns={**POLAR, "real": "mag_dB", "imag": "phase_deg"}, units=POLAR_UNITS),
                   "both as real/imag and as magnitude/phase", True),
    "unit of an absent role": (dict(columns={"frequency": "freq_Hz", "real": "mag_dB", "imag": "phase_deg"},
                                    units=POLAR_UNITS), "units for 'magnitude', but the table has no", True),
    "text column": (dict(columns={**POLAR, "phase": "comment"}, units=POLAR_UNITS),
                    "column 'comment': 'ok; fine' is not a number", False),
}


@pytest.mark.parametrize("case", sorted(BAD_DECLARATIONS))
def test_bad_declarations_are_named_errors(case, polar_csv):
    kwargs, expected, with_example = BAD_DECLARATIONS[case]
    with pytest.raises(si.DataError) as info:
        FrequencyData.from_table(polar_csv, **kwargs)
    assert expected in str(info.value)
    if with_example:
        assert str(info.value).endswith(FRF_EXAMPLE) and len(FRF_EXAMPLE.splitlines()) == 2


def test_series_errors_quote_the_series_example():
    with pytest.raises(si.DataError) as info:
        IOData.from_table({"u": [1.0, 2.0], "y": [1.0, 2.0]}, columns={"input": "u", "output": "y"})
    assert "no time column declared and no dt= given" in str(info.value)
    assert str(info.value).endswith(SERIES_EXAMPLE)


def test_hostile_csv_tables(tmp_path):
    big = tmp_path / "big.csv"
    with open(big, "wb") as fh:
        fh.truncate(MAX_TABLE_BYTES + 1)  # sparse: the size is refused before anything is read
    with pytest.raises(si.DataError, match="more than the 1073741824 symid reads"):
        FrequencyData.from_table(big, columns=POLAR, units=POLAR_UNITS)
    ragged = write_csv(tmp_path / "ragged.csv", ["f,re,im", "1,2,3", "4,5"])
    with pytest.raises(si.DataError, match=r"line 3: 2 cells; the header .* has 3 columns"):
        FrequencyData.from_table(ragged, columns={"frequency": "f", "real": "re", "imag": "im"},
                                 units={"frequency": "Hz"})
    nan = write_csv(tmp_path / "nan.csv", ["f,re,im", "1,2,3", "4,nan,5"])
    with pytest.raises(si.DataError, match="line 3, column 're': nan is not a finite number"):
        FrequencyData.from_table(nan, columns={"frequency": "f", "real": "re", "imag": "im"},
                                 units={"frequency": "Hz"})
    dup = write_csv(tmp_path / "dup.csv", ["f,re,re", "1,2,3"])
    with pytest.raises(si.DataError, match="names column 're' twice"):
        FrequencyData.from_table(dup, columns={"frequency": "f", "real": "re", "imag": "re"},
                                 units={"frequency": "Hz"})
    if os.name == "posix":
        fifo = tmp_path / "fifo"
        os.mkfifo(fifo)
        with pytest.raises(si.DataError, match="not a regular file"):
            FrequencyData.from_table(fifo, columns=POLAR, units=POLAR_UNITS)
    symid_own = tmp_path / "own.csv"
    FrequencyData([1.0], [1.0]).to_csv(symid_own)
    with pytest.raises(si.DataError, match="is a symid CSV file: read it without columns"):
        FrequencyData.from_table(symid_own, columns=POLAR, units=POLAR_UNITS)


def test_read_data_without_columns_reads_symid_files_and_explains_plain_ones(polar_csv, tmp_path):
    own = tmp_path / "own.npz"
    IOData(np.ones(3), np.arange(3.0), dt=0.1, time_unit="ms").to_npz(own)
    assert read_data(own) == IOData(np.ones(3), np.arange(3.0), dt=0.1, time_unit="ms")
    with pytest.raises(si.DataError) as info:
        read_data(polar_csv)
    assert "is not a symid CSV file" in str(info.value) and FRF_EXAMPLE in str(info.value)


# -- the time unit travels with the record ---------------------------------------------------------------

def test_time_unit_round_trips_through_csv_npz_and_pickle(tmp_path):
    import pickle

    io = IOData(np.ones((4, 1)), np.arange(4.0), dt=0.25, time_unit="h")
    io.to_csv(tmp_path / "io.csv")
    io.to_npz(tmp_path / "io.npz")
    assert IOData.from_csv(tmp_path / "io.csv") == io == IOData.from_npz(tmp_path / "io.npz")
    assert pickle.loads(pickle.dumps(io)) == io
    assert io != IOData(np.ones((4, 1)), np.arange(4.0), dt=0.25)  # same numbers, other unit
    assert repr(io) == "IOData(4 samples, dt = 0.25 h, 1 input(s), 1 output(s))"
    with pytest.raises(si.DataError, match="unknown unit 'fortnight'"):
        IOData(np.ones(2), np.ones(2), dt=1.0, time_unit="fortnight")
    ts = TimeSeries([0.0, 1.0], [0.0, 0.0], [1.0, 0.5], time_unit="min")
    ts.to_npz(tmp_path / "ts.npz")
    assert TimeSeries.from_npz(tmp_path / "ts.npz") == ts and si.data.load(tmp_path / "ts.npz") == ts


def test_files_without_a_time_unit_are_in_seconds(tmp_path):
    """NPZ and CSV files written before the time unit existed read as seconds (format unchanged otherwise)."""
    np.savez(tmp_path / "old.npz", kind=np.array("IOData"), format_version=np.array(1), u=np.ones((3, 1)),
             y=np.zeros((3, 1)), dt=np.array(0.1))
    assert IOData.from_npz(tmp_path / "old.npz").time_unit == "s"
    write_csv(tmp_path / "old.csv", ["# symid IOData csv v2", "# dt: 0.1", "# n_inputs: 1", "# n_outputs: 1",
                                     "# n_rows: 2", "u[0],y[0]", "1.0,0.0", "1.0,0.5", "# end"])
    assert IOData.from_csv(tmp_path / "old.csv").time_unit == "s"


# -- MATLAB files -----------------------------------------------------------------------------------------

def test_mat_file_vectors_and_matrices(tmp_path):
    path = tmp_path / "rec.mat"
    t = np.arange(200) * 1e-3
    acc = np.vstack([np.sin(t), np.cos(t), t])  # 3 channels in rows, as the F-16 benchmark stores them
    scipy.io.savemat(path, {"t": t.reshape(-1, 1), "force": t.reshape(1, -1), "acc": acc}, do_compression=True)
    io = IOData.from_table(path, columns={"time": "t", "input": "force", "output": "acc"}, units={"time": "s"})
    assert io.n_outputs == 3 and io.dt == pytest.approx(1e-3, rel=1e-12)
    np.testing.assert_array_equal(io.y, acc.T)  # samples × channels, transposed by its sample axis
    one = IOData.from_table(path, columns={"time": "t", "input": "force", "output": "acc[1]"}, units={"time": "s"})
    np.testing.assert_array_equal(one.y[:, 0], np.cos(t))


def test_real_measurements_from_a_mat_file():
    """The EMPS benchmark's own file (shared data, MATLAB v5, compressed): 24 841 samples at 1 ms."""
    path = Path(os.environ.get("SYMID_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"))
    path = path / "emps" / "DATA_EMPS.mat"
    if not path.is_file():
        pytest.skip(f"the EMPS data are not beside the repository ({path})")
    io = IOData.from_table(path, columns={"time": "t", "input": "vir", "output": "qm"}, units={"time": "s"})
    assert io.n_samples == 24841 and io.dt == pytest.approx(1e-3, rel=1e-9)  # the data set's README


def test_hostile_mat_files(tmp_path):
    cells = tmp_path / "cells.mat"
    scipy.io.savemat(cells, {"t": np.arange(3.0), "c": np.array([[1.0], "x"], dtype=object),
                             "s": {"a": 1.0}})
    for name, kind in (("c", "cell"), ("s", "struct")):
        with pytest.raises(si.DataError, match=f"variable '{name}' is a MATLAB {kind}, not a numeric array"):
            IOData.from_table(cells, columns={"time": "t", "input": name, "output": "t"}, units={"time": "s"})
    with pytest.raises(si.DataError, match="has no variable 'u'"):
        IOData.from_table(cells, columns={"time": "t", "input": "u", "output": "t"}, units={"time": "s"})
    # a compression bomb: 256 MB of zeros in a file of a few hundred kB
    bomb = tmp_path / "bomb.mat"
    scipy.io.savemat(bomb, {"t": np.arange(3.0), "z": np.zeros((4096, 8192))}, do_compression=True)
    assert bomb.stat().st_size < 2**20
    with pytest.raises(si.DataError, match="expand to more than"):
        IOData.from_table(bomb, columns={"time": "t", "input": "t", "output": "t"}, units={"time": "s"})
    hdf5 = tmp_path / "v73.mat"
    hdf5.write_bytes(b"MATLAB 7.3 MAT-file, Platform: x" + b" " * 96 + b"\x89HDF\r\n\x1a\n" + b"\0" * 64)
    with pytest.raises(si.DataError, match=r"v7.3 .HDF5. file; save it with save"):
        IOData.from_table(hdf5, columns={"time": "t", "input": "t", "output": "t"}, units={"time": "s"})
    lying = tmp_path / "lying.mat"
    good = tmp_path / "good.mat"
    scipy.io.savemat(good, {"t": np.arange(3.0)})
    raw = bytearray(good.read_bytes())
    raw[132:136] = (2**31).to_bytes(4, "little")  # the first element claims 2 GB
    lying.write_bytes(bytes(raw))
    with pytest.raises(si.DataError, match=r"more than the .* left in the file"):
        IOData.from_table(lying, columns={"time": "t", "input": "t", "output": "t"}, units={"time": "s"})


# -- pandas DataFrames (pandas is a test dependency, not one of symid) ------------------------------------

def test_pandas_dataframe():
    pd = pytest.importorskip("pandas", reason="pandas is in the test extra")
    df = pd.DataFrame({"f": F_HZ, "mag": 20 * np.log10(np.abs(H_TRUE)), "ph": np.degrees(np.angle(H_TRUE)),
                       "note": ["a", "b", "c", "d", "e"]})
    frf = FrequencyData.from_table(df, columns={"frequency": "f", "magnitude": "mag", "phase": "ph"},
                                   units=POLAR_UNITS)
    np.testing.assert_allclose(frf.H[:, 0, 0], H_TRUE, rtol=1e-12)
    with pytest.raises(si.DataError, match="must hold numbers"):
        FrequencyData.from_table(df, columns={"frequency": "f", "magnitude": "mag", "phase": "note"},
                                 units=POLAR_UNITS)


def test_duck_typed_frame_without_pandas():
    class Column:
        def __init__(self, values):
            self.values = values

        def to_numpy(self):
            return np.asarray(self.values)

    class Frame:
        columns = ("t", "u", "y")

        def __getitem__(self, key):
            return Column({"t": [0.0, 1.0, 2.0], "u": [1.0, 0.0, 0.0], "y": [0.0, 0.5, 0.7]}[key])

    io = IOData.from_table(Frame(), columns={"time": "t", "input": "u", "output": "y"}, units={"time": "s"})
    assert io.dt == 1.0 and io.n_samples == 3


# -- the command line -------------------------------------------------------------------------------------

def test_cli_identifies_from_a_plain_csv_table(tmp_path, capsys):
    entry = si.load_model("mass_damper_2dof")
    frf = entry.data()
    lines = ["# units: Hz, dB, deg", "f,mag,ph"] + [
        f"{float(w / (2 * np.pi))!r},{float(20 * np.log10(abs(h)))!r},{float(np.degrees(np.angle(h)))!r}"
        for w, h in zip(frf.w, frf.H[:, 0, 0], strict=True)]
    path = write_csv(tmp_path / "plain.csv", lines)
    argv = ["identify", "mass_damper_2dof", "--data", str(path), "--method", "ipopt", "--seed", "3",
            "--columns", "frequency=f", "magnitude=mag", "phase=ph", "--units", "frequency=Hz", "magnitude=dB",
            "phase=deg"]
    assert main(argv) == 0
    assert "data: " + str(path) in capsys.readouterr().out
    argv_bad = [*argv[:-3], "frequency=rad/s", "magnitude=dB", "phase=deg"]
    assert main(argv_bad) == 2
    err = capsys.readouterr().err
    assert "the file states Hz" in err and "Traceback" not in err


def test_cli_table_flags_need_columns(tmp_path, capsys):
    assert main(["identify", "belt_drive", "--data", "x.csv", "--units", "frequency=Hz"]) == 2
    assert "--units describe a table: give --columns too" in capsys.readouterr().err
    assert main(["identify", "belt_drive", "--columns", "frequency=f"]) == 2
    assert "describe the table given with --data" in capsys.readouterr().err


def test_a_header_split_by_another_separator_says_which(tmp_path):
    path = write_csv(tmp_path / "semi.csv", ["f_Hz;mag_dB;phase_deg", "1;-20;-90", "2;-26;-95"])
    with pytest.raises(si.DataError, match=r"the header looks ';'-separated, not ',': read it with delimiter=';'"):
        FrequencyData.from_table(path, columns={"frequency": "f_Hz", "magnitude": "mag_dB", "phase": "phase_deg"},
                                 units={"frequency": "Hz", "magnitude": "dB", "phase": "deg"})


def test_a_decimal_comma_is_named(tmp_path):
    """A European export, ';' between cells and ',' as the decimal point (a new user's trial)."""
    path = write_csv(tmp_path / "eu.csv", ["t;u;y", "0,0;1,5;0,25", "0,1;1,5;0,5"])
    with pytest.raises(si.DataError, match=r"line 2, column 't': '0,0' is not a number \(a decimal comma\?"):
        IOData.from_table(path, columns={"time": "t", "input": "u", "output": "y"}, units={"time": "s"},
                          delimiter=";")


@pytest.mark.parametrize("kind", ["IOData", "TimeSeries"])
def test_times_out_of_order_name_the_files_lines_and_unit(tmp_path, kind):
    """Times that repeat or go back: the file's line numbers (after a comment and the header), the column and the
    declared unit, not the indices of the converted array."""
    cols, units = {"time": "t", "input": "u", "output": "y"}, {"time": "ms"}
    dup = write_csv(tmp_path / "dup.csv", ["# a rig export", "t,u,y", "0,1,0.1", "10,1,0.2", "10,1,0.3", "30,1,0.4"])
    with pytest.raises(si.DataError, match=r"dup.csv', lines 4 and 5, column 't': both times are 10 ms: a "
                                           r"duplicated sample time"):
        read_data(dup, columns=cols, units=units, kind=kind)
    back = write_csv(tmp_path / "back.csv", ["t,u,y", "0,1,0.1", "20,1,0.2", "10,1,0.3", "30,1,0.4"])
    with pytest.raises(si.DataError, match=r"back.csv', lines 3 and 4, column 't': the time 10 ms comes after "
                                           r"20 ms: sample times must increase; sort the rows by time"):
        read_data(back, columns=cols, units=units, kind=kind)
    with pytest.raises(si.DataError, match=r"the table, rows 1 and 2, column 't': both times are 10 ms"):
        read_data({"t": [0, 10, 10], "u": [1, 1, 1], "y": [1, 2, 3]}, columns=cols, units=units, kind=kind)


def test_numbers_in_double_quotes_are_read(tmp_path):
    """Spreadsheets may quote every cell, numbers too: a quoted cell is its text (the header's names were already)."""
    path = write_csv(tmp_path / "quoted.csv", ['"t","u","y"', '"0","1.5","0.25"', '"0.1","1.5","0.5"'])
    rec = IOData.from_table(path, columns={"time": "t", "input": "u", "output": "y"}, units={"time": "s"})
    np.testing.assert_array_equal(rec.y[:, 0], [0.25, 0.5])
    assert rec.dt == 0.1


def test_a_unit_symid_does_not_know_is_warned_about_not_passed_over(tmp_path):
    """``t [Std]`` (German hours) in a units comment: symid cannot check it against the declared unit, and says
    so (a DataWarning naming the line, the column and the declared unit); an unknown unit of an input or output
    column is not a time unit at all and is not warned about."""
    path = write_csv(tmp_path / "std.csv", ["# units: t [Std], u [Skt], y [m]", "t,u,y", "0,1,0.1", "1,1,0.2"])
    with pytest.warns(si.DataWarning) as seen:
        rec = IOData.from_table(path, columns={"time": "t", "input": "u", "output": "y"}, units={"time": "s"})
    texts = [str(w.message) for w in seen if issubclass(w.category, si.DataWarning)]
    assert len(texts) == 1 and "line 1: the file states 'Std' for 't', which symid does not read as a time unit, " \
        "so it is not checked against the time unit declared (s)" in texts[0]
    assert rec.dt == 1.0


def test_a_cell_that_is_not_a_number_in_a_dict_or_frame_is_named_with_its_row():
    """A dict or DataFrame column holding text, or None (a new user's trial: "got objects that are not numbers",
    no row; None was even called a complex value)."""
    cols, units = {"time": "t", "input": "u", "output": "y"}, {"time": "s"}
    with pytest.raises(si.DataError, match=r"column 'y' must hold numbers; got text, 'x' at \[1\]"):
        IOData.from_table({"t": [0, 1, 2], "u": [1, 1, 1], "y": [1, "x", 3]}, columns=cols, units=units)
    with pytest.raises(si.DataError, match=r"must hold numbers; got 'x' at \[1\]"):
        IOData(np.array([1, "x", 3], dtype=object), np.ones(3), 1.0)
    with pytest.raises(si.DataError, match=r"holds None at \[2\]: a missing value\?"):
        IOData(np.array([1.0, 2.0, None], dtype=object), np.ones(3), 1.0)


def test_mega_is_not_milli_but_capitals_are_read_as_written():
    """A new user's trial: --units time=Ms and time=MS were both read as milliseconds. Ms (mega) is refused with
    the reason; MS in capitals (a logger's TIME_MS) is ms; RAD/S in capitals is rad/s, not rad and s."""
    from symid.data.units import canonical_unit, unit_tokens

    with pytest.raises(si.DataError, match=r"unknown unit 'Ms' \(M is mega: milliseconds are ms\)"):
        canonical_unit("Ms", "time", "units of 'time'")
    assert canonical_unit("MS", "time", "units of 'time'") == "ms"
    assert canonical_unit("ms", "time", "units of 'time'") == "ms"
    assert unit_tokens("Ms", strict=True) == [] and unit_tokens("MSEC", strict=True) == [("time", "ms")]
    assert unit_tokens("RAD/S", strict=True) == [("frequency", "rad/s")]


def test_a_gap_in_an_equally_spaced_record_names_its_lines_and_size(tmp_path):
    """A new user's 3-day record with 10 minutes missing was told "sample 1000 is at 60599.9988, 7.66 sample times
    away from an even grid of step 60.1392" (seconds, of a file in hours; no line). The gap is named: the file's
    lines, the times in its unit, how many samples are missing."""
    t = [k / 60 for k in range(200) if not 100 <= k < 110]  # one minute in hours; 10 samples missing
    rows = "\n".join(f"{v:.6f},1.0,0.5" for v in t)
    path = write_csv(tmp_path / "gap.csv", ["t_h,P,Ta", rows])
    with pytest.raises(si.DataError, match=r"lines 101 and 102, column 't_h': the times jump from 1.65 to 1.833333 "
                                           r"h, 11 steps of 0.0166\d* h: about 10 samples are missing"):
        IOData.from_table(path, columns={"time": "t_h", "input": "P", "output": "Ta"}, units={"time": "h"})
    assert TimeSeries.from_table(path, columns={"time": "t_h", "input": "P", "output": "Ta"},
                                 units={"time": "h"}).n_samples == 190


def test_a_units_comment_may_name_a_column_without_its_unit_suffix(tmp_path):
    """A new user's "# units: t [min], q [W], T [degC]" over the header "t_min,q_W,T_degC": the time's unit was
    matched but the input's was not, so W against the model's kW went unchecked (g 1000 times off, success). The
    comment's names now match a column by its name without the unit it ends in, as for the time; a name that is no
    column either way is said."""
    rows = "0,0,0\n1,1,0.1\n2,1,0.2\n3,0,0.25\n4,0,0.2\n"
    (tmp_path / "a.csv").write_text("# units: t [min], q [W], T [degC]\nt_min,q_W,T_degC\n" + rows)
    rec = si.read_data(tmp_path / "a.csv", columns={"time": "t_min", "input": "q_W", "output": "T_degC"},
                       units={"time": "min"})
    assert rec.stated_units["input"] == (("q_W", "W"),) and rec.stated_units["output"] == (("T_degC", "degC"),)
    (tmp_path / "b.csv").write_text("# units: t [min], q [kW], T [degC]\ntime_min,power,temp\n" + rows)
    with pytest.warns(si.DataWarning, match=r"the units comment names 't', 'q', 'T', which are no columns"):
        rec = si.read_data(tmp_path / "b.csv", columns={"time": "time_min", "input": "power", "output": "temp"},
                           units={"time": "min"})
    assert rec.stated_units["input"] == (("power", None),)


def test_quoted_cells_delimiters_and_a_units_row(tmp_path):
    """A new user's tables: a quoted text cell with a comma ("a, b") and quoted decimal commas ("0,0002") were split
    at their commas ('5 cells; the header has 4'); a ';'-separated file read with ',' was told only its cell counts;
    a row of units under the header was "'s' is not a number"."""
    cols = {"time": "t", "input": "u", "output": "y"}
    quoted = tmp_path / "quoted.csv"
    quoted.write_text('t,u,y,note\n0,1,0.5,"a, b"\n1,1,0.6,"c"\n2,0,0.4,""\n', encoding="utf-8")
    io = IOData.from_table(quoted, columns=cols, units={"time": "s"})
    np.testing.assert_array_equal(io.y[:, 0], [0.5, 0.6, 0.4])
    commas = tmp_path / "commas.csv"
    commas.write_text('t,u,y\n"0","1","0,5"\n"1","1","0,6"\n', encoding="utf-8")
    with pytest.raises(si.DataError, match=r"line 2, column 'y': '0,5' is not a number \(a decimal comma\?"):
        IOData.from_table(commas, columns=cols, units={"time": "s"})
    semi = tmp_path / "semi.csv"
    semi.write_text("t;u;y\n0;1;0,5\n1;1;0,6\n", encoding="utf-8")
    with pytest.raises(si.DataError, match=r"the header \(line 1\) has 1 column \(delimiter ','\); the header holds "
                                           r"';': is that the delimiter\? \(delimiter=';'"):
        IOData.from_table(semi, columns=cols, units={"time": "s"})
    units = tmp_path / "units.csv"
    units.write_text("t,u,y\ns,A,rad/s\n0,1,0.5\n1,1,0.6\n", encoding="utf-8")
    with pytest.raises(si.DataError, match=r"'s' is not a number \(a row of units under the header\? .*'t \[s\]'"):
        IOData.from_table(units, columns=cols, units={"time": "s"})


def test_a_preamble_above_the_header_is_said_and_skipped(tmp_path):
    """A dynamic signal analyzer's export (a new user's): "Instrument: …", "Date: …" lines, a blank one, then the
    header. It was "line 5: 3 cells; the header (line 1) has 1 column". The first line that names every column
    asked for is the header, when every line above it has fewer cells; the lines above are said in a DataWarning
    and kept as comments. Without such a line the error says where a header is looked for."""
    path = tmp_path / "dsa.csv"
    path.write_text("Instrument: DSA-1234\nDate: 2026-11-29\nAverages: 20\n\n"
                    "Frequency (Hz),Magnitude (dB),Phase (deg)\n1,20,-90\n2,14,-120\n4,6,-150\n", encoding="utf-8")
    cols = {"frequency": "Frequency (Hz)", "magnitude": "Magnitude (dB)", "phase": "Phase (deg)"}
    units = {"frequency": "Hz", "magnitude": "dB", "phase": "deg"}
    with pytest.warns(si.DataWarning, match=r"lines 1–3 read as a preamble above the header \(line 5, the first to "
                                           r"name the columns asked for\): 'Instrument: DSA-1234'") as seen:
        frf = si.FrequencyData.from_table(path, columns=cols, units=units)
    assert seen[0].filename == __file__  # pointed at the caller, not at symid's reader
    np.testing.assert_allclose(frf.w, 2 * np.pi * np.array([1.0, 2.0, 4.0]), rtol=1e-15)
    np.testing.assert_allclose(np.abs(frf.H[:, 0, 0]), 10 ** (np.array([20, 14, 6]) / 20), rtol=1e-12)
    wrong = dict(cols, phase="Phase [deg]")  # a name no line holds: the reader's error, with where it looked
    with pytest.raises(si.DataError, match=r"line 5: 3 cells; the header \(line 1\) has 1 column .*a preamble .*"
                                           r"'Phase \[deg\]'\), and none of the first 50 does"):
        si.FrequencyData.from_table(path, columns=wrong, units=units)
    # a file whose first line names the columns is read as before, whatever lines below hold
    plain = tmp_path / "plain.csv"
    plain.write_text("t,u,y\n0,1,0\n1,1,0.5\n", encoding="utf-8")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        io = IOData.from_table(plain, columns={"time": "t", "input": "u", "output": "y"}, units={"time": "s"})
    assert io.y.shape == (2, 1)



def test_a_phase_in_degrees_declared_in_radians_is_said(tmp_path):
    """A new user's analyzer file in degrees, declared rad (a neutral column name): every phase a radian count up to
    91, and the fit failed with a generic message. A phase in rad beyond ±2π that also jumps between neighbouring
    lines is said; a smooth unwrapped phase in rad beyond 2π (a high-order response) is not."""
    f = np.linspace(1, 100, 200)
    H = 1 / ((1j * 2 * np.pi * f / 30 + 1) ** 6)  # phase from 0 to about −6 × 87°, unwrapped to −9.1 rad
    deg = np.degrees(np.unwrap(np.angle(H)))
    for name, phase, said in (("deg.csv", deg, True), ("rad.csv", np.radians(deg), False)):
        path = tmp_path / name
        np.savetxt(path, np.column_stack([f, np.abs(H), phase]), delimiter=",", header="f,mag,ph", comments="")
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            si.FrequencyData.from_table(path, columns={"frequency": "f", "magnitude": "mag", "phase": "ph"},
                                        units={"frequency": "Hz", "magnitude": "linear", "phase": "rad"})
        texts = [str(w.message) for w in seen if issubclass(w.category, si.DataWarning)]
        assert any("phase 'ph' is declared in rad but reaches" in t and "is it in degrees?" in t
                   for t in texts) == said, texts


def test_a_sparse_phase_in_radians_is_not_said_to_be_degrees(tmp_path):
    """No false alarm on a coarse grid of a lightly damped two-mode response in rad, unwrapped beyond −2π (steps
    of up to 1.4 rad at the resonances)."""
    w = np.logspace(0, 2, 40)
    s = 1j * w
    H = 1 / ((s**2 + 0.1 * s + 9) * (s**2 + 0.4 * s + 900) * (s / 50 + 1) ** 2)
    path = tmp_path / "sparse.csv"
    np.savetxt(path, np.column_stack([w, np.abs(H), np.unwrap(np.angle(H))]), delimiter=",", header="w,mag,ph",
               comments="")
    assert np.abs(np.unwrap(np.angle(H))).max() > 2 * np.pi
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        si.FrequencyData.from_table(path, columns={"frequency": "w", "magnitude": "mag", "phase": "ph"},
                                    units={"frequency": "rad/s", "magnitude": "linear", "phase": "rad"})


def test_megahertz_and_gigahertz_are_read(tmp_path):
    """A network analyzer exports in MHz (a new user's 10 kHz – 100 MHz sweep): "unknown unit 'MHz'", and a column
    named f_MHz declared Hz was read silently (f_kHz was caught). MHz and GHz are read, MHz is not mHz, and 'mhz'
    in lower case, mega or milli, is refused."""
    path = tmp_path / "vna.csv"
    np.savetxt(path, np.column_stack([[0.01, 1.0, 100.0], [1.0, 0.9, 0.1], [0.0, -10.0, -170.0]]), delimiter=",",
               header="f_MHz,mag,ph", comments="")
    cols = {"frequency": "f_MHz", "magnitude": "mag", "phase": "ph"}
    frf = si.FrequencyData.from_table(path, columns=cols, units={"frequency": "MHz", "magnitude": "linear",
                                                                 "phase": "deg"})
    np.testing.assert_allclose(frf.w, 2 * np.pi * np.array([1e4, 1e6, 1e8]), rtol=1e-15)
    with pytest.raises(si.DataError, match=r"'f_MHz', which states MHz, but the frequency unit declared is Hz"):
        si.FrequencyData.from_table(path, columns=cols, units={"frequency": "Hz", "magnitude": "linear",
                                                               "phase": "deg"})
    with pytest.raises(si.DataError, match=r"unknown unit 'mhz' \(mega or milli\? write MHz or mHz\)"):
        si.FrequencyData.from_table(path, columns=cols, units={"frequency": "mhz", "magnitude": "linear",
                                                               "phase": "deg"})
    from symid.data.units import canonical_unit

    assert [canonical_unit(u, "frequency", "f") for u in ("MHz", "MHZ", "mHz", "GHz", "ghz")] == \
        ["MHz", "MHz", "mHz", "GHz", "GHz"]
