"""The page's status as a fold of the daemon's events: what is healthy, what is out of repair
and how a person gets it back, the repairs in the order they started.
"""

from __future__ import annotations

from host.events import (
    ActionRecord,
    ActionState,
    Event,
    HoldChange,
    JournalHealth,
    QuarantineChange,
    RunStarted,
    Stamped,
)
from host.fold import EventFold
from host.web import MemoryStatusSource
from host.web.fold import PageProjection
from host.web.status import Status

WALL0 = 1_800_000_000.0


def _fold(*events: Event) -> Status:
    source = MemoryStatusSource(Status(robot="tedusar"))
    fold = EventFold()
    PageProjection(source, fold)
    for i, e in enumerate(events):
        fold(Stamped(WALL0 + i, 100.0 + i, e))
    return source.snapshot()


RUN = RunStarted("20270115T080000-0a0a", "tedusar", "tcp://127.0.0.1:7000",
                 healthy={"tripped(hokuyo)": False, "on(hokuyo)": True})


def test_the_run_says_its_id_and_which_values_are_healthy() -> None:
    st = _fold(RUN)
    assert st.run_id == "20270115T080000-0a0a"
    assert st.healthy == {"tripped(hokuyo)": False, "on(hokuyo)": True}
    data = st.to_json()
    assert data["healthy"] == {"on(hokuyo)": True, "tripped(hokuyo)": False}
    assert data["run_id"] == st.run_id


def test_quarantines_and_holds_say_since_when_and_how_to_release_them() -> None:
    st = _fold(RUN,
               QuarantineChange("hokuyo", True, "3 attempts failed", "shutdown(hokuyo)"),
               HoldChange("jaguar", True, "switched off on the board by a command this daemon "
                          "did not send", by="board"),
               HoldChange("imu", True, "new cable", by="person"))
    assert st.quarantined == {"hokuyo": "3 attempts failed"}  # the API's simple maps stay
    assert set(st.held) == {"jaguar", "imu"}
    rows = {r.component: r for r in st.out_of_repair}
    assert [r.component for r in st.out_of_repair] == ["hokuyo", "jaguar", "imu"]
    q = rows["hokuyo"]
    assert (q.state, q.by, q.since, q.safe_state) == ("quarantined", "daemon", WALL0 + 1,
                                                      "shutdown(hokuyo)")
    assert q.release == "dxboard quarantine clear hokuyo"
    assert rows["imu"].release == "dxboard hold release imu"
    assert rows["jaguar"].release == ("switch it on again (dxboard board tcp://127.0.0.1:7000 "
                                      "on jaguar), or dxboard hold release jaguar")
    assert st.to_json()["out_of_repair"][0]["release"] == "dxboard quarantine clear hokuyo"
    # released: gone from both
    st2 = _fold(RUN, QuarantineChange("hokuyo", True, "x"), HoldChange("imu", True),
                QuarantineChange("hokuyo", False, by="person"), HoldChange("imu", False))
    assert st2.out_of_repair == () and not st2.quarantined and not st2.held


def test_a_daemon_on_another_operator_socket_is_named_in_the_command() -> None:
    run = RunStarted("r", "tedusar", "tcp://b:7000", operator="/run/dxboard/op.sock")
    st = _fold(run, QuarantineChange("hokuyo", True, "x"))
    assert st.out_of_repair[0].release == (
        "dxboard quarantine clear hokuyo --operator /run/dxboard/op.sock")
    st = _fold(RunStarted("r", "t", operator="dxboard-journal.sock"),
               QuarantineChange("hokuyo", True, "x"))
    assert st.out_of_repair[0].release == "dxboard quarantine clear hokuyo"


def test_repairs_keep_the_order_they_started_in() -> None:
    def act(aid: str, state: ActionState, t: float) -> ActionRecord:
        return ActionRecord(aid, "power_up", (aid,), state, t,
                            None if state is ActionState.STARTED else t + 1)

    st = _fold(act("a1", ActionState.STARTED, 100.0), act("a2", ActionState.STARTED, 101.0),
               act("a1", ActionState.SUCCEEDED, 100.0))
    assert [(r.args, r.state) for r in st.repairs] == [(("a1",), "succeeded"),
                                                       (("a2",), "started")]


def test_the_journal_health_reaches_the_status() -> None:
    s = _fold(RUN, JournalHealth("disk full", 40, 0))
    assert (s.journal_problem, s.journal_held, s.journal_dropped) == ("disk full", 40, 0)
    s = _fold(RUN, JournalHealth("disk full", 40, 0), JournalHealth("", 0, 0))
    assert (s.journal_problem, s.journal_held) == ("", 0)
