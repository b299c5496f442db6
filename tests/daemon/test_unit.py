"""The systemd unit shipped for the daemon: it restarts on failure, stops the daemon first and
takes every leftover process with it, and systemd itself accepts it."""

from __future__ import annotations

import configparser
import shutil
import subprocess
from importlib import resources
from pathlib import Path


def unit() -> tuple[str, configparser.ConfigParser]:
    text = resources.files("host").joinpath("deploy/dxboard.service").read_text()
    cp = configparser.ConfigParser(strict=False, interpolation=None)
    cp.optionxform = str  # type: ignore[assignment,method-assign]
    cp.read_string(text)
    return text, cp


def test_the_unit_restarts_the_daemon_and_leaves_no_process_behind() -> None:
    _, cp = unit()
    svc = cp["Service"]
    assert svc["Restart"] == "on-failure" and float(svc["RestartSec"]) > 0
    assert svc["KillMode"] == "mixed"  # SIGTERM to the daemon, the rest with the cgroup
    argv = svc["ExecStart"].split()
    assert argv[1:3] == ["run", "${DXBOARD_ROBOT}"] and "--board" in argv
    assert "--key-file" in argv and "--journal" in argv and "--operator" in argv
    assert cp["Install"]["WantedBy"] == "multi-user.target"
    env = resources.files("host").joinpath("deploy/dxboard.env.example").read_text()
    for name in ("DXBOARD_ROBOT", "DXBOARD_BOARD", "DXBOARD_WEB"):
        assert f"{name}=" in env and "${" + name + "}" in svc["ExecStart"]


def test_systemd_accepts_the_unit(tmp_path: Path) -> None:
    analyze = shutil.which("systemd-analyze")
    text, _ = unit()
    # systemd-analyze verify checks the program exists: point it at a stand-in
    fake = tmp_path / "dxboard"
    fake.write_text("#!/bin/sh\n")
    fake.chmod(0o755)
    path = tmp_path / "dxboard.service"
    path.write_text(text.replace("/usr/local/bin/dxboard", str(fake)))
    assert analyze is not None, "systemd-analyze (Debian's systemd) checks the unit"
    out = subprocess.run([analyze, "verify", str(path)], capture_output=True, text=True,
                         timeout=60)
    problems = [ln for ln in out.stderr.splitlines() if "dxboard.service" in ln]
    assert out.returncode == 0 and not problems, out.stderr
