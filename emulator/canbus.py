"""The firmware's CAN node (``firmware/can.py``) on a python-can bus, for the emulated board.

``CanFrontEnd(emu, "INTERFACE:CHANNEL")`` opens the bus (``virtual`` in tests, ``socketcan``,
``udp_multicast`` ...), sends the frames ``CanNode.poll`` makes after every protection step
(``pump``, called by ``FrontEnds``) and feeds received frames to ``CanNode.receive`` from a
python-can ``Notifier`` on the emulator's loop. A reboot gets a new node (new nonce, counters
start again), as on the board. Must be built on the emulator's loop.
"""

from __future__ import annotations

import asyncio
import logging
from typing import Any

import can

from emulator.sim import Emulator
from firmware.can import CanNode
from firmware.session import board_key

log = logging.getLogger(__name__)


class CanFrontEnd:
    def __init__(self, emu: Emulator, spec: str, node: int = 0, rate_hz: int = 10) -> None:
        interface, _, channel = spec.partition(":")
        self.emu = emu
        self.node_id = node
        self.rate_hz = rate_hz
        self.url = f"can://{interface}/{channel}"
        self.bus: Any = can.Bus(interface=interface, channel=channel, receive_own_messages=False)
        self.firmware: Any = None
        self.node: CanNode | None = None
        self._attach()
        self.notifier = can.Notifier(self.bus, [self._on_message],
                                     loop=asyncio.get_running_loop())

    def _attach(self) -> None:
        fw = self.emu.firmware
        board = fw.board
        self.firmware = fw
        self.node = CanNode(board, board_key(board), fw.hal.random_bytes, self.node_id,
                            self.rate_hz)

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
        assert self.node is not None
        self._send(self.node.poll(now))

    def _on_message(self, msg: can.Message) -> None:
        if msg.is_extended_id or msg.is_remote_frame or self.node is None:
            return
        self._send(self.node.receive(msg.arbitration_id, bytes(msg.data),
                                     self.emu.hal.ticks_ms()))

    def close(self) -> None:
        self.notifier.stop()
        self.bus.shutdown()
