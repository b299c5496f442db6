"""``scripts/names.py``: class names defined more than once in the product code, run as a process.

A fake tree with one name defined in two modules (and one defined twice in a single module,
which is not a second meaning) is listed with its places and counted; ``--check`` fails past
the limit, and so does a name outside the allow-list (``KNOWN``) under it; a file that does not
parse is one line and exit code 2. On the real tree only names of the allow-list are defined
twice (three since one fold serves the page and ``/diagnostics``: no ``Status`` nor
``StatusFold`` twice), each place with a comment saying why.
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


def test_check_fails_on_a_name_outside_the_allow_list(tmp_path: Path) -> None:
    known = run("--root", str(write(tmp_path / "a", {"host/a.py": "class Task: ...\n",
                                                      "emulator/b.py": "class Task: ...\n"})),
                "--check")
    assert known.returncode == 0, known.stdout
    new = run("--root", str(write(tmp_path / "b", {"host/a.py": "class StatusFold: ...\n",
                                                    "host/b.py": "class StatusFold: ...\n"})),
              "--check")
    assert new.returncode == 1
    assert "StatusFold is not in KNOWN: rename one, or add it to KNOWN" in new.stdout


def test_a_file_that_does_not_parse_is_one_line_and_exit_code_2(tmp_path: Path) -> None:
    out = run("--root", str(write(tmp_path, {"host/bad.py": "class (:\n"})))
    assert out.returncode == 2
    assert "host/bad.py:1: does not parse" in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1 and "Traceback" not in out.stderr


def test_the_real_tree_keeps_the_limit_and_says_why_at_each_second_name() -> None:
    out = run("--check")  # make lint runs this
    assert out.returncode == 0, out.stdout
    listed = [line for line in out.stdout.splitlines()[:-1] if " x" in line]
    assert len(listed) <= 5
    names = {line.split(" x", 1)[0] for line in listed}
    assert names <= {"BoardEvent", "Observation", "Task"}, names  # not Status nor StatusFold
    for line in listed:  # "Name x2: path:line, path:line": a comment right above each
        for place in line.split(": ", 1)[1].split(", "):
            path, lineno = place.rsplit(":", 1)
            above = (ROOT / path).read_text(encoding="utf-8").splitlines()[:int(lineno) - 1]
            while above and above[-1].lstrip().startswith("@"):  # past its decorators
                above.pop()
            assert above and above[-1].lstrip().startswith("#"), f"{place}: say why ({line})"
