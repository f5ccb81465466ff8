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
