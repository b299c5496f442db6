"""The host's name for ``emulator.stopsignals``: SIGINT and SIGTERM never lost, stops bounded.

The signal handling lives in ``emulator/`` (below ``host/`` in the layers, ``scripts/layers.py``)
because the virtual robot's node processes need it too: asyncio's ``add_signal_handler`` shares
the loop's self-pipe with every ``call_soon_threadsafe`` (issue 25). ``dxboard run`` and
``dxboard record`` import it from here.
"""

from emulator.stopsignals import (
    DEADLINE_S,
    EXIT_DEADLINE,
    EXIT_SECOND,
    NUDGE_S,
    STOP_SIGNALS,
    StopSignals,
    kill_children,
)

__all__ = ["DEADLINE_S", "EXIT_DEADLINE", "EXIT_SECOND", "NUDGE_S", "STOP_SIGNALS", "StopSignals",
           "kill_children"]
