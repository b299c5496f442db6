"""SUBSCRIBE's ``per_frame``: the session samples at the subscribed rate and sends its readings
k at a time (MEASUREMENT_BATCH), on a real Board (test HAL, simulated clock), both interpreters.

What must hold: every reading is sampled on time and numbered as before; none waits longer
than k - 1 periods; an EVENT or any answer goes out only after the readings taken before it
(in order); a slow reader's skipped readings still spend their numbers; a bad ``per_frame``
is refused and changes nothing; a new session (HELLO) starts without batching.
"""

import unittest

from protocol.constants import E_BAD_VALUE, EV_TRIP
from protocol.messages import (
    Ack,
    Error,
    Event,
    Hello,
    HelloRequest,
    Measurement,
    MeasurementBatch,
    Ping,
    Pong,
    Subscribe,
    Switch,
    Switched,
)
from tests.firmware.test_session import Pair, rig


def run_for(p, ms, step=10):
    """Advance the board ``ms`` in ``step`` ms ticks; every push with the uptime it left at."""
    out = []
    for _ in range(ms // step):
        p.r.run(step)
        up = p.r.hal.now - p.r.board.boot_ms
        for e in p.pushes():
            out.append((up, e))
    return out


def readings(pushed):
    got = []
    for _, e in pushed:
        if isinstance(e, MeasurementBatch):
            got.extend(e.readings)
        elif isinstance(e, Measurement):
            got.append(e)
    return got


class BatchTest(unittest.TestCase):
    def test_sampled_at_the_rate_sent_k_at_a_time(self):
        p = Pair()
        p.r.hal.load_ma[0] = 321
        p.one(Switch(0, True), Switched)
        run_for(p, 300)  # past the inrush window: no EVENT from here on
        self.assertEqual(p.one(Subscribe(100, per_frame=4), Ack).of_type, Subscribe.TYPE)
        pushed = [(p.r.hal.now - p.r.board.boot_ms, e) for e in p.pushes()]
        pushed += run_for(p, 1000)
        frames = [e for _, e in pushed]
        self.assertFalse([e for e in frames if isinstance(e, Measurement)])
        got = readings(pushed)
        self.assertTrue(99 <= len(got) <= 101, len(got))
        self.assertEqual([m.seq for m in got], list(range(1, len(got) + 1)))
        steps = [got[i + 1].uptime_ms - got[i].uptime_ms for i in range(len(got) - 1)]
        self.assertEqual(set(steps), {10})  # sampled every period, not when sent
        self.assertEqual([len(e.readings) for e in frames], [4] * len(frames))
        for up, e in pushed:  # none waited longer than 3 periods
            self.assertLessEqual(up - e.readings[0].uptime_ms, 30)
        last = got[-1]
        self.assertEqual((last.currents_ma[0], last.on_mask, len(last.currents_ma)), (321, 1, 10))

    def test_event_goes_after_the_readings_before_it(self):
        p = Pair(rig(channels={1: {"rated_ma": 1000, "inrush_ms": 0}}))
        p.one(Switch(1, True), Switched)
        p.pushes()
        p.one(Subscribe(100, per_frame=10), Ack)
        run_for(p, 50)
        p.r.hal.load_ma[1] = 10000
        pushed = run_for(p, 150)
        frames = [e for _, e in pushed]
        trips = [i for i, e in enumerate(frames) if isinstance(e, Event) and e.kind == EV_TRIP]
        self.assertEqual(len(trips), 1)
        trip = frames[trips[0]]
        before = readings([(0, e) for e in frames[:trips[0]]])
        after = readings([(0, e) for e in frames[trips[0]:]])
        self.assertTrue(before and after)  # held readings went out just before the EVENT
        self.assertLessEqual(max(m.uptime_ms for m in before), trip.uptime_ms)
        self.assertGreaterEqual(min(m.uptime_ms for m in after), trip.uptime_ms)
        got = readings(pushed)
        self.assertEqual([m.seq for m in got], list(range(got[0].seq, got[0].seq + len(got))))

    def test_an_answer_goes_after_the_readings_before_it(self):
        p = Pair()
        p.one(Subscribe(100, per_frame=10), Ack)
        held = run_for(p, 30)  # readings taken, none sent yet
        self.assertEqual(held, [])
        got = p.ask(Ping(7))
        self.assertEqual([type(e).__name__ for e in got], ["MeasurementBatch", "Pong"])
        n = len(got[0].readings)
        self.assertGreaterEqual(n, 3)
        self.assertEqual([m.seq for m in got[0].readings], list(range(1, n + 1)))
        self.assertIsInstance(got[1], Pong)
        # the next batch starts afresh: ten more readings, then one frame
        self.assertEqual(run_for(p, 90), [])
        later = run_for(p, 10)
        self.assertEqual([m.seq for m in readings(later)], list(range(n + 1, n + 11)))

    def test_skipped_readings_spend_their_numbers(self):
        p = Pair()
        p.one(Subscribe(100, per_frame=4), Ack)
        self.assertEqual(p.pushes(), [])  # reading 1 held
        for _ in range(2):  # readings 2 and 3 skipped: the reader is slow
            p.r.run(10)
            self.assertEqual(p.s.poll(p.r.hal.now, send_measurement=False), b"")
        p.r.run(10)
        got = p.pushes()  # reading 4 ends the batch: 1 and 4
        self.assertEqual([m.seq for m in got[0].readings], [1, 4])
        self.assertEqual([m.seq for m in readings(run_for(p, 40))], [5, 6, 7, 8])

    def test_bad_per_frame_is_refused_and_changes_nothing(self):
        p = Pair()
        for k in (0, 11, 255):
            self.assertEqual(p.one(Subscribe(100, per_frame=k), Error).code, E_BAD_VALUE)
        self.assertEqual(run_for(p, 50), [])  # still not subscribed
        p.one(Subscribe(100, per_frame=2), Ack)
        self.assertEqual(p.one(Subscribe(50, per_frame=11), Error).code, E_BAD_VALUE)
        got = readings(run_for(p, 100))  # still 100 Hz, two a frame
        self.assertTrue(9 <= len(got) <= 11, len(got))

    def test_a_new_session_sends_what_it_held_then_starts_plain(self):
        p = Pair()
        p.one(Subscribe(100, per_frame=10), Ack)
        run_for(p, 20)
        got = p.ask(HelloRequest())
        self.assertEqual([type(e).__name__ for e in got], ["MeasurementBatch", "Hello"])
        self.assertIsInstance(got[1], Hello)
        self.assertEqual(run_for(p, 50), [])  # no subscription in the new session
        p.one(Subscribe(100), Ack)
        plain = run_for(p, 50)
        self.assertTrue(plain and all(isinstance(e, Measurement) for _, e in plain))
        self.assertEqual(plain[0][1].seq, 1)


if __name__ == "__main__":
    unittest.main()
