"""The board's front end in the original TEDUSAR format (``protocol/tug.py``), for old hosts.

Theory of operation. ``TugSession(board, switching, now)`` is one link, sans I/O, with the
interface ``firmware.net`` drives a native ``Session`` by (``start``, ``receive``, ``poll``,
``rate_hz``), so ``serve(net, host, port, switching)`` hands its connections to
``Net.serve_stream``: the same bounded queues, the same pump after every protection step, and
a reboot closes them as it closes every link. It answers as the original board
(``Board.cpp``) did, because the original host driver depends on it:

- on connect: SPECIFICATIONS, unasked (each channel's ``rated_ma`` and the input voltage);
- SET FREQUENCY, any rate (the original host asks 200): MEASUREMENTS at once, then once a
  second on the board's clock (``BROADCAST_MS``), as the original board's broadcaster;
  a later SET FREQUENCY does not add broadcasts, nothing stops them but the link's end;
- REQUEST (length 0, or 1): a one-byte ACK, then MEASUREMENTS;
- CHANNEL: a one-byte ACK: 0 when done, else the refusal (``protocol.tug.ACK_*``).

MEASUREMENTS carry status 1 when the channel's switch reads back on, else 0 (the original's
hardware observer takes ``status == 1`` for on), the current, and the input voltage on an on
channel (0 on an off one). Frames hold at most ``MAX_CHANNELS`` channels.

Safety, since the format has no authentication: the front end runs only when started
(``dxboard emulate --tug``; the flashed configuration's ``tug_port`` for ``firmware/main.py``,
0 by default); without ``switching`` (its ``tug_switch``)
every CHANNEL is refused (``ACK_READ_ONLY``); with it, switching never uses force, so a
protected channel is never switched off from here, and a latched or inhibited channel stays
as the board's protection left it; a CHANNEL with a channel the board lacks or a state other
than 0 or 1 changes nothing; malformed frames are dropped unanswered. Tug links never count
as the host for the dead-man. There is no idle timeout (the original host is silent between
its actions): at most ``MAX_LINKS`` tug links, a new one closes the oldest; they count among
the board's ``max_clients`` like every other link.
"""

import asyncio

from protocol import tug as tw
from protocol.compat import const

MAX_LINKS = const(2)

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from firmware.board import Board
    from firmware.net import ByteReader, ClosingWriter, Net


class TugSession:
    def __init__(self, board: "Board", switching: bool, now: int) -> None:
        self.board = board
        self.switching = switching
        self.decoder = tw.TugDecoder(tw.FROM_HOST)
        self.rate_hz = 0  # 1 while broadcasting (``Net.pump`` counts skips by it)
        self.due = now
        self.bad = 0  # malformed input, in events (``protocol.tug.Bad``)
        n = board.n
        self.n = n if n < tw.MAX_CHANNELS else tw.MAX_CHANNELS

    def start(self, now: int) -> bytes:
        return self.specs()

    def specs(self) -> bytes:
        b = self.board
        volts = b.input_mv / 1000
        chans = b.channels
        return tw.specs([(chans[i].cfg["rated_ma"] / 1000, volts) for i in range(self.n)])

    def measurements(self) -> bytes:
        b = self.board
        volts = b.input_mv / 1000
        chans = b.channels
        out = []
        for i in range(self.n):
            c = chans[i]
            on = bool(c.physical)
            out.append((tw.STATUS_ON if on else tw.STATUS_OFF, c.current_ma / 1000,
                        volts if on else 0.0))
        return tw.measurements(out)

    def receive(self, data: bytes, now: int) -> bytes:
        """Bytes from the host in, the replies out."""
        if not data:
            return b""
        self.decoder.feed(data)
        out = []
        ev = self.decoder.next()
        while ev is not None:
            if isinstance(ev, tw.Bad):
                self.bad += 1
            else:
                out.append(self._answer(ev, now))
            ev = self.decoder.next()
        return b"".join(out)

    def _answer(self, frame: "tw.Frame", now: int) -> bytes:
        cmd = frame.command
        if cmd == tw.SET_FREQ:
            self.rate_hz = 1
            self.due = now  # the first broadcast goes out with this reply (``poll``)
            return b""
        if cmd == tw.REQUEST:
            return tw.ack(tw.ACK_OK) + self.measurements()
        return tw.ack(self._switch(frame.payload[0], frame.payload[1]))

    def _switch(self, ch: int, state: int) -> int:
        if not self.switching:
            return tw.ACK_READ_ONLY
        if ch >= self.n:
            return tw.ACK_BAD_CHANNEL
        if state > 1:
            return tw.ACK_BAD_STATE
        err = self.board.switch(ch, state == 1)[0]
        return tw.ack_code(err)

    def poll(self, now: int, room: bool = True) -> bytes:
        """The broadcast, when due (skipped, not delayed, while the link's queue is full)."""
        if not self.rate_hz or now < self.due:
            return b""
        self.due += tw.BROADCAST_MS
        if self.due <= now:  # late: no burst to catch up
            self.due = now + tw.BROADCAST_MS
        return self.measurements() if room else b""


async def serve(net: "Net", host: str = "127.0.0.1", port: int = 5000,
                switching: bool = False) -> "asyncio.Server":
    """Serve the tug format on ``host:port`` through ``net`` (a ``firmware.net.Net``)."""

    async def client(reader: "ByteReader", writer: "ClosingWriter") -> None:
        if net.halted:  # a board held in reset serves nothing
            writer.close()
            return
        links = []
        for c in net.clients:
            if not c.closed and isinstance(c.session, TugSession):
                links.append(c)
        while len(links) >= MAX_LINKS:
            links.pop(0).close()
        session = TugSession(net.app.board, switching, net.now())
        await net.serve_stream(reader, writer, 0, "tug", True, session)

    return await asyncio.start_server(client, host, port)
