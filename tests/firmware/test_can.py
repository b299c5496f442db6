"""CAN frames of the board (firmware/can.py) on a real Board: layout, broadcasts, commands."""

import struct
import unittest

from benchmarks._rigs.testhal import Rig
from firmware.can import CanNode
from protocol.can import (
    ID_CHANNEL,
    ID_CMD,
    ID_CURRENTS,
    ID_NONCE,
    ID_RESULT,
    ID_STATUS,
    ID_TAG_A,
    ID_TAG_B,
    OP_CYCLE,
    OP_OFF,
    OP_ON,
    channel_frame,
    command_frame,
    command_tag,
    currents_frame,
    parse_channel,
    parse_command,
    parse_currents,
    parse_result,
    parse_status,
    result_frame,
    status_frame,
)
from protocol.constants import (
    E_AUTH_REQUIRED,
    E_BAD_TAG,
    E_BAD_VALUE,
    E_MALFORMED,
    E_PROTECTED,
    E_REPLAYED,
    ST_INRUSH,
    ST_OFF,
    ST_ON,
)

KEY = bytes(range(32))
KEY_HEX = "".join("%02x" % b for b in KEY)


def rig(**kw):
    return Rig(board={"key": KEY_HEX}, **kw)


def ids(frames):
    return [f[0] for f in frames]


class FrameTest(unittest.TestCase):
    def test_golden_bytes(self):
        self.assertEqual(channel_frame((True, True, 2, -1500, 3, 0, 1, 0)),
                         bytes.fromhex("3224fa0f03000100"))
        self.assertEqual(status_frame((24000, 0, 61999, 1, 2, 0x21)),
                         bytes.fromhex("3d000000c05d2121"))
        self.assertEqual(currents_frame([1234, -20, 0, 70000, 5], 0),
                         struct.pack("<4h", 123, -2, 0, 7000))
        self.assertEqual(currents_frame([1234, -20, 0, 70000, 5], 1),
                         struct.pack("<4h", 1, 0, 0, 0))
        self.assertEqual(command_frame(OP_CYCLE, 3, True, 20, 0x01020304),
                         bytes.fromhex("0303011404030201"))
        self.assertEqual(result_frame(OP_ON, 3, 301, 4, True), bytes.fromhex("01032d0114000000"))

    def test_parse_inverts_pack(self):
        self.assertEqual(parse_channel(channel_frame((True, True, 2, -1500, 3, 0, 1, 0))),
                         (2, True, True, -1500, 3, 1, 0))
        self.assertEqual(parse_status(status_frame((24000, 0, 61999, 1, 2, 0x21))),
                         (61, 24000, 0x21, 1, 2))
        self.assertEqual(parse_currents(currents_frame([1234, -20, 0, 70000], 0)),
                         [1230, -20, 0, 70000])
        self.assertEqual(parse_command(command_frame(OP_CYCLE, 3, True, 20, 7)),
                         (OP_CYCLE, 3, True, 20, 7))
        self.assertEqual(parse_result(result_frame(OP_ON, 3, 301, 4, True)),
                         (OP_ON, 3, 301, 4, True))
        self.assertRaises(ValueError, parse_command, bytes(7))

    def test_current_saturates(self):
        f = channel_frame((False, False, 0, 10 ** 7, 0, 0, 300, 999))
        self.assertEqual(f[1:4], bytes([0xFF, 0xFF, 0x07]))
        self.assertEqual(f[6:8], bytes([255, 255]))


class BroadcastTest(unittest.TestCase):
    def test_schedule(self):
        r = rig()
        node = CanNode(r.board, KEY, r.hal.random_bytes, rate_hz=10)
        first = node.poll(r.hal.now)
        self.assertIn(ID_STATUS, ids(first))
        self.assertIn(ID_NONCE, ids(first))
        self.assertEqual([i for i in ids(first) if ID_CURRENTS <= i < ID_CURRENTS + 3],
                         [ID_CURRENTS, ID_CURRENTS + 1, ID_CURRENTS + 2])
        self.assertEqual(len([i for i in ids(first) if i >= ID_CHANNEL and i < ID_CHANNEL + 16]),
                         10)
        counts = {}
        for _ in range(100):  # 1 s in 10 ms steps
            r.run(10)
            for i in ids(node.poll(r.hal.now)):
                counts[i] = counts.get(i, 0) + 1
        self.assertEqual(counts[ID_STATUS], 1)
        self.assertEqual(counts[ID_NONCE], 1)
        self.assertTrue(9 <= counts[ID_CURRENTS] <= 11, counts[ID_CURRENTS])
        self.assertEqual(counts[ID_CHANNEL + 4], 1)

    def test_state_change_at_once(self):
        r = rig()
        node = CanNode(r.board, KEY, r.hal.random_bytes)
        node.poll(r.hal.now)
        r.run(10)
        node.poll(r.hal.now)
        r.board.switch(4, True)
        r.run(10)
        got = [f for f in node.poll(r.hal.now) if f[0] == ID_CHANNEL + 4]
        self.assertEqual(len(got), 1)
        self.assertIn(got[0][1][0] & 0xF, (ST_INRUSH, ST_ON))

    def test_node_offsets(self):
        r = rig()
        node = CanNode(r.board, KEY, r.hal.random_bytes, node=2)
        got = ids(node.poll(0))
        self.assertIn(ID_STATUS + 2, got)
        self.assertIn(ID_CURRENTS + 8, got)
        self.assertIn(ID_CHANNEL + 32, got)


class CommandTest(unittest.TestCase):
    def setUp(self):
        self.r = rig(channels={5: {"protected": True}})
        self.node = CanNode(self.r.board, KEY, self.r.hal.random_bytes)

    def send(self, cmd, tag=None, key=KEY, gap_ms=0, tag_b=True):
        now = self.r.hal.now
        out = self.node.receive(ID_CMD, cmd, now)
        tag = tag if tag is not None else command_tag(key, self.node.nonce, cmd)
        out += self.node.receive(ID_TAG_A, tag[:8], now + gap_ms)
        if tag_b:
            out += self.node.receive(ID_TAG_B, tag[8:], now + gap_ms)
        return out

    def result(self, frames):
        res = [f for f in frames if f[0] == ID_RESULT]
        self.assertEqual(len(res), 1, frames)
        op, ch, err, sp = struct.unpack_from("<BBHB", res[0][1])
        return op, ch, err, sp & 0xF, bool(sp & 0x10)

    def test_switch_on_and_off(self):
        self.assertEqual(self.result(self.send(command_frame(OP_ON, 3, counter=1))),
                         (OP_ON, 3, 0, ST_INRUSH, True))
        self.assertTrue(self.r.hal.cmd[3])
        self.assertEqual(self.result(self.send(command_frame(OP_OFF, 3, counter=2)))[2:],
                         (0, ST_OFF, False))
        self.assertFalse(self.r.hal.cmd[3])

    def test_refusals_change_nothing(self):
        cmd = command_frame(OP_ON, 3, counter=1)
        self.assertEqual(self.result(self.send(cmd, key=b"k" * 32))[2], E_BAD_TAG)
        self.assertFalse(self.r.hal.cmd[3])
        self.assertEqual(self.result(self.send(cmd, gap_ms=150))[2], E_AUTH_REQUIRED)
        self.assertFalse(self.r.hal.cmd[3])
        self.assertEqual(self.node.receive(ID_CMD, cmd, self.r.hal.now), [])
        self.r.run(200)
        self.assertEqual(self.result(self.node.poll(self.r.hal.now))[2], E_AUTH_REQUIRED)
        self.assertFalse(self.r.hal.cmd[3])
        self.assertEqual(self.result(self.send(cmd))[2], 0)
        self.r.board.switch(3, False)
        self.assertEqual(self.result(self.send(cmd))[2], E_REPLAYED)
        self.assertFalse(self.r.hal.cmd[3])

    def test_no_key_and_protected(self):
        node = CanNode(self.r.board, None, self.r.hal.random_bytes)
        self.node = node
        self.assertEqual(self.result(self.send(command_frame(OP_ON, 3, counter=1)))[2],
                         E_AUTH_REQUIRED)
        self.assertFalse(self.r.hal.cmd[3])
        self.node = CanNode(self.r.board, KEY, self.r.hal.random_bytes)
        self.send(command_frame(OP_ON, 5, counter=1))
        self.assertEqual(self.result(self.send(command_frame(OP_OFF, 5, counter=2)))[2],
                         E_PROTECTED)
        self.assertTrue(self.r.hal.cmd[5])
        self.assertEqual(self.result(self.send(command_frame(OP_OFF, 5, True, 0, 3)))[2], 0)

    def test_cycle(self):
        self.send(command_frame(OP_ON, 2, counter=1))
        self.assertEqual(self.result(self.send(command_frame(OP_CYCLE, 2, False, 3, 2)))[2:],
                         (0, ST_OFF, False))
        self.r.run(400)
        self.assertTrue(self.r.hal.cmd[2])

    def test_garbage_frames_change_nothing(self):
        self.assertEqual(self.result(self.node.receive(ID_CMD, b"\x01\x02", 0))[2], E_MALFORMED)
        self.assertEqual(self.node.receive(ID_TAG_B, bytes(8), 0), [])
        self.assertEqual(self.node.receive(0x7FF, bytes(8), 0), [])
        self.assertEqual(self.r.hal.cmd, [False] * 10)


class MalformedTest(unittest.TestCase):
    """Frames of the command ids that are not 8 bytes are answered, never ignored."""

    setUp = CommandTest.setUp
    send = CommandTest.send
    result = CommandTest.result

    def test_short_command_is_answered_with_105(self):
        out = self.node.receive(ID_CMD, command_frame(OP_ON, 3, counter=1)[:5], self.r.hal.now)
        self.assertEqual(self.result(out), (OP_ON, 3, E_MALFORMED, ST_OFF, False))
        out = self.node.receive(ID_CMD, b"", self.r.hal.now)
        self.assertEqual(self.result(out)[:3], (0, 0, E_MALFORMED))
        self.assertFalse(self.r.hal.cmd[3])

    def test_short_tag_ends_the_pending_command(self):
        cmd = command_frame(OP_ON, 3, counter=1)
        tag = command_tag(KEY, self.node.nonce, cmd)
        now = self.r.hal.now
        self.assertEqual(self.node.receive(ID_CMD, cmd, now), [])
        self.assertEqual(self.result(self.node.receive(ID_TAG_A, tag[:7], now))[2],
                         E_MALFORMED)
        self.assertEqual(self.node.receive(ID_TAG_B, tag[8:], now), [])  # nothing pending
        self.assertFalse(self.r.hal.cmd[3])
        self.assertEqual(self.result(self.send(cmd))[2], 0)  # the counter was not spent

    def test_unknown_op_is_303_and_changes_nothing(self):
        self.assertEqual(self.result(self.send(command_frame(9, 3, counter=1)))[:3],
                         (9, 3, E_BAD_VALUE))
        self.assertFalse(self.r.hal.cmd[3])
