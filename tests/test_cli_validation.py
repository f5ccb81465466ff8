"""`symid identify --data FILE.csv` on a time series writes the validation (issue 15, item 4)."""

from __future__ import annotations

import json

import numpy as np

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
