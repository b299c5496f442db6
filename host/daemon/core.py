"""The daemon: board stream → observers → observations → diagnosis → repair, journaled and shown.

Theory of operation. ``Daemon.run`` builds the pieces from the robot directory — the model and
its clauses (``host.diagnosis``), the observers of its ``observers:`` section, a ``Diagnoser``,
the journal and the web page — and runs four tasks on one asyncio loop:

- the board task keeps a ``BoardClient`` subscribed (reconnecting with backoff) and feeds every
  reading, event and link notice to the observer hub and the ``BoardView``; events and link
  changes are journaled, readings are journaled as 1 Hz telemetry summaries;
- the observer hub calls ``_on_updates`` with every change (and the refreshes that keep
  literals valid); the daemon applies them to the diagnoser (S ⊕ o), journals each change of
  a literal's value (true, false, unknown) and wakes the diagnosis task;
- the diagnosis task diagnoses on every change of the observation set, plus a slow safety tick
  that also expires literals whose observers fell silent; a changed diagnosis is journaled,
  shown, and handed to the repairs (``host.daemon.repairs``), which start after a debounce;
- the status task samples the channels for the page's sparklines a few times a second.

Nothing below the daemon reads the clock: the daemon owns one monotonic clock (``clock``) for
observations and deadlines and one wall clock (``wall``) for the journal and the page.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import logging
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from host.board import BoardClient
from host.board.types import BoardEvent, BoardState, LinkDown, LinkUp, Reading, Rebooted
from host.diagnosis import Diagnoser, DiagnosisResult, generate, load_system
from host.diagnosis.diagnoser import UnknownLiteral
from host.diagnosis.observations import Observation
from host.errors import UserError
from host.journal import (
    BoardEvent as JournalBoardEvent,
)
from host.journal import (
    DiagnosisRecord,
    Journal,
    Note,
    Payload,
    TelemetryDownsampler,
)
from host.journal import (
    Observation as JournalObservation,
)
from host.observers import ObserverHub, check_atoms, load_observers
from host.observers.base import Update
from host.web.server import WebServer
from host.web.status import DiagnosisStatus, MemoryStatusSource, Status
from protocol.constants import EVENT_NAMES, FAULT_NAMES, RESET_NAMES, STATE_NAMES

from .view import BoardView

if TYPE_CHECKING:
    from host.daemon.repairs import Repairs

log = logging.getLogger(__name__)

SOURCE = "daemon"


@dataclass
class DaemonOptions:
    system_dir: Path
    board_url: str
    key: bytes | None = None
    web: tuple[str, int] | None = None
    journal: Path | None = None
    dry_run: bool = False
    rate_hz: int = 100
    zenoh_listen: list[str] | None = None
    safety_tick_s: float = 2.0
    repair_debounce_s: float = 0.5
    max_card: int | None = None  # no bound: a power-up has every component abnormal
    max_count: int = 20
    time_budget_s: float = 0.5
    node_env: Mapping[str, str] = field(default_factory=dict)  # for the processes it starts
    max_parallel_steps: int | None = None  # repair steps at once; None: as the plan allows


def flag_names(mask: int, names: tuple[str, ...]) -> list[str]:
    return [n for i, n in enumerate(names) if mask >> i & 1]


class Daemon:
    def __init__(
        self,
        opts: DaemonOptions,
        clock: Callable[[], float] = time.monotonic,
        wall: Callable[[], float] = time.time,
    ) -> None:
        self.opts = opts
        self.clock = clock
        self.wall = wall
        self.model = load_system(opts.system_dir)
        self.theory = generate(self.model)
        self.observers_cfg = load_observers(opts.system_dir, self.model)
        unknown = check_atoms(self.observers_cfg, self.theory)
        if unknown:
            raise UserError(
                f"{self.observers_cfg.file}: observers report {', '.join(unknown)}, "
                "which no clause of the model mentions",
                "remove those observers or extend the model",
            )
        if opts.zenoh_listen is not None:
            self.observers_cfg.source = dataclasses.replace(
                self.observers_cfg.source, listen=tuple(opts.zenoh_listen))
        self.diagnoser = Diagnoser(self.theory)
        self.hub = ObserverHub(self.observers_cfg.observers, self._on_updates, clock=clock)
        self.view = BoardView()
        self.status = MemoryStatusSource(Status(robot=self.model.name))
        self.journal: Journal | None = None
        self.web: WebServer | None = None
        self.web_port: int | None = None
        self.client: BoardClient | None = None
        self.link_up = False
        self.result: DiagnosisResult | None = None
        self._values: dict[str, bool | None] = {}
        self._changed = asyncio.Event()
        self._stop = asyncio.Event()
        self._tasks: list[asyncio.Task[Any]] = []
        self._telemetry = TelemetryDownsampler(period_s=1.0)
        self._counters = {"observation_changes": 0, "diagnosis_runs": 0}
        self._latency_sum = 0.0
        self.repairs: Repairs | None = None  # built in start()

    # --- the journal ------------------------------------------------------------------

    def record(self, payload: Payload) -> None:
        if self.journal is not None:
            self.journal.record(payload, wall=self.wall(), mono=self.clock())

    # --- running ----------------------------------------------------------------------

    async def start(self) -> None:
        """Open the journal, the web page and the observers, and start the tasks."""
        from host.daemon.repairs import Repairs

        opts = self.opts
        if opts.journal is not None:
            self.journal = Journal(opts.journal)
        self.record(Note(f"dxboard run {self.model.name}: board {opts.board_url}"
                         + (" (dry run)" if opts.dry_run else "")))
        if opts.web is not None:
            self.web = WebServer(self.status, self.journal.reader if self.journal else None)
            self.web_port = await self.web.start(*opts.web)
        self.repairs = Repairs(self)
        spec = self.observers_cfg.source
        try:
            self.source = spec.open()
        except Exception as exc:  # zenoh raises its own ZError: say what to do instead
            raise UserError(
                f"cannot open the topic source ({spec.kind} on {', '.join(spec.listen)}): "
                f"{str(exc).split(' at /')[0]}",
                "is another dxboard run using it? give --zenoh tcp/127.0.0.1:PORT",
            ) from None
        await self.hub.start(self.source, self.observers_cfg.processes,
                             poll=self.observers_cfg.poll)
        self._tasks = [
            asyncio.ensure_future(self._board_task()),
            asyncio.ensure_future(self._diagnosis_task()),
            asyncio.ensure_future(self._status_task()),
        ]

    async def wait(self) -> None:
        """Run until ``stop()`` is called or a task fails (its exception is raised here)."""
        stopper = asyncio.ensure_future(self._stop.wait())
        done, _ = await asyncio.wait([stopper, *self._tasks],
                                     return_when=asyncio.FIRST_COMPLETED)
        stopper.cancel()
        for task in done:
            if task is not stopper and not task.cancelled() and task.exception() is not None:
                raise task.exception()  # type: ignore[misc]

    def stop(self) -> None:
        self._stop.set()

    async def close(self) -> None:
        """Stop everything, in the reverse order of starting; idempotent."""
        for task in self._tasks:
            task.cancel()
        for task in self._tasks:
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        self._tasks = []
        if self.repairs is not None:
            await self.repairs.close()
        await self.hub.close()
        with contextlib.suppress(Exception):
            self.source.close()
        if self.web is not None:
            await self.web.close()
            self.web = None
        telemetry = self._telemetry.flush()
        if telemetry is not None:
            self.record(telemetry)
        self.record(Note("dxboard run stopped"))
        if self.journal is not None:
            await self.journal.flush()
            self.journal.close()
            self.journal = None
        self.diagnoser.close()

    # --- observations -----------------------------------------------------------------

    def _on_updates(self, updates: list[Update]) -> None:
        changed = False
        for u in updates:
            if isinstance(u, Observation):
                atom, value, source = u.literal.atom, u.literal.positive, u.source
                try:
                    self.diagnoser.observe(u)
                except UnknownLiteral:
                    log.warning("observation %s is not in the model; ignored", u.literal)
                    continue
            else:
                atom, value, source = u.atom, None, u.source
                self.diagnoser.retract(atom)
            if self._values.get(atom, "absent") != value:
                self._values[atom] = value
                self.record(JournalObservation(atom, value, source))
                self._counters["observation_changes"] += 1
                changed = True
        if self.repairs is not None:
            self.repairs.observed(updates)
        if changed:
            self.status.update(observations=dict(self._values),
                               observation_changes=self._counters["observation_changes"],
                               updated=self.wall())
            self._changed.set()

    # --- diagnosis --------------------------------------------------------------------

    async def _diagnosis_task(self) -> None:
        while True:
            trigger = "observation"
            try:
                await asyncio.wait_for(self._changed.wait(), self.opts.safety_tick_s)
            except TimeoutError:
                trigger = "safety tick"
            self._changed.clear()
            self.diagnose(trigger)

    def diagnose(self, trigger: str) -> DiagnosisResult:
        """One diagnosis now; journaled and shown when it differs from the last one."""
        for gone in self.diagnoser.expire(self.clock()):
            if self._values.get(gone.literal.atom) is not None:
                self._values[gone.literal.atom] = None
                self.record(JournalObservation(gone.literal.atom, None, "expired"))
        t0 = time.perf_counter()
        result = self.diagnoser.diagnose(max_card=self.opts.max_card,
                                         max_count=self.opts.max_count,
                                         time_budget_s=self.opts.time_budget_s)
        elapsed = time.perf_counter() - t0
        self._counters["diagnosis_runs"] += 1
        self._latency_sum += elapsed
        old = self.result
        self.result = result
        changed = old is None or old.bad_sets() != result.bad_sets()
        if changed:
            self.record(DiagnosisRecord.of(
                result.bad_sets(), complete=result.complete, trigger=trigger,
                elapsed_s=elapsed, probabilities=[d.probability for d in result.diagnoses]))
        self.status.update(
            diagnoses=tuple(DiagnosisStatus(tuple(sorted(d.bad)), d.probability)
                            for d in result.diagnoses if d.bad),
            diagnosis_complete=result.complete,
            diagnosis_runs=self._counters["diagnosis_runs"],
            diagnosis_latency_sum_s=self._latency_sum,
            diagnosis_last_latency_s=elapsed,
            updated=self.wall(),
        )
        if changed and self.repairs is not None:
            self.repairs.diagnosis_changed(result)
        return result

    def healthy(self) -> bool:
        """True when the current diagnosis is 'nothing is broken'."""
        return self.result is not None and self.result.bad_sets() in ([], [frozenset()])

    # --- the board ----------------------------------------------------------------------

    async def _board_task(self) -> None:
        backoff = 0.2
        while True:
            try:
                async with BoardClient(self.opts.board_url, self.opts.key) as client:
                    self.client = client
                    backoff = 0.2
                    await self._board_state(await client.state(), "connected")
                    async for item in client.subscribe(self.opts.rate_hz):
                        self.hub.feed_board(item)
                        self.view.apply(item)
                        await self._board_item(client, item)
            except UserError as exc:  # unreachable, refused, ...: keep trying, say so once
                if self.link_up or backoff == 0.2:
                    self.record(Note(f"board: {exc}", "error"))
                    log.warning("board: %s", exc)
                self._set_link(False)
            finally:
                self.client = None
            await asyncio.sleep(backoff)
            backoff = min(backoff * 2, 5.0)

    async def _board_state(self, state: BoardState, why: str) -> None:
        self.hub.feed_board(state)
        self.view.reset(state)
        self._set_link(True)
        self.status.update(channels=self.view.channels(), updated=self.wall())
        self.record(JournalBoardEvent(why, None, {
            "boot_id": f"{state.boot_id:08x}",
            "reset_cause": RESET_NAMES[state.reset_cause]
            if state.reset_cause < len(RESET_NAMES) else state.reset_cause,
            "config_status": state.config_status,
        }))

    async def _board_item(self, client: BoardClient, item: object) -> None:
        if isinstance(item, Reading):
            summary = self._telemetry.add(
                item.host_mono, dict(enumerate(float(c) for c in item.currents_ma)))
            if summary is not None:
                self.record(summary)
        elif isinstance(item, BoardEvent):
            kind = EVENT_NAMES[item.kind] if item.kind < len(EVENT_NAMES) else str(item.kind)
            name = self.view.names()[item.channel] if item.channel < len(self.view.names()) \
                else "board"
            self.record(JournalBoardEvent(kind, None if item.channel == 255 else item.channel, {
                "name": name,
                "from": STATE_NAMES[item.old_state] if item.old_state < 6 else item.old_state,
                "to": STATE_NAMES[item.new_state] if item.new_state < 6 else item.new_state,
                "faults": flag_names(item.faults, FAULT_NAMES),
                "value_ma": item.value_ma,
            }))
        elif isinstance(item, LinkDown):
            self._set_link(False)
            self.record(JournalBoardEvent("link_down", None, {"reason": item.reason}))
        elif isinstance(item, LinkUp | Rebooted):
            if isinstance(item, Rebooted):
                self.record(JournalBoardEvent("rebooted", None, {
                    "old_boot_id": f"{item.old_boot_id:08x}",
                    "new_boot_id": f"{item.new_boot_id:08x}", "how": item.how}))
            await self._board_state(await client.state(),
                                    "link_up" if isinstance(item, LinkUp) else "state")

    def _set_link(self, up: bool) -> None:
        if up != self.link_up:
            self.link_up = up
            self.status.update(board_link_up=up, updated=self.wall())

    async def _status_task(self) -> None:
        while True:
            await asyncio.sleep(0.2)
            if self.link_up:
                self.view.sample()
                self.status.update(channels=self.view.channels(), updated=self.wall())
