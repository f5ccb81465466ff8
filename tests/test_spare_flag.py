"""The spare-core flag of the identifiability report's child processes (symid.structural.steps.SpareFlag)."""

from __future__ import annotations

import multiprocessing as mp
import os
import signal
import threading
import time

import pytest

from symid.structural.steps import SpareFlag

CTX = mp.get_context("fork") if "fork" in mp.get_all_start_methods() else None


def _wait_forever(flag):
    while not flag.wait(0.02):
        pass


@pytest.mark.skipif(CTX is None, reason="needs fork")
def test_set_returns_after_a_waiting_child_was_killed():
    # a multiprocessing.Event would hang here: the killed child stays counted as a sleeper of its
    # condition, and set() waits for it to wake (the hang of a report whose global step ended early)
    flag = SpareFlag(CTX)
    child = CTX.Process(target=_wait_forever, args=(flag,))
    child.start()
    time.sleep(0.3)
    os.kill(child.pid, signal.SIGKILL)
    child.join()
    done = threading.Event()
    setter = threading.Thread(target=lambda: (flag.set(), done.set()), daemon=True)
    setter.start()
    assert done.wait(5), "set() blocked"
    assert flag.is_set() and flag.wait(0)


@pytest.mark.skipif(CTX is None, reason="needs fork")
def test_a_child_sees_the_parent_set_it():
    flag = SpareFlag(CTX)
    assert not flag.wait(0.01)
    child = CTX.Process(target=_wait_forever, args=(flag,))
    child.start()
    time.sleep(0.1)
    flag.set()
    child.join(5)
    assert child.exitcode == 0
