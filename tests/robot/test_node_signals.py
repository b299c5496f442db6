"""A node of the virtual robot hears SIGTERM while its bus floods it and its loop is held up.

Issue 25, item 1, on the robot's side: with ``loop.add_signal_handler`` the signal's number
travels as one byte through the loop's self-pipe, and every message a middleware thread handed
over with ``call_soon_threadsafe`` wrote a byte into that same pipe. A node whose loop was held
up while its subscriptions flooded filled the pipe (about 280 one-byte writes fill a Unix
socket's buffer), the kernel refused SIGTERM's byte and the node never stopped: the daemon then
had to kill it, or, killed itself, left it orphaned. ``emulator.robot.node`` now hears its
signals on a thread of its own (``emulator.stopsignals``) and its bus hands messages over in
batches (``emulator.inbox``).

The node here is a real ``python -m emulator.robot.node`` process of the TEDUSAR model on real
Zenoh; the test only replaces what the node does (``run_node``) by a subscription whose first
message holds the node's loop up (a blocking callback, as a stuck behaviour would) until the
test releases it. The test floods the node during the stall, sends SIGTERM, releases the loop,
and the node must exit 0 having said ``stopped``; a loop never released is cut short at the
stop's deadline (exit 124). Checked on the old code: with ``emulator/robot`` at cd6da42^
(add_signal_handler, one ``call_soon_threadsafe`` per message) the first test failed (the node
did not stop within the deadline); with only ``node.py``'s add_signal_handler restored (the
batching bus kept) the second failed the same way.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from emulator.robot.bus import Bus
from emulator.stopsignals import EXIT_DEADLINE
from tests.ports import zenoh_endpoint
from tests.robot.conftest import ROOT, TEDUSAR
from tests.wait import wait_until

FLOOD = 3000  # messages sent while the node's loop is held up (ten times what fills a pipe)
DEADLINE_S = 90.0  # generous: only a node that lost the signal takes this long
STALL_MAX_S = 600.0  # the node's loop is held up at most this long (the test releases it)

HARNESS = """\
import sys, time
from pathlib import Path
import emulator.robot.node as node

marks = Path(sys.argv[1])

async def stalled(spec, bus, stop):
    def on_flood(_topic, _values):  # on the node's loop: its first message holds it up
        if (marks / "stalled").exists():
            return
        (marks / "stalled").write_text("yes")
        end = time.monotonic() + float(sys.argv[3])
        while not (marks / "release").exists() and time.monotonic() < end:
            time.sleep(0.05)
    bus.subscribe("/flood", on_flood)
    await stop.wait()

node.run_node = stalled
sys.exit(node.main(["hector_mapping", sys.argv[2]]))
"""


def _flooded_stalled_node(tmp_path: Path, release: bool) -> tuple[int, str]:
    """The node's exit code and stderr after SIGTERM during a flood and a stall (released at
    once after the signal, or never)."""
    endpoint = zenoh_endpoint()
    marks = tmp_path / "marks"
    marks.mkdir()
    env = {**os.environ, "DXBOARD_ZENOH": endpoint, "DXBOARD_MIDDLEWARE": "zenoh",
           "PYTHONPATH": str(ROOT)}
    bus = Bus(connect="tcp/127.0.0.1:1", listen=endpoint)  # where the node connects
    p = subprocess.Popen([sys.executable, "-c", HARNESS, str(marks), str(TEDUSAR),
                          str(STALL_MAX_S)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                         cwd=tmp_path)
    try:
        # the node connects and subscribes: publish until its first message holds it up
        wait_until(lambda: (bus.publish("/flood", {"n": -1}) or (marks / "stalled").exists()
                            or p.poll() is not None), DEADLINE_S, "the node's loop held up")
        assert p.poll() is None, p.communicate()[1]
        for n in range(FLOOD):
            bus.publish("/flood", {"n": n})
        # the flood reaches the node's zenoh threads while its loop is held up (only the old
        # code's failure depends on this pause; the new code stops whenever the signal comes)
        time.sleep(1.0)
        p.send_signal(signal.SIGTERM)
        if release:
            (marks / "release").write_text("yes")
        try:
            _, err = p.communicate(timeout=DEADLINE_S)
        except subprocess.TimeoutExpired:
            raise AssertionError(f"the node did not stop within {DEADLINE_S:g} s of SIGTERM "
                                 "(the signal was lost)") from None
        assert "Traceback" not in err, err
        return p.returncode, err
    finally:
        if p.poll() is None:
            p.kill()
            p.communicate()
        bus.close()


def test_sigterm_stops_a_node_whose_loop_is_held_up_while_its_bus_floods_it(
        tmp_path: Path) -> None:
    code, err = _flooded_stalled_node(tmp_path, release=True)
    assert code == 0, err  # an orderly stop once the loop runs again
    assert "stopped" in err, err


def test_a_node_whose_loop_stays_held_up_is_cut_short_after_its_stop_deadline(
        tmp_path: Path) -> None:
    # the loop never runs again (a behaviour stuck for good): the signal thread ends the
    # process once the stop has run DEADLINE_S (9 s); with add_signal_handler alone (even with
    # the batching bus) the handler would wait for the loop, and the node for ever
    code, err = _flooded_stalled_node(tmp_path, release=False)
    assert code == EXIT_DEADLINE, err
    assert "the stop took longer than" in err, err
