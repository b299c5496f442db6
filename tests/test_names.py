"""``scripts/names.py``: class names defined more than once in the product code, run as a process.

A fake tree with one name defined in two modules (and one defined twice in a single module,
which is not a second meaning) is listed with its places and counted; ``--check`` fails past
the limit; a file that does not parse is one line and exit code 2. On the real tree, the
renamed classes are gone from the list and the count is printed.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "scripts" / "names.py"


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(SCRIPT), *args], capture_output=True, text=True,
                          timeout=300, cwd=ROOT)


def write(base: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        (base / name).parent.mkdir(parents=True, exist_ok=True)
        (base / name).write_text(text, encoding="utf-8")
    return base


def test_a_name_defined_in_two_modules_is_listed_with_its_places(tmp_path: Path) -> None:
    root = write(tmp_path, {
        "host/a.py": "class Step:\n    pass\n",
        "protocol/b.py": "\n\nclass Step: ...\nclass Once: ...\n",
        "host/c.py": "class Twice: ...\nif True:\n    class Twice: ...\n",
    })
    out = run("--root", str(root))
    assert out.returncode == 0, out.stderr
    assert "Step x2: protocol/b.py:3, host/a.py:1" in out.stdout
    assert "Twice" not in out.stdout and "Once" not in out.stdout
    assert out.stdout.splitlines()[-1].startswith("1 class names defined more than once")


def test_check_fails_past_the_limit(tmp_path: Path) -> None:
    files = {f"host/m{i}.py": "".join(f"class C{k}: ...\n" for k in range(6)) for i in range(2)}
    out = run("--root", str(write(tmp_path, files)), "--check")
    assert out.returncode == 1
    assert "6 class names defined more than once (at most 5 wanted)" in out.stdout


def test_a_file_that_does_not_parse_is_one_line_and_exit_code_2(tmp_path: Path) -> None:
    out = run("--root", str(write(tmp_path, {"host/bad.py": "class (:\n"})))
    assert out.returncode == 2
    assert "host/bad.py:1: does not parse" in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1 and "Traceback" not in out.stderr


def test_the_real_tree_says_each_layer_in_its_names() -> None:
    out = run()
    assert out.returncode == 0, out.stderr
    listed = {line.split(" x", 1)[0] for line in out.stdout.splitlines()[:-1]}
    assert "Observation" in listed  # the literal (diagnosis) and its change (events)
    observation = next(x for x in out.stdout.splitlines() if x.startswith("Observation x"))
    assert "host/layers.py" not in observation and "plandiag" not in observation
    assert "Step x" in out.stdout and "plandiag" not in out.stdout.split("Step x", 1)[1].split(
        "\n", 1)[0]
    assert "class names defined more than once" in out.stdout.splitlines()[-1]
