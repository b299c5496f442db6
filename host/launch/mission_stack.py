"""The mission stack on a running daemon: layers 1-3 wired to layer 0 and the world.

``MissionStack.start(daemon, world_url, system_dir)`` reads the robot's mission
(``host.mission.files``), connects to the world's skill servers (``host.skills.WorldClient``),
and wires, as the daemon wires everything, with the daemon's clock and its one event stream:

- layer 0 seen from above: a ``Layer0View`` on the daemon's one fold of its stream (so it
  knows the diagnosis, quarantines and holds from before the mission), told whether a repair is
  running;
- layer 1: a ``Skill`` per skill of ``mission.yaml``;
- layer 2: the ``Executive`` with the recipes;
- layer 3: the ``KnowledgeBase``, the ``Dispatcher`` (sensing from the world) and the
  ``MissionRunner``.

Every event of the layers goes onto the daemon's stream (``daemon.emit``), so the journal, the
web page and the terminal show the mission beside the components. ``flat=True`` builds the
baseline without the layers' hand-over: skills that abort once their inputs stop, trees without
guards or retries, a planner that does not know what layer 0 has taken away (``dxboard experiment
mission-fault``). ``run()`` runs the mission once; ``close()`` disconnects. ``wire`` builds
layers 1-3 over any world client, layer-0 view, clock and stream (the tests use it with a world
in their own process). Unless flat, layer 3 has plan-execution diagnosis
(``host.plandiag.live``): the mission's domain read as STRIPS with ``faults.pddl`` beside it,
layer 0's word on the components the skills need as the sensor interpreter's input.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from host.events import Event
from host.executive import Executive
from host.mission.dispatcher import Dispatcher
from host.mission.files import MissionFiles, load_mission
from host.mission.kb import KnowledgeBase
from host.mission.runner import MissionOutcome, MissionRunner
from host.plandiag.history import ComponentHealth
from host.plandiag.live import MissionDiagnoser
from host.plandiag.strips import load_mission_model
from host.skills import Layer0View, Skill, WorldClient

if TYPE_CHECKING:
    from host.daemon.core import Daemon

log = logging.getLogger(__name__)


def wire(files: MissionFiles, world: WorldClient, layer0: Layer0View,
         clock: Callable[[], float], emit: Callable[[Event], None], *, flat: bool = False,
         mission_id: str = "m1") -> MissionRunner:
    """Layers 1-3 over ``world`` and layer 0 as ``layer0`` sees it, on one clock and stream."""
    skills = {n: Skill(spec, world, layer0, clock, flat=flat)
              for n, spec in files.skills.items()}
    params = {a: act.param_names for a, act in files.domain.actions.items()}
    executive = Executive(files.recipes, params, skills, layer0, clock, emit,
                          max_hold_s=files.max_hold_s, flat=flat)
    diagnoser = None if flat else MissionDiagnoser(
        load_mission_model(files.domain, files.path.parent), files.domain, mission_id,
        lambda: health(layer0, files))
    if diagnoser is not None:
        plain, recorder = emit, diagnoser.on_event

        def emit(e: Event) -> None:
            recorder(e)
            plain(e)

    kb = KnowledgeBase(files.problem.objects, emit)
    dispatcher = Dispatcher(kb, executive, world.state, files.sensing, emit, clock, mission_id,
                            on_sensed=None if diagnoser is None else diagnoser.sensed)
    return MissionRunner(files.domain, files.problem, files.rules, kb, dispatcher,
                         files.needs_of(), None if flat else layer0, emit, mission_id,
                         diagnoser=diagnoser)


def health(layer0: Layer0View, files: MissionFiles) -> ComponentHealth:
    """Layer 0's word on the components the mission's skills need (nothing before its first
    diagnosis): broken what it blames, healthy the rest."""
    if not layer0.diagnosed:
        return ComponentHealth()
    comps = {n for spec in files.skills.values() for n in spec.needs if not n.startswith("/")}
    broken = {c for c in comps if c in layer0.suspects or c in layer0.quarantined}
    return ComponentHealth(frozenset(comps - broken - layer0.repairing), frozenset(broken))


class MissionStack:
    def __init__(self, files: MissionFiles, world: WorldClient, layer0: Layer0View,
                 runner: MissionRunner, unsubscribe: object) -> None:
        self.files = files
        self.world = world
        self.layer0 = layer0
        self.runner = runner
        self._unsubscribe = unsubscribe

    @classmethod
    async def start(cls, daemon: Daemon, world_url: str, system_dir: Path, *,
                    flat: bool = False, mission_id: str = "m1") -> MissionStack:
        files = load_mission(system_dir, daemon.model)
        # layer 0 reads the daemon's one fold: what happened before the mission is in it
        layer0 = Layer0View(repair_active=lambda: daemon.repairs.active, fold=daemon.fold)
        unsubscribe = layer0.detach
        world = await WorldClient.connect(world_url)
        runner = wire(files, world, layer0, daemon.clock, daemon.emit, flat=flat,
                      mission_id=mission_id)
        return cls(files, world, layer0, runner, unsubscribe)

    async def run(self) -> MissionOutcome:
        return await self.runner.run()

    async def close(self) -> None:
        if callable(self._unsubscribe):
            self._unsubscribe()
        await self.world.close()
