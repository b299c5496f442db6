"""dxboard board firmware, in the MicroPython subset: protection that runs on its own.

``board.Board`` owns the channels (``channel.Channel``, one table-driven state machine each)
and runs one protection step per ``tick(now_ms)``; ``config`` persists the configuration as
versioned JSON with a CRC; ``supervisor`` feeds the hardware watchdog only while every task is
alive; ``app.App`` wires them for a main loop. All hardware is behind ``hal`` and passed in:
only ``main.py`` builds real ``machine`` objects (``hal.target``); the emulator passes a
simulated HAL instead and runs exactly this code.
"""
