"""The virtual TEDUSAR robot: devices on the emulated board's channels and its ROS-like nodes.

``config`` reads ``robot.yaml`` (the devices) and the nodes of ``system.yaml``; ``devices`` is
what each device sends and accepts (the line protocol) and the motion they share; ``server``
serves each device on TCP inside the emulator, powered by the simulated electronics
(``dxboard emulate SYSTEM_DIR --robot``); ``bus`` is the few lines of Eclipse Zenoh the nodes
publish and subscribe with; ``behaviours`` and ``node`` are the node processes
(``python -m emulator.robot.node NAME SYSTEM_DIR``).
"""
