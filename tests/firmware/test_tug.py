"""The board's tug front end (``firmware/tug.py``) on a real Board (test HAL), on simulated time,
on both interpreters: what the original host gets, and what it can never make the board do."""

import unittest

from benchmarks._rigs.testhal import Rig
from firmware.tug import TugSession
from protocol import tug as tw
from protocol.constants import ST_LATCHED, ST_TRIPPED

CHANNELS = {2: {"protected": True, "powerup": True, "rated_ma": 5000},
            7: {"rated_ma": 1000, "short_retries": 0, "retry_ms": [], "inrush_ms": 0}}


class Link:
    """A TugSession on a Rig, with the host's decoder."""

    def __init__(self, switching=True, **kw):
        self.r = Rig(channels=kw.pop("channels", CHANNELS), **kw)
        self.r.run(500)  # the protected PC comes on at power-up
        self.s = TugSession(self.r.board, switching, self.r.hal.now)
        self.host = tw.TugDecoder(tw.FROM_BOARD)
        self.host.feed(self.s.start(self.r.hal.now))

    def send(self, data):
        now = self.r.hal.now
        self.host.feed(self.s.receive(data, now) + self.s.poll(now))
        return self.got()

    def got(self):
        out = self.host.frames()
        for e in out:
            assert isinstance(e, tw.Frame), e
        return out

    def run(self, ms):
        """Step the board; the broadcasts due on the way, as ``Net.pump`` collects them."""
        end = self.r.hal.now + ms
        while self.r.hal.now < end:
            self.r.run(10)
            self.host.feed(self.s.poll(self.r.hal.now))
        return self.got()

    def ack(self, data):
        got = self.send(data)
        assert len(got) == 1 and got[0].command == tw.ACK, got
        return got[0].payload[0]

    def measure(self):
        got = self.send(tw.request())
        assert [f.command for f in got] == [tw.ACK, tw.MEASUREMENTS], got
        assert got[0].payload == b"\x00"
        return tw.parse_measurements(got[1].payload)


class TestWhatTheOriginalHostGets(unittest.TestCase):
    def test_specifications_on_connect(self):
        link = Link()
        specs = link.got()
        self.assertEqual([f.command for f in specs], [tw.SPECS])
        got = tw.parse_specs(specs[0].payload)
        self.assertEqual(len(got), 10)
        self.assertEqual(got[2], (5.0, 24.0))
        self.assertEqual(got[0], (1.0, 24.0))

    def test_once_a_second_whatever_rate_is_asked(self):
        for rate in (200, 0, 1, 255):
            link = Link()
            link.got()
            self.assertEqual(link.run(3000), [])  # nothing until asked
            first = link.send(tw.set_frequency(rate))
            self.assertEqual([f.command for f in first], [tw.MEASUREMENTS])
            self.assertEqual(link.run(990), [])
            self.assertEqual(len(link.run(10)), 1)  # 1000 ms after the first
            self.assertEqual(len(link.run(5000)), 5)
            link.send(tw.set_frequency(rate))  # asked again: one at once, still 1 Hz
            self.assertEqual(len(link.run(3000)), 3)

    def test_request_gets_an_ack_and_measurements(self):
        link = Link()
        link.got()
        chans = link.measure()
        self.assertEqual(len(chans), 10)
        self.assertEqual(chans[2][0], tw.STATUS_ON)
        self.assertEqual(chans[2][2], 24.0)
        self.assertEqual(chans[0], (tw.STATUS_OFF, 0.0, 0.0))
        # the original: length 0 and a stray byte; a stray 0x02 swallows nothing
        got = link.send(bytes([2, 3, 0, 0, 2]) + tw.channel(5, True))
        self.assertEqual([f.command for f in got], [tw.ACK, tw.MEASUREMENTS, tw.ACK])
        self.assertEqual(got[2].payload, b"\x00")

    def test_channel_switches_and_acks_one_byte(self):
        link = Link()
        link.got()
        self.assertEqual(link.ack(tw.channel(5, True)), tw.ACK_OK)
        link.run(20)
        self.assertEqual(link.measure()[5][0], tw.STATUS_ON)
        self.assertTrue(link.r.board.channels[5].commanded)
        self.assertEqual(link.ack(tw.channel(5, False)), tw.ACK_OK)
        link.run(20)
        self.assertEqual(link.measure()[5][0], tw.STATUS_OFF)

    def test_status_is_0_or_1_whatever_the_faults(self):
        chans = dict(CHANNELS)
        chans[3] = {"open_load_ma": 100, "open_load_ms": 100}
        link = Link(channels=chans)
        link.got()
        link.ack(tw.channel(3, True))
        link.ack(tw.channel(7, True))
        link.r.hal.load_ma[3] = 10  # on, below the open-load level: a live fault
        link.r.hal.load_ma[7] = 20000
        link.run(500)
        self.assertTrue(link.r.board.channels[3].live)
        self.assertEqual(link.r.state(7), ST_LATCHED)
        chans = link.measure()
        self.assertEqual(chans[3][0], tw.STATUS_ON)
        self.assertEqual(chans[7][0], tw.STATUS_OFF)
        self.assertEqual({c[0] for c in chans}, {0, 1})


class TestWhatItCannotDo(unittest.TestCase):
    def test_read_only_unless_started_with_switching(self):
        link = Link(switching=False)
        link.got()
        self.assertEqual(link.ack(tw.channel(5, True)), tw.ACK_READ_ONLY)
        self.assertEqual(link.ack(tw.channel(2, False)), tw.ACK_READ_ONLY)
        link.run(50)
        self.assertFalse(link.r.hal.cmd[5])
        self.assertTrue(link.r.hal.cmd[2])

    def test_protected_never_switched_off(self):
        link = Link()
        link.got()
        self.assertEqual(link.ack(tw.channel(2, False)), tw.ACK_PROTECTED)
        link.run(50)
        self.assertTrue(link.r.hal.cmd[2])
        self.assertEqual(link.ack(tw.channel(2, True)), tw.ACK_OK)  # on is allowed

    def test_bad_channel_and_state_change_nothing(self):
        link = Link()
        link.got()
        before = list(link.r.hal.cmd)
        switched = len(link.r.hal.switch_log)
        self.assertEqual(link.ack(tw.channel(10, True)), tw.ACK_BAD_CHANNEL)
        self.assertEqual(link.ack(tw.channel(95, False)), tw.ACK_BAD_CHANNEL)  # shut_down's
        self.assertEqual(link.ack(tw.encode(tw.CHANNEL, b"\x05\x02")), tw.ACK_BAD_STATE)
        self.assertEqual(link.ack(tw.encode(tw.CHANNEL, b"\x02\xff")), tw.ACK_BAD_STATE)
        link.run(50)
        self.assertEqual(link.r.hal.cmd, before)
        self.assertEqual(len(link.r.hal.switch_log), switched)

    def test_latched_stays_latched(self):
        link = Link()
        link.got()
        link.ack(tw.channel(7, True))
        link.r.hal.load_ma[7] = 20000
        link.run(200)
        self.assertEqual(link.r.state(7), ST_LATCHED)
        self.assertEqual(link.ack(tw.channel(7, True)), tw.ACK_LATCHED)
        self.assertNotEqual(link.r.state(7), ST_TRIPPED)

    def test_malformed_frames_are_dropped_unanswered(self):
        link = Link()
        link.got()
        junk = [tw.encode(tw.CHANNEL, b"\x05"), tw.encode(tw.CHANNEL, b"\x05\x01\x01"),
                tw.ack(0), tw.measurements([(1, 1.0, 1.0)]), tw.encode(9, b"\x05\x01"),
                b"\xff\x00\x02\x02\x02\x04"]
        for data in junk:
            self.assertEqual(link.send(data), [], data)
        # a cut CHANNEL, then the next frame: its 0x02 lands in the state byte: refused
        got = link.send(bytes([2, 4, 2, 0, 5]) + tw.channel(5, True))
        self.assertEqual(got, [tw.Frame(tw.ACK, bytes([tw.ACK_BAD_STATE]))])
        link.run(50)
        self.assertFalse(link.r.hal.cmd[5])
        self.assertGreater(link.s.bad, 0)
        self.assertEqual(link.s.rate_hz, 0)

    def test_a_full_queue_skips_broadcasts(self):
        link = Link()
        link.got()
        link.send(tw.set_frequency(10))
        now = link.r.hal.now + 1000
        self.assertEqual(link.s.poll(now, False), b"")
        self.assertEqual(link.s.poll(now + 999, True), b"")  # skipped, not delayed
        self.assertTrue(link.s.poll(now + 1000, True))

    def test_at_most_28_channels_in_a_frame(self):
        link = Link(n=30, channels={})
        specs = tw.parse_specs(link.got()[0].payload)
        self.assertEqual(len(specs), tw.MAX_CHANNELS)
        self.assertEqual(len(link.measure()), tw.MAX_CHANNELS)
        self.assertLess(len(tw.measurements([(0, 0.0, 0.0)] * tw.MAX_CHANNELS)) - 4, 256)
        self.assertEqual(link.ack(tw.channel(29, True)), tw.ACK_BAD_CHANNEL)
