"""The board's stream as ROS 2 messages: what the hardware observer watches, for bags.

The daemon's ``/board_measurements`` (a few times a second, currents only) and its per-channel
``/diagnostics`` statuses (once a second and at changes) do not carry what the hardware
observer's rules need: every reading (its rules count ``settle`` agreeing readings at the
board's 100 Hz and judge the link by ``link_timeout``, 0.25 s, without one), the live-fault
bits, the board's events (a trip is a claim the readings must bear out), its state replies,
the link going down and up and reboots. So the daemon also publishes, on ``/board_stream``
(``diagnostic_msgs/DiagnosticArray``, a standard type: ``ros2 topic echo``, Foxglove and
``rosbags`` read it), every item its hardware observer is fed, as it is fed:

- ``header.stamp``: when the daemon fed it to its hardware observer (wall clock; by default
  the item's ``host_time``, when the host received it);
- ``status[0]``: name ``dxboard board stream``, level OK (ERROR for ``link_down``), message the
  item's kind (``reading``, ``event``, ``state``, ``link_down``, ``link_up``, ``rebooted``),
  ``hardware_id`` ``board``, and one key/value per field of the item as ``host.board.types``
  names it (``on_mask``, ``fault_mask``: the channels' bits; ``currents_ma``: comma-separated,
  index = channel; ``new_state``: the state's number in ``protocol.constants``), numbers in
  decimal;
- a ``state`` item adds one status per channel, name ``dxboard board stream: channel N``, with
  the fields of ``ChannelState``; a ``link_up`` adds one, ``dxboard board stream: info``, with
  the fields of ``BoardInfo`` (HELLO).

``encode(item)`` gives the array's statuses as plain ``StreamRecord`` values, ``message(item)`` the
message the publisher sends, and ``decode(msg)`` turns a recorded message back into the
item, so ``dxboard record`` / ``dxboard replay`` feed the hardware observer what the daemon's
was fed, at the stamp's time (``when``). Anything that does not decode is None (logged).
"""

from __future__ import annotations

import dataclasses
import logging
import typing
from dataclasses import dataclass
from typing import Any

from host.board.types import (
    BoardEvent,
    BoardInfo,
    BoardState,
    ChannelState,
    LinkDown,
    LinkUp,
    Reading,
    Rebooted,
)
from host.observers.hardware import BoardInput
from host.observers.sources.ros2_message import RosMessage

log = logging.getLogger(__name__)

TOPIC = "/board_stream"
# messages of the stream its publisher and a recorder keep while the other end lags: 30 s of
# items at the board's 100 Hz (a few hundred bytes each). With ROS's usual 100 a recorder held
# up 1 s on a loaded machine (two suites side by side) lost board items, two trips among them
DEPTH = 3000
TYPE = "diagnostic_msgs/msg/DiagnosticArray"
NAME = "dxboard board stream"
CHANNEL, INFO = f"{NAME}: channel ", f"{NAME}: info"
KINDS: dict[str, type[Any]] = {"reading": Reading, "event": BoardEvent, "state": BoardState,
                               "link_down": LinkDown, "link_up": LinkUp, "rebooted": Rebooted}
_KIND_OF = {cls: kind for kind, cls in KINDS.items()}
OK, ERROR = 0, 2


@dataclass(frozen=True)
class StreamRecord:
    """One ``DiagnosticStatus`` of a ``/board_stream`` message."""

    level: int
    name: str
    message: str
    values: tuple[tuple[str, str], ...]


def encode(item: BoardInput) -> list[StreamRecord]:
    """The statuses that carry ``item``."""
    kind = _KIND_OF[type(item)]
    level = ERROR if kind == "link_down" else OK
    out = [StreamRecord(level, NAME, kind, _values(item))]
    if isinstance(item, BoardState):
        out += [StreamRecord(OK, f"{CHANNEL}{c.channel}", "channel", _values(c))
                for c in item.channels]
    elif isinstance(item, LinkUp):
        out.append(StreamRecord(OK, INFO, "info", _values(item.info)))
    return out


def message(item: BoardInput, stamp: float | None = None) -> Any:
    """``item`` as the ``diagnostic_msgs/DiagnosticArray`` that ``/board_stream`` carries,
    stamped ``stamp`` (default: its ``host_time``)."""
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

    records = encode(item)
    stamp = item.host_time if stamp is None else stamp
    msg = DiagnosticArray()
    set_stamp(msg.header, stamp)
    msg.status = [DiagnosticStatus(level=bytes([r.level]), name=r.name, message=r.message,
                                   hardware_id="board",
                                   values=[KeyValue(key=k, value=v) for k, v in r.values])
                  for r in records]
    return msg


def set_stamp(header: Any, t: float) -> None:
    """A ``std_msgs/Header``'s stamp to ``t`` (seconds; whole nanoseconds)."""
    sec = int(t // 1)
    header.stamp.sec, header.stamp.nanosec = sec, min(int((t - sec) * 1e9), 999_999_999)


def when(msg: RosMessage) -> float:
    """The time a bag message counts at: a board item's own stamp, else its arrival."""
    if msg.topic == TOPIC:
        stamp = msg.stamp
        if stamp is not None:
            return stamp
    return msg.time


def decode(msg: RosMessage) -> BoardInput | None:
    """The board item a ``/board_stream`` message carries (None: not one)."""
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.serialization import deserialize_message

    try:
        array = deserialize_message(msg.payload, DiagnosticArray)
        statuses = {s.name: (s.message, {kv.key: kv.value for kv in s.values})
                    for s in array.status}
        kind, values = statuses[NAME]
        cls = KINDS[kind]
        extra: dict[str, Any] = {}
        if cls is BoardState:
            extra["channels"] = tuple(sorted(
                (_build(ChannelState, v, {}) for n, (_, v) in statuses.items()
                 if n.startswith(CHANNEL)), key=lambda c: c.channel))
        elif cls is LinkUp:
            extra["info"] = _build(BoardInfo, statuses[INFO][1], {})
        item: BoardInput = _build(cls, values, extra)
        return item
    except Exception as exc:  # bad CDR, a missing key, a bad number: not a board item
        log.warning("%s at %.3f: not a board stream item (%s)", msg.topic, msg.time, exc)
        return None


def _values(obj: Any) -> tuple[tuple[str, str], ...]:
    out = []
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        if f.name in ("channels", "info") and not isinstance(v, int):
            continue  # a state's channels, a link's info: statuses of their own
        if isinstance(v, bool):
            text = "true" if v else "false"
        elif isinstance(v, frozenset):
            text = ",".join(sorted(str(x) for x in v))
        elif isinstance(v, tuple):
            text = ",".join(str(x) for x in v)
        else:
            text = repr(v) if isinstance(v, float) else str(v)
        out.append((f.name, text))
    return tuple(out)


_HINTS: dict[type[Any], dict[str, Any]] = {}


def _hints(cls: type[Any]) -> dict[str, Any]:
    """A dataclass's field types (read once per class: ``get_type_hints`` is slow)."""
    if cls not in _HINTS:
        _HINTS[cls] = typing.get_type_hints(cls)
    return _HINTS[cls]


def _build(cls: type[Any], values: dict[str, str], extra: dict[str, Any]) -> Any:
    hints = _hints(cls)
    args: dict[str, Any] = dict(extra)
    for f in dataclasses.fields(cls):
        if f.name in args:
            continue
        if f.name not in values:
            if f.default is not dataclasses.MISSING:
                continue
            raise KeyError(f.name)
        args[f.name] = _parse(hints[f.name], values[f.name])
    return cls(**args)


def _parse(hint: Any, text: str) -> Any:
    origin = typing.get_origin(hint)
    if hint is bool:
        return text == "true"
    if hint in (int, float, str):
        return hint(text)
    parts = [p for p in text.split(",") if p]
    if origin is tuple:
        return tuple(int(p) for p in parts)
    if origin is frozenset:
        return frozenset(parts)
    raise TypeError(f"cannot read {hint}")
