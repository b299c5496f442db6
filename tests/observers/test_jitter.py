"""The frequency observer on a loaded machine, on a simulated clock: no flapping, faults found.

``Loaded`` (``tests.observers.loaded``) plays the hub's part on a consumer that stalls now and
then, as a daemon does when the machine is busy; the publisher keeps its own clock in each
message's ``stamp``. No wall clock, no timing assertions: the verdicts and their simulated
times are the result.
"""

from __future__ import annotations

import functools

import pytest

import host.atoms as A
from host.observers import FrequencyObserver, TopicMessage
from host.observers.payload import encode, stamp_of
from host.observers.silence import JITTER_S
from host.observers.topics import JITTER_FLOOR_S
from tests.observers.loaded import Loaded as LoadedBase
from tests.observers.loaded import stalls

TOPIC = "/imu_data"
RATE = 100.0  # XSens MTi, as system.yaml observes it
OFFSET = 1234.5  # the publisher's clock is not ours


class Loaded(LoadedBase):
    """The simulated consumer of one topic's messages."""

    def run_messages(self, sends: list[tuple[float, float | None]], end: float) -> None:
        """Deliver ``sends`` ((time sent, stamp or None), in order) and tick until ``end``."""
        self.run([(sent, functools.partial(message, i, stamp))
                  for i, (sent, stamp) in enumerate(sends)], end)

    def topic_verdicts(self) -> list[tuple[bool | None, float]]:
        return self.verdicts(str(A.ok(TOPIC)))


def message(seq: int, stamp: float | None, arrival: float) -> TopicMessage:
    payload = encode({"seq": seq} if stamp is None else {"seq": seq, "stamp": stamp})
    return TopicMessage(arrival, TOPIC, payload)


def stream(start: float, end: float, rate: float, stamped: bool = True
           ) -> list[tuple[float, float | None]]:
    n = int((end - start) * rate)
    return [(start + k / rate, OFFSET + start + k / rate if stamped else None)
            for k in range(n)]


def imu() -> FrequencyObserver:
    return FrequencyObserver(TOPIC, rate=RATE, tolerance=25, window=0.5)  # silence: default


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_bunched_arrivals_at_the_stamped_rate_never_flap(seed: int) -> None:
    # stalls of up to 0.3 s: six times the silence limit, 30 messages queued at once
    sim = Loaded(imu(), stalls(seed, 60.0, 0.3))
    sim.run_messages(stream(0.0, 60.0, RATE), 60.0)
    assert sim.topic_verdicts() == [(True, pytest.approx(0.01))]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_bunched_arrivals_without_stamps_are_counted_as_one_burst(seed: int) -> None:
    # no stamps: arrival counts over the window; a stall that keeps the window's count within
    # the tolerance (25 Hz x 0.5 s = 12 messages, so up to ~0.12 s) is not a rate drop
    sim = Loaded(imu(), stalls(seed, 60.0, 0.1))
    sim.run_messages(stream(0.0, 60.0, RATE, stamped=False), 60.0)
    assert [ok for ok, _ in sim.topic_verdicts()] == [True]


@pytest.mark.parametrize("stamped", [True, False])
def test_a_silent_publisher_is_found_within_the_window_despite_stalls(stamped: bool) -> None:
    obs = imu()
    stalled = stalls(4, 30.0, 0.1 if not stamped else 0.3)
    sim = Loaded(obs, stalled)
    sim.run_messages(stream(0.0, 20.0, RATE, stamped), 30.0)
    got = sim.topic_verdicts()
    assert [ok for ok, _ in got] == [True, False]
    last = 20.0 - 1 / RATE
    # no later than the silence limit plus the window, however the stalls fell
    assert last + obs.max_gap <= got[1][1] <= sim.resumed(last + obs.max_gap + obs.window)


def test_delays_on_the_way_are_learned_from_the_stamps_and_tolerated() -> None:
    # the driver is descheduled now and then while the daemon is awake: messages arrive late
    # and bunched. Up to 80 ms (within the least delay tolerated) from the start, then up to
    # 150 ms: tolerated, as twice the worst delay seen lately
    obs = imu()
    delayed = [(a, a + 0.6 * (b - a)) for a, b in stalls(6, 10.0, 0.08)]
    delayed += [(a, b) for a, b in stalls(7, 30.0, 0.15) if a > 10.0]
    sim = Loaded(obs, [], delayed)
    sim.run_messages(stream(0.0, 30.0, RATE), 30.0)
    assert [ok for ok, _ in sim.topic_verdicts()] == [True]
    assert JITTER_FLOOR_S < obs.allowance <= obs.window
    # and a publisher that then stops is still found within the window
    sim.run_messages(stream(30.0, 31.0, RATE)[:1], 32.0)
    got = sim.topic_verdicts()
    assert [ok for ok, _ in got] == [True, False] and got[1][1] <= 30.0 + obs.max_gap + obs.window


def test_a_silent_publisher_on_an_idle_consumer_is_found_at_the_limit_and_confirmed() -> None:
    obs = imu()
    sim = Loaded(obs, [])
    sim.run_messages(stream(0.0, 2.0, RATE), 3.0)
    last = 2.0 - 1 / RATE
    assert sim.topic_verdicts() == [(True, pytest.approx(0.01)), (False, pytest.approx(
        last + obs.max_gap + JITTER_FLOOR_S + JITTER_S))]


@pytest.mark.parametrize("stamped", [True, False])
def test_a_slow_publisher_is_found_within_the_window_despite_stalls(stamped: bool) -> None:
    obs = imu()
    # a quarter of the rate: clearly out of tolerance (near its edge, the window's mix of the
    # two regimes may cross it back and forth while the old one leaves, stalls or not)
    sends = stream(0.0, 10.0, RATE, stamped) + stream(10.0, 20.0, RATE / 4, stamped)
    sim = Loaded(obs, stalls(5, 20.0, 0.1))
    sim.run_messages(sends, 20.0)
    got = sim.topic_verdicts()
    assert [ok for ok, _ in got] == [True, False]
    assert 10.0 < got[1][1] <= sim.resumed(10.0 + obs.window + 2 / RATE)
    assert obs.frequency == pytest.approx(RATE / 4, rel=0.2)


def test_a_restarted_publisher_starts_the_window_afresh() -> None:
    obs = imu()
    sim = Loaded(obs, [])
    # its clock restarts from an earlier stamp after 1 s: not a negative span, not a burst
    sends = stream(0.0, 1.0, RATE) + [(t, None if s is None else s - 500.0)
                                      for t, s in stream(1.0, 2.0, RATE)]
    sim.run_messages(sends, 2.0)
    assert [ok for ok, _ in sim.topic_verdicts()] == [True]
    assert obs.frequency == pytest.approx(RATE, rel=0.05)


def test_stamps_are_read_from_the_publishers_conventions() -> None:
    assert stamp_of({"stamp": 12.5}) == 12.5
    assert stamp_of({"seq": 3, "t_ms": 1500}) == 1.5  # the virtual robot's device frames
    assert stamp_of({"header": {"stamp": {"sec": 7, "nanosec": 250_000_000}}}) == 7.25
    assert stamp_of({"stamp": "soon"}) is None and stamp_of({"seq": 1}) is None
    assert stamp_of(None) is None
    assert TopicMessage(0.0, TOPIC, b"not json").stamp is None
