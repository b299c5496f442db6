"""What each node of the virtual robot does: drivers read a device, ordinary nodes compute.

A *driver* (kind SN or HN: ``jaguar_node``, ``hokuyo_node``, ``laser_alignment_node``,
``imu_node``, ``joy_node``) connects to its device's TCP endpoint (``$DXBOARD_DEVICES``), retrying
while the device refuses (it is not powered yet), and publishes every frame the device sends,
as it is (``emulator.robot.devices`` lists the keys), on its one published topic; messages on
its subscribed topics become device commands (``COMMANDS``). When the connection drops (the
device lost power) the driver keeps running but publishes nothing and does not reconnect:
like the paper's drivers it must be restarted after the device is powered up again.

An *ordinary* node (kind N) publishes only while its inputs arrive: an input with no message
for ``STALE_S`` (a few periods of the slowest input) stops the outputs that depend on it::

    jaguar_teleop_node       /joy -> /cmd_vel at 10 Hz  {"seq", "linear", "angular"}
    hector_mapping           /scan -> /slam_out_pose per scan {"seq", "x", "y", "yaw"}
                             (yaw tracked by matching scans to a keyframe), /map every 2 s
                             {"seq", "resolution", "width", "height", "scans"}
    laser_alignment_control  /imu_data -> /laser_alignment/command at 10 Hz {"seq", "roll",
                             "pitch"} (levels the laser against the body's roll and pitch)
    rviz                     subscribes only
    (any other N node)       every output at 10 Hz while all its inputs arrive: {"seq"}

The node process (``emulator.robot.node``) adds its publisher's stamp to every message
(``"stamp"``: its monotonic clock, seconds), as a ROS node fills in a header's stamp.

Behaviours are plain objects driven by ``on_message(topic, values, now)`` and ``tick(now)``
(seconds, monotonic), publishing through a callable: no I/O, so they are tested directly.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from emulator.robot.config import NodeSpec

Publish = Callable[[str, dict[str, Any]], None]

STALE_S = 0.5
# input topic of a driver -> the command its device accepts (fields are the message's)
COMMANDS = {"/cmd_vel": "velocity", "/laser_alignment/command": "angle"}

TELEOP_LINEAR = 0.5  # m/s at full forward stick
TELEOP_ANGULAR = 1.0  # rad/s at full turn stick
MATCH_STRIDE = 8  # hector: scan matching on every 8th beam
MATCH_SHIFT = 12  # +-12 beams (3 deg) between consecutive scans


def device_command(topic: str, values: dict[str, Any]) -> dict[str, Any] | None:
    """The device command for a driver's input message (None: the device takes none)."""
    cmd = COMMANDS.get(topic)
    if cmd is None:
        return None
    return {**{k: v for k, v in values.items() if k != "seq"}, "cmd": cmd}


class Behaviour:
    tick_s = 0.1

    def __init__(self, spec: NodeSpec, publish: Publish) -> None:
        self.spec = spec
        self.publish = publish
        self.last: dict[str, tuple[float, dict[str, Any]]] = {}
        self.seq: dict[str, int] = {}

    def fresh(self, topic: str, now: float) -> dict[str, Any] | None:
        """The latest message on ``topic`` if it came within ``STALE_S``."""
        got = self.last.get(topic)
        return got[1] if got is not None and now - got[0] <= STALE_S else None

    def put(self, topic: str, values: dict[str, Any]) -> None:
        n = self.seq.get(topic, 0)
        self.seq[topic] = n + 1
        self.publish(topic, {"seq": n, **values})

    def on_message(self, topic: str, values: dict[str, Any], now: float) -> None:
        self.last[topic] = (now, values)
        self.react(topic, values, now)

    def react(self, topic: str, values: dict[str, Any], now: float) -> None:
        pass

    def tick(self, now: float) -> None:
        pass


class Relay(Behaviour):
    """Any ordinary node: each output at 10 Hz while every input it depends on arrives."""

    def tick(self, now: float) -> None:
        for topic, inputs in self.spec.publishes.items():
            if all(self.fresh(t, now) is not None for t in inputs):
                self.put(topic, {})


class Teleop(Behaviour):
    def tick(self, now: float) -> None:
        joy = self.fresh("/joy", now)
        if joy is None:
            return
        axes = joy.get("axes")
        turn, forward = (axes[0], axes[1]) if isinstance(axes, list) and len(axes) >= 2 \
            and all(isinstance(a, int | float) for a in axes[:2]) else (0.0, 0.0)
        self.put("/cmd_vel", {"linear": round(forward * TELEOP_LINEAR, 4),
                              "angular": round(turn * TELEOP_ANGULAR, 4)})


class Mapping(Behaviour):
    tick_s = 2.0

    def __init__(self, spec: NodeSpec, publish: Publish) -> None:
        super().__init__(spec, publish)
        self.key: list[int] | None = None  # the keyframe scan and the yaw it was taken at
        self.key_yaw = 0.0
        self.scans = 0
        self.yaw = 0.0

    def react(self, topic: str, values: dict[str, Any], now: float) -> None:
        if topic != "/scan":
            return
        ranges = values.get("ranges_mm")
        inc = values.get("angle_increment")
        if not isinstance(ranges, list) or not isinstance(inc, float) \
                or len(ranges) < 4 * MATCH_SHIFT or not all(isinstance(r, int) for r in ranges):
            return
        self.scans += 1
        if self.key is None or len(self.key) != len(ranges):
            self.key, self.key_yaw = ranges, self.yaw
        else:
            # matched against a keyframe, not the previous scan: small turns add up
            shift = match_shift(self.key, ranges)
            self.yaw = self.key_yaw - shift * inc
            if abs(shift) > MATCH_SHIFT // 2:
                self.key, self.key_yaw = ranges, self.yaw
        self.put("/slam_out_pose", {"x": 0.0, "y": 0.0, "yaw": round(self.yaw, 4)})

    def tick(self, now: float) -> None:
        if self.fresh("/scan", now) is not None:
            self.put("/map", {"resolution": 0.05, "width": 2048, "height": 2048,
                              "scans": self.scans})


def match_shift(prev: list[int], cur: list[int]) -> int:
    """The shift ``s`` with ``cur[i] ~ prev[i + s]``: the robot turned ``-s`` beams."""
    best, best_cost = 0, float("inf")
    lo, hi = MATCH_SHIFT, len(cur) - MATCH_SHIFT
    for s in range(-MATCH_SHIFT, MATCH_SHIFT + 1):
        cost = sum(abs(cur[i] - prev[i + s]) for i in range(lo, hi, MATCH_STRIDE))
        if cost < best_cost:
            best, best_cost = s, cost
    return best


class AlignmentControl(Behaviour):
    def tick(self, now: float) -> None:
        imu = self.fresh("/imu_data", now)
        if imu is None:
            return
        roll, pitch = imu.get("roll"), imu.get("pitch")
        if not isinstance(roll, int | float) or not isinstance(pitch, int | float):
            return
        self.put("/laser_alignment/command", {"roll": round(-roll, 4), "pitch": round(-pitch, 4)})


class Sink(Behaviour):
    tick_s = 1.0


BEHAVIOURS: dict[str, type[Behaviour]] = {
    "jaguar_teleop_node": Teleop,
    "hector_mapping": Mapping,
    "laser_alignment_control": AlignmentControl,
    "rviz": Sink,
}


def make(spec: NodeSpec, publish: Publish) -> Behaviour:
    cls = BEHAVIOURS.get(spec.name, Relay if spec.publishes else Sink)
    return cls(spec, publish)
