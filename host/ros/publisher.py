"""The daemon reports through ROS 2: a reader of its event stream that publishes standard messages.

``RosPublisher(components, domain_id)`` is one rclpy node, ``dxboard`` (``sources.ros2_node``: a
thread of its own), subscribed to the daemon's ``EventStream`` (it is called with every
``Stamped`` event on the loop's thread) or, in the daemon, a listener of its one ``EventFold``
(``host.fold``, which the page reads too). It reads the fold with ``host.ros.status`` and
publishes, with standard types only, so any ROS 2 tool reads them (``rqt_robot_monitor``,
the diagnostic aggregator, Foxglove, ``ros2 topic echo``)::

    /diagnostics         diagnostic_msgs/DiagnosticArray  every status (components, board
                         channels, board) at once whenever one changes, and once a second
    /board_measurements  std_msgs/Float32MultiArray       channel currents in A, index =
                         channel number (names: the /diagnostics statuses), each sample
    /battery_state       sensor_msgs/BatteryState         voltage = the board's input voltage
                         (NaN only while the board does not say it), current = -(sum of
                         the channels) (discharging is negative); charge etc. NaN
    /board_stream        diagnostic_msgs/DiagnosticArray  every item the daemon's hardware
                         observer is fed (readings at the board's rate, events, states, the
                         link), fed by ``board(item)`` (``host.ros.boardstream``), for bags
    /diagnosis           diagnostic_msgs/DiagnosticArray  the minimal diagnoses of each run
                         that changed them: one status per diagnosis, best first, named
                         "dxboard diagnosis N", level ERROR (OK for the empty one), message the
                         abnormal components, key/values: one per component ("abnormal"),
                         probability, complete, trigger

The node offers no service and subscribes to nothing: nothing that switches power (or
changes anything) is reachable from ROS 2 (a DDS domain has no authentication). QoS:
reliable, keep last 10; ``/diagnostics`` and ``/diagnosis`` are also transient local, so a
monitor that starts late gets the latest at once.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray, KeyValue
from diagnostic_msgs.msg import DiagnosticStatus as StatusMsg
from rclpy.qos import DurabilityPolicy, QoSProfile
from sensor_msgs.msg import BatteryState
from std_msgs.msg import Float32MultiArray, MultiArrayDimension

from host.events import ChannelSample, DiagnosisRecord, Stamped
from host.fold import EventFold
from host.observers.hardware import BoardInput
from host.observers.sources.ros2_node import RosNode
from host.ros import boardstream
from host.ros.status import ERROR, OK, STALE, Diagnostics, DiagnosticStatus

log = logging.getLogger(__name__)

PERIOD_S = 1.0
LATCHED = QoSProfile(depth=10, durability=DurabilityPolicy.TRANSIENT_LOCAL)


class RosPublisher:
    def __init__(self, components: Sequence[str], domain_id: int | None = None,
                 name: str = "dxboard", fold: EventFold | None = None) -> None:
        self._own_fold = fold is None  # then it is fed by calling this publisher
        self.fold = fold if fold is not None else EventFold()
        self.diagnostics = Diagnostics(components, self.fold)
        self.ros = RosNode(name, domain_id)
        node = self.ros.node
        self._diagnostics = node.create_publisher(DiagnosticArray, "/diagnostics", LATCHED)
        self._diagnosis = node.create_publisher(DiagnosticArray, "/diagnosis", LATCHED)
        self._measurements = node.create_publisher(Float32MultiArray, "/board_measurements", 10)
        self._battery = node.create_publisher(BatteryState, "/battery_state", 10)
        self._stream = node.create_publisher(DiagnosticArray, boardstream.TOPIC,
                                            boardstream.DEPTH)
        self._closed = False
        self._last: tuple[DiagnosticStatus, ...] = tuple(self.diagnostics.statuses())
        self._publish_statuses()
        self._timer = node.create_timer(PERIOD_S, self._publish_statuses)  # on rclpy's thread
        self.fold.listeners.append(self._changed)

    def __call__(self, stamped: Stamped) -> None:
        """A reader of the event stream, for a publisher with a fold of its own (on the
        daemon's loop thread); one given a fold publishes when that fold changes."""
        if self._own_fold and not self._closed:
            self.fold.feed(stamped)

    def _changed(self, stamped: Stamped) -> None:
        """The fold changed with ``stamped`` (on the daemon's loop thread)."""
        if self._closed:
            return
        event = stamped.event
        if isinstance(event, DiagnosisRecord):
            self._diagnosis.publish(self._diagnosis_msg(event))
        elif isinstance(event, ChannelSample):
            self._publish_board()
        statuses = tuple(self.diagnostics.statuses())
        if statuses != self._last:
            self._last = statuses  # one reference swap: the timer's thread reads it
            self._publish_statuses()

    def board(self, item: BoardInput, fed_at: float) -> None:
        """One item the hardware observer was fed at ``fed_at`` (wall clock), on
        ``/board_stream`` (on the loop's thread)."""
        if not self._closed:
            self._stream.publish(boardstream.message(item, fed_at))

    def _stamp(self) -> Any:
        return self.ros.node.get_clock().now().to_msg()

    def _publish_statuses(self) -> None:
        msg = DiagnosticArray()
        msg.header.stamp = self._stamp()
        msg.status = [_status(s) for s in self._last]
        self._diagnostics.publish(msg)

    def _publish_board(self) -> None:
        currents = self.fold.currents_a
        m = Float32MultiArray()
        m.layout.dim = [MultiArrayDimension(label="channel", size=len(currents),
                                            stride=len(currents))]
        m.data = currents
        self._measurements.publish(m)
        b = BatteryState()
        b.header.stamp = self._stamp()
        b.temperature = b.charge = b.capacity = b.design_capacity = math.nan
        b.percentage = math.nan
        volts = self.fold.input_v
        b.voltage = math.nan if volts is None else volts
        b.current = -sum(currents)
        b.present = True
        b.power_supply_status = BatteryState.POWER_SUPPLY_STATUS_UNKNOWN
        b.location = "dxboard input"
        self._battery.publish(b)

    def _diagnosis_msg(self, record: DiagnosisRecord) -> DiagnosticArray:
        msg = DiagnosticArray()
        msg.header.stamp = self._stamp()
        for i, bad in enumerate(record.diagnoses, 1):
            values = [KeyValue(key=c, value="abnormal") for c in bad]
            if i <= len(record.probabilities):
                values.append(KeyValue(key="probability",
                                       value=f"{record.probabilities[i - 1]:.6g}"))
            values += [KeyValue(key="complete", value=str(record.complete).lower()),
                       KeyValue(key="trigger", value=record.trigger)]
            # nothing found broken is "all healthy" only when nothing went unobserved
            level, text = (ERROR, ", ".join(bad)) if bad else (
                (STALE, "unknown: " + ", ".join(record.unknown)) if record.unknown
                else (OK, "all healthy"))
            msg.status.append(StatusMsg(
                level=bytes([level]), name=f"dxboard diagnosis {i}",
                message=text, hardware_id="", values=values))
        return msg

    def close(self) -> None:
        """Stop publishing (idempotent); events after this are ignored."""
        self._closed = True
        self.ros.close()


def _status(s: DiagnosticStatus) -> StatusMsg:
    return StatusMsg(level=bytes([s.level]), name=s.name, message=s.message,
                            hardware_id=s.hardware_id,
                            values=[KeyValue(key=k, value=v) for k, v in s.values])
