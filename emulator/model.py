"""A robot's emulated electronics, read from ``models/<robot>/emulator.yaml``.

The file has a ``board`` section (input voltage, the voltage below which the board's own
regulator drops out, the watchdog timeout, a random seed) and a ``channels`` list, index = channel
number, each with ``name``, ``nominal_ma`` (steady draw when working), ``noise_ma`` (standard
deviation of the measured noise), ``inrush_peak_ma`` and ``inrush_ms`` (a linear decay from the
peak to nominal after switch-on), ``boot_ms`` (until the device is ready) and ``idle_ma`` (what a
hung device keeps drawing; default nominal). Missing fields take the defaults below; a wrong
field is an ``EmulatorModelError`` naming the file, the channel and the field.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from emulator.errors import InputError

FILE = "emulator.yaml"


class EmulatorModelError(InputError):
    """The emulator model file is wrong; the message says where and how to fix it."""


@dataclass(frozen=True)
class LoadSpec:
    name: str
    nominal_ma: int = 0
    noise_ma: int = 0
    inrush_peak_ma: int = 0
    inrush_ms: int = 0
    boot_ms: int = 0
    idle_ma: int | None = None

    @property
    def hung_ma(self) -> int:
        return self.nominal_ma if self.idle_ma is None else self.idle_ma


@dataclass(frozen=True)
class BoardSpec:
    input_mv: int = 24000
    reset_mv: int = 7000
    wdt_timeout_ms: int = 2000
    seed: int = 1


@dataclass(frozen=True)
class EmulatorModel:
    board: BoardSpec = field(default_factory=BoardSpec)
    channels: tuple[LoadSpec, ...] = ()

    def index(self, name_or_number: str | int) -> int:
        """The channel number of ``"3"``, ``3`` or ``"hokuyo"``; ``EmulatorModelError`` if none."""
        if isinstance(name_or_number, int) or name_or_number.isdigit():
            n = int(name_or_number)
            if 0 <= n < len(self.channels):
                return n
        else:
            for i, c in enumerate(self.channels):
                if c.name == name_or_number:
                    return i
        names = ", ".join(c.name for c in self.channels)
        raise EmulatorModelError(
            f"no channel {name_or_number!r} (0..{len(self.channels) - 1} or {names})")


def _ints(where: str, raw: dict[str, Any], allowed: set[str]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in raw.items():
        if key not in allowed:
            known = ", ".join(sorted(allowed))
            raise EmulatorModelError(f"{where}: unknown field {key!r} (known: {known})")
        if key == "name":
            if not isinstance(value, str) or not value:
                raise EmulatorModelError(f"{where}: name must be a non-empty string")
        elif not isinstance(value, int) or isinstance(value, bool) or value < 0:
            raise EmulatorModelError(
                f"{where}: {key} must be a non-negative integer, not {value!r}")
        out[key] = value
    return out


def parse(data: Any, source: str = FILE) -> EmulatorModel:
    if not isinstance(data, dict):
        raise EmulatorModelError(f"{source}: expected a mapping with 'board' and 'channels'")
    board = _ints(f"{source}: board", data.get("board") or {}, set(BoardSpec.__dataclass_fields__))
    chans = data.get("channels")
    if not isinstance(chans, list) or not chans:
        raise EmulatorModelError(f"{source}: 'channels' must be a non-empty list")
    specs = []
    for i, c in enumerate(chans):
        if not isinstance(c, dict):
            raise EmulatorModelError(f"{source}: channel {i} must be a mapping")
        fields = _ints(f"{source}: channel {i}", c, set(LoadSpec.__dataclass_fields__))
        fields.setdefault("name", f"ch{i}")
        specs.append(LoadSpec(**fields))
    return EmulatorModel(BoardSpec(**board), tuple(specs))


def load(system_dir: str | Path) -> EmulatorModel:
    path = Path(system_dir) / FILE
    try:
        text = path.read_text()
    except OSError as exc:
        raise EmulatorModelError(f"{path}: cannot read ({exc.strerror})") from exc
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise EmulatorModelError(f"{path}: not valid YAML ({exc})") from exc
    return parse(data, str(path))
