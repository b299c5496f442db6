"""Node log files: rotated at a size cap, and never a reason for a start or stop to fail.

Each node's stdout and stderr go to ``<log_dir>/<node>.log``. ``NodeLogs.open(node, header)``
rotates the file first when it has reached ``max_bytes`` (the old one becomes
``<node>.log.1``, replacing any older ``.1``: one old file kept), then opens it for appending
and writes the header. When the file cannot be opened or written (a full disk: ENOSPC, a
read-only one, a missing directory, or less than ``MIN_FREE_BYTES`` free: the node's first
lines would fail), it returns ``/dev/null`` instead, so the node starts with
its output discarded, and says so once on the daemon's terminal (a warning), and once more when
logs can be written again. ``write``/``close`` of a log and ``write_record`` (the atomic
``nodes.json``) swallow ``OSError`` the same way: the reaper that writes a node's exit footer
on a full disk raised ENOSPC, so ``stop_node`` never ended (issue 25 item 4). Rotation happens
at a start (the node writes straight to its file, with no pipe through the daemon), so a file
may exceed the cap by what one run writes.
"""

from __future__ import annotations

import contextlib
import errno
import logging
import os
from pathlib import Path
from typing import IO

log = logging.getLogger(__name__)

DEFAULT_MAX_BYTES = 10 * 1024 * 1024
MIN_FREE_BYTES = 64 * 1024  # below this a node's first lines would already fail: a full disk


class NodeLogs:
    """The log files of the nodes of one supervisor, under ``log_dir``."""

    def __init__(self, log_dir: Path, max_bytes: int = DEFAULT_MAX_BYTES) -> None:
        self.log_dir = log_dir
        self.max_bytes = max_bytes
        self.failing = False  # the last open fell back to /dev/null (told once)

    def path(self, node: str) -> Path:
        return self.log_dir / f"{node}.log"

    def open(self, node: str, header: str) -> IO[bytes]:
        """The node's log (rotated if over the cap) with ``header`` written, or /dev/null."""
        path = self.path(node)
        try:
            self.log_dir.mkdir(parents=True, exist_ok=True)
            self._rotate(path)
            st = os.statvfs(self.log_dir)
            if st.f_bavail * st.f_frsize < MIN_FREE_BYTES:
                raise OSError(errno.ENOSPC, "No space left on device")
            f = path.open("ab")
        except OSError as exc:
            return self._devnull(node, exc)
        try:
            f.write(header.encode())
            f.flush()
        except OSError as exc:
            _close(f)
            return self._devnull(node, exc)
        if self.failing:
            self.failing = False
            log.warning("node logs: %s is writable again; %s's output goes to %s",
                        self.log_dir, node, path)
        return f

    def _rotate(self, path: Path) -> None:
        try:
            size = path.stat().st_size
        except FileNotFoundError:
            return
        if size >= self.max_bytes:
            os.replace(path, path.with_name(path.name + ".1"))

    def _devnull(self, node: str, exc: OSError) -> IO[bytes]:
        if not self.failing:
            self.failing = True
            log.warning("node logs: cannot write %s (%s); %s and later nodes start with their "
                        "output to /dev/null until it can", self.log_dir,
                        exc.strerror or exc, node)
        return open(os.devnull, "ab")  # closed by the reaper

    def write_record(self, name: str, text: str) -> None:
        """Write ``log_dir/name`` atomically; on a disk that refuses, keep the old one."""
        tmp = self.log_dir / (name + ".tmp")
        try:
            self.log_dir.mkdir(parents=True, exist_ok=True)
            tmp.write_text(text)
            os.replace(tmp, self.log_dir / name)
        except OSError as exc:
            log.debug("node logs: cannot write %s: %s", name, exc)
            with contextlib.suppress(OSError):
                tmp.unlink()


def write(f: IO[bytes], line: str) -> None:
    """Append ``line`` to a node's log; a disk that refuses loses the line, nothing else."""
    with contextlib.suppress(OSError, ValueError):
        f.write(line.encode())
        f.flush()


def _close(f: IO[bytes]) -> None:
    with contextlib.suppress(OSError):
        f.close()


close = _close
