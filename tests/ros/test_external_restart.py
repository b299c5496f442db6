"""A node started by another launcher is restarted through the actuator the model names for it.

The finding (issue 28, item 2): nodes launched by ``ros2 launch``, systemd or a container are
seen in the graph but no action can restart them. Here the thermal camera's driver is a plain
rclpy camera-like publisher (``second_robot/camera.py``, no dxboard code) started by the test,
as a launcher would; the model names it in ``external:`` with a ``command`` that restarts it
the launcher's way (``second_robot/restart.py``: stop the old pid, start it again in the
background). ``dxboard run`` on ROS 2 watches it; the test kills it; the daemon plans
``restart_node`` and runs the command, and the new process publishes again.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
from pathlib import Path

import psutil
import pytest
from diagnostic_msgs.msg import DiagnosticArray
from sensor_msgs.msg import Image

from tests.daemon.runner import RunningDaemon, fast_copy
from tests.ros.conftest import Peer
from tests.ros.test_daemon_ros import OK, latest
from tests.ros.test_lifecycle_manager import DAEMON_WAIT_S, actions
from tests.wait import wait_until

HERE = Path(__file__).parent / "second_robot"
NODE, TOPIC = "thermal_camera_node", "/thermal/image"


@pytest.mark.timeout(900)  # a whole robot's power-up under a load of 100 on 2 cores
def test_a_node_started_by_another_launcher_is_restarted_by_its_command(
        tmp_path: Path, peer: Peer) -> None:
    pidfile = tmp_path / "camera.pid"
    camera = [sys.executable, str(HERE / "camera.py"), NODE, TOPIC, "--pidfile", str(pidfile)]
    restart = [sys.executable, str(HERE / "restart.py"), str(pidfile), "--", *camera]
    system = fast_copy(tmp_path)
    f = system / "system.yaml"
    text = "\n".join(x for x in f.read_text().splitlines()
                     if not x.startswith(f"  {NODE}: {{command"))
    text = text.replace("observers:\n", "observers:\n  source: {kind: ros2}\n", 1).replace(
        f"    {NODE}: {{supervised: true}}", f"    {NODE}: {{graph: true}}")
    f.write_text(text + f"\nexternal:\n  {NODE}: {{command: {restart!r}}}\n".replace("'", '"'))
    peer.listen(TOPIC, Image)
    peer.listen("/diagnostics", DiagnosticArray)
    launched = subprocess.Popen(camera, start_new_session=True)  # the launcher: not dxboard
    daemon = RunningDaemon(tmp_path, system)
    try:
        # (the daemon's /diagnostics, not its web page: a loaded machine slows that down)
        peer.wait_for(lambda: latest(peer, f"dxboard/components/{NODE}") == OK, "the driver OK",
                      DAEMON_WAIT_S)
        peer.collect(TOPIC, 9, DAEMON_WAIT_S)
        launched.kill()  # the driver dies
        launched.wait(30)
        wait_until(lambda: ("restart_node", "succeeded") in actions(daemon, NODE),
                   DAEMON_WAIT_S, "dxboard restarted it", show=lambda: actions(daemon, NODE))
        # the new process writes its pid as it starts
        wait_until(lambda: pidfile.read_text() != str(launched.pid), DAEMON_WAIT_S,
                   "the restarted process's pid")
        peer.collect(TOPIC, 9, DAEMON_WAIT_S)  # the new process publishes
        peer.wait_for(lambda: latest(peer, f"dxboard/components/{NODE}") == OK,
                      "the driver OK again", DAEMON_WAIT_S)
        assert {a for a, _ in actions(daemon, NODE)} <= {"restart_node"}
    finally:
        daemon.close()
        if launched.poll() is None:
            launched.kill()
            launched.wait(10)
        with contextlib.suppress(FileNotFoundError, ValueError, ProcessLookupError):
            os.kill(int(pidfile.read_text()), signal.SIGKILL)
        # every camera the restarts started, also one a second restart overtook before it
        # wrote its pid (on a busy machine): their command lines name this test's pidfile
        for proc in psutil.process_iter(["cmdline"]):
            if str(pidfile) in (proc.info["cmdline"] or []):
                with contextlib.suppress(psutil.Error):
                    proc.kill()
