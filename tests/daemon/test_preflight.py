"""``dxboard run --emulate`` checks the robot directory and its addresses before it starts anything.

A mistake a person can fix (an address in use, a broken ``system.yaml`` or ``repair.pddl``) is
one line on stderr naming the cause and the fix, exit code 2 — and nothing has started or been
printed: no URL line, no emulated board, no journal. The run is a real process; whether an
emulated board was started is read from its own debug log (``-v``: the launcher logs "starting
the emulated board" before it starts one) and from the files a started daemon would have made.
"""

from __future__ import annotations

import re
import shutil
import socket
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.daemon.runner import ROOT, TEDUSAR
from tests.ports import free_port


def _run(robot: Path, tmp: Path, *args: str, verbose: bool = False
         ) -> subprocess.CompletedProcess[str]:
    argv = [sys.executable, "-m", "host.cli", *(["-v"] if verbose else []), "run", str(robot),
            "--emulate", "--journal", str(tmp / "journal.sqlite"), *args]
    return subprocess.run(argv, cwd=ROOT, capture_output=True, text=True, timeout=120)


def _refused(robot: Path, tmp: Path, *args: str) -> str:
    """Run it twice (plain, then ``-v``); check nothing started; return the one error line."""
    plain = _run(robot, tmp, *args)
    assert plain.returncode == 2, plain.stderr
    assert plain.stdout == ""  # no URL line
    lines = plain.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("dxboard run: error: "), plain.stderr
    loud = _run(robot, tmp, *args, verbose=True)
    assert loud.returncode == 2 and loud.stdout == ""
    assert "starting the emulated board" not in loud.stderr
    assert not (tmp / "journal.sqlite").exists() and not (tmp / "journal.sock").exists()
    return lines[0]


@pytest.fixture
def robot(tmp_path: Path) -> Path:
    copy = tmp_path / "robot"
    shutil.copytree(TEDUSAR, copy)
    return copy


@pytest.fixture
def busy_port() -> Iterator[int]:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        yield int(s.getsockname()[1])


@pytest.mark.parametrize("flag", ["--web", "--control", "--zenoh"])
def test_an_address_in_use_is_one_line_before_anything_starts(
        robot: Path, tmp_path: Path, busy_port: int, flag: str) -> None:
    value = {"--zenoh": f"tcp/127.0.0.1:{busy_port}"}.get(flag, f"127.0.0.1:{busy_port}")
    extra = () if flag == "--zenoh" else ("--zenoh", f"tcp/127.0.0.1:{free_port()}")
    web = () if flag == "--web" else ("--web", "127.0.0.1:0")
    line = _refused(robot, tmp_path, flag, value, *extra, *web)
    assert f"127.0.0.1:{busy_port}" in line and "in use" in line
    assert "choose another address" in line


def test_a_broken_system_yaml_is_one_line_naming_the_file_and_line(
        robot: Path, tmp_path: Path) -> None:
    text = (robot / "system.yaml").read_text()
    (robot / "system.yaml").write_text(text.replace("    channel: 3\n", "    channel: [3\n", 1))
    line = _refused(robot, tmp_path, "--web", "127.0.0.1:0")
    assert re.search(r"/system\.yaml:\d+: YAML syntax error", line), line


def test_a_model_that_names_an_unknown_component_is_one_line(robot: Path,
                                                             tmp_path: Path) -> None:
    text = (robot / "system.yaml").read_text()
    assert "    kind: SN\n" in text
    (robot / "system.yaml").write_text(text.replace("    kind: SN\n", "    kind: XX\n", 1))
    line = _refused(robot, tmp_path, "--web", "127.0.0.1:0")
    assert "system.yaml" in line and "XX" in line


def test_a_broken_repair_domain_is_one_line(robot: Path, tmp_path: Path) -> None:
    (robot / "repair.pddl").write_text("(define (domain dxboard-repair) (:action")
    line = _refused(robot, tmp_path, "--web", "127.0.0.1:0")
    assert "repair.pddl" in line
