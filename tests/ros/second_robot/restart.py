"""A launcher's restart, not dxboard's: ``python restart.py PIDFILE -- ARGV...``.

Stops the process whose pid PIDFILE holds (SIGTERM; already gone is fine) and starts ARGV again
in a session of its own, in the background, as ``systemctl restart`` or a launch file's respawn
would; the new process writes its own pid. Exits 0 once it has started it.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
from pathlib import Path


def main() -> None:
    pidfile, argv = sys.argv[1], sys.argv[sys.argv.index("--") + 1:]
    with contextlib.suppress(FileNotFoundError, ValueError, ProcessLookupError):
        os.kill(int(Path(pidfile).read_text()), signal.SIGTERM)
    subprocess.Popen(argv, start_new_session=True, stdin=subprocess.DEVNULL,
                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


if __name__ == "__main__":
    main()
