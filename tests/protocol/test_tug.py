"""The tug codec (``protocol/tug.py``) on both interpreters: golden bytes as the original code
packs them, frames fed whole, one byte at a time and after garbage, the original REQUEST's
stray byte (every value), cut frames, wrong lengths and directions, and the capped buffer."""

import struct
import unittest

from protocol import tug as tw
from protocol.constants import E_BAD_CHANNEL, E_INHIBITED, E_LATCHED, E_PROTECTED, E_SWITCH_FAULT
from protocol.errors import LocalProtocolError
from tests.protocol.util import GARBAGE, chunks

HOST_FRAMES = [tw.set_frequency(200), tw.request(), tw.channel(3, True), tw.channel(9, False),
               tw.encode(tw.REQUEST, b"\x02")]
BOARD_FRAMES = [tw.specs([(1.5, 24.0), (5.0, 24.0)]),
                tw.measurements([(1, 0.25, 24.0), (0, 0.0, 0.0)]), tw.ack(0), tw.ack(4),
                tw.measurements([])]


def decode(accept, data, how="whole"):
    d = tw.TugDecoder(accept)
    out = []
    for chunk in chunks(data, how):
        d.feed(chunk)
        out.extend(d.frames())
    return out


def frames(events):
    return [e for e in events if isinstance(e, tw.Frame)]


def raw(frame):
    return tw.encode(frame.command, frame.payload)


class TestGolden(unittest.TestCase):
    def test_frames_as_the_original_packs_them(self):
        # Message.cpp: 02 01 01 00 c8 (main.cpp asks 200), 02 04 02 00 ch st, 02 03 00 00
        self.assertEqual(tw.set_frequency(200), bytes([2, 1, 1, 0, 200]))
        self.assertEqual(tw.channel(3, True), bytes([2, 4, 2, 0, 3, 1]))
        self.assertEqual(tw.channel(3, False), bytes([2, 4, 2, 0, 3, 0]))
        self.assertEqual(tw.request(), bytes([2, 3, 0, 0]))
        # Board.cpp send_Ack: five bytes, one error byte
        self.assertEqual(tw.ack(), bytes([2, 5, 1, 0, 0]))
        self.assertEqual(tw.specs([(1.5, 24.0)]),
                         bytes.fromhex("02000900" "01" "0000c03f" "0000c041"))
        self.assertEqual(tw.measurements([(1, 0.25, 24.0)]),
                         bytes.fromhex("02020a00" "01" "01" "0000803e" "0000c041"))

    def test_parse(self):
        got = frames(decode(tw.FROM_BOARD, b"".join(BOARD_FRAMES)))
        self.assertEqual(tw.parse_specs(got[0].payload), [(1.5, 24.0), (5.0, 24.0)])
        self.assertEqual(tw.parse_measurements(got[1].payload),
                         [(1, 0.25, 24.0), (0, 0.0, 0.0)])
        self.assertEqual(got[3].payload, b"\x04")

    def test_builders_refuse_what_does_not_fit(self):
        for bad in (lambda: tw.channel(256, True), lambda: tw.set_frequency(300),
                    lambda: tw.ack(-1), lambda: tw.specs([(1.0, 1.0)] * 256)):
            with self.assertRaises(LocalProtocolError):
                bad()

    def test_ack_codes_and_errors(self):
        self.assertEqual(tw.ack_code(0), tw.ACK_OK)
        self.assertEqual(tw.ack_code(E_PROTECTED), tw.ACK_PROTECTED)
        self.assertEqual(tw.ack_code(E_LATCHED), tw.ACK_LATCHED)
        self.assertEqual(tw.ack_code(E_SWITCH_FAULT), tw.ACK_REFUSED)
        self.assertEqual(tw.error_of(tw.ACK_OK), 0)
        self.assertEqual(tw.error_of(tw.ACK_BAD_CHANNEL), E_BAD_CHANNEL)
        self.assertEqual(tw.error_of(tw.ACK_READ_ONLY), E_INHIBITED)
        self.assertEqual(tw.error_of(200), E_INHIBITED)
        for code in tw.ACK_TEXT:
            if code:
                self.assertTrue(tw.error_of(code))


class TestDecoder(unittest.TestCase):
    def test_every_feed_both_directions(self):
        for accept, sent in ((tw.FROM_HOST, HOST_FRAMES), (tw.FROM_BOARD, BOARD_FRAMES)):
            for how in ("whole", "bytewise", "garbage"):
                with self.subTest(how=how):
                    out = decode(accept, b"".join(sent), how)
                    self.assertEqual([raw(f) for f in frames(out)], sent)
                    bad = [e for e in out if isinstance(e, tw.Bad)]
                    self.assertEqual(sum(b.skipped for b in bad),
                                     len(GARBAGE) if how == "garbage" else 0)

    def test_the_original_request_with_any_stray_byte(self):
        # Message.cpp 104-123: length 0, and the heap's next byte is sent too
        after = tw.channel(3, True) + tw.request() + b"\x02" + tw.set_frequency(200)
        for stray in range(256):
            for how in ("whole", "bytewise"):
                data = bytes([2, 3, 0, 0, stray]) + after
                got = [raw(f) for f in frames(decode(tw.FROM_HOST, data, how))]
                self.assertEqual(got, [tw.request(), tw.channel(3, True), tw.request(),
                                       tw.set_frequency(200)], "stray %d %s" % (stray, how))

    def test_the_wrong_direction_is_dropped(self):
        out = decode(tw.FROM_HOST, tw.ack(0) + tw.measurements([(1, 1.0, 1.0)])
                     + tw.channel(2, True))
        self.assertEqual(frames(out), [tw.Frame(tw.CHANNEL, b"\x02\x01")])
        out = decode(tw.FROM_BOARD, tw.channel(2, True) + tw.ack(0))
        self.assertEqual(frames(out), [tw.Frame(tw.ACK, b"\x00")])

    def test_wrong_lengths_are_dropped_and_what_follows_decodes(self):
        for bad in (tw.encode(tw.CHANNEL, b"\x01"), tw.encode(tw.SET_FREQ, b""),
                    tw.encode(tw.REQUEST, b"\x00\x00"), tw.encode(tw.CHANNEL, b"\x01\x01\x01")):
            for how in ("whole", "bytewise"):
                out = decode(tw.FROM_HOST, bad + tw.channel(1, False), how)
                self.assertEqual([raw(f) for f in frames(out)], [tw.channel(1, False)])
                self.assertIsInstance(out[0], tw.Bad)
        count_lies = struct.pack("<BBHB", 2, 2, 10, 2) + bytes(9)  # says 2, holds 1
        for how in ("whole", "bytewise"):
            out = decode(tw.FROM_BOARD, count_lies + tw.ack(0), how)
            self.assertEqual(frames(out), [tw.Frame(tw.ACK, b"\x00")])

    def test_a_cut_channel_frame_never_switches(self):
        whole = tw.channel(3, True)
        nxt = tw.channel(5, False) + tw.request()
        for cut in range(1, len(whole)):
            for how in ("whole", "bytewise"):
                got = frames(decode(tw.FROM_HOST, whole[:cut] + nxt, how))
                for f in got:
                    if f.command == tw.CHANNEL and f.payload[1] <= 1:
                        self.assertEqual(raw(f), tw.channel(5, False), "cut %d" % cut)

    def test_need_more_data(self):
        d = tw.TugDecoder(tw.FROM_BOARD)
        frame = tw.measurements([(1, 2.0, 3.0)] * 3)
        d.feed(frame[:-1])
        self.assertIsNone(d.next())
        self.assertEqual(d.pending, len(frame) - 1)
        d.feed(frame[-1:])
        self.assertEqual(raw(d.next()), frame)
        self.assertIsNone(d.next())

    def test_a_flood_is_capped_and_never_raises(self):
        d = tw.TugDecoder(tw.FROM_HOST)
        flood = bytes([2, 1]) * 4000 + bytes(range(256)) * 20
        for i in range(0, len(flood), 1000):
            d.feed(flood[i:i + 1000])
            self.assertLessEqual(d.pending, tw.BUFFER_CAP)
        d.feed(bytes(tw.BUFFER_CAP + 10))  # more than the cap without draining
        self.assertLessEqual(d.pending, tw.BUFFER_CAP)
        out = d.frames()
        self.assertIsInstance(out[0], tw.Bad)
        self.assertEqual(out[0].reason, "receive buffer overflow")
        d.feed(tw.channel(1, True))
        self.assertEqual(frames(d.frames()), [tw.Frame(tw.CHANNEL, b"\x01\x01")])
