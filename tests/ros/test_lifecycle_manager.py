"""dxboard as the lifecycle manager of managed nodes it did not start (issue 28, item 1).

The subjects are plain rclpy lifecycle nodes written by the suite (``second_robot/
lifecycle_node.py``: no dxboard code in them), started by the test as a launcher would, each
waiting unconfigured for a manager. Before this, dxboard never called a node's
``change_state`` unless it had started the node itself with ``lifecycle: true`` and had
power-switched its device. Checked here: the bring-up from unconfigured, a configure slower
than the call's timeout (judged by ``get_state``: a success), the repair from active, inactive
and unconfigured as the state requires, the transition events watched, finalized refused in
one line; and the planner's steps (``activate_node`` in dependency order, ``reset_node``)
carried out by the daemon's actuator.
"""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState
from std_msgs.msg import String

from host.events import ActionRecord, Kind
from host.journal import JournalReader
from host.observers.sources.ros2_node import RosNode
from host.ros.lifecycle import LifecycleError
from host.ros.manager import LifecycleManager
from tests.daemon.runner import RunningDaemon, fast_copy
from tests.robot.conftest import ROOT
from tests.ros.conftest import Peer
from tests.wait import wait_until

SUBJECT = Path(__file__).parent / "second_robot" / "lifecycle_node.py"
WAIT_S = 90.0
DAEMON_WAIT_S = 240.0  # a power-up of the whole robot on a loaded 2-core machine


class Subjects:
    """Lifecycle node processes the test starts (not dxboard), stopped at the end."""

    def __init__(self, env: dict[str, str]) -> None:
        self.env = env
        self.procs: list[subprocess.Popen[bytes]] = []

    def start(self, name: str, *args: str) -> subprocess.Popen[bytes]:
        p = subprocess.Popen([sys.executable, str(SUBJECT), name, *args], env=self.env,
                             cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.procs.append(p)
        return p

    def stop_all(self) -> None:
        for p in self.procs:
            p.terminate()
        for p in self.procs:
            try:
                p.wait(10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(10)


@pytest.fixture
def subjects(env: dict[str, str]) -> Iterator[Subjects]:
    s = Subjects(env)
    yield s
    s.stop_all()


@pytest.fixture
def manager(domain: int) -> Iterator[LifecycleManager]:
    ros = RosNode("dxboard_lifecycle_manager", domain)
    yield LifecycleManager(ros, call_timeout_s=2.0, settle_s=WAIT_S)
    ros.close()


def plain_transition(peer: Peer, node: str, transition: int) -> bool:
    """A transition asked by the test's own rclpy client (not dxboard's)."""
    client: Any = peer.node.create_client(ChangeState, f"/{node}/change_state")
    assert client.wait_for_service(WAIT_S)
    req = ChangeState.Request()
    req.transition.id = transition
    done = threading.Event()
    future = client.call_async(req)
    future.add_done_callback(lambda _: done.set())
    assert done.wait(WAIT_S)
    result: Any = future.result()
    return bool(result.success)


RESEND_S = 10.0  # a get_state request unanswered this long is asked again (see plain_state)


def plain_state(peer: Peer, node: str) -> str:
    """The node's state, by the test's own get_state client. A request sent just as a new
    client's service is found can be lost (the server's reply writer not yet matched with the
    client's reader: no reply ever comes), so one unanswered for ``RESEND_S`` is sent again;
    reading the state twice changes nothing. ``WAIT_S`` in all."""
    client: Any = peer.node.create_client(GetState, f"/{node}/get_state")
    try:
        assert client.wait_for_service(WAIT_S)
        deadline = time.monotonic() + WAIT_S
        while True:
            done = threading.Event()
            future = client.call_async(GetState.Request())
            future.add_done_callback(lambda _, ev=done: ev.set())
            if done.wait(max(0.0, min(RESEND_S, deadline - time.monotonic()))):
                result: Any = future.result()
                return str(result.current_state.label)
            client.remove_pending_request(future)
            assert time.monotonic() < deadline, f"no get_state reply from {node} in {WAIT_S} s"
    finally:
        peer.node.destroy_client(client)


async def test_a_node_waiting_for_a_manager_is_brought_up_watched_and_repaired(
        subjects: Subjects, manager: LifecycleManager, peer: Peer) -> None:
    peer.listen("/camera/out", String)
    subjects.start("camera")
    await manager.client.discovered("camera", WAIT_S)  # its services found
    assert plain_state(peer, "camera") == "unconfigured"  # it waits for a manager
    seen: list[str] = []
    manager.watch("camera", lambda _n, s: seen.append(s))

    assert await manager.activate("camera") == \
        "camera bring up from unconfigured: configure, activate"
    assert plain_state(peer, "camera") == "active"
    peer.collect("/camera/out", 5, WAIT_S)
    wait_until(lambda: seen[-1:] == ["active"], WAIT_S, "the transition events watched",
               show=lambda: seen)
    assert "inactive" in seen
    assert await manager.activate("camera") == "camera bring up from active: already active"

    # repaired from whatever state it is in: active, inactive (a person deactivated it),
    # unconfigured (cleaned up)
    assert await manager.reset("camera") == \
        "camera reset from active: deactivate, cleanup, configure, activate"
    assert plain_transition(peer, "camera", Transition.TRANSITION_DEACTIVATE)
    assert await manager.reset("camera") == \
        "camera reset from inactive: cleanup, configure, activate"
    assert plain_transition(peer, "camera", Transition.TRANSITION_DEACTIVATE)
    assert plain_transition(peer, "camera", Transition.TRANSITION_CLEANUP)
    assert await manager.reset("camera") == "camera reset from unconfigured: configure, activate"
    n = len(peer.messages("/camera/out"))
    peer.wait_for(lambda: len(peer.messages("/camera/out")) >= n + 5, "output after repair")

    # finalized: no transition leads back; one line that says what to do
    assert plain_transition(peer, "camera", Transition.TRANSITION_ACTIVE_SHUTDOWN)
    with pytest.raises(LifecycleError, match=r"^camera is finalized: no lifecycle transition "
                                             r"leads back to active"):
        await manager.reset("camera")


async def test_a_configure_that_outlasts_the_call_timeout_but_succeeds_is_a_success(
        subjects: Subjects, manager: LifecycleManager, peer: Peer) -> None:
    peer.listen("/slow/out", String)
    subjects.start("slow", "--configure-delay", "5")  # > the manager's 2 s call timeout
    await manager.client.discovered("slow", WAIT_S)  # its services found
    detail = await manager.activate("slow")
    assert detail == ("slow bring up from unconfigured: configure (reached inactive by "
                      "get_state: the call timed out), activate")
    assert plain_state(peer, "slow") == "active"
    peer.collect("/slow/out", 3, WAIT_S)


async def test_a_configure_that_fails_because_the_device_is_off_is_one_clear_error(
        tmp_path: Path, subjects: Subjects, manager: LifecycleManager, peer: Peer) -> None:
    device = tmp_path / "device"
    subjects.start("driver", "--device", str(device))
    await manager.client.discovered("driver", WAIT_S)  # its services found
    with pytest.raises(LifecycleError, match=r"^driver: configure left it unconfigured"):
        await manager.activate("driver")
    device.touch()  # the device powered
    assert await manager.activate("driver") == \
        "driver bring up from unconfigured: configure, activate"


@pytest.mark.timeout(900)  # a whole robot's power-up under a load of 100 on 2 cores
def test_the_daemon_brings_up_and_repairs_a_lifecycle_node_it_did_not_start(
        tmp_path: Path, subjects: Subjects, peer: Peer) -> None:
    # The finding: a standard lifecycle node waiting for a manager was restarted three times,
    # then quarantined, its change_state never called. Here the thermal camera's driver is a
    # plain rclpy lifecycle node the test starts (as ros2 launch would); the model names it
    # in external: with lifecycle: true. dxboard run powers the camera up and then brings the
    # driver up through its transitions; when a person deactivates it, dxboard repairs it.
    system = fast_copy(tmp_path)
    f = system / "system.yaml"
    text = "\n".join(x for x in f.read_text().splitlines()
                     if not x.startswith("  thermal_camera_node: {command"))
    text = text.replace("observers:\n", "observers:\n  source: {kind: ros2}\n", 1).replace(
        "    thermal_camera_node: {supervised: true}", "    thermal_camera_node: {graph: true}")
    f.write_text(text + "\nexternal:\n  thermal_camera_node: {lifecycle: true}\n")
    node = "thermal_camera_node"
    peer.listen("/thermal/image", String)
    proc = subjects.start(node, "--topic", "/thermal/image", "--rate", "9")
    daemon = RunningDaemon(tmp_path, system)
    try:
        wait_until(lambda: plain_state(peer, node) == "active", DAEMON_WAIT_S,
                   "dxboard brought the driver up", show=lambda: actions(daemon, node))
        peer.collect("/thermal/image", 9, DAEMON_WAIT_S)
        assert {a for a, _ in actions(daemon, node)} & {"activate_node", "reset_node"}
        assert not {a for a, _ in actions(daemon, node)} & {"start_node", "stop_node"}

        assert plain_transition(peer, node, Transition.TRANSITION_DEACTIVATE)  # a person
        wait_until(lambda: plain_state(peer, node) == "active", DAEMON_WAIT_S,
                   "dxboard repaired the driver", show=lambda: actions(daemon, node))
        assert proc.poll() is None  # the same process: never restarted by dxboard
    finally:
        daemon.close()


def actions(daemon: RunningDaemon, node: str) -> list[tuple[str, str]]:
    """The repair actions on ``node`` the daemon journaled: (action, state)."""
    if not daemon.journal_path.exists():
        return []
    with JournalReader(daemon.journal_path) as r:
        records = [e.payload for e in r.query(kind=Kind.ACTION, limit=100000)]
    return [(a.action, a.state.value) for a in records
            if isinstance(a, ActionRecord) and node in a.args]
