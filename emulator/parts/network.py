"""The ``network`` module of MicroPython's network ports (rp2 Pico W, ESP32), over a ``World``.

Put ``emulator/parts`` on ``MICROPYPATH`` and ``boot.py``'s ``import network`` gets this:
``LAN()`` is a wired interface whose cable is ``world.lan_cable`` (True: plugged into a network
that hands out ``world.lan_ip``); ``WLAN(STA_IF)`` joins the access points in
``world.wifi`` (ssid -> (password, ip)) after ``WIFI_JOIN_US`` of simulated time, or fails
(``STAT_WRONG_PASSWORD``, ``STAT_NO_AP_FOUND``). ``active``, ``isconnected``, ``ifconfig``,
``status`` and ``connect`` behave as on the board. The unix port has no ``network``: with this
module absent, the board's sockets are the host's.
"""

from emulator.parts import world as _world

STA_IF = 0
AP_IF = 1
STAT_IDLE = 0
STAT_CONNECTING = 1
STAT_WRONG_PASSWORD = -3
STAT_NO_AP_FOUND = -2
STAT_GOT_IP = 3
WIFI_JOIN_US = 2000000  # a Pico W joins a WPA2 access point in about 2 s

_NO_IP = ("0.0.0.0", "0.0.0.0", "0.0.0.0", "0.0.0.0")


def _ip(ip: str) -> "tuple[str, str, str, str]":
    return (ip, "255.255.255.0", ip.rsplit(".", 1)[0] + ".1", ip.rsplit(".", 1)[0] + ".1")


class LAN:
    def __init__(self, *args: object, **kw: object) -> None:
        self.w = _world.current()
        self.on = False

    def active(self, on: "bool | None" = None) -> bool:
        if on is not None:
            self.on = bool(on)
        return self.on

    def isconnected(self) -> bool:
        return self.on and bool(getattr(self.w, "lan_cable", False))

    def ifconfig(self) -> "tuple[str, str, str, str]":
        return _ip(getattr(self.w, "lan_ip", "")) if self.isconnected() else _NO_IP


class WLAN:
    def __init__(self, interface: int = STA_IF) -> None:
        self.w = _world.current()
        self.on = False
        self.state = STAT_IDLE
        self.since = 0
        self.ip = ""

    def active(self, on: "bool | None" = None) -> bool:
        if on is not None:
            self.on = bool(on)
        return self.on

    def connect(self, ssid: str, key: str = "") -> None:
        if not self.on:
            raise OSError("WLAN not active")
        aps = getattr(self.w, "wifi", {})
        if ssid not in aps:
            self.state = STAT_NO_AP_FOUND
            return
        password, ip = aps[ssid]
        if password != key:
            self.state = STAT_WRONG_PASSWORD
            return
        self.state = STAT_CONNECTING
        self.since = self.w.now_us
        self.ip = ip

    def status(self) -> int:
        if self.state == STAT_CONNECTING and self.w.now_us - self.since >= WIFI_JOIN_US:
            self.state = STAT_GOT_IP
        return self.state

    def isconnected(self) -> bool:
        return self.on and self.status() == STAT_GOT_IP

    def ifconfig(self) -> "tuple[str, str, str, str]":
        return _ip(self.ip) if self.isconnected() else _NO_IP
