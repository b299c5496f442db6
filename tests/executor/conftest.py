"""The executor's test rig: the emulated board, real processes, real observers, no mocks.

``Rig`` wires what the daemon will wire: the TEDUSAR firmware on the emulator (over the
in-memory transport, ``tests/host/memboard.py``) read by a ``BoardClient`` whose stream feeds
the hardware observer; a ``ProcessSupervisor`` running small Python scripts as nodes, their
pids handed to the observer hub's process watcher (node observers); optionally a Zenoh peer
source for topic observers, the nodes publishing with ``TopicPublisher``. Every observer update
goes to a real ``Diagnoser``'s observation set, on which ``ObservedBeliefs`` waits. Observers
refresh every 0.1 s and settle times are short, so each test takes a few seconds.
"""

from __future__ import annotations

import asyncio
import contextlib
import re
import shutil
import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pytest

from host.board import BoardClient
from host.diagnosis.diagnoser import Diagnoser
from host.diagnosis.generation import generate
from host.diagnosis.logic import Literal
from host.diagnosis.model import SystemModel, load_system
from host.observers import (
    Device,
    FrequencyObserver,
    HardwareObserver,
    NodeObserver,
    ObserverHub,
    ProcessSpec,
    Update,
    apply_updates,
)
from host.observers.base import Observer
from host.observers.sources.zenoh_peer import ZenohSource
from host.repair.actuators import Actuators
from host.repair.beliefs import ObservedBeliefs
from host.repair.effects import settle_times
from host.repair.executor import Event, Executor
from host.repair.limits import AttemptLimiter
from host.repair.planner import RepairPlanner
from host.repair.policy import Candidate
from host.repair.processes import load_processes
from host.repair.supervisor import ProcessSupervisor
from tests.host.memboard import KEY, MemoryBoard, tedusar
from tests.ports import zenoh_endpoint

ROOT = Path(__file__).resolve().parents[2]
TEDUSAR = ROOT / "models" / "tedusar"
REFRESH, VALIDITY = 0.1, 0.35

ODOM_NODE = """\
import os, sys, time
from host.observers.publisher import TopicPublisher
print("jaguar_node up", flush=True)
with TopicPublisher([os.environ["ENDPOINT"]]) as pub:
    n = 0
    while True:
        pub.put("/odom", {"seq": n})
        n += 1
        time.sleep(0.05)
"""


def robot_dir(tmp: Path, processes: str, domain: str | None = None) -> Path:
    """A copy of models/tedusar with a ``processes:`` section (and optionally a domain)."""
    d = tmp / "robot"
    d.mkdir()
    text = re.sub(r"(?ms)^processes:\n.*?(?=^\S|\Z)", "",
                  (TEDUSAR / "system.yaml").read_text())  # the model's own, if any
    (d / "system.yaml").write_text(text + "\nprocesses:\n" + textwrap.indent(processes, "  "))
    if domain is None:
        shutil.copy(TEDUSAR / "repair.pddl", d / "repair.pddl")
    else:
        (d / "repair.pddl").write_text(domain)
    return d


# how long a step's effect may take to show: generous, since a step that works ends the moment
# its effect is seen and a busy machine starts a process slowly (a deadline only bounds how long
# a broken step takes to fail); tests that expect a step to fail pass a short one
VERIFY_S = 30.0
EXPECTED_FAILURE_VERIFY_S = 1.5


class Rig:
    def __init__(self, robot: Path, devices: Sequence[str], nodes: Sequence[str],
                 topics: Sequence[str] = (), endpoint: str | None = None,
                 max_attempts: int = 3, dry_run: bool = False, verify_s: float = VERIFY_S,
                 refresh: float = REFRESH, stretch: float = 1.0,
                 judge_s: dict[str, float] | None = None,
                 hardware_refresh: float | None = None) -> None:
        """``refresh``: how often observers repeat an unchanged literal (validity 3.5x);
        ``hardware_refresh``: the hardware observer's, if not ``refresh``; ``stretch``: the
        executor's stretch of each step's time (the daemon's follows the machine's load)."""
        self.stretch = stretch
        self.judge_s = judge_s
        self.robot = robot
        self.verify_s = verify_s
        self.model: SystemModel = load_system(robot)
        self.planner = RepairPlanner.for_system(robot)
        self.processes = load_processes(robot, self.model)
        self.devices = devices
        self.nodes = nodes
        self.topics = topics
        self.endpoint = endpoint
        self.max_attempts = max_attempts
        self.dry_run = dry_run
        self.refresh, self.validity = refresh, refresh * VALIDITY / REFRESH
        self.hw_refresh = refresh if hardware_refresh is None else hardware_refresh
        self.diagnoser = Diagnoser(generate(self.model))
        self.beliefs = ObservedBeliefs(self.diagnoser.observations)
        self.events: list[Event] = []
        self.updates: list[Update] = []
        self._tasks: list[asyncio.Task[Any]] = []
        self._stack = contextlib.AsyncExitStack()

    def sink(self, updates: list[Update]) -> None:
        self.updates.extend(updates)
        apply_updates(updates, self.diagnoser)  # the one set the beliefs wait on

    async def __aenter__(self) -> Rig:
        s = self._stack
        self.board = await s.enter_async_context(MemoryBoard(tedusar()))
        self.client = await s.enter_async_context(BoardClient(self.board.url, KEY))
        observers: list[Observer[Any]] = [HardwareObserver(
            {d: Device(d, c.channel or 0, c.current) for d in self.devices
             for c in [self.model.components[d]]},
            link_timeout=0.5, refresh=self.hw_refresh,
            validity=self.hw_refresh * VALIDITY / REFRESH)]
        observers += [NodeObserver(n, refresh=self.refresh, validity=self.validity)
                      for n in self.nodes]
        observers += [FrequencyObserver(t, rate=20, tolerance=8, window=0.5,
                                        refresh=self.refresh, validity=self.validity)
                      for t in self.topics]
        self.observable = {a for o in observers for a in o.atoms()}
        self.hub = ObserverHub(observers, self.sink)
        source = ZenohSource(listen=[self.endpoint]) if self.endpoint else None
        if source is not None:
            s.callback(source.close)
        await self.hub.start(source, {n: ProcessSpec(n, supervised=True) for n in self.nodes},
                             poll=0.1)
        s.push_async_callback(self.hub.close)
        self.hub.feed_board(await self.client.state())
        self._tasks.append(asyncio.get_running_loop().create_task(self._pump()))
        self.supervisor = ProcessSupervisor(self.processes, self.robot / "logs",
                                            on_start=self._track)
        s.push_async_callback(self.supervisor.close)
        self.actuators = Actuators(self.model, self.client, self.supervisor, spacing_s=0.2,
                                   off_s=0.3)
        self.executor = Executor(
            self.actuators, self.beliefs,
            settle=settle_times(self.model, self.processes,
                                devices=dict.fromkeys(self.model.components, 0.3)),
            limiter=AttemptLimiter(self.max_attempts, 600.0), report=self.events.append,
            dry_run=self.dry_run, verify_s=self.verify_s, observable=self.observable,
            stretch=lambda: self.stretch, judge_s=self.judge_s)
        return self

    async def __aexit__(self, *exc: object) -> None:
        for t in self._tasks:
            t.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await t
        await self._stack.aclose()

    def _track(self, node: str, pid: int) -> None:
        if self.hub.watcher is not None:
            self.hub.watcher.track(node, pid)

    async def _pump(self) -> None:
        async for item in self.client.subscribe(50):
            self.hub.feed_board(item)

    async def diagnose(self) -> tuple[list[Candidate], list[Literal]]:
        res = self.diagnoser.diagnose(max_card=3)
        return ([Candidate(d.bad, d.probability) for d in res.diagnoses],
                self.diagnoser.observations.literals())

    async def until(self, expected: dict[str, bool], timeout: float = 30.0) -> None:
        ok = await self.beliefs.wait_for(expected, -1.0, timeout)
        assert ok, self.beliefs.missing(expected, -1.0)

    def starts(self, node: str) -> int:
        f = self.supervisor.log_file(node)
        return f.read_text().count(" start: ") if f.exists() else 0


@pytest.fixture
def endpoint() -> str:
    return zenoh_endpoint()
