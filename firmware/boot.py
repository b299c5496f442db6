"""Bring the network up before ``main.py`` runs: wired first, then Wi-Fi from the flashed file.

MicroPython runs ``boot.py`` at the root of the flash, then ``main.py``; ``dxboard flash``
writes a ``boot.py`` that calls ``run()`` here. ``up(network, wifi, sleep_ms, ticks_ms)`` (the
port's ``network`` module and clock passed in) tries, in order:

1. a wired interface (``network.LAN``, where the port has one): activated, used if its link is up
   within ``LAN_WAIT_MS``;
2. a Wi-Fi station (``network.WLAN(network.STA_IF)``) joining the access point of the flashed
   file ``wifi.json`` (``{"ssid": ..., "password": ...}``) within ``WIFI_WAIT_MS``;
3. nothing: ``main.py`` then listens on loopback only (``listen_address``).

It returns the line the board prints: ``network: lan 192.168.1.50``, ``network: wlan 10.0.0.7
(ssid robot)``, or ``network: none (why)``. The unix port has no ``network`` module: the host's
sockets stand in for the interface, and ``run()`` says so.
"""

import json

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from collections.abc import Callable
    from typing import Any, Protocol

    class Nic(Protocol):
        """A network interface of the port (``network.LAN()``, ``network.WLAN(STA_IF)``)."""

        def active(self, on: "bool | None" = None) -> bool: ...

        def isconnected(self) -> bool: ...

        def ifconfig(self) -> "tuple[str, str, str, str]": ...

        def connect(self, ssid: str, key: str) -> None: ...

        def status(self) -> int: ...

    class Network(Protocol):
        """The port's ``network`` module, as far as ``boot.py`` and ``main.py`` use it (``LAN``
        only where the port has one: looked up with ``hasattr``)."""

        STA_IF: int

        def LAN(self) -> Nic: ...

        def WLAN(self, interface: int) -> Nic: ...

WIFI_FILE = "wifi.json"
LAN_WAIT_MS = 3000
WIFI_WAIT_MS = 15000
POLL_MS = 100


def read_wifi(path: str = WIFI_FILE) -> "dict[str, Any] | None":
    """The flashed Wi-Fi credentials, or None (no file, or not ``{"ssid": ...}``)."""
    try:
        with open(path) as f:
            got = json.loads(f.read())
    except (OSError, ValueError):
        return None
    if not isinstance(got, dict) or not isinstance(got.get("ssid"), str):
        return None
    return got


def _wait(nic: "Nic", ms: int, sleep_ms: "Callable[[int], None]",
          ticks_ms: "Callable[[], int]") -> bool:
    start = ticks_ms()
    while not nic.isconnected():
        if ticks_ms() - start >= ms:
            return False
        sleep_ms(POLL_MS)
    return True


def up(network: "Network | None", wifi: "dict[str, Any] | None",
       sleep_ms: "Callable[[int], None]", ticks_ms: "Callable[[], int]") -> str:
    if network is None:
        return "network: none (no network module: the host's sockets stand in)"
    if hasattr(network, "LAN"):
        try:
            lan = network.LAN()
            lan.active(True)
            if _wait(lan, LAN_WAIT_MS, sleep_ms, ticks_ms):
                return "network: lan " + str(lan.ifconfig()[0])
            lan.active(False)
        except (OSError, ValueError):
            pass
    if not hasattr(network, "WLAN"):
        return "network: none (no link on the wired interface, no Wi-Fi)"
    if wifi is None:
        return "network: none (no link on the wired interface, no " + WIFI_FILE + " flashed)"
    sta = network.WLAN(network.STA_IF)
    sta.active(True)
    sta.connect(wifi["ssid"], wifi.get("password", ""))
    if _wait(sta, WIFI_WAIT_MS, sleep_ms, ticks_ms):
        return "network: wlan " + str(sta.ifconfig()[0]) + " (ssid " + str(wifi["ssid"]) + ")"
    status = sta.status()
    sta.active(False)
    return "network: none (Wi-Fi " + str(wifi["ssid"]) + " not joined, status " + str(status) + ")"


def run() -> str:
    """On the board: the port's ``network`` and clock; prints and returns the line."""
    import time

    try:
        import network  # type: ignore[import-not-found]  # MicroPython's: no stubs
    except ImportError:
        network = None
    # sleep_ms and ticks_ms: MicroPython's time, which CPython's stubs lack
    line = up(network, read_wifi(), time.sleep_ms, time.ticks_ms)  # type: ignore[attr-defined]
    print(line)
    return line
