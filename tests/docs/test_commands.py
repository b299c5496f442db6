"""Every command the docs show in a ``console`` block runs, exits as shown (0 unless the block
says ``[exit N]``) and prints what is shown.

The docs cannot drift from the code: each page's blocks run in order (``tests/docs/blocks.py``
says how they are marked) in a directory of their own that sees the project's ``models/`` and
``.venv``, with a model cache and a warm server's socket of its own (a server a page started is
stopped after it, passed or failed). A block titled "runs until Ctrl-C" is started, its
shown lines awaited with a generous deadline, then stopped with SIGINT and awaited; it is killed
if it does not stop, and the test fails.
"""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

import pytest

from tests.docs.blocks import DOCS, ROOT, Block, blocks, gen_docs, pages, unmatched

RUNNABLE = [p for p in pages() if blocks(p)]
DEADLINE_S = 600.0  # an experiment on a busy machine; a command normally takes seconds


def workdir(tmp: Path) -> tuple[Path, dict[str, str]]:
    for name in ("models", ".venv", "scripts"):
        (tmp / name).symlink_to(ROOT / name)
    env = {**os.environ, "PYTHONPATH": str(ROOT), "XDG_CACHE_HOME": str(tmp / "cache"),
           "COLUMNS": "100", "DXBOARD_WARM_SOCKET": str(tmp / "warm.sock")}
    return tmp, env


def run_block(block: Block, cwd: Path, env: dict[str, str]) -> None:
    for cmd in block.commands:
        done = subprocess.run(["bash", "-c", cmd.line], cwd=cwd, env=env, capture_output=True,
                              text=True, timeout=DEADLINE_S)
        assert done.returncode == cmd.exit_code, (block.name, cmd.line, done.stdout[-3000:],
                                                  done.stderr[-3000:])
        if cmd.exit_code == 2:  # a person's mistake: one line, no traceback
            assert "Traceback" not in done.stderr and done.stderr.count("\n") == 1, \
                (block.name, cmd.line, done.stderr)
        missing = unmatched(cmd, done.stdout + done.stderr)
        assert not missing, (block.name, cmd.line, missing, done.stdout[-3000:])


def run_long(block: Block, cwd: Path, env: dict[str, str]) -> None:
    assert len(block.commands) == 1, f"{block.name}: one long-running command a block"
    cmd = block.commands[0]
    out = cwd / "long-running.out"
    with out.open("w") as sink:
        proc = subprocess.Popen(["bash", "-c", f"exec {cmd.line}"], cwd=cwd, env=env,
                                stdout=sink, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        deadline = time.monotonic() + 120.0
        while unmatched(cmd, out.read_text()) and proc.poll() is None \
                and time.monotonic() < deadline:
            time.sleep(0.2)
        assert not unmatched(cmd, out.read_text()), (block.name, out.read_text()[-3000:])
        assert proc.poll() is None, (block.name, "ended by itself", out.read_text()[-3000:])
        proc.send_signal(signal.SIGINT)
        code = proc.wait(timeout=60)
        assert code in (0, 130), (block.name, code, out.read_text()[-3000:])
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


@pytest.mark.parametrize("page", RUNNABLE, ids=[str(p.relative_to(DOCS)) for p in RUNNABLE])
def test_the_commands_of_the_page_run_as_shown(page: Path, tmp_path: Path) -> None:
    cwd, env = workdir(tmp_path)
    try:
        for block in blocks(page):
            (run_long if block.long_running else run_block)(block, cwd, env)
    finally:  # a page that started a warm server (on its own socket) leaves none behind
        if Path(env["DXBOARD_WARM_SOCKET"]).exists():
            subprocess.run([".venv/bin/dxboard", "warm", "stop"], cwd=cwd, env=env,
                           capture_output=True, timeout=DEADLINE_S, check=False)


def test_the_docs_have_runnable_blocks_of_both_kinds() -> None:
    every = [b for p in pages() for b in blocks(p)]
    assert any(b.long_running for b in every) and any(not b.long_running for b in every)
    assert all(b.commands for b in every), [b.name for b in every if not b.commands]


def test_every_commands_help_runs_and_is_what_the_reference_shows(tmp_path: Path) -> None:
    """``dxboard CMD --help`` of every command, as a person runs it, is the text of the
    Commands page (which scripts/gen_docs.py makes from the same parsers in the build)."""
    from host.cli import COMMANDS
    cwd, env = workdir(tmp_path)
    reference = gen_docs().commands_page()
    for name in ["", *COMMANDS]:
        args = [name, "--help"] if name else ["--help"]
        done = subprocess.run([".venv/bin/dxboard", *args], cwd=cwd, env=env,
                              capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, (name, done.stderr[-2000:])
        assert done.stdout.startswith(f"usage: dxboard {name}".rstrip()), done.stdout[:200]
        assert done.stdout in reference, f"dxboard {name} --help differs from the reference"
