"""The ``processes:`` section of ``system.yaml`` and the actuators that start and stop nodes.

How the repair executor starts and stops each software node (``start_node``/``stop_node``)::

    processes:
      jaguar_node:                       # a process the host supervises itself
        command: [python, drivers/jaguar.py, --port, /dev/ttyUSB0]
        env: {ROS_DOMAIN_ID: "7"}        # added to the host's environment
        cwd: drivers                     # default: the project root
        settle_s: 2.0                    # after a start, its outputs are ok within this time
        stop_timeout_s: 5.0              # SIGTERM, then SIGKILL after this long
        lifecycle: true                  # a ROS 2 managed node: with a ros2 source the
                                         # planner may repair it by reconfigure_node
      hector_mapping:
        systemd: hector-mapping.service  # a unit: systemctl start/stop
        settle_s: 3.0

Exactly one of ``command`` (a list of strings) or ``systemd`` (a unit name) per node, and every
name must be a node (N, HN, SN) of the model. ``python`` as ``command[0]`` means the host's own
interpreter (``sys.executable``), so drivers written in Python run in the host's environment.

Relative paths are resolved against the **project root**: the nearest directory, starting at
the robot directory (the one holding ``system.yaml``) and going up, that contains
``pyproject.toml`` or ``.git``; without one, the robot directory itself. This applies to ``cwd``
and to the program: ``command[0]``, or the script ``command[1]`` after ``python``, when it
contains a ``/`` (``drivers/jaguar.py``; ``roslaunch`` is looked up on ``PATH``, ``-m`` and
other options are left alone). Other arguments are passed unchanged; they are relative to
``cwd``, where the process runs (the project root by default).

``load_processes(dir, model)`` returns ``{node: ProcessConfig}`` or raises
``ProcessConfigError`` naming the file, the line and the fix for every problem;
``managed_nodes(processes, middleware)`` those the planner may repair by lifecycle
transitions (the daemon's and ``dxboard plan``'s one rule). ``ProcessSupervisor`` (in
``host.repair.supervisor``) runs them.
"""

from __future__ import annotations

import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from host.diagnosis import yamlpos
from host.diagnosis.model import ModelError, Problem, SystemModel, read_section

SECTION = "processes"
DEFAULT_SETTLE_S = 2.0
DEFAULT_STOP_TIMEOUT_S = 5.0
_COMMAND_KEYS = {"command", "env", "cwd", "settle_s", "stop_timeout_s", "lifecycle"}
_SYSTEMD_KEYS = {"systemd", "settle_s", "stop_timeout_s", "lifecycle"}
_ROOT_MARKERS = ("pyproject.toml", ".git")


class ProcessConfigError(ModelError):
    """The ``processes:`` section has problems; ``problems`` lists all of them."""


@dataclass(frozen=True)
class ProcessConfig:
    """How one node is started and stopped: ``argv`` (already resolved) or a systemd ``unit``."""

    node: str
    argv: tuple[str, ...] = ()
    unit: str | None = None
    env: dict[str, str] = field(default_factory=dict)
    cwd: Path | None = None
    settle_s: float = DEFAULT_SETTLE_S
    stop_timeout_s: float = DEFAULT_STOP_TIMEOUT_S
    line: int = 0
    lifecycle: bool = False  # a ROS 2 managed (lifecycle) node

    @property
    def is_systemd(self) -> bool:
        return self.unit is not None


def managed_nodes(processes: Mapping[str, ProcessConfig], middleware: str) -> list[str]:
    """The nodes repaired by lifecycle transitions (``reconfigure_node``): those marked
    ``lifecycle: true``, and only on ROS 2 (``middleware`` ``ros2``: Zenoh has no lifecycle)."""
    return [n for n, p in processes.items() if p.lifecycle] if middleware == "ros2" else []


def project_root(robot_dir: Path) -> Path:
    """The nearest ancestor of ``robot_dir`` (itself included) holding a project marker."""
    start = robot_dir.resolve()
    for d in (start, *start.parents):
        if any((d / m).exists() for m in _ROOT_MARKERS):
            return d
    return start


def load_processes(path: str | Path, model: SystemModel | None = None) -> dict[str, ProcessConfig]:
    """Read and validate ``processes:`` of ``path`` (a robot directory or its system.yaml).

    With ``model``, every name must be a node of it. Raises ``ProcessConfigError``."""
    file, section, lines = read_section(path, SECTION, ProcessConfigError)
    b = _ProcessBuilder(file, lines, model, project_root(file.parent))
    out = b.build(section)
    if b.problems:
        raise ProcessConfigError(b.problems)
    return out


class _ProcessBuilder:
    def __init__(self, file: Path, lines: yamlpos.SourceLines, model: SystemModel | None,
                 root: Path) -> None:
        self.file = file
        self.lines = lines
        self.model = model
        self.root = root
        self.problems: list[Problem] = []

    def err(self, path: tuple[object, ...], message: str, fix: str) -> None:
        self.problems.append(Problem(self.file, self.lines(SECTION, *path), message, fix))

    def build(self, section: Any) -> dict[str, ProcessConfig]:
        if section is None:
            return {}
        if not isinstance(section, dict):
            self.err((), "processes is not a mapping",
                     "write processes: {jaguar_node: {command: [python, jaguar.py]}}")
            return {}
        out: dict[str, ProcessConfig] = {}
        for name, spec in section.items():
            cfg = self.node(str(name), spec)
            if cfg is not None:
                out[cfg.node] = cfg
        return out

    def node(self, name: str, spec: Any) -> ProcessConfig | None:
        p: tuple[object, ...] = (name,)
        if self.model is not None:
            c = self.model.components.get(name)
            if c is None or not c.is_node:
                self.err(p, f"{name!r} is not a node of the model",
                         "name a component of kind N, HN or SN")
        if not isinstance(spec, dict):
            self.err(p, f"{name}: not a mapping",
                     f"write {name}: {{command: [python, {name}.py]}} or {{systemd: UNIT}}")
            return None
        if ("command" in spec) == ("systemd" in spec):
            self.err(p, f"{name}: give exactly one of command and systemd",
                     "command: [argv...] for a process the host runs, systemd: UNIT for a unit")
            return None
        allowed = _COMMAND_KEYS if "command" in spec else _SYSTEMD_KEYS
        for key in spec:
            if key not in allowed:
                self.err((*p, key), f"{name}: unknown key {key!r}", f"use one of {sorted(allowed)}")
        settle = self.seconds((*p, "settle_s"), spec.get("settle_s"), DEFAULT_SETTLE_S)
        stop = self.seconds((*p, "stop_timeout_s"), spec.get("stop_timeout_s"),
                            DEFAULT_STOP_TIMEOUT_S)
        line = self.lines(SECTION, name)
        lifecycle = spec.get("lifecycle", False)
        if not isinstance(lifecycle, bool):
            self.err((*p, "lifecycle"), f"{name}: lifecycle {lifecycle!r} is not true or false",
                     "write lifecycle: true for a ROS 2 managed node, or leave it out")
            lifecycle = False
        if "systemd" in spec:
            unit = spec["systemd"]
            if not isinstance(unit, str) or not unit or unit.startswith("-") or " " in unit:
                self.err((*p, "systemd"), f"{name}: systemd unit {unit!r} is not a unit name",
                         "write systemd: hector-mapping.service")
                return None
            return ProcessConfig(name, unit=unit, settle_s=settle, stop_timeout_s=stop, line=line,
                                 lifecycle=lifecycle)
        argv = self.command((*p, "command"), spec["command"])
        env = self.env((*p, "env"), spec.get("env"))
        cwd = self.root
        raw_cwd = spec.get("cwd")
        if raw_cwd is not None:
            if not isinstance(raw_cwd, str) or not raw_cwd:
                self.err((*p, "cwd"), f"{name}: cwd {raw_cwd!r} is not a path",
                         "write cwd: drivers (relative to the project root) or an absolute path")
            else:
                cwd = self.root / raw_cwd
                if not cwd.is_dir():
                    self.err((*p, "cwd"), f"{name}: cwd {cwd} is not a directory",
                             f"create it or fix the path (relative paths start at {self.root})")
        if argv is None:
            return None
        return ProcessConfig(name, argv=argv, env=env, cwd=cwd, settle_s=settle,
                             stop_timeout_s=stop, line=line, lifecycle=lifecycle)

    def command(self, p: tuple[object, ...], value: Any) -> tuple[str, ...] | None:
        if not isinstance(value, list) or not value or not all(
                isinstance(a, str | int | float) and not isinstance(a, bool) for a in value):
            self.err(p, f"command {value!r} is not a list of arguments",
                     "write command: [python, drivers/jaguar.py, --port, /dev/ttyUSB0]")
            return None
        argv = [str(a) for a in value]
        program = 0
        if argv[0] == "python":
            argv[0] = sys.executable
            program = 1  # the script, if one is given
        if program < len(argv) and "/" in argv[program] and not argv[program].startswith("-") \
                and not Path(argv[program]).is_absolute():
            path = self.root / argv[program]
            if not path.exists():
                self.err((*p, program), f"{argv[program]} does not exist under the project "
                         f"root {self.root}", "fix the path, or give an absolute one")
            argv[program] = str(path)
        return tuple(argv)

    def env(self, p: tuple[object, ...], value: Any) -> dict[str, str]:
        if value is None:
            return {}
        if not isinstance(value, dict) or not all(
                isinstance(v, str | int | float) and not isinstance(v, bool)
                for v in value.values()):
            self.err(p, f"env {value!r} is not a mapping of names to strings",
                     'write env: {ROS_DOMAIN_ID: "7"}')
            return {}
        return {str(k): str(v) for k, v in value.items()}

    def seconds(self, p: tuple[object, ...], value: Any, default: float) -> float:
        if value is None:
            return default
        if isinstance(value, bool) or not isinstance(value, int | float) or value < 0:
            self.err(p, f"{p[-1]} {value!r} is not a number of seconds >= 0",
                     f"write {p[-1]}: {default:g}")
            return default
        return float(value)
