"""``scripts/layers.py``: the package graph and its floors, run as ``make lint`` runs it.

The script runs as a real process (as in the Makefile) on small fake trees written into a temp
directory, each with one thing to find: an import running up a floor (at the top of a module,
in a function, under ``TYPE_CHECKING``, spelled relatively), one sideways between packages of
one floor, a cycle; a clean tree passes; bad input (a package the floors do not know, a file
that does not parse) is one line and exit code 2. Last, the real tree must pass: the layers of
ARCHITECTURE.md hold in the code.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "scripts" / "layers.py"


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(SCRIPT), *args], capture_output=True, text=True,
                          timeout=300, cwd=ROOT)


def tree(base: Path, files: dict[str, str]) -> Path:
    """A fake repository: every package's ``__init__.py`` plus the given modules."""
    for name, text in files.items():
        path = base / name
        for parent in [p for p in path.relative_to(base).parents if str(p) != "."]:
            (base / parent).mkdir(parents=True, exist_ok=True)
            (base / parent / "__init__.py").touch()
        path.write_text(text, encoding="utf-8")
    return base


CLEAN = {
    "protocol/codec.py": "import struct\n",
    "firmware/board.py": "from protocol import codec\n",
    "host/board/client.py": "from protocol.codec import x\nfrom host.errors import E\n",
    "host/errors.py": "class E(Exception): ...\n",
    "host/diagnosis/logic.py": "import host.errors\n",
    "host/observers/base.py": "from host.diagnosis.logic import Literal\n",
    "host/daemon/core.py": "from host.board.client import C\nfrom ..observers import base\n",
}


def test_a_clean_tree_passes_and_prints_its_floors(tmp_path: Path) -> None:
    out = run("--root", str(tree(tmp_path, CLEAN)))
    assert out.returncode == 0, out.stdout + out.stderr
    assert "host.daemon -> host.board, host.observers" in out.stdout
    assert "host.observers -> host.diagnosis" in out.stdout
    assert "0 running up or sideways, 0 cycles" in out.stdout


@pytest.mark.parametrize(("module", "text", "kind"), [
    ("host/board/client.py", "from host.daemon.core import D\n", "up"),
    ("host/board/client.py", "def f():\n    import host.daemon.core\n", "up"),
    ("host/board/client.py",
     "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from host.daemon import core\n",
     "up (type only)"),
    ("host/board/client.py", "from ..daemon import core\n", "up"),
    ("host/web/page.py", "from host.ros import node\n", "sideways"),
])
def test_an_arrow_up_or_sideways_fails_naming_the_place(
        tmp_path: Path, module: str, text: str, kind: str) -> None:
    files = {**CLEAN, module: text, "host/ros/node.py": "import host.events\n",
             "host/events.py": ""}
    out = run("--root", str(tree(tmp_path, files)))
    assert out.returncode == 1, out.stdout + out.stderr
    source, target = ("host.web", "host.ros") if kind == "sideways" else ("host.board",
                                                                          "host.daemon")
    lines = [line for line in out.stdout.splitlines() if line.startswith("arrow ")]
    assert len(lines) == 1, out.stdout
    assert lines[0].startswith(f"arrow {kind}: {source} ")
    assert f"imports {target} " in lines[0]
    assert lines[0].endswith(f"at {module}:" + str(text.count("\n")))
    assert "1 running up or sideways" in out.stdout


def test_a_cycle_fails_naming_its_packages(tmp_path: Path) -> None:
    files = {**CLEAN,
             "host/observers/base.py": "from host.diagnosis.logic import Literal\n",
             "host/diagnosis/logic.py": "def f():\n    from host.observers import base\n"}
    out = run("--root", str(tree(tmp_path, files)))
    assert out.returncode == 1, out.stdout + out.stderr
    assert "cycle: host.diagnosis <-> host.observers" in out.stdout
    assert "1 cycles" in out.stdout


@pytest.mark.parametrize(("files", "message"), [
    ({"host/gadgets/x.py": "import host.errors\n"},
     "package host.gadgets has no floor; add it to LAYERS in scripts/layers.py"),
    ({"host/board/client.py": "def broken(:\n"}, "does not parse"),
])
def test_bad_input_is_one_line_and_exit_code_2(
        tmp_path: Path, files: dict[str, str], message: str) -> None:
    out = run("--root", str(tree(tmp_path, {**CLEAN, **files})))
    assert out.returncode == 2, out.stdout + out.stderr
    assert message in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1, out.stderr
    assert "Traceback" not in out.stderr


def test_a_directory_without_packages_is_bad_input(tmp_path: Path) -> None:
    out = run("--root", str(tmp_path))
    assert out.returncode == 2
    assert "pass the repository with --root" in out.stderr


@pytest.mark.parametrize("text", [
    "from tests.daemon.runner import RunningDaemon\n",
    "import tests.wait\n",
    "def main():\n    from tests.plandiag.synth import synthetic_domain\n",
])
def test_a_benchmark_that_imports_the_tests_fails_naming_the_place(
        tmp_path: Path, text: str) -> None:
    files = {**CLEAN, "benchmarks/loop.py": "import host.errors\n" + text,
             "benchmarks/_rigs.py": "from host.launch.running import RunningDaemon\n"}
    out = run("--root", str(tree(tmp_path, files)))
    assert out.returncode == 1, out.stdout + out.stderr
    assert "benchmark imports tests: benchmarks/loop.py:" in out.stdout
    assert "1 imports of tests/ by benchmarks/" in out.stdout
    assert "0 running up or sideways, 0 cycles" in out.stdout  # the floors are not the reason


def test_benchmarks_on_the_launcher_and_their_rigs_pass(tmp_path: Path) -> None:
    files = {**CLEAN, "benchmarks/loop.py": "from benchmarks._rigs import KEY\n",
             "benchmarks/_rigs.py": "from host.launch.running import RunningDaemon\n"}
    out = run("--root", str(tree(tmp_path, files)))
    assert out.returncode == 0, out.stdout + out.stderr
    assert "0 imports of tests/ by benchmarks/" in out.stdout


def test_the_real_tree_keeps_its_layers() -> None:
    out = run()
    assert out.returncode == 0, out.stdout + out.stderr
    assert "host.planning" in out.stdout
    assert "0 running up or sideways, 0 cycles" in out.stdout
    assert "0 imports of tests/ by benchmarks/" in out.stdout


def test_dot_prints_the_graph_for_graphviz(tmp_path: Path) -> None:
    out = run("--root", str(tree(tmp_path, CLEAN)), "--dot")
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("digraph dxboard {")
    assert '"host.daemon" -> "host.board"' in out.stdout
