"""Starting a robot: the emulated board as a child process (``emulated``), its control endpoint
(``control``), and the one launcher that starts the emulated robot and the daemon for
``dxboard run``, the experiments and the tests (``robot``); ``mission_stack`` wires the
mission layers (``host.mission``, ``host.executive``, ``host.skills``, ``host.plandiag``) to a
running daemon, the one place that composes the daemon with them (MISSIONS.md).
"""
