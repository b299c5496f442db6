"""Layer 3 of the mission stack (paper 001 §II-A, §III-C): the mission.

``pddl`` reads the temporal PDDL domain and problem (durative actions: start, over-all and end
conditions and effects), ``planner`` grounds them and finds an optimal schedule, ``kb`` is the
knowledge base, ``sensing`` is ψ (the world's state as atoms), ``dispatcher`` checks, dispatches,
monitors and applies each action ROSPlan-like, ``runner`` reasons about goals and replans, and
``files`` reads a robot's ``mission/mission.yaml``. The temporal PDDL itself is
``host.planning``'s; ``host.launch.mission_stack`` wires the stack to a running daemon and the
world (``dxboard mission``), so nothing here knows the daemon.
"""
