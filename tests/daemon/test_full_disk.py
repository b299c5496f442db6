"""A full disk never stops self-repair, and the journal loses nothing (issue 25 item 4).

The finding: with the journal and node logs on a full 3 MB tmpfs, a lidar hang was diagnosed,
the repair stopped at ``stop_node(hokuyo_node) started`` for good, the robot was not healthy
90 s after space was freed, and only stderr said anything. Here a real daemon on a real tmpfs
(``benchmarks._rigs.disk``): the hang is repaired while the disk is full, the page and
``/api/status`` say "journal: disk full, N entries held", the terminal says it once and says
once that it writes again, the node restarted on the full disk runs with its output to
/dev/null (said once), and after the space returns every entry the daemon recorded is in the
journal.
"""

from __future__ import annotations

import re
from pathlib import Path

from benchmarks._rigs.disk import full_disk_run


def test_a_lidar_hang_is_repaired_on_a_full_disk_and_no_entry_is_lost(tmp_path: Path) -> None:
    run = full_disk_run(tmp_path)
    head = run.full_status["headline"]
    assert head["state"] == "needs_you"
    assert re.fullmatch(r"needs you: journal: disk full, \d+ entries held", head["text"]), head
    assert run.full_status["journal"]["held"] > 0
    done = {(r["action"], tuple(r["args"]), r["state"]) for r in run.repaired}
    assert ("power_cycle", ("hokuyo",), "succeeded") in done
    assert ("start_node", ("hokuyo_node",), "succeeded") in done, run.repaired
    assert run.recorded > 0 and run.lost == 0 and run.dropped == 0
    assert run.exit_code == 0
    err = run.stderr
    assert len(re.findall(r"journal .*: cannot commit \(disk full\)", err)) == 1, err[-3000:]
    assert len(re.findall(r"journal .*: writing again; the \d+ entries held", err)) == 1, \
        err[-3000:]
    assert err.count("output to /dev/null") == 1, err[-3000:]
    assert "nodes.json" in run.node_logs
