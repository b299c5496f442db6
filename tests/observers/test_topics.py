"""Frequency and response observers on a simulated clock: literals, their times, expiry."""

from __future__ import annotations

import pytest

from host.diagnosis.observations import Observation, ObservationSet
from host.observers import (
    FrequencyObserver,
    ResponseObserver,
    Retraction,
    TopicMessage,
    apply_updates,
)
from host.observers.silence import JITTER_S
from host.observers.topics import JITTER_FLOOR_S


class SetSink:
    def __init__(self) -> None:
        self.s = ObservationSet()

    def observe(self, obs: Observation) -> bool:
        return self.s.add(obs)

    def retract(self, atom: str) -> bool:
        return self.s.retract(atom)


def run_until(obs: FrequencyObserver | ResponseObserver, end: float) -> list:
    """Tick the observer at each of its deadlines up to ``end`` (what the hub does)."""
    out = []
    while (d := obs.next_deadline()) is not None and d <= end:
        out += obs.tick(d)
    return out


def test_frequency_ok_then_silence_at_its_deadline() -> None:
    f = FrequencyObserver("/odom", rate=10, tolerance=2, window=1.0, silence=5)
    out = []
    for i in range(10):
        out += f.feed(TopicMessage(i * 0.1, "/odom"), i * 0.1)
    assert [(str(o.literal), o.time) for o in out] == [("ok(/odom)", 0.1)]
    assert out[0].source == "frequency:/odom" and out[0].validity == 3.0
    # silence after t=0.9: ~ok 5 periods and the least delay tolerated later (confirmed
    # JITTER_S on), not on a 1 s poll
    later = run_until(f, 5.0)
    assert [str(o.literal) for o in later] == ["ok(/odom)"] + ["~ok(/odom)"] * 4
    # a refresh at 1.1 (1 s after the change), ~ok 5 periods after the last message and
    # confirmed, then only refreshes, one per refresh period
    j = JITTER_FLOOR_S + JITTER_S  # messages on time: the least delay tolerated
    assert [o.time for o in later] == pytest.approx([1.1, 1.4 + j, 2.4 + j, 3.4 + j, 4.4 + j])


def test_frequency_wrong_rate_and_recovery() -> None:
    f = FrequencyObserver("/scan", rate=10, tolerance=2, window=1.0)
    out = []
    t = 0.0
    for _ in range(10):  # 10 Hz
        out += f.feed(TopicMessage(t, "/scan"), t)
        t += 0.1
    for _ in range(10):  # 20 Hz: too fast once the window holds the new regime
        out += f.feed(TopicMessage(t, "/scan"), t)
        t += 0.05
    lits = [str(o.literal) for o in out]
    assert lits == ["ok(/scan)", "~ok(/scan)"]
    assert f.frequency is not None and f.frequency > 12


def test_refresh_keeps_it_and_expiry_makes_it_unknown() -> None:
    f = FrequencyObserver("/imu_data", rate=100, tolerance=20, window=0.5, silence=5)
    sink = SetSink()
    t = 0.0
    while t < 2.0:
        apply_updates(f.feed(TopicMessage(t, "/imu_data"), t), sink)
        apply_updates(f.tick(t), sink)
        t += 0.01
    o = sink.s.get("ok(/imu_data)")
    assert o is not None and o.literal.positive and o.time >= 1.0  # refreshed
    # the observer dies (no more ticks): the literal expires after its validity
    assert sink.s.expire(o.time + 2.9) == []
    assert [str(x.literal) for x in sink.s.expire(o.time + 3.0)] == ["ok(/imu_data)"]
    assert sink.s.get("ok(/imu_data)") is None  # unknown, not false


def test_topic_never_heard_is_not_ok_after_the_silence_limit() -> None:
    f = FrequencyObserver("/map", rate=2, tolerance=1, window=2.0, silence=3)
    assert f.tick(10.0) == []  # the first tick starts the clock
    out = run_until(f, 12.0)
    assert str(out[0].literal) == "~ok(/map)" and out[0].time == pytest.approx(
        11.5 + JITTER_FLOOR_S + JITTER_S)


def test_response_within_and_missed() -> None:
    r = ResponseObserver("/cmd_vel", "/odom", within=0.2)
    out = r.feed(TopicMessage(1.0, "/cmd_vel"), 1.0)
    out += r.feed(TopicMessage(1.1, "/odom"), 1.1)
    assert [(str(o.literal), o.time) for o in out] == [("ok(/odom)", 1.1)]
    out = r.feed(TopicMessage(2.0, "/cmd_vel"), 2.0)
    out += r.feed(TopicMessage(2.05, "/cmd_vel"), 2.05)  # the oldest unanswered input counts
    out += run_until(r, 2.2)
    assert [(str(o.literal), o.time) for o in out] == [("ok(/odom)", 2.1), ("~ok(/odom)", 2.2)]
    assert r.feed(TopicMessage(2.3, "/odom"), 2.3) == []  # too late: answers nothing
    assert r.next_deadline() == pytest.approx(3.2)  # refresh only


def test_stop_retracts() -> None:
    r = ResponseObserver("/a", "/b", within=1.0, atom="ok(b_follows_a)")
    r.feed(TopicMessage(0.0, "/a"), 0.0)
    r.feed(TopicMessage(0.5, "/b"), 0.5)
    assert r.stop(0.6) == [Retraction("ok(b_follows_a)", 0.6, "response:/a->/b")]


def test_bad_parameters_are_refused() -> None:
    with pytest.raises(ValueError, match="window"):
        FrequencyObserver("/x", rate=1, tolerance=0.5, window=1.0)
    with pytest.raises(ValueError, match="refresh"):
        FrequencyObserver("/x", rate=10, tolerance=1, refresh=5.0, validity=3.0)
