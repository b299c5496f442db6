"""The board on CAN, sans I/O: frames per ``protocol/can.py`` (and the DBC) out, commands in.

``CanNode(board, key, random_bytes, node=0, rate_hz=10)``; ``poll(now_ms)`` returns the
frames due, as ``(can_id, data)`` pairs (11-bit ids, 8 data bytes, little-endian as the DBC
says): DXB_Status (0x100+N) and DXB_Nonce (0x1F0+N) every second, DXB_Currents_g
(0x110+4N+g, channels 4g..4g+3, i16 in 10 mA) at ``rate_hz``, DXB_Channel_k (0x140+16N+k)
every second and at once when the channel's state, command or read-back changes.
``receive(can_id, data, now_ms)`` takes a frame from the bus and returns the replies.

CAN has no session, so commands carry their own authentication: DXB_Cmd (0x180+N: op 1 on,
2 off, 3 cycle, 4 clear; channel; force; off time in 100 ms; a counter, strictly increasing
per boot) is followed within ``TAG_WINDOW_MS`` by DXB_CmdTagA and DXB_CmdTagB (0x181+N,
0x182+N), the first and second 8 bytes of HMAC-SHA256(key, CAN nonce || the command's 8
bytes). The nonce is 8 random bytes chosen at boot and broadcast in DXB_Nonce. Each command
is answered with DXB_CmdResult (0x188+N): op, channel, error (0 or E_*), state, read-back. A
command whose tags do not arrive in time (E_AUTH_REQUIRED), with a bad tag (E_BAD_TAG), with
a counter not above the last accepted (E_REPLAYED) or on a board without key changes nothing.
An unknown op is E_BAD_VALUE (303), checked after the tag and the counter. A DXB_Cmd whose
data is not 8 bytes is answered with E_MALFORMED (105), and so is the pending command when a
tag frame of the wrong length comes: a command is never silently ignored.
"""

from protocol.auth import equal
from protocol.can import (
    CURRENT_GROUPS,
    FRAME_LEN,
    ID_CMD,
    ID_NONCE,
    ID_RESULT,
    ID_STATUS,
    ID_TAG_A,
    ID_TAG_B,
    MAX_CHANNELS,
    OP_CLEAR,
    OP_CYCLE,
    OP_OFF,
    OP_ON,
    SLOW_MS,
    TAG_WINDOW_MS,
    channel_frame,
    channel_id,
    command_tag,
    currents_frame,
    currents_id,
    parse_command,
    result_frame,
    status_frame,
)
from protocol.constants import (
    E_AUTH_REQUIRED,
    E_BAD_CHANNEL,
    E_BAD_TAG,
    E_BAD_VALUE,
    E_MALFORMED,
    E_REPLAYED,
)

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from collections.abc import Callable

    from firmware.board import Board, Reply

    Frame = tuple[int, bytes]  # (11-bit CAN id, data)


class CanNode:
    def __init__(self, board: "Board", key: "bytes | None",
                 random_bytes: "Callable[[int], bytes]", node: int = 0, rate_hz: int = 10) -> None:
        self.board = board
        self.key = key
        self.node = node
        self.nonce = random_bytes(8)
        self.period = 1000 // rate_hz if rate_hz else 0
        self.counter = 0
        self.pending: "bytes | None" = None
        self.pending_at = 0
        self.tag_a: "bytes | None" = None
        self.slow_at = 0
        self.fast_at = 0
        self.last: "list[tuple[bool, bool, int]]" = []  # (commanded, physical, state) each
        self.readback: "Reply | None" = None

    # --- broadcasts ---------------------------------------------------------------------

    def poll(self, now: int) -> "list[Frame]":
        out = []
        n = self.node
        if self.pending is not None and now - self.pending_at > TAG_WINDOW_MS:
            out.append(self._result(self.pending, E_AUTH_REQUIRED))
            self.pending = None
        bstat, chans = self.board.status()
        chans = chans[:MAX_CHANNELS]
        slow = now >= self.slow_at
        if slow:
            self.slow_at = now + SLOW_MS
            out.append((ID_STATUS + n, status_frame(bstat)))
            out.append((ID_NONCE + n, bytes(self.nonce)))
        if self.period and now >= self.fast_at:
            self.fast_at = now + self.period
            currents = [c[3] for c in chans]
            for g in range(CURRENT_GROUPS):
                out.append((currents_id(n, g), currents_frame(currents, g)))
        last = self.last
        for k in range(len(chans)):
            c = chans[k]
            key = (c[0], c[1], c[2])
            if slow or k >= len(last) or last[k] != key:
                out.append((channel_id(n, k), channel_frame(c)))
        self.last = [(c[0], c[1], c[2]) for c in chans]
        return out

    # --- commands -----------------------------------------------------------------------

    def receive(self, can_id: int, data: bytes, now: int) -> "list[Frame]":
        n = self.node
        out = []
        cmd_ids = can_id == ID_CMD + n
        tag_ids = can_id == ID_TAG_A + n or can_id == ID_TAG_B + n
        if len(data) != FRAME_LEN:
            # a command frame of the wrong length is answered (E_MALFORMED), as is the
            # command pending when a tag frame of the wrong length comes; others: not ours
            if cmd_ids or (tag_ids and self.pending is not None):
                if self.pending is not None:
                    pending = self.pending
                    self.pending = None
                    self.tag_a = None
                    out.append(self._result(pending, E_AUTH_REQUIRED if cmd_ids
                                            else E_MALFORMED))
                if cmd_ids:
                    out.append(self._result(bytes(data[:2]) + bytes(2 - len(data[:2])),
                                            E_MALFORMED))
            return out
        if cmd_ids:
            if self.pending is not None:
                out.append(self._result(self.pending, E_AUTH_REQUIRED))
            self.pending = bytes(data)
            self.pending_at = now
            self.tag_a = None
        elif can_id == ID_TAG_A + n and self.pending is not None:
            self.tag_a = bytes(data)
        elif can_id == ID_TAG_B + n and self.pending is not None:
            cmd = self.pending
            tag_a = self.tag_a
            self.pending = None
            self.tag_a = None
            if now - self.pending_at > TAG_WINDOW_MS or tag_a is None:
                out.append(self._result(cmd, E_AUTH_REQUIRED))
            else:
                out.append(self._result(cmd, self._check(cmd, tag_a + bytes(data))))
        return out

    def _check(self, cmd: bytes, tag: bytes) -> int:
        """0 if the command may run (and then runs it), else the error code."""
        if self.key is None:
            return E_AUTH_REQUIRED
        if not equal(command_tag(self.key, self.nonce, cmd), tag):
            return E_BAD_TAG
        op, ch, force, off, counter = parse_command(cmd)
        if counter <= self.counter:
            return E_REPLAYED
        self.counter = counter
        self.board.host_seen(self.board.now)
        b = self.board
        if op == OP_ON:
            res = b.switch(ch, True)
        elif op == OP_OFF:
            res = b.switch(ch, False, force)
        elif op == OP_CYCLE:
            res = b.power_cycle(ch, off * 100, force)
        elif op == OP_CLEAR:
            res = b.clear(ch)
        else:
            return E_BAD_VALUE
        self.readback = res  # (error, state, physical read back from the switch)
        err: int = res[0]
        return err

    def _result(self, cmd: bytes, err: int) -> "Frame":
        op = cmd[0]
        ch = cmd[1]
        b = self.board
        state = 0
        physical = False
        rb = self.readback
        self.readback = None
        if 0 <= ch < b.n:
            if rb is not None:
                state = rb[1]
                physical = rb[2]
            else:
                state = b.channels[ch].state
                physical = b.hal.read_switch(ch)
        elif not err and op != OP_CLEAR:
            err = E_BAD_CHANNEL
        return (ID_RESULT + self.node, result_frame(op, ch, err, state, physical))
