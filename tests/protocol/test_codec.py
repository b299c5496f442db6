"""The codec on both interpreters: every message round-trips, and bad bytes of every kind
become the documented error while the bytes that follow still decode.

Each test feeds its input whole, one byte at a time, and with garbage in front.
"""

import struct
import unittest

from protocol import messages as m
from protocol.connection import BOARD, HOST, Connection
from protocol.constants import (
    E_AUTH_REQUIRED,
    E_BAD_CRC,
    E_BAD_TAG,
    E_GARBAGE,
    E_MALFORMED,
    E_NO_SESSION,
    E_NOT_A_REQUEST,
    E_REPLAYED,
    E_TOO_LARGE,
    E_TRUNCATED,
    E_UNKNOWN_TYPE,
    E_VERSION,
)
from protocol.errors import LocalProtocolError
from protocol.framing import BUFFER_CAP, MAGIC, MAX_PAYLOAD, BadFrame, encode_frame, seal
from tests.protocol.samples import later_samples, samples
from tests.protocol.util import FEEDS, KEY, feed, hello, pair


def codes(events: list) -> list:  # type: ignore[type-arg]
    return [e.code if isinstance(e, BadFrame) else type(e).__name__ for e in events]


class TestRoundTrip(unittest.TestCase):
    def test_every_message_every_feed(self) -> None:
        for how in FEEDS:
            board, host = pair()
            for msg in samples() + later_samples():
                with self.subTest(msg=type(msg).__name__, how=how):
                    if msg.DIR == "B":
                        got = feed(host, board.send(msg), how)
                    else:
                        got = feed(board, host.send(msg), how)
                    self.assertEqual(got, [msg])

    def test_many_frames_in_one_chunk(self) -> None:
        board, host = pair()
        msgs = [s for s in samples() + later_samples() if s.DIR == "B"]
        data = b"".join(board.send(x) for x in msgs)
        for how in FEEDS:
            with self.subTest(how=how):
                self.assertEqual(feed(host, data, how), msgs)

    def test_request_ids_skip_zero(self) -> None:
        host = Connection(HOST)
        self.assertEqual(host.next_request_id(), 1)
        seen_zero = False
        last = 1
        for _ in range(0xFFFF):
            last = host.next_request_id()
            seen_zero = seen_zero or last == 0
        self.assertFalse(seen_zero)
        self.assertEqual(last, 1)  # wrapped from 65535 to 1


class TestBadFrames(unittest.TestCase):
    def setUp(self) -> None:
        self.board, self.host = pair()
        self.good = self.board.send(m.Pong(1, 2, req_id=9))

    def check_then_good(self, bad: bytes, expected: list) -> None:  # type: ignore[type-arg]
        """``bad`` yields the errors ``expected``; the good frame after it still decodes."""
        for how in FEEDS:
            with self.subTest(how=how):
                _, host = pair()
                got = feed(host, bad + self.good, how)
                self.assertEqual(codes(got), expected + ["Pong"])
                self.assertEqual(got[-1], m.Pong(1, 2, req_id=9))

    def test_truncated_then_stream_ends(self) -> None:
        for how in FEEDS:
            with self.subTest(how=how):
                _, host = pair()
                got = feed(host, self.good + self.good[:-3], how)
                host.receive_data(b"")
                got += host.events()
                self.assertEqual(codes(got), ["Pong", E_TRUNCATED])
                # and the connection still works afterwards
                self.assertEqual(codes(feed(host, self.good, how)), ["Pong"])

    def test_truncated_then_next_frame(self) -> None:
        self.check_then_good(self.good[:-3], [E_BAD_CRC])

    def test_truncate_on_timeout(self) -> None:
        _, host = pair()
        host.receive_data(self.good[:5])
        self.assertEqual(host.events(), [])
        host.truncate()
        got = host.events()
        self.assertEqual(codes(got), [E_TRUNCATED])
        self.assertEqual(codes(feed(host, self.good, "whole")), ["Pong"])

    def test_oversized(self) -> None:
        bad = MAGIC + struct.pack(">BBHH", 1, 0x04, 1, MAX_PAYLOAD + 1) + b"\x00" * 8
        self.check_then_good(bad, [E_TOO_LARGE])

    def test_wrong_crc(self) -> None:
        bad = self.good[:-1] + bytes(((self.good[-1] ^ 0x01),))
        self.check_then_good(bad, [E_BAD_CRC])

    def test_wrong_version(self) -> None:
        payload = m.Pong(5, 6).payload()
        bad = encode_frame(m.Pong.TYPE, 33, payload, version=2)
        self.check_then_good(bad, [E_VERSION])
        _, host = pair()
        ev = feed(host, bad, "whole")[0]
        self.assertEqual((ev.version, ev.req_id, ev.of_type), (2, 33, m.Pong.TYPE))

    def test_unknown_type(self) -> None:
        self.check_then_good(encode_frame(0x55, 4, b"xyz"), [E_UNKNOWN_TYPE])

    def test_malformed_payloads(self) -> None:
        bad_ones = (
            encode_frame(m.Pong.TYPE, 1, b"\x00\x01"),  # too short
            encode_frame(m.Pong.TYPE, 1, b"\x00" * 9),  # a byte too many
            encode_frame(m.Switched.TYPE, 1, b"\x03\x02\x01\x02"),  # flag byte 2
            encode_frame(m.Error.TYPE, 1, b"\x01\x2d\x20\x03\xff\xfe\xfd"),  # not UTF-8
            encode_frame(m.Error.TYPE, 1, b"\x01\x2d\x20\x09ab"),  # string past the end
            encode_frame(m.Measurement.TYPE, 1, b"\x00" * 14 + b"\x05" + b"\x00" * 4),
        )
        for bad in bad_ones:
            self.check_then_good(bad, [E_MALFORMED])

    def test_every_single_bit_flip(self) -> None:
        """No flipped bit of a frame decodes as a message; the next frame always does."""
        frame = self.board.send(m.Switched(3, True, True, 2, req_id=77))
        for bit in range(len(frame) * 8):
            bad = bytearray(frame)
            bad[bit // 8] ^= 1 << (bit % 8)
            _, host = pair()
            got = feed(host, bytes(bad) + self.good + self.good, "whole")
            host.receive_data(b"")  # a flipped length may still be waiting for bytes
            got += host.events()
            msgs = [e for e in got if not isinstance(e, BadFrame)]
            with self.subTest(bit=bit):
                self.assertTrue(any(isinstance(e, BadFrame) for e in got))
                self.assertTrue(all(isinstance(x, m.Pong) for x in msgs))
                self.assertGreaterEqual(len(msgs), 1)

    def test_wrong_direction(self) -> None:
        frame = encode_frame(m.Pong.TYPE, 3, m.Pong(1, 1).payload())
        for how in FEEDS:
            with self.subTest(how=how):
                board = Connection(BOARD, KEY)
                board.send(hello())
                got = feed(board, frame, how)
                self.assertEqual(codes(got), [E_NOT_A_REQUEST])

    def test_request_with_req_id_0_is_refused(self) -> None:
        """0 marks pushes: the board refuses a request that uses it (its ERROR carries 0)."""
        board, host = pair()
        host.counter = 0
        signed = host.send(m.Switch(2, True, req_id=0))
        for frame in (encode_frame(m.GetState.TYPE, 0, b""), signed):
            got = feed(board, frame, "whole")
            self.assertEqual(codes(got), [E_MALFORMED])
            self.assertEqual((got[0].req_id, got[0].text), (0, "malformed payload: req_id 0 "
                                                                 "is reserved for pushes"))
            reply = board.error_reply(got[0])
            self.assertIsNotNone(reply)
        self.assertEqual(board.counter, 0)  # the signed one was refused before its counter


class TestAuthentication(unittest.TestCase):
    def test_signed_command_accepted_once(self) -> None:
        for how in FEEDS:
            with self.subTest(how=how):
                board, host = pair()
                frame = host.send(m.Switch(3, True, req_id=1))
                got = feed(board, frame + frame, how)
                self.assertEqual(codes(got), ["Switch", E_REPLAYED])

    def test_out_of_order_counter(self) -> None:
        board, host = pair()
        first = host.send(m.Clear(1, req_id=1))
        second = host.send(m.Clear(2, req_id=2))
        self.assertEqual(codes(feed(board, second + first, "whole")), ["Clear", E_REPLAYED])

    def test_bad_tag(self) -> None:
        board, host = pair()
        frame = bytearray(host.send(m.Switch(3, False, req_id=1)))
        frame[9] ^= 0x01  # the channel number: 3 -> 2, CRC made good again
        forged = seal(bytes(frame[:-4]))
        for how in FEEDS:
            with self.subTest(how=how):
                board, _ = pair()
                self.assertEqual(codes(feed(board, forged, how)), [E_BAD_TAG])

    def test_wrong_key(self) -> None:
        board = Connection(BOARD, KEY)
        host = Connection(HOST, b"another key")
        host.receive_data(board.send(hello()))
        host.events()
        got = feed(board, host.send(m.Switch(1, True, req_id=1)), "whole")
        self.assertEqual(codes(got), [E_BAD_TAG])

    def test_no_key_on_board(self) -> None:
        board = Connection(BOARD, None)
        host = Connection(HOST, KEY)
        host.receive_data(board.send(hello()))
        host.events()
        got = feed(board, host.send(m.Switch(1, True, req_id=1)), "whole")
        self.assertEqual(codes(got), [E_AUTH_REQUIRED])

    def test_no_session_on_board(self) -> None:
        _, host = pair()
        fresh = Connection(BOARD, KEY)
        got = feed(fresh, host.send(m.Switch(1, True, req_id=1)), "whole")
        self.assertEqual(codes(got), [E_NO_SESSION])

    def test_unsigned_actuation(self) -> None:
        board, _ = pair()
        bare = encode_frame(m.Switch.TYPE, 1, m.Switch(1, True).payload())
        self.assertEqual(codes(feed(board, bare, "whole")), [E_AUTH_REQUIRED])

    def test_new_session_needs_new_signatures(self) -> None:
        board, host = pair()
        old = host.send(m.Switch(1, True, req_id=1))
        host.receive_data(board.send(hello(bytes(16))))  # a new session, a new nonce
        host.events()
        self.assertEqual(codes(feed(board, old, "whole")), [E_BAD_TAG])
        fresh = host.send(m.Switch(1, True, req_id=2))
        self.assertEqual(codes(feed(board, fresh, "whole")), ["Switch"])

    def test_reading_needs_no_key(self) -> None:
        board = Connection(BOARD, KEY)
        board.send(hello())
        host = Connection(HOST)  # no key at all
        got = feed(board, host.send(m.GetState(req_id=1)), "whole")
        self.assertEqual(codes(got), ["GetState"])

    def test_error_replies(self) -> None:
        board, host = pair()
        frame = bytearray(host.send(m.Switch(3, False, req_id=42)))
        frame[9] ^= 0x01
        bad = feed(board, seal(bytes(frame[:-4])), "whole")[0]
        reply = board.error_reply(bad)
        self.assertIsNotNone(reply)
        got = feed(host, reply or b"", "whole")
        self.assertEqual(got, [m.Error(E_BAD_TAG, m.Switch.TYPE, "bad authentication tag", 42)])
        self.assertIsNone(board.error_reply(BadFrame(E_BAD_CRC)))


class TestLocalErrors(unittest.TestCase):
    def test_misuse_raises_local_error(self) -> None:
        board, host = pair()
        with self.assertRaises(LocalProtocolError):
            Connection(HOST).send(m.Switch(1, True))  # no key
        with self.assertRaises(LocalProtocolError):
            Connection(HOST, KEY).send(m.Switch(1, True))  # no session
        with self.assertRaises(LocalProtocolError):
            board.send(m.Switch(1, True))  # a board does not send commands
        with self.assertRaises(LocalProtocolError):
            host.send(m.Pong(1, 1))
        with self.assertRaises(LocalProtocolError):
            host.send(m.Subscribe(300))  # does not fit a byte
        with self.assertRaises(LocalProtocolError):
            board.send(m.Error(1, 1, "x" * 300))
        many = [samples()[5].channels[0]] * 80  # 80 x 15 bytes > MAX_PAYLOAD
        with self.assertRaises(LocalProtocolError):
            board.send(m.State(0, 0, 0, 0, 0, 0, many))
        with self.assertRaises(LocalProtocolError):
            Connection("router")

    def test_feeding_without_draining(self) -> None:
        _, host = pair()
        host.receive_data(b"\x00" * BUFFER_CAP)
        with self.assertRaises(LocalProtocolError):
            host.receive_data(b"\x00")
        self.assertEqual(codes(host.events()), [E_GARBAGE])
        host.receive_data(b"\x00")  # drained: accepted again
