"""A driver's health as ROS 2 drivers report it: a ``/diagnostics`` status once a second.

Real ROS drivers (the Hokuyo driver, the Jaguar base driver) publish a
``diagnostic_msgs/DiagnosticArray`` through ``diagnostic_updater``: one ``DiagnosticStatus``
named ``"NODE: DEVICE"`` with the device as ``hardware_id``, a level and key/values. The
virtual drivers do the same in ROS 2 mode (``emulator.robot.ros_msgs`` makes the message)::

    level  when                                             message
    OK     connected, frames within the last STALE_S        "streaming"
    ERROR  connected, no frame for STALE_S (device hung)    "no data from the device"
    ERROR  not connected (no power, or connection lost)     "device not connected"

    key/values: frames (since start), rate_hz (over the last period), connected (true/false)

``DriverStatus`` is a plain object: ``frame(now)`` counts, ``report(now)`` returns the dict
the bus publishes; the node program calls them (times are its monotonic seconds).
"""

from __future__ import annotations

from typing import Any

OK, WARN, ERROR, STALE = 0, 1, 2, 3
PERIOD_S = 1.0
STALE_S = 1.0


class DriverStatus:
    def __init__(self, node: str, device: str) -> None:
        self.name = f"{node}: {device}"
        self.device = device
        self.connected = False
        self.frames = 0
        self.last_frame: float | None = None
        self._counted = 0
        self._since: float | None = None

    def frame(self, now: float) -> None:
        self.frames += 1
        self.last_frame = now

    def report(self, now: float) -> dict[str, Any]:
        """The ``/diagnostics`` message (as a dict) for the period ending ``now``."""
        span = now - self._since if self._since is not None else 0.0
        rate = (self.frames - self._counted) / span if span > 0 else 0.0
        self._counted, self._since = self.frames, now
        if not self.connected:
            level, message = ERROR, "device not connected"
        elif self.last_frame is None or now - self.last_frame > STALE_S:
            level, message = ERROR, "no data from the device"
        else:
            level, message = OK, "streaming"
        return {"status": [{
            "level": level, "name": self.name, "message": message, "hardware_id": self.device,
            "values": {"frames": self.frames, "rate_hz": round(rate, 2),
                       "connected": str(self.connected).lower()}}]}
