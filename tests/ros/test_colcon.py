"""The ROS 2 package ``ros/dxboard_ros`` built the ROS way: ``colcon build`` in a fresh workspace.

colcon-core, colcon-ros and ros-ament-package come from PyPI (the test extra); colcon must
see the package as ``ament_python`` (its install gets the ament prefix hook), and the install
space must hold the launch entry, the params file (the one in the repository, every option of
``dxboard run``), the analyzers file, the ament index marker and a ``dxboard`` executable that
runs: sourced as a ROS user would (``. install/setup.sh``), it prints ``dxboard run``'s help,
and its ``--ros-args --params-file`` become the daemon's options (a params file naming a robot
directory that does not exist gets the daemon's own one-line error about that directory).
launch and launch_ros are not on PyPI, so the launch file is compiled here, not launched.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "ros" / "dxboard_ros"
BUILD_S = 600.0  # generous: a busy machine; the build takes seconds when quiet


def build(ws: Path) -> subprocess.CompletedProcess[str]:
    shutil.copytree(PACKAGE, ws / "src" / "dxboard_ros",
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    colcon = Path(sys.executable).parent / "colcon"
    env = {**os.environ, "COLCON_HOME": str(ws / "colcon-home"), "PYTHONPATH": str(ROOT)}
    return subprocess.run([str(colcon), "build", "--event-handlers", "console_direct-"],
                          cwd=ws, env=env, capture_output=True, text=True, timeout=BUILD_S)


def sourced(ws: Path, command: str) -> subprocess.CompletedProcess[str]:
    """``command`` in a shell that sourced the workspace, as a ROS user runs things."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(["sh", "-c", f". ./install/setup.sh && {command}"], cwd=ws, env=env,
                          capture_output=True, text=True, timeout=BUILD_S)


def test_colcon_builds_the_package_into_a_runnable_install(tmp_path: Path, env: dict[str, str]
                                                           ) -> None:
    done = build(tmp_path)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    install = tmp_path / "install" / "dxboard_ros"
    share = install / "share" / "dxboard_ros"
    assert (share / "package.xml").is_file()
    assert (install / "share" / "ament_index" / "resource_index" / "packages"
            / "dxboard_ros").is_file()
    assert (share / "hook" / "ament_prefix_path.dsv").is_file()  # colcon-ros: ament_python
    assert (share / "config" / "dxboard.yaml").read_text() == (
        PACKAGE / "config" / "dxboard.yaml").read_text()
    assert "diagnostic_aggregator/AnalyzerGroup" in (share / "config"
                                                      / "analyzers.yaml").read_text()
    launch = share / "launch" / "dxboard.launch.py"
    compile(launch.read_text(), str(launch), "exec")
    exe = install / "lib" / "dxboard_ros" / "dxboard"
    assert os.access(exe, os.X_OK)

    helped = sourced(tmp_path, "install/dxboard_ros/lib/dxboard_ros/dxboard --help")
    assert helped.returncode == 0, helped.stderr
    assert "usage: dxboard run" in helped.stdout and "--board URL" in helped.stdout

    params = tmp_path / "robot.yaml"
    params.write_text("dxboard:\n  ros__parameters:\n"
                      f"    system_dir: {tmp_path / 'no-robot'}\n    emulate: true\n")
    ran = sourced(tmp_path, "install/dxboard_ros/lib/dxboard_ros/dxboard "
                            f"--ros-args --params-file {params}")
    assert ran.returncode == 2, ran.stderr
    assert f"dxboard run: error: {tmp_path / 'no-robot'}: no system.yaml here" in ran.stderr
    assert "Traceback" not in ran.stderr

    # docs/your-robot.md's example of a wrong type, word for word
    wrong = sourced(tmp_path, "install/dxboard_ros/lib/dxboard_ros/dxboard "
                              "--ros-args -p rate:=fast")
    assert (wrong.returncode, wrong.stderr) == (
        2, "dxboard run: error: parameter rate = 'fast' has the wrong type (give an integer)\n")
