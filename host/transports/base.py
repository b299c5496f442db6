"""The one small base class in front of every transport (STYLE.md 5, after python-can's BusABC).

A transport carries the dxboard protocol's *messages* (``protocol.messages``) between the host
and one board, whatever the wire: the native transports (tcp, serial, memory) put the codec's
frames on a byte stream; the translating ones (modbus, can, tug) turn each message into their
own wire format and turn what comes back into the same messages (a ``Hello`` on open, ``State``,
``Switched``, ``Measurement``, ``Error``...), so the board client above knows one language.

Public methods own timeouts, logging and the translation of ``OSError`` into ``BoardUnreachable``;
backends implement the private half: ``_open() -> Hello``, ``_send(msg)``, ``_receive()`` and
``_close()``, and ``_pump`` where messages can be handed up as they are decoded. ``open``
returns the board's HELLO; ``send`` takes a host message whose ``req_id`` the caller set
(replies carry it back); ``receive`` returns the next board message (a reply or a push) or a
``BadFrame``, and raises ``LinkLost`` when the link ends; ``pump(deliver)`` hands every message
to ``deliver`` instead, in batches, until the link ends. ``close`` is idempotent. Transports
are async context managers.

``CAPS`` says what a transport can do natively (the table in ``host/transports/__init__.py``).
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from types import TracebackType
from typing import ClassVar

from host.transports.errors import BoardUnreachable, LinkLost, TransportError
from host.transports.url import BoardUrl
from protocol.framing import BadFrame
from protocol.messages import Hello, Message

log = logging.getLogger(__name__)

# capability names (CAPS)
PUSH = "push"  # the board pushes measurements (else the transport polls and says so)
EVENTS = "events"  # the board pushes events (trips, state changes, reboots)
AUTH = "auth"  # actuation is authenticated with the key
CYCLE = "power_cycle"  # the board times a power cycle itself (else off, wait, on)
CONFIG = "config"  # channel and board configuration can be read and written
SAVE = "save"  # the configuration can be persisted on the board
NAMES = "names"  # channel names can be read from the board
BOOT_ID = "boot_id"  # the HELLO's boot id is the board's own (a new one at every boot)

# Request ids (PROTOCOL.md §3: 1-65535; 0 is a push): the board client numbers its requests
# 1..CLIENT_MAX_REQ_ID, a transport's own requests use ids above it, so that a late answer to
# one of them can never be taken for the answer to one of the client's.
CLIENT_MAX_REQ_ID = 0xFFFD
HELLO_REQ_ID = 0xFFFE  # HELLO_REQUEST when the board's greeting does not come at once
CLAIM_REQ_ID = 0xFFFF  # AUTH_PING, the key proved at open


class Transport:
    """Base of every transport; see the module docstring."""

    SCHEME: ClassVar[str] = ""
    CAPS: ClassVar[frozenset[str]] = frozenset()
    # the most measurements a second the board sends, whatever rate was subscribed (None: the
    # subscribed rate); the link's silence rule counts periods of the rate actually sent
    MAX_PUSH_HZ: ClassVar[float | None] = None

    def __init__(self, url: BoardUrl, key: bytes | None = None) -> None:
        self.url = url
        self.key = key
        # readings a frame the URL asks of a board that can batch them (``?per_frame=K`` on the
        # native transports); 0: not asked, the board client chooses
        self.per_frame = 0
        # what the board said of the key at open: "accepted", "refused: <why>", or "" (not
        # known: no key, or a wire that cannot ask before a command)
        self.key_check = ""
        self._opened = False
        self._closed = False

    # --- public half ------------------------------------------------------------------

    @property
    def caps(self) -> frozenset[str]:
        """What this transport can do with the device it is for: ``CAPS``, unless the device
        adds to them (a Modbus board with boot id registers)."""
        return self.CAPS

    @property
    def is_open(self) -> bool:
        return self._opened and not self._closed

    async def open(self, timeout: float = 5.0) -> Hello:
        """Connect and return the board's HELLO; ``BoardUnreachable`` if that fails."""
        log.debug("opening %s", self.url.text)
        self._closed = False
        try:
            hello = await asyncio.wait_for(self._open(), timeout)
        except TimeoutError:
            await self._safe_close()
            raise BoardUnreachable(
                f"{self.url.text}: no HELLO from the board within {timeout:g} s",
                "is the board powered and is this its URL? (--verbose shows the exchange)",
            ) from None
        except OSError as exc:
            await self._safe_close()
            raise BoardUnreachable(f"cannot reach {self.url.text}: {exc.strerror or exc}",
                                   "check that the board is on and the URL is right") from exc
        except TransportError:
            await self._safe_close()
            raise
        self._opened = True
        log.debug("open %s: board %s boot %08x", self.url.text, hello.board_id, hello.boot_id)
        return hello

    async def send(self, msg: Message) -> None:
        """Send one host message (signed by the transport when it needs it)."""
        if not self.is_open:
            raise LinkLost(f"{self.url.text}: link is not open", "reconnect")
        log.debug("%s <- %r", self.url.text, msg)
        try:
            await self._send(msg)
        except OSError as exc:
            raise LinkLost(f"{self.url.text}: link lost while sending: {exc}",
                           "the board may have rebooted; reconnect") from exc

    async def receive(self) -> Message | BadFrame:
        """The next message from the board; ``LinkLost`` when the link ends."""
        if not self.is_open:
            raise LinkLost(f"{self.url.text}: link is not open", "reconnect")
        try:
            msg = await self._receive()
        except OSError as exc:
            raise LinkLost(f"{self.url.text}: link lost: {exc}",
                           "the board may have rebooted; reconnect") from exc
        if log.isEnabledFor(logging.DEBUG):
            log.debug("%s -> %r", self.url.text, msg)
        return msg

    async def pump(self, deliver: Callable[[list[Message | BadFrame]], None]) -> None:
        """Hand everything from the board to ``deliver`` (a batch: what arrived together, in
        order) until the link ends: ``LinkLost``, as ``receive`` would raise. A transport that
        decodes as bytes arrive calls ``deliver`` from its data callback: no task wakes per
        message (``_pump``); the default receives one message at a time."""
        if not self.is_open:
            raise LinkLost(f"{self.url.text}: link is not open", "reconnect")
        try:
            await self._pump(deliver)
        except OSError as exc:
            raise LinkLost(f"{self.url.text}: link lost: {exc}",
                           "the board may have rebooted; reconnect") from exc

    async def close(self) -> None:
        """Close the link; safe to call more than once."""
        if self._closed:
            return
        self._closed = True
        await self._safe_close()
        log.debug("closed %s", self.url.text)

    async def _safe_close(self) -> None:
        try:
            await self._close()
        except OSError as exc:
            log.debug("closing %s: %s", self.url.text, exc)

    async def __aenter__(self) -> Transport:
        await self.open()
        return self

    async def __aexit__(self, exc_type: type[BaseException] | None,
                        exc: BaseException | None, tb: TracebackType | None) -> None:
        await self.close()

    # --- backend half -----------------------------------------------------------------

    async def _open(self) -> Hello:
        raise NotImplementedError

    async def _send(self, msg: Message) -> None:
        raise NotImplementedError

    async def _receive(self) -> Message | BadFrame:
        raise NotImplementedError

    async def _close(self) -> None:
        raise NotImplementedError

    async def _pump(self, deliver: Callable[[list[Message | BadFrame]], None]) -> None:
        while True:
            deliver([await self.receive()])
