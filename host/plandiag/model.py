"""The plan-diagnosis model: a mission domain plus its fault modes and exogenous events.

A domain directory holds two PDDL files. ``mission.pddl`` is the mission domain the planner and
the dispatcher use (typed STRIPS, negative preconditions, equality; quantifiers and
disjunctions only over static predicates). ``faults.pddl`` is a second PDDL domain over the same
types and predicates whose actions say how execution can go wrong; each is preceded by one
annotation comment::

    ; @mode navigate prior=0.05 components=jaguar,jaguar_node
    (:action navigate-stuck ...)      ; a variant of navigate: it ran, but like this
    ; @event prior=0.01
    (:action door-closes ...)         ; happens by itself, between two steps

A **fault mode** replaces the action it names when that action runs; its first parameters have
the action's types, in order (they are bound to the executed step's arguments), and it may add
more (``navigate-elsewhere ?r ?from ?to ?actual``: where the robot ended up). An **exogenous
event** may happen in any gap between two steps, for any grounding whose precondition holds.
``prior`` (0 < p < 1) is the probability of the mode when its action runs, or of the event in
one gap; ``components`` names the robot's components whose failure causes the mode (layer 0's
diagnosis then confirms or clears it). ``faults.pddl`` may leave out ``:requirements``,
``:types``, ``:constants`` and ``:predicates``: they are taken from ``mission.pddl``
(``annotate.complete``). Both files are parsed by the ``pddl`` library through
``host.planning.domain``; ``load_model`` returns one ``PlanModel``.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path

from host.plandiag.annotate import Annotation, complete, read_annotations
from host.plandiag.errors import PlanModelError
from host.planning.domain import Domain, EAnd, Eff, EForall, EWhen, Schema, parse_domain_text
from host.planning.errors import DomainError

log = logging.getLogger(__name__)

MISSION_FILE = "mission.pddl"
FAULTS_FILE = "faults.pddl"


class FaultKind(StrEnum):
    MODE = "mode"
    EVENT = "event"


@dataclass(frozen=True)
class FaultSchema:
    """One lifted fault mode or exogenous event of ``faults.pddl``."""

    schema: Schema
    kind: FaultKind
    prior: float
    mode_of: str | None = None
    components: tuple[str, ...] = ()

    @property
    def name(self) -> str:
        return self.schema.name


@dataclass(frozen=True)
class PlanModel:
    """The mission actions, their fault modes and the exogenous events, as one domain.

    ``domain`` holds every schema (actions, modes, events), so a predicate only an event
    changes is a fluent; ``actions`` are the mission's own, ``modes`` maps an action's name to
    its fault modes, ``events`` lists the exogenous events.
    """

    domain: Domain
    actions: Mapping[str, Schema]
    modes: Mapping[str, tuple[FaultSchema, ...]]
    events: tuple[FaultSchema, ...]
    mission_path: Path
    faults_path: Path | None

    def faults(self) -> list[FaultSchema]:
        return [m for ms in self.modes.values() for m in ms] + list(self.events)


def model_files(domain_dir: str | Path) -> tuple[Path, Path | None]:
    """``(mission.pddl, faults.pddl or None)`` of a domain directory (or a mission file)."""
    p = Path(domain_dir)
    mission = p / MISSION_FILE if p.is_dir() else p
    faults = mission.parent / FAULTS_FILE
    return mission, faults if faults.exists() else None


def load_model(domain_dir: str | Path, faults_file: str | Path | None = None) -> PlanModel:
    """Read ``DOMAIN_DIR/mission.pddl`` and ``faults.pddl`` (or the files given)."""
    mission, faults = model_files(domain_dir)
    if faults_file is not None:
        faults = Path(faults_file)
    mission_text = _read(mission, "the mission domain",
                         f"write it as {MISSION_FILE} in the domain directory")
    faults_text = None
    if faults is not None:
        faults_text = _read(faults, "the fault modes and events",
                            f"write them as {FAULTS_FILE} beside {MISSION_FILE}")
    return build_model(mission_text, faults_text, mission, faults)


def _read(path: Path, what: str, hint: str) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except OSError as exc:
        raise PlanModelError(f"{path}: cannot read {what} ({exc.strerror})", hint) from exc


def _parse(text: str, path: Path) -> Domain:
    try:
        return parse_domain_text(text, path)
    except DomainError as exc:
        raise PlanModelError(exc.message, exc.hint) from exc


def build_model(
    mission_text: str,
    faults_text: str | None,
    mission_path: Path = Path(MISSION_FILE),
    faults_path: Path | None = None,
) -> PlanModel:
    """The model from the two files' text (``faults_text`` None: no faults declared)."""
    mission = _parse(mission_text, mission_path)
    for s in mission.schemas:
        _no_conditional_effects(s, mission_path)
    actions = {s.name: s for s in mission.schemas}
    modes: dict[str, list[FaultSchema]] = {}
    events: list[FaultSchema] = []
    fault_schemas: list[Schema] = []
    if faults_text is not None:
        fpath = faults_path or Path(FAULTS_FILE)
        notes = read_annotations(faults_text, fpath)
        faults = _parse(complete(faults_text, mission_text), fpath)
        _same_vocabulary(mission, faults, fpath)
        for s in faults.schemas:
            note = notes.get(s.name)
            if note is None:  # annotate.read_annotations saw every (:action; be safe
                raise PlanModelError(f"{fpath}: action {s.name} has no annotation",
                                     "put '; @mode ACTION prior=P' or '; @event prior=P' "
                                     "on the line before it")
            _no_conditional_effects(s, fpath)
            fs = _fault_schema(s, note, actions, fpath)
            fault_schemas.append(s)
            if fs.mode_of is None:
                events.append(fs)
            else:
                modes.setdefault(fs.mode_of, []).append(fs)
    fluents = set(mission.fluents)
    for s in fault_schemas:
        _collect_writes(s.effect, fluents)
    domain = Domain(
        mission.name, mission_path, mission.types, mission.predicates,
        mission.schemas + tuple(fault_schemas), frozenset(fluents), mission.vocabulary,
        mission.signatures,
    )
    log.debug("plan model %s: %d actions, %d modes, %d events", mission.name, len(actions),
              sum(len(m) for m in modes.values()), len(events))
    return PlanModel(domain, actions, {k: tuple(v) for k, v in modes.items()}, tuple(events),
                     mission_path, faults_path)


def _fault_schema(
    s: Schema, note: Annotation, actions: Mapping[str, Schema], path: Path
) -> FaultSchema:
    where = f"{path}:{note.line}: action {s.name}"
    if s.name in actions:
        raise PlanModelError(f"{where}: the name is already a mission action",
                             "give the fault mode or event a name of its own")
    if note.kind == FaultKind.EVENT:
        return FaultSchema(s, FaultKind.EVENT, note.prior, None, note.components)
    assert note.mode_of is not None
    action = actions.get(note.mode_of)
    if action is None:
        raise PlanModelError(
            f"{where}: @mode names {note.mode_of!r}, which the mission domain lacks",
            f"name one of {', '.join(sorted(actions)) or '(no actions)'}")
    want = [t for _, t in action.parameters]
    have = [t for _, t in s.parameters[: len(want)]]
    if have != want:
        raise PlanModelError(
            f"{where}: its first parameters have the types ({' '.join(have)}), "
            f"{note.mode_of}'s are ({' '.join(want)})",
            f"start its parameters with {note.mode_of}'s, in order; extra ones may follow")
    return FaultSchema(s, FaultKind.MODE, note.prior, note.mode_of, note.components)


def _same_vocabulary(mission: Domain, faults: Domain, path: Path) -> None:
    for name, arity in faults.predicates.items():
        if mission.predicates.get(name) != arity:
            raise PlanModelError(
                f"{path}: predicate {name}/{arity} is not in the mission domain",
                "declare every predicate in mission.pddl (faults.pddl may leave "
                ":predicates out and use the mission's)")
    for name, parent in faults.types.items():
        if mission.types.get(name, parent) != parent or (
                name not in mission.types and name != "object"):
            raise PlanModelError(f"{path}: type {name} differs from the mission domain's",
                                 "declare types in mission.pddl only")


def _no_conditional_effects(s: Schema, path: Path) -> None:
    def walk(e: Eff) -> None:
        if isinstance(e, EWhen):
            raise PlanModelError(
                f"{path}: action {s.name} has a conditional effect (when)",
                "plan-execution diagnosis takes STRIPS effects: split the action, or make "
                "the variant a fault mode of its own")
        if isinstance(e, EAnd):
            for x in e.args:
                walk(x)
        elif isinstance(e, EForall):
            walk(e.body)

    walk(s.effect)


def _collect_writes(e: Eff, out: set[str]) -> None:
    if isinstance(e, EAnd):
        for x in e.args:
            _collect_writes(x, out)
    elif isinstance(e, EForall | EWhen):
        _collect_writes(e.body, out)
    else:
        out.add(e.atom.pred)
