"""The emulated board speaking the original TEDUSAR format (``tug://``), for old host software.

``TugServer(emu).start(host, port)`` (on the emulator's loop, ``control.Background.run``)
serves the format of ``host/transports/tug_codec.py`` (one codec for both ends; its header
documents the frames and our assumptions) over TCP. Every request is answered from the firmware
through its ``Board`` API, never by logic of its own: SPECIFICATIONS are each channel's
``rated_ma`` and the input voltage; MEASUREMENTS are ``Board.status()`` (status bit 0 = the
switch reads back on, bit 1 = tripped, latched or faulted; voltage = the input voltage on an
on channel, else 0); CHANNEL calls ``Board.switch`` (the old board had no notion of protected
channels or keys; a refusal is an ACK with result 1). SET FREQUENCY starts the broadcast of
MEASUREMENTS at that rate (0 stops it). A reboot of the emulated board closes every link, as
it does on the native protocol.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging

from emulator.sim import Emulator
from host.transports import tug_codec as tc
from protocol.constants import ST_FAULTED, ST_LATCHED, ST_TRIPPED

log = logging.getLogger(__name__)

FAULT_STATES = (ST_TRIPPED, ST_LATCHED, ST_FAULTED)


class TugServer:
    def __init__(self, emu: Emulator) -> None:
        self.emu = emu
        self.server: asyncio.Server | None = None
        self.tasks: set[asyncio.Task[None]] = set()
        self.url = ""

    async def start(self, host: str = "127.0.0.1", port: int = 0) -> str:
        self.server = await asyncio.start_server(self._client, host, port)
        h, p = self.server.sockets[0].getsockname()[:2]
        self.url = f"tug://{f'[{h}]' if ':' in h else h}:{p}"
        return self.url

    async def stop(self) -> None:
        if self.server is not None:
            self.server.close()
        for task in list(self.tasks):
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task

    def specs(self) -> bytes:
        board = self.emu.board
        volts = board.input_mv / 1000
        return tc.specs([(board.channels[i].cfg["rated_ma"] / 1000, volts)
                         for i in range(board.n)])

    def measurements(self) -> bytes:
        (mv, *_rest), chans = self.emu.board.status()
        out = []
        for c in chans:
            physical, state, current_ma = c[1], c[2], c[3]
            status = (tc.STATUS_ON if physical else 0) | \
                (tc.STATUS_FAULT if state in FAULT_STATES else 0)
            out.append((status, current_ma / 1000, mv / 1000 if physical else 0.0))
        return tc.measurements(out)

    def answer(self, frame: tc.TugFrame, rate: list[int]) -> bytes:
        """The reply to one frame; ``rate[0]`` is this link's broadcast frequency."""
        cmd, payload = frame.command, frame.payload
        if cmd == tc.REQUEST:
            if payload[0] == tc.SPECS:
                return self.specs()
            if payload[0] == tc.MEASUREMENTS:
                return self.measurements()
            return tc.ack(tc.REQUEST, 1)
        if cmd == tc.SET_FREQ:
            if payload[0] > 100:
                return tc.ack(tc.SET_FREQ, 1)
            rate[0] = payload[0]
            return tc.ack(tc.SET_FREQ, 0)
        if cmd == tc.CHANNEL:
            err = self.emu.board.switch(payload[0], bool(payload[1]))[0]
            return tc.ack(tc.CHANNEL, 1 if err else 0)
        return b""  # frames a host should not send (SPECS, MEASUREMENTS, ACK): ignored

    async def _client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        if task is not None:
            self.tasks.add(task)
        firmware = self.emu.firmware
        decoder = tc.Decoder()
        rate = [0]
        loop = asyncio.get_running_loop()
        next_at = loop.time()
        read: asyncio.Task[bytes] | None = None
        try:
            while self.emu.firmware is firmware:
                if read is None:
                    read = asyncio.ensure_future(reader.read(4096))
                wait = 0.05 if not rate[0] else max(0.0, min(0.05, next_at - loop.time()))
                done, _ = await asyncio.wait({read}, timeout=wait)
                if read in done:
                    data = read.result()
                    read = None
                    if not data:
                        return
                    decoder.feed(data)
                    for frame in decoder.frames():
                        if isinstance(frame, tc.TugFrame):
                            writer.write(self.answer(frame, rate))
                if rate[0] and loop.time() >= next_at:
                    writer.write(self.measurements())
                    next_at = max(next_at + 1 / rate[0], loop.time())
                await writer.drain()
        except (ConnectionError, OSError) as exc:
            log.debug("tug client: %s", exc)
        finally:
            if read is not None:
                read.cancel()
            writer.close()
            if task is not None:
                self.tasks.discard(task)
