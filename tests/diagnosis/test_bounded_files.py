"""Files a person gives are bounded: a "billion laughs" YAML file, a huge file, deep nesting.

Each is refused through the real command line with one line naming the file (and the line)
and the fix, exit code 2, no traceback. The commands run as subprocesses with their address
space capped, so that the old, unbounded loader fails here by running out of memory or time
instead of taking the machine (it grew to 2.2 GB over 90 s); the deadline is generous: it
only bounds how long a broken loader takes to fail.
"""

from __future__ import annotations

import resource
import subprocess
import sys
from pathlib import Path

import pytest

from host.diagnosis import load_system, yamlpos
from host.errors import UserError
from host.mission.files import load_mission
from tests.diagnosis.conftest import TEDUSAR

ROOT = Path(__file__).resolve().parents[2]
DEADLINE_S = 120.0
ADDRESS_SPACE = 3 * 1024**3  # far above what a refusal needs, far below what the bomb grows to


def billion_laughs(tail: str = "") -> str:
    lines = ['a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    for prev, name in zip("abcdefgh", "bcdefghi", strict=True):
        lines.append(f"{name}: &{name} [" + ",".join([f"*{prev}"] * 9) + "]")
    return "\n".join(lines) + "\n" + tail


def _capped() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))


def dxboard(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "host.cli", *args], cwd=ROOT, text=True,
                          capture_output=True, timeout=DEADLINE_S, preexec_fn=_capped)


def refused(out: subprocess.CompletedProcess[str], file: Path) -> str:
    assert out.returncode == 2, out.stderr[-3000:]
    assert "Traceback" not in out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and str(file) in lines[0], out.stderr
    return lines[0]


@pytest.fixture
def bomb_robot(tmp_path: Path) -> Path:
    (tmp_path / "system.yaml").write_text(billion_laughs(
        "components:\n  jaguar: {kind: device, channel: *i}\n"))
    (tmp_path / "o.obs").write_text("ok(/scan)\n")
    return tmp_path


def test_a_billion_laughs_model_is_refused_by_model_check_and_diagnose(
        bomb_robot: Path) -> None:
    file = bomb_robot / "system.yaml"
    line = refused(dxboard("model", "check", str(bomb_robot)), file)
    assert f"{file}:7:" in line and "alias" in line  # as docs/security.md shows it
    line = refused(dxboard("diagnose", str(bomb_robot), "--obs", str(bomb_robot / "o.obs")),
                   file)
    assert "alias" in line
    line = refused(dxboard("model", "clauses", str(file)), file)
    assert "alias" in line


def test_a_huge_file_is_refused_before_it_is_read(tmp_path: Path) -> None:
    model = tmp_path / "system.yaml"
    with model.open("w") as f:  # a sparse file: large, costs no disk
        f.truncate(64 * 1024**2)
    line = refused(dxboard("model", "check", str(tmp_path)), model)
    assert "bytes" in line and "smaller" in line
    obs = tmp_path / "huge.obs"
    with obs.open("w") as f:
        f.truncate(100 * 1024**3)  # 100 GB of nothing
    line = refused(dxboard("diagnose", str(TEDUSAR), "--obs", str(obs)), obs)
    assert "bytes" in line


def test_deep_nesting_is_refused_with_its_line(tmp_path: Path) -> None:
    deep = "[" * 900 + "]" * 900
    (tmp_path / "system.yaml").write_text(f"components: {{}}\nx: {deep}\n")
    line = refused(dxboard("model", "check", str(tmp_path)), tmp_path / "system.yaml")
    assert ":2:" in line and "deep" in line


def test_a_mission_file_bomb_is_refused(tmp_path: Path) -> None:
    robot = tmp_path / "robot"
    robot.mkdir()
    (robot / "mission").mkdir()
    (robot / "mission" / "mission.yaml").write_text(billion_laughs())
    with pytest.raises(UserError) as err:
        load_mission(robot)
    assert "mission.yaml:" in str(err.value) and "alias" in str(err.value)


def test_ordinary_aliases_still_load(tmp_path: Path) -> None:
    text = (TEDUSAR / "system.yaml").read_text()
    value, _ = yamlpos.load("base: &b {a: 1, b: [1, 2]}\nx: *b\ny: {<<: *b, c: 3}\n")
    assert value["x"] == {"a": 1, "b": [1, 2]} and value["y"]["c"] == 3
    (tmp_path / "system.yaml").write_text(text)
    assert load_system(tmp_path).name == load_system(TEDUSAR).name
