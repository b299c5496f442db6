"""Modbus TCP request handling (firmware/modbus.py) on a real Board: map, writes, framing."""

import struct
import unittest

from benchmarks._rigs.testhal import Rig, config_text
from firmware.modbus import Framer, handle
from protocol.constants import ST_LATCHED, ST_OFF, ST_ON

ALLOWED = "10.0.0.5"


def rig(write=True, **kw):
    return Rig(board={"modbus_write": write, "modbus_allow": [ALLOWED]}, **kw)


def adu(pdu, tid=7, unit=3):
    return struct.pack(">HHHB", tid, 0, len(pdu) + 1, unit) + pdu


def ask(r, pdu, ip=ALLOWED):
    out = handle(r.board, adu(pdu), ip)
    tid, proto, length, unit = struct.unpack_from(">HHHB", out)
    assert (tid, proto, unit, length) == (7, 0, 3, len(out) - 6)
    return out[7:]


def regs(r, fc, addr, count):
    pdu = ask(r, struct.pack(">BHH", fc, addr, count))
    if pdu[0] != fc:
        raise AssertionError("exception %r" % pdu)
    return list(struct.unpack(">%dH" % count, pdu[2:]))


def bits(r, fc, addr, count):
    pdu = ask(r, struct.pack(">BHH", fc, addr, count))
    if pdu[0] != fc:
        raise AssertionError("exception %r" % pdu)
    return [(pdu[2 + i // 8] >> (i % 8)) & 1 for i in range(count)]


def exc(r, pdu, ip=ALLOWED):
    out = ask(r, pdu, ip)
    if not out[0] & 0x80:
        raise AssertionError("no exception: %r" % out)
    return out[1]


class ReadTest(unittest.TestCase):
    def test_input_registers(self):
        r = rig(channels={1: {"rated_ma": 5000}})
        r.hal.load_ma[1] = 1234
        r.board.switch(1, True)
        r.run(300)
        r.board.boot_id = 0xA1B2C3D4  # (the test HAL's random bytes are zeros)
        got = regs(r, 4, 0, 112)
        self.assertEqual(got[1], 1234)
        self.assertEqual(got[16 + 1], ST_ON)
        self.assertEqual(got[16 + 12], 0)  # channel 12 does not exist
        self.assertEqual(got[100], 24000)
        self.assertEqual((got[101] << 16) | got[102], 1234)
        self.assertEqual((got[103] << 16) | got[104], r.hal.now)
        self.assertEqual(got[108], 10)
        self.assertEqual(got[109], 1)
        self.assertEqual(got[110:112], [0xA1B2, 0xC3D4])  # the HELLO's boot id

    def test_coils_and_discrete(self):
        r = rig()
        r.board.switch(2, True)
        r.hal.stuck[4] = True
        r.hal.load_ma[4] = 500
        r.run(300)
        self.assertEqual(bits(r, 1, 0, 16), [0, 0, 1] + [0] * 13)
        d = bits(r, 2, 0, 32)
        self.assertEqual(d[2], 1)
        self.assertEqual(d[4], 1)  # stuck on: physical on
        self.assertEqual(d[16 + 4], 1)  # and a live fault

    def test_holding_layout(self):
        r = rig(channels={3: {"rated_ma": 70000 - 10001, "retry_ms": [100, 200],
                              "retry_reset_ms": 100000, "protected": True}})
        got = regs(r, 3, 1000 + 32 * 3, 22)
        self.assertEqual((got[0] << 16) | got[1], 59999)
        self.assertEqual(got[15], 1)
        self.assertEqual(got[16:20], [100, 200, 0, 0])
        self.assertEqual((got[20] << 16) | got[21], 100000)
        b = regs(r, 3, 900, 10)
        self.assertEqual((b[0] << 16) | b[1], 20000)
        self.assertEqual(b[6], 10)  # tick_ms
        self.assertEqual(regs(r, 3, 990, 1), [0])

    def test_errors(self):
        r = rig()
        self.assertEqual(exc(r, struct.pack(">BHH", 4, 100, 13)), 2)  # 112 is past the end
        self.assertEqual(exc(r, struct.pack(">BHH", 4, 0, 126)), 3)
        self.assertEqual(exc(r, struct.pack(">BHH", 1, 10, 7)), 2)
        self.assertEqual(exc(r, struct.pack(">BHH", 3, 899, 2)), 2)
        self.assertEqual(exc(r, bytes([0x2B, 0x0E, 1, 0])), 1)
        self.assertEqual(exc(r, bytes([4, 0])), 3)


class WriteTest(unittest.TestCase):
    def test_refused_without_permission(self):
        for r, ip in ((rig(write=False), ALLOWED), (rig(), "10.0.0.6")):
            self.assertEqual(exc(r, struct.pack(">BHH", 5, 1, 0xFF00), ip), 1)
            self.assertEqual(exc(r, struct.pack(">BHH", 6, 1000, 7), ip), 1)
            self.assertFalse(r.hal.cmd[1])
            self.assertEqual(r.board.cfg["channels"][0]["rated_ma"], 1000)

    def test_coils(self):
        r = rig()
        on = struct.pack(">BHH", 5, 1, 0xFF00)
        self.assertEqual(ask(r, on), on)
        self.assertTrue(r.hal.cmd[1])
        self.assertEqual(exc(r, struct.pack(">BHH", 5, 1, 0x1234)), 3)
        self.assertEqual(ask(r, struct.pack(">BHHBB", 15, 0, 3, 1, 0b101)),
                         struct.pack(">BHH", 15, 0, 3))
        self.assertEqual(r.hal.cmd[:3], [True, False, True])
        self.assertEqual(exc(r, struct.pack(">BHH", 5, 12, 0xFF00)), 2)

    def test_refused_by_board(self):
        r = rig(channels={6: {"protected": True, "powerup": True},
                          7: {"short_retries": 0, "retry_ms": [], "inrush_ms": 0}})
        r.run(500)
        self.assertEqual(exc(r, struct.pack(">BHH", 5, 6, 0)), 4)
        self.assertTrue(r.hal.cmd[6])
        r.board.switch(7, True)
        r.hal.load_ma[7] = 50000
        r.run(100)
        self.assertEqual(r.state(7), ST_LATCHED)
        self.assertEqual(exc(r, struct.pack(">BHH", 5, 7, 0xFF00)), 4)
        self.assertFalse(r.hal.cmd[7])

    def test_registers(self):
        r = rig()
        base = 1000 + 32 * 2
        w = struct.pack(">BHH", 6, base + 1, 2500)
        self.assertEqual(ask(r, w), w)
        self.assertEqual(r.board.cfg["channels"][2]["rated_ma"], 2500)
        self.assertEqual(exc(r, struct.pack(">BHH", 6, base + 1, 0)), 3)  # rated_ma 0: refused
        self.assertEqual(r.board.cfg["channels"][2]["rated_ma"], 2500)
        self.assertEqual(exc(r, struct.pack(">BHH", 6, base + 15, 1)), 2)  # protected
        self.assertFalse(r.board.cfg["channels"][2]["protected"])
        self.assertEqual(exc(r, struct.pack(">BHH", 6, base + 25, 1)), 2)
        vals = struct.pack(">4H", 0, 70, 300, 0)
        pdu = struct.pack(">BHHB", 16, base + 16, 4, 8) + vals
        self.assertEqual(ask(r, pdu), struct.pack(">BHH", 16, base + 16, 4))
        self.assertEqual(r.board.cfg["channels"][2]["retry_ms"], [70, 300])
        self.assertEqual(ask(r, struct.pack(">BHH", 6, 906, 20))[0], 6)
        self.assertEqual(r.board.cfg["board"]["tick_ms"], 20)

    def test_save_command(self):
        r = rig()
        self.assertEqual(exc(r, struct.pack(">BHH", 6, 990, 2)), 3)
        ask(r, struct.pack(">BHH", 6, 1000 + 1, 3333))
        self.assertEqual(ask(r, struct.pack(">BHH", 6, 990, 1))[0], 6)
        self.assertIn(b"3333", config_text(r.hal.storage))


class FramerTest(unittest.TestCase):
    def test_split_and_bad(self):
        f = Framer()
        a = adu(struct.pack(">BHH", 4, 0, 1))
        data = a + a
        for i in range(len(data)):
            f.feed(data[i:i + 1])
        self.assertEqual(f.next(), a)
        self.assertEqual(f.next(), a)
        self.assertIsNone(f.next())
        f.feed(struct.pack(">HHHB", 1, 5, 6, 1) + bytes(5))
        self.assertIsNone(f.next())
        self.assertTrue(f.bad)
        g = Framer()
        g.feed(struct.pack(">HHHB", 1, 0, 255, 1))
        self.assertIsNone(g.next())
        self.assertTrue(g.bad)

    def test_state_after_off(self):
        r = rig()
        ask(r, struct.pack(">BHH", 5, 0, 0xFF00))
        ask(r, struct.pack(">BHH", 5, 0, 0))
        r.run(20)
        self.assertEqual(regs(r, 4, 16, 1), [ST_OFF])
