"""The ``observers:`` section of ``system.yaml``: schema, validation, and the observers built.

::

    observers:
      refresh: 1.0            # s between repeats of an unchanged literal (default 1.0)
      validity: 3.0           # s a literal stays true without fresh evidence (> refresh)
      poll: 0.5               # s between process scans and CPU/memory samples
      source: {kind: zenoh, listen: [tcp/127.0.0.1:7447], connect: [], prefix: ""}
      # or ROS 2 (host.observers.sources.ros2); domain defaults to $ROS_DOMAIN_ID, types
      # (topic -> pkg/msg/Type) to what the ROS 2 graph says: source: {kind: ros2, domain: 7}
      hardware: {link_timeout: 0.25, link_slack: 0.75, settle: 3, link: link(board)}
                              # devices: SH components; link_slack: the most link_timeout
                              # grows on a busy machine (0: never)
      nodes:                  # node observer: running(n); exactly one of pid, match, supervised
        hector_mapping: {match: 'hector_mapping'}     # regex on the command line (pgrep -f)
        jaguar_node: {supervised: true}               # the daemon starts it and tracks its pid
        hokuyo_node: {graph: true}                    # ROS 2 source: present in the ROS 2 graph
        camera_driver: {lifecycle: true}              # ROS 2 managed node: its state is active
        planner: {heartbeat: /planner/heartbeat, timeout: 0.5}  # a message at least every 0.5 s
      topics:                 # general observer: ok(/t) iff |f - rate| < tolerance over window
        /odom: {rate: 10, tolerance: 3, window: 1.0, silence: 4}   # silence in periods (default 4)
        /scan: {rate: 40, tolerance: 10, window: 0.5, own_time: false}   # see below
      trends:                 # qualitative observer: inc/dec/const(v), slope b per second
        odom_yaw_rate: {topic: /odom, key: twist.angular.z, window: 1.0, slope: 0.05}
      matched: [[odom_yaw_rate, imu_yaw_rate]]          # binary qualitative: matched(v1,v2)
      diagnostics:            # diagnostic observer: thresholds on key/value pairs of a topic
        /diagnostics: [{key: cpu.temp, max: 80, literal: ok(temp_cpu1)}]
      properties:             # property observer: ok(n/cpu), ok(n/memory)
        hector_mapping: {cpu_percent: 90, memory_mb: 800}
      responses:              # multiple observer: output within a time limit of its input
        - {input: /cmd_vel, output: /odom, within: 0.5}               # -> ok(/odom)

A topic's silence is judged in its publishers' own time where the daemon knows their processes
(``host.observers.starvation``); ``own_time: false`` judges it by the delay seen lately alone.
Any entry may override ``refresh`` and ``validity``. With a ``SystemModel`` the loader checks
names against it (nodes are node components, topics are published, the hardware observer
watches every switchable device with its channel and current band); without one,
``hardware:`` lists ``devices: {name: {channel: 3, current: [0.2, 1.2]}}``. Every problem is
reported with the file, the line and the fix (``ObserverConfigError``, a ``UserError``).
``check_atoms`` lists the emitted atoms a diagnosis theory does not know.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypedDict

import host.atoms as A
from host.diagnosis import yamlpos
from host.diagnosis.logic import Theory, parse_literal
from host.diagnosis.model import ComponentKind, Problem, SystemModel, read_section
from host.observers.base import DEFAULT_REFRESH, DEFAULT_VALIDITY, Observer
from host.observers.hardware import (
    DEFAULT_LINK_ATOM,
    DEFAULT_LINK_SLACK,
    DEFAULT_LINK_TIMEOUT,
    DEFAULT_SETTLE,
    Device,
    HardwareObserver,
)
from host.observers.processes import DEFAULT_POLL, NodeObserver, ProcessSpec, PropertyObserver
from host.observers.section import SECTION, SectionReader
from host.observers.section import ObserverConfigError as ObserverConfigError
from host.observers.section import SourceSpec as SourceSpec
from host.observers.sources.ros2_graph import GraphObserver
from host.observers.sources.ros2_lifecycle import (
    DEFAULT_HEARTBEAT_TIMEOUT,
    HeartbeatObserver,
    LifecycleObserver,
)
from host.observers.topics import DEFAULT_SILENCE, FrequencyObserver, ResponseObserver
from host.observers.values import (
    DiagnosticObserver,
    MatchObserver,
    Threshold,
    TrendObserver,
    ValueRef,
)

_TOP = {"refresh", "validity", "poll", "source", "hardware", "nodes", "topics", "trends",
        "matched", "diagnostics", "properties", "responses"}
_TIMING = {"refresh", "validity"}
_NODE_WAYS = ("pid", "match", "supervised", "graph", "lifecycle", "heartbeat")


class Timing(TypedDict):
    refresh: float
    validity: float


@dataclass
class ObserversConfig:
    file: Path
    observers: list[Observer[Any]] = field(default_factory=list)
    processes: dict[str, ProcessSpec] = field(default_factory=dict)
    source: SourceSpec = field(default_factory=SourceSpec)
    poll: float = DEFAULT_POLL


def load_observers(path: str | Path, model: SystemModel | None = None) -> ObserversConfig:
    """Read and validate the ``observers:`` section of ``path`` (a robot directory or its
    ``system.yaml``) and build its observers. Raises ``ObserverConfigError``."""
    file, section, lines = read_section(path, SECTION, ObserverConfigError)
    b = _ConfigBuilder(file, lines, model)
    config = b.build(section)
    if b.problems:
        raise ObserverConfigError(b.problems)
    return config


def check_atoms(config: ObserversConfig, theory: Theory) -> list[str]:
    """The atoms the observers may emit that no clause of ``theory`` mentions."""
    known = theory.observable_atoms()
    return [a for o in config.observers for a in o.atoms() if a not in known]


class _ConfigBuilder(SectionReader):
    def __init__(self, file: Path, lines: yamlpos.SourceLines, model: SystemModel | None) -> None:
        super().__init__(file, lines, model)
        self.refresh = DEFAULT_REFRESH
        self.validity = DEFAULT_VALIDITY

    def number(self, path: tuple[object, ...], value: Any, default: float | None,
               minimum: float = 0.0, what: str = "seconds") -> float | None:
        if value is None:
            return default
        if isinstance(value, bool) or not isinstance(value, int | float) or value <= minimum:
            self.err(path, f"{path[-1]} {value!r} is not a number above {minimum:g}",
                     f"give {what}, e.g. {path[-1]}: 1.0")
            return default
        return float(value)

    def timing(self, path: tuple[object, ...], spec: dict[str, Any]) -> Timing:
        refresh = self.number((*path, "refresh"), spec.get("refresh"), self.refresh) or 1.0
        validity = self.number((*path, "validity"), spec.get("validity"), self.validity) or 3.0
        if validity <= refresh:
            self.err((*path, "validity"), f"validity {validity:g} s is not above refresh "
                     f"{refresh:g} s", "give a validity of about 3 refresh periods")
            validity = 3 * refresh
        return {"refresh": refresh, "validity": validity}

    def topic(self, path: tuple[object, ...], topic: Any) -> str | None:
        if not isinstance(topic, str) or not re.fullmatch(r"(/[^/\s*$?#]+)+", topic):
            self.err(path, f"{topic!r} is not a topic name", "write a name like /odom")
            return None
        if self.model is not None and topic not in {
                t for c in self.model.components.values() for t in c.publishes}:
            self.err(path, f"topic {topic} is published by no component of the model",
                     "name a topic some component publishes, or add it to its publishes")
        return topic

    def node(self, path: tuple[object, ...], name: str) -> bool:
        if self.model is None:
            return True
        c = self.model.components.get(name)
        if c is None or not c.is_node:
            self.err(path, f"{name!r} is not a node of the model",
                     "name a component of kind N, HN or SN")
            return False
        return True

    # -- sections --------------------------------------------------------------------------
    def build(self, section: Any) -> ObserversConfig:
        config = ObserversConfig(self.file)
        top = self.mapping((), section, _TOP, "observers: {topics: {/odom: {rate: 10, ...}}}")
        if top is None:
            return config
        t = self.timing((), top)
        self.refresh, self.validity = t["refresh"], t["validity"]
        config.poll = self.number(("poll",), top.get("poll"), DEFAULT_POLL) or DEFAULT_POLL
        config.source = self.source(top.get("source"))
        obs = config.observers
        if "hardware" in top:
            obs += self._hardware(top["hardware"])
        obs += self._nodes(top.get("nodes"), config.processes)
        obs += self._topics(top.get("topics"))
        trends = self._trends(top.get("trends"), obs)
        obs += self._matched(top.get("matched"), trends)
        obs += self._diagnostics(top.get("diagnostics"))
        obs += self._properties(top.get("properties"), config.processes)
        obs += self._responses(top.get("responses"))
        self._unique(obs)
        return config

    def _hardware(self, value: Any) -> list[Observer[Any]]:
        p: tuple[object, ...] = ("hardware",)
        spec = self.mapping(p, value, {"link_timeout", "link_slack", "settle", "link", "devices",
                                       *_TIMING},
                            "hardware: {link_timeout: 0.25}")
        if spec is None:
            return []
        devices = self._devices(spec.get("devices"))
        settle = spec.get("settle", DEFAULT_SETTLE)
        if not isinstance(settle, int) or isinstance(settle, bool) or settle < 1:
            self.err((*p, "settle"), f"settle {settle!r} is not a positive integer",
                     "give the readings a band change needs, e.g. settle: 3")
            settle = DEFAULT_SETTLE
        link = spec.get("link", DEFAULT_LINK_ATOM)
        if link is not None:
            try:
                link = parse_literal(str(link)).atom
            except ValueError as exc:
                self.err((*p, "link"), str(exc), "write link: link(board), or link: null")
                link = DEFAULT_LINK_ATOM
        timeout = self.number((*p, "link_timeout"), spec.get("link_timeout"),
                              DEFAULT_LINK_TIMEOUT) or DEFAULT_LINK_TIMEOUT
        slack = spec.get("link_slack", DEFAULT_LINK_SLACK)
        if isinstance(slack, bool) or not isinstance(slack, int | float) or slack < 0:
            self.err((*p, "link_slack"), f"link_slack {slack!r} is not a number of seconds "
                     ">= 0", "give the most the link timeout may grow, e.g. link_slack: 0.75")
            slack = DEFAULT_LINK_SLACK
        return [HardwareObserver(devices, timeout, settle, link, link_slack=float(slack),
                                 **self.timing(p, spec))]

    def _devices(self, value: Any) -> dict[str, Device]:
        p: tuple[object, ...] = ("hardware", "devices")
        if self.model is not None:
            if value is not None:
                self.err(p, "devices are given, but the model already lists them",
                         "remove devices: the switchable components are watched")
            return {c.name: Device(c.name, c.channel, c.current)
                    for c in self.model.by_kind(ComponentKind.SH) if c.channel is not None}
        spec = self.mapping(p, value, set(value) if isinstance(value, dict) else set(),
                            "devices: {hokuyo: {channel: 3, current: [0.2, 1.2]}}")
        if not spec:
            self.err(p, "no devices for the hardware observer",
                     "list devices: {name: {channel: 3, current: [0.2, 1.2]}}")
            return {}
        out: dict[str, Device] = {}
        for name, d in spec.items():
            ok = (isinstance(d, dict) and isinstance(d.get("channel"), int)
                  and (d.get("current") is None or (
                      isinstance(d["current"], list) and len(d["current"]) == 2
                      and all(isinstance(x, int | float) for x in d["current"]))))
            if not ok:
                self.err((*p, name), f"device {name!r} is not {{channel: N, current: [lo, hi]}}",
                         "write {channel: 3, current: [0.2, 1.2]}")
                continue
            cur = d.get("current")
            out[str(name)] = Device(str(name), d["channel"],
                                    None if cur is None else (float(cur[0]), float(cur[1])))
        return out

    def _nodes(self, value: Any, procs: dict[str, ProcessSpec]) -> list[Observer[Any]]:
        nodes = self.mapping(("nodes",), value, set(value) if isinstance(value, dict) else set(),
                             "nodes: {hector_mapping: {match: hector_mapping}}")
        out: list[Observer[Any]] = []
        for name, spec in (nodes or {}).items():
            p = ("nodes", name)
            s = self.mapping(p, spec, {*_NODE_WAYS, "timeout", *_TIMING},
                             "{match: 'regex'} or {pid: 1234} or {supervised: true}")
            if s is None or not self.node(p, str(name)):
                continue
            given = [k for k in _NODE_WAYS if s.get(k) not in (None, False)]
            if len(given) != 1:
                self.err(p, f"node {name!r} gives {given or 'none'} of "
                         f"{', '.join(_NODE_WAYS)}", "give exactly one: {match: "
                         "'hector_mapping'}, {pid: N}, {supervised: true}, or on ROS 2 "
                         "{graph: true}, {lifecycle: true} or {heartbeat: /NODE/heartbeat}")
                continue
            if s.get("timeout") is not None and given != ["heartbeat"]:
                self.err((*p, "timeout"), "timeout is the heartbeat's",
                         "drop it, or give heartbeat: TOPIC with it")
                continue
            if given == ["graph"]:
                out.append(GraphObserver(str(name), **self.timing(p, s)))
                continue
            if given == ["lifecycle"]:
                out.append(LifecycleObserver(str(name), **self.timing(p, s)))
                continue
            if given == ["heartbeat"]:
                beat = self._heartbeat(p, str(name), s)
                if beat is not None:
                    out.append(beat)
                continue
            pid, match = s.get("pid"), s.get("match")
            if pid is not None and (not isinstance(pid, int) or isinstance(pid, bool) or pid < 1):
                self.err((*p, "pid"), f"pid {pid!r} is not a process id", "give pid: 1234")
                continue
            if match is not None:
                try:
                    re.compile(str(match))
                except re.error as exc:
                    self.err((*p, "match"), f"match {match!r} is not a regular expression: {exc}",
                             "quote it and escape special characters")
                    continue
            procs[str(name)] = ProcessSpec(str(name), pid, None if match is None else str(match),
                                           bool(s.get("supervised", False)))
            out.append(NodeObserver(str(name), **self.timing(p, s)))
        return out

    def _heartbeat(self, p: tuple[object, ...], name: str,
                   s: dict[str, Any]) -> HeartbeatObserver | None:
        topic = s["heartbeat"]
        if not isinstance(topic, str) or not topic.startswith("/"):
            self.err((*p, "heartbeat"), f"heartbeat {topic!r} is not a topic",
                     f"give heartbeat: /{name}/heartbeat")
            return None
        timeout = self.number((*p, "timeout"), s.get("timeout"), DEFAULT_HEARTBEAT_TIMEOUT,
                              what="s")
        if timeout is None:
            return None
        return HeartbeatObserver(name, topic, timeout, **self.timing(p, s))

    def _topics(self, value: Any) -> list[Observer[Any]]:
        topics = self.mapping(("topics",), value, set(value) if isinstance(value, dict) else set(),
                              "topics: {/odom: {rate: 10, tolerance: 3}}")
        out: list[Observer[Any]] = []
        for topic, spec in (topics or {}).items():
            p = ("topics", topic)
            s = self.mapping(p, spec, {"rate", "tolerance", "window", "silence", "own_time",
                                       *_TIMING},
                             "{rate: 10, tolerance: 3, window: 1.0}")
            if s is None or self.topic(p, topic) is None:
                continue
            rate = self.number((*p, "rate"), s.get("rate"), None, what="Hz")
            if rate is None:
                self.err(p, f"topic {topic} has no rate", "give its expected rate: rate: 10")
                continue
            tol = self.number((*p, "tolerance"), s.get("tolerance"), rate * 0.3, what="Hz")
            window = self.number((*p, "window"), s.get("window"), max(1.0, 2.0 / rate)) or 1.0
            silence = self.number((*p, "silence"), s.get("silence"), DEFAULT_SILENCE,
                                  what="periods") or DEFAULT_SILENCE
            if window * rate < 2:
                self.err((*p, "window"), f"window {window:g} s holds fewer than 2 messages at "
                         f"{rate:g} Hz", f"give window: {2 / rate:g} or more")
                continue
            own_time = s.get("own_time", True)
            if not isinstance(own_time, bool):
                self.err((*p, "own_time"), f"own_time {own_time!r} is not true or false",
                         "give own_time: false to judge silence without the publishers' "
                         "run-queue wait, or leave it out")
                continue
            out.append(FrequencyObserver(topic, rate, tol or rate * 0.3, window, silence,
                                         own_time=own_time, **self.timing(p, s)))
        return out

    def _trends(self, value: Any, obs: list[Observer[Any]]) -> dict[str, tuple[ValueRef, dict[
            str, Any]]]:
        trends = self.mapping(("trends",), value, set(value) if isinstance(value, dict) else set(),
                              "trends: {v: {topic: /odom, key: x, slope: 0.05}}")
        out: dict[str, tuple[ValueRef, dict[str, Any]]] = {}
        for name, spec in (trends or {}).items():
            p = ("trends", name)
            s = self.mapping(p, spec, {"topic", "key", "window", "slope", "min_samples",
                                       *_TIMING}, "{topic: /odom, key: twist.angular.z}")
            if s is None or self.topic((*p, "topic"), s.get("topic")) is None:
                continue
            if not isinstance(s.get("key"), str) or not s["key"]:
                self.err(p, f"trend {name!r} has no key", "give the payload key: key: yaw_rate")
                continue
            n = s.get("min_samples", 3)
            if not isinstance(n, int) or isinstance(n, bool) or n < 2:
                self.err((*p, "min_samples"), f"min_samples {n!r} is below 2",
                         "give min_samples: 3 or more")
                n = 3
            slope = s.get("slope", 0.0)
            if isinstance(slope, bool) or not isinstance(slope, int | float) or slope < 0:
                self.err((*p, "slope"), f"slope {slope!r} is not a number >= 0",
                         "give the slope (value units per second) that counts as a trend")
                slope = 0.0
            window = self.number((*p, "window"), s.get("window"), 1.0) or 1.0
            kw: dict[str, Any] = {"window": window, "slope": float(slope), "min_samples": n,
                                  **self.timing(p, s)}
            ref = ValueRef(str(name), s["topic"], s["key"])
            out[str(name)] = (ref, kw)
            obs.append(TrendObserver(ref, **kw))
        return out

    def _matched(self, value: Any, trends: dict[str, tuple[ValueRef, dict[str, Any]]]
                 ) -> list[Observer[Any]]:
        if value is None:
            return []
        if not isinstance(value, list):
            self.err(("matched",), "matched is not a list", "write matched: [[v1, v2]]")
            return []
        out: list[Observer[Any]] = []
        for i, pair in enumerate(value):
            p = ("matched", i)
            if not (isinstance(pair, list) and len(pair) == 2 and pair[0] != pair[1]):
                self.err(p, f"matched entry {pair!r} is not a pair of two values",
                         "write [v1, v2]")
                continue
            missing = [v for v in pair if v not in trends]
            if missing:
                self.err(p, f"matched names {missing}, not declared under trends",
                         "declare each value under trends: with its topic and key")
                continue
            (r1, kw), (r2, _) = trends[pair[0]], trends[pair[1]]
            out.append(MatchObserver(r1, r2, **kw))
        return out

    def _diagnostics(self, value: Any) -> list[Observer[Any]]:
        diags = self.mapping(("diagnostics",), value,
                             set(value) if isinstance(value, dict) else set(),
                             "diagnostics: {/diagnostics: [{key: temp, max: 40, literal: ...}]}")
        out: list[Observer[Any]] = []
        for topic, rules in (diags or {}).items():
            p = ("diagnostics", topic)
            if self.topic(p, topic) is None:
                continue
            if not isinstance(rules, list) or not rules:
                self.err(p, f"diagnostics of {topic} is not a list of rules",
                         "write - {key: temp_cpu1, max: 40.0, literal: ok(temp_cpu1)}")
                continue
            built: list[Threshold] = []
            for i, r in enumerate(rules):
                rule = self._threshold((*p, i), r)
                if rule is not None:
                    built.append(rule)
            if built:
                out.append(DiagnosticObserver(topic, built, refresh=self.refresh,
                                              validity=self.validity))
        return out

    def _threshold(self, p: tuple[object, ...], r: Any) -> Threshold | None:
        s = self.mapping(p, r, {"key", "literal", "min", "max", "equals"},
                         "{key: temp_cpu1, max: 40.0, literal: ok(temp_cpu1)}")
        if s is None:
            return None
        key, lit = s.get("key"), s.get("literal")
        if not isinstance(key, str) or not key:
            self.err(p, "rule has no key", "give the payload key: key: temp_cpu1")
            return None
        try:
            literal = parse_literal(str(lit if lit is not None else A.ok(key)))
        except ValueError as exc:
            self.err((*p, "literal"), str(exc), "write literal: ok(temp_cpu1)")
            return None
        if not literal.positive:
            self.err((*p, "literal"), f"literal {lit} is negated",
                     "name the atom that holds when the value is in range")
            return None
        bounds = {k: s.get(k) for k in ("min", "max")}
        for k, v in bounds.items():
            if v is not None and (isinstance(v, bool) or not isinstance(v, int | float)):
                self.err((*p, k), f"{k} {v!r} is not a number", f"write {k}: 40.0")
                return None
        if s.get("equals") is None and bounds["min"] is None and bounds["max"] is None:
            self.err(p, f"rule for {key} has no min, max or equals", "give max: 40.0")
            return None
        lo, hi = bounds["min"], bounds["max"]
        return Threshold(key, literal.atom, None if lo is None else float(lo),
                         None if hi is None else float(hi), s.get("equals"))

    def _properties(self, value: Any, procs: dict[str, ProcessSpec]) -> list[Observer[Any]]:
        props = self.mapping(("properties",), value,
                             set(value) if isinstance(value, dict) else set(),
                             "properties: {hector_mapping: {cpu_percent: 90}}")
        out: list[Observer[Any]] = []
        for name, spec in (props or {}).items():
            p = ("properties", name)
            s = self.mapping(p, spec, {"cpu_percent", "memory_mb", *_TIMING},
                             "{cpu_percent: 90, memory_mb: 800}")
            if s is None:
                continue
            if name not in procs:
                self.err(p, f"properties of {name!r}, which has no node observer",
                         f"add {name} under nodes: (with how to find its process)")
                continue
            cpu = self.number((*p, "cpu_percent"), s.get("cpu_percent"), None, what="percent")
            mem = self.number((*p, "memory_mb"), s.get("memory_mb"), None, what="megabytes")
            if cpu is None and mem is None:
                self.err(p, f"properties of {name!r} give no limit",
                         "give cpu_percent: 90 and/or memory_mb: 800")
                continue
            out.append(PropertyObserver(str(name), cpu, mem, **self.timing(p, s)))
        return out

    def _responses(self, value: Any) -> list[Observer[Any]]:
        if value is None:
            return []
        if not isinstance(value, list):
            self.err(("responses",), "responses is not a list",
                     "write responses: [{input: /cmd_vel, output: /odom, within: 0.5}]")
            return []
        out: list[Observer[Any]] = []
        for i, spec in enumerate(value):
            p = ("responses", i)
            s = self.mapping(p, spec, {"input", "output", "within", "literal", *_TIMING},
                             "{input: /cmd_vel, output: /odom, within: 0.5}")
            if s is None:
                continue
            src = self.topic((*p, "input"), s.get("input"))
            dst = self.topic((*p, "output"), s.get("output"))
            within = self.number((*p, "within"), s.get("within"), None)
            if src is None or dst is None or within is None or src == dst:
                if within is None:
                    self.err(p, "response has no time limit", "give within: 0.5 (seconds)")
                elif src is not None and src == dst:
                    self.err(p, "input and output are the same topic", "name two topics")
                continue
            atom = None
            if s.get("literal") is not None:
                try:
                    atom = parse_literal(str(s["literal"])).atom
                except ValueError as exc:
                    self.err((*p, "literal"), str(exc), "write literal: ok(/odom)")
                    continue
            out.append(ResponseObserver(src, dst, within, atom, **self.timing(p, s)))
        return out

    def _unique(self, obs: list[Observer[Any]]) -> None:
        seen: dict[str, str] = {}
        for o in obs:
            for atom in o.atoms():
                if atom in seen and seen[atom] != o.name:
                    self.problems.append(Problem(
                        self.file, self.lines(SECTION), f"{atom} is emitted by two observers, "
                        f"{seen[atom]} and {o.name}", "give one of them another literal: "
                        "each atom needs one source, or they overwrite each other"))
                seen.setdefault(atom, o.name)
