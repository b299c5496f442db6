"""The host daemon (``dxboard run``): it wires the board client, the observers, the one
observation set, the diagnosis runner, the repair service, the operator socket, the journal and
the web page, and owns the clocks.

``core.Daemon`` wires and runs the loop; ``stream.EventStream`` is its one way out: every event
(``host.events``) goes to every projection — the journal, the page's status
(``host.web.fold``), the terminal (``host.commands.terminal``). Starting a robot (its emulated
board and the daemon) is ``host.launch``.
"""
