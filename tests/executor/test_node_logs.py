"""Node logs on a full disk and their rotation, on a real tmpfs that really answers ENOSPC.

The finding (issue 25 item 4): with the node logs on a full disk, ``stop_node`` never ended
(the supervisor's exit footer raised ENOSPC inside the reaper, so the stop's await failed with
an OSError no repair step expected) and starts failed. Now a log that cannot be written never
stops a start or a stop: the node's output goes to /dev/null and the supervisor says so once.
"""

from __future__ import annotations

import asyncio
import logging
import sys
from pathlib import Path

import pytest

from benchmarks._rigs.fulldisk import small_disk
from host.repair.processes import ProcessConfig
from host.repair.supervisor import ProcessSupervisor

SLEEPER = "import time, sys\nprint('up', flush=True)\ntime.sleep(60)\n"


def _config(tmp_path: Path, name: str = "n") -> ProcessConfig:
    script = tmp_path / "sleeper.py"
    script.write_text(SLEEPER)
    return ProcessConfig(name, argv=(sys.executable, str(script)), stop_timeout_s=5.0)


async def test_start_and_stop_work_on_a_full_disk(tmp_path: Path,
                                                   caplog: pytest.LogCaptureFixture) -> None:
    cfg = _config(tmp_path)
    with small_disk(tmp_path / "disk") as disk:
        sup = ProcessSupervisor({"n": cfg}, disk.path / "logs")
        try:
            pid = await sup.start("n")       # a log file and its record made while space remains
            assert pid is not None
            disk.fill()
            # the stop's footer cannot be written: the stop still ends, within its deadline
            await asyncio.wait_for(sup.stop("n"), 30.0)
            assert sup.pid("n") is None
            with caplog.at_level(logging.WARNING, logger="host.repair"):
                for _ in range(3):
                    pid = await asyncio.wait_for(sup.start("n"), 30.0)
                    assert pid is not None and sup.pid("n") == pid
                    await asyncio.wait_for(sup.stop("n"), 30.0)
            told = [r for r in caplog.records if "/dev/null" in r.getMessage()]
            assert len(told) == 1, [r.getMessage() for r in caplog.records]
            # space returns: the next start writes its log again, and says so
            disk.free()
            await sup.start("n")
            await asyncio.wait_for(sup.stop("n"), 30.0)
            assert "start:" in sup.log_file("n").read_text().splitlines()[-2]
        finally:
            await sup.close()


async def test_logs_rotate_with_one_old_file_kept(tmp_path: Path) -> None:
    cfg = _config(tmp_path)
    logs = tmp_path / "logs"
    sup = ProcessSupervisor({"n": cfg}, logs, log_max_bytes=200)
    try:
        for _ in range(6):
            await sup.start("n")
            await sup.stop("n")
        assert sup.log_file("n").stat().st_size <= 200 + 400  # one run's lines over the cap
        old = logs / "n.log.1"
        assert old.exists() and old.stat().st_size <= 200 + 400
        assert sorted(p.name for p in logs.iterdir() if p.name.startswith("n.log")) == \
            ["n.log", "n.log.1"]
    finally:
        await sup.close()
