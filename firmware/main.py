"""The board's entry point: build the real HAL for this board revision and run the firmware.

This is the only module that touches ``machine`` (through ``firmware.hal.target``). The board
revision is data (``firmware.boards``: rev A is ten high-side switches with status outputs, ten
INA226 monitors on I2C(0), the input voltage on an ADC pin through a 1:11 divider; rev B the
same switches measured by four INA3221; rev C five dual smart switches read through the ADC);
the one this board was flashed as is read at boot and its HAL built from it. Everything runs
on asyncio (``firmware.net``): the protection loop (one step per tick, then the pushes), the native
protocol on TCP port 7000 and on UART(1), Modbus TCP on port 502, each registered with the
supervisor; the original TEDUSAR format (``firmware/tug.py``) only when the flashed
configuration's ``tug_port`` is set (it has no authentication; 0, off, by default; the original
board's port is 5000), switching only when its ``tug_switch`` is true as well. The network
interface is brought up by ``boot.py`` before this runs; the servers listen on its address
only (or on the configuration's ``listen``), never on every interface unless the
configuration says ``listen: "0.0.0.0"``.
"""

import asyncio

import machine  # type: ignore[import-not-found]  # MicroPython only: no stubs

from firmware import boards, build, modbus, tug
from firmware.app import App
from firmware.factory import FACTORY
from firmware.hal import target
from firmware.hal.storage import FileStorage
from firmware.net import Net
from firmware.session import FIRMWARE_VERSION
from protocol.constants import (
    CAP_AUTH,
    CAP_BATCH,
    CAP_CONFIG,
    CAP_EVENTS,
    CAP_MODBUS,
    CAP_SUBSCRIBE,
    CAP_VOLTAGE,
)

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from typing import Protocol

    from firmware.boot import Nic
    from firmware.net import ByteReader, ByteWriter

    class Stream(ByteReader, ByteWriter, Protocol):
        """MicroPython's ``asyncio.StreamReader`` over a UART: its one ``Stream`` class, which
        reads and writes."""

TCP_PORT = 7000
MODBUS_PORT = 502
UART_ID = 1
UART_BAUD = 115200
CAPS = (CAP_AUTH | CAP_SUBSCRIBE | CAP_EVENTS | CAP_CONFIG | CAP_MODBUS | CAP_VOLTAGE
        | CAP_BATCH)


def listen_address(app: App) -> str:
    """Where the servers listen: the configuration's ``listen`` if set (``dxboard flash``;
    "0.0.0.0" means every interface, on purpose), else the address of the network interface
    ``boot.py`` brought up (wired first, then Wi-Fi station), else loopback only."""
    chosen: str = app.board.cfg["board"].get("listen", "")
    if chosen:
        return chosen
    try:
        import network  # type: ignore[import-not-found]  # MicroPython's: no stubs
    except ImportError:
        return "127.0.0.1"
    for kind in ("LAN", "WLAN"):
        if not hasattr(network, kind):
            continue
        try:
            nic: "Nic" = network.LAN() if kind == "LAN" else network.WLAN(network.STA_IF)
            if nic.active() and nic.isconnected():
                return nic.ifconfig()[0]
        except (OSError, ValueError):
            continue
    return "127.0.0.1"


async def run(app: App, uart: object) -> None:
    net = Net(app, FIRMWARE_VERSION, CAPS)
    host = listen_address(app)
    await net.serve_tcp(host, TCP_PORT)
    await modbus.serve(net, host, MODBUS_PORT)
    b = app.board.cfg["board"]
    if b.get("tug_port", 0):  # flashed only: the original format has no authentication
        await tug.serve(net, host, b["tug_port"], b.get("tug_switch", False))
    tasks = [asyncio.create_task(net.housekeeping())]
    # MicroPython's StreamReader(uart) is its one Stream, both halves; CPython's takes a limit
    stream: "Stream" = asyncio.StreamReader(uart)  # type: ignore[arg-type, assignment]
    tasks.append(asyncio.create_task(net.serve_serial(stream, stream)))
    build.running = True  # dxboard flash checks this after a reset
    await net.protect()


def main() -> None:
    board = boards.load()
    hal = target.build(board, FileStorage(""))
    print("dxboard", FIRMWARE_VERSION, board["name"], board["mcu"])
    for line in hal.report():  # each sensor: ok, no answer, wrong chip, bus held low
        print(line)
    app = App(hal, FACTORY)  # the flashed configuration, if no stored copy is good
    app.start()
    uart = machine.UART(UART_ID, UART_BAUD)
    asyncio.run(run(app, uart))


main()
