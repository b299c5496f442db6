"""The ``external:`` section of ``system.yaml``: nodes dxboard repairs but did not start.

A node started by ``ros2 launch``, systemd, a container or a composed process is no entry of
``processes:`` (that section is for the nodes dxboard starts itself); ``external:`` says, per
node, how dxboard may act on it::

    external:
      camera_driver: {lifecycle: true}                    # a managed node: lifecycle only
      lidar_driver: {lifecycle: true, after: [camera_driver],   # brought up after the camera
                     systemd: lidar.service}              # and restarted by systemctl restart
      mapper: {command: [ros2, launch, my_robot, mapper.launch.py]}  # a command restarts it
      detector: {container: detector}                     # docker restart detector

``lifecycle: true``: a ROS 2 managed node; dxboard is its lifecycle manager (configure and
activate to bring it up, deactivate/cleanup/configure/activate to repair it; the repair
domain's ``activate_node`` and ``reset_node``), whoever started its process. ``after``: the
nodes it is brought up after (besides what the model says it needs). At most one restart
actuator: ``systemd`` (a unit: ``systemctl restart UNIT``), ``command`` (argv run to restart
it, which must exit 0), ``container`` (``docker restart NAME``); the repair domain's
``restart_node``. A node with neither lifecycle nor an actuator is watched only: its faults
are diagnosed and said to be "not repairable here". Every name must be a node of the model
and not in ``processes:``. ``load_external(dir, model)`` returns ``{node: ExternalNode}`` or
raises ``ExternalConfigError`` naming the file, the line and the fix for every problem.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from host.diagnosis import yamlpos
from host.diagnosis.model import ModelError, Problem, SystemModel, read_section
from host.repair.problem import RepairModel

SECTION = "external"
ACTUATORS = ("systemd", "command", "container")
_KEYS = {"lifecycle", "after", *ACTUATORS}


class ExternalConfigError(ModelError):
    """The ``external:`` section has problems; ``problems`` lists all of them."""


@dataclass(frozen=True)
class ExternalNode:
    """One node started elsewhere: whether dxboard manages its lifecycle, what it is brought
    up after, and the actuator that restarts it (``kind`` of ``ACTUATORS``, or None)."""

    node: str
    lifecycle: bool = False
    after: tuple[str, ...] = ()
    kind: str | None = None
    target: tuple[str, ...] = ()  # the unit, the argv or the container
    line: int = 0

    @property
    def restartable(self) -> bool:
        return self.kind is not None


def not_repairable(node: str) -> str:
    """The words for a node started elsewhere that dxboard may not act on."""
    return (f"{node} is started elsewhere and system.yaml names no actuator for it: "
            "not repairable here")


def lifecycle_nodes(external: Mapping[str, ExternalNode]) -> list[str]:
    return [n for n, e in external.items() if e.lifecycle]


def restartable_nodes(external: Mapping[str, ExternalNode]) -> list[str]:
    return [n for n, e in external.items() if e.restartable]


def with_external(model: RepairModel, external: Mapping[str, ExternalNode]) -> RepairModel:
    """``model`` with the nodes started elsewhere: ``(external n)``, ``(restartable n)``, and
    each lifecycle node's ``after`` as what it needs (brought up after them)."""
    if not external:
        return model
    needs = dict(model.needs)
    for n, e in external.items():
        if e.after:
            needs[n] = tuple(dict.fromkeys((*needs.get(n, ()), *e.after)))
    return dataclasses.replace(
        model, needs=needs, external=frozenset(n for n in external if n in model.types),
        restartable=frozenset(n for n in restartable_nodes(external) if n in model.types))


def load_external(path: str | Path, model: SystemModel | None = None,
                  processes: Mapping[str, object] | None = None) -> dict[str, ExternalNode]:
    """Read and validate ``external:`` of ``path`` (a robot directory or its system.yaml).
    With ``model`` every name must be a node of it; none may be in ``processes``."""
    file, section, lines = read_section(path, SECTION, ExternalConfigError)
    problems: list[Problem] = []

    def err(p: tuple[object, ...], message: str, fix: str) -> None:
        problems.append(Problem(file, lines(SECTION, *p), message, fix))

    if section is None:
        return {}
    if not isinstance(section, dict):
        err((), "external is not a mapping", "write external: {camera_driver: {lifecycle: true}}")
        raise ExternalConfigError(problems)
    out = {}
    for name, spec in section.items():
        node = _node(str(name), spec, model, processes or {}, lines, err)
        if node is not None:
            out[node.node] = node
    for n in out.values():
        for a in n.after:
            if a not in out or not out[a].lifecycle:
                err((n.node, "after"), f"{n.node}: after {a!r}, which is no lifecycle node "
                    "of external:", "name nodes of external: with lifecycle: true")
    if problems:
        raise ExternalConfigError(problems)
    return out


def _node(name: str, spec: Any, model: SystemModel | None, processes: Mapping[str, object],
          lines: yamlpos.SourceLines, err: Any) -> ExternalNode | None:
    p: tuple[object, ...] = (name,)
    if model is not None:
        c = model.components.get(name)
        if c is None or not c.is_node:
            err(p, f"{name!r} is not a node of the model", "name a component of kind N, HN or SN")
    if name in processes:
        err(p, f"{name}: in processes: too (dxboard starts it)",
            "keep it in one of processes: (dxboard starts it) and external: (started elsewhere)")
    if not isinstance(spec, dict):
        err(p, f"{name}: not a mapping", f"write {name}: {{lifecycle: true}}")
        return None
    for key in spec:
        if key not in _KEYS:
            err((*p, key), f"{name}: unknown key {key!r}", f"use one of {sorted(_KEYS)}")
    lifecycle = spec.get("lifecycle", False)
    if not isinstance(lifecycle, bool):
        err((*p, "lifecycle"), f"{name}: lifecycle {lifecycle!r} is not true or false",
            "write lifecycle: true for a ROS 2 managed node")
        lifecycle = False
    after = spec.get("after", [])
    if not isinstance(after, list) or not all(isinstance(a, str) for a in after):
        err((*p, "after"), f"{name}: after {after!r} is not a list of node names",
            "write after: [camera_driver]")
        after = []
    kinds = [k for k in ACTUATORS if k in spec]
    if len(kinds) > 1:
        err(p, f"{name}: more than one actuator ({', '.join(kinds)})",
            "give one of systemd, command and container")
        return None
    kind = kinds[0] if kinds else None
    target: tuple[str, ...] = ()
    if kind == "command":
        value = spec["command"]
        if not isinstance(value, list) or not value or not all(
                isinstance(a, str | int | float) and not isinstance(a, bool) for a in value):
            err((*p, "command"), f"{name}: command {value!r} is not a list of arguments",
                "write command: [systemctl, --user, restart, mapper.service]")
            return None
        target = tuple(str(a) for a in value)
    elif kind is not None:
        value = spec[kind]
        if not isinstance(value, str) or not value or value.startswith("-") or " " in value:
            err((*p, kind), f"{name}: {kind} {value!r} is not a name",
                f"write {kind}: {'lidar.service' if kind == 'systemd' else 'detector'}")
            return None
        target = (value,)
    return ExternalNode(name, lifecycle, tuple(after), kind, target, lines(SECTION, name))
