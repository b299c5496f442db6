"""The virtual robot's description: ``robot.yaml`` (devices) and the nodes of ``system.yaml``.

``robot.yaml`` has one section, ``devices``: name -> ``{kind, channel, rate_hz}`` (see
``models/tedusar/robot.yaml``). ``kind`` is one of ``devices.KINDS``; ``channel`` (optional) names
a channel of ``emulator.yaml`` (or gives its number) whose load powers the device; ``rate_hz``
is the data rate of a working device. ``load_devices`` checks every field against the
emulator model and raises ``RobotModelError`` (a ``EmulatorModelError``) naming the file, the device
and the fix.

``load_node`` reads one component of ``system.yaml`` the way the node runner needs it (kind,
hardware, published topics with their inputs, subscribed topics, and the robot's middleware:
``ros2`` when ``observers: source: {kind: ros2}``, else ``zenoh``). The emulator does not import
the host, so this is a small reader of its own; ``dxboard model check`` is what validates the
whole model.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from emulator.model import EmulatorModel, EmulatorModelError

FILE = "robot.yaml"
SYSTEM_FILE = "system.yaml"
KINDS = ("base", "lidar", "servo", "imu", "joystick", "camera")
MIDDLEWARES = ("zenoh", "ros2")  # observers: source: kind: of system.yaml ("memory" is zenoh)
MAX_RATE_HZ = 1000.0


class RobotModelError(EmulatorModelError):
    """``robot.yaml`` or a node of ``system.yaml`` is wrong; the message says how to fix it."""


@dataclass(frozen=True)
class DeviceSpec:
    name: str
    kind: str
    rate_hz: float
    channel: int | None = None  # None: always powered (not on the board)


@dataclass(frozen=True)
class NodeSpec:
    name: str
    kind: str  # N, HN, SN
    hardware: tuple[str, ...] = ()
    publishes: dict[str, tuple[str, ...]] = field(default_factory=dict)
    subscribes: tuple[str, ...] = ()
    middleware: str = "zenoh"  # zenoh or ros2


def _read_yaml(path: Path) -> Any:
    try:
        text = path.read_text()
    except OSError as exc:
        raise RobotModelError(f"{path}: cannot read ({exc.strerror})") from exc
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise RobotModelError(f"{path}: not valid YAML ({exc})") from exc


def parse_devices(data: Any, emu_model: EmulatorModel, source: str = FILE) -> list[DeviceSpec]:
    if not isinstance(data, dict) or not isinstance(data.get("devices"), dict) \
            or not data["devices"]:
        raise RobotModelError(f"{source}: expected a mapping with a non-empty 'devices' mapping")
    unknown = set(data) - {"devices"}
    if unknown:
        raise RobotModelError(f"{source}: unknown section {sorted(unknown)[0]!r} (known: devices)")
    out = []
    for name, raw in data["devices"].items():
        where = f"{source}: device {name!r}"
        if not isinstance(name, str) or not name:
            raise RobotModelError(f"{source}: device names must be non-empty strings")
        if not isinstance(raw, dict):
            raise RobotModelError(f"{where}: must be a mapping {{kind, channel, rate_hz}}")
        bad = set(raw) - {"kind", "channel", "rate_hz"}
        if bad:
            raise RobotModelError(f"{where}: unknown field {sorted(bad)[0]!r} "
                                  "(known: channel, kind, rate_hz)")
        kind = raw.get("kind")
        if kind not in KINDS:
            raise RobotModelError(f"{where}: kind must be one of {', '.join(KINDS)}, "
                                  f"not {kind!r}")
        rate = raw.get("rate_hz")
        if not isinstance(rate, int | float) or isinstance(rate, bool) \
                or not 0 < rate <= MAX_RATE_HZ:
            raise RobotModelError(f"{where}: rate_hz must be a number in (0, {MAX_RATE_HZ:g}], "
                                  f"not {rate!r}")
        channel = raw.get("channel")
        index: int | None = None
        if channel is not None:
            if isinstance(channel, bool) or not isinstance(channel, str | int):
                raise RobotModelError(f"{where}: channel must be a channel name or number")
            try:
                index = emu_model.index(channel)
            except EmulatorModelError as exc:
                raise RobotModelError(f"{where}: {exc}; fix 'channel'") from None
        out.append(DeviceSpec(name, kind, float(rate), index))
    return out


def load_devices(system_dir: str | Path, emu_model: EmulatorModel) -> list[DeviceSpec]:
    path = Path(system_dir) / FILE
    return parse_devices(_read_yaml(path), emu_model, str(path))


def _topics(where: str, value: Any) -> tuple[str, ...]:
    if value is None:
        return ()
    if not isinstance(value, list) or not all(isinstance(t, str) and t.startswith("/")
                                              for t in value):
        raise RobotModelError(f"{where}: expected a list of topics like /scan, not {value!r}")
    return tuple(value)


def load_node(system_dir: str | Path, name: str) -> NodeSpec:
    """Component ``name`` of ``SYSTEM_DIR/system.yaml``; it must be a node (N, HN or SN)."""
    path = Path(system_dir) / SYSTEM_FILE
    data = _read_yaml(path)
    comps = data.get("components") if isinstance(data, dict) else None
    if not isinstance(comps, dict):
        raise RobotModelError(f"{path}: no 'components' mapping")
    raw = comps.get(name)
    nodes = sorted(n for n, c in comps.items()
                   if isinstance(c, dict) and c.get("kind") in ("N", "HN", "SN"))
    if not isinstance(raw, dict) or raw.get("kind") not in ("N", "HN", "SN"):
        raise RobotModelError(f"{path}: no node {name!r} (nodes: {', '.join(nodes)})")
    where = f"{path}: {name}"
    pubs_raw = raw.get("publishes") or {}
    if not isinstance(pubs_raw, dict):
        raise RobotModelError(f"{where}: publishes must map topics to their input topics")
    pubs = {str(t): _topics(f"{where}: publishes {t}", deps) for t, deps in pubs_raw.items()}
    hardware = raw.get("hardware") or []
    if not isinstance(hardware, list) or not all(isinstance(h, str) for h in hardware):
        raise RobotModelError(f"{where}: hardware must be a list of component names")
    return NodeSpec(name, str(raw["kind"]), tuple(hardware), pubs,
                    _topics(f"{where}: subscribes", raw.get("subscribes")), _middleware(data))


def _middleware(data: dict[str, Any]) -> str:
    """The robot's middleware: ros2 when ``observers: source: kind:`` says so, else zenoh."""
    obs = data.get("observers")
    source = obs.get("source") if isinstance(obs, dict) else None
    kind = source.get("kind") if isinstance(source, dict) else None
    return "ros2" if kind == "ros2" else "zenoh"
