"""The robot model: ``models/<robot>/system.yaml`` loaded into a typed, validated ``SystemModel``.

Components come in the kinds of paper 000 §IV-D: ordinary software nodes ``N``, hardware
nodes ``HN`` (drivers of non-switchable hardware), driver nodes of switchable hardware ``SN``,
switchable hardware ``SH`` (powered through a board channel) and other hardware ``H``. The
file::

    robot: tedusar
    board: {channels: 10, protected: [2]}      # optional; protected channels hold no SH
                                               # name: board (the default) names its component
    components:
      jaguar:      {kind: SH, channel: 7, current: [0.3, 6.0], prior: 0.02}
      imu:         {kind: H}
      jaguar_node: {kind: SN, hardware: [jaguar], subscribes: [/cmd_vel],
                    publishes: {/odom: [/cmd_vel]}}   # output -> the inputs it depends on
      imu_node:    {kind: HN, hardware: [imu], publishes: [/imu_data]}
      hector_mapping: {kind: N, subscribes: [/scan], publishes: [/map]}  # list: all inputs
    values:  {/odom: [odom_yaw_rate], /imu_data: [imu_yaw_rate]}       # value(t)
    related: [[odom_yaw_rate, imu_yaw_rate]]                            # related(v1, v2)

The literal vocabulary observers emit (and that ``dxboard diagnose`` accepts), each negatable
with ``~`` or ``not``:

- ``on(d)``            switchable device ``d`` is powered (hardware observer, board)
- ``in_band(d)``       ``d``'s current lies in its expected band (board)
- ``tripped(d)``       ``d``'s channel was tripped or latched off by the board's protection
- ``link(board)``      the host hears the board (hardware observer; the board component)
- ``running(n)``       node ``n`` runs (node observer)
- ``ok(/topic)``       the topic is published at its expected rate (general observer)
- ``inc(v)``, ``dec(v)``, ``const(v)``  trend of value ``v`` (qualitative observer)
- ``matched(v1,v2)``   the trends of two related values agree (binary qualitative observer)

With a ``board:`` section, the power board and its link to the host are a component too
(kind ``H``, named ``board`` unless ``board: {name: ...}`` says otherwise), observed through
``link(board)``: when the link is lost the board's other literals become unknown, and the
diagnosis names the link rather than the devices behind it.

``load_system(dir)`` returns the model or raises ``ModelError`` (a ``UserError``) listing every
problem with file, line, offending value and fix; ``check_system(dir)`` returns the problems.
The API (``SystemModel``, ``Component``, ``ComponentKind``) is stable: the repair planner reads it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import Any

from host.diagnosis import yamlpos
from host.errors import UserError

SYSTEM_FILE = "system.yaml"
DEFAULT_CHANNELS = 10


class ComponentKind(StrEnum):
    N = "N"  # ordinary software node
    HN = "HN"  # driver node of non-switchable hardware
    SN = "SN"  # driver node of switchable hardware
    SH = "SH"  # switchable hardware, on a board channel
    H = "H"  # other hardware

    @property
    def is_node(self) -> bool:
        return self in (ComponentKind.N, ComponentKind.HN, ComponentKind.SN)


@dataclass(frozen=True)
class Component:
    """One component of the robot. ``publishes`` maps each output topic to the input topics
    it depends on; ``channel`` and ``current`` (amperes, low..high) are set for ``SH`` only."""

    name: str
    kind: ComponentKind
    line: int = 0
    channel: int | None = None
    current: tuple[float, float] | None = None
    hardware: tuple[str, ...] = ()
    publishes: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    subscribes: tuple[str, ...] = ()
    prior: float | None = None
    description: str = ""

    @property
    def is_node(self) -> bool:
        return self.kind.is_node


@dataclass(frozen=True)
class SystemModel:
    """A validated robot model. ``components`` keeps the file's order."""

    name: str
    path: Path
    components: Mapping[str, Component]
    values: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    related: tuple[tuple[str, str], ...] = ()
    channels: int = DEFAULT_CHANNELS
    protected: frozenset[int] = frozenset()
    board: str | None = None  # the board's component, when the model has a board section

    def by_kind(self, *kinds: ComponentKind) -> list[Component]:
        return [c for c in self.components.values() if c.kind in kinds]

    def topics(self) -> list[str]:
        seen: dict[str, None] = {}
        for c in self.components.values():
            for t in (*c.publishes, *c.subscribes):
                seen.setdefault(t)
        return list(seen)

    def publishers(self, topic: str) -> list[Component]:
        return [c for c in self.components.values() if topic in c.publishes]

    def device_on_channel(self, channel: int) -> Component | None:
        for c in self.components.values():
            if c.channel == channel:
                return c
        return None

    def drivers_of(self, hardware: str) -> list[Component]:
        return [c for c in self.components.values() if hardware in c.hardware]


@dataclass(frozen=True)
class Problem:
    """One validation error: where, what, and how to fix it."""

    file: Path
    line: int
    message: str
    fix: str

    def __str__(self) -> str:
        return f"{self.file}:{self.line}: {self.message} ({self.fix})"


class ModelError(UserError):
    """The model has problems; ``problems`` lists all of them."""

    def __init__(self, problems: list[Problem]) -> None:
        more = f" (+{len(problems) - 1} more problems)" if len(problems) > 1 else ""
        super().__init__(str(problems[0]) + more)
        self.problems = problems


# "observers" is read by host.observers.config, "processes" by host.repair.processes and
# "external" by host.repair.external, from the same file.
_TOP_KEYS = {
    "robot", "board", "components", "values", "related", "description", "observers", "processes",
    "external",
}
_COMMON_KEYS = {"kind", "prior", "description"}
_KIND_KEYS = {
    ComponentKind.N: {"publishes", "subscribes"},
    ComponentKind.HN: {"publishes", "subscribes", "hardware"},
    ComponentKind.SN: {"publishes", "subscribes", "hardware"},
    ComponentKind.SH: {"channel", "current"},
    ComponentKind.H: set(),
}


def system_file(path: str | Path) -> Path:
    p = Path(path)
    return p / SYSTEM_FILE if p.is_dir() else p


def read_section(
    path: str | Path, section: str, error: type[ModelError] = ModelError
) -> tuple[Path, Any, yamlpos.SourceLines]:
    """``system.yaml`` of ``path`` (a robot directory or the file) as ``(file, the section's
    data or None, line lookup)``, for the loaders of its other sections (``observers:``,
    ``processes:``); an unreadable file or bad YAML raises ``error`` naming file and line."""
    file = system_file(path)
    try:
        text = yamlpos.read_text(file)
    except yamlpos.YamlTooBig as exc:
        raise exc.to_user_error(file) from None
    except (OSError, UnicodeDecodeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) else "not a UTF-8 text file"
        raise error([Problem(file, 0, f"cannot read: {why}",
                             "give a robot directory holding system.yaml")]) from exc
    try:
        data, lines = yamlpos.load(text, source=file)
    except yamlpos.YamlTooBig as exc:
        raise exc.to_user_error(file) from None
    except yamlpos.YamlSyntaxError as exc:
        raise error([Problem(file, exc.line, str(exc), exc.fix)]) from exc
    return file, data.get(section) if isinstance(data, dict) else None, lines


def load_system(path: str | Path) -> SystemModel:
    """Load and validate ``path/system.yaml`` (or the file itself). Raises ``ModelError``."""
    model, problems = _load(system_file(path))
    if problems or model is None:
        raise ModelError(problems)
    return model


def check_system(path: str | Path) -> list[Problem]:
    """Every problem of the model at ``path`` (empty when it is valid)."""
    return _load(system_file(path))[1]


def _load(file: Path) -> tuple[SystemModel | None, list[Problem]]:
    try:
        text = yamlpos.read_text(file)
    except yamlpos.YamlTooBig as exc:
        raise exc.to_user_error(file) from None
    except (OSError, UnicodeDecodeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) else "not a UTF-8 text file"
        return None, [Problem(file, 0, f"cannot read the model: {why}",
                              "give a robot directory holding system.yaml")]
    try:
        data, lines = yamlpos.load(text, source=file)
    except yamlpos.YamlTooBig as exc:
        raise exc.to_user_error(file) from None
    except yamlpos.YamlSyntaxError as exc:
        return None, [Problem(file, exc.line, str(exc), exc.fix)]
    return _Builder(file, lines).build(data)


def build_system(data: Any, lines: yamlpos.SourceLines, file: Path) -> SystemModel:
    """The model of already parsed ``system.yaml`` data (see ``yamlpos.load``); raises
    ``ModelError``."""
    model, problems = _Builder(file, lines).build(data)
    if problems or model is None:
        raise ModelError(problems)
    return model


class _Builder:
    def __init__(self, file: Path, lines: yamlpos.SourceLines) -> None:
        self.file = file
        self.lines = lines
        self.problems: list[Problem] = []

    def err(self, path: tuple[object, ...], message: str, fix: str) -> None:
        self.problems.append(Problem(self.file, self.lines(*path), message, fix))

    def build(self, data: Any) -> tuple[SystemModel | None, list[Problem]]:
        if not isinstance(data, dict):
            self.err((), "the model is not a mapping", "start with 'robot:' and 'components:'")
            return None, self.problems
        for key in data:
            if key not in _TOP_KEYS:
                self.err((key,), f"unknown key {key!r}", f"use one of {sorted(_TOP_KEYS)}")
        channels, protected, board = self._board(data.get("board"))
        raw = data.get("components")
        if not isinstance(raw, dict) or not raw:
            self.err(("components",), "no components", "add a 'components:' mapping")
            return None, self.problems
        comps = {str(name): self._component(str(name), spec) for name, spec in raw.items()}
        if board is not None:
            if board in comps:
                self.err(("components", board), f"component {board!r} clashes with the board",
                         f"rename it, or name the board: board: {{name: {board}_board}}")
            else:
                comps[board] = Component(board, ComponentKind.H, self.lines("board"),
                                         description="the power board and its link to the host")
        self._check_references(comps, channels, protected)
        values = self._values(data.get("values"), comps)
        related = self._related(data.get("related"), values)
        model = SystemModel(
            name=str(data.get("robot", self.file.parent.name)),
            path=self.file,
            components=comps,
            values=values,
            related=related,
            channels=channels,
            protected=frozenset(protected),
            board=board,
        )
        return model, self.problems

    def _board(self, board: Any) -> tuple[int, list[int], str | None]:
        if board is None:
            return DEFAULT_CHANNELS, [], None
        if not isinstance(board, dict):
            self.err(("board",), "'board' is not a mapping", "write board: {channels: 10}")
            return DEFAULT_CHANNELS, [], None
        name = board.get("name", "board")
        if not isinstance(name, str) or not name.isidentifier():
            self.err(("board", "name"), f"board name {name!r} is not a plain name",
                     "write name: board")
            name = "board"
        channels = board.get("channels", DEFAULT_CHANNELS)
        if not isinstance(channels, int) or isinstance(channels, bool) or channels < 1:
            self.err(("board", "channels"), f"channels {channels!r} is not a positive integer",
                     "give the board's number of channels, e.g. 10")
            channels = DEFAULT_CHANNELS
        protected = board.get("protected", [])
        if not isinstance(protected, list) or not all(isinstance(p, int) for p in protected):
            self.err(("board", "protected"), f"protected {protected!r} is not a list of channels",
                     "write protected: [2]")
            protected = []
        return channels, protected, name

    def _component(self, name: str, spec: Any) -> Component:
        path = ("components", name)
        if not isinstance(spec, dict):
            self.err(path, f"component {name!r} is not a mapping", "write {kind: N, ...}")
            return Component(name, ComponentKind.N, self.lines(*path))
        try:
            kind = ComponentKind(str(spec.get("kind")))
        except ValueError:
            self.err((*path, "kind"), f"component {name!r} has kind {spec.get('kind')!r}",
                     "set kind to one of N, HN, SN, SH, H")
            kind = ComponentKind.N
        allowed = _COMMON_KEYS | _KIND_KEYS[kind]
        for key in spec:
            if key not in allowed:
                self.err((*path, key), f"{name!r} ({kind.value}) has unknown key {key!r}",
                         f"use one of {sorted(allowed)}")
        prior = spec.get("prior")
        if prior is not None and (not isinstance(prior, int | float) or not 0 < prior < 1):
            self.err((*path, "prior"), f"prior {prior!r} of {name!r} is not in (0, 1)",
                     "give a fault probability such as 0.01")
            prior = None
        subscribes = self._names((*path, "subscribes"), spec.get("subscribes", []), "topics")
        publishes = self._publishes(path, spec.get("publishes", {}), subscribes)
        return Component(
            name=name,
            kind=kind,
            line=self.lines(*path),
            channel=self._channel(path, spec, kind),
            current=self._current(path, spec.get("current")),
            hardware=tuple(self._names((*path, "hardware"), spec.get("hardware", []), "names")),
            publishes=publishes,
            subscribes=tuple(subscribes),
            prior=None if prior is None else float(prior),
            description=str(spec.get("description", "")),
        )

    def _names(self, path: tuple[object, ...], value: Any, what: str) -> list[str]:
        if value is None:
            return []
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            self.err(path, f"{path[-1]} {value!r} is not a list of {what}",
                     f"write {path[-1]}: [a, b]")
            return []
        return list(value)

    def _publishes(
        self, path: tuple[object, ...], value: Any, subscribes: list[str]
    ) -> dict[str, tuple[str, ...]]:
        p = (*path, "publishes")
        if isinstance(value, list):
            return {t: tuple(subscribes) for t in self._names(p, value, "topics")}
        if not isinstance(value, dict):
            self.err(p, f"publishes {value!r} is neither a list nor a mapping",
                     "write publishes: [/out] or publishes: {/out: [/in]}")
            return {}
        out: dict[str, tuple[str, ...]] = {}
        for topic, inputs in value.items():
            ins = self._names((*p, topic), inputs, "input topics")
            for i in ins:
                if i not in subscribes:
                    self.err((*p, topic), f"{path[-1]!r} publishes {topic} from {i}, "
                             "which it does not subscribe", f"add {i} to its subscribes")
            out[str(topic)] = tuple(ins)
        return out

    def _channel(self, path: tuple[object, ...], spec: dict[str, Any],
                 kind: ComponentKind) -> int | None:
        if kind is not ComponentKind.SH:
            return None
        ch = spec.get("channel")
        if not isinstance(ch, int) or isinstance(ch, bool):
            self.err(path, f"switchable device {path[-1]!r} has channel {ch!r}",
                     "give the board channel it is wired to, e.g. channel: 3")
            return None
        return ch

    def _current(self, path: tuple[object, ...], band: Any) -> tuple[float, float] | None:
        if band is None:
            return None
        ok = (isinstance(band, list) and len(band) == 2
              and all(isinstance(b, int | float) for b in band) and 0 <= band[0] <= band[1])
        if not ok:
            self.err((*path, "current"), f"current band {band!r} is not [low, high] amperes",
                     "write current: [0.2, 1.5] with 0 <= low <= high")
            return None
        return float(band[0]), float(band[1])

    def _check_references(
        self, comps: dict[str, Component], channels: int, protected: list[int]
    ) -> None:
        used: dict[int, str] = {}
        published = {t for c in comps.values() for t in c.publishes}
        for c in comps.values():
            path = ("components", c.name)
            if c.channel is not None:
                if not 0 <= c.channel < channels:
                    self.err((*path, "channel"), f"channel {c.channel} of {c.name!r} does not "
                             f"exist", f"use a channel from 0 to {channels - 1}")
                elif c.channel in protected:
                    self.err((*path, "channel"), f"channel {c.channel} of {c.name!r} is protected",
                             "protected channels power the host; pick another channel")
                elif c.channel in used:
                    self.err((*path, "channel"), f"channel {c.channel} used twice: "
                             f"{used[c.channel]!r} and {c.name!r}",
                             "give each switchable device its own channel")
                else:
                    used[c.channel] = c.name
            if c.kind is ComponentKind.SN and not c.hardware:
                self.err(path, f"driver node {c.name!r} (SN) has no hardware",
                         "list its switchable device under hardware:, or make it kind N")
            for h in c.hardware:
                target = comps.get(h)
                want = ((ComponentKind.SH,) if c.kind is ComponentKind.SN
                        else (ComponentKind.H, ComponentKind.SH))
                if target is None:
                    self.err((*path, "hardware"), f"{c.name!r} needs unknown component {h!r}",
                             f"declare {h!r} under components or fix the name")
                elif target.kind not in want:
                    self.err((*path, "hardware"), f"{c.name!r} needs {h!r}, which is "
                             f"{target.kind.value}", f"hardware of a {c.kind.value} must be "
                             + " or ".join(k.value for k in want))
            for t in c.subscribes:
                if t not in published:
                    self.err((*path, "subscribes"), f"topic {t} that {c.name!r} subscribes "
                             "is published by nobody", "add a publisher or remove it")

    def _values(self, value: Any, comps: dict[str, Component]) -> dict[str, tuple[str, ...]]:
        if value is None:
            return {}
        if not isinstance(value, dict):
            self.err(("values",), "'values' is not a mapping", "write values: {/odom: [v]}")
            return {}
        published = {t for c in comps.values() for t in c.publishes}
        out: dict[str, tuple[str, ...]] = {}
        for topic, names in value.items():
            if topic not in published:
                self.err(("values", topic), f"values given for topic {topic}, which nobody "
                         "publishes", "name a published topic")
            out[str(topic)] = tuple(self._names(("values", topic), names, "value names"))
        return out

    def _related(
        self, value: Any, values: dict[str, tuple[str, ...]]
    ) -> tuple[tuple[str, str], ...]:
        if value is None:
            return ()
        known = {v for vs in values.values() for v in vs}
        out: list[tuple[str, str]] = []
        if not isinstance(value, list):
            self.err(("related",), "'related' is not a list", "write related: [[v1, v2]]")
            return ()
        for i, pair in enumerate(value):
            if not (isinstance(pair, list) and len(pair) == 2 and pair[0] != pair[1]):
                self.err(("related", i), f"related entry {pair!r} is not a pair of two values",
                         "write [v1, v2]")
                continue
            for v in pair:
                if v not in known:
                    self.err(("related", i), f"related value {v!r} is unknown",
                             "declare it under values: for the topic that carries it")
            out.append((str(pair[0]), str(pair[1])))
        return tuple(out)
