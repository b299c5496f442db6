"""One physical truth: what the board, the devices and their drivers let the world's robot do.

The arena's robot is the same robot whose devices the emulated board powers. Before a skill
advances the world a step it asks the ``Truth`` what stops it, in the words a skill server on a
real robot would use (a symptom, never the cause — finding the cause is the diagnosers' work)::

    base    the base's device works (powered, booted, not hung), its driver (jaguar_node) is
            connected, and it is being commanded (velocity commands within the base's
            command hold: the driver relays /cmd_vel)       else "no odometry from the base"
                                                                or "the base gets no commands"
    lidar   the lidar works and its driver reads it           else "no laser scans"
    camera  the camera works and its driver reads it          else "no thermal images"
    mount   the laser mount works, its driver is connected and it gets angle commands (from
            laser_alignment_control through the driver)  else "the laser mount does not answer"
                                                             or "the laser mount gets no commands"

Each check returns ``None`` when nothing stops it. ``BoardTruth`` reads the device servers of
``emulator.robot.server`` (their state follows the electronics, their clients are the driver
nodes' connections) and the devices' last commands, on the emulator's clock; it runs on the
emulator's loop like the servers it reads.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping
from typing import Protocol

from emulator.robot import devices as D

NEEDS = ("base", "lidar", "camera", "mount")


class Truth(Protocol):
    def blocked(self, need: str) -> str | None:
        """What stops ``need`` (one of ``NEEDS``) now; None when nothing does."""


class Served(Protocol):
    """What ``BoardTruth`` reads of a device server (``emulator.robot.server.DeviceServer``)."""

    device: D.SimDevice
    state: str

    @property
    def clients(self) -> Collection[object]: ...


# the device kind each need reads, and its symptoms: not working or unread, not commanded
_KIND = {"base": "base", "lidar": "lidar", "camera": "camera", "mount": "servo"}
_DOWN = {"base": "no odometry from the base", "lidar": "no laser scans",
         "camera": "no thermal images", "mount": "the laser mount does not answer"}
_IDLE = {"base": "the base gets no commands", "mount": "the laser mount gets no commands"}


class BoardTruth:
    """The truth of the device servers, by need; ``now_ms`` is the emulator's clock."""

    def __init__(self, servers: Mapping[str, Served], now_ms: Callable[[], int]) -> None:
        self.now_ms = now_ms
        self.by_need: dict[str, Served] = {}
        for need, kind in _KIND.items():
            found = [s for s in servers.values() if s.device.spec.kind == kind]
            if found:
                self.by_need[need] = found[0]

    def blocked(self, need: str) -> str | None:
        server = self.by_need.get(need)
        if server is None:
            return f"the robot has no {_KIND.get(need, need)}"
        if server.state != "ready" or not server.clients:
            return _DOWN[need]
        if need in _IDLE and self.now_ms() - self._last_command(server.device) \
                >= D.COMMAND_HOLD_MS:
            return _IDLE[need]
        return None

    @staticmethod
    def _last_command(device: D.SimDevice) -> int:
        if isinstance(device, D.Base):
            return device.world.cmd_ms
        if isinstance(device, D.Servo):
            return device.cmd_ms
        return 0
