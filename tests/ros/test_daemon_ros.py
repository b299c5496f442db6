"""The daemon on the ROS 2 robot, seen by an independent rclpy peer that knows nothing of dxboard.

``dxboard run --emulate`` on a copy of ``models/tedusar`` whose one setting says ROS 2
(``observers: source: {kind: ros2}``): the daemon starts the robot's nodes as rclpy nodes,
observes them over DDS and publishes its state on ``/diagnostics``, ``/diagnosis``,
``/board_measurements`` and ``/battery_state``. The peer (plain rclpy and the standard message
packages, in this test's own DDS domain) sees the Hokuyo go ERROR when it hangs and OK once
the daemon has repaired it (a power cycle, then its managed driver reconfigured by lifecycle
transitions: ``reconfigure_node``), and finds nothing on the daemon's node it could switch
power with.
"""

from __future__ import annotations

from pathlib import Path

import yaml
from diagnostic_msgs.msg import DiagnosticArray
from sensor_msgs.msg import BatteryState
from std_msgs.msg import Float32MultiArray

from tests.daemon.runner import RunningDaemon, fast_copy
from tests.ros.conftest import Peer

OK, ERROR = 0, 2
WAIT_S = 180.0  # a power-up of the whole robot, on a loaded 2-core machine


def level(msg: DiagnosticArray, name: str) -> int | None:
    for s in msg.status:
        if s.name == name:
            return s.level[0] if isinstance(s.level, bytes) else int(s.level)
    return None


def latest(peer: Peer, name: str) -> int | None:
    msgs = peer.messages("/diagnostics")
    return level(msgs[-1], name) if msgs else None


def repair_of(peer: Peer, component: str) -> str:
    """The ``repair`` key/value of the component's latest status."""
    msgs = peer.messages("/diagnostics")
    return next((kv.value for s in (msgs[-1].status if msgs else ())
                 if s.name == f"dxboard/components/{component}" for kv in s.values
                 if kv.key == "repair"), "")


def battery_v(system: Path) -> float:
    """The emulated battery's voltage: ``board: input_mv`` of the robot's ``emulator.yaml``."""
    board = yaml.safe_load((system / "emulator.yaml").read_text())["board"]
    return float(board["input_mv"]) / 1000.0


def ros_robot(tmp: Path) -> Path:
    d = fast_copy(tmp)
    text = (d / "system.yaml").read_text()
    (d / "system.yaml").write_text(text.replace("observers:\n",
                                                "observers:\n  source: {kind: ros2}\n", 1))
    return d


def test_an_independent_subscriber_sees_the_hokuyo_go_error_on_a_hang_and_ok_after_repair(
        tmp_path: Path, domain: int, peer: Peer) -> None:
    for topic, kind in (("/diagnostics", DiagnosticArray), ("/diagnosis", DiagnosticArray),
                        ("/board_measurements", Float32MultiArray),
                        ("/battery_state", BatteryState)):
        peer.listen(topic, kind)
    system = ros_robot(tmp_path)
    daemon = RunningDaemon(tmp_path, system)
    try:
        # the power-up: everything starts off, the daemon brings the robot up by itself (only
        # the Hokuyo, its driver and the board matter here: on a loaded machine another
        # component may flap meanwhile)
        peer.wait_for(lambda: latest(peer, "dxboard/components/hokuyo") == OK
                      and latest(peer, "dxboard/components/hokuyo_node") == OK
                      and latest(peer, "dxboard/board/link") == OK, "the Hokuyo up", WAIT_S)
        peer.wait_for(lambda: "hokuyo_node" in peer.nodes(),  # the driver is a ROS 2 node
                      "hokuyo_node in the peer's graph", WAIT_S)  # (discovery may lag)
        board = peer.collect("/board_measurements", 3)[-1]
        assert len(board.data) == 10 and board.layout.dim[0].label == "channel"
        assert 0.2 <= board.data[3] <= 1.2  # the Hokuyo's channel, in its band (A)
        battery = peer.collect("/battery_state", 1)[-1]
        assert battery.current < 0 and battery.present  # discharging
        # the board's input: the emulated battery's voltage (the model's value, 10 mV steps)
        assert abs(battery.voltage - battery_v(system)) < 0.05, battery.voltage
        # (the power-up's first diagnoses may go out before DDS discovery has matched the
        # peer's subscription — volatile QoS, as a real topic: /diagnosis is checked on the
        # hang below, published long after discovery)

        daemon.inject("hokuyo", "hang")
        peer.wait_for(lambda: latest(peer, "dxboard/components/hokuyo") == ERROR,
                      "the Hokuyo ERROR after the hang", WAIT_S)
        status = next(s for s in peer.messages("/diagnostics")[-1].status
                      if s.name == "dxboard/components/hokuyo")
        assert "abnormal in the best diagnosis" in status.message
        peer.wait_for(lambda: any(s.name.startswith("dxboard diagnosis ") and s.level == b"\x02"
                                  and "hokuyo" in [kv.key for kv in s.values]
                                  for m in peer.messages("/diagnosis") for s in m.status),
                      "/diagnosis naming the Hokuyo", WAIT_S)
        # OK again, and the repair action on it recorded as succeeded (the diagnosis may clear
        # it a moment before the executor has verified the action's effects)
        peer.wait_for(lambda: latest(peer, "dxboard/components/hokuyo") == OK
                      and repair_of(peer, "hokuyo").startswith("power_cycle(hokuyo)")
                      and repair_of(peer, "hokuyo").endswith("succeeded"),
                      "the Hokuyo OK after a successful power cycle", WAIT_S)
        # its managed driver lost the device: repaired by lifecycle transitions, not restarted
        peer.wait_for(lambda: repair_of(peer, "hokuyo_node").endswith("succeeded"),
                      "the Hokuyo driver's repair verified", WAIT_S)
        assert repair_of(peer, "hokuyo_node").startswith("reconfigure_node(hokuyo_node)")
        assert latest(peer, "dxboard/components/hokuyo_node") == OK

        # nothing that switches power is reachable from ROS 2: no subscription, no service
        # but rclpy's own parameter and type-description services
        node = peer.node
        assert node.get_subscriber_names_and_types_by_node("dxboard", "/") == []
        services = {n for n, _ in node.get_service_names_and_types_by_node("dxboard", "/")}
        assert all(n.startswith("/dxboard/") and n.rsplit("/", 1)[1] in (
            "describe_parameters", "get_parameter_types", "get_parameters",
            "list_parameters", "set_parameters", "set_parameters_atomically",
            "get_type_description") for n in services), services
    finally:
        assert daemon.interrupt() == 0
