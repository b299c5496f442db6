"""The requests in flight on one board link, each matched to its reply by ``req_id``.

``Requests`` numbers every request the board link (``host.board.link``) sends (1 up to
``CLIENT_MAX_REQ_ID``: the transports' own ids lie above), keeps a future for it until the reply
with that ``req_id`` arrives (``deliver``, from the link's reader) or ``timeout_s`` passes
(``RequestTimeout``), and turns an ERROR reply into ``BoardRefused`` (``AuthRefused`` for a bad
or missing key: nothing changed on the board). A lost link fails everything pending at once
(``fail_all``): a request of an old session never gets its answer.
"""

from __future__ import annotations

import asyncio

from host.transports.base import CLIENT_MAX_REQ_ID, Transport
from host.transports.errors import AuthRefused, BoardRefused, RequestTimeout
from protocol.constants import E_AUTH_REQUIRED, E_BAD_TAG, E_NO_SESSION, E_REPLAYED, ERROR_TEXT
from protocol.messages import Error, Message

AUTH_CODES = (E_AUTH_REQUIRED, E_BAD_TAG, E_REPLAYED, E_NO_SESSION)


class Requests:
    """See the module docstring."""

    def __init__(self, url: str, timeout_s: float) -> None:
        self.url = url
        self.timeout_s = timeout_s
        self._pending: dict[int, asyncio.Future[Message]] = {}
        self._req = 0

    def _next_req(self) -> int:
        self._req = self._req % CLIENT_MAX_REQ_ID + 1
        return self._req

    def deliver(self, msg: Message) -> bool:
        """Complete the request ``msg`` answers; False when it answers none (not a reply)."""
        fut = self._pending.pop(msg.req_id, None) if msg.req_id else None
        if fut is None:
            return False
        if not fut.done():
            fut.set_result(msg)
        return True

    def fail_all(self, exc: Exception) -> None:
        """Every pending request fails with ``exc``."""
        pending, self._pending = self._pending, {}
        for fut in pending.values():
            if not fut.done():
                fut.set_exception(exc)

    async def send(self, transport: Transport, msg: Message) -> Message:
        """Send ``msg`` on ``transport`` and wait for its reply."""
        msg.req_id = self._next_req()
        fut: asyncio.Future[Message] = asyncio.get_running_loop().create_future()
        self._pending[msg.req_id] = fut
        name = type(msg).__name__
        try:
            await transport.send(msg)
            reply = await asyncio.wait_for(fut, self.timeout_s)
        except TimeoutError:
            raise RequestTimeout(
                f"{self.url}: the board did not answer {name} within {self.timeout_s:g} s",
                "the board stopped answering; check its power and the link") from None
        finally:
            self._pending.pop(msg.req_id, None)
        if isinstance(reply, Error):
            text = reply.text or ERROR_TEXT.get(reply.code, "error")
            if reply.code in AUTH_CODES:
                raise AuthRefused(f"{self.url}: the board refused {name}: {text}",
                                  "check the key (DXBOARD_KEY or --key-file); nothing changed",
                                  reply.code)
            raise BoardRefused(f"{self.url}: the board refused {name}: {text}",
                               "nothing was changed", reply.code)
        return reply
