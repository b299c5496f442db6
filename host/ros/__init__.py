"""dxboard in ROS 2 terms: the daemon's outputs, lifecycles and bags.

``status`` folds the daemon's event stream into ``diagnostic_msgs`` statuses and ``publisher``
publishes them with ``/diagnosis``, ``/board_measurements`` and ``/battery_state``;
``lifecycle`` drives a managed node through ``ChangeState``/``GetState``
(``LifecycleActuator``: the repair domain's ``reconfigure_node``); ``bag`` writes and reads
rosbag2 (MCAP) files, ``boardstream`` and ``graphlog`` put the board's samples and the ROS 2
graph into bags, and ``offline`` runs the observers and the diagnosis on a clock the caller
drives (``host.commands.bagrun`` records and replays bags with them for ``dxboard
record``/``replay``). ROS 2 as an observation source lives with the other sources:
``host.observers.sources.ros2`` with its rclpy thread (``ros2_node``), messages as dicts
(``ros2_convert``), the CDR topic message (``ros2_message``) and node presence
(``ros2_graph``). Every module but ``status`` and ``offline`` needs the ``ros`` extra (rclpy,
rosbags).
"""
