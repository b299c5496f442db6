"""The world the virtual robot acts in: a pyrobosim arena beside the robot's devices.

``dxboard emulate SYSTEM_DIR --robot --world`` serves it in the emulator process, next to the
devices it shares one physical truth with: ``arena`` is the pyrobosim world of
``SYSTEM_DIR/arena/world.yaml`` (rooms, doors, rubble, victims, the robot); ``truth`` says what
the board, the devices and their drivers let the robot do now; ``skills`` are the robot's skill
servers (navigate, detect, mark, open, level) stepped on the emulator's clock; ``server`` serves
them on TCP (``world: tcp://...``), as a robot's action servers. The host's skill layer
(``host.skills``) is their client.
"""
