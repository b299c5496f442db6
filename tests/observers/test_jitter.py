"""The frequency observer on a loaded machine, on a simulated clock: no flapping, faults found.

``Loaded`` plays the hub's part (``host.observers.hub``) on a consumer that stalls now and then,
as a daemon does when the machine is busy: while it is stalled nothing is fed and no timer
fires; when it resumes, the timer that came due fires first (late) and then every message
that queued up meanwhile is fed, all at once, stamped with the time it was finally read — the
worst bunching there is. The publisher keeps its own clock in each message's ``stamp``.
No wall clock, no timing assertions: the verdicts and their simulated times are the result.
"""

from __future__ import annotations

import random
from collections.abc import Sequence

import pytest

from host.observers import FrequencyObserver, Message
from host.observers.base import Update
from host.observers.payload import encode, stamp_of
from host.observers.topics import JITTER_FLOOR_S, JITTER_S

TOPIC = "/imu_data"
RATE = 100.0  # XSens MTi, as system.yaml observes it
OFFSET = 1234.5  # the publisher's clock is not ours


def stalls(seed: int, end: float, longest: float) -> list[tuple[float, float]]:
    """Seeded stalls of the consumer: one every 0.1-0.5 s, each up to ``longest`` s."""
    rng = random.Random(seed)
    out, t = [], 0.5
    while t < end:
        d = rng.uniform(0.2, 1.0) * longest
        out.append((t, t + d))
        t += d + rng.uniform(0.1, 0.5)
    return out


class Loaded:
    """Feeds and ticks ``obs`` as a hub would, on a consumer stalled during ``stalled``;
    messages sent during ``delayed`` arrive at its end (held up on their way, as by a
    descheduled driver process), while the consumer's own timers stay on time."""

    def __init__(self, obs: FrequencyObserver, stalled: list[tuple[float, float]],
                 delayed: Sequence[tuple[float, float]] = ()) -> None:
        self.obs = obs
        self.stalled = stalled
        self.delayed = list(delayed)
        self.updates: list[Update] = []

    def resumed(self, t: float) -> float:
        """When the consumer gets to something due at ``t``."""
        for a, b in self.stalled:
            if a <= t < b:
                return b
        return t

    def arrives(self, sent: float) -> float:
        for a, b in self.delayed:
            if a <= sent < b:
                return self.resumed(b)
        return self.resumed(sent)

    def run(self, sends: list[tuple[float, float | None]], end: float) -> None:
        """Deliver ``sends`` ((time sent, stamp or None), in order) and tick until ``end``."""
        i = 0
        while True:
            due = self.obs.next_deadline()
            tick = None if due is None else self.resumed(due)
            msg = self.arrives(sends[i][0]) if i < len(sends) else None
            if msg is not None and (tick is None or msg < tick):
                stamp = sends[i][1]
                payload = encode({"seq": i} if stamp is None else {"seq": i, "stamp": stamp})
                self.updates += self.obs.feed(Message(msg, TOPIC, payload), msg)
                i += 1
            elif tick is not None and tick <= end:
                self.updates += self.obs.tick(tick)  # a late timer fires before the backlog
            else:
                return

    def verdicts(self) -> list[tuple[bool, float]]:
        """The changes of ``ok(topic)``: (positive, simulated time)."""
        out: list[tuple[bool, float]] = []
        for u in self.updates:
            lit = getattr(u, "literal", None)
            if lit is not None and (not out or out[-1][0] != lit.positive):
                out.append((lit.positive, u.time))
        return out


def stream(start: float, end: float, rate: float, stamped: bool = True
           ) -> list[tuple[float, float | None]]:
    n = int((end - start) * rate)
    return [(start + k / rate, OFFSET + start + k / rate if stamped else None)
            for k in range(n)]


def imu() -> FrequencyObserver:
    return FrequencyObserver(TOPIC, rate=RATE, tolerance=25, window=0.5, silence=5)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_bunched_arrivals_at_the_stamped_rate_never_flap(seed: int) -> None:
    # stalls of up to 0.3 s: six times the silence limit, 30 messages queued at once
    sim = Loaded(imu(), stalls(seed, 60.0, 0.3))
    sim.run(stream(0.0, 60.0, RATE), 60.0)
    assert sim.verdicts() == [(True, pytest.approx(0.01))]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_bunched_arrivals_without_stamps_are_counted_as_one_burst(seed: int) -> None:
    # no stamps: arrival counts over the window; a stall that keeps the window's count within
    # the tolerance (25 Hz x 0.5 s = 12 messages, so up to ~0.12 s) is not a rate drop
    sim = Loaded(imu(), stalls(seed, 60.0, 0.1))
    sim.run(stream(0.0, 60.0, RATE, stamped=False), 60.0)
    assert [ok for ok, _ in sim.verdicts()] == [True]


@pytest.mark.parametrize("stamped", [True, False])
def test_a_silent_publisher_is_found_within_the_window_despite_stalls(stamped: bool) -> None:
    obs = imu()
    stalled = stalls(4, 30.0, 0.1 if not stamped else 0.3)
    sim = Loaded(obs, stalled)
    sim.run(stream(0.0, 20.0, RATE, stamped), 30.0)
    got = sim.verdicts()
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
    sim.run(stream(0.0, 30.0, RATE), 30.0)
    assert [ok for ok, _ in sim.verdicts()] == [True]
    assert JITTER_FLOOR_S < obs.allowance <= obs.window
    # and a publisher that then stops is still found within the window
    sim.run(stream(30.0, 31.0, RATE)[:1], 32.0)
    got = sim.verdicts()
    assert [ok for ok, _ in got] == [True, False] and got[1][1] <= 30.0 + obs.max_gap + obs.window


def test_a_silent_publisher_on_an_idle_consumer_is_found_at_the_limit_and_confirmed() -> None:
    obs = imu()
    sim = Loaded(obs, [])
    sim.run(stream(0.0, 2.0, RATE), 3.0)
    last = 2.0 - 1 / RATE
    assert sim.verdicts() == [(True, pytest.approx(0.01)), (False, pytest.approx(
        last + obs.max_gap + JITTER_FLOOR_S + JITTER_S))]


@pytest.mark.parametrize("stamped", [True, False])
def test_a_slow_publisher_is_found_within_the_window_despite_stalls(stamped: bool) -> None:
    obs = imu()
    # a quarter of the rate: clearly out of tolerance (near its edge, the window's mix of the
    # two regimes may cross it back and forth while the old one leaves, stalls or not)
    sends = stream(0.0, 10.0, RATE, stamped) + stream(10.0, 20.0, RATE / 4, stamped)
    sim = Loaded(obs, stalls(5, 20.0, 0.1))
    sim.run(sends, 20.0)
    got = sim.verdicts()
    assert [ok for ok, _ in got] == [True, False]
    assert 10.0 < got[1][1] <= sim.resumed(10.0 + obs.window + 2 / RATE)
    assert obs.frequency == pytest.approx(RATE / 4, rel=0.2)


def test_a_restarted_publisher_starts_the_window_afresh() -> None:
    obs = imu()
    sim = Loaded(obs, [])
    # its clock restarts from an earlier stamp after 1 s: not a negative span, not a burst
    sends = stream(0.0, 1.0, RATE) + [(t, None if s is None else s - 500.0)
                                      for t, s in stream(1.0, 2.0, RATE)]
    sim.run(sends, 2.0)
    assert [ok for ok, _ in sim.verdicts()] == [True]
    assert obs.frequency == pytest.approx(RATE, rel=0.05)


def test_stamps_are_read_from_the_publishers_conventions() -> None:
    assert stamp_of({"stamp": 12.5}) == 12.5
    assert stamp_of({"seq": 3, "t_ms": 1500}) == 1.5  # the virtual robot's device frames
    assert stamp_of({"header": {"stamp": {"sec": 7, "nanosec": 250_000_000}}}) == 7.25
    assert stamp_of({"stamp": "soon"}) is None and stamp_of({"seq": 1}) is None
    assert stamp_of(None) is None
    assert Message(0.0, TOPIC, b"not json").stamp is None
