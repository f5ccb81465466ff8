"""The ``symid`` command line: every command has --help; models, show, identify, compare work."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import symid as si
from symid.cli import NO_FIT, build_parser, main

ROOT = Path(__file__).resolve().parents[1]
COMMANDS = ["models", "show", "identify", "compare", "demo", "identifiability"]


def test_every_command_is_registered():
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    assert sorted(sub.choices) == sorted(COMMANDS)


@pytest.mark.parametrize("command", COMMANDS)
def test_help_on_every_command(command, capsys):
    with pytest.raises(SystemExit) as info:
        main([command, "--help"])
    assert info.value.code == 0
    assert "usage: symid " + command in capsys.readouterr().out


def test_models_lists_the_zoo(capsys):
    assert main(["models"]) == 0
    out = capsys.readouterr().out
    for name in ("belt_drive", "mass_damper_2dof", "truss8", "enose"):
        assert name in out


def test_show_prints_parameters_matrices_truth(capsys):
    assert main(["show", "mass_damper_2dof"]) == 0
    out = capsys.readouterr().out
    assert "M =" in out and "truth:" in out and "m1" in out


def test_unknown_model_is_a_clear_error(capsys):
    assert main(["show", "no_such_model"]) == 2
    assert "no zoo model named 'no_such_model'" in capsys.readouterr().err


def test_identify_writes_results(tmp_path, capsys):
    data = tmp_path / "frf.csv"

    entry = si.load_model("belt_drive")
    entry.data().to_csv(data)
    code = main(["identify", "belt_drive", "--data", str(data), "--method", "ipopt", "--starts", "1",
                 "--out", str(tmp_path / "out")])
    out = capsys.readouterr().out
    assert "method: ipopt" in out
    assert code in (0, 4)
    result = json.loads((tmp_path / "out" / "result.json").read_text())
    assert result["method"] == "ipopt" and len(result["starts"]) == 1
    assert (tmp_path / "out" / "bode.png").stat().st_size > 1000
    # summary.txt says what it is of, as result.json does, before the summary (a frequency response: no time unit)
    summary = (tmp_path / "out" / "summary.txt").read_text().splitlines()
    assert summary[:3] == ["model: belt_drive", f"data: {data}", ""] and summary[3].startswith("method: ipopt")


def test_compare_on_zoo_recipe(tmp_path, capsys):
    assert main(["compare", "mass_damper_2dof", "--methods", "ipopt", "--starts", "3",
                 "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "ipopt" in out and "successes" in out
    assert json.loads((tmp_path / "comparison.json").read_text())["n_starts"] == 3


def test_module_runs_from_the_source_tree():
    """`python -m symid.cli` in the repository root imports the checkout's symid/ (not the
    installed one), where the zoo is the folder models/ rather than symid.zoo_models."""
    proc = subprocess.run([sys.executable, "-m", "symid.cli", "models"], capture_output=True, text=True,
                          timeout=120, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    assert "belt_drive" in proc.stdout


def test_console_script_runs_from_any_directory(tmp_path):
    script = Path(sys.executable).with_name("symid")
    assert script.is_file(), f"console script not installed beside {sys.executable}"
    proc = subprocess.run([str(script), "show", "belt_drive"], capture_output=True, text=True, timeout=120,
                          cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "theta1" in proc.stdout


def test_identify_scr_with_polish_and_its_progress_bar(tmp_path, capsys):
    code = main(["identify", "mass_damper_2dof", "--method", "scr", "--starts", "2", "--seed", "1", "--max-iter", "15",
                 "--polish", "--out", str(tmp_path)])
    captured = capsys.readouterr()
    assert code == 0
    assert "method: scr " in captured.out and "after polish:" in captured.out
    assert "scr starts" in captured.err  # the progress bar of the multi-start run (standard error)
    result = json.loads((tmp_path / "result.json").read_text())
    assert result["method"] == "scr" and result["polished"]["method"] == "scr+polish"
    # what the result is of, as --json says it (a new user's trial: the file had no model or data)
    assert result["model"] == "mass_damper_2dof" and result["data"] == "the zoo recipe" and result["time_unit"] is None
    assert (tmp_path / "convergence.png").stat().st_size > 10_000


def test_compare_scr_polish_ipopt(capsys):
    assert main(["compare", "belt_drive", "--methods", "scr,scr+polish,ipopt", "--starts", "3"]) == 0
    captured = capsys.readouterr()
    for row in ("   scr ", "scr+polish", "ipopt"):
        assert row in captured.out
    assert "ipopt" in captured.err  # progress bars


def test_data_that_does_not_fit_the_model_is_a_clear_error(tmp_path, capsys):
    import numpy as np


    path = tmp_path / "two_outputs.npz"
    si.FrequencyData(np.array([0.4, 0.5, 0.6]), np.ones((3, 2, 1), dtype=complex)).to_npz(path)
    assert main(["identify", "belt_drive", "--data", str(path)]) == 2
    err = capsys.readouterr().err
    assert "symid: error: data H has 2 output(s) × 1 input(s) per frequency; the model has 1 output(s)" in err
    assert "Traceback" not in err


def test_demo_writes_table_and_both_figures(tmp_path, capsys):
    from symid.demo import run_demo

    assert run_demo(out=tmp_path, starts=3, convergence_iterations=20) == 0
    out = capsys.readouterr().out
    assert "time to solution s" in out and "‖θ̂ − θ*‖₂" in out
    for name in ("bode.png", "convergence.png"):
        assert (tmp_path / name).stat().st_size > 10_000


def test_closed_pipe_is_not_a_traceback(monkeypatch, tmp_path):
    """`symid models | head -1`: when the reader has closed the pipe, writing raises BrokenPipeError;
    the command stops quietly with exit code 0 instead of a traceback."""

    class ClosedPipe:
        def __init__(self, fd):
            self.fd = fd

        def write(self, text):
            raise BrokenPipeError(32, "Broken pipe")

        def flush(self):
            raise BrokenPipeError(32, "Broken pipe")

        def fileno(self):
            return self.fd

    with open(tmp_path / "stdout", "w") as sink:
        monkeypatch.setattr(sys, "stdout", ClosedPipe(os.dup(sink.fileno())))
        assert main(["models"]) == 0


def _exit_code(argv: list[str]) -> int:
    """main()'s status, whether it returns it or argparse exits with it."""
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code)


@pytest.fixture
def bad_paths(tmp_path):
    afile = tmp_path / "afile.txt"
    afile.write_text("not data\n")
    (tmp_path / "adir").mkdir()
    return {"file": str(afile), "dir": str(tmp_path / "adir"), "missing": str(tmp_path / "missing.csv")}


BAD_COMMAND_LINES = {  # issue 12 item 6, and the same kinds found while fixing them
    "negative seed": (["identify", "belt_drive", "--seed", "-1"], "--seed: must be an integer ≥ 0"),
    "float seed": (["identifiability", "belt_drive", "--seed", "1.5"], "'1.5' is not an integer"),
    "missing data file": (["identify", "belt_drive", "--data", "{missing}"], "No such file"),
    "data is a folder": (["identify", "belt_drive", "--data", "{dir}"], "Is a directory"),
    "out is a file": (["identify", "belt_drive", "--out", "{file}"], "exists and is not a folder"),
    "out unwritable": (["identify", "belt_drive", "--out", "/proc/x"], "cannot write to --out"),
    "compare out is a file": (["compare", "belt_drive", "--out", "{file}"], "exists and is not a folder"),
    "demo out is a file": (["demo", "--out", "{file}"], "exists and is not a folder"),
    "timeout nan": (["identifiability", "belt_drive", "--timeout", "nan"], "finite number of seconds > 0"),
    "timeout inf": (["identifiability", "belt_drive", "--timeout", "inf"], "finite number of seconds > 0"),
    "timeout negative": (["identifiability", "belt_drive", "--timeout", "-1"], "finite number of seconds > 0"),
    "known nan": (["identifiability", "belt_drive", "--known", "theta1=nan"], "must be finite"),
    "known inf": (["identifiability", "belt_drive", "--known", "theta1=inf"], "must be finite"),
    "known overflow": (["identifiability", "belt_drive", "--known", "theta1=1e400"], "must be finite"),
    "known no value": (["identifiability", "belt_drive", "--known", "theta1"], "expects name=value"),
    "known twice": (["identifiability", "belt_drive", "--known", "theta1=1", "theta1=2"], "twice"),
    "max-iter 0": (["identify", "belt_drive", "--max-iter", "0"], "--max-iter: must be an integer ≥ 1"),
    "starts 0": (["identify", "belt_drive", "--starts", "0"], "--starts: must be an integer between 1"),
    "starts huge": (["compare", "belt_drive", "--starts", "1000000000"], "--starts: must be an integer between"),
    "no methods": (["compare", "belt_drive", "--methods", ","], "names no method"),
    "unknown command": (["frobnicate"], "invalid choice"),
}


@pytest.mark.parametrize("case", sorted(BAD_COMMAND_LINES))
def test_bad_command_lines_give_one_line_and_status_2(case, bad_paths, capsys):
    argv, expected = BAD_COMMAND_LINES[case]
    argv = [a.format(**bad_paths) for a in argv]
    assert _exit_code(argv) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert len(err.strip().splitlines()) == 1, err
    assert expected.format(**bad_paths) in err


def test_a_plain_file_without_columns_is_explained(bad_paths, capsys):
    assert _exit_code(["identify", "belt_drive", "--data", bad_paths["file"]]) == 2
    err = capsys.readouterr().err
    assert f"'{bad_paths['file']}' is not a symid CSV file" in err and "Traceback" not in err
    assert "--columns frequency=f magnitude=mag phase=ph --units frequency=Hz" in err  # how to read it instead


def test_version_is_printed(capsys):
    from importlib.metadata import version

    assert _exit_code(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"symid {version('symid')}"


def test_max_iter_is_honoured(tmp_path, capsys):
    # `--max-iter 1` must reach SCR (it was dropped by a truthiness test when 0, and is now checked ≥ 1)
    code = main(["identify", "mass_damper_2dof", "--method", "scr", "--max-iter", "1", "--out", str(tmp_path)])
    assert code in (0, 4)
    result = json.loads((tmp_path / "result.json").read_text())
    assert result["iterations"] == 1 and result["options"]["max_iter"] == 1


def test_internal_error_is_one_line_and_status_3(monkeypatch, capsys):
    import symid.zoo

    def broken(name):
        raise RuntimeError("simulated bug")

    monkeypatch.setattr(symid.zoo, "load_model", broken)
    monkeypatch.delenv("SYMID_TRACEBACK", raising=False)
    assert main(["show", "belt_drive"]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "internal error: RuntimeError: simulated bug" in err


def test_interrupted_identify_writes_the_finished_starts(tmp_path, monkeypatch, capsys):
    from symid.fit.frf import ipopt as nlls_frf

    real = nlls_frf.IpoptFRF.run
    calls = {"n": 0}

    def run(self, x0):
        calls["n"] += 1
        if calls["n"] == 3:
            raise KeyboardInterrupt
        return real(self, x0)

    monkeypatch.setattr(nlls_frf.IpoptFRF, "run", run)
    assert main(["identify", "belt_drive", "--method", "ipopt", "--starts", "5", "--out", str(tmp_path)]) == 130
    captured = capsys.readouterr()
    assert "symid: interrupted (the finished starts are shown above)" in captured.err
    result = json.loads((tmp_path / "result.json").read_text())
    assert len(result["starts"]) == 2 and result["options"]["interrupted"] is True


def test_no_fit_is_exit_status_4_with_the_result_written(tmp_path, capsys):
    """One IPOPT iteration from θ = 0 cannot fit the belt drive: the result is still printed and written."""
    code = main(["identify", "belt_drive", "--method", "ipopt", "--max-iter", "1", "--x0", "theta1=0", "theta2=0",
                 "theta3=0", "theta4=0", "--out", str(tmp_path)])
    captured = capsys.readouterr()
    assert code == 4
    assert "no start fitted the data (exit status 4)" in captured.out
    result = json.loads((tmp_path / "result.json").read_text())
    assert result["success"] is False and result["options"]["max_iter"] == 1


def test_identify_json_for_scripts(capsys):
    code = main(["identify", "mass_damper_2dof", "--method", "ipopt", "--x0", "m1=1", "m2=1", "c1=0.2", "c2=0.2",
                 "k1=1.5", "k2=1.5", "--tol", "1e-10", "--json"])
    captured = capsys.readouterr()
    doc = json.loads(captured.out)  # standard output is the JSON document alone
    assert code == doc["exit_status"] == 0 and doc["fitted"] is True and doc["determined"] is True
    assert doc["result"]["starts"][0]["start"] == [1.0, 1.0, 0.2, 0.2, 1.5, 1.5]
    assert doc["result"]["options"]["tol"] == 1e-10
    assert "method: ipopt" in captured.err  # the human report moved to standard error


def test_a_partial_x0_is_completed_from_the_scale_and_the_bounds(capsys):
    """--x0 k1=3 changes one value (a new user's trial: every parameter had to be listed); the others come from
    the scale, else the centre of their finite bounds."""
    code = main(["identify", "mass_damper_2dof", "--method", "lm", "--known", "m1=1", "m2=1", "--scale", "c1=0.1",
                 "c2=0.3", "k1=2", "k2=1", "--x0", "k1=3", "--json"])
    doc = json.loads(capsys.readouterr().out)
    assert code == 0
    np.testing.assert_allclose(doc["result"]["starts"][0]["start"], [0.1, 0.3, 3.0, 1.0], rtol=1e-15)
    code = main(["identify", "mass_damper_2dof", "--method", "lm", "--known", "m1=1", "m2=1", "--bounds",
                 "c1=0.01:1", "c2=0.01:1", "k1=1:4", "k2=0.25:4", "--x0", "c1=0.2", "--json"])
    doc = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(doc["result"]["starts"][0]["start"], [0.2, 0.1, 2.0, 1.0], rtol=1e-12)


def test_known_scale_bounds_and_options_reach_the_estimator(tmp_path, capsys):
    code = main(["identify", "mass_damper_2dof", "--method", "ipopt", "--known", "m1=1", "m2=1",
                 "--scale", "c1=0.1", "c2=0.3", "k1=2", "k2=1", "--bounds", "k1=0.5:5", "k2=:10",
                 "--time-limit", "60", "--option", "hessian=limited-memory", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0, out
    result = json.loads((tmp_path / "result.json").read_text())
    assert result["parameter_names"] == ["c1", "c2", "k1", "k2"] and result["known"] == {"m1": 1.0, "m2": 1.0}
    assert result["options"]["scale"] == [0.1, 0.3, 2.0, 1.0]
    assert result["options"]["time_limit"] == 60.0
    assert result["options"]["hessian"] == "limited-memory"
    # every free parameter has finite bounds? k2's low end is open, so the method's own first start is used
    assert "centre of the bounds" not in out


BOUNDS = ["--bounds", "m1=0.5:2", "m2=0.5:2", "c1=0.01:1", "c2=0.01:1", "k1=3:10", "k2=0.1:10"]


def test_bounds_give_the_first_start_and_flag_estimates_outside(capsys):
    code = main(["identify", "mass_damper_2dof", "--method", "scr", *BOUNDS, "--json"])  # SCR takes no bounds
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    start = doc["result"]["starts"][0]["start"]
    np.testing.assert_allclose(start, [1.0, 1.0, 0.1, 0.1, np.sqrt(30), 1.0], rtol=1e-12)  # geometric centres
    # SCR's estimate on this exact data is the truth to ~4e-7 (measured 3.6e-7): k1 = 2, below its bound 3
    assert code == 0 and doc["outside_bounds"] == {"k1": pytest.approx(2.0, rel=1e-5)}
    assert "note: method 'scr' does not use the bounds" in captured.err


@pytest.mark.parametrize("method", ["ipopt", "lm", "auto"])
def test_bounds_reach_a_method_that_takes_them(capsys, method):
    code = main(["identify", "mass_damper_2dof", "--method", method, *BOUNDS, "--json"])
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    assert doc["result"]["options"]["bounds"]["k1"] == [3.0, 10.0]  # a dict option is JSON, not its repr
    # held at the bound the truth (k1 = 2, thesis (4-21)) lies below; exit status 4: no start fits the data
    assert code == 4 and doc["outside_bounds"] == {}
    assert doc["result"]["theta"]["k1"] == pytest.approx(3.0, rel=1e-9)
    on = doc["result"]["on_bounds"]  # a field a script can read, beside the message
    assert on["k1"] == "lower" and set(on) <= {"m1", "m2", "c1", "c2", "k1", "k2"}
    assert "NEXT: the estimate sits on its bounds (" in captured.err and "k1 (lower)" in captured.err
    assert "does not use the bounds" not in captured.err
    assert code == NO_FIT  # no fit of these data inside the bounds: said by the exit status


OPTION_ERRORS = {
    "backend on ls": (["identify", "belt_drive", "--method", "ls", "--backend", "admm"],
                      "--backend: not taken by method 'ls'"),
    "backend on ipopt": (["identify", "belt_drive", "--method", "ipopt", "--backend", "admm"],
                         "--backend: not taken by method 'ipopt'"),
    "x0 incomplete": (["identify", "belt_drive", "--x0", "theta1=1"],
                      "x0 lacks theta2, theta3, theta4 and the model file gives no start, scale or finite bounds"),
    "x0 outside bounds": (["identify", "belt_drive", "--x0", "theta1=1", "theta2=1", "theta3=1", "theta4=1",
                           "--bounds", "theta1=-2:0"], "lies outside its bounds"),
    "known not a parameter": (["identify", "belt_drive", "--known", "mass=1"], "'mass', not a parameter"),
    "bounds syntax": (["identify", "belt_drive", "--bounds", "theta1=1"], "--bounds expects NAME=LOW:HIGH"),
    "tol negative": (["identify", "belt_drive", "--tol", "-1"], "--tol: must be a finite number > 0"),
    "option for a flag": (["identify", "belt_drive", "--option", "scale=2"], "use the flag --scale instead"),
    "unknown option": (["identify", "belt_drive", "--option", "gamma0=model"], "has no option 'gamma0'"),
}


@pytest.mark.parametrize("case", sorted(OPTION_ERRORS))
def test_options_a_method_does_not_take_are_named(case, capsys):
    argv, expected = OPTION_ERRORS[case]
    assert _exit_code(argv) == 2
    err = capsys.readouterr().err
    assert expected in err and "Traceback" not in err


def test_other_commands_speak_json(capsys):
    for argv in (["models", "--json"], ["show", "belt_drive", "--json"],
                 ["identifiability", "belt_drive", "--json"],
                 ["compare", "belt_drive", "--methods", "scr", "--starts", "2", "--json"]):
        assert main(argv) == 0
        json.loads(capsys.readouterr().out)  # a valid document, nothing else on standard output


def test_warnings_read_as_the_commands_words(capsys):
    """Not `/…/symid/cli.py:304: IdentifiabilityWarning: … return identify(…)` (a new user's report)."""
    main(["identify", "compartment_catenary", "--method", "lm"])
    err = capsys.readouterr().err
    assert "symid: warning (IdentifiabilityWarning): parameter(s) theta1, theta2, theta3, theta4 are not" in err
    assert "cli.py" not in err and "return identify(" not in err


def test_a_long_estimate_is_seen_to_be_alive(capsys):
    """A new user's 4000-sample record: 41 s of default fit with nothing on the screen."""
    import time

    from symid.progress import Heartbeat

    with Heartbeat("auto, 1 start", after=0.05, every=0.1):
        time.sleep(0.4)
    lines = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("symid: still estimating")]
    assert 2 <= len(lines) <= 5 and "(auto, 1 start)" in lines[0]  # at 0.05 s, then every 0.1 s until 0.4 s
    with Heartbeat("auto, 1 start", after=10.0):  # a run shorter than `after` says nothing
        pass
    assert "still estimating" not in capsys.readouterr().err


def _strict(text):
    """json.loads that refuses NaN and Infinity, as jq or a JavaScript reader would."""
    def refuse(name):
        raise ValueError(f"non-standard JSON constant {name}")
    return json.loads(text, parse_constant=refuse)


def test_json_output_is_standard_json(capsys):
    """An open bound (k1 = 0.5: has no upper side, inf) and infinite values anywhere in the
    result are written as null, as result.json does, so that any JSON reader (jq, JavaScript) takes the --json
    output; json.dumps alone writes Infinity, which they refuse."""
    code = main(["identify", "mass_damper_2dof", "--method", "lm", "--known", "m1=1", "m2=1", "--bounds",
                 "k1=0.5:", "--json"])
    doc = _strict(capsys.readouterr().out)
    assert code == 0 and doc["result"]["options"]["bounds"]["k1"] == [0.5, None]  # an open upper side: null
    assert main(["identifiability", "mass_damper_2dof", "--json"]) == 0
    _strict(capsys.readouterr().out)


def test_an_error_model_reaches_a_time_series_fit(tmp_path, capsys):
    """--option 'variance={"proportional": …, "additive": …}': the combined error model of a concentration
    record, read from the user's own CSV (an infusion stopping between samples, the stop a row with no output)."""
    (tmp_path / "pk.py").write_text(
        "import symid as si\n"
        "k, q = si.parameters('k q', positive=True)\n"
        "model = si.StateSpaceModel(A=[[-k]], B=[[1]], C=[[q]])\n"
        "start = {'k': 0.5, 'q': 0.1}\n")
    k, q = si.parameters("k q", positive=True)
    t = np.array([0.0, 0.5, 0.75, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0])
    u = np.where(t < 0.75, 100.0, 0.0)
    y = si.simulate_io(si.StateSpaceModel(A=[[-k]], B=[[1]], C=[[q]]), {"k": 0.3, "q": 0.05},
                       np.where(np.arange(0, 12.0001, 0.25) < 0.75, 100.0, 0.0), 0.25).y[(t / 0.25).astype(int), 0]
    rows = "\n".join(f"{a},{b},{'' if a == 0.75 else repr(float(c))}" for a, b, c in zip(t, u, y, strict=True))
    (tmp_path / "pk.csv").write_text(f"# units: t [h], dose [mg/h], conc [mg/L]\nt,dose,conc\n{rows}\n")
    code = main(["identify", str(tmp_path / "pk.py"), "--data", str(tmp_path / "pk.csv"), "--columns", "time=t",
                 "input=dose", "output=conc", "--units", "time=h", "--time-unit", "h", "--kind", "TimeSeries",
                 "--option", 'variance={"proportional": 0.02, "additive": 0.01}', "--json"])
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    assert code == 0 and doc["result"]["cost_kind"].startswith("weighted relative output misfit")
    assert doc["time_unit"] == "h"
    assert ("time unit: h, the record's and the estimates' (rates per h; the model file states no time_unit, so "
            "its values (start) are taken per h)") in captured.err
    main(["identify", str(tmp_path / "pk.py"), "--data", str(tmp_path / "pk.csv"), "--columns", "time=t",
          "input=dose", "output=conc", "--units", "time=h", "--time-unit", "h", "--kind", "TimeSeries",
          "--out", str(tmp_path / "out")])
    written = json.loads((tmp_path / "out" / "result.json").read_text())
    assert written["time_unit"] == "h" and written["data"] == str(tmp_path / "pk.csv")
    assert "time unit: h\n" in (tmp_path / "out" / "summary.txt").read_text()
    assert doc["result"]["options"]["variance"] == {"proportional": 0.02, "additive": 0.01, "weights": "prediction"}
    np.testing.assert_allclose([doc["result"]["theta"]["k"], doc["result"]["theta"]["q"]], [0.3, 0.05], rtol=1e-6)


def test_a_model_files_time_unit_is_the_records(tmp_path, capsys):
    """A new user's stirred tank with rates per minute in the model file, fitted on a log in seconds: every rate
    came out 60 times off with success=True, and `time_unit = "min"` in the file was passed over in silence. The
    file's time_unit is now the unit the table's times are read into (reference: the rates the record was
    simulated with, per minute; exact data, so the fit recovers them to its tolerance), and a record read in
    another unit (--time-unit s) is warned about."""
    (tmp_path / "tank.py").write_text(
        "import symid as si\n"
        "a, b = si.parameters('a b', positive=True)\n"
        "model = si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[1]])\n"
        "start = {'a': 0.3, 'b': 1.0}\n"
        "time_unit = 'min'\n")
    a, b = si.parameters("a b", positive=True)
    u = np.where(np.arange(240) % 80 < 40, 1.0, -1.0)
    io = si.simulate_io(si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[1]]), {"a": 0.6, "b": 1.8}, u, 5.0 / 60.0)
    rows = "\n".join(f"{5.0 * i},{u[i]},{float(io.y[i, 0])!r}" for i in range(240))
    (tmp_path / "log.csv").write_text(f"t,u,y\n{rows}\n")
    args = ["identify", str(tmp_path / "tank.py"), "--data", str(tmp_path / "log.csv"), "--columns", "time=t",
            "input=u", "output=y", "--units", "time=s"]
    assert main([*args, "--json"]) == 0
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    assert doc["time_unit"] == "min" and "the file's times, in s, were converted to the model file's time_unit, " \
        "min" in captured.err
    np.testing.assert_allclose([doc["result"]["theta"]["a"], doc["result"]["theta"]["b"]], [0.6, 1.8], rtol=1e-6)
    main([*args, "--time-unit", "h", "--max-iter", "1"])
    said = capsys.readouterr()
    assert "the model file's time unit is min (its rates are per min), but the record's is h" in said.err
    assert "the file's times, in s, were converted to h, as --time-unit asks" in said.out


def test_time_unit_on_a_frequency_response_is_said_to_play_no_part(tmp_path, capsys):
    """A new user's `--time-unit min` on a frequency-response table was ignored without a word (the estimates per
    second): it is now said."""
    frf = si.simulate_frf(si.load_model("mass_damper_2dof").model, si.load_model("mass_damper_2dof").truth,
                          np.linspace(0.2, 3.0, 30))
    H = np.asarray(frf.H)[:, 0, 0]
    rows = "\n".join(f"{w!r},{h.real!r},{h.imag!r}" for w, h in zip(frf.w.tolist(), H.tolist(), strict=True))
    (tmp_path / "frf.csv").write_text(f"w,re,im\n{rows}\n")
    main(["identify", "mass_damper_2dof", "--data", str(tmp_path / "frf.csv"), "--columns", "frequency=w", "real=re",
          "imag=im", "--units", "frequency=rad/s", "--time-unit", "min", "--max-iter", "1"])
    assert "--time-unit min sets the time unit of a time-series record; these data are no time series" \
        in capsys.readouterr().err


def _infusion_files(tmp_path, records: dict[str, int]) -> None:
    """pk.py (one compartment, elimination ke, q = 1/V) and, per file name and noise seed, 48 h of two 500 mg/h
    infusions sampled every 15 min with 15 % proportional noise on the concentration (ke = 0.2, q = 0.025)."""
    (tmp_path / "pk.py").write_text(
        "import symid as si\n"
        "ke, q = si.parameters('ke q', positive=True)\n"
        "model = si.StateSpaceModel(A=[[-ke]], B=[[q]], C=[[1]])\n"
        "start = {'ke': 0.3, 'q': 0.05}\n")
    ke, q = si.parameters("ke q", positive=True)
    t = np.arange(0, 48.125, 0.25)
    u = np.where(t < 2, 500.0, 0.0) + np.where((t >= 12) & (t < 13), 500.0, 0.0)
    y0 = si.simulate_io(si.StateSpaceModel(A=[[-ke]], B=[[q]], C=[[1]]), {"ke": 0.2, "q": 0.025}, u, 0.25).y[:, 0]
    for name, seed in records.items():
        y = y0 * (1 + 0.15 * np.random.default_rng(seed).standard_normal(t.size))
        np.savetxt(tmp_path / name, np.column_stack([t, u, y]), delimiter=",", header="t,rate,conc", comments="")


def test_the_validation_of_identify_uses_the_fits_error_model(tmp_path, capsys):
    """A one-compartment infusion record with 15 % proportional noise (193 samples): `symid identify` with the
    error model validates with it too, the residual tests on (y − ŷ)/σ (without it the true model's residual
    tests as coloured: si.validate's test in tests/test_validation.py)."""
    _infusion_files(tmp_path, {"pk.csv": 2001})
    main(["identify", str(tmp_path / "pk.py"), "--data", str(tmp_path / "pk.csv"), "--columns", "time=t",
          "input=rate", "output=conc", "--units", "time=h", "--time-unit", "h",
          "--option", 'variance={"proportional": 0.15}'])
    said = capsys.readouterr().out
    assert "residual tests on (y − ŷ)/σ, σ from the given variance (an error model" in said
    assert "verdict: residual white and independent of the " in said


def test_identify_validates_on_other_records_with_validate(tmp_path, capsys):
    """A new user's trial: the command line could validate only on the records fitted. --validate FILE reads other
    records as --data was read and validates the estimate there: the true structure passes on a second record
    (the infusion model, 15 % proportional noise, its error model), a wrong one (elimination fixed at half the
    truth) fails; a frequency response is refused by name."""
    _infusion_files(tmp_path, {"a.csv": 2001, "b.csv": 2002})
    args = ["--data", str(tmp_path / "a.csv"), "--validate", str(tmp_path / "b.csv"), "--columns", "time=t",
            "input=rate", "output=conc", "--units", "time=h", "--time-unit", "h",
            "--option", 'variance={"proportional": 0.15}']
    main(["identify", str(tmp_path / "pk.py"), *args])
    said = capsys.readouterr().out
    assert f"validation on {tmp_path / 'b.csv'} (not the records fitted)" in said
    assert "verdict: residual white and independent of the " in said
    main(["identify", str(tmp_path / "pk.py"), *args, "--known", "ke=0.1"])
    said = capsys.readouterr().out
    assert "verdict: residual NOT white" in said or "residual correlated with past inputs" in said
    code = main(["identify", "mass_damper_2dof", "--validate", str(tmp_path / "b.csv")])
    assert code == 2 and "--validate checks an estimate on other time-series records" in capsys.readouterr().err


def test_times_converted_to_seconds_are_said(tmp_path, capsys):
    """A file in hours read without --time-unit: the record, and so every rate, is per second. Said, with the flag
    that keeps hours (a new user's trial: rates 3600 times smaller, with nothing said)."""
    (tmp_path / "io.csv").write_text("t_h,u,y\n" + "\n".join(f"{0.5 * i},{1.0 if i < 3 else 0.0},{0.1 * i}"
                                                              for i in range(20)) + "\n")
    main(["identify", "mass_damper_2dof", "--data", str(tmp_path / "io.csv"), "--columns", "time=t_h", "input=u",
          "output=y", "--units", "time=h", "--max-iter", "1"])
    captured = capsys.readouterr()
    err = captured.out + captured.err
    assert "time unit: s, the record's and the estimates' (rates per s) (the file's times, in h, were converted; " \
           "--time-unit h keeps them)" in err


def test_an_input_unit_the_file_states_against_the_model_files_is_said(tmp_path, capsys):
    """# units: dose [ug/h] read for a model file whose input unit is mg/h: symid converts neither, so the gain
    comes out 1000 times off (a new user's trial: said nowhere). A warning names both; the same units say nothing."""
    (tmp_path / "pk.py").write_text(
        "import symid as si\n"
        "k, q = si.parameters('k q', positive=True)\n"
        "model = si.StateSpaceModel(A=[[-k]], B=[[1]], C=[[q]])\n"
        "start = {'k': 0.5, 'q': 0.1}\n"
        "input_units, output_units = 'mg/h', 'mg/L'\n")
    rows = "\n".join(f"{0.5 * i},{100.0 if i < 2 else 0.0},{0.01 * i}" for i in range(12))
    args = ["--columns", "time=t", "input=dose", "output=conc", "--units", "time=h", "--time-unit", "h",
            "--max-iter", "1"]
    for unit, warned in (("ug/h", True), ("mg / h", False)):
        (tmp_path / "pk.csv").write_text(f"# units: t [h], dose [{unit}], conc [mg/L]\nt,dose,conc\n{rows}\n")
        main(["identify", str(tmp_path / "pk.py"), "--data", str(tmp_path / "pk.csv"), *args])
        err = capsys.readouterr().err
        assert ("the file states ug/h for input 'dose'; the model file's input unit is mg/h" in err) == warned


def test_identify_prints_the_estimates_modes(capsys):
    """A frequency axis in Hz read as rad/s moves every mode by 2π, which a person sees at once in Hz (a new
    user's trial asked for it): the modes of the estimate, natural frequency and damping ratio. Reference: the
    eigenvalues of the thesis's 2-DOF mass-damper at its truth (4-20), computed here."""
    entry = si.load_model("mass_damper_2dof")
    assert main(["identify", "mass_damper_2dof", "--method", "ipopt"]) in (0, 4)
    out = capsys.readouterr().out
    assert out.count("modes of the estimate: ") == 1
    line = next(x for x in out.splitlines() if x.startswith("modes of the estimate: "))
    poles = np.linalg.eigvals(entry.model.state_space(entry.truth)[0])
    wn = sorted(abs(p) for p in poles if p.imag > 0)
    hz = [float(x.split(" Hz")[0]) for x in line.removeprefix("modes of the estimate: ").split("; ")]
    np.testing.assert_allclose(hz, np.array(wn) / (2 * np.pi), rtol=1e-3)  # printed to 4 digits


def test_the_python_summary_holds_the_modes_once():
    """The command line printed the modes, the Python result held them nowhere (a new user's servo): they are in
    options["modes"] and summary(), and the command line prints them once. Reference: as above."""
    entry = si.load_model("mass_damper_2dof")
    res = si.identify(entry.model, entry.data(), method="ipopt", identifiability_check=False)
    assert res.options["modes"].startswith("modes of the estimate: ")
    assert res.summary().count("modes of the estimate: ") == 1
    poles = np.linalg.eigvals(entry.model.state_space(entry.truth)[0])
    hz = [float(x.split(" Hz")[0]) for x in res.options["modes"].removeprefix("modes of the estimate: ").split("; ")]
    np.testing.assert_allclose(hz, np.sort([abs(p) for p in poles if p.imag > 0]) / (2 * np.pi), rtol=1e-3)


def test_a_mimo_frequency_response_gets_a_bode_figure_per_entry(tmp_path, capsys):
    """Two sensors, one force (a new user's trial: bode.png showed output 0 alone): bode_0_0.png and bode_1_0.png."""
    (tmp_path / "two.py").write_text(
        "import symid as si\n"
        "m1, m2, c1, c2, k1, k2 = si.parameters('m1 m2 c1 c2 k1 k2', positive=True)\n"
        "model = si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],\n"
        "                            K=[[k1 + k2, -k2], [-k2, k2]], B=[[0], [1]], C=[[1, 0], [0, 1]])\n"
        "start = {'m1': 1.5, 'm2': 1.5, 'c1': 0.3, 'c2': 0.3, 'k1': 3.0, 'k2': 1.5}\n")
    model = si.load_model(tmp_path / "two.py").model
    truth = {"m1": 1, "m2": 1, "c1": 0.2, "c2": 0.2, "k1": 2, "k2": 1}
    si.simulate_frf(model, truth, np.linspace(0.3, 3, 60)).to_csv(tmp_path / "frf.csv")
    assert main(["identify", str(tmp_path / "two.py"), "--data", str(tmp_path / "frf.csv"), "--out",
                 str(tmp_path / "out")]) == 0
    for name in ("bode_0_0.png", "bode_1_0.png"):
        assert (tmp_path / "out" / name).stat().st_size > 1000
    assert not (tmp_path / "out" / "bode.png").exists()


def test_the_modes_line_groups_poles_at_zero():
    """A new user's room (K = 0, temperatures as velocities) listed "real pole 0 /s" once per node, then "2 poles at
    0"; another user's LC ladder in the same form read "5 poles at 0", which are no poles of its response (the
    positions' integrators, which a velocity output does not see): the line lists the first-order system's own
    poles (reference: the eigenvalues of A, computed here, less its two at 0)."""
    from symid.fit.modes import modes_line

    Ca, Cw, Haw, Hwo = si.parameters("Ca Cw Haw Hwo", positive=True)
    model = si.SecondOrderModel(M=[[Ca, 0], [0, Cw]], V=[[Haw, -Haw], [-Haw, Haw + Hwo]], K=[[0, 0], [0, 0]],
                                B=[[1], [0]], C=[[1, 0]], output="velocity")
    theta = [5e5, 8e6, 300.0, 80.0]
    line = modes_line(model, theta, "s")
    poles = sorted(np.linalg.eigvals(np.asarray(model.state_space(theta)[0], float)).real, key=abs)[2:]
    assert line == ("modes of the estimate: " + "; ".join(f"real pole {p:.4g} /s" for p in poles))


def test_a_model_file_can_say_the_records_do_not_start_at_rest(tmp_path, capsys):
    """A new user's trial: a second-order model file could not declare the estimated initial state, so every call
    needed --option initial_state=estimate. `initial_state = "estimate"` in the file now does it (time series);
    a frequency response's method, which takes none, is told so and runs; a bad value is named."""
    (tmp_path / "room.py").write_text(
        "import symid as si\n"
        "Ca, Cw, Haw, Hwo = si.parameters('Ca Cw Haw Hwo', positive=True)\n"
        "model = si.SecondOrderModel(M=[[Ca, 0], [0, Cw]], V=[[Haw, -Haw], [-Haw, Haw + Hwo]], K=[[0, 0], [0, 0]],\n"
        "                            B=[[1], [0]], C=[[1, 0]], output='velocity')\n"
        "start = {'Ca': 4e5, 'Cw': 9e6, 'Haw': 250.0, 'Hwo': 100.0}\n"
        "initial_state = 'estimate'\n")
    spec = si.load_model(str(tmp_path / "room.py"))
    assert spec.initial_state == "estimate" and "initial state: estimate" in spec.summary()
    truth = {"Ca": 5e5, "Cw": 8e6, "Haw": 300.0, "Hwo": 80.0}
    u = np.where((np.arange(2000) // 97) % 2 == 0, 2000.0, 0.0)
    io = si.simulate_io(spec.model, truth, u, 60.0, x0=[0.0, 0.0, 18.0, 17.5], noise_std=0.05, seed=3)
    rows = "\n".join(f"{60.0 * k},{a!r},{b!r}" for k, (a, b) in enumerate(zip(io.u[:, 0].tolist(),
                                                                              io.y[:, 0].tolist(), strict=True)))
    (tmp_path / "rec.csv").write_text(f"t,P,Ta\n{rows}\n")
    code = main(["identify", str(tmp_path / "room.py"), "--data", str(tmp_path / "rec.csv"), "--columns", "time=t",
                 "input=P", "output=Ta", "--units", "time=s", "--json"])
    doc = json.loads(capsys.readouterr().out)
    assert code == 0 and doc["result"]["options"]["initial_state"] == "estimate"
    np.testing.assert_allclose([doc["result"]["theta"][n] for n in truth], list(truth.values()), rtol=0.05)
    frf = si.simulate_frf(spec.model, truth, np.logspace(-5, -2, 30))
    frf.to_csv(tmp_path / "frf.csv")
    assert main(["identify", str(tmp_path / "room.py"), "--data", str(tmp_path / "frf.csv")]) in (0, 4)
    assert "does not use the model file's initial_state" in capsys.readouterr().out
    (tmp_path / "bad.py").write_text((tmp_path / "room.py").read_text().replace("'estimate'", "'guess'"))
    with pytest.raises(si.ModelError, match=r"initial_state is 'estimate' .* or 'zero'; got 'guess'"):
        si.load_model(str(tmp_path / "bad.py"))


def test_compare_takes_the_method_options_and_a_noise_floor(tmp_path, capsys):
    """A new user's trial: `symid compare` took no noise floor, time limit, scale or bounds (``--option`` was
    "unrecognized"), so 15 % noise failed every method. Each option goes to the methods that take it; one that no
    method compared takes is an error naming the flag; ``--option noise_floor=`` judges every method's fit."""
    _infusion_files(tmp_path, {"pk.csv": 2001})
    data = ["--data", str(tmp_path / "pk.csv"), "--columns", "time=t", "input=rate", "output=conc", "--units",
            "time=h", "--time-unit", "h", "--starts", "1"]
    assert main(["compare", str(tmp_path / "pk.py"), *data, "--methods", "auto,oe", "--json"]) == 0
    plain = json.loads(capsys.readouterr().out)
    assert [s["n_success"] for s in plain["methods"]] == [0, 0]  # 15 % noise: a misfit beyond 1e-2 fails, unjudged
    assert main(["compare", str(tmp_path / "pk.py"), *data, "--methods", "auto,oe,svf", "--time-limit", "30",
                 "--tol", "1e-12", "--option", "noise_floor=0.03", "--json"]) == 0
    captured = capsys.readouterr()
    judged = json.loads(captured.out)
    assert [s["n_success"] for s in judged["methods"][:2]] == [1, 1]  # (svf: an estimate biased by the noise)
    assert "note: --tol goes to auto, oe (the others do not take it)" in captured.err  # svf has no tol
    assert main(["compare", str(tmp_path / "pk.py"), *data, "--methods", "auto,oe", "--backend", "cvxpy"]) == 2
    assert "--backend: none of the methods compared (auto, oe) takes backend" in capsys.readouterr().err


def test_a_warning_is_said_once_per_command(tmp_path, capsys, motor):
    """A new user's trial: each DataWarning printed twice, by the fit and by its validation on the same record."""
    rows = motor[1](300)
    (tmp_path / "rec.csv").write_text(f"# units: t [s], tau [N m], w [deg/s]\nt,tau,w\n{rows}\n")
    main(["identify", str(motor[0]), "--data", str(tmp_path / "rec.csv"), "--columns", "time=t",
          "input=tau", "output=w", "--units", "time=s"])
    err = capsys.readouterr().err
    assert err.count("the file states deg/s for output 'w'") == 1, err


def test_validate_reads_files_with_their_own_columns_and_units(tmp_path, capsys):
    """A new user's trial: the validation log had its time in minutes under another name, and --validate read it
    with the fitting file's --columns and --units only ("no column named 't'"). --validate-columns and
    --validate-units describe those files; their times are converted to the model's time unit as --data's are."""
    _infusion_files(tmp_path, {"a.csv": 2001, "b.csv": 2002})
    b = np.loadtxt(tmp_path / "b.csv", delimiter=",", skiprows=1)
    b[:, 0] *= 60.0  # hours → minutes
    np.savetxt(tmp_path / "b_min.csv", b, delimiter=",", header="t_min,rate,conc", comments="")
    args = ["--data", str(tmp_path / "a.csv"), "--columns", "time=t", "input=rate", "output=conc", "--units",
            "time=h", "--time-unit", "h", "--option", 'variance={"proportional": 0.15}',
            "--validate", str(tmp_path / "b_min.csv")]
    assert main(["identify", str(tmp_path / "pk.py"), *args]) == 2
    assert "no column named 't'" in capsys.readouterr().err
    main(["identify", str(tmp_path / "pk.py"), *args, "--validate-columns", "time=t_min", "input=rate",
          "output=conc", "--validate-units", "time=min"])
    said = capsys.readouterr().out
    assert f"validation on {tmp_path / 'b_min.csv'} (not the records fitted)" in said
    assert "verdict: residual white and independent of the " in said
    assert main(["identify", str(tmp_path / "pk.py"), *args[:-2], "--validate-units", "time=min"]) == 2
    assert "give --validate FILE too" in capsys.readouterr().err


def test_compare_leaves_out_a_method_that_refuses_and_keeps_the_others(tmp_path, capsys):
    """A new user's trial: scr refused the data (an unstable black box) and `symid compare` gave no table at all;
    now that method is left out with its reason and the others run. Every method refusing is an error. (Here scr
    refuses an acceleration output, thesis §7-7-3.)"""
    (tmp_path / "mass.py").write_text(
        "import symid as si\n"
        "m, c, k = si.parameters('m c k', positive=True)\n"
        "model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]], output='acceleration')\n"
        "start = {'m': 1.5, 'c': 1.0, 'k': 40.0}\n")
    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]], output="acceleration")
    io = si.simulate_io(model, {"m": 2.0, "c": 0.8, "k": 50.0}, np.random.default_rng(0).standard_normal(400), 0.05)
    np.savetxt(tmp_path / "rec.csv", np.column_stack([io.t, io.u[:, 0], io.y[:, 0]]), delimiter=",",
               header="t,f,a", comments="")
    data = ["--data", str(tmp_path / "rec.csv"), "--columns", "time=t", "input=f", "output=a", "--units", "time=s",
            "--starts", "1"]
    assert main(["compare", str(tmp_path / "mass.py"), *data, "--methods", "oe,scr"]) == 0
    said = capsys.readouterr().out
    assert "note: left out, scr:" in said and "    oe        1/1" in said
    assert main(["compare", str(tmp_path / "mass.py"), *data, "--methods", "scr"]) == 2
    assert "every method refused the model or data" in capsys.readouterr().err


def test_the_modes_line_shows_one_rigid_body_pole_as_zero():
    """A new user's drivetrain (nothing to the ground but a bearing's friction) read "real pole 1.359e-11 /s",
    positive, as if unstable: a single pole at 0 to rounding is "1 pole at 0"."""
    from symid.fit.modes import modes_line

    m, c = si.parameters("m c", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[0]], B=[[1]], C=[[1]])
    assert modes_line(model, [2.0, 3.0], "s") == "modes of the estimate: 1 pole at 0; real pole -1.5 /s"


def test_identifiability_at_your_own_values(tmp_path, capsys):
    """--at NAME=VALUE (or --at start, the model file's start) lists the other solutions at those values (an oral
    dose's flip-flop: ka and ke swap, reference 1.2 · 0.025 = 0.15 · 0.2); a file without a start is named."""
    (tmp_path / "oral.py").write_text(
        "import symid as si\n"
        "ka, ke, q = si.parameters('ka ke q', positive=True)\n"
        "model = si.StateSpaceModel(A=[[-ka, 0], [ka, -ke]], B=[[1], [0]], C=[[0, q]])\n"
        "start = {'ka': 1.2, 'ke': 0.15, 'q': 0.025}\n")
    path = str(tmp_path / "oral.py")
    assert main(["identifiability", path, "--at", "ka=1.2", "ke=0.15", "q=0.025"]) == 0
    out = capsys.readouterr().out
    assert "1 other admissible set(s) of values" in out and "1: ka = 0.15, ke = 1.2, q = 0.2" in out
    assert main(["identifiability", path, "--at", "start"]) == 0
    assert "1: ka = 0.15, ke = 1.2, q = 0.2" in capsys.readouterr().out
    (tmp_path / "bare.py").write_text(
        "import symid as si\n"
        "ka, ke, q = si.parameters('ka ke q', positive=True)\n"
        "model = si.StateSpaceModel(A=[[-ka, 0], [ka, -ke]], B=[[1], [0]], C=[[0, q]])\n")
    assert main(["identifiability", str(tmp_path / "bare.py"), "--at", "start"]) == 2
    assert "the model file gives no start" in capsys.readouterr().err


def test_kelvin_against_celsius_is_said_to_be_an_offset():
    """A new user's temperatures logged in K beside a model file in °C were told "a factor between them goes into the
    estimates": K against °C is an offset. Other units are still a factor."""
    from symid.fit.identify import unit_mismatches

    k, g = si.parameters("k g", positive=True)
    model = si.StateSpaceModel(A=[[-k]], B=[[g]], C=[[1]])
    model.io_units = {"input": ("W",), "output": ("°C",)}
    io = si.IOData([[1.0], [0.0], [0.0]], [[290.0], [291.0], [290.5]], 0.1)
    object.__setattr__(io, "stated_units", {"input": (("P", "kW"),), "output": (("Ti", "K"),)})
    said = unit_mismatches(model, io)
    assert any("Ti" in s and "an offset between them" in s for s in said)
    assert any("'P'" in s and "a factor between them" in s for s in said)


def test_output_only_records_are_fitted_from_the_command_line(tmp_path, capsys):
    """Two new users' output-only records (a footbridge, a 4-storey frame) could not be fitted from the command line
    ("no input column declared"): --phi-uu gives the white input's intensity, and the records' spectra are estimated
    (Welch) and fitted. Reference: an oscillator m = 2, c = 0.8, k = 200 under a white force of intensity 0.5,
    simulated by si.simulate_io (samples of variance 0.5/dt), 20 minutes, position measured: m and k within 3 %, the
    damper within 10 % (5 lines across the mode's half-power bandwidth: the window's smoothing adds a few %)."""
    import json

    import numpy as np

    (tmp_path / "osc.py").write_text("import symid as si\nm, c, k = si.parameters('m c k', positive=True)\n"
                                     "model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])\n"
                                     "start = {'m': 1.0, 'c': 1.0, 'k': 100.0}\n", encoding="utf-8")
    dt, n = 0.01, 120_000
    force = np.random.default_rng(0).standard_normal(n) * np.sqrt(0.5 / dt)
    y = si.simulate_io(si.load_model(str(tmp_path / "osc.py")).model, {"m": 2.0, "c": 0.8, "k": 200.0}, force,
                       dt).y[:, 0]
    np.savetxt(tmp_path / "y.csv", np.column_stack([np.arange(n) * dt, y]), delimiter=",", header="t,x",
               comments="")
    code = main(["identify", str(tmp_path / "osc.py"), "--data", str(tmp_path / "y.csv"), "--columns", "time=t",
                 "output=x", "--units", "time=s", "--phi-uu", "0.5", "--nperseg", "8192", "--band", "3:30", "--json"])
    doc = json.loads(capsys.readouterr().out)
    assert code == doc["exit_status"] == 0 and doc["fitted"] is True
    theta = doc["result"]["theta"]
    np.testing.assert_allclose([theta["m"], theta["k"]], [2.0, 200.0], rtol=0.03)
    np.testing.assert_allclose(theta["c"], 0.8, rtol=0.10)
    assert main(["identify", str(tmp_path / "osc.py"), "--data", str(tmp_path / "y.csv"), "--columns", "time=t",
                 "output=x", "--units", "time=s", "--band", "3:30"]) == 2
    assert "give --phi-uu too" in capsys.readouterr().err
