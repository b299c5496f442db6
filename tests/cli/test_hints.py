"""The hints a person is given are ones they can follow (issue 26 item 6, three misleading hints).

- ``dxboard journal`` and ``dxboard report`` have no ``--journal`` option: a journal they cannot
  read must not tell the person to "give --journal" anything;
- ``dxboard inject http://...`` must say which URL form it expects, not "Name or service not
  known" from a DNS look-up of ``http``;
- ``dxboard board --help`` must show the port the firmware listens on (7000), not 4840.

Each runs the real ``dxboard`` command in its own process.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tests.host.emulate import ENV

FIRMWARE_TCP_PORT = 7000  # firmware/main.py's TCP_PORT


def dxboard(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "host.cli", *args], capture_output=True,
                          text=True, env=ENV, cwd=cwd, timeout=120)


def one_line(done: subprocess.CompletedProcess[str]) -> str:
    assert done.returncode == 2, (done.stdout, done.stderr)
    assert "Traceback" not in done.stderr and done.stderr.count("\n") == 1, done.stderr
    return done.stderr


@pytest.mark.parametrize("command", [["journal"], ["report", "-o", "x.png"]])
@pytest.mark.parametrize("what", ["missing", "directory", "not-a-journal", "empty"])
def test_journal_readers_never_hint_at_an_option_they_lack(
        tmp_path: Path, command: list[str], what: str) -> None:
    path = tmp_path / "j.sqlite"
    if what == "directory":
        path.mkdir()
    elif what == "not-a-journal":
        path.write_text("hello\n")
    elif what == "empty":
        path.touch()
    line = one_line(dxboard(command[0], str(path), *command[1:], cwd=tmp_path))
    assert "--journal" not in line, line
    assert str(path) in line


@pytest.mark.parametrize("url", ["http://127.0.0.1:7001", "tcp://127.0.0.1:7001"])
def test_inject_with_a_url_of_another_kind_says_the_form_it_expects(url: str) -> None:
    line = one_line(dxboard("inject", url, "hokuyo", "hang"))
    assert "Name or service not known" not in line, line
    assert "control://HOST:PORT" in line and url in line, line


def test_board_help_shows_the_port_the_firmware_listens_on() -> None:
    done = dxboard("board", "--help")
    assert done.returncode == 0, done.stderr
    assert f":{FIRMWARE_TCP_PORT}" in done.stdout and "4840" not in done.stdout, done.stdout
