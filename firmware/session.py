"""One client of the native protocol, sans I/O: bytes in, reply bytes out, pushes on poll.

A ``Session`` serves one TCP connection or one serial stream. It owns a
``protocol.connection.Connection(BOARD, key)`` and a ``Board``; it never touches a socket or a
clock (time comes in as ``now_ms``, on the HAL clock the board ticks on). The front end
(``firmware/net.py``) moves the bytes. API:

``Session(board, key, random_bytes, firmware_version, capabilities, now_ms)``
    ``key`` the actuation key (bytes, or None: every authenticated command is refused with
    E_AUTH_REQUIRED; ``board_key(board)`` reads it from the board config); ``random_bytes(n)``
    the HAL's random source (session nonces); ``firmware_version`` a string for HELLO;
    ``capabilities`` the ``CAP_*`` mask for HELLO.
``start(now_ms) -> bytes``
    the HELLO that opens the session: a fresh 16-byte nonce, the board's boot id, reset cause
    and configuration status. Events logged before ``start`` are not pushed to this session.
``receive(data, now_ms) -> bytes``
    feed bytes (``b""`` = the stream ended); returns every reply frame: STATE, ACK, PONG,
    HELLO, SWITCHED (with the physical read-back), CHANNEL_CONFIG, BOARD_CONFIG, or ERROR
    (``Connection.error_reply`` for a bad frame, the board's E_* for a refused command). A
    refused or malformed command changes nothing. A request whose HMAC checks out (any
    authenticated command, AUTH_PING first of all) makes the session ``authenticated``: the
    host's. Every authenticated message, and a PING of the host's session, restarts the
    board's host dead-man (``board.host_seen``); a PING of anyone else does not.
``poll(now_ms, send_measurement=True) -> bytes``
    the pushes due now: every new board event as EVENT (its log ``seq``; ``dropped`` = events
    this session lost to the ring since the last EVENT), then a reading when the
    subscription (SUBSCRIBE 1-100 Hz, 0 stops) is due, numbered from 1 per session. A front end
    whose client cannot keep up passes ``send_measurement=False``: the due reading is
    skipped but its number is used, so the client sees the gap. Events are never skipped.
    With SUBSCRIBE's ``per_frame`` k > 1 the readings are held and sent k at a time as one
    MEASUREMENT_BATCH: the batch goes out at every k-th due reading (fewer in it when some were
    skipped), so none is held longer than k - 1 periods; readings held are sent first, in
    order, before an EVENT and before the answer to any request.
``next_due(now_ms) -> int``
    when ``poll`` next has something to send (``now_ms`` if events are waiting).
``idle_ms(now_ms) -> int``
    how long the session has been idle; the front end closes a session idle for longer than
    its read timeout, and evicts the idlest unauthenticated session for a newcomer. The host's
    (authenticated) session is idle only while nothing arrives (it PINGs to stay connected);
    an unauthenticated one while it sends nothing but PING (a subscribed one never is), so
    PINGs alone do not keep a stranger's session open.
``closed``
    True once the stream ended (``receive(b"")``).
"""

from firmware.board import (
    C_COMMANDED,
    C_CURRENT_MA,
    C_LIVE,
    C_PHYSICAL,
    C_RETRIES,
    C_STATE,
    C_STICKY,
    C_TRIPS,
)
from protocol.auth import NONCE_LEN
from protocol.connection import BOARD, Connection
from protocol.constants import (
    BOARD_CHANNEL,
    E_BAD_VALUE,
    ERROR_TEXT,
    NOT_FAULTS,
    PROTOCOL_VERSION,
)
from protocol.framing import BadFrame
from protocol.measurements import MAX_PER_FRAME
from protocol.messages import (
    Ack,
    AuthPing,
    BoardConfig,
    ChannelConfig,
    ChannelStatus,
    Clear,
    Error,
    Event,
    GetConfig,
    GetState,
    Hello,
    HelloRequest,
    Measurement,
    MeasurementBatch,
    Ping,
    Pong,
    PowerCycle,
    Reboot,
    SaveConfig,
    SetBoardConfig,
    SetChannelConfig,
    State,
    Subscribe,
    Switch,
    Switched,
)
from protocol.settings import int_to_ip, ip_to_int

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from collections.abc import Callable
    from typing import Any

    from firmware.board import Board, Reply
    from protocol.message import Message

FIRMWARE_VERSION = "0.1.0"
FRAME_GAP_MS = 250  # serial lines: an incomplete frame is dropped after this much silence
MAX_RATE_HZ = 100
EVENTS_PER_POLL = 16
IDLE_DUE_MS = 1000  # next_due when nothing is scheduled


def board_key(board: "Board") -> "bytes | None":
    """The actuation key from the board configuration (hex), or None when none is set."""
    text = board.cfg["board"].get("key", "")
    if not text:
        return None
    try:
        return bytes.fromhex(text)
    except ValueError:
        return None


def _u16(v: int) -> int:
    return 0 if v < 0 else (0xFFFF if v > 0xFFFF else v)


class Session:
    def __init__(self, board: "Board", key: "bytes | None",
                 random_bytes: "Callable[[int], bytes]",
                 firmware_version: str, capabilities: int, now_ms: int,
                 frame_gap_ms: int = 0) -> None:
        self.board = board
        self.frame_gap_ms = frame_gap_ms
        self.conn = Connection(BOARD, key)
        self.random_bytes = random_bytes
        self.firmware_version = firmware_version
        self.capabilities = capabilities
        self.last_rx = now_ms
        self.last_active = now_ms  # the last request that counts against the idle timeout
        self.authenticated = False  # a request of this session passed the HMAC check
        self.cursor = board.events.seq
        self.lost = 0
        self.rate_hz = 0
        self.period = 0
        self.meas_at = 0
        self.meas_seq = 0
        self.per_frame = 1  # readings a frame (SUBSCRIBE's per_frame)
        self.held: "list[Measurement]" = []  # readings not yet sent, oldest first
        self.batch_left = 0  # due readings until the held ones go out
        self.closed = False

    # --- session ----------------------------------------------------------------------

    def _hello(self, req_id: int) -> bytes:
        """A HELLO that starts a new session: a fresh nonce and counter (the codec), and no
        subscription, measurements counted from 1 again, only events from now on."""
        b = self.board
        self.authenticated = False
        self.rate_hz = 0
        self.meas_seq = 0
        self.per_frame = 1
        self.held = []
        self.cursor = b.events.seq
        self.lost = 0
        nonce = self.random_bytes(NONCE_LEN)
        return self.conn.send(Hello(
            PROTOCOL_VERSION, b.cfg["board"]["board_id"], self.firmware_version,
            b.n, self.capabilities, getattr(b, "boot_id", 0), nonce,
            b.reset_cause, b.cfg_status, req_id))

    def start(self, now_ms: int) -> bytes:
        self.last_rx = self.last_active = now_ms
        return self._hello(0)

    def idle_ms(self, now_ms: int) -> int:
        """How long this session has been idle: since the last bytes for the authenticated
        host; for anyone else since the last request other than PING (a subscribed session,
        busy reading its measurements, is never idle)."""
        if self.authenticated:
            return now_ms - self.last_rx
        if self.rate_hz:
            return 0
        return now_ms - self.last_active

    # --- receiving --------------------------------------------------------------------

    def receive(self, data: bytes, now_ms: int) -> bytes:
        conn = self.conn
        out: "list[bytes]" = []
        if data:
            if self.frame_gap_ms and conn.pending and now_ms - self.last_rx >= self.frame_gap_ms:
                conn.truncate()  # the frame in progress stopped arriving: drop it (E_TRUNCATED)
                self._drain(now_ms, out)
            self.last_rx = now_ms
        else:
            self.closed = True
        conn.receive_data(data)
        self._drain(now_ms, out)
        return b"".join(out)

    def _drain(self, now_ms: int, out: "list[bytes]") -> None:
        conn = self.conn
        while True:
            ev = conn.next_event()
            if ev is None:
                break
            if self.held:  # whatever is answered comes after the readings taken before it
                out.append(self._flush())
            if isinstance(ev, BadFrame):
                reply = conn.error_reply(ev)
            else:
                if ev.AUTH:  # its tag checked out: this is the host that holds the key
                    self.authenticated = True
                if ev.AUTH or (self.authenticated and isinstance(ev, Ping)):
                    self.board.host_seen(now_ms)
                if self.authenticated or not isinstance(ev, Ping):
                    self.last_active = now_ms
                reply = self._answer(ev, now_ms)
            if reply:
                out.append(reply)

    def _error(self, code: int, msg: "Message") -> bytes:
        return self.conn.send(Error(code, msg.TYPE, ERROR_TEXT.get(code, ""),
                                    req_id=msg.req_id))

    def _switched(self, msg: "Switch | PowerCycle | Clear", result: "Reply") -> bytes:
        err, state, physical = result
        if err:
            return self._error(err, msg)
        ch = msg.channel
        commanded = self.board.channels[ch].commanded
        return self.conn.send(Switched(ch, commanded, physical, state, msg.req_id))

    def _answer(self, msg: "Message", now_ms: int) -> "bytes | None":
        b = self.board
        send = self.conn.send
        rid = msg.req_id
        if isinstance(msg, GetState):
            return send(self.state_message(rid))
        if isinstance(msg, (Ping, AuthPing)):
            return send(Pong(msg.token, _uptime(b), rid))
        if isinstance(msg, Subscribe):
            rate = msg.rate_hz
            if rate > MAX_RATE_HZ or not 1 <= msg.per_frame <= MAX_PER_FRAME:
                return self._error(E_BAD_VALUE, msg)
            self.rate_hz = rate
            self.per_frame = self.batch_left = msg.per_frame
            if rate:
                self.period = 1000 // rate
                self.meas_at = now_ms
            return send(Ack(Subscribe.TYPE, rid))
        if isinstance(msg, HelloRequest):
            return self._hello(rid)
        if isinstance(msg, Switch):
            return self._switched(msg, b.switch(msg.channel, msg.on, msg.force))
        if isinstance(msg, PowerCycle):
            return self._switched(msg, b.power_cycle(msg.channel, msg.off_ms, msg.force))
        if isinstance(msg, Clear):
            result = b.clear(msg.channel)
            if msg.channel == BOARD_CHANNEL and not result[0]:
                return send(Ack(Clear.TYPE, rid))
            return self._switched(msg, result)
        if isinstance(msg, GetConfig):
            if msg.channel == BOARD_CHANNEL:
                return send(self.board_config_message(rid))
            return self._channel_config(msg, msg.channel, rid)
        if isinstance(msg, SetChannelConfig):
            fields = {}
            for name, _ in SetChannelConfig.FIELDS:
                if name != "channel":
                    fields[name] = getattr(msg, name)
            err = b.set_channel_config(msg.channel, fields)
            if err:
                return self._error(err, msg)
            return self._channel_config(msg, msg.channel, rid)
        if isinstance(msg, SetBoardConfig):
            fields = {}
            for name, _ in SetBoardConfig.FIELDS:
                fields[name] = getattr(msg, name)
            try:
                fields["modbus_allow"] = [int_to_ip(n) for n in msg.modbus_allow]
            except (TypeError, ValueError):
                return self._error(E_BAD_VALUE, msg)
            err = b.set_board_config(fields)
            if err:
                return self._error(err, msg)
            return send(self.board_config_message(rid))
        if isinstance(msg, SaveConfig):
            err = b.save_config()
            return self._error(err, msg) if err else send(Ack(SaveConfig.TYPE, rid))
        if isinstance(msg, Reboot):
            b.request_reboot()
            return send(Ack(Reboot.TYPE, rid))
        return None  # HELLO from the host cannot happen: the codec refuses board messages

    def _channel_config(self, msg: "Message", ch: int, rid: int) -> bytes:
        err, cfg = self.board.get_channel_config(ch)
        if err:
            return self._error(err, msg)
        cfg["channel"] = ch
        return self.conn.send(ChannelConfig(req_id=rid, **cfg))

    # --- messages built from the board ----------------------------------------------------

    def state_message(self, req_id: int = 0) -> State:
        (mv, total, uptime, cause, cfg_status, flags), chans = self.board.status()
        out = []
        for i in range(len(chans)):
            c: "tuple[Any, ...]" = chans[i]  # a ChannelRow, read by C_* (mypy cannot follow)
            out.append(ChannelStatus(
                channel=i, commanded=c[C_COMMANDED], physical=c[C_PHYSICAL], state=c[C_STATE],
                current_ma=c[C_CURRENT_MA], live_faults=c[C_LIVE], sticky_faults=c[C_STICKY],
                trips=_u16(c[C_TRIPS]), retries=min(c[C_RETRIES], 255)))
        return State(uptime, _u16(mv), total, cause, cfg_status, flags, out, req_id)

    def board_config_message(self, req_id: int = 0) -> BoardConfig:
        cfg = self.board.get_board_config()
        cfg["modbus_allow"] = [ip_to_int(text) for text in cfg["modbus_allow"]]
        return BoardConfig(req_id=req_id, **cfg)

    # --- pushes -----------------------------------------------------------------------

    def poll(self, now_ms: int, send_measurement: bool = True) -> bytes:
        b = self.board
        out = []
        log = b.events
        if log.seq > self.cursor:
            if self.held:
                out.append(self._flush())
            evs, self.cursor, lost = log.read(self.cursor, EVENTS_PER_POLL)
            self.lost += lost
            for e in evs:
                seq, kind, ch, old, new, faults, value, uptime = e
                out.append(self.conn.send(Event(seq, uptime, kind, ch, old, new, faults & 0xFFFF,
                                                value, min(self.lost, 0xFFFF))))
                self.lost = 0
        if self.rate_hz and now_ms >= self.meas_at:
            self.meas_seq += 1
            self.meas_at += self.period
            if self.meas_at <= now_ms:  # late: no burst to catch up
                self.meas_at = now_ms + self.period
            if self.per_frame == 1:
                if send_measurement:
                    out.append(self.conn.send(self.measurement()))
            else:
                if send_measurement:
                    self.held.append(self.measurement())
                self.batch_left -= 1
                if self.batch_left <= 0:
                    if self.held:
                        out.append(self._flush())
                    else:
                        self.batch_left = self.per_frame
        return b"".join(out)

    def _flush(self) -> bytes:
        """The held readings as one MEASUREMENT_BATCH; the next batch starts empty."""
        held, self.held = self.held, []
        self.batch_left = self.per_frame
        return self.conn.send(MeasurementBatch(held))

    def measurement(self) -> Measurement:
        b = self.board
        on = 0
        faults = 0
        currents = []
        chans = b.channels
        for i in range(len(chans)):
            c = chans[i]
            if c.physical:
                on |= 1 << i
            if c.live & ~NOT_FAULTS:  # not F_LOW: how a reading was made is no fault
                faults |= 1 << i
            currents.append(c.current_ma)
        return Measurement(self.meas_seq, _uptime(b), _u16(b.input_mv), on, faults,
                           currents)

    def next_due(self, now_ms: int) -> int:
        if self.board.events.seq > self.cursor:
            return now_ms
        if self.rate_hz:
            return self.meas_at if self.meas_at > now_ms else now_ms
        return now_ms + IDLE_DUE_MS


def _uptime(board: "Board") -> int:
    up = board.now - board.boot_ms
    return up & 0xFFFFFFFF
