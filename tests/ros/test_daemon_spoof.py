"""A stranger on the robot's DDS domain can neither make the daemon switch power nor hide a fault.

The fast virtual TEDUSAR robot under ``dxboard run --emulate`` on ROS 2 (its nodes are real
rclpy nodes, in this test's own domain). A stranger — a plain rclpy node named ``stranger``,
no part of the model — first publishes ``/odom`` at 300 Hz, in bursts of 10 thirty times a
second (the observer's 1 s window sees 300 Hz all the same; the base's topic, 20 Hz in the
model: taken for the base's, it is a rate the daemon repairs by power-cycling the base), then
``/scan`` at 40 Hz from the moment the Hokuyo hangs (the Hokuyo's rate: taken for the
Hokuyo's, it hides the hang). The daemon
ignores both (issue 25 item 5): no repair while the base is healthy, the real Hokuyo hang
repaired under the spoofed ``/scan``, and each stranger told once in the journal as a
security note naming the topic and the node.
"""

from __future__ import annotations

from pathlib import Path

from nav_msgs.msg import Odometry
from sensor_msgs.msg import LaserScan

from host.events import Note
from tests.daemon.runner import RunningDaemon, actions_started, healthy, last_id
from tests.ros.conftest import Peer
from tests.ros.test_daemon_ros import ros_robot

WAIT_S = 180.0  # a power-up of the whole robot, on a loaded 2-core machine
SPOOF_S = 15.0  # the window the stranger publishes /odom in (the finding: 2 repairs in it)
BURST = 10  # /odom messages the stranger sends at once, 30 times a second


def security_notes(d: RunningDaemon) -> list[str]:
    return [e.payload.text for e in d.journal("note")
            if isinstance(e.payload, Note) and e.payload.text.startswith("security:")]


def scan() -> LaserScan:
    msg = LaserScan()
    msg.header.frame_id = "laser"
    msg.angle_min, msg.angle_max, msg.angle_increment = -2.0, 2.0, 0.01
    msg.range_min, msg.range_max = 0.1, 30.0
    msg.ranges = [1.0] * 400
    return msg


def test_a_stranger_on_the_domain_neither_repairs_the_base_nor_hides_a_lidar_hang(
        tmp_path: Path, domain: int) -> None:
    daemon = RunningDaemon(tmp_path, ros_robot(tmp_path))
    stranger = Peer(domain, "stranger")
    try:
        daemon.wait_for(healthy, WAIT_S, "the robot powered up and healthy")
        mark = last_id(daemon)
        odom = stranger.node.create_publisher(Odometry, "/odom", 10)
        fake = Odometry()
        fake.twist.twist.angular.z = 3.0  # a base spinning, as the stranger says

        def spoof_odom() -> None:  # 300 Hz, in bursts (a timer at 300 Hz costs this test's
            for _ in range(BURST):  # process a fifth of a CPU the robot's nodes need)
                fake.header.stamp = stranger.node.get_clock().now().to_msg()
                odom.publish(fake)

        odom_timer = stranger.node.create_timer(BURST / 300, spoof_odom)
        stranger.wait_for(lambda: odom.get_subscription_count() >= 1,
                          "the daemon subscribed the stranger's /odom", WAIT_S)
        daemon.settled(SPOOF_S, runs=5)
        assert actions_started(daemon, mark) == []  # not one repair for the spoofed /odom
        daemon.wait_journal(lambda: any("/odom" in n for n in security_notes(daemon)),
                            WAIT_S, "the security note on /odom")
        odom_timer.cancel()

        # the lidar hangs and, from then on, the stranger publishes /scan at its rate (matched
        # with the daemon's reader beforehand, so that its first scans arrive at once)
        scan_pub = stranger.node.create_publisher(LaserScan, "/scan", 10)
        stranger.wait_for(lambda: scan_pub.get_subscription_count() >= 1,
                          "the daemon subscribed the stranger's /scan", WAIT_S)
        spoofed = scan()
        mark = last_id(daemon)
        daemon.inject("hokuyo", "hang")

        def spoof_scan() -> None:  # stamped now, as a real driver's
            spoofed.header.stamp = stranger.node.get_clock().now().to_msg()
            scan_pub.publish(spoofed)

        scan_timer = stranger.node.create_timer(1 / 40, spoof_scan)
        daemon.wait_journal(lambda: "power_cycle(hokuyo)" in actions_started(daemon, mark),
                            WAIT_S, "the hung Hokuyo power-cycled under the spoofed /scan")
        daemon.wait_for(healthy, WAIT_S, "the robot healthy again")
        daemon.wait_journal(lambda: any("/scan" in n for n in security_notes(daemon)),
                            WAIT_S, "the security note on /scan")
        scan_timer.cancel()
        notes = security_notes(daemon)
        assert len(notes) == 2, notes  # each stranger's topic told once
        assert all("stranger" in n for n in notes)
        for n in notes:  # and said on the daemon's terminal
            assert any(n in line for line in daemon.lines), (n, daemon.lines[-20:])
    finally:
        stranger.close()
        assert daemon.interrupt() == 0
