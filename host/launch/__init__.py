"""Starting a robot, and every process of ours: the one launcher of the product, the tests and
the benchmarks. ``procs`` is a child process (started in a session of its own and tied to us,
ready once it printed what it promised, stopped by a bounded signal-then-kill); ``emulated``
the emulated board as one (``dxboard run --emulate``), ``running`` ``dxboard run`` as one and
``boards`` ``dxboard emulate`` on its own (driven as a person would: the tests' and
benchmarks' daemon and board), ``prometheus`` the fleet view's servers; ``control`` the
emulated board's control endpoint; ``robot`` the in-process launcher that starts the emulated
robot and the daemon for ``dxboard run``, the experiments and the tests; ``ports``,
``domains`` and ``waiting`` what a launcher needs around them (ports named in advance, ROS 2
domains of one's own, waits with generous deadlines); ``stopping`` and ``signals`` a stop's
reports and signals; ``mission_stack`` wires the mission layers (``host.mission``,
``host.executive``, ``host.skills``, ``host.plandiag``) to a running daemon, the one place
that composes the daemon with them (MISSIONS.md).
"""
