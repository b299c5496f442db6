"""One JSON-lines request/reply helper for every line server of ours and their clients.

The wire: one JSON object per line (UTF-8, ``\\n``-terminated, at most ``max_line`` bytes) each
way. ``Lines`` is the server side: ``Lines(handlers, error=...)`` dispatches each request on its
kind (``msg["op"]``) to a handler ``(msg, conn) -> reply`` (a dict, None for no reply, or an
awaitable of either; ``conn`` is the connection's ``StreamWriter``), answers a line that is not
a JSON object, an unknown kind (naming the kinds there are), a refusal (``ValueError``, with its
words) or a failed handler (logged; the server stays up) with an error object built by
``error(words)``, caps the line length (a longer line is answered and ends the connection), and
takes a client that goes away quietly. ``answer(line, conn)`` is the reply to one line;
``serve`` is an ``asyncio.start_server`` callback running the connection. The client side:
``ask`` (one request, one reply, blocking, over TCP or a Unix socket, within a deadline) and
``connect`` (an asyncio connection within a deadline, ``messages`` reading its objects);
``connect_retrying`` is the one reconnect policy (the robot's drivers to their devices).

Where it lives: ``emulator/`` is the lowest package both the emulator's servers (control port,
devices, world) and the host's (operator socket, skills client, control client) may import:
``protocol/`` is the MicroPython codec (no sockets, no asyncio), ``emulator/`` may not import
``host/``, and ``scripts/layers.py`` puts ``emulator`` on a floor below every host package
(ARCHITECTURE.md forbids host only ``firmware/``; ``host.commands`` already imports the
emulator to launch it). So one copy here serves all, instead of a copy on each side.
"""

from __future__ import annotations

import asyncio
import contextlib
import inspect
import json
import logging
import socket
from collections.abc import AsyncIterator, Awaitable, Callable, Mapping
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

log = logging.getLogger(__name__)

MAX_LINE = 65536
NOT_JSON = "not a JSON object on one line"
TOO_LONG = "line too long"

Msg = dict[str, Any]
Reply = Msg | None
Handler = Callable[[Msg, Any], Reply | Awaitable[Reply]]


def ok_error(words: str) -> Msg:
    """The error object of the request/reply endpoints (control, operator)."""
    return {"ok": False, "error": words}


def encode(msg: Msg) -> bytes:
    """One message as one line."""
    return json.dumps(msg, separators=(",", ":")).encode() + b"\n"


def decode(line: bytes) -> Msg | None:
    """The JSON object on ``line``, None if it is not one."""
    try:
        msg = json.loads(line)
    except (ValueError, UnicodeDecodeError):
        return None
    return msg if isinstance(msg, dict) else None


class Lines:
    """A JSON-lines server's request handling: a handler per kind, errors as ``error`` builds.

    ``handlers`` maps each kind to its handler (their order is the order the unknown-kind error
    names them in); ``fallback`` takes every request instead when there are no kinds (a device
    takes any command object). ``listening()`` false: lines are read and dropped unanswered (a
    device that is booting or hung). ``on_close(conn)`` runs when a connection ends."""

    def __init__(self, handlers: Mapping[str, Handler] | None = None, *,
                 error: Callable[[str], Msg] = ok_error, key: str = "op",
                 fallback: Handler | None = None, max_line: int = MAX_LINE,
                 listening: Callable[[], bool] | None = None,
                 on_close: Callable[[Any], None] | None = None) -> None:
        self.handlers = dict(handlers or {})
        self.error = error
        self.key = key
        self.fallback = fallback
        self.max_line = max_line
        self.listening = listening
        self.on_close = on_close

    def answer(self, line: bytes, conn: Any = None) -> Reply | Awaitable[Reply]:
        """The reply to one request line (awaitable if its handler is a coroutine)."""
        msg = decode(line)
        if msg is None:
            return self.error(NOT_JSON)
        handler = self.fallback
        if handler is None:
            kind = msg.get(self.key)
            handler = self.handlers.get(kind) if isinstance(kind, str) else None
            if handler is None:
                return self.error(f"unknown {self.key} {kind!r} ({', '.join(self.handlers)})")
        try:
            return handler(msg, conn)
        except ValueError as exc:  # a refusal, in the handler's words
            return self.error(str(exc))

    async def reply(self, line: bytes, conn: Any = None) -> Reply:
        """``answer``, awaited; a handler that fails is logged and answered, never raised."""
        try:
            got = self.answer(line, conn)
            return await got if inspect.isawaitable(got) else got
        except ValueError as exc:
            return self.error(str(exc))
        except Exception as exc:  # the server stays up; the client hears why
            log.exception("request failed")
            return self.error(f"failed: {exc}")

    async def serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        """Run one connection: a line in, its reply out, until the client goes away."""
        try:
            while True:
                try:
                    line = await reader.readuntil(b"\n")
                except (asyncio.LimitOverrunError, ValueError):
                    send(writer, self.error(TOO_LONG))
                    break
                except asyncio.IncompleteReadError:
                    break
                if self.listening is not None and not self.listening():
                    continue
                reply = await self.reply(line, writer)
                if reply is not None and not writer.is_closing():
                    send(writer, reply)
                    await writer.drain()
        except ConnectionError:
            pass
        finally:
            if self.on_close is not None:
                self.on_close(writer)
            if writer.transport.get_write_buffer_size() > self.max_line:
                writer.transport.abort()  # a client that does not read gets no more
            else:
                writer.close()


def send(writer: asyncio.StreamWriter, msg: Msg) -> None:
    """Queue one message on a connection, unless it is closing."""
    if not writer.is_closing():
        writer.write(encode(msg))


def ask(address: tuple[str, int] | Path, request: Msg, timeout: float) -> Msg | None:
    """Send one request and return its reply (None if the reply is not a JSON object), all
    within ``timeout`` seconds for each step; ``address`` is (host, port) or a Unix socket's
    path. Raises ``OSError`` (``FileNotFoundError``, ``PermissionError``, a timeout...) when
    the endpoint cannot be reached or goes away."""
    if isinstance(address, Path):
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            sock.settimeout(timeout)
            sock.connect(str(address))
        except BaseException:
            sock.close()
            raise
    else:
        sock = socket.create_connection(address, timeout=timeout)
    with sock:
        sock.sendall(encode(request))
        buf = b""
        while not buf.endswith(b"\n") and len(buf) <= MAX_LINE:
            chunk = sock.recv(MAX_LINE)
            if not chunk:
                break
            buf += chunk
    return decode(buf)


def tcp_address(url: str) -> tuple[str, int] | None:
    """(host, port) of a ``tcp://HOST:PORT`` URL, None if it is not one."""
    parts = urlsplit(url)
    try:
        port = parts.port
    except ValueError:
        return None
    if parts.scheme != "tcp" or not parts.hostname or port is None:
        return None
    return parts.hostname, port


async def connect(host: str, port: int, timeout: float, max_line: int = MAX_LINE,
                  ) -> tuple[asyncio.StreamReader, asyncio.StreamWriter]:
    """An asyncio connection within ``timeout`` seconds (``OSError`` or ``TimeoutError``)."""
    return await asyncio.wait_for(asyncio.open_connection(host, port, limit=max_line), timeout)


async def connect_retrying(address: tuple[str, int], every: float, *,
                           deadline: float | None = None, stop: asyncio.Event | None = None,
                           refused: Callable[[OSError], None] | None = None,
                           max_line: int = MAX_LINE,
                           ) -> tuple[asyncio.StreamReader, asyncio.StreamWriter] | None:
    """The reconnect policy, in one place: connect to ``address``, trying again every
    ``every`` seconds while it refuses (a device may be off or booting), until connected (the
    pair), ``stop`` is set (None), or the event loop's clock passes ``deadline`` (the last
    refusal is raised). ``refused(exc)`` hears each refusal."""
    loop = asyncio.get_running_loop()
    while stop is None or not stop.is_set():
        try:
            return await asyncio.open_connection(*address, limit=max_line)
        except OSError as exc:
            if refused is not None:
                refused(exc)
            if deadline is not None and loop.time() >= deadline:
                raise
        if stop is None:
            await asyncio.sleep(every)
        else:
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(stop.wait(), every)
    return None


async def messages(reader: asyncio.StreamReader) -> AsyncIterator[Msg]:
    """The JSON objects a connection sends, until it ends (``IncompleteReadError``,
    ``ConnectionError``, ``LimitOverrunError`` raised); lines that are not one are logged and
    skipped."""
    while True:
        line = await reader.readuntil(b"\n")
        msg = decode(line)
        if msg is None:
            log.warning("not a JSON object: %r", line[:80])
            continue
        yield msg
