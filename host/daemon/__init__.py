"""The host daemon (``dxboard run``): it wires the board client, the observers, the diagnoser,
the repair planner and executor, the journal and the web page, and owns the clocks.

``core.Daemon`` is the loop; ``repairs.Repairs`` turns changed diagnoses into verified repairs;
``view.BoardView`` folds the board stream into what the page shows; ``emulated.EmulatedBoard``
starts the robot's emulated board for ``--emulate``.
"""
