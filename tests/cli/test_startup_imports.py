"""Everyday commands import only what they use (issue 30 item 2): behaviour, not timing.

Each check runs the real console entry point in a fresh interpreter and reads ``sys.modules``
at its end. ``dxboard plan`` and ``model check`` read the robot's observers' section (numpy,
psutil, asyncio and the board client are for the running daemon) and, from their second run,
the repair domain from the user's cache (no PDDL grammar built: lark and pddl stay out);
``explain`` likewise for the mission domain; from their second run PyYAML stays out too
(``system.yaml`` read back from the cache), and no command loads PySAT's RC2 it does not run.
``plan`` reads only the observers' ``source:`` (the robot's middleware), not the whole
section. Timing is benchmarks/startup.py's.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.plandiag.conftest import ARENA

ROOT = Path(__file__).resolve().parents[2]
TEDUSAR = ROOT / "models" / "tedusar"
# the entry point; prints, on stderr's last line, what the process imported
_MAIN = """\
import json, sys
from host.cli import main
try:
    code = main(sys.argv[1:])
finally:
    sys.stdout.flush()
    print(json.dumps(sorted(sys.modules)), file=sys.stderr)
sys.exit(code)
"""
# what no offline command needs: the daemon's, the web page's, ROS 2's, the report's
NEVER = {"numpy", "asyncio", "psutil", "aiohttp", "rclpy", "matplotlib", "zenoh", "sqlite3",
         "host.board.client", "host.observers.watcher"}
GRAMMAR = {"lark", "pddl"}
# what a second run reads from the user's cache instead: the domain's grammar, and PyYAML
# (system.yaml parsed once, then unpickled)
CACHED = GRAMMAR | {"yaml", "host.diagnosis.yamlparse"}
RC2 = "pysat.examples.rc2"  # about 4 ms: loaded where MaxSAT runs, not before


def dxboard(*args: str) -> tuple[str, set[str]]:
    """Stdout and the top-level names of the modules the command's process imported."""
    proc = subprocess.run([sys.executable, "-c", _MAIN, *args], capture_output=True,
                          text=True, cwd=ROOT, timeout=300, check=False)
    *err, modules = proc.stderr.rstrip("\n").split("\n")
    assert proc.returncode == 0, "\n".join(err)
    names = set(json.loads(modules))
    return proc.stdout, names | {m.split(".")[0] for m in names}


@pytest.mark.parametrize("args, says", [
    (("plan", str(TEDUSAR), "--bad", "jaguar"), "power_up(jaguar)"),
    (("model", "check", str(TEDUSAR)), "ok"),
    (("explain", str(ARENA / "m2-door-closed.json"), str(ARENA)), "class:"),
])
def test_offline_commands_load_neither_the_daemon_nor_a_grammar_twice(
        args: tuple[str, ...], says: str) -> None:
    out, first = dxboard(*args)
    assert says in out
    assert not first & NEVER, sorted(first & NEVER)
    if args[0] == "plan":  # the robot's middleware only: no observer is built
        assert "host.observers.config" not in first
    out, second = dxboard(*args)  # the domain and system.yaml now come from the user's cache
    assert says in out
    assert not second & (NEVER | CACHED), sorted(second & (NEVER | CACHED))
    assert RC2 not in first | second
