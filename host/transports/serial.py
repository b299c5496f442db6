"""``serial:///dev/ttyACM0?baud=115200``: the native protocol over a serial line (pyserial).

URL grammar: ``serial://DEVICE[?baud=N][&per_frame=K]`` with DEVICE an absolute path (so three
slashes: ``serial:///dev/ttyACM0``), baud 300..4000000, default 115200; 8N1, no flow control;
``per_frame`` as for ``tcp://`` (``host/transports/stream.py``). A serial
line has no connection: the board may have greeted long ago, so the host asks for a fresh HELLO
(HELLO_REQUEST) when none arrives at once. A board that reboots greets again; the board client
sees the new boot id in that HELLO. POSIX only: reads wait on the file descriptor with the
event loop's ``add_reader``; writes are small and go straight to the device.
"""

from __future__ import annotations

import asyncio
import logging

import serial as pyserial

from host.transports.stream import PER_FRAME, READ_SIZE, StreamTransport
from host.transports.url import BoardUrl

log = logging.getLogger(__name__)

SCHEME = "serial"
DEFAULT_BAUD = 115200


class SerialTransport(StreamTransport):
    SCHEME = SCHEME

    def __init__(self, url: BoardUrl, key: bytes | None = None) -> None:
        super().__init__(url, key)
        url.check_params(("baud", PER_FRAME))
        self.device = url.need_path("device", "serial:///dev/ttyACM0?baud=115200")
        self.baud = url.int_param("baud", DEFAULT_BAUD, 300, 4_000_000)
        self._port: pyserial.Serial | None = None

    async def _connect(self) -> None:
        try:
            self._port = pyserial.Serial(self.device, self.baud, timeout=0, write_timeout=2)
        except pyserial.SerialException as exc:
            raise OSError(str(exc)) from exc

    async def _read(self) -> bytes:
        port = self._port
        if port is None:
            raise ConnectionResetError("not connected")
        loop = asyncio.get_running_loop()
        while True:
            try:
                data = port.read(max(1, min(READ_SIZE, port.in_waiting)))
            except pyserial.SerialException as exc:
                raise OSError(str(exc)) from exc
            except TypeError:  # pyserial when the port was closed under it
                return b""
            if data:
                return bytes(data)
            ready: asyncio.Future[None] = loop.create_future()
            fd = port.fileno()

            def wake(fut: asyncio.Future[None] = ready) -> None:
                if not fut.done():
                    fut.set_result(None)

            loop.add_reader(fd, wake)
            try:
                await ready
            finally:
                loop.remove_reader(fd)

    async def _write(self, data: bytes) -> None:
        if self._port is None:
            raise ConnectionResetError("not connected")
        try:
            self._port.write(data)
        except pyserial.SerialException as exc:
            raise OSError(str(exc)) from exc

    async def _disconnect(self) -> None:
        port, self._port = self._port, None
        if port is not None:
            port.close()


TRANSPORT = SerialTransport
