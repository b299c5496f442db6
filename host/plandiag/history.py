"""The executed history a plan-execution diagnosis explains, and its JSON form.

What the mission layer's journal records and ``dxboard explain HISTORY.json DOMAIN_DIR``
reads::

    {"objects": {"tedusar": "robot", "hall1": "place", "door1": "door"},
     "init": ["at(tedusar,start)", "connected(start,hall1)", "locked(door3)"],
     "steps": [
       {"action": "navigate", "args": ["tedusar", "start", "hall1"],
        "start": 0.0, "end": 12.5, "result": "success",
        "observations": [{"atom": "at(tedusar,hall1)", "value": true, "where": "post",
                          "time": 12.5, "source": "localization"}]},
       {"action": "pass-door", "args": ["tedusar", "door1", "room1", "hall1"],
        "start": 80.0, "result": "not-run",
        "observations": [{"atom": "open(door1)", "value": false, "where": "pre"}]}],
     "alarm": {"step": 2, "where": "pre", "critical": false,
               "atoms": ["~open(door1)"], "message": "door1 is closed"},
     "components": {"healthy": ["jaguar", "hokuyo"], "broken": []}}

``init`` is the knowledge base before the first step (ground atoms; what it does not list is
false). Steps are numbered from 1 in list order; ``result`` is ``success``, ``fail`` (the
action ran and did not achieve its effects), ``halted`` (a critical alarm stopped it before
its end) or ``not-run`` (its precondition check failed, so it was never dispatched: only the
last step can be). An observation's ``where`` is the moment it was made: ``pre`` (the step's
precondition check, before it ran), ``during`` (while it ran) or ``post`` (its expected-state
check, after it ended). The ``alarm`` names the step and the moment that started the
diagnosis; ``critical`` alarms halt the running step at once. ``components`` is layer 0's word
on the robot's components at the alarm (``host.plandiag.interpret.sensor_interpreter``).
``load_history`` reports the place of any mistake (``HistoryError``).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import Any

from host.atoms import Atom
from host.plandiag.errors import HistoryError


class Where(StrEnum):
    PRE = "pre"
    DURING = "during"
    POST = "post"


class StepResult(StrEnum):
    SUCCESS = "success"
    FAIL = "fail"
    HALTED = "halted"
    NOT_RUN = "not-run"


@dataclass(frozen=True)
class MissionObservation:
    atom: Atom
    value: bool
    where: Where
    time: float | None = None
    source: str = ""

    def literal(self) -> str:
        return str(self.atom) if self.value else f"~{self.atom}"

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"atom": str(self.atom), "value": self.value,
                               "where": self.where.value}
        if self.time is not None:
            out["time"] = self.time
        if self.source:
            out["source"] = self.source
        return out


@dataclass(frozen=True)
class HistoryStep:
    action: str
    args: tuple[str, ...]
    result: StepResult = StepResult.SUCCESS
    observations: tuple[MissionObservation, ...] = ()
    start: float | None = None
    end: float | None = None

    def label(self) -> str:
        return f"{self.action}({','.join(self.args)})"

    def executed(self) -> bool:
        return self.result is not StepResult.NOT_RUN

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"action": self.action, "args": list(self.args),
                               "result": self.result.value}
        if self.start is not None:
            out["start"] = self.start
        if self.end is not None:
            out["end"] = self.end
        out["observations"] = [o.to_json() for o in self.observations]
        return out


@dataclass(frozen=True)
class Alarm:
    """What started the diagnosis: at step ``step`` (from 1), at moment ``where``."""

    step: int
    where: Where
    critical: bool = False
    atoms: tuple[tuple[Atom, bool], ...] = ()
    message: str = ""
    time: float | None = None

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "step": self.step, "where": self.where.value, "critical": self.critical,
            "atoms": [str(a) if v else f"~{a}" for a, v in self.atoms],
        }
        if self.message:
            out["message"] = self.message
        if self.time is not None:
            out["time"] = self.time
        return out


@dataclass(frozen=True)
class ComponentHealth:
    """Layer 0's diagnosis as plan diagnosis needs it: components shown working, and broken."""

    healthy: frozenset[str] = frozenset()
    broken: frozenset[str] = frozenset()

    def to_json(self) -> dict[str, Any]:
        return {"healthy": sorted(self.healthy), "broken": sorted(self.broken)}


@dataclass(frozen=True)
class History:
    objects: Mapping[str, str]
    init: frozenset[Atom]
    steps: tuple[HistoryStep, ...]
    alarm: Alarm | None = None
    components: ComponentHealth = field(default_factory=ComponentHealth)

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "objects": dict(self.objects),
            "init": sorted(str(a) for a in self.init),
            "steps": [s.to_json() for s in self.steps],
        }
        if self.alarm is not None:
            out["alarm"] = self.alarm.to_json()
        out["components"] = self.components.to_json()
        return out


def load_history(path: str | Path) -> History:
    """Read a history JSON file; ``HistoryError`` names the file and the place of a mistake."""
    p = Path(path)
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except OSError as exc:
        raise HistoryError(f"{p}: cannot read the history ({exc.strerror})",
                           "give the JSON file the mission journal wrote") from exc
    except ValueError as exc:
        raise HistoryError(f"{p}: not JSON ({exc})", "fix the file's JSON syntax") from exc
    return history_from_json(data, str(p))


def history_from_json(data: Any, where: str = "<history>") -> History:
    r = _Reader(where)
    top = r.obj(data, "")
    objects = {str(k): r.text(v, f"objects.{k}") for k, v in r.obj(top.get("objects", {}),
                                                                  "objects").items()}
    init = frozenset(r.atom(a, f"init[{i}]")
                     for i, a in enumerate(r.array(top.get("init", []), "init")))
    steps = tuple(r.step(s, f"steps[{i}]")
                  for i, s in enumerate(r.array(top.get("steps"), "steps")))
    for i, s in enumerate(steps[:-1]):
        if not s.executed():
            raise HistoryError(f"{where}: steps[{i}] is not-run but later steps ran",
                               "only the last step may be not-run (its precondition failed)")
    alarm = None if top.get("alarm") is None else r.alarm(top["alarm"], len(steps))
    comp = r.obj(top.get("components", {}), "components")
    health = ComponentHealth(
        frozenset(r.text(c, "components.healthy")
                  for c in r.array(comp.get("healthy", []), "components.healthy")),
        frozenset(r.text(c, "components.broken")
                  for c in r.array(comp.get("broken", []), "components.broken")),
    )
    return History(objects, init, steps, alarm, health)


class _Reader:
    """Typed access to the JSON with one clear error naming the place."""

    def __init__(self, where: str) -> None:
        self.where = where

    def fail(self, place: str, what: str, hint: str) -> HistoryError:
        return HistoryError(f"{self.where}: {place or 'the top level'}: {what}", hint)

    def obj(self, v: Any, place: str) -> dict[str, Any]:
        if not isinstance(v, dict):
            raise self.fail(place, "expected an object", "see `dxboard explain --help`")
        return v

    def array(self, v: Any, place: str) -> list[Any]:
        if not isinstance(v, list):
            raise self.fail(place, "expected a list", "see `dxboard explain --help`")
        return v

    def text(self, v: Any, place: str) -> str:
        if not isinstance(v, str) or not v:
            raise self.fail(place, f"{v!r} is not a name", "write a non-empty string")
        return v

    def time(self, v: Any, place: str) -> float | None:
        if v is None:
            return None
        if isinstance(v, bool) or not isinstance(v, int | float):
            raise self.fail(place, f"{v!r} is not a time", "give seconds as a number")
        return float(v)

    def atom(self, v: Any, place: str) -> Atom:
        try:
            return Atom.parse(self.text(v, place))
        except ValueError as exc:
            raise self.fail(place, str(exc), "write atoms like at(tedusar,hall1)") from exc

    def literal(self, v: Any, place: str) -> tuple[Atom, bool]:
        s = self.text(v, place).strip()
        value = not s.startswith("~")
        return self.atom(s.lstrip("~"), place), value

    def enum(self, kind: type[StrEnum], v: Any, place: str) -> Any:
        try:
            return kind(v)
        except ValueError:
            names = ", ".join(m.value for m in kind)
            raise self.fail(place, f"{v!r} is not one of {names}", f"use one of {names}") from None

    def observation(self, v: Any, place: str) -> MissionObservation:
        o = self.obj(v, place)
        value = o.get("value", True)
        if not isinstance(value, bool):
            raise self.fail(f"{place}.value", f"{value!r} is not true or false",
                            "write true or false")
        return MissionObservation(self.atom(o.get("atom"), f"{place}.atom"), value,
                           self.enum(Where, o.get("where", "post"), f"{place}.where"),
                           self.time(o.get("time"), f"{place}.time"),
                           str(o.get("source", "")))

    def step(self, v: Any, place: str) -> HistoryStep:
        s = self.obj(v, place)
        args = tuple(self.text(a, f"{place}.args") for a in self.array(s.get("args", []),
                                                                         f"{place}.args"))
        obs = tuple(self.observation(o, f"{place}.observations[{i}]")
                    for i, o in enumerate(self.array(s.get("observations", []),
                                                     f"{place}.observations")))
        result = self.enum(StepResult, s.get("result", "success"), f"{place}.result")
        if result is StepResult.NOT_RUN:
            late = [o for o in obs if o.where is not Where.PRE]
            if late:
                raise self.fail(f"{place}.observations", "a not-run step has observations "
                                f"at {late[0].where.value}", "a step that never ran has only "
                                "its precondition check (where: pre)")
        return HistoryStep(self.text(s.get("action"), f"{place}.action"), args, result, obs,
                    self.time(s.get("start"), f"{place}.start"),
                    self.time(s.get("end"), f"{place}.end"))

    def alarm(self, v: Any, n_steps: int) -> Alarm:
        a = self.obj(v, "alarm")
        step = a.get("step")
        if isinstance(step, bool) or not isinstance(step, int) or not 1 <= step <= n_steps:
            raise self.fail("alarm.step", f"{step!r} is not a step number",
                            f"give 1..{n_steps} (steps are numbered from 1)")
        critical = a.get("critical", False)
        if not isinstance(critical, bool):
            raise self.fail("alarm.critical", f"{critical!r} is not true or false",
                            "write true or false")
        atoms = tuple(self.literal(x, f"alarm.atoms[{i}]")
                      for i, x in enumerate(self.array(a.get("atoms", []), "alarm.atoms")))
        return Alarm(step, self.enum(Where, a.get("where", "during"), "alarm.where"), critical,
                     atoms, str(a.get("message", "")), self.time(a.get("time"), "alarm.time"))
