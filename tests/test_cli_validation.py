"""`symid identify --data FILE.csv` on a time series writes the validation (issue 15, item 4)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import symid as si
from symid.cli import main

MODEL = '''import symid as si

k, g = si.parameters("k g", positive=True)
model = si.StateSpaceModel(A=[[-k]], B=[[g]], C=[[1]])
input_units, output_units = "V", "m"
'''


def test_identify_on_a_time_series_writes_the_validation(tmp_path, capsys):
    (tmp_path / "first_order.py").write_text(MODEL)
    k, g = si.parameters("k g", positive=True)
    model = si.StateSpaceModel(A=[[-k]], B=[[g]], C=[[1]])
    u = np.random.default_rng(0).standard_normal(400)
    si.simulate_io(model, {"k": 0.5, "g": 2.0}, u, dt=0.1, noise=0.05, seed=1).to_csv(tmp_path / "rec.csv")
    out = tmp_path / "out"
    code = main(["identify", str(tmp_path / "first_order.py"), "--data", str(tmp_path / "rec.csv"),
                 "--method", "oe", "--out", str(out)])
    assert code == 0
    text = capsys.readouterr().out
    assert "fit %" in text and "whiteness" in text
    doc = json.loads((out / "validation.json").read_text())
    assert 94 < doc["fit_percent"][0] < 97  # 5 % noise of std(y): about 95 %
    assert doc["white"] == [True] and doc["samples"] == 400
    for name in ("validation.txt", "validation_output.png", "validation_residual.png"):
        assert (out / name).stat().st_size > 0


def test_the_validation_plot_names_the_table_columns(tmp_path, monkeypatch):
    """A table read with --columns: the validation plot's axes name its output and input columns (not "output 0"),
    with the model file's units."""
    from symid.fit.validation import Validation

    (tmp_path / "first_order.py").write_text(MODEL)
    k, g = si.parameters("k g", positive=True)
    model = si.StateSpaceModel(A=[[-k]], B=[[g]], C=[[1]])
    u = np.random.default_rng(0).standard_normal(200)
    rec = si.simulate_io(model, {"k": 0.5, "g": 2.0}, u, dt=0.1, noise=0.05, seed=1)
    rows = zip(rec.t, rec.u[:, 0], rec.y[:, 0], strict=True)
    lines = ["time,voltage,position"] + [f"{t:.17g},{a:.17g},{b:.17g}" for t, a, b in rows]
    (tmp_path / "rec.csv").write_text("\n".join(lines) + "\n")
    seen = {}
    original = Validation.plot

    def spy(self, path, **kwargs):
        seen.update(kwargs)
        return original(self, path, **kwargs)

    monkeypatch.setattr(Validation, "plot", spy)
    code = main(["identify", str(tmp_path / "first_order.py"), "--data", str(tmp_path / "rec.csv"), "--columns",
                 "time=time", "input=voltage", "output=position", "--units", "time=s", "--method", "oe",
                 "--out", str(tmp_path / "out")])
    assert code == 0
    assert seen["output_names"] == ["position"] and seen["input_names"] == ["voltage"]
    assert seen["output_units"] == ["m"]
    text = (tmp_path / "out" / "validation.txt").read_text()  # the table too names them, not "output 0"
    rows = text.splitlines()
    assert rows[2].split()[0] == "position" and rows[4].split()[:2] == ["position", "voltage"]


def test_repeated_flags_are_merged_and_repeated_data_are_several_records(tmp_path, capsys):
    """A flag given twice is not the last one alone (a new user's trial: --known b=… --known k=… kept k only,
    and the second --bounds dropped the first): the items are merged, a name given twice is an error; --data given
    twice fits both time-series records together."""
    (tmp_path / "first_order.py").write_text(MODEL)
    k, g = si.parameters("k g", positive=True)
    model = si.StateSpaceModel(A=[[-k]], B=[[g]], C=[[1]])
    for seed in (0, 1):
        u = np.random.default_rng(seed).standard_normal(300)
        si.simulate_io(model, {"k": 0.5, "g": 2.0}, u, dt=0.1, noise=0.02, seed=seed + 5).to_csv(
            tmp_path / f"rec{seed}.csv")
    files = ["--data", str(tmp_path / "rec0.csv"), "--data", str(tmp_path / "rec1.csv")]
    code = main(["identify", str(tmp_path / "first_order.py"), *files, "--method", "oe", "--x0", "k=1",
                 "--x0", "g=1", "--bounds", "k=0.1:5", "--bounds", "g=0.5:", "--json"])
    doc = json.loads(capsys.readouterr().out)
    assert code == 0 and doc["result"]["options"]["records"] == 2
    assert doc["data"] == [str(tmp_path / "rec0.csv"), str(tmp_path / "rec1.csv")]
    assert doc["result"]["options"]["bounds"] == {"k": [0.1, 5.0], "g": [0.5, None]}
    assert doc["result"]["starts"][0]["start"] == [1.0, 1.0]
    np.testing.assert_allclose([doc["result"]["theta"]["k"], doc["result"]["theta"]["g"]], [0.5, 2.0], rtol=0.02)
    assert main(["identify", str(tmp_path / "first_order.py"), *files, "--method", "oe", "--known", "g=2",
                 "--known", "g=3"]) == 2
    assert "--known gives 'g' twice" in capsys.readouterr().err
    code = main(["identify", str(tmp_path / "first_order.py"), *files, "--method", "oe", "--known", "g=2",
                 "--x0", "k=1", "--json"])
    doc = json.loads(capsys.readouterr().out)
    assert code == 0 and doc["known"] == {"g": 2.0} and list(doc["result"]["theta"]) == ["k"]


def test_repeated_data_of_another_kind_is_refused(tmp_path, capsys):
    """Only time-series records are fitted together: two frequency responses are a usage error naming the file."""
    si.load_model("belt_drive").data().to_csv(tmp_path / "frf.csv")
    si.load_model("belt_drive").data().to_csv(tmp_path / "frf2.csv")
    f, g = str(tmp_path / "frf.csv"), str(tmp_path / "frf2.csv")
    assert main(["identify", "belt_drive", "--data", f, "--data", g]) == 2
    assert f"but {f!r} holds FrequencyData, not a time series" in capsys.readouterr().err


def test_values_a_model_file_gives_are_said_to_be_in_the_models_time_unit(tmp_path, capsys):
    """--time-unit min with a known rate in the model file (a new user's trial: a gain written per second came out
    60 times off, said nowhere): a warning that symid converts none of the file's numbers; none in seconds."""
    (tmp_path / "first_order.py").write_text(MODEL + 'known = {"g": 2.0}\n')
    k, g = si.parameters("k g", positive=True)
    model = si.StateSpaceModel(A=[[-k]], B=[[g]], C=[[1]])
    u = np.random.default_rng(0).standard_normal(200)
    rec = si.simulate_io(model, {"k": 0.5, "g": 2.0}, u, dt=0.1, noise=0.02, seed=1)
    rows = zip(rec.t, rec.u[:, 0], rec.y[:, 0], strict=True)
    (tmp_path / "rec.csv").write_text("\n".join(["t,u,y"] + [f"{t:.17g},{a:.17g},{b:.17g}" for t, a, b in rows]))
    args = ["identify", str(tmp_path / "first_order.py"), "--data", str(tmp_path / "rec.csv"), "--columns", "time=t",
            "input=u", "output=y", "--units", "time=s", "--method", "oe"]
    assert main(args) == 0
    assert "symid converts none of them" not in capsys.readouterr().err
    main([*args, "--time-unit", "min"])
    assert ("symid: warning: the known values of the model file and the command line are taken as they are, in the "
            "model's time unit min: symid converts none of them") in capsys.readouterr().err


def test_a_single_valued_flag_given_twice_with_different_values_is_an_error(capsys):
    """A new user's trial: `--method lm ... --method ipopt` ran ipopt without a word (the last one won); the README
    said any flag given twice is merged. A single-valued flag given twice with different values is now an error
    naming both; the same value twice is harmless."""
    for argv, said in ((["--method", "lm", "--method", "ipopt"], "--method is given twice ('lm' and 'ipopt'): give "
                                                                 "it once"),
                       (["--max-iter", "5", "--max-iter", "7"], "--max-iter is given twice (5 and 7)")):
        with pytest.raises(SystemExit) as info:  # argparse's usage error: exit status 2
            main(["identify", "mass_damper_2dof", *argv])
        assert info.value.code == 2 and said in capsys.readouterr().err
    assert main(["identify", "mass_damper_2dof", "--method", "ipopt", "--method", "ipopt", "--max-iter", "1"]) in (0, 4)


def test_a_file_given_twice_is_refused(tmp_path, capsys):
    """A new user's trial: --data a.csv --data a.csv fitted the record twice, the standard errors √2 too small."""
    si.load_model("belt_drive").data().to_csv(tmp_path / "frf.csv")
    f = str(tmp_path / "frf.csv")
    assert main(["identify", "belt_drive", "--data", f, "--data", f]) == 2
    assert f"--data gives {f!r} more than once: each record once" in capsys.readouterr().err
