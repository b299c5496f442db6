"""The ``observers:`` section's frame: its errors, its reader's helpers and its topic source.

``SectionReader`` holds what every part of the section's validation shares (the file, the line
lookup, the problems found, ``err`` and ``mapping``) and reads the ``source:`` entry into a
``SourceSpec`` (which middleware the robot's topics come over, and where). ``config.py`` builds
the observers on it; ``load_source`` reads the source alone, for a command that needs only the
robot's middleware (``dxboard plan``: are managed nodes repaired by lifecycle transitions?)
without loading every observer kind, numpy or the board client. Problems are reported as by
``load_observers``: file, line and fix (``ObserverConfigError``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from host.diagnosis import yamlpos
from host.diagnosis.model import ModelError, Problem, SystemModel, read_section

if TYPE_CHECKING:
    from host.observers.sources.base import TopicSource

SECTION = "observers"


class ObserverConfigError(ModelError):
    """The ``observers:`` section has problems; ``problems`` lists all of them."""


@dataclass(frozen=True)
class SourceSpec:
    kind: str = "zenoh"
    listen: tuple[str, ...] = ("tcp/127.0.0.1:7447",)
    connect: tuple[str, ...] = ()
    prefix: str = ""
    domain: int | None = None  # ros2: the DDS domain (None: $ROS_DOMAIN_ID)
    types: tuple[tuple[str, str], ...] = ()  # ros2: topic -> message type, where given
    # ros2: topic -> the model's nodes that publish it; other nodes' messages are ignored
    publishers: tuple[tuple[str, tuple[str, ...]], ...] = ()

    def open(self, auth: Path | None = None) -> TopicSource:
        """The topic source (a zenoh session opens here; call inside the event loop); ``auth``:
        zenoh's credentials file (``host.observers.sources.zenoh_auth``)."""
        if self.kind == "memory":
            from host.observers.sources.memory import MemorySource
            return MemorySource()
        if self.kind == "ros2":
            from host.observers.sources.ros2 import Ros2Source
            return Ros2Source(self.domain, dict(self.types), publishers=dict(self.publishers))
        from host.observers.sources.zenoh_peer import ZenohSource
        return ZenohSource(self.listen, self.connect, self.prefix, auth=auth)


class SectionReader:
    """The file, its lines and the problems found, for the section's validation."""

    def __init__(self, file: Path, lines: yamlpos.SourceLines, model: SystemModel | None) -> None:
        self.file = file
        self.lines = lines
        self.model = model
        self.problems: list[Problem] = []

    def err(self, path: tuple[object, ...], message: str, fix: str) -> None:
        self.problems.append(Problem(self.file, self.lines(SECTION, *path), message, fix))

    # -- helpers ---------------------------------------------------------------------------
    def mapping(self, path: tuple[object, ...], value: Any, allowed: set[str],
                example: str) -> dict[str, Any] | None:
        if value is None:
            return {}
        if not isinstance(value, dict):
            self.err(path, f"{'.'.join(map(str, path)) or SECTION} is not a mapping",
                     f"write {example}")
            return None
        for key in value:
            if key not in allowed:
                self.err((*path, key), f"unknown key {key!r}", f"use one of {sorted(allowed)}")
        return value

    def source(self, value: Any) -> SourceSpec:
        """The ``source:`` entry (its problems recorded), as the daemon opens it."""
        spec = self.mapping(("source",), value,
                            {"kind", "listen", "connect", "prefix", "domain", "types"},
                            "source: {kind: zenoh, listen: [tcp/127.0.0.1:7447]}")
        if not spec:
            return SourceSpec()
        kind = spec.get("kind", "zenoh")
        if kind not in ("zenoh", "memory", "ros2"):
            self.err(("source", "kind"), f"source kind {kind!r} is unknown",
                     "use zenoh (the robot's topics), ros2 (ROS 2 topics) or memory")
        domain, types = spec.get("domain"), spec.get("types") or {}
        if domain is not None and (not isinstance(domain, int) or isinstance(domain, bool)
                                   or not 0 <= domain <= 232):
            self.err(("source", "domain"), f"domain {domain!r} is not a ROS 2 domain id",
                     "give an integer 0..232 (or leave it out for $ROS_DOMAIN_ID)")
            domain = None
        if not isinstance(types, dict) or not all(
                isinstance(t, str) and isinstance(m, str) and m.count("/") == 2
                for t, m in types.items()):
            self.err(("source", "types"), f"types {types!r} is not a mapping of topics to types",
                     "write types: {/scan: sensor_msgs/msg/LaserScan}")
            types = {}
        ends: dict[str, tuple[str, ...]] = {}
        for key, default in (("listen", SourceSpec.listen), ("connect", ())):
            v = spec.get(key, list(default))
            if not isinstance(v, list) or not all(isinstance(e, str) and "/" in e for e in v):
                self.err(("source", key), f"{key} {v!r} is not a list of endpoints",
                         f"write {key}: [tcp/127.0.0.1:7447]")
                v = list(default)
            ends[key] = tuple(v)
        publishers = () if self.model is None else tuple(
            (t, tuple(sorted(c.name for c in self.model.publishers(t))))
            for t in self.model.topics() if self.model.publishers(t))
        return SourceSpec(str(kind), ends["listen"], ends["connect"], str(spec.get("prefix", "")),
                          domain, tuple(sorted(types.items())), publishers)


def load_source(path: str | Path, model: SystemModel | None = None) -> SourceSpec:
    """The ``observers: source:`` entry of ``path`` (a robot directory or its ``system.yaml``)
    alone. Raises ``ObserverConfigError`` for its problems (the rest of the section is
    ``load_observers``' to check)."""
    file, section, lines = read_section(path, SECTION, ObserverConfigError)
    reader = SectionReader(file, lines, model)
    top = section if isinstance(section, dict) else {}
    spec = reader.source(top.get("source"))
    if reader.problems:
        raise ObserverConfigError(reader.problems)
    return spec
