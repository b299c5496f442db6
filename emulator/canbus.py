"""The firmware's CAN node (``firmware/can.py``) on a python-can bus, for the emulated board.

``CanFrontEnd(emu, "INTERFACE:CHANNEL")`` opens the bus (``virtual`` in tests, ``socketcan``,
``udp_multicast`` ...), sends the frames the node's ``poll`` makes after every protection step
(``pump``, called by ``FrontEnds``) and feeds received frames to its ``receive`` from a
python-can ``Notifier`` on the emulator's loop. This module only moves frames: the node is the
firmware's ``CanNode``, built in this interpreter by default, or by ``node_factory(firmware)``
(``--runtime micropython``: a node that lives in the micropython process, ``emulator/mpy.py``).
A reboot gets a new node (new nonce, counters start again), as on the board. Must be built on
the emulator's loop.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from typing import Any

import can

from emulator.sim import Emulator
from firmware.can import CanNode
from firmware.session import board_key

log = logging.getLogger(__name__)


def local_node(firmware: Any, node: int = 0, rate_hz: int = 10) -> CanNode:
    """The firmware's CAN node for a firmware running in this interpreter."""
    board = firmware.board
    return CanNode(board, board_key(board), firmware.hal.random_bytes, node, rate_hz)


class CanFrontEnd:
    def __init__(self, emu: Emulator, spec: str,
                 node_factory: Callable[[Any], Any] = local_node) -> None:
        interface, _, channel = spec.partition(":")
        self.emu = emu
        self.node_factory = node_factory
        self.url = f"can://{interface}/{channel}"
        self.bus: Any = can.Bus(interface=interface, channel=channel, receive_own_messages=False)
        self.firmware: Any = None
        self.node: Any = None
        self._attach()
        self.notifier = can.Notifier(self.bus, [self._on_message],
                                     loop=asyncio.get_running_loop())

    def _attach(self) -> None:
        self.firmware = self.emu.firmware
        self.node = self.node_factory(self.firmware)

    def _send(self, frames: list[tuple[int, bytes]]) -> None:
        for can_id, data in frames:
            try:
                self.bus.send(can.Message(arbitration_id=can_id, data=data,
                                          is_extended_id=False))
            except can.CanError as exc:  # a full or absent bus must not stop the board
                log.debug("CAN send failed: %s", exc)

    def pump(self, now: int) -> None:
        if self.firmware is not self.emu.firmware:
            self._attach()
        self._send(self.node.poll(now))

    def _on_message(self, msg: can.Message) -> None:
        if msg.is_extended_id or msg.is_remote_frame or self.node is None \
                or self.emu.in_reset:
            return
        self._send(self.node.receive(msg.arbitration_id, bytes(msg.data),
                                     self.emu.hal.ticks_ms()))

    def close(self) -> None:
        self.notifier.stop()
        self.bus.shutdown()
