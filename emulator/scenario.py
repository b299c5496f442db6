"""Scenario files: a YAML timeline of faults (and switch commands) for repeatable runs.

    # models/tedusar/scenarios/hokuyo-hang.yaml
    description: the laser range finder hangs and is power-cycled back to life
    duration_s: 20                     # how long ``play`` runs (optional)
    events:
      - {at: 0.0, switch: on, channel: hokuyo}
      - {at: 6.0, inject: hang, channel: hokuyo, params: {permanent: false}}
      - {at: 12.0, switch: cycle, channel: hokuyo, off_ms: 1000}
      - {at: 15.0, clear: all}         # or a channel, or board; optional fault: NAME

``at`` is seconds from the start of the scenario. ``inject`` takes the fault names and
parameters of ``dxboard inject`` (``emulator.faults``); ``switch`` is ``on``, ``off``, ``cycle``
or ``clear`` and goes to the firmware's command methods as a host command would. ``load``
checks the whole file first (a ``ScenarioError`` names the file, the event and the fix);
``schedule`` puts the events on an ``Emulator``'s clock; ``play`` also runs it to the end.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from emulator import faults as F
from emulator.errors import InputError
from emulator.sim import BOARD, Emulator

SWITCH_ACTIONS = ("on", "off", "cycle", "clear")


class ScenarioError(InputError):
    """The scenario file is wrong; the message names the file and the event."""


@dataclass(frozen=True)
class ScenarioStep:
    at_ms: int
    kind: str  # "inject", "clear" or "switch"
    channel: str | int | None
    name: str = ""  # fault name, or switch action
    params: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Scenario:
    steps: tuple[ScenarioStep, ...]
    duration_ms: int
    description: str = ""


def _step(where: str, ev: Any) -> ScenarioStep:
    if not isinstance(ev, dict) or "at" not in ev:
        raise ScenarioError(f"{where}: each event is a mapping with 'at' (seconds)")
    at = ev["at"]
    if not isinstance(at, int | float) or isinstance(at, bool) or at < 0:
        raise ScenarioError(f"{where}: 'at' must be a number of seconds >= 0, not {at!r}")
    at_ms = round(at * 1000)
    channel = ev.get("channel")
    if channel is not None and not isinstance(channel, str | int):
        raise ScenarioError(f"{where}: 'channel' must be a number or a name")
    kinds = [k for k in ("inject", "clear", "switch") if k in ev]
    if len(kinds) != 1:
        raise ScenarioError(f"{where}: give exactly one of inject:, clear:, switch:")
    kind = kinds[0]
    try:
        if kind == "inject":
            fault = str(ev["inject"])
            params = F.parse_params(fault, ev.get("params") or {})
            if F.scope(fault) == BOARD:
                channel = BOARD
            elif channel is None:
                raise ScenarioError(f"{where}: {fault} needs a channel")
            return ScenarioStep(at_ms, kind, channel, fault, params)
    except F.FaultError as exc:
        raise ScenarioError(f"{where}: {exc}") from exc
    if kind == "clear":
        target = ev["clear"]
        return ScenarioStep(at_ms, kind, None if target == "all" else target,
                            str(ev.get("fault") or ""))
    action = ev["switch"]
    if isinstance(action, bool):  # YAML 1.1 reads a bare on/off as a boolean
        action = "on" if action else "off"
    if action not in SWITCH_ACTIONS or channel is None:
        raise ScenarioError(f"{where}: switch: one of {', '.join(SWITCH_ACTIONS)}, with a channel")
    off_ms = ev.get("off_ms", 1000)
    if not isinstance(off_ms, int) or isinstance(off_ms, bool):
        raise ScenarioError(f"{where}: off_ms must be an integer")
    return ScenarioStep(at_ms, kind, channel, action,
                        {"off_ms": off_ms, "force": bool(ev.get("force"))})


def parse(data: Any, source: str = "scenario") -> Scenario:
    if not isinstance(data, dict) or not isinstance(data.get("events"), list):
        raise ScenarioError(f"{source}: expected a mapping with an 'events' list")
    steps = tuple(sorted((_step(f"{source}: event {i}", ev) for i, ev in enumerate(data["events"])),
                         key=lambda s: s.at_ms))
    duration = data.get("duration_s")
    if duration is None:
        duration_ms = (steps[-1].at_ms if steps else 0) + 1000
    elif isinstance(duration, int | float) and not isinstance(duration, bool) and duration >= 0:
        duration_ms = int(duration * 1000)
    else:
        raise ScenarioError(f"{source}: duration_s must be a number of seconds")
    return Scenario(steps, duration_ms, str(data.get("description", "")))


def load(path: str | Path) -> Scenario:
    try:
        text = Path(path).read_text()
    except OSError as exc:
        raise ScenarioError(f"{path}: cannot read ({exc.strerror})") from exc
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise ScenarioError(f"{path}: not valid YAML ({exc})") from exc
    return parse(data, str(path))


def _run(emu: Emulator, step: ScenarioStep) -> None:
    if step.kind == "inject":
        assert step.channel is not None
        emu.inject(step.channel, step.name, step.params)
    elif step.kind == "clear":
        emu.clear(step.channel, step.name or None)
    else:
        assert step.channel is not None
        if emu.in_reset:  # a board held in reset executes nothing
            return
        ch = emu.channel_index(step.channel)
        board = emu.board
        if step.name == "on":
            board.switch(ch, True)
        elif step.name == "off":
            board.switch(ch, False, step.params["force"])
        elif step.name == "cycle":
            board.power_cycle(ch, step.params["off_ms"], step.params["force"])
        else:
            board.clear(ch)


def schedule(emu: Emulator, scenario: Scenario, start_ms: int | None = None) -> None:
    """Put every step on the emulator's clock; channel names are checked now."""
    start = emu.now if start_ms is None else start_ms
    for step in scenario.steps:
        if step.channel not in (None, BOARD):
            try:
                emu.channel_index(step.channel)
            except F.FaultError as exc:
                raise ScenarioError(f"at {step.at_ms / 1000:g} s: {exc}") from exc
        emu.at(start + step.at_ms, functools.partial(_run, emu, step))


def play(emu: Emulator, scenario: Scenario) -> None:
    """Schedule the scenario and run the simulated clock to its end."""
    schedule(emu, scenario)
    emu.advance(scenario.duration_ms)
