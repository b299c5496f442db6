"""``dxboard model diff OLD NEW``: what changed between two models, exit 0 same, 1 differ, 2 bad
input, through the real command line."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

from host.learn.diff import diff_models

ROOT = Path(__file__).resolve().parents[3]
TEDUSAR = ROOT / "models" / "tedusar"


def dxboard(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "host.cli", *args], capture_output=True,
                          text=True, cwd=ROOT, timeout=300)


def changed_copy(tmp_path: Path) -> Path:
    new = tmp_path / "new"
    new.mkdir()
    text = (TEDUSAR / "system.yaml").read_text()
    for old, new_text in (
            ("    current: [0.2, 1.2]\n", "    current: [0.25, 1.5]\n"),
            ("    subscribes: [/scan]\n    publishes: {/map: [/scan], /slam_out_pose: [/scan]}",
             "    subscribes: [/scan, /imu_data]\n"
             "    publishes: {/map: [/scan, /imu_data], /slam_out_pose: [/scan]}"),
            ("    /scan: {rate: 40, tolerance: 10, window: 0.5}",
             "    /scan: {rate: 39.8, tolerance: 8, window: 0.5}"),
            ("  rviz:\n    kind: N\n    subscribes: [/map, /scan, /slam_out_pose]\n", "")):
        assert old in text
        text = text.replace(old, new_text)
    (new / "system.yaml").write_text(text.replace("  rviz: {command", "  # rviz: {command"))
    return new


def test_what_changed_one_line_each(tmp_path: Path) -> None:
    lines = diff_models(TEDUSAR, changed_copy(tmp_path))
    assert lines == [
        "- component rviz (N)",
        "~ component hokuyo: current [0.2, 1.2] -> [0.25, 1.5]",
        "~ component hector_mapping: subscribes [/scan] -> [/imu_data, /scan]",
        "~ component hector_mapping: /map depends on [/scan] -> [/imu_data, /scan]",
        "~ observer of /scan: rate 40 -> 39.8, tolerance 10 -> 8",
    ]


def test_the_command_exits_like_diff(tmp_path: Path) -> None:
    same = dxboard("model", "diff", str(TEDUSAR), str(TEDUSAR))
    assert (same.returncode, same.stdout) == (0, "")
    copy = tmp_path / "copy"
    shutil.copytree(TEDUSAR, copy)
    assert dxboard("model", "diff", str(TEDUSAR), str(copy / "system.yaml")).returncode == 0
    differ = dxboard("model", "diff", str(TEDUSAR), str(changed_copy(tmp_path)))
    assert differ.returncode == 1 and "- component rviz (N)" in differ.stdout
    bad = dxboard("model", "diff", str(TEDUSAR), str(tmp_path / "nothing"))
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1
    assert "Traceback" not in bad.stderr
