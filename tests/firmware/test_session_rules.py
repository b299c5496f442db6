"""Session rules found by independent peers (issue 12): the serial line's incomplete-frame
timeout, and a new session (HELLO_REQUEST) that starts the subscription and ``seq`` afresh."""

import unittest

from firmware.session import FRAME_GAP_MS, Session
from protocol.connection import HOST, Connection
from protocol.constants import E_BAD_TAG
from protocol.framing import encode_frame
from protocol.messages import (
    Ack,
    AuthPing,
    GetState,
    Hello,
    HelloRequest,
    Measurement,
    Ping,
    Pong,
    Subscribe,
)
from tests.firmware.test_session import KEY, Counter, rig


class Serial:
    """A session as the serial front end runs it, and the host end."""

    def __init__(self, gap=FRAME_GAP_MS):
        self.r = rig()
        self.s = Session(self.r.board, KEY, Counter(), "1.2.3", 0x7F, self.r.hal.now,
                         frame_gap_ms=gap)
        self.host = Connection(HOST, KEY)
        self.host.receive_data(self.s.start(self.r.hal.now))
        self.host.events()

    def send(self, raw, at_ms):
        self.r.run(at_ms - self.r.hal.now)
        self.host.receive_data(self.s.receive(raw, self.r.hal.now))
        return self.host.events()


class FrameGapTest(unittest.TestCase):
    def test_partial_frame_dropped_after_250_ms_of_silence(self):
        ser = Serial()
        ping = encode_frame(Ping.TYPE, 9, b"\x00\x00\x00\x2a")
        # 7 bytes of a frame that announces a long payload, then silence
        partial = encode_frame(Ping.TYPE, 3, bytes(231))[:7]
        self.assertEqual(ser.send(partial, 0), [])
        got = ser.send(ping, FRAME_GAP_MS + 10)
        self.assertEqual(len(got), 1)
        self.assertIsInstance(got[0], Pong)
        self.assertEqual((got[0].req_id, got[0].token), (9, 42))

    def test_a_frame_split_by_shorter_pauses_still_arrives(self):
        ser = Serial()
        ping = encode_frame(Ping.TYPE, 5, b"\x00\x00\x00\x07")
        t = 0
        got = []
        for i in range(len(ping)):
            t += FRAME_GAP_MS - 50
            got += ser.send(ping[i:i + 1], t)
        self.assertEqual([(type(m).__name__, m.req_id) for m in got], [("Pong", 5)])

    def test_tcp_sessions_have_no_gap_rule(self):
        ser = Serial(gap=0)
        partial = encode_frame(Ping.TYPE, 3, b"\x00\x00\x00\x01")[:7]
        ser.send(partial, 0)
        self.assertEqual(ser.send(b"\x00", 1000), [])  # still waiting for that frame


class NewSessionTest(unittest.TestCase):
    def test_hello_request_resets_subscription_and_seq(self):
        ser = Serial()
        sub = Subscribe(100, req_id=1)
        self.assertIsInstance(ser.send(ser.host.send(sub), 0)[0], Ack)
        seqs = []
        for _ in range(5):
            ser.r.run(10)
            ser.host.receive_data(ser.s.poll(ser.r.hal.now))
            seqs += [m.seq for m in ser.host.events() if isinstance(m, Measurement)]
        self.assertEqual(seqs, [1, 2, 3, 4, 5])
        got = ser.send(ser.host.send(HelloRequest(req_id=2)), ser.r.hal.now)
        self.assertIsInstance(got[0], Hello)
        self.assertEqual(got[0].req_id, 2)  # the HELLO answers the request
        for _ in range(5):  # a new session: no subscription carried over
            ser.r.run(10)
            ser.host.receive_data(ser.s.poll(ser.r.hal.now))
            self.assertEqual(ser.host.events(), [])
        self.assertIsInstance(ser.send(ser.host.send(Subscribe(100, req_id=3)),
                                       ser.r.hal.now)[0], Ack)
        ser.r.run(10)
        ser.host.receive_data(ser.s.poll(ser.r.hal.now))
        first = [m.seq for m in ser.host.events() if isinstance(m, Measurement)]
        self.assertEqual(first, [1])  # each session counts from 1


class StrangerTest(unittest.TestCase):
    """Who is the host: a session whose request passed the HMAC check. Only its PINGs keep it
    open and feed the dead-man; a stranger that only PINGs goes idle."""

    def test_auth_ping_makes_the_session_the_hosts_until_a_new_hello(self):
        ser = Serial(gap=0)
        self.assertFalse(ser.s.authenticated)
        got = ser.send(ser.host.send(AuthPing(5, req_id=1)), 0)
        self.assertIsInstance(got[0], Pong)
        self.assertTrue(ser.s.authenticated)
        ser.send(ser.host.send(HelloRequest(req_id=2)), 10)
        self.assertFalse(ser.s.authenticated)  # a new session: not proven yet

    def test_a_wrong_key_proves_nothing(self):
        ser = Serial(gap=0)
        ser.host.key = b"\x55" * 32
        got = ser.send(ser.host.send(AuthPing(5, req_id=1)), 0)
        self.assertEqual(got[0].code, E_BAD_TAG)
        self.assertFalse(ser.s.authenticated)

    def test_a_strangers_pings_do_not_keep_it_open(self):
        ser = Serial(gap=0)
        for t in range(1000, 31000, 1000):
            ser.send(ser.host.send(Ping(t, req_id=t // 1000)), t)
        self.assertEqual(ser.s.idle_ms(31000), 31000)
        ser.send(ser.host.send(GetState(req_id=99)), 31000)  # a real request does
        self.assertEqual(ser.s.idle_ms(31000), 0)
        ser.send(ser.host.send(Subscribe(1, req_id=100)), 32000)
        self.assertEqual(ser.s.idle_ms(90000), 0)  # a subscriber reads: never idle

    def test_the_hosts_pings_keep_it_open(self):
        ser = Serial(gap=0)
        ser.send(ser.host.send(AuthPing(1, req_id=1)), 0)
        for t in range(1000, 31000, 1000):
            ser.send(ser.host.send(Ping(t, req_id=t // 1000 + 1)), t)
        self.assertEqual(ser.s.idle_ms(31000), 1000)
