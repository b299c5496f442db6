"""The host's name for ``emulator.inbox``: handing middleware messages to the loop in batches.

The batching inbox lives in ``emulator/`` (below ``host/`` in the layers, ``scripts/layers.py``)
because the virtual robot's node processes hand their Zenoh and ROS 2 messages to their loop
the same way (issue 25); the host's topic sources import it from here.
"""

from emulator.inbox import MAXLEN, TELL_EVERY_S, Inbox

__all__ = ["MAXLEN", "TELL_EVERY_S", "Inbox"]
