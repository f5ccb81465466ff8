"""symid.progress: the bar on a terminal, plain lines elsewhere."""

from __future__ import annotations


def test_a_long_run_off_a_terminal_says_how_far_it_is(monkeypatch, capsys):
    """A new user's trial: si.compare ran 391 s in a script without a word (the bar shows only on a terminal). Off a
    terminal and a notebook, progress=None now writes a plain line at most every HEARTBEAT_S seconds (0 here, so
    every item but the first); a short run says nothing (the default 30 s), and progress=False never."""
    import symid.progress as prog

    monkeypatch.setattr(prog, "_interactive", lambda: False)
    assert list(prog.progress_bar(range(3), desc="lm starts")) == [0, 1, 2]
    assert capsys.readouterr().err == ""  # within the first 30 s: nothing
    monkeypatch.setattr(prog, "HEARTBEAT_S", 0.0)
    assert list(prog.progress_bar(range(3), desc="lm starts")) == [0, 1, 2]
    assert capsys.readouterr().err.splitlines()[-1].startswith("lm starts: 2 of 3 done, ")
    assert list(prog.progress_bar(range(3), desc="lm starts", enabled=False)) == [0, 1, 2]
    assert capsys.readouterr().err == ""


def test_one_long_start_says_it_is_alive(monkeypatch, capsys):
    """A new user's single start ran 77 s in Python without a word (the bar is for several starts). identify's
    default now says after HEARTBEAT_AFTER_S seconds (10, as the command line) that it is still estimating;
    progress=False says nothing."""
    import time

    import numpy as np

    import symid as si
    import symid.progress as prog
    from symid.fit.frf.lm import AutoFRF

    m, c, k = si.parameters("m c k", positive=True)
    model = si.SecondOrderModel(M=[[m]], V=[[c]], K=[[k]], B=[[1]], C=[[1]])
    frf = si.simulate_frf(model, [2.0, 0.5, 3.0], np.linspace(0.5, 2.0, 20))
    real_run = AutoFRF.run

    def slow(self, x0):
        time.sleep(0.3)
        return real_run(self, x0)

    monkeypatch.setattr(AutoFRF, "run", slow)
    monkeypatch.setattr(prog, "HEARTBEAT_AFTER_S", 0.1)
    si.identify(model, frf, x0=[2.0, 0.5, 3.0], identifiability_check=False)
    assert "symid: still estimating (auto, 1 start): 0 s so far" in capsys.readouterr().err
    si.identify(model, frf, x0=[2.0, 0.5, 3.0], identifiability_check=False, progress=False)
    assert "still estimating" not in capsys.readouterr().err
