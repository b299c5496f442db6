"""Transports chosen by URL, loaded lazily (STYLE.md 6, after pyserial's ``serial_for_url``).

``open_transport(url, key)`` parses the URL, imports the module registered for its scheme in
``SCHEMES`` only then (so pymodbus or python-can load only for the URLs that need them) and
returns the module's ``TRANSPORT`` class built for that URL, not yet opened. Each module
documents its URL grammar in its header. What each can do (``Transport.CAPS``):

=============  ====  ======  ====  ===========  ======  ====  =====  =======
scheme         push  events  auth  power_cycle  config  save  names  boot_id
=============  ====  ======  ====  ===========  ======  ====  =====  =======
tcp, serial,   yes   yes     yes   yes          yes     yes   yes    yes
memory
modbus+tcp,    poll  no      none  off/wait/on  yes     yes   no     yes*
modbus+rtu
can            yes   no      yes   yes          no      no    no     yes
tug            yes   no      none  off/wait/on  no      no    no     no
=============  ====  ======  ====  ===========  ======  ====  =====  =======

"poll": the transport reads the registers at the subscribed rate and hands the results up as
measurements; "none": the wire has no authentication, so the key is not used and anyone on the
link can switch (the Modbus board only accepts writes from configured client addresses);
"off/wait/on": the host times the power cycle; "boot_id": the HELLO carries the board's own
boot id, random at every boot (without it a reboot is told by an uptime that fell behind);
"yes*": when the device has the boot id registers (a dxboard board does; a map file may name
them, ``boot_id``).
The board client turns a missing capability into ``NotSupported`` with what to use instead.
"""

from __future__ import annotations

import importlib
import logging

from host.transports.base import Transport
from host.transports.errors import BadUrl
from host.transports.url import BoardUrl, parse

log = logging.getLogger(__name__)

# scheme -> module defining TRANSPORT
SCHEMES: dict[str, str] = {
    "tcp": "host.transports.tcp",
    "serial": "host.transports.serial",
    "modbus+tcp": "host.transports.modbus",
    "modbus+rtu": "host.transports.modbus",
    "can": "host.transports.can",
    "tug": "host.transports.tug",
    "memory": "host.transports.memory",
}


def transport_class(scheme: str) -> type[Transport]:
    module = SCHEMES.get(scheme)
    if module is None:
        raise BadUrl(f"unknown board URL scheme {scheme!r}",
                     "use one of " + ", ".join(f"{s}://" for s in SCHEMES))
    loaded = importlib.import_module(module)
    cls: type[Transport] = getattr(loaded, "TRANSPORTS", {}).get(scheme, loaded.TRANSPORT)
    return cls


def open_transport(url: str | BoardUrl, key: bytes | None = None) -> Transport:
    """The transport for ``url`` (not opened yet); ``BadUrl`` if the URL is wrong."""
    parsed = parse(url) if isinstance(url, str) else url
    return transport_class(parsed.scheme)(parsed, key)


__all__ = ["SCHEMES", "BoardUrl", "Transport", "open_transport", "parse", "transport_class"]
