"""Trend, match and diagnostic observers on a simulated clock."""

from __future__ import annotations

import pytest

from host.observers import (
    DiagnosticObserver,
    MatchObserver,
    Retraction,
    Threshold,
    TopicMessage,
    TrendObserver,
    ValueRef,
    encode,
    pick,
)


def msg(t: float, topic: str, **values: object) -> TopicMessage:
    return TopicMessage(t, topic, encode(values))


def signs(updates: list) -> dict[str, bool | None]:
    out: dict[str, bool | None] = {}
    for u in updates:
        out[u.atom if isinstance(u, Retraction) else u.literal.atom] = (
            None if isinstance(u, Retraction) else u.literal.positive)
    return out


def test_trend_inc_dec_const_by_regression() -> None:
    tr = TrendObserver(ValueRef("yaw", "/odom", "twist.z"), window=1.0, slope=0.1)
    out = []
    for i in range(20):  # rising 0.5 per second
        t = i * 0.05
        out += tr.feed(TopicMessage(t, "/odom", encode({"twist": {"z": 0.5 * t}})), t)
    assert signs(out) == {"inc(yaw)": True, "dec(yaw)": False, "const(yaw)": False}
    assert out[0].time == pytest.approx(0.1)  # judged at the third sample
    assert tr.trend.fitted == pytest.approx(0.5)
    out = []
    for i in range(20, 80):  # flat: const once the window holds only flat samples
        t = i * 0.05
        out += tr.feed(TopicMessage(t, "/odom", encode({"twist": {"z": 0.5}})), t)
    assert signs(out)["const(yaw)"] is True and signs(out)["inc(yaw)"] is False
    # no messages: the window runs dry and the trend becomes unknown (retracted)
    gone = []
    while (t := tr.next_deadline()) is not None:
        gone += tr.tick(t)
    assert {u.atom for u in gone if isinstance(u, Retraction)} == set(tr.atoms())
    # the third-newest sample (t=3.85) left the 1 s window: too few to fit a line
    assert [u.time for u in gone if isinstance(u, Retraction)] == pytest.approx([4.85] * 3)


def test_match_of_two_trends() -> None:
    m = MatchObserver(ValueRef("a", "/odom", "v"), ValueRef("b", "/imu_data", "w"),
                      window=1.0, slope=0.05)
    out = []
    for i in range(20):
        t = i * 0.05
        out += m.feed(msg(t, "/odom", v=t), t)
        out += m.feed(msg(t + 0.01, "/imu_data", w=2 * t), t + 0.01)
    assert signs(out) == {"matched(a,b)": True}
    out = []
    for i in range(20, 60):
        t = i * 0.05
        out += m.feed(msg(t, "/odom", v=t), t)  # still rising
        out += m.feed(msg(t + 0.01, "/imu_data", w=-t), t + 0.01)  # now falling
    assert signs(out) == {"matched(a,b)": False}


def test_diagnostic_thresholds_on_key_values() -> None:
    d = DiagnosticObserver("/diagnostics", [
        Threshold("cpu.temp", "ok(temp_cpu1)", max=40.0),
        Threshold("battery", "ok(battery)", min=11.0, max=14.0),
        Threshold("mode", "ok(mode)", equals="auto"),
    ])
    out = d.feed(msg(1.0, "/diagnostics", cpu={"temp": 35.5}, battery=12.1, mode="auto"), 1.0)
    assert signs(out) == {"ok(temp_cpu1)": True, "ok(battery)": True, "ok(mode)": True}
    out = d.feed(msg(2.0, "/diagnostics", cpu={"temp": 41}), 2.0)  # only this key: one change
    assert [(str(o.literal), o.time) for o in out] == [("~ok(temp_cpu1)", 2.0)]
    assert d.feed(TopicMessage(2.5, "/diagnostics", b"not json"), 2.5) == []
    # no message for the validity: everything is retracted, not left stale
    out = []
    while (t := d.next_deadline()) is not None and t <= 6.0:
        out += d.tick(t)
    assert {u.atom for u in out if isinstance(u, Retraction)} == set(d.atoms())
    assert all(u.time == pytest.approx(5.5) for u in out if isinstance(u, Retraction))


def test_pick_follows_dots_and_indexes() -> None:
    obj = {"a": {"b": [1, {"c": 2}]}}
    assert pick(obj, "a.b.1.c") == 2 and pick(obj, "a.b.-2") == 1
    assert pick(obj, "a.x") is None and pick(obj, "a.b.7") is None and pick(None, "a") is None
