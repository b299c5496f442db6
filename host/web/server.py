"""The web server: the status page, a JSON API, Prometheus metrics and a live WebSocket.

``WebServer(source, journal)`` serves, read-only (no route changes anything, whatever the
client sends):

- ``GET /`` — the page (``static/index.html``: one file, plain JavaScript and CSS, no CDN);
- ``GET /api/status`` — the latest ``Status`` as JSON, plus ``server_time`` and ``stale``;
- ``GET /api/journal?since=ID&limit=N&kind=K[,K]`` — entries after ``since`` (or, without it,
  the last ``limit``), each with a one-line ``summary``; 404 when there is no journal;
- ``GET /metrics`` — Prometheus text format (``metrics``: the daemon's ``host.fleet.metrics``);
- ``GET /ws`` — a WebSocket that sends ``{"type": "status", ...}`` on every change (at most
  one every ``push_interval_s``, and at least one every ``heartbeat_s`` so the page can tell a
  quiet daemon from a lost link) and ``{"type": "journal", "entries": [...]}`` with new entries.

One broadcaster task waits on ``StatusSource.wait_changed`` and fans each snapshot out to all
clients, so a hundred open pages cost one JSON encoding per change. Journal reads run in a
worker thread (``asyncio.to_thread``) so a slow disk never stalls the daemon's loop. It binds to
127.0.0.1 unless given another host (``--web 0.0.0.0:8080`` exposes it to the network).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import time
from collections.abc import Callable, Iterable
from importlib import resources
from typing import Any, Protocol

from aiohttp import WSMsgType, web

from host.errors import UserError
from host.events import Kind
from host.journal.entries import Entry
from host.journal.summary import summarize
from host.web.guard import AccessPolicy, middlewares
from host.web.headline import BEHIND_AFTER_S, diagnosis_age, headline
from host.web.status import Status, StatusSource

log = logging.getLogger(__name__)

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8080
MAX_LIMIT = 1000
MAX_ID = 2**63 - 1  # SQLite's largest integer: a larger ``since`` is a bad query, not a 500
QUERIES = {  # the query parameters each route takes (guard.middlewares refuses the others)
    "/api/status": frozenset(), "/api/journal": frozenset({"since", "limit", "kind"}),
    "/metrics": frozenset(), "/ws": frozenset(),
}


class JournalView(Protocol):
    """The read side of the journal the server needs (``JournalReader`` is one)."""

    def tail(self, n: int, kind: Kind | str | Iterable[Kind | str] | None = None) -> list[Entry]:
        ...

    def since(self, after_id: int, limit: int | None = 1000,
              kind: Kind | str | Iterable[Kind | str] | None = None) -> list[Entry]:
        ...

    def counts(self) -> dict[str, int]:
        ...

    def size_bytes(self) -> int:
        ...


def parse_listen(text: str) -> tuple[str, int]:
    """``HOST:PORT``, ``:PORT`` or ``PORT`` (host 127.0.0.1) for ``--web``."""
    host, sep, port_text = text.rpartition(":")
    if not sep:
        host = ""
    host = host.strip("[]") or DEFAULT_HOST
    try:
        port = int(port_text)
    except ValueError:
        port = -1
    if not 0 <= port <= 65535:
        raise UserError(f"--web {text!r} is not HOST:PORT",
                        "give e.g. --web 127.0.0.1:8080, or --web 0.0.0.0:8080 for the network")
    return host, port


def entry_json(entry: Entry) -> dict[str, Any]:
    return {**entry.to_json(), "summary": summarize(entry.payload)}


class WebServer:
    """The aiohttp application around one ``StatusSource`` and, optionally, a journal."""

    def __init__(self, source: StatusSource, journal: JournalView | None = None, *,
                 clock: Callable[[], float] = time.time, push_interval_s: float = 0.25,
                 heartbeat_s: float = 1.0, stale_after_s: float = 5.0,
                 journal_tail: int = 50, metrics: Callable[[], bytes] | None = None,
                 allow_origins: Iterable[str] = ()) -> None:
        self.source = source
        self.metrics = metrics  # the Prometheus exposition of one scrape (host.fleet.metrics)
        self.journal = journal
        self.clock = clock  # wall clock, only to judge how old the daemon's data is
        self.push_interval_s = push_interval_s
        self.heartbeat_s = heartbeat_s
        self.stale_after_s = stale_after_s
        self.journal_tail = journal_tail
        self._page = (resources.files("host.web") / "static" / "index.html").read_bytes()
        self._clients: set[web.WebSocketResponse] = set()
        self._broadcaster: asyncio.Task[None] | None = None
        self._runner: web.AppRunner | None = None
        self.port = 0
        self.allow_origins = tuple(allow_origins)
        self.policy = AccessPolicy(DEFAULT_HOST, self.allow_origins)  # start() sets the host
        self.app = web.Application(middlewares=middlewares(lambda: self.policy, QUERIES))
        self.app.router.add_get("/", self._index)
        self.app.router.add_get("/api/status", self._status)
        self.app.router.add_get("/api/journal", self._journal)
        self.app.router.add_get("/metrics", self._metrics)
        self.app.router.add_get("/ws", self._ws)
        self.app.on_startup.append(self._start_broadcaster)
        self.app.on_shutdown.append(self._close_clients)

    # --- life cycle -----------------------------------------------------------------------

    async def start(self, host: str = DEFAULT_HOST, port: int = DEFAULT_PORT) -> int:
        """Listen on ``host:port`` (port 0: any free one); returns the port."""
        self.policy = AccessPolicy(host, self.allow_origins)
        self._runner = web.AppRunner(self.app, access_log=None)
        await self._runner.setup()
        site = web.TCPSite(self._runner, host, port)
        try:
            await site.start()
        except OSError as exc:
            await self._runner.cleanup()
            raise UserError(f"cannot listen on {host}:{port} ({exc.strerror})",
                            "choose another port with --web HOST:PORT") from exc
        self.port = int(self._runner.addresses[0][1])
        log.info("web page on http://%s:%d/", host, self.port)
        return self.port

    async def close(self) -> None:
        if self._runner is not None:
            runner, self._runner = self._runner, None
            await runner.cleanup()

    async def _start_broadcaster(self, app: web.Application) -> None:
        self._broadcaster = asyncio.create_task(self._broadcast(), name="web-broadcast")

    async def _close_clients(self, app: web.Application) -> None:
        if self._broadcaster is not None:
            # Python 3.11's wait_for swallows a cancellation that lands while the status it
            # waits for arrives (the broadcaster then runs on and a single cancel() waits for it
            # forever): cancel until the task has ended.
            task, self._broadcaster = self._broadcaster, None
            while not task.done():
                task.cancel()
                await asyncio.wait({task}, timeout=0.1)
            with contextlib.suppress(asyncio.CancelledError, Exception):
                task.result()
        for ws in list(self._clients):
            await ws.close(code=1001, message=b"server shutdown")

    # --- what is sent ---------------------------------------------------------------------

    def _status_json(self, status: Status) -> dict[str, Any]:
        now = self.clock()
        age = diagnosis_age(status, now)
        return {**status.to_json(), "server_time": now, "stale_after_s": self.stale_after_s,
                "stale": now - status.updated > self.stale_after_s,
                "diagnosis_age_s": age,
                "behind": status.loop_behind or (age is not None and age > BEHIND_AFTER_S),
                "headline": headline(status, now, self.stale_after_s)}

    def _status_message(self, status: Status) -> str:
        return json.dumps({"type": "status", "status": self._status_json(status)})

    async def _read_journal(self, after_id: int | None, limit: int,
                            kind: list[str] | None = None) -> list[Entry]:
        if self.journal is None:
            return []
        if after_id is None:
            return await asyncio.to_thread(self.journal.tail, limit, kind)
        return await asyncio.to_thread(self.journal.since, after_id, limit, kind)

    async def _broadcast(self) -> None:
        status = self.source.snapshot()
        tail = await self._read_journal(None, 1)
        last_id = tail[-1].id if tail else 0
        while True:
            try:
                status = await asyncio.wait_for(self.source.wait_changed(status.version),
                                                self.heartbeat_s)
            except TimeoutError:
                status = self.source.snapshot()
            except Exception:  # a broken source must not end the pushes for good
                log.exception("web: waiting for a status change failed")
                await asyncio.sleep(self.heartbeat_s)
                status = self.source.snapshot()
            messages = [self._status_message(status)] if self._clients else []
            try:
                entries = await self._read_journal(last_id, 200)
            except Exception as exc:  # a journal read error must not end the page's updates
                log.warning("web: reading the journal failed: %s", exc)
                entries = []
            if entries:
                last_id = entries[-1].id
                if self._clients:
                    messages.append(json.dumps(
                        {"type": "journal", "entries": [entry_json(e) for e in entries]}))
            for ws in list(self._clients):
                try:
                    for text in messages:
                        await asyncio.wait_for(ws.send_str(text), self.heartbeat_s * 5)
                except (ConnectionError, TimeoutError, RuntimeError) as exc:
                    log.debug("web: dropping a client: %r", exc)
                    self._clients.discard(ws)
                    await ws.close()
            await asyncio.sleep(self.push_interval_s)

    # --- handlers -------------------------------------------------------------------------

    async def _index(self, request: web.Request) -> web.Response:
        return web.Response(body=self._page, content_type="text/html", charset="utf-8",
                            headers={"Cache-Control": "no-cache"})

    async def _status(self, request: web.Request) -> web.Response:
        return web.json_response(self._status_json(self.source.snapshot()))

    async def _journal(self, request: web.Request) -> web.Response:
        if self.journal is None:
            return web.json_response(
                {"error": "no journal: start the daemon with --journal FILE"}, status=404)
        q = request.query
        try:
            since = int(q["since"]) if "since" in q else None
            limit = int(q.get("limit", "100"))
            kinds = [Kind(k).value for k in q["kind"].split(",")] if "kind" in q else None
            if (since is not None and not 0 <= since <= MAX_ID) or not 0 < limit <= MAX_LIMIT:
                raise ValueError("out of range")
        except ValueError as exc:
            return web.json_response(
                {"error": f"bad query ({exc}): since is an id >= 0, limit 1..{MAX_LIMIT}, "
                          f"kind one or more of {', '.join(k.value for k in Kind)}"},
                status=400)
        entries = await self._read_journal(since, limit, kinds)
        return web.json_response({"entries": [entry_json(e) for e in entries],
                                  "last_id": entries[-1].id if entries else since})

    async def _metrics(self, request: web.Request) -> web.Response:
        if self.metrics is None:
            return web.Response(status=404, text="no metrics: this server was given none\n")
        return web.Response(body=self.metrics(),
                            headers={"Content-Type": "text/plain; version=0.0.4; charset=utf-8"})

    async def _ws(self, request: web.Request) -> web.WebSocketResponse:
        ws = web.WebSocketResponse(heartbeat=max(10.0, self.heartbeat_s * 5))
        await ws.prepare(request)
        await ws.send_str(self._status_message(self.source.snapshot()))
        entries = await self._read_journal(None, self.journal_tail)
        await ws.send_str(json.dumps({"type": "journal",
                                      "entries": [entry_json(e) for e in entries]}))
        self._clients.add(ws)
        try:
            async for msg in ws:  # read-only: what a client sends is ignored
                if msg.type == WSMsgType.ERROR:
                    break
        finally:
            self._clients.discard(ws)
        return ws
