"""Journals of the paper's two experiments (paper 000 §VI), written with the real ``Journal``.

``power_up``: the whole robot starts switched off; the first diagnosis (at 1.0 s) blames all
11 components of the paper's model; a plan powers up laser_alignment (from 8.1 s), hokuyo and
jaguar, then starts the nodes one by one; each becomes normal in the next diagnosis, and the
last diagnosis, at 38.3 s, finds everything healthy: 30.2 s after the first action, as in the
paper's figure 5. With ``failing=True`` hector_mapping's first start fails and its retry
times out before a third start works (for the failed/timeout drawing).

``device_shut_down``: everything runs (all healthy at 0.5 s); at 10 s the jaguar base loses
power; the diagnosis blames jaguar, then jaguar and jaguar_node (its odometry stops); a plan
powers jaguar up, a second plan stops and starts jaguar_node, and at 16.4 s all is normal again
(the paper's figure 6).

Entries carry wall = T0 + t and mono = MONO0 + t (each shifted by ``offset`` seconds, for a
later run in the same file); actions' ``started``/``finished`` are wall times (or mono with
``action_clock="mono"``). Telemetry and notes are mixed in as a daemon would. With ``run=ID``
the history begins with the ``RunStarted`` a daemon writes first, and is appended to the file:
several runs in one journal, as ``make run`` leaves it, each counting its actions from ``a1``.
``python -m tests.report.journals DIR`` writes both (and the failing variant) into DIR.
"""

from __future__ import annotations

import sys
from pathlib import Path

from host.journal import (
    ActionRecord,
    ActionState,
    BoardEvent,
    ChannelSummary,
    DiagnosisRecord,
    Journal,
    Note,
    Observation,
    Payload,
    PlanRecord,
    PlanStep,
    RunStarted,
    Telemetry,
)

TEDUSAR_DIR = str(Path(__file__).resolve().parents[2] / "models" / "tedusar")
T0 = 1_800_000_000.0
MONO0 = 5_000.0

HARDWARE = ("laser_alignment", "hokuyo", "jaguar")
NODES = ("laser_alignment_node", "hokuyo_node", "hector_mapping", "jaguar_teleop_node",
         "jaguar_node", "laser_alignment_control", "imu_node", "joy_node")
COMPONENTS = HARDWARE + NODES  # the paper's 11 (j, h, la, lan, lac, hm, jn, hn, in, jtn, jyn)

Event = tuple[float, Payload]


class _History:
    def __init__(self, action_clock: str, run: str | None = None, offset: float = 0.0) -> None:
        self.events: list[Event] = []
        self.clock = action_clock
        self.offset = offset
        self._n = 0
        if run is not None:
            self.at(0.0, RunStarted(run, "tedusar", "tcp://127.0.0.1:7000"))

    def at(self, t: float, payload: Payload) -> None:
        self.events.append((t, payload))

    def _time(self, t: float) -> float:
        return (MONO0 if self.clock == "mono" else T0) + self.offset + t

    def action(self, action: str, arg: str, start: float, end: float,
               state: ActionState = ActionState.SUCCEEDED, plan: str = "",
               detail: str = "") -> str:
        self._n += 1
        aid = f"a{self._n}"
        self.at(start, ActionRecord(aid, action, (arg,), ActionState.STARTED, self._time(start),
                                    plan_id=plan))
        self.at(end, ActionRecord(aid, action, (arg,), state, self._time(start),
                                  self._time(end), plan, detail))
        return aid

    def telemetry(self, until: float, on: dict[int, float]) -> None:
        for i in range(int(until)):
            self.at(i + 0.99, Telemetry(1.0, tuple(
                ChannelSummary(ch, 100, ma, ma * 0.9, ma * 1.1, ma) for ch, ma in on.items())))

    def write(self, path: Path) -> None:
        with Journal(path) as journal:
            for t, payload in sorted(self.events, key=lambda e: e[0]):
                journal.record(payload, wall=T0 + self.offset + t, mono=MONO0 + self.offset + t)


def _bad(*components: str) -> DiagnosisRecord:
    return DiagnosisRecord.of([sorted(components)], trigger="observation", elapsed_s=0.01)


def power_up(path: Path, *, failing: bool = False, action_clock: str = "wall",
             run: str | None = None, offset: float = 0.0) -> Path:
    h = _History(action_clock, run, offset)
    h.at(0.0, Note("daemon started: robot tedusar"))
    for hw in HARDWARE:
        h.at(0.2, Observation(f"on({hw})", False, "board"))
    for n in NODES:
        h.at(0.3, Observation(f"running({n})", False, "nodes"))
    bad = set(COMPONENTS)
    h.at(1.0, _bad(*bad))
    steps = tuple(PlanStep("power_up", (hw,)) for hw in HARDWARE) + tuple(
        PlanStep("start_node", (n,)) for n in NODES)
    h.at(8.0, PlanRecord("p1", steps, tuple(sorted(bad))))
    t = 8.1
    for hw in HARDWARE:
        h.action("power_up", hw, t, t + 1.2, plan="p1")
        h.at(t + 1.25, Observation(f"on({hw})", True, "board"))
        bad.discard(hw)
        h.at(t + 1.4, _bad(*bad))
        t += 1.5
    t = 12.6
    for n in NODES:
        if failing and n == "hector_mapping":
            h.action("start_node", n, t, t + 0.6, ActionState.FAILED, "p1", "exit status 1")
            h.action("start_node", n, t + 0.7, t + 1.6, ActionState.TIMEOUT, "p1",
                     "no /map within 0.9 s")
            h.action("start_node", n, t + 1.7, t + 2.0, plan="p1")
        else:
            h.action("start_node", n, t, t + 2.0, plan="p1")
        h.at(t + 2.05, Observation(f"running({n})", True, "nodes"))
        bad.discard(n)
        h.at(t + 2.6, _bad(*bad))
        t += 3.3
    h.telemetry(42, {1: 800.0, 3: 650.0})
    h.write(path)
    return path


def device_shut_down(path: Path, *, action_clock: str = "wall", run: str | None = None,
                     offset: float = 0.0) -> Path:
    h = _History(action_clock, run, offset)
    h.at(0.0, Note("daemon started: robot tedusar"))
    for hw in HARDWARE:
        h.at(0.2, Observation(f"on({hw})", True, "board"))
    for n in NODES:
        h.at(0.3, Observation(f"running({n})", True, "nodes"))
    h.at(0.5, DiagnosisRecord.of([[]], trigger="start"))
    h.at(10.0, BoardEvent("state", 7, {"old": "on", "new": "off"}))
    h.at(10.05, Observation("on(jaguar)", False, "board"))
    h.at(10.2, _bad("jaguar"))
    h.at(10.3, PlanRecord("p1", (PlanStep("power_up", ("jaguar",)),), ("jaguar",)))
    h.action("power_up", "jaguar", 10.4, 11.9, plan="p1")
    h.at(10.9, Observation("ok(/odom)", False, "topics"))
    h.at(10.95, _bad("jaguar", "jaguar_node"))
    h.at(11.95, Observation("on(jaguar)", True, "board"))
    h.at(12.2, _bad("jaguar_node"))
    h.at(12.3, PlanRecord("p2", (PlanStep("stop_node", ("jaguar_node",)),
                                 PlanStep("start_node", ("jaguar_node",))), ("jaguar_node",)))
    h.action("stop_node", "jaguar_node", 12.4, 13.1, plan="p2")
    h.action("start_node", "jaguar_node", 13.2, 15.0, plan="p2")
    h.at(16.3, Observation("ok(/odom)", True, "topics"))
    h.at(16.4, DiagnosisRecord.of([[]], trigger="observation"))
    h.telemetry(20, {1: 800.0, 3: 650.0, 7: 2400.0})
    h.write(path)
    return path


if __name__ == "__main__":
    out = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    for name, make in (("power_up", power_up), ("device_shut_down", device_shut_down)):
        (out / f"{name}.sqlite").unlink(missing_ok=True)
        print(make(out / f"{name}.sqlite"))
    (out / "power_up_failing.sqlite").unlink(missing_ok=True)
    print(power_up(out / "power_up_failing.sqlite", failing=True))


def load_flaps(path: Path, *, run: str | None = "20261123T210826-3fa2") -> Path:
    """A healthy robot on a loaded machine: five times the IMU's topic drops below its rate for
    a moment and the diagnosis blames {imu, imu_node}, retracted 0.2-0.4 s later, within the
    repair debounce (0.5 s), so nothing is repaired (load artefacts, issue 26); then, at 30 s, a
    real fault: the base loses power and is repaired as in ``device_shut_down``."""
    h = _History("wall", run)
    h.at(0.0, Note("daemon started: robot tedusar"))
    h.at(0.5, DiagnosisRecord.of([[]], trigger="start"))
    for t in (4.0, 5.1, 6.0, 14.0, 22.5):
        h.at(t, Observation("ok(/imu_data)", False, "topics"))
        h.at(t + 0.05, _bad("imu", "imu_node"))
        h.at(t + 0.3, Observation("ok(/imu_data)", True, "topics"))
        h.at(t + 0.35, DiagnosisRecord.of([[]], trigger="observation"))
    h.at(30.0, Observation("on(jaguar)", False, "board"))
    h.at(30.1, _bad("jaguar", "jaguar_node"))
    h.at(30.7, PlanRecord("p1", (PlanStep("power_up", ("jaguar",)),
                                 PlanStep("stop_node", ("jaguar_node",)),
                                 PlanStep("start_node", ("jaguar_node",))),
                          ("jaguar", "jaguar_node")))
    h.action("power_up", "jaguar", 30.8, 32.0, plan="p1")
    h.action("stop_node", "jaguar_node", 32.1, 32.6, plan="p1")
    h.action("start_node", "jaguar_node", 32.7, 34.5, plan="p1")
    h.at(35.0, DiagnosisRecord.of([[]], trigger="observation"))
    h.telemetry(38, {1: 800.0, 3: 650.0, 7: 2400.0})
    h.write(path)
    return path
