"""A robot model with short device boot times, for tests and the fault campaign (``--fast``).

``fast_model(system_dir, dest)`` copies the robot directory to ``dest`` and sets each channel's
``boot_ms`` in the copy's ``emulator.yaml`` from ``FAST_BOOT_MS`` (the real devices' figures are
the default everywhere else). Nothing else needs changing: the daemon tells the nodes it starts
which robot directory they belong to (``$DXBOARD_ROBOT``), and asks the emulated robot for its
boot times.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import yaml

from host.diagnosis import yamlpos
from host.errors import UserError

# the lidar keeps a noticeable boot (it orders the plan's timeline), the rest is near instant
FAST_BOOT_MS = {"hokuyo": 1500, "jaguar": 300, "laser_alignment": 300}


def fast_model(system_dir: Path, dest: Path) -> Path:
    """``system_dir`` copied into ``dest`` with the boot times of ``FAST_BOOT_MS``."""
    d = dest / system_dir.resolve().name
    shutil.copytree(system_dir, d)
    emu_file = d / "emulator.yaml"
    if not emu_file.is_file():
        raise UserError(f"{system_dir}: no emulator.yaml, so no boot times to shorten",
                        "leave out --fast, or use a robot with an emulator.yaml")
    try:  # the one bounded loader of files a person gives
        emu, _ = yamlpos.load(yamlpos.read_text(emu_file))
    except yamlpos.YamlSyntaxError as exc:
        raise UserError(f"{emu_file}:{exc.line}: {exc}", exc.fix) from None
    for ch in emu.get("channels", []):
        if ch.get("name") in FAST_BOOT_MS:
            ch["boot_ms"] = FAST_BOOT_MS[ch["name"]]
    emu_file.write_text(yaml.safe_dump(emu))
    return d
