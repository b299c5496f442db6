"""The world the robot acts in (``emulator.robot.world``): the pyrobosim arena and its skills.

Two parts. Without processes: the real arena of ``models/tedusar`` and the skills stepped on a
simulated clock, with the truth given by the test (the seam where the board's state enters):
navigation stalls while the truth blocks it and resumes where it stopped, no path behind a
closed door, victims seen only in their room, a door opened only from beside it. Then one
physical truth end to end: ``dxboard emulate --robot --world`` with real driver nodes — the
base moves only while its channel is on, its driver connected and commanded; a lidar hang stalls
navigation until the lidar is power-cycled and its driver restarted; the camera's driver is
needed to detect a victim.
"""

from __future__ import annotations

import asyncio
import json
import socket
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from emulator.robot.config import RobotModelError
from emulator.robot.world.arena import Arena, load_arena
from emulator.robot.world.skills import Goal, Progress, make_goal
from tests.robot.conftest import TEDUSAR, Nodes, Robot, Topics


class GivenTruth:
    """The truth as the test says: ``blocked[need]`` is the symptom, absent when it works."""

    def __init__(self) -> None:
        self.blocked_by: dict[str, str] = {}

    def blocked(self, need: str) -> str | None:
        return self.blocked_by.get(need)


@pytest.fixture(scope="module")
def arena_factory() -> Iterator[Any]:
    yield lambda: load_arena(TEDUSAR)


def prepare(goal: Goal) -> None:
    asyncio.run(goal.prepare(lambda fn: asyncio.get_running_loop().run_in_executor(None, fn)))


def run(goal: Goal, t0: int = 0, until: int = 60_000, step: int = 50,
        prepared: bool = False) -> tuple[int, Progress]:
    if not prepared:
        prepare(goal)
    t = t0
    while t < until:
        prog = goal.step(t)
        if prog.done:
            return t, prog
        t += step
    raise AssertionError(f"{goal.skill} did not end by {until} ms")


def test_navigation_stalls_while_blocked_and_resumes_where_it_stopped(arena_factory: Any) -> None:
    arena: Arena = arena_factory()
    truth = GivenTruth()
    nav = make_goal(arena, truth, "navigate", {"to": "office"})
    assert nav.check() == ""
    prepare(nav)
    t = 0
    while nav.step(t).progress < 0.3:
        t += 50
    where = arena.pose()
    truth.blocked_by["lidar"] = "no laser scans"
    for _ in range(40):  # 2 s of a hung lidar: not a millimetre
        t += 50
        prog = nav.step(t)
        assert prog.waiting == ("no laser scans",) and not prog.done
    assert arena.pose() == where
    del truth.blocked_by["lidar"]
    t_end, prog = run(nav, t, prepared=True)
    assert prog.success and prog.data["place"] == "office" and arena.place() == "office"
    assert 8_000 < t_end - 2_000 < 11_000  # about 8.9 m at 1 m/s, plus the 2 s stalled


def test_no_path_behind_a_closed_door_and_open_only_from_beside_it(arena_factory: Any) -> None:
    arena: Arena = arena_factory()
    truth = GivenTruth()
    _, prog = run(make_goal(arena, truth, "navigate", {"to": "lab"}))
    assert not prog.success and "closed: door_lab" in prog.message
    assert "not beside entrance" in make_goal(arena, truth, "open", {"door": "door_lab"}).check()
    _, prog = run(make_goal(arena, truth, "navigate", {"to": "corridor"}))
    assert prog.success
    opener = make_goal(arena, truth, "open", {"door": "door_lab"})
    assert opener.check() == ""
    prepare(opener)
    truth.blocked_by["base"] = "the base gets no commands"
    assert not opener.step(0).done and not opener.step(5_000).done  # pushes nothing
    del truth.blocked_by["base"]
    _, prog = run(opener, 5_000, prepared=True)
    assert prog.success and arena.doors()["door_lab"]
    _, prog = run(make_goal(arena, truth, "navigate", {"to": "lab"}))
    assert prog.success and arena.place() == "lab"


def test_victims_are_seen_only_in_their_room_and_marked_only_in_view(arena_factory: Any) -> None:
    arena: Arena = arena_factory()
    truth = GivenTruth()
    _, prog = run(make_goal(arena, truth, "detect", {}))
    assert prog.success and prog.data["victims"] == []  # from the entrance: walls
    _, prog = run(make_goal(arena, truth, "mark", {"victim": "victim_1"}))
    assert not prog.success and "not in view" in prog.message
    run(make_goal(arena, truth, "navigate", {"to": "corridor"}))
    run(make_goal(arena, truth, "navigate", {"to": "office"}))
    truth.blocked_by["camera"] = "no thermal images"
    det = make_goal(arena, truth, "detect", {})
    prepare(det)
    assert all(not det.step(t).done for t in range(0, 5_000, 100))
    del truth.blocked_by["camera"]
    _, prog = run(det, 5_000, prepared=True)
    assert prog.data["victims"] == ["victim_1"]  # not victim_2 behind the lab's closed door
    _, prog = run(make_goal(arena, truth, "mark", {"victim": "victim_1"}))
    assert prog.success and arena.state()["marked"] == ["victim_1"]
    assert arena.world.get_object_by_name("marker_victim_1") is not None


def test_a_locked_door_does_not_open_and_a_jammed_dispenser_leaves_no_marker(
        arena_factory: Any) -> None:
    from emulator.robot.world.server import WorldServer

    arena: Arena = arena_factory()
    truth = GivenTruth()
    server = WorldServer(arena, truth, lambda: 0)
    bad = server._request(b'{"op": "door", "door": "door_lab", "open": false, "locked": 1}', None)
    assert bad is not None and bad["event"] == "error" and "locked" in bad["error"]
    assert not arena.locked()  # bad input changes nothing
    ok = server._request(b'{"op": "door", "door": "door_lab", "open": false, "locked": true}',
                         None)
    assert ok == {"event": "door", "door": "door_lab", "open": False}
    assert arena.state()["locked"] == ["door_lab"]
    run(make_goal(arena, truth, "navigate", {"to": "corridor"}))
    _, prog = run(make_goal(arena, truth, "open", {"door": "door_lab"}))
    assert not prog.success and "locked" in prog.message and not arena.doors()["door_lab"]
    assert server._request(b'{"op": "jam"}', None) == {"event": "jam"}
    run(make_goal(arena, truth, "navigate", {"to": "office"}))
    run(make_goal(arena, truth, "detect", {}))
    _, prog = run(make_goal(arena, truth, "mark", {"victim": "victim_1"}))
    assert prog.success and arena.state()["marked"] == []  # it says so, and left nothing
    _, prog = run(make_goal(arena, truth, "mark", {"victim": "victim_1"}))
    assert prog.success and arena.state()["marked"] == ["victim_1"]  # one jam, one marking


def test_requests_for_what_the_arena_lacks_are_refused(arena_factory: Any,
                                                       tmp_path: Path) -> None:
    arena: Arena = arena_factory()
    truth = GivenTruth()
    assert "no room 'kitchen'" in make_goal(arena, truth, "navigate", {"to": "kitchen"}).check()
    with pytest.raises(ValueError, match="no skill 'fly'"):
        make_goal(arena, truth, "fly", {})
    with pytest.raises(ValueError, match="needs 'victim'"):
        make_goal(arena, truth, "mark", {})
    with pytest.raises(RobotModelError, match="no arena here"):
        load_arena(tmp_path)
    bad = tmp_path / "arena"
    bad.mkdir()
    (bad / "world.yaml").write_text("rooms: []\n")
    with pytest.raises(RobotModelError, match="exactly one robot"):
        load_arena(tmp_path)


# --- one physical truth, end to end ----------------------------------------------------------

class WorldClient:
    """The world's TCP skill servers, spoken to as the host's skill layer does."""

    def __init__(self, url: str) -> None:
        host, port = url.removeprefix("tcp://").rsplit(":", 1)
        self.sock = socket.create_connection((host, int(port)), timeout=30)
        self.file = self.sock.makefile("rwb")

    def send(self, msg: dict[str, Any]) -> None:
        self.file.write(json.dumps(msg).encode() + b"\n")
        self.file.flush()

    def read(self) -> dict[str, Any]:
        line = self.file.readline()
        assert line, "the world closed the connection"
        got: dict[str, Any] = json.loads(line)
        return got

    def until(self, pred: Any, timeout: float = 30.0) -> dict[str, Any]:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            msg = self.read()
            if pred(msg):
                return msg
        raise AssertionError("the world did not say it in time")

    def close(self) -> None:
        self.sock.close()


@pytest.fixture
def world_robot(robot_dir: Path) -> Iterator[Robot]:
    r = Robot(robot_dir, "--world")
    yield r
    r.stop()


def test_one_physical_truth_with_the_board_devices_and_drivers(
        world_robot: Robot, robot_dir: Path, topics: Topics) -> None:
    robot = world_robot
    nodes = Nodes(robot_dir, robot, topics)
    w = WorldClient(robot.urls["world"])
    try:
        w.send({"op": "goal", "id": "n1", "skill": "navigate", "args": {"to": "office"}})
        assert w.read() == {"id": "n1", "event": "accepted"}
        fb = w.until(lambda m: m.get("event") == "feedback")
        assert set(fb["waiting"]) == {"no odometry from the base", "no laser scans"}
        for ch in ("jaguar", "hokuyo"):
            robot.board("on", ch)
        nodes.start("jaguar_node", "hokuyo_node")  # connected, but nothing commands the base
        fb = w.until(lambda m: m.get("waiting") == ["the base gets no commands"])
        nodes.start("joy_node", "jaguar_teleop_node")  # /cmd_vel through the driver
        fb = w.until(lambda m: m.get("event") == "feedback" and m["progress"] > 0.2)
        robot.inject("hokuyo", "hang")
        fb = w.until(lambda m: m.get("waiting") == ["no laser scans"])
        stalled = fb["state"]["pose"]
        fb = w.until(lambda m: m.get("event") == "feedback" and m["state"]["t_ms"]
                     > fb["state"]["t_ms"] + 1500)
        assert fb["state"]["pose"] == stalled and fb["waiting"] == ["no laser scans"]
        robot.board("cycle", "hokuyo")  # a hang is cured by power; the driver lost its device
        time.sleep(2.5)
        fb = w.until(lambda m: m.get("event") == "feedback")
        assert fb["waiting"] == ["no laser scans"] and fb["state"]["pose"] == stalled
        nodes.stop("hokuyo_node")
        nodes.start("hokuyo_node")
        res = w.until(lambda m: m.get("event") == "result", timeout=60)
        assert res["status"] == "succeeded" and res["state"]["place"] == "office"
        w.send({"op": "goal", "id": "d1", "skill": "detect", "args": {}})
        w.until(lambda m: m.get("event") == "accepted")
        fb = w.until(lambda m: m.get("event") == "feedback")
        assert fb["waiting"] == ["no thermal images"]
        robot.board("on", "thermal_camera")
        nodes.start("thermal_camera_node")
        topics.wait_for("/thermal/image", timeout=15)
        res = w.until(lambda m: m.get("event") == "result", timeout=30)
        assert res["status"] == "succeeded" and res["data"]["victims"] == ["victim_1"]
    finally:
        w.close()
        nodes.stop_all()


def test_in_a_doorway_the_robot_is_in_the_nearer_room(arena_factory: Any) -> None:
    arena: Arena = arena_factory()
    arena.set_pose(2.0, 0.0, 0.0)  # in door_entrance, nearer the entrance than the corridor
    assert arena.place() == "door_entrance" and arena.room() == "entrance"
    assert arena.state()["room"] == "entrance"
    arena.set_pose(3.6, 0.0, 0.0)
    assert arena.place() == "corridor" and arena.room() == "corridor"
