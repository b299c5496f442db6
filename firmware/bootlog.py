"""The boot record: how many watchdog resets came in a row, to detect a reset loop.

On every boot ``on_boot`` reads ``boot.json``; a watchdog reset adds one to the count, any other
cause sets it to 0; the count is written back. When the firmware has run ``STABLE_MS`` (60 s)
the board calls ``mark_stable``, which writes 0 again. So ``SAFE_AFTER`` (3) watchdog resets
with no minute of stable running in between — a reset loop — make the board boot in safe mode
(only protected channels on). A board has no clock that survives a reset, so "within 60 s" is
measured as uptime between resets. The file is written at most twice per boot.
"""

import json

from protocol.compat import const
from protocol.constants import RESET_WATCHDOG

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from firmware.hal import Storage

FILE = "boot.json"
STABLE_MS = const(60000)
SAFE_AFTER = const(3)


def on_boot(storage: "Storage", cause: int) -> int:
    """Record this boot; returns the number of watchdog resets in a row (0 if none)."""
    n = 0
    if cause == RESET_WATCHDOG:
        try:
            data = storage.read(FILE)
            rec = json.loads(data) if data else {}
            n = rec.get("wdt", 0) if isinstance(rec, dict) else 0
            if not isinstance(n, int):
                n = 0
        except (OSError, ValueError):
            n = 0
        n += 1
    _write(storage, n)
    return n


def mark_stable(storage: "Storage") -> None:
    _write(storage, 0)


def _write(storage: "Storage", n: int) -> None:
    try:  # noqa: SIM105 (MicroPython has no contextlib)
        storage.write(FILE, json.dumps({"wdt": n}).encode())
    except OSError:
        pass  # a board that cannot write still boots; it just cannot count resets
