"""A reader that stops early (``dxboard journal --json | head``) ends the command quietly.

The command runs as a real process whose stdout is a real pipe; the test reads one line and
closes its end, as ``head -1`` does, while the command still has far more than a pipe's buffer
to write. It must end without a traceback, with the exit status of a process that a closed
pipe stopped (141, as ``yes | head`` gives under ``set -o pipefail``), for every way of
printing (JSON lines, text lines).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from host.journal import Journal, Observation

ROOT = Path(__file__).resolve().parents[2]
ENTRIES = 4000  # about 400 KB of output: several times a pipe's buffer


@pytest.fixture(scope="module")
def big_journal(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("pipe") / "big.sqlite"
    with Journal(path) as journal:
        for i in range(ENTRIES):
            journal.record(Observation(f"ok(/topic_{i % 50})", i % 2 == 0, "topics"),
                           wall=1_800_000_000.0 + i, mono=float(i))
    return path


@pytest.mark.parametrize("args", [("--json",), ()], ids=["json", "text"])
def test_a_closed_stdout_ends_the_command_without_a_traceback(big_journal: Path,
                                                              args: tuple[str, ...]) -> None:
    proc = subprocess.Popen(
        [sys.executable, "-m", "host.cli", "journal", str(big_journal), "--tail",
         str(ENTRIES), *args], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdout is not None and proc.stderr is not None
    first = proc.stdout.readline()
    assert first.strip(), "the command printed nothing"
    proc.stdout.close()  # what `head -1` does after its line
    err = proc.stderr.read().decode()
    code = proc.wait(60)
    assert "Traceback" not in err and "BrokenPipe" not in err, err
    assert err == ""
    assert code == 141
