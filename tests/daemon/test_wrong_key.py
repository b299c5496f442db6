"""A wrong board key is said at once (issue 11, item 7): ``dxboard run --board URL`` with a key
the board does not hold says so on its terminal and its page as the link comes up — not first
when a repair's switch is refused, and not only in the journal.

A real ``dxboard emulate`` board (key A) and a real ``dxboard run`` (key B, ``--dry-run`` so
that nothing is switched either way)."""

from __future__ import annotations

import contextlib
import json
import subprocess
import sys
import threading
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.host.emulate import ENV, KEY_HEX, ROOT, Emulate
from tests.ports import zenoh_endpoint
from tests.wait import wait_until

WRONG_KEY = "ff" * 16


@pytest.fixture
def board() -> Iterator[Emulate]:
    e = Emulate()
    yield e
    e.stop()


def _status(url: str) -> dict[str, Any]:
    """The daemon's status, or {} when it did not answer this time (asked again by the
    caller's wait: a busy daemon answers late)."""
    try:
        with urllib.request.urlopen(url + "api/status", timeout=30) as r:
            data: dict[str, Any] = json.load(r)
    except (OSError, ValueError):
        return {}
    return data


@contextlib.contextmanager
def daemon(board: Emulate, tmp_path: Path, key_hex: str) -> Iterator[tuple[dict[str, Any],
                                                                            list[str]]]:
    """``dxboard run --board`` with this key: its status once the link is up, and the lines
    its terminal printed (growing as it goes on)."""
    argv = [sys.executable, "-m", "host.cli", "run", str(ROOT / "models" / "tedusar"),
            "--board", board.urls["board"], "--dry-run", "--web", "127.0.0.1:0",
            "--journal", str(tmp_path / "j.sqlite"), "--zenoh", zenoh_endpoint()]
    proc = subprocess.Popen(argv, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, env={**ENV, "DXBOARD_KEY": key_hex})
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.extend(proc.stdout or ()), daemon=True)
    reader.start()
    try:
        web = wait_until(lambda: next((x.split(": ", 1)[1].strip() for x in lines
                                       if x.startswith("web: ")), None),
                         60, "the web URL", show=lambda: lines[-20:])
        yield wait_until(lambda: (s := _status(web)).get("board_link_up") and s, 60,
                         "the board link up"), lines
    finally:
        proc.terminate()
        proc.wait(30)


def test_a_wrong_key_is_said_on_the_terminal_and_the_page(board: Emulate,
                                                           tmp_path: Path) -> None:
    with daemon(board, tmp_path, WRONG_KEY) as (status, lines):
        assert status["board_key"].startswith("refused")
        said = wait_until(lambda: [x for x in lines if "refused this daemon's key" in x], 30,
                          "the refusal on the terminal", show=lambda: lines[-20:])
        assert "--key-file" in said[0]


def test_the_right_key_is_accepted(board: Emulate, tmp_path: Path) -> None:
    with daemon(board, tmp_path, KEY_HEX) as (status, lines):
        assert status["board_key"] == "accepted"
        assert not any("refused this daemon's key" in x for x in lines)
