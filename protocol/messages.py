"""The message catalogue of PROTOCOL.md §4: one class per message type.

Every message has ``TYPE`` (the frame's type byte), ``FIELDS`` (its payload layout, see
``protocol.fields``), ``AUTH`` (True when the board requires an HMAC trailer, PROTOCOL.md
§5), ``DIR`` (who sends it: "H" host to board, "B" board to host) and a ``req_id`` (the
frame's request id: a reply carries its request's id; pushes carry 0). Messages compare by
value, and ``to_dict``/``message_from_dict`` give the JSON form used by the golden vectors.
The base class is ``protocol/message.py``; the measurement pushes are in
``protocol/measurements.py`` and listed here with the rest.
"""

from protocol import settings
from protocol.fields import Record
from protocol.measurements import Measurement, MeasurementBatch
from protocol.message import Message

if False:  # typing only; MicroPython never imports typing
    from typing import Any


# --- session and link ------------------------------------------------------------------


class Hello(Message):
    """Board -> host, first frame of every session: who the board is and the session nonce."""

    TYPE = 0x01
    DIR = "B"
    FIELDS = (
        ("version", "B"),
        ("board_id", "str"),
        ("firmware", "str"),
        ("channels", "B"),
        ("capabilities", "H"),
        ("boot_id", "I"),
        ("nonce", "nonce"),
        ("reset_cause", "B"),
        ("config_status", "B"),
    )

    def __init__(
        self,
        version: int,
        board_id: str,
        firmware: str,
        channels: int,
        capabilities: int,
        boot_id: int,
        nonce: bytes,
        reset_cause: int,
        config_status: int,
        req_id: int = 0,
    ) -> None:
        self.version = version
        self.board_id = board_id
        self.firmware = firmware
        self.channels = channels
        self.capabilities = capabilities
        self.boot_id = boot_id
        self.nonce = nonce
        self.reset_cause = reset_cause
        self.config_status = config_status
        self.req_id = req_id


class HelloRequest(Message):
    """Host -> board: start a new session (the board answers with a fresh HELLO)."""

    TYPE = 0x02

    def __init__(self, req_id: int = 0) -> None:
        self.req_id = req_id


class Ping(Message):
    """Host -> board keepalive; also feeds the board's host dead-man timer."""

    TYPE = 0x03
    FIELDS = (("token", "I"),)

    def __init__(self, token: int, req_id: int = 0) -> None:
        self.token = token
        self.req_id = req_id


class AuthPing(Message):
    """Host -> board, authenticated PING: proves that this session's host holds the key. The
    board answers PONG and from then on counts the session as the authenticated host's: its
    PINGs keep it open and feed the dead-man, and it is never evicted for a newcomer."""

    TYPE = 0x05
    AUTH = True
    FIELDS = (("token", "I"),)

    def __init__(self, token: int, req_id: int = 0) -> None:
        self.token = token
        self.req_id = req_id


class Pong(Message):
    """Board -> host: the PING's token and the board's uptime."""

    TYPE = 0x04
    DIR = "B"
    FIELDS = (("token", "I"), ("uptime_ms", "I"))

    def __init__(self, token: int, uptime_ms: int, req_id: int = 0) -> None:
        self.token = token
        self.uptime_ms = uptime_ms
        self.req_id = req_id


# --- reading ---------------------------------------------------------------------------


class GetState(Message):
    """Host -> board: ask for STATE."""

    TYPE = 0x10

    def __init__(self, req_id: int = 0) -> None:
        self.req_id = req_id


class ChannelStatus(Record):
    """One channel inside STATE."""

    FIELDS = (
        ("channel", "B"),
        ("commanded", "?"),
        ("physical", "?"),
        ("state", "B"),
        ("current_ma", "i"),
        ("live_faults", "H"),
        ("sticky_faults", "H"),
        ("trips", "H"),
        ("retries", "B"),
    )

    def __init__(
        self,
        channel: int,
        commanded: bool,
        physical: bool,
        state: int,
        current_ma: int,
        live_faults: int,
        sticky_faults: int,
        trips: int,
        retries: int,
    ) -> None:
        self.channel = channel
        self.commanded = commanded
        self.physical = physical
        self.state = state
        self.current_ma = current_ma
        self.live_faults = live_faults
        self.sticky_faults = sticky_faults
        self.trips = trips
        self.retries = retries


class State(Message):
    """Board -> host: the whole board, every channel."""

    TYPE = 0x11
    DIR = "B"
    FIELDS = (
        ("uptime_ms", "I"),
        ("input_mv", "H"),
        ("total_ma", "i"),
        ("reset_cause", "B"),
        ("config_status", "B"),
        ("board_flags", "H"),
        ("channels", ChannelStatus),
    )

    def __init__(
        self,
        uptime_ms: int,
        input_mv: int,
        total_ma: int,
        reset_cause: int,
        config_status: int,
        board_flags: int,
        channels: "list[ChannelStatus]",
        req_id: int = 0,
    ) -> None:
        self.uptime_ms = uptime_ms
        self.input_mv = input_mv
        self.total_ma = total_ma
        self.reset_cause = reset_cause
        self.config_status = config_status
        self.board_flags = board_flags
        self.channels = channels
        self.req_id = req_id


class Subscribe(Message):
    """Host -> board: sample at ``rate_hz`` (1-100) on this session, 0 stops; ``per_frame``
    (optional, 1-10, to a board with capability ``batch``): send the readings up to that many
    at a time, as MEASUREMENT_BATCH (1, the default, is not sent: one MEASUREMENT each)."""

    TYPE = 0x12
    FIELDS = (("rate_hz", "B"),)
    OPTIONAL = (("per_frame", 1),)

    def __init__(self, rate_hz: int, per_frame: int = 1, req_id: int = 0) -> None:
        self.rate_hz = rate_hz
        self.per_frame = per_frame
        self.req_id = req_id


# MEASUREMENT (0x13) and MEASUREMENT_BATCH (0x15): protocol/measurements.py


class Event(Message):
    """Board -> host push, sent at once: a trip, state change, fault, reboot, warning, shed."""

    TYPE = 0x14
    DIR = "B"
    FIELDS = (
        ("seq", "I"),
        ("uptime_ms", "I"),
        ("kind", "B"),
        ("channel", "B"),
        ("old_state", "B"),
        ("new_state", "B"),
        ("faults", "H"),
        ("value_ma", "i"),
        ("dropped", "H"),
    )

    def __init__(
        self,
        seq: int,
        uptime_ms: int,
        kind: int,
        channel: int,
        old_state: int,
        new_state: int,
        faults: int,
        value_ma: int,
        dropped: int = 0,
        req_id: int = 0,
    ) -> None:
        self.seq = seq
        self.uptime_ms = uptime_ms
        self.kind = kind
        self.channel = channel
        self.old_state = old_state
        self.new_state = new_state
        self.faults = faults
        self.value_ma = value_ma
        self.dropped = dropped
        self.req_id = req_id


# --- actuation (authenticated) ---------------------------------------------------------


class Switch(Message):
    """Host -> board: switch a channel on or off; ``force`` is needed to switch off a
    protected channel. Answered with SWITCHED (the physical state read back) or ERROR."""

    TYPE = 0x20
    AUTH = True
    FIELDS = (("channel", "B"), ("on", "?"), ("force", "?"))

    def __init__(self, channel: int, on: bool, force: bool = False, req_id: int = 0) -> None:
        self.channel = channel
        self.on = on
        self.force = force
        self.req_id = req_id


class Switched(Message):
    """Board -> host: a channel after a SWITCH, POWER_CYCLE or CLEAR, read back."""

    TYPE = 0x21
    DIR = "B"
    FIELDS = (("channel", "B"), ("commanded", "?"), ("physical", "?"), ("state", "B"))

    def __init__(
        self, channel: int, commanded: bool, physical: bool, state: int, req_id: int = 0
    ) -> None:
        self.channel = channel
        self.commanded = commanded
        self.physical = physical
        self.state = state
        self.req_id = req_id


class PowerCycle(Message):
    """Host -> board: switch off, wait ``off_ms``, switch on again (the board times it)."""

    TYPE = 0x22
    AUTH = True
    FIELDS = (("channel", "B"), ("off_ms", "H"), ("force", "?"))

    def __init__(self, channel: int, off_ms: int, force: bool = False, req_id: int = 0) -> None:
        self.channel = channel
        self.off_ms = off_ms
        self.force = force
        self.req_id = req_id


class Clear(Message):
    """Host -> board: clear a latched or faulted channel and its sticky faults (stays off)."""

    TYPE = 0x23
    AUTH = True
    FIELDS = (("channel", "B"),)

    def __init__(self, channel: int, req_id: int = 0) -> None:
        self.channel = channel
        self.req_id = req_id


# --- configuration ---------------------------------------------------------------------


class GetConfig(Message):
    """Host -> board: one channel's CHANNEL_CONFIG, or BOARD_CONFIG for channel 255."""

    TYPE = 0x30
    FIELDS = (("channel", "B"),)

    def __init__(self, channel: int, req_id: int = 0) -> None:
        self.channel = channel
        self.req_id = req_id


_CHANNEL_CONFIG_FIELDS = settings.CHANNEL_WIRE
CHANNEL_CONFIG_KEYS = tuple(name for name, _ in _CHANNEL_CONFIG_FIELDS)


class _Settings(Message):
    """A message whose payload is a table of ``protocol.settings``: built from keywords, one
    per field, every field required (the table, not a signature, lists them)."""

    def __init__(self, req_id: int = 0, **fields: "Any") -> None:
        names = [name for name, _ in self.FIELDS]
        missing = [n for n in names if n not in fields]
        unknown = [n for n in fields if n not in names]
        if missing or unknown:
            raise TypeError("%s: missing %s, unknown %s" % (type(self).__name__, missing,
                                                            unknown))
        for name in names:
            setattr(self, name, fields[name])
        self.req_id = req_id

    def __getattr__(self, name: str) -> "Any":  # the fields, for type checkers
        raise AttributeError(name)


class ChannelConfig(_Settings):
    """Board -> host: one channel's configuration (fields: ``protocol.settings.CHANNEL``)."""

    TYPE = 0x31
    DIR = "B"
    FIELDS = _CHANNEL_CONFIG_FIELDS


class SetChannelConfig(ChannelConfig):
    """Host -> board: replace one channel's configuration (answered with CHANNEL_CONFIG)."""

    TYPE = 0x32
    DIR = "H"
    AUTH = True


_BOARD_CONFIG_FIELDS = settings.BOARD_WIRE
BOARD_CONFIG_KEYS = tuple(name for name, _ in _BOARD_CONFIG_FIELDS)


class BoardConfig(_Settings):
    """Board -> host: the board-wide configuration (fields: ``protocol.settings.BOARD``, those
    with a wire kind); never the key."""

    TYPE = 0x33
    DIR = "B"
    FIELDS = _BOARD_CONFIG_FIELDS


class SetBoardConfig(BoardConfig):
    """Host -> board: replace the board-wide configuration (answered with BOARD_CONFIG)."""

    TYPE = 0x34
    DIR = "H"
    AUTH = True


class SaveConfig(Message):
    """Host -> board: persist the running configuration (answered with ACK)."""

    TYPE = 0x35
    AUTH = True

    def __init__(self, req_id: int = 0) -> None:
        self.req_id = req_id


class Reboot(Message):
    """Host -> board: answer ACK, then reset the board."""

    TYPE = 0x36
    AUTH = True

    def __init__(self, req_id: int = 0) -> None:
        self.req_id = req_id


# --- generic replies -------------------------------------------------------------------


class Ack(Message):
    """Board -> host: the request of type ``of_type`` was done."""

    TYPE = 0x7E
    DIR = "B"
    FIELDS = (("of_type", "B"),)

    def __init__(self, of_type: int, req_id: int = 0) -> None:
        self.of_type = of_type
        self.req_id = req_id


class Error(Message):
    """Board -> host: the request of type ``of_type`` failed with ``code`` (E_*)."""

    TYPE = 0x7F
    DIR = "B"
    FIELDS = (("code", "H"), ("of_type", "B"), ("text", "str"))

    def __init__(self, code: int, of_type: int, text: str, req_id: int = 0) -> None:
        self.code = code
        self.of_type = of_type
        self.text = text
        self.req_id = req_id


ALL = (
    Hello,
    HelloRequest,
    Ping,
    Pong,
    AuthPing,
    GetState,
    State,
    Subscribe,
    Measurement,
    Event,
    MeasurementBatch,
    Switch,
    Switched,
    PowerCycle,
    Clear,
    GetConfig,
    ChannelConfig,
    SetChannelConfig,
    BoardConfig,
    SetBoardConfig,
    SaveConfig,
    Reboot,
    Ack,
    Error,
)
BY_TYPE = {cls.TYPE: cls for cls in ALL}
BY_NAME = {cls.__name__: cls for cls in ALL}


def message_from_dict(name: str, data: "dict[str, Any]", req_id: int = 0) -> Message:
    """Build a message from its class name and a dict as made by ``Message.to_dict``."""
    return BY_NAME[name].from_dict(data, req_id)


__all__ = ["ALL", "BY_NAME", "BY_TYPE", "ChannelStatus", "Measurement", "MeasurementBatch",
           "Message", "message_from_dict"]
