"""Every benchmark runs as documented: ``python benchmarks/X.py`` and ``python -m benchmarks.X``.

Each runnable benchmark (a file with a ``__main__`` block) is started both ways from the
checkout, with ``--help``, as a real process without ``PYTHONPATH`` (so nothing but the file's
own start-up puts the checkout on the path): it must exit 0, print its usage, and leave no
traceback. Run as a script, ``benchmarks/`` comes first on ``sys.path``; a module there named
like a package of ours (the old ``benchmarks/protocol.py``) would shadow it.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
RUNNABLE = sorted(p.stem for p in (ROOT / "benchmarks").glob("*.py")
                  if "__main__" in p.read_text(encoding="utf-8"))


def test_no_benchmark_shadows_a_package_of_ours() -> None:
    ours = {p.name for p in ROOT.iterdir() if (p / "__init__.py").exists()}
    assert ours >= {"protocol", "host", "firmware", "emulator"}
    assert not ours & {p.stem for p in (ROOT / "benchmarks").glob("*.py")}


@pytest.mark.parametrize("name", RUNNABLE)
@pytest.mark.parametrize("way", ["script", "module"])
def test_the_benchmark_starts_both_ways(name: str, way: str) -> None:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    how = [f"benchmarks/{name}.py"] if way == "script" else ["-m", f"benchmarks.{name}"]
    proc = subprocess.run([sys.executable, *how, "--help"], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=240, check=False)
    assert "Traceback" not in proc.stderr, proc.stderr[-2000:]
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "usage:" in proc.stdout.lower(), proc.stdout[-500:]


def test_plandiag_without_k_star_says_how_to_get_it_in_one_line() -> None:
    """K* comes with ``.[bench]``; a machine without it gets the fix, not a traceback."""
    hide = ("import runpy, sys; sys.modules['kstar_planner'] = None; "
            "sys.argv = ['plandiag', '--sizes', '10']; "
            "runpy.run_module('benchmarks.plandiag', run_name='__main__')")
    proc = subprocess.run([sys.executable, "-c", hide], cwd=ROOT, capture_output=True,
                          text=True, timeout=240, check=False)
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr
    assert "--no-planner" in proc.stderr and ".[bench]" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1  # refused before anything runs


def test_board_cortexm_without_the_arm_tools_says_which_to_install_in_one_line(
        tmp_path: Path) -> None:
    """The Cortex-M count needs Debian's cross compiler and QEMU, which ``make test`` does not
    install; without them the benchmark names the packages instead of failing in make."""
    (tmp_path / "make").symlink_to(shutil.which("make") or "/usr/bin/make")
    env = dict(os.environ, PATH=str(tmp_path))  # no arm-none-eabi-gcc, no qemu-system-arm
    proc = subprocess.run([sys.executable, "-m", "benchmarks.board_cortexm"], cwd=ROOT,
                          env=env, capture_output=True, text=True, timeout=240, check=False)
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr
    assert "gcc-arm-none-eabi" in proc.stderr and "qemu-system-arm" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
