"""Model files (symid.modelfile): the user's model in a Python file, from Python and the command line.

What a file may declare, what each declaration does, and the named errors for files that do not fit.
"""

from __future__ import annotations

import json
import textwrap
import warnings

import numpy as np
import pytest

import symid as si
from symid.cli import main
from symid.modelfile import EXAMPLE, ModelFile, substitute_known

CHAIN = '''
import symid as si

m1, m2, c1, c2, k1, k2 = si.parameters("m1 m2 c1 c2 k1 k2", positive=True)
model = si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[c1 + c2, -c2], [-c2, c2]],
                            K=[[k1 + k2, -k2], [-k2, k2]], B=[[0], [1]], C=[[1, 0]])
'''


def write(tmp_path, text, name="chain.py"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def test_a_file_with_only_a_model(tmp_path):
    spec = si.load_model(write(tmp_path, CHAIN))
    assert type(spec) is ModelFile and spec.name == "chain"
    assert spec.model.parameter_names == ("m1", "m2", "c1", "c2", "k1", "k2")
    assert spec.known == {} and spec.start is None and spec.free_model() is spec.model
    assert "chain" in spec.summary() and "M =" in spec.summary()


def test_every_optional_declaration(tmp_path):
    path = write(tmp_path, CHAIN + '''
known = {"m1": 0.5}
start = {"m2": 1.0, "c1": 0.5, "c2": 0.5, "k1": 100.0, "k2": 100.0}
scale = {"m2": 1.0, "c1": 0.5, "c2": 0.5, "k1": 100.0, "k2": 100.0}
bounds = {"k1": (10, 1000), "k2": (10, None)}
title = "two masses"
input_units, output_units = "N", "m"
''')
    spec = si.load_model(str(path))
    assert spec.known == {"m1": 0.5} and spec.title == "two masses"
    assert spec.bounds == {"k1": (10.0, 1000.0), "k2": (10.0, float("inf"))}
    assert spec.h_unit() == "m/N"
    free = spec.free_model()
    assert free.parameter_names == ("m2", "c1", "c2", "k1", "k2")
    theta = {"m2": 2.0, "c1": 0.3, "c2": 0.4, "k1": 50.0, "k2": 70.0}
    full = {**theta, "m1": 0.5}
    w = np.array([0.5, 3.0, 20.0])
    np.testing.assert_allclose(free.frequency_response(theta, w), spec.model.frequency_response(full, w),
                               rtol=1e-14, atol=0)  # substitution is exact
    assert spec.outside_bounds({**theta, "k1": 5000.0}) == {"k1": (5000.0, 10.0, 1000.0)}
    for line in ("known (substituted before estimation): m1 = 0.5", "10 ≤ k1 ≤ 1000", "units: inputs N"):
        assert line in spec.summary()


def test_substitute_known_keeps_an_affine_initial_state():
    k10, k12, d = si.parameters("k10 k12 d", positive=True)
    pk = si.StateSpaceModel(A=[[-k10 - k12]], B=[[0]], C=[[1]], x0=[d * 2])
    free = substitute_known(pk, {"k12": 0.1})
    assert free.parameter_names == ("k10", "d") and free.initial_state_kind == "affine"
    np.testing.assert_array_equal(free.initial_state({"k10": 1.0, "d": 3.0}), [6.0])
    with pytest.raises(si.ModelError, match="'q', not a parameter"):
        substitute_known(pk, {"q": 1.0})


BAD_FILES = {
    "no model": ("x = 1\n", "defines no model"),
    "several models": (CHAIN.replace("model =", "chain =") + "one = si.SecondOrderModel(M=[[m1]], V=[[c1]], "
                       "K=[[k1]], B=[[1]], C=[[1]])\n", "defines several models (chain, one); name the one to use"),
    "model not a model": ("model = 3\n", "`model` is a int, not a si.StateSpaceModel"),
    "old entry() format": ("def entry():\n    return None\n", "defines entry(), the format of older"),
    "syntax error": ("model = (\n", "line 1: syntax error"),
    "error when run": ("import symid as si\nmodel = si.SecondOrderModel(M=[[1]], V=[[1]], K=[['k/m']], B=[[1]], "
                       "C=[[1]])\n", "line 2: NonAffineError"),
    "name error": ("import symid as si\nk = si.parameters('k')\nmodel = undefined_name\n",
                   "line 3: NameError: name 'undefined_name' is not defined"),
    "known not a parameter": (CHAIN + "known = {'mass': 1.0}\n", "known names 'mass', not a parameter"),
    "known nan": (CHAIN + "known = {'m1': float('nan')}\n", "known m1 must be finite"),
    "start partial": (CHAIN + "start = {'m1': 1.0}\n", "start lacks m2, c1, c2, k1, k2"),
    # a new user's typo was listed with every name but not pointed at
    "start typo": (CHAIN + "start = dict(M1=1, m2=1, c1=1, c2=1, k1=1, k2=1)\n", "'M1', not a parameter of the model "
                                                                             "(did you mean 'm1'?)"),
    "known typo": (CHAIN + "known = {'K2': 1.0}\n", "(did you mean 'k2'?)"),
    "scale negative": (CHAIN + "scale = -1\n", "a typical magnitude is a positive number"),
    "bounds reversed": (CHAIN + "bounds = {'k1': (100, 10)}\n", "the low end must be below the high end"),
    "bounds not a pair": (CHAIN + "bounds = {'k1': 10}\n", "must be a pair (low, high)"),
    "start outside bounds": (CHAIN + "start = dict(m1=1, m2=1, c1=1, c2=1, k1=1, k2=1)\nbounds = {'k1': (10, 20)}\n",
                             "lies outside its bounds"),
    "units of one side": (CHAIN + "input_units = 'N'\n", "give both input_units and output_units"),
    "units count": (CHAIN + "input_units, output_units = ['N', 'N'], 'm'\n", "gives 2 unit(s); the model has 1"),
    "truth without recipe": (CHAIN + "truth = {}\n", "defines truth but not make_data"),
}


@pytest.mark.parametrize("case", sorted(BAD_FILES))
def test_bad_model_files_are_named_errors(case, tmp_path):
    text, expected = BAD_FILES[case]
    path = write(tmp_path, text, "bad.py")
    with pytest.raises(si.ModelError) as info:
        si.load_model(path)
    assert expected in str(info.value)
    assert "bad.py" in str(info.value)


@pytest.mark.parametrize("case", ["no model", "several models", "model not a model"])
def test_missing_model_errors_quote_a_two_line_example(case, tmp_path):
    with pytest.raises(si.ModelError) as info:
        si.load_model(write(tmp_path, BAD_FILES[case][0], "bad.py"))
    assert str(info.value).endswith(EXAMPLE) and len(EXAMPLE.splitlines()) == 2
    namespace: dict = {}
    exec("import symid as si\n" + "\n".join(line.strip() for line in EXAMPLE.splitlines()), namespace)
    assert isinstance(namespace["model"], si.SecondOrderModel)  # the quoted example is a working model file


def test_missing_files_and_other_suffixes(tmp_path):
    with pytest.raises(si.ModelError, match="does not exist"):
        si.load_model(tmp_path / "missing.py")
    (tmp_path / "model.txt").write_text(CHAIN)
    with pytest.raises(si.ModelError, match=r"ending in \.py"):
        si.load_model(tmp_path / "model.txt")


def test_the_zoo_is_the_same_format_plus_truth_and_recipe():
    entry = si.load_model("mass_damper_2dof")
    assert isinstance(entry, ModelFile) and isinstance(entry, si.ZooEntry)
    assert entry.truth["k1"] == 2.0 and entry.recipe and entry.data().H.shape == (30, 1, 1)


# -- the command line on a model file ---------------------------------------------------------------------

@pytest.fixture
def chain_files(tmp_path):
    """A user's model file with a known mass and a start, and a measured FRF saved by symid (1 % noise)."""
    path = write(tmp_path, CHAIN + '''
known = {"m1": 1.0}
start = {"m2": 0.8, "c1": 0.2, "c2": 0.2, "k1": 1.5, "k2": 1.5}
''')
    truth = {"m1": 1.0, "m2": 1.0, "c1": 0.1, "c2": 0.3, "k1": 2.0, "k2": 1.0}
    spec = si.load_model(path)
    w = np.logspace(np.log10(0.3), np.log10(3.0), 40)
    data = tmp_path / "frf.npz"
    si.simulate_frf(spec.model, truth, w).to_npz(data)
    return path, data, truth


def test_cli_show_and_identifiability_on_a_model_file(chain_files, capsys):
    path, _, _ = chain_files
    assert main(["show", str(path)]) == 0
    out = capsys.readouterr().out
    assert "known (substituted before estimation): m1 = 1" in out and "start: m2 = 0.8" in out
    assert main(["identifiability", str(path)]) == 0
    out = capsys.readouterr().out
    assert "m1" in out and "known" in out  # the file's known value is honoured


def test_cli_identify_and_compare_on_a_model_file(chain_files, tmp_path, capsys):
    path, data, truth = chain_files
    code = main(["identify", str(path), "--data", str(data), "--method", "ipopt", "--out", str(tmp_path / "o")])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "known: m1 = 1" in out
    result = json.loads((tmp_path / "o" / "result.json").read_text())
    assert result["parameter_names"] == ["m2", "c1", "c2", "k1", "k2"]
    np.testing.assert_allclose(result["theta"]["k1"], truth["k1"], rtol=1e-6)  # exact data, identifiable
    np.testing.assert_allclose(result["starts"][0]["start"], [0.8, 0.2, 0.2, 1.5, 1.5], rtol=0)  # the file's start
    assert main(["compare", str(path), "--data", str(data), "--methods", "ipopt", "--starts", "2"]) == 0


def test_cli_model_file_without_data_is_a_usage_error(chain_files, capsys):
    path, _, _ = chain_files
    assert main(["identify", str(path)]) == 2
    assert "without a data recipe: give the measurements with --data FILE" in capsys.readouterr().err


def test_cli_bad_model_file_is_status_2(tmp_path, capsys):
    path = write(tmp_path, "x = 1\n", "empty.py")
    assert main(["show", str(path)]) == 2
    err = capsys.readouterr().err
    assert "defines no model" in err and "Traceback" not in err


def test_a_model_file_passed_where_a_model_goes_names_the_step_to_take(tmp_path):
    """A new user's si.identify(si.load_model(path), data) ended in AttributeError ('parameter_names')."""
    spec = si.load_model(write(tmp_path, CHAIN + 'known = {"m1": 1.0}\n'))
    frf = si.simulate_frf(spec.free_model(), [1.0, 0.1, 0.2, 2.0, 1.0], np.logspace(-1, 1, 30))
    for call in (lambda: si.identify(spec, frf), lambda: si.compare(spec, frf, methods=["lm"], starts=1)):
        with pytest.raises(si.ModelError, match=r"model is a ModelFile .* pass spec.free_model\(\)"):
            call()
    with pytest.raises(si.ModelError, match=r"pass its .free_model\(\)"):
        si.identifiability(spec)


def test_a_known_value_below_zero_for_a_positive_parameter_is_refused():
    """with_known({"q": -1.0}) for a q declared positive (a new user's trial: accepted)."""
    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    with pytest.raises(si.ModelError, match=r"known m = -1, but m is declared positive"):
        model.with_known({"m": -1.0})
    assert model.with_known({"c": 0.0}).parameter_names == ("m", "k")  # 0 is not negative


def test_a_start_giving_a_known_value_says_it_is_known():
    """x0 with a parameter fixed by with_known (a new user's trial: "names unknown parameter(s) m", as if misspelt;
    a model file already said "declared known"): the message names it as known, with its value, through twice;
    identify leaves such names out of its start (test below)."""
    import numpy as np

    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]]).with_known({"m": 2.0}).with_known(
        {"c": 0.5})
    frf = si.simulate_frf(model, {"k": 3.0}, np.linspace(0.5, 2.0, 20))
    with pytest.raises(si.ModelError, match=r"theta gives c, m, whose value is known in this model "
                                            r"\(with_known: c = 0.5, m = 2\); leave it out"):
        model.theta_vector({"m": 1.0, "c": 1.0, "k": 1.0})
    # identify's start (a model file's, for every parameter) serves: the known names are left out
    res = si.identify(model, frf, x0={"m": 1.0, "c": 1.0, "k": 1.0}, identifiability_check=False)
    assert res.success and res.theta["k"] == pytest.approx(3.0, rel=1e-8)
    with pytest.raises(si.ModelError, match=r"theta names unknown parameter\(s\) q"):
        model.theta_vector({"q": 1.0, "k": 1.0})


def test_a_name_nearly_one_symid_reads_is_warned_about(tmp_path):
    """``bound`` for ``bounds``, ``Known`` for ``known``, ``starts`` for ``start`` (a new user's trial: the fit ran
    without its bounds, on the wrong branch, and nothing said so): a ModelWarning each, naming the intended one;
    other names (``k_max``, a helper value) are left alone."""
    path = write(tmp_path, CHAIN + '''
bound = {"k1": (10.0, 1000.0)}
Known = {"m1": 0.5}
starts = {"k1": 100.0}
k_max = 1000.0
''')
    with pytest.warns(si.ModelWarning) as seen:
        spec = si.load_model(path)
    texts = sorted(str(w.message) for w in seen if issubclass(w.category, si.ModelWarning))
    assert len(texts) == 3
    for wrote, meant in (("bound", "bounds"), ("Known", "known"), ("starts", "start")):
        assert any(f"defines {wrote!r}, which symid does not read; did you mean {meant!r}?" in t for t in texts)
    assert spec.bounds == {} and spec.known == {} and spec.start is None  # passed over, as said


def test_a_non_symmetric_mass_damping_or_stiffness_matrix_is_warned_about():
    """A shear frame with -k3 where -k4 belonged (a new user's trial: built and fitted without a word): a
    ModelWarning naming the entry; a symmetric model gives none."""
    import warnings

    k3, k4, m = si.parameters("k3 k4 m", positive=True)
    with pytest.warns(si.ModelWarning, match=r"K\[0, 1\] = -k3 but K\[1, 0\] = -k4: K is not symmetric"):
        si.SecondOrderModel(M=[[m, 0], [0, m]], V=[[0, 0], [0, 0]], K=[[k3 + k4, -k3], [-k4, k4]], B=[[1], [0]],
                            C=[[1, 0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        si.SecondOrderModel(M=[[m, 0], [0, m]], V=[[0, 0], [0, 0]], K=[[k3 + k4, -k4], [-k4, k4]], B=[[1], [0]],
                            C=[[1, 0]])
        # a DC motor's electromechanical coupling is skew (+K, −K), and right
        si.SecondOrderModel(M=[[5e-3, 0], [0, m]], V=[[2.0, k3], [-k3, k4]], K=[[0, 0], [0, 0]], B=[[1], [0]],
                            C=[[0, 1]], output="velocity")


def test_the_non_symmetric_warning_is_said_once_per_model_not_again_for_its_known_values(tmp_path):
    """A new user's trial: `symid identify` printed the warning of a non-symmetric K twice, once for the file's
    model and once for the model with its known masses substituted; the derived model says nothing more."""
    import warnings

    path = tmp_path / "asym.py"
    path.write_text("import symid as si\n"
                    "m1, m2, k1, k2, k3 = si.parameters('m1 m2 k1 k2 k3', positive=True)\n"
                    "model = si.SecondOrderModel(M=[[m1, 0], [0, m2]], V=[[0.1, 0], [0, 0.1]],\n"
                    "                            K=[[k1 + k2, -k2], [-k3, k3]], B=[[1], [0]], C=[[0, 1]])\n"
                    "known = {'m1': 2.0}\n")
    with pytest.warns(si.ModelWarning, match=r"K\[0, 1\] = -k2 but K\[1, 0\] = -k3") as seen:
        spec = si.load_model(str(path))
    assert sum(issubclass(w.category, si.ModelWarning) for w in seen) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        free = spec.free_model()
        assert free.parameter_names == ("m2", "k1", "k2", "k3")
        spec.model.with_known({"m2": 3.0})


def test_identify_warns_when_a_data_files_units_differ_from_the_model_files(tmp_path, motor):
    """A new user's trial, in Python: encoder angles stated in degrees (`# units: theta [deg]`) fitted a model
    file whose output unit is rad: success=True with every inertia off by π/180 and nothing said (the command line
    warned; Python dropped the comment). si.identify now compares the units the file states for its input and
    output columns with the model file's, and a DataWarning names both; the same units say nothing."""
    import warnings

    spec = si.load_model(str(motor[0]))
    assert spec.free_model().io_units == {"input": ("N m",), "output": ("rad/s",)}
    rows = motor[1](200)
    cols = {"time": "t", "input": "tau", "output": "w"}
    for unit, warned in (("deg/s", True), ("rad / s", False)):
        path = tmp_path / "rec.csv"
        path.write_text(f"# units: t [s], tau [N m], w [{unit}]\nt,tau,w\n{rows}\n")
        io = si.IOData.from_table(str(path), columns=cols, units={"time": "s"})
        assert io.stated_units == {"input": (("tau", "N m"),), "output": (("w", unit),), "file": repr(str(path))}
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            si.identify(spec.free_model(), io, x0=spec.start, identifiability_check=False, max_iter=2)
        said = [str(w.message) for w in seen if issubclass(w.category, si.DataWarning)]
        assert any(f"the file states {unit} for output 'w'; the model file's output unit is rad/s" in s
                   for s in said) == warned, said
        if warned:  # with several records, the file is named
            from symid.fit.identify import unit_mismatches

            assert unit_mismatches(spec.free_model(), [io, io])[0].endswith(f"(in {str(path)!r})")
        with warnings.catch_warnings(record=True) as seen:  # validation on such a record says it too
            warnings.simplefilter("always")
            si.validate(spec.free_model(), {"J": 1e-3, "b": 1e-2}, io)
        assert any("the file states" in str(w.message) for w in seen
                   if issubclass(w.category, si.DataWarning)) == warned
    # the unit in a column's own name (a new user's tank level "h2 [mm]" against a model in cm: not checked)
    for unit, warned in (("deg/s", True), ("rad/s", False)):
        path = tmp_path / "named.csv"
        path.write_text(f"t,tau [N m],w [{unit}]\n{rows}\n")
        io = si.IOData.from_table(str(path), columns={"time": "t", "input": "tau [N m]", "output": f"w [{unit}]"},
                                  units={"time": "s"})
        assert io.stated_units["output"] == ((f"w [{unit}]", unit),)
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            si.identify(spec.free_model(), io, x0=spec.start, identifiability_check=False, max_iter=2)
        assert any(f"the file states {unit} for output 'w [{unit}]'" in str(w.message) for w in seen
                   if issubclass(w.category, si.DataWarning)) == warned


def test_a_model_files_dicts_serve_the_model_with_some_values_known():
    """A new user's quarter car: ``si.identify(spec.model.with_known({"ms": 320}), io, x0=spec.start,
    scale=spec.scale, bounds=spec.bounds)`` was refused three times ("'ms' is not a parameter"); the known names
    are left out of those dicts (the command line's --known did so already)."""
    import numpy as np

    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    truth = {"m": 2.0, "c": 0.8, "k": 50.0}
    io = si.simulate_io(model, truth, np.random.default_rng(0).standard_normal(400), dt=0.05)
    start, scale = {"m": 1.5, "c": 1.0, "k": 40.0}, {"m": 1.0, "c": 1.0, "k": 10.0}
    bounds = {"m": (0.1, 10.0), "c": (0.01, 10.0), "k": (1.0, 1e3)}
    known = model.with_known({"m": 2.0})
    assert known.known_values == {"m": 2.0}
    res = si.identify(known, io, x0=start, scale=scale, bounds=bounds, identifiability_check=False)
    assert res.success and set(res.theta) == {"c", "k"}
    np.testing.assert_allclose([res.theta["c"], res.theta["k"]], [0.8, 50.0], rtol=1e-6)
    cmp = si.compare(known, io, methods=("oe",), starts=1, x0=start, options={"oe": {"scale": scale, "bounds": bounds}})
    assert cmp.stats[0].n_success == 1
    # a known value outside the bounds given for it is said (they drop out with it)
    with pytest.warns(si.DataWarning, match=r"m is known as 20, outside the bounds \[0.1, 10\] given for it"):
        si.identify(model.with_known({"m": 20.0}), io, x0=start, bounds=bounds, identifiability_check=False,
                    max_iter=1)


def test_a_unit_per_second_against_a_record_in_milliseconds_warns():
    """A new user's accelerations in m/s^2 (the model file's output unit) with the record's time axis in ms: no fit
    after 60 s and a generic message. The unit's time and the record's time unit are compared (a DataWarning)."""
    import warnings

    import numpy as np

    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]], output="acceleration")
    model.io_units = {"input": ("N",), "output": ("m/s^2",)}
    u = np.random.default_rng(0).standard_normal(100)
    for unit, warned in (("ms", True), ("s", False)):
        io = si.IOData(u, np.sin(np.arange(100.0)), 1.0, time_unit=unit)
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            si.identify(model, io, x0={"m": 1.0, "c": 1.0, "k": 1.0}, identifiability_check=False, max_iter=1)
        said = [str(w.message) for w in seen if issubclass(w.category, si.DataWarning)]
        assert any("the model file's output unit m/s^2 is per s, but the record's time unit (the model's time "
                   "axis) is ms" in t for t in said) == warned, said


def test_a_model_files_time_unit_is_read_and_compared_with_the_records(tmp_path):
    """`time_unit = "min"` in a model file was ignored (a new user's rates per minute, record in seconds: every
    rate 60 times off, success=True). It is read (canonical name, in the summary and to_dict), a unit symid does not
    know is refused naming it, and si.identify warns when a record's time unit, or a frequency response's rad/s,
    is another; the same unit says nothing."""
    import warnings

    import numpy as np

    text = ("import symid as si\n"
            "a, b = si.parameters('a b', positive=True)\n"
            "model = si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[1]])\n"
            "time_unit = {!r}\n")
    (tmp_path / "tank.py").write_text(text.format("minutes"))
    spec = si.load_model(tmp_path / "tank.py")
    assert spec.time_unit == "min" and spec.to_dict()["time_unit"] == "min"
    assert "time unit: min (rates per min)" in spec.summary()
    (tmp_path / "bad.py").write_text(text.format("fortnight"))
    with pytest.raises(si.ModelError, match=r"bad.py': time_unit: unknown unit 'fortnight'"):
        si.load_model(tmp_path / "bad.py")
    model = spec.free_model()
    u = np.where(np.arange(60) < 30, 1.0, 0.0)
    omega = np.array([0.1, 1.0, 10.0])
    frf = si.FrequencyData(omega, (1.8 / (1j * omega + 0.6)).reshape(-1, 1, 1))
    for data, warned in ((si.IOData(u, u, 5.0, time_unit="s"), "the record's is s"),
                         (si.IOData(u, u, 5.0 / 60, time_unit="min"), None),
                         (frf, "the frequencies are in rad/s: give ω in rad/min")):
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            si.identify(model, data, x0={"a": 1.0, "b": 1.0}, identifiability_check=False, max_iter=1)
        said = [str(w.message) for w in seen if issubclass(w.category, si.DataWarning)
                and "the model file's time unit is min" in str(w.message)]
        assert (said[0] if said else None) is None if warned is None else warned in said[0], said
    # the result says what its rates are per (a new user's Python result in minutes said it nowhere)
    res = si.identify(model, si.IOData(u, u, 5.0 / 60, time_unit="min"), x0={"a": 1.0, "b": 1.0},
                      identifiability_check=False, max_iter=1)
    assert res.options["time_unit"] == "min" and "rates per min (the record's time unit)" in res.summary()


def test_a_model_file_with_units_but_no_time_unit_is_per_second(tmp_path):
    """The README: a model file's rates are per second when it states no time_unit. A new user's tank model with
    input and output units but no time_unit, fitted to a record read in minutes, drew no warning (a file with
    `time_unit = "s"` did); now the same warning, saying the unit is the default. A file with no units at all (or
    a model written in Python) states nothing to compare."""
    import warnings

    import numpy as np

    head = ("import symid as si\n"
            "a, b = si.parameters('a b', positive=True)\n"
            "model = si.StateSpaceModel(A=[[-a]], B=[[b]], C=[[1]])\n")
    (tmp_path / "units.py").write_text(head + "input_units, output_units = 'kW', 'K'\n")
    (tmp_path / "bare.py").write_text(head)
    u = np.where(np.arange(60) < 30, 1.0, 0.0)
    for name, record, expected in (
            ("units.py", si.IOData(u, u, 5.0 / 60, time_unit="min"),
             "the model file states no time_unit, so its rates are per s (its default), but the record's is min"),
            ("units.py", si.IOData(u, u, 5.0, time_unit="s"), None),
            ("bare.py", si.IOData(u, u, 5.0 / 60, time_unit="min"), None)):
        model = si.load_model(tmp_path / name).free_model()
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            si.identify(model, record, x0={"a": 1.0, "b": 1.0}, identifiability_check=False, max_iter=1)
        said = [str(w.message) for w in seen if issubclass(w.category, si.DataWarning) and "time_unit" in
                str(w.message)]
        if expected is None:
            assert not said, said
        else:
            assert expected in said[0] and "time_unit = 'min' in the model file" in said[0], said


def test_a_known_value_outside_the_model_files_bounds_is_said(tmp_path):
    """A new user's `--known k2=5` against the model file's bounds k2 in [10, 1000]: nothing said, and the fit's
    advice named another parameter's bound."""
    (tmp_path / "m.py").write_text(
        "import symid as si\n"
        "m, k = si.parameters('m k', positive=True)\n"
        "model = si.SecondOrderModel(M=[[m]], V=[[0.1]], K=[[k]], B=[[1]], C=[[1]])\n"
        "bounds = {'m': (0.1, 10.0), 'k': (10.0, 1000.0)}\n")
    spec = si.load_model(str(tmp_path / "m.py"))
    with pytest.warns(si.DataWarning, match=r"k is known as 5, outside the bounds \[10, 1000\] the model file gives"):
        spec.updated(known={"k": 5.0})
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", si.DataWarning)
        assert spec.updated(known={"k": 50.0}).known == {"k": 50.0}


def test_a_scale_by_name_extends_the_files_scale(tmp_path):
    """A new user's `--scale J1=2e-4` against a file whose scale names every parameter was refused ("scale lacks
    J2, ..."), where `--x0` extends the file's start: a scale by name now extends the file's (the names given win);
    a name the file's scale lacks must still be given, and one number still replaces it."""
    (tmp_path / "m.py").write_text(
        "import symid as si\n"
        "m, k = si.parameters('m k', positive=True)\n"
        "model = si.SecondOrderModel(M=[[m]], V=[[0.1]], K=[[k]], B=[[1]], C=[[1]])\n"
        "scale = {'m': 1.0, 'k': 100.0}\n")
    spec = si.load_model(str(tmp_path / "m.py"))
    assert spec.updated(scale={"m": 2.0}).scale == {"m": 2.0, "k": 100.0}
    assert spec.updated(scale=3.0).scale == {"m": 3.0, "k": 3.0}
    (tmp_path / "n.py").write_text(
        "import symid as si\n"
        "m, k = si.parameters('m k', positive=True)\n"
        "model = si.SecondOrderModel(M=[[m]], V=[[0.1]], K=[[k]], B=[[1]], C=[[1]])\n")
    with pytest.raises(si.ModelError, match="scale lacks k"):
        si.load_model(str(tmp_path / "n.py")).updated(scale={"m": 2.0})


def test_a_start_scale_or_bounds_entry_on_a_known_parameter_is_left_out_and_said(tmp_path):
    """Two new users added `known` to a model file whose start named the parameter, and were refused ("declared
    known"); the known value is what the fit uses, so the entry is left out with a ModelWarning naming it."""
    path = tmp_path / "chain.py"
    path.write_text(CHAIN + "known = {'m1': 1.0}\nstart = dict(m1=2.0, m2=1, c1=1, c2=1, k1=1, k2=1)\n"
                    "scale = dict(m1=2.0, m2=1, c1=1, c2=1, k1=1, k2=1)\nbounds = {'m1': (0.5, 3.0)}\n",
                    encoding="utf-8")
    with pytest.warns(si.ModelWarning) as record:
        spec = si.load_model(path)
    said = [str(w.message) for w in record]
    for what in ("start", "scale", "bounds"):
        assert any(f"{what} gives m1, declared known (m1 = 1): known parameters are not estimated, so this entry is "
                   "left out" in text for text in said), what
    assert "m1" not in spec.start and "m1" not in spec.scale and "m1" not in spec.bounds
    assert spec.known == {"m1": 1.0}


def test_a_start_giving_the_known_value_itself_is_set_aside_quietly(tmp_path):
    """A new user's model file for a drive, its start listing every parameter and `known` fixing the motor constant
    at the same value (so that one file serves the fits with it free and known): a ModelWarning on every load. An
    entry equal to the known value is left out without a word; one that differs is still said."""
    path = tmp_path / "chain.py"
    path.write_text(CHAIN + "known = {'m1': 1.0}\nstart = dict(m1=1.0, m2=1, c1=1, c2=1, k1=1, k2=1)\n",
                    encoding="utf-8")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        spec = si.load_model(path)
    assert "m1" not in spec.start and spec.known == {"m1": 1.0}
    path.write_text(CHAIN + "known = {'m1': 1.0}\nstart = dict(m1=1.5, m2=1, c1=1, c2=1, k1=1, k2=1)\n",
                    encoding="utf-8")
    with pytest.warns(si.ModelWarning, match="start gives m1, declared known"):
        si.load_model(path)
