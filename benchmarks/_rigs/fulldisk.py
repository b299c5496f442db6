"""A real small filesystem that really fills up: a tmpfs of a few MB mounted by the test.

``small_disk(directory, size="3m")`` mounts a tmpfs on ``directory`` (the suite runs as root) and
always unmounts it on the way out, even when the test fails; the ``SmallDisk`` it yields fills
the disk with one file (``fill()``: writes until the kernel answers ENOSPC) and frees the space
by deleting that file (``free()``). Nothing is simulated: the journal and the node logs on it
meet the same ENOSPC as on a full SD card.
"""

from __future__ import annotations

import contextlib
import errno
import os
import subprocess
from collections.abc import Iterator
from pathlib import Path

FILLER = ".filler"


class SmallDisk:
    """A mounted tmpfs: ``path``, and the filler file that makes it full."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.filler = path / FILLER

    def fill(self) -> int:
        """Write to the filler until ENOSPC; returns the bytes it took."""
        written = 0
        block = b"\0" * 65536
        fd = os.open(self.filler, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
        try:
            for size in (65536, 4096, 512, 1):
                while True:
                    try:
                        n = os.write(fd, block[:size])
                    except OSError as exc:
                        if exc.errno != errno.ENOSPC:
                            raise
                        break
                    written += n
        finally:
            os.close(fd)
        return written

    def free(self) -> None:
        """Delete the filler: the space is back."""
        with contextlib.suppress(FileNotFoundError):
            self.filler.unlink()

    def available(self) -> int:
        st = os.statvfs(self.path)
        return st.f_bavail * st.f_frsize


@contextlib.contextmanager
def small_disk(directory: Path, size: str = "3m") -> Iterator[SmallDisk]:
    """Mount a tmpfs of ``size`` on ``directory`` (created if needed); unmount it after."""
    directory.mkdir(parents=True, exist_ok=True)
    subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(directory)],
                   check=True, capture_output=True)
    try:
        yield SmallDisk(directory)
    finally:
        # lazy: a process of a failed test that still holds a file must not leave it mounted
        subprocess.run(["umount", "-l", str(directory)], check=False, capture_output=True)
