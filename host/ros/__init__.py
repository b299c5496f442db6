"""dxboard in ROS 2 terms: the rclpy thread, messages as dicts, the projections out, lifecycles.

``node`` runs one rclpy node in a thread of its own with its own executor and context (the
daemon's asyncio loop is never blocked by DDS); ``convert`` turns any generated message into
the plain dict the observers read by path, and names types (``sensor_msgs/msg/LaserScan``);
``message`` is the topic ``Message`` whose payload is CDR, decoded only when an observer asks
for values; ``graph`` reads node presence from the ROS 2 graph; ``status`` folds the
daemon's event stream into ``diagnostic_msgs`` statuses and ``publisher`` publishes them
with ``/diagnosis``, ``/board_measurements`` and ``/battery_state``; ``lifecycle`` drives a
managed node through ``ChangeState``/``GetState`` (``LifecycleActuator``: the repair domain's
``reconfigure_node``); ``bag`` writes and reads rosbag2 (MCAP) files, ``offline`` runs the
observers and the diagnosis on a clock the caller drives and ``bagrun`` records and replays
bags with them (``dxboard record``/``replay``). The observation source is
``host.observers.sources.ros2``. Every module but ``graph``, ``status`` and ``offline`` needs
the ``ros`` extra (rclpy, rosbags).
"""
