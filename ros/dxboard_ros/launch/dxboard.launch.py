"""Launch dxboard's daemon as a ROS 2 node with the package's (or your) parameters file.

``ros2 launch dxboard_ros dxboard.launch.py [params_file:=FILE]``: the node ``dxboard`` of
the executable ``dxboard`` with ``--ros-args --params-file FILE`` (default: this package's
``config/dxboard.yaml``, every option of ``dxboard run``). With ``aggregator:=true`` it also
starts diagnostic_aggregator with ``config/analyzers.yaml``, so that rqt_robot_monitor shows
dxboard's statuses as one tree under ``dxboard``.
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def generate_launch_description():
    share = get_package_share_directory("dxboard_ros")
    params_file = LaunchConfiguration("params_file")
    return LaunchDescription([
        DeclareLaunchArgument(
            "params_file", default_value=os.path.join(share, "config", "dxboard.yaml"),
            description="the daemon's parameters (every option of `dxboard run`)"),
        DeclareLaunchArgument(
            "aggregator", default_value="false",
            description="also start diagnostic_aggregator with config/analyzers.yaml"),
        Node(package="dxboard_ros", executable="dxboard", name="dxboard", output="screen",
             parameters=[params_file]),
        Node(package="diagnostic_aggregator", executable="aggregator_node",
             name="analyzers", output="screen",
             parameters=[os.path.join(share, "config", "analyzers.yaml")],
             condition=IfCondition(LaunchConfiguration("aggregator"))),
    ])
