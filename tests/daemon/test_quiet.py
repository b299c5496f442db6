"""Ten simulated minutes of a fault-free robot: no diagnosis but healthy, no repair.

The daemon runs on wall time with real processes, so ten minutes of it would take ten minutes.
Instead this test runs the daemon's own pieces on one simulated clock, as fast as they go:

- the board: the real firmware on the emulator's simulated electronics (``emulator.sim``,
  ``models/tedusar/emulator.yaml`` with its noise and seed, ``board.json`` as flashed),
  advanced 10 ms at a time; after every step the test builds the ``Reading`` a
  ``BoardClient`` would deliver, field for field as the firmware's ``Session.measurement``
  sends it (physical switch states, live faults, every channel's current) — 100 Hz;
- the host: a real ``Daemon`` (``host.daemon.core``) built from ``models/tedusar`` with its
  monotonic and wall clocks set to the simulated clock, its journal in a temporary file, the
  real repair service (``host.repair.service``) and an ``ObserverHub`` holding the real
  hardware observer of ``system.yaml`` (settle 3, link timeout 0.25 s) with the daemon's sink.
  Deadlines (link timeout, literal refreshes) are fired when the simulated clock reaches
  them, as the hub's timers would; the daemon diagnoses after every change of the
  observations and on its safety tick (every ``safety_tick_s`` of simulated time), as its
  diagnosis runner's task does, expiring stale literals each time.

The devices (jaguar, hokuyo, laser_alignment, thermal_camera) are switched on as the power-up
repair does, then the robot is up once the diagnosis is healthy; from then on, over 60 000
readings with noise, the board raises no event, the daemon's diagnosis never names a
component, the repair trigger is never asked to act, and the journal holds no plan and no action.

What it leaves out: the topic and process observers (their inputs come from real node
processes, which do not run on a simulated clock); they are covered on wall time by
``test_repairs.py``. This test is about the board side: that the noise of 100 Hz readings
never crosses a current band or the link rule and so never starts a repair.
"""

from __future__ import annotations

import json
from pathlib import Path

from emulator.model import load as load_emulator
from emulator.sim import Emulator
from host.board.types import Reading
from host.daemon.core import Daemon, DaemonOptions
from host.diagnosis import DiagnosisResult
from host.journal import ActionRecord, DiagnosisRecord, Journal, JournalReader, PlanRecord
from host.observers import ObserverHub
from host.observers.base import Update
from host.observers.hardware import HardwareObserver
from tests.daemon.runner import TEDUSAR
from tests.wait import wait_until_async

MINUTES = 10
TICK_MS = 10
DEVICES = {"laser_alignment": 1, "hokuyo": 3, "thermal_camera": 6, "jaguar": 7}


class SimClock:
    """The one simulated clock: the emulator's milliseconds as the host's seconds."""

    def __init__(self, emulator: Emulator, wall0: float = 1.7e9) -> None:
        self.emulator = emulator
        self.wall0 = wall0

    def mono(self) -> float:
        return self.emulator.now / 1000.0

    def wall(self) -> float:
        return self.wall0 + self.mono()


def reading(emu: Emulator, seq: int, now: float, wall: float) -> Reading:
    """What the board pushes after a step (``firmware.session.Session.measurement``)."""
    b = emu.board
    on = faults = 0
    currents = []
    for i, c in enumerate(b.channels):
        if c.physical:
            on |= 1 << i
        if c.live:
            faults |= 1 << i
        currents.append(int(c.current_ma))
    return Reading(host_time=wall, host_mono=now, boot_id=1, seq=seq,
                   uptime_ms=emu.now, input_mv=int(b.input_mv), on_mask=on,
                   fault_mask=faults, currents_ma=tuple(currents))


async def test_ten_fault_free_simulated_minutes_perform_no_repair(tmp_path: Path) -> None:
    emu = Emulator(load_emulator(TEDUSAR),
                   board_config=json.loads((TEDUSAR / "board.json").read_text()))
    clock = SimClock(emu)
    journal_path = tmp_path / "journal.sqlite"
    daemon = Daemon(DaemonOptions(system_dir=TEDUSAR, board_url="sim://", journal=journal_path),
                    clock=clock.mono, wall=clock.wall)
    daemon.attach_journal(Journal(journal_path))
    hardware = [o for o in daemon.observers_cfg.observers if isinstance(o, HardwareObserver)]
    assert len(hardware) == 1
    changed = False

    def sink(updates: list[Update]) -> None:
        nonlocal changed
        daemon_sink(updates)
        changed = True

    daemon_sink = daemon.hub.sink
    daemon.hub = ObserverHub(hardware, sink, clock=clock.mono)
    triggers: list[tuple[float, list[frozenset[str]]]] = []
    real_trigger = daemon.diagnosis.on_changed
    assert real_trigger is not None

    def trigger(result: DiagnosisResult) -> None:
        if not daemon.healthy():  # the case in which the service schedules a repair
            triggers.append((clock.mono(), result.bad_sets()))
        real_trigger(result)

    daemon.diagnosis.on_changed = trigger
    (hw,) = hardware
    cursor = emu.board.events.read(0, 1000)[1]
    seq = 0
    next_safety = 0.0

    async def step() -> None:
        nonlocal seq, changed, next_safety
        emu.advance(TICK_MS)
        now = clock.mono()
        seq += 1
        changed = False
        daemon.hub.feed_board(reading(emu, seq, now, clock.wall()), now)
        deadline = hw.next_deadline()
        if deadline is not None and deadline <= now:
            updates = hw.tick(now)
            if updates:
                sink(updates)
        if changed:
            await daemon.diagnosis.run("observation")
        if now >= next_safety:
            next_safety = now + daemon.opts.safety_tick_s
            await daemon.diagnosis.run("safety tick")

    # the pipeline sees: with the devices still off, the diagnosis names them
    for _ in range(50):
        await step()
    assert daemon.result is not None
    assert set(DEVICES) <= set().union(*daemon.result.bad_sets()), daemon.result
    # power-up, as the repair does it: each device on, 0.2 s apart; then until healthy
    for ch in DEVICES.values():
        assert emu.board.switch(ch, True)[0] == 0
        for _ in range(20):
            await step()
    for _ in range(1000):
        await step()
        if daemon.healthy() and all(hw.bands.get(d) == "nominal" for d in DEVICES):
            break
    assert daemon.healthy(), daemon.result
    up_at = clock.mono()
    cursor = emu.board.events.read(cursor, 1000)[1]
    triggers_before = len(triggers)
    runs_before = daemon.status.snapshot().diagnosis_runs

    for _ in range(MINUTES * 60 * 1000 // TICK_MS):
        await step()
        assert daemon.healthy(), f"at {clock.mono() - up_at:.2f} s: {daemon.result}"

    assert clock.mono() - up_at >= MINUTES * 60
    assert seq >= MINUTES * 60 * 100
    events, _, lost = emu.board.events.read(cursor, 1000)
    assert events == [] and lost == 0  # the board itself saw nothing to act on
    assert len(triggers) == triggers_before  # no repair asked for after the robot is up
    assert daemon.status.snapshot().diagnosis_runs - runs_before >= MINUTES * 60 / 2  # it did run
    assert set(hw.bands.values()) == {"nominal"}
    # a repair whose debounce is pending would start: wait until none is pending
    await wait_until_async(lambda: daemon.repairs.busy or not daemon.repairs.active,
                           what="no repair pending")
    assert not daemon.repairs.busy
    await daemon.repairs.close()
    assert daemon.journal is not None
    await daemon.journal.flush()
    daemon.journal.close()
    daemon.diagnosis.close()

    entries = JournalReader(journal_path).query(limit=1_000_000)
    assert not [e for e in entries if isinstance(e.payload, PlanRecord | ActionRecord)]
    after = [e.payload for e in entries if e.mono > up_at
             and isinstance(e.payload, DiagnosisRecord)]
    assert all(p.diagnoses in ((), ((),)) for p in after), after
