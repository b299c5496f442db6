"""The daemon: board stream → observers → one observation set → diagnosis → repair service, and
one event stream out.

Theory of operation. ``Daemon`` builds the pieces from the robot directory and only wires them:

- the model and its clauses (``host.diagnosis``), the observers of its ``observers:`` section
  and their ``ObserverHub``;
- one ``ObservationSet``: the hub's updates go into it (S ⊕ o), the ``DiagnosisRunner`` diagnoses
  snapshots of it off the loop, and the repair executor's effect checks wait on it;
- the ``RepairService`` (``host.repair.service``), fed every changed diagnosis and the board
  link, emitting plans, steps, results and quarantines;
- one ``EventStream``: everything the daemon learns or does is emitted there once, as a typed
  event (``host.events``), and the journal, the one fold of it (``host.fold``) that the web
  page's status (``host.web.fold``) and ``/diagnostics`` read, the terminal's lines
  (``host.commands.terminal``) and any other reader are projections of it.

Tasks on one asyncio loop: the board task keeps a ``BoardClient`` subscribed (a new client
after a failed one, waiting as the one reconnect policy, ``host.board.backoff``, says) and
feeds every reading, event and link notice to the hub and the ``BoardView``; the diagnosis
runner's task; the sample task that emits the channels a few times a second; the
lag probe of the metrics (``host.fleet.metrics.LagProbe``: how late the loop runs) and its
watch (``lagwatch``: a ``LoopLag`` event when the daemon falls behind or catches up). Nothing
below the daemon reads the clock: the daemon owns one monotonic clock (``clock``) for
observations and deadlines and one wall clock (``wall``) for the journal and the page.
"""

from __future__ import annotations

import asyncio
import dataclasses
import gc
import logging
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from host.board import BoardClient
from host.board.backoff import Backoff
from host.board.types import (
    BoardEvent,
    BoardState,
    LinkDown,
    LinkUp,
    Reading,
    Rebooted,
    StreamItem,
)
from host.board.view import BoardView
from host.diagnosis import Diagnoser, generate, load_system, observation_lags
from host.diagnosis.healthy import healthy_values
from host.diagnosis.logic import Theory
from host.diagnosis.model import SystemModel
from host.diagnosis.observations import ObservationSet
from host.diagnosis.runner import DiagnosisRunner, fold_updates
from host.errors import RemoteError, UserError
from host.events import JOURNALED, Event, LinkChange, Note, RunStarted, Stamped
from host.events import BoardEvent as BoardEventRecord
from host.fleet.metrics import FleetMetrics, LagProbe
from host.fold import EventFold
from host.journal import Journal, TelemetryDownsampler
from host.journal.runs import Run, list_runs, new_run_id
from host.journal.summary import Replay
from host.observers import ObserverHub, check_atoms, load_observers
from host.observers.base import Update
from host.observers.config import ObserversConfig, SourceSpec
from host.observers.sources.zenoh_auth import ENV as AUTH_ENV
from host.observers.sources.zenoh_auth import beside
from host.observers.starvation import wire_probes
from host.operator.server import OperatorServer
from host.repair import service
from host.repair.external import ExternalNode, lifecycle_nodes, load_external
from host.repair.planner import RepairPlanner
from host.repair.processes import ProcessConfig, load_processes, managed_nodes
from host.web.fold import PageProjection
from host.web.server import WebServer
from host.web.status import MemoryStatusSource, Status

from . import journalwatch, lagwatch
from .external import ExternalActuators, check_external
from .stages import StopStages
from .stream import EventStream

log = logging.getLogger(__name__)

SAMPLE_S = 0.2  # the page's sparklines: a sample of every channel this often
STOP_BUDGET_S = 6.5  # close(): all its stages (host.daemon.stages), below the signals' 9 s
JOURNAL_S = 1.5  # of which the journal's last commit may take this much
RECONNECT_FIRST_S = 0.2  # the board task's first wait for a new client after a failed one...
RECONNECT_CAP_S = 5.0  # ...doubling up to this (host.board.backoff, jittered)


@dataclass
class DaemonOptions:
    system_dir: Path
    board_url: str
    key: bytes | None = None
    web: tuple[str, int] | None = None
    web_allow_origins: tuple[str, ...] = ()  # other origins the page's data may be read from
    journal: Path | None = None
    dry_run: bool = False
    rate_hz: int = 100
    zenoh_listen: list[str] | None = None
    middleware: str | None = None  # zenoh or ros2 instead of the model's source kind
    safety_tick_s: float = 2.0
    repair_debounce_s: float = 0.5
    max_card: int | None = None  # no bound: a power-up has every component abnormal
    max_count: int = 20
    time_budget_s: float = 0.5
    node_env: Mapping[str, str] = field(default_factory=dict)  # for the processes it starts
    max_parallel_steps: int | None = None  # repair steps at once; None: as the plan allows
    device_boot_s: Mapping[str, float] = field(default_factory=dict)  # settle times of devices
    operator: Path | None = None  # the operator socket (quarantine, hold); None: none
    device_pids: Mapping[str, int] = field(default_factory=dict)  # process feeding a device
    robot: str = ""  # the robot's name in the metrics and on the page; "": the model's
    site: str = "default"  # where the robot is, a label of every metric (host.fleet)


@dataclass(frozen=True)
class RobotFiles:
    """Everything the daemon reads from a robot directory, loaded and checked."""

    model: SystemModel
    theory: Theory
    observers: ObserversConfig
    processes: Mapping[str, ProcessConfig]
    planner: RepairPlanner
    external: Mapping[str, ExternalNode] = field(default_factory=dict)  # started elsewhere


def load_robot(system_dir: Path, zenoh_listen: list[str] | None = None,
               middleware: str | None = None) -> RobotFiles:
    """Load and check the robot directory (``system.yaml``, ``repair.pddl``): a ``UserError``
    naming the file, the line and the fix before anything is started."""
    model = load_system(system_dir)
    theory = generate(model)
    observers = load_observers(system_dir, model)
    unknown = check_atoms(observers, theory)
    if unknown:
        raise UserError(f"{observers.file}: observers report {', '.join(unknown)}, "
                        "which no clause of the model mentions",
                        "remove those observers or extend the model")
    if zenoh_listen is not None:
        observers.source = dataclasses.replace(observers.source, listen=tuple(zenoh_listen))
    if middleware is not None:
        observers.source = dataclasses.replace(observers.source, kind=middleware)
    processes = load_processes(system_dir, model)
    external = load_external(system_dir, model, processes)
    check_external(observers.file, external, observers.source.kind)
    managed = managed_nodes(processes, observers.source.kind)
    return RobotFiles(model, theory, observers, processes,
                      RepairPlanner.for_system(system_dir, managed=managed), external)


def _middleware_env(source: SourceSpec) -> dict[str, str]:
    """What the nodes the daemon starts need to use its middleware (and ROS 2 domain)."""
    env = {"DXBOARD_MIDDLEWARE": "ros2" if source.kind == "ros2" else "zenoh"}
    if source.kind == "ros2" and source.domain is not None:
        env["ROS_DOMAIN_ID"] = str(source.domain)
    return env


def freeze_long_lived() -> None:
    """Move what the process holds now (the model, its clauses, the diagnoser's encoding, the
    observers) out of the cyclic collector's reach, once the daemon has started. A full
    collection holds the GIL while it walks every tracked object, so it stops the event loop
    even while a diagnosis runs in its worker thread: with a 10,000-component model one took
    0.3-3 s on this machine, over the board link's 0.25 s deadline (benchmarks/stall.py). The
    frozen objects live as long as the run anyway; what is made later is collected as before.
    """
    gc.collect()
    gc.freeze()


class Daemon:
    def __init__(self, opts: DaemonOptions, clock: Callable[[], float] = time.monotonic,
                 wall: Callable[[], float] = time.time, files: RobotFiles | None = None) -> None:
        self.opts = opts
        self.clock = clock
        robot = files or load_robot(opts.system_dir, opts.zenoh_listen, opts.middleware)
        self.model, self.theory, self.observers_cfg = robot.model, robot.theory, robot.observers
        self._managed = [*managed_nodes(robot.processes, robot.observers.source.kind),
                         *lifecycle_nodes(robot.external)]  # their reconfigure_node too
        self.external = ExternalActuators(robot.external, robot.observers.source.kind,
                                          robot.observers.source.domain)
        self.stream = EventStream(clock, wall)
        self.emit = self.stream.emit
        self.status = MemoryStatusSource(Status(robot=opts.robot or self.model.name))
        self.fold = EventFold()  # the one fold of the stream; the page and /diagnostics read it
        self.stream.subscribe(self.fold)
        PageProjection(self.status, self.fold)
        self.lag = LagProbe()
        self.metrics = FleetMetrics(self.status, robot=opts.robot or self.model.name,
                                    site=opts.site, components=list(self.model.components),
                                    protected=self.model.protected, lag=self.lag)
        self.stream.subscribe(self.metrics.events)
        self.observations = ObservationSet()
        self._known = self.theory.observable_atoms()
        self.diagnosis = DiagnosisRunner(
            Diagnoser(self.theory, observations=self.observations,
                      lags=observation_lags(self.observers_cfg.observers)), self.observations,
            self.emit, clock=clock, on_changed=self._diagnosis_changed,
            safety_tick_s=opts.safety_tick_s, max_card=opts.max_card, max_count=opts.max_count,
            time_budget_s=opts.time_budget_s)
        self.hub = ObserverHub(self.observers_cfg.observers, self._on_updates, clock=clock)
        self.view = BoardView()
        journal = opts.journal or Path("dxboard-journal.sqlite")
        # zenoh: the endpoint admits only peers with this file's credentials (the nodes)
        self.zenoh_auth = beside(journal) if self.observers_cfg.source.kind == "zenoh" else None
        self.repairs = service.build(
            robot.planner, self.model, robot.processes, observations=self.observations,
            observable={a for o in self.hub.observers for a in o.atoms()},
            diagnose=lambda: self.diagnosis.run("repair"), emit=self.emit,
            logs_dir=journal.parent / (journal.stem + "-logs"),
            env={"DXBOARD_ZENOH": self.observers_cfg.source.listen[0],
                 **_middleware_env(self.observers_cfg.source),
                 **({AUTH_ENV: str(self.zenoh_auth)} if self.zenoh_auth else {}),
                 "DXBOARD_ROBOT": str(opts.system_dir.resolve()), **opts.node_env},
            device_boot_s=opts.device_boot_s, on_start=self._started, dry_run=opts.dry_run,
            clock=clock, max_parallel=opts.max_parallel_steps,
            debounce_s=opts.repair_debounce_s, board=self.model.board or "board",
            confirmed=self.hub.confirmed,
            judge_s={a: t for o in self.hub.observers for a, t in o.judge_s().items()})
        self.journal: Journal | None = None
        self.run_id = ""  # set by start()
        self.web: WebServer | None = None
        self.web_port: int | None = None
        self.operator: OperatorServer | None = None
        self.client: BoardClient | None = None
        self.reconnect = Backoff(RECONNECT_FIRST_S, RECONNECT_CAP_S)  # between two clients
        self.link_up = False
        self._stop = asyncio.Event()
        self._tasks: list[asyncio.Task[Any]] = []
        self._telemetry = TelemetryDownsampler(period_s=1.0)
        self.ros_out: Any = None  # the ROS 2 publisher, with a ros2 source
        self.lifecycle: Any = None  # the lifecycle actuator, with a ros2 source
        self._stages: StopStages | None = None  # the stop, once close() began

    @property
    def result(self) -> Any:
        """The latest diagnosis (None before the first)."""
        return self.diagnosis.result

    def healthy(self) -> bool:
        """True when the current diagnosis is 'nothing is broken'."""
        return service.is_healthy(self.diagnosis.result)

    # --- running ----------------------------------------------------------------------

    async def start(self) -> None:
        """Open the journal, the web page and the observers, and start the tasks."""
        opts = self.opts
        if opts.journal is not None and self.journal is None:
            self.attach_journal(Journal(opts.journal))
        # every entry from here to the next run's start is this run's (host.journal.runs); the
        # healthy value of each atom lets the page colour observations by health
        self.run_id = new_run_id(self.stream.wall())
        previous = list_runs(self.journal.reader)[-1:] if self.journal is not None else []
        self.emit(RunStarted(self.run_id, self.model.name, opts.board_url, opts.dry_run,
                             str(opts.operator or ""), healthy_values(self.theory)))
        if self.journal is not None:
            self._restore(self.journal, previous[0] if previous else None)
        if opts.web is not None:
            self.metrics.journal = self.journal
            self.web = WebServer(self.status, self.journal.reader if self.journal else None,
                                 metrics=self.metrics.render,
                                 allow_origins=opts.web_allow_origins)
            self.web_port = await self.web.start(*opts.web)
        if opts.operator is not None:
            self.operator = OperatorServer(self.repairs, opts.operator)
            await self.operator.start()
        spec = self.observers_cfg.source
        try:
            self.source = spec.open(self.zenoh_auth)
        except Exception as exc:  # zenoh raises its own ZError: say what to do instead
            raise UserError(
                f"cannot open the topic source ({spec.kind} on {', '.join(spec.listen)}): "
                f"{str(exc).split(' at /')[0]}",
                "is another dxboard run using it? give --zenoh tcp/127.0.0.1:PORT",
            ) from None
        if spec.kind == "ros2":  # the daemon reports through ROS 2 too (host.ros.publisher)
            self.source.on_stranger = self._stranger  # type: ignore[attr-defined]
            from host.ros.lifecycle import LifecycleActuator
            from host.ros.publisher import RosPublisher
            self.ros_out = RosPublisher(list(self.model.components), spec.domain, fold=self.fold)
            self.lifecycle = LifecycleActuator(spec.domain, self._managed)  # reconfigure_node
            self.lifecycle.open()  # its node now, each managed node's services once seen
            self.repairs.executor.actuators.add("reconfigure_node",
                                                self.lifecycle.reconfigure_node)
        self.external.open(self.repairs.executor.actuators)  # restart_node, lifecycle manager
        await self.hub.start(self.source, self.observers_cfg.processes,
                             poll=self.observers_cfg.poll)
        watcher = self.hub.watcher
        wired = wire_probes(self.hub.observers, self.model,
                            watcher.pid if watcher is not None else lambda _: None,
                            opts.device_pids, way_in=[os.getpid()])
        log.info("silences judged in the publishers' own time: %s", ", ".join(
            f"{t} ({' '.join(n + f)})" for t, (n, f) in wired.items()) or "none")
        await self.repairs.adopt()
        freeze_long_lived()
        self._tasks = [asyncio.ensure_future(t) for t in (
            self._board_task(), self.diagnosis.task(), self._sample_task(), self.lag.run(),
            lagwatch.watch(self.lag, self.emit))]
        if self.journal is not None:  # a journal that cannot write says so (a full disk)
            self._tasks.append(asyncio.ensure_future(journalwatch.watch(self.journal,
                                                                        self.emit)))

    def _stranger(self, topic: str, node: str) -> None:
        """A node the model does not name published one of its topics (ROS 2): said once."""
        owners = ", ".join(c.name for c in self.model.publishers(topic))
        self.emit(Note(f"security: node {node} publishes {topic}, which the model says only "
                       f"{owners} publishes: its messages are ignored for diagnosis", "warning"))

    def _restore(self, journal: Journal, previous: Run | None) -> None:
        """Quarantines and holds that earlier runs left in the journal stay in force; a repair
        the previous run was killed in is said (the robot is diagnosed afresh)."""
        past = Replay.of(journal.reader.query(kind=("quarantine", "hold"), limit=None))
        self.repairs.restore(past.quarantined, past.held)
        if previous is None:
            return
        actions = journal.reader.tail(200, kind="action", after_id=previous.after_id,
                                      to_id=previous.last_id)
        cut = [a for a in Replay.of(actions).actions.values() if a.finished is None]
        if cut:
            self.emit(Note("an earlier run stopped during " + ", ".join(
                f"{a.action}({','.join(a.args)})" for a in cut)
                + "; the robot is diagnosed afresh and repaired from what is seen now",
                "warning"))

    def attach_journal(self, journal: Journal) -> None:
        """Journal every journaled event from now on (the journal is a projection too)."""
        self.journal = journal

        def record(s: Stamped) -> None:
            if s.event.kind in JOURNALED:
                journal.record(s.event, wall=s.wall, mono=s.mono)

        self.stream.subscribe(record)

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
        """Stop everything, in the reverse order of starting (but the observers before the
        nodes, whose silence the stop causes); idempotent. Each stage has a
        deadline within ``STOP_BUDGET_S`` (``host.daemon.stages``): one that overruns it is
        cut short (the nodes then get SIGKILL), logged, and the stop goes on. The stage
        running now is ``self.closing`` (``host.launch.stopping`` says it while it waits)."""
        stages = self._stages = StopStages(STOP_BUDGET_S)
        keep = JOURNAL_S + 0.5  # the journal's last commit comes late: keep it its time

        if self._tasks:
            running, self._tasks = self._tasks, []
            for task in running:
                task.cancel()
            await stages.run("the daemon's tasks (the board link, the diagnosis)",
                             asyncio.gather(*running, return_exceptions=True), 1.0,
                             reserve_s=keep)
        if self.operator is not None:
            operator, self.operator = self.operator, None
            await stages.run("the operator socket", operator.close(), 0.5, reserve_s=keep)
        # the observers before the nodes: a topic whose publisher the stop ends is not judged
        # silent (nor said so on the terminal) while the daemon itself stops it
        await stages.run("the observers", self.hub.close(), 1.0, reserve_s=keep)
        sup = self.repairs.executor.actuators.supervisor
        await stages.run("the repairs and the nodes they started", self.repairs.close(), 3.0,
                         on_cut=None if sup is None else sup.kill_all, reserve_s=keep)
        source = getattr(self, "source", None)
        if source is not None:
            await stages.run("the topic source", source.close, 1.0, reserve_s=keep)
        if self.ros_out is not None:
            ros_out, self.ros_out = self.ros_out, None
            await stages.run("the ROS 2 publishers", ros_out.close, 0.5, reserve_s=keep)
        if self.lifecycle is not None:
            lifecycle, self.lifecycle = self.lifecycle, None
            await stages.run("the lifecycle client", lifecycle.close, 0.5, reserve_s=keep)
        await stages.run("the nodes started elsewhere (their lifecycle clients)",
                         self.external.close, 0.5, reserve_s=keep)
        if self.web is not None:
            web, self.web = self.web, None
            await stages.run("the web page", web.close(), 1.0, reserve_s=keep)
        telemetry = self._telemetry.flush()
        if telemetry is not None:
            self.emit(telemetry)
        if stages.cut:
            self.emit(Note("the stop cut short " + ", ".join(stages.cut), "warning"))
        self.emit(Note("dxboard run stopped"))
        if self.journal is not None:
            journal, self.journal = self.journal, None
            if not await stages.run("the journal's last commit", journal.flush(), JOURNAL_S):
                log.error("journal %s: not everything was committed within the stop's "
                          "deadline", journal.path)
            await stages.run("the journal file", journal.close, 0.5)
        await stages.run("the diagnosis engine", self.diagnosis.close, 0.5)
        gc.unfreeze()  # what the run kept may be collected again (tests run daemons in turn)
        self.closing = "the rest"

    @property
    def closing(self) -> str:
        """What ``close()`` is closing now ("" before it started)."""
        return self._stages.current if self._stages is not None else ""

    @closing.setter
    def closing(self, what: str) -> None:
        if self._stages is not None:
            self._stages.current = what

    # --- observations and diagnoses -----------------------------------------------------

    def _on_updates(self, updates: list[Update]) -> None:
        if fold_updates(updates, self.observations, self._known, self.emit):
            self.diagnosis.poke()

    def _diagnosis_changed(self, result: Any) -> None:
        self.repairs.diagnosed(result)

    def _started(self, node: str, pid: int) -> None:
        if self.hub.watcher is not None:
            self.hub.watcher.track(node, pid)

    # --- the board ----------------------------------------------------------------------

    async def _board_task(self) -> None:
        """Keep a client subscribed; between two clients wait as the one reconnect policy
        says (``self.reconnect``: jittered, doubling, capped; reset by a good connection)."""
        backoff = self.reconnect
        while True:
            try:
                async with BoardClient(self.opts.board_url, self.opts.key, clock=self.clock,
                                       wall=self.stream.wall) as client:
                    self.client = client
                    backoff.reset()
                    await self._board_state(await client.state(), "connected")
                    async for item in client.subscribe(self.opts.rate_hz):
                        self._feed_board(item)
                        self.view.apply(item)
                        await self._board_item(client, item)
            except RemoteError as exc:  # unreachable, lost, refused: keep trying, say so once
                if self.link_up or not backoff.attempts:
                    self.emit(Note(f"board: {exc}", "error"))
                    log.warning("board: %s", exc)
                self._set_link(False, str(exc))
            finally:
                self.client = None
            await asyncio.sleep(backoff.next())

    async def _board_state(self, state: BoardState, why: str) -> None:
        self._feed_board(state)
        self.view.reset(state)
        self.emit(BoardEventRecord(why, None, {
            "boot_id": f"{state.boot_id:08x}",
            "reset_cause": state.reset_cause_name,
            "config_status": state.config_status,
        }))
        self._set_link(True, why)
        self.emit(self.view.sample())

    def _feed_board(self, item: BoardState | StreamItem) -> None:
        """The hardware observer's input; on ROS 2 also on ``/board_stream`` (for bags)."""
        self.hub.feed_board(item)
        if self.ros_out is not None:
            self.ros_out.board(item, self.stream.wall())

    async def _board_item(self, client: BoardClient, item: object) -> None:
        if isinstance(item, Reading):
            summary = self._telemetry.add(
                item.host_mono, dict(enumerate(float(c) for c in item.currents_ma)))
            if summary is not None:
                self.emit(summary)
        elif isinstance(item, BoardEvent):
            self.emit(BoardEventRecord(item.kind_name,
                                       None if item.channel == 255 else item.channel,
                                       item.fields(self.view.names())))
            switched = item.switched()
            if switched is not None:
                self.repairs.board_switched(item.channel, switched)
        elif isinstance(item, LinkDown):
            self._set_link(False, item.reason)
        elif isinstance(item, Rebooted):  # LinkUp follows, with the new boot's state
            cause = item.reset_cause_name
            self.repairs.board_rebooted()
            self.emit(BoardEventRecord("rebooted", None, {
                "old_boot_id": f"{item.old_boot_id:08x}",
                "new_boot_id": f"{item.new_boot_id:08x}", "how": item.how,
                "reset_cause": cause}))
            self.emit(Note(f"the board rebooted (reset cause {cause}): every channel started "
                           "anew; its fresh state follows", "warning"))
            self._set_link(False, f"the board rebooted (reset cause {cause})")
        elif isinstance(item, LinkUp):
            await self._board_state(await client.state(), "link_up")

    def _set_link(self, up: bool, reason: str) -> None:
        if up != self.link_up:
            self.link_up = up
            self.repairs.link(self.client if up else None)
            key = self._key_check() if up else ""
            self.emit(LinkChange(up, reason, key))
            if key.startswith("refused"):
                why = key.partition(":")[2].strip()
                self.emit(Note(f"the board refused this daemon's key ({why}): every repair "
                               "that switches power will fail; give the board's own key "
                               "(--key-file or $DXBOARD_KEY)", "error"))

    def _key_check(self) -> str:
        """What the board said of the key as the link came up (``LinkChange.key``)."""
        if self.opts.key is None:
            return "none"
        return self.client.transport.key_check if self.client is not None else ""

    async def _sample_task(self) -> None:
        while True:
            await asyncio.sleep(SAMPLE_S)
            if self.link_up:
                self.emit(self.view.sample())

    def subscribe(self, reader: Callable[[Stamped], None]) -> Callable[[], None]:
        """Add a reader of the event stream (a projection)."""
        return self.stream.subscribe(reader)

    def record(self, event: Event) -> None:
        """Emit an event from outside (an experiment's mark, a person's command)."""
        self.emit(event)
