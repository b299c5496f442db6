"""The timeline model rebuilds, from journals of the paper's experiments, exactly what happened.

Intervals come from the first-ranked diagnosis over time; action spans are the recorded
start and end (on either clock the daemon used); windows cut and re-base the axis.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from host.journal import DiagnosisRecord, Journal, JournalReader
from host.report.source import load_timeline
from host.report.timeline import EmptyWindow, Group, HealthState, WindowBound, build_timeline
from tests.report.journals import COMPONENTS, HARDWARE, NODES, T0, device_shut_down, power_up

A, N, U = HealthState.ABNORMAL, HealthState.NORMAL, HealthState.UNKNOWN


def test_device_shut_down_intervals_and_actions_are_as_recorded(tmp_path: Path) -> None:
    t = load_timeline(device_shut_down(tmp_path / "d.sqlite"))
    assert t.name == "d" and t.clock == "mono"
    assert t.end == pytest.approx(19.99)
    assert {r.name for r in t.rows} == set(COMPONENTS)
    assert [r.group for r in t.rows] == [Group.HARDWARE] * 3 + [Group.NODES] * 8
    jaguar = [(pytest.approx(i.start), pytest.approx(i.end), i.state)
              for i in t.row("jaguar").intervals]
    assert jaguar == [(0.0, 0.5, U), (0.5, 10.2, N), (10.2, 12.2, A), (12.2, 19.99, N)]
    node = t.row("jaguar_node").intervals
    assert [i.state for i in node] == [U, N, A, N]
    assert node[2].start == pytest.approx(10.95) and node[2].end == pytest.approx(16.4)
    assert [i.state for i in t.row("hokuyo").intervals] == [U, N]
    spans = [(a.label, pytest.approx(a.start), pytest.approx(a.end), a.outcome, a.plan_id)
             for a in t.actions]
    assert spans == [("power_up(jaguar)", 10.4, 11.9, "succeeded", "p1"),
                     ("stop_node(jaguar_node)", 12.4, 13.1, "succeeded", "p2"),
                     ("start_node(jaguar_node)", 13.2, 15.0, "succeeded", "p2")]
    assert [(p.plan_id, pytest.approx(p.time)) for p in t.plans] == [("p1", 10.3), ("p2", 12.3)]
    (rec,) = t.recoveries
    assert rec.abnormal_since == pytest.approx(10.2)
    assert rec.normal_at == pytest.approx(16.4)
    assert rec.repair_s == pytest.approx(6.0)


def test_power_up_is_all_abnormal_then_all_normal_30_2_s_after_the_first_action(
        tmp_path: Path) -> None:
    t = load_timeline(power_up(tmp_path / "p.sqlite"))
    for r in t.rows:
        assert [i.state for i in r.intervals] == [U, A, N], r.name
        assert r.intervals[1].start == pytest.approx(1.0)
    assert t.row("laser_alignment").intervals[1].end == pytest.approx(9.5)
    assert t.row("joy_node").intervals[1].end == pytest.approx(38.3)
    assert [a.label for a in t.actions] == (
        [f"power_up({h})" for h in HARDWARE] + [f"start_node({n})" for n in NODES])
    assert all(a.ok for a in t.actions)
    (rec,) = t.recoveries
    assert (rec.abnormal_since, rec.first_action) == (pytest.approx(1.0), pytest.approx(8.1))
    assert rec.normal_at == pytest.approx(38.3) and rec.repair_s == pytest.approx(30.2)


def test_failed_and_timed_out_actions_keep_their_outcome(tmp_path: Path) -> None:
    t = load_timeline(power_up(tmp_path / "f.sqlite", failing=True))
    hm = [(a.outcome, a.detail) for a in t.actions if a.args == ("hector_mapping",)]
    assert hm == [("failed", "exit status 1"), ("timeout", "no /map within 0.9 s"),
                  ("succeeded", "")]


def test_action_times_on_the_monotonic_clock_land_in_the_same_place(tmp_path: Path) -> None:
    wall = load_timeline(device_shut_down(tmp_path / "w.sqlite"))
    mono = load_timeline(device_shut_down(tmp_path / "m.sqlite", action_clock="mono"))
    assert [x for a in mono.actions for x in (a.start, a.end)] == pytest.approx(
        [x for a in wall.actions for x in (a.start, a.end)])


def test_a_window_cuts_and_rebases_the_axis(tmp_path: Path) -> None:
    path = device_shut_down(tmp_path / "d.sqlite")
    t = load_timeline(path, start=WindowBound(9.0), end=WindowBound(13.0))
    assert t.end == pytest.approx(4.0)
    jaguar = [(pytest.approx(i.start), pytest.approx(i.end), i.state)
              for i in t.row("jaguar").intervals]
    assert jaguar == [(0.0, 1.2, N), (1.2, 3.2, A), (3.2, 4.0, N)]
    # start_node(jaguar_node) begins at 13.2: outside; stop_node is cut at the window's end
    assert [(a.label, pytest.approx(a.start), pytest.approx(a.end)) for a in t.actions] == [
        ("power_up(jaguar)", 1.4, 2.9), ("stop_node(jaguar_node)", 3.4, 4.0)]
    assert t.recoveries == ()  # all normal only at 16.4 s
    assert t.origin_wall == pytest.approx(T0 + 9.0)
    # by journal ids: from the first diagnosis blaming jaguar to the end
    with JournalReader(path) as reader:
        first_bad = next(e for e in reader.since(0, limit=None)
                         if isinstance(e.payload, DiagnosisRecord) and e.payload.diagnoses[0])
    by_id = load_timeline(path, start=WindowBound(first_bad.id, is_id=True))
    assert by_id.first_id == first_bad.id
    first = by_id.row("jaguar").intervals[0]
    assert (first.start, first.end, first.state) == (0.0, pytest.approx(2.0), A)


def test_the_model_gives_all_rows_in_its_order_and_groups(tmp_path: Path) -> None:
    t = load_timeline(device_shut_down(tmp_path / "d.sqlite"), model="models/tedusar")
    assert t.robot == "tedusar"
    names = [r.name for r in t.rows]
    assert names[:3] == ["jaguar", "hokuyo", "laser_alignment"]  # the file's order
    assert {"imu", "joystick", "rviz"} <= set(names)  # never diagnosed, still a row
    groups = {r.name: r.group for r in t.rows}
    assert groups["jaguar_node"] is Group.DRIVERS and groups["imu_node"] is Group.DRIVERS
    assert groups["hector_mapping"] is Group.NODES and groups["imu"] is Group.HARDWARE
    assert [i.state for i in t.row("rviz").intervals] == [U, N]


def test_no_diagnosis_in_a_record_makes_everything_unknown(tmp_path: Path) -> None:
    path = tmp_path / "c.sqlite"
    with Journal(path) as j:
        j.record(DiagnosisRecord.of([["a"], ["b"]]), wall=T0, mono=0.0)
        j.record(DiagnosisRecord.of([]), wall=T0 + 2, mono=2.0)
        j.record(DiagnosisRecord.of([[]]), wall=T0 + 3, mono=3.0)
        j.flush_blocking(10)
        entries = j.reader.since(0, limit=None)
    t = build_timeline(entries, name="c")
    # only the first-ranked diagnosis counts: b (in the second) stays normal
    assert [(i.state, i.start, i.end) for i in t.row("a").intervals] == [
        (A, 0.0, 2.0), (U, 2.0, 3.0)]
    assert [i.state for i in t.row("b").intervals] == [N, U]
    (rec,) = t.recoveries
    assert (rec.abnormal_since, rec.first_action, rec.normal_at) == (0.0, None, 3.0)
    with pytest.raises(EmptyWindow):
        build_timeline(entries, name="c", start=WindowBound(5.0))
    with pytest.raises(EmptyWindow):
        build_timeline(entries, name="c", start=WindowBound(99, is_id=True))


def test_bounds_parse_seconds_and_ids() -> None:
    assert WindowBound.parse("12.5") == WindowBound(12.5)
    assert WindowBound.parse("3s") == WindowBound(3.0)
    assert WindowBound.parse("#120") == WindowBound(120.0, True)
    assert WindowBound.parse("id:7") == WindowBound(7.0, True)
    for bad in ("x", "#0", "#", "nan", "inf"):
        with pytest.raises(ValueError):
            WindowBound.parse(bad)
