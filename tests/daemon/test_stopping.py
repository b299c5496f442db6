"""A slow stop says, every few seconds, how long it has taken and what it is waiting for: the
stage the closing code named last, read while that code holds the event loop up."""

from __future__ import annotations

import threading

from host.launch.stopping import Stopping
from tests.wait import wait_until


def test_a_slow_stop_names_what_it_waits_for_until_it_is_done() -> None:
    said: list[str] = []
    stage = ["the repairs and the nodes they started"]
    stopping = Stopping(lambda: stage[0], every_s=0.05, report=said.append)
    stopping.start()
    wait_until(lambda: len(said) >= 2, 30, "two reports")
    stage[0] = "the journal's last commit"
    n = len(said)
    wait_until(lambda: any("journal" in s for s in said[n:]), 30, "the next stage named")
    stopping.done()
    after = len(said)
    assert all(s.startswith("still stopping after ") for s in said)
    assert "waiting for the repairs and the nodes they started" in said[0]
    assert not any(t.name == "stopping" for t in threading.enumerate())
    assert len(said) == after  # nothing after done()


def test_a_quick_stop_says_nothing() -> None:
    said: list[str] = []
    stopping = Stopping(lambda: "anything", every_s=60.0, report=said.append)
    stopping.start()
    stopping.done()
    assert said == []
