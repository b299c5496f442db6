"""Who may read the page's data: Origin and Host checks, query checks, clients that go away.

The page, the JSON API and the WebSocket are read-only, but what they show (live status, the
journal) is the robot's, so two browser attacks are closed here. A *cross-site WebSocket*: any
page the operator visits can open ``ws://127.0.0.1:8080/ws``; the browser then sends that page's
``Origin``, which must be this page's own origin or one named with ``--web-allow-origin``. *DNS
rebinding*: a stranger's name made to resolve to the robot makes the browser send ``Host:
stranger.example``; the ``Host`` must be an address the server listens on (for a loopback
listen, any of 127.0.0.1, localhost and ::1; for 0.0.0.0 or ::, any IP literal or this
machine's own name) or the host of an allowed origin. ``AccessPolicy.refusal`` is the pure rule;
``middlewares`` applies it to ``/ws`` and ``/api/*`` (a refusal is a 403 naming the reason and
the fix), refuses unknown or repeated query parameters with a 400 naming them, and turns a
client that hangs up mid-answer into a debug line instead of aiohttp's traceback. Requests
without ``Origin`` (curl, Prometheus, scripts) are not browsers' cross-site requests and pass.
"""

from __future__ import annotations

import ipaddress
import logging
import socket
from collections.abc import Awaitable, Callable, Iterable, Mapping

from aiohttp import web
from aiohttp.typedefs import Middleware
from yarl import URL

log = logging.getLogger(__name__)

LOOPBACK_NAMES = frozenset({"127.0.0.1", "localhost", "::1"})
WILDCARDS = frozenset({"", "0.0.0.0", "::"})
FIX = "open the page by the address it listens on, or start it with --web-allow-origin ORIGIN"

Handler = Callable[[web.Request], Awaitable[web.StreamResponse]]


def _ip(name: str) -> ipaddress.IPv4Address | ipaddress.IPv6Address | None:
    try:
        return ipaddress.ip_address(name)
    except ValueError:
        return None


def _host_name(header: str) -> str | None:
    """The lower-case host of a ``Host`` header (``name``, ``name:port``, ``[v6]:port``)."""
    try:
        return URL(f"http://{header}").host
    except ValueError:
        return None


def parse_origin(text: str) -> str:
    """``scheme://host[:port]`` in canonical form; ValueError when ``text`` is not one."""
    try:
        url = URL(text)
    except ValueError:
        url = URL()
    if url.scheme not in ("http", "https") or not url.host or url.path not in ("", "/") \
            or url.query_string or url.user:
        raise ValueError(f"{text!r} is not an origin like http://robot.local:8080")
    port = f":{url.explicit_port}" if url.explicit_port is not None else ""
    host = f"[{url.host}]" if ":" in url.host else url.host
    return f"{url.scheme}://{host}{port}"


class AccessPolicy:
    """The ``Host`` and ``Origin`` a request to the listen address ``listen_host`` may carry."""

    def __init__(self, listen_host: str, allow_origins: Iterable[str] = ()) -> None:
        self.origins = frozenset(parse_origin(o) for o in allow_origins)
        listen = listen_host.strip("[]").lower()
        ip = _ip(listen)
        self.any_ip = listen in WILDCARDS
        names = {listen}
        if self.any_ip:
            names = {"localhost", socket.gethostname().lower(), socket.getfqdn().lower()}
        elif listen in LOOPBACK_NAMES or (ip is not None and ip.is_loopback):
            names |= LOOPBACK_NAMES
        names |= {URL(o).host or "" for o in self.origins}
        self.names = frozenset(names - {""})

    def refusal(self, host: str | None, origin: str | None) -> str | None:
        """None when the request may be served, else the reason it may not."""
        if not host:
            return "the request has no Host header"
        name = _host_name(host)
        if name is None or not (name in self.names or (self.any_ip and _ip(name) is not None)):
            return (f"Host {host!r} is not an address of this robot's page (DNS rebinding?); "
                    f"{FIX}")
        if origin is None:
            return None
        try:
            canonical = parse_origin(origin)
        except ValueError:
            canonical = origin
        if canonical in self.origins:
            return None
        if canonical.partition("://")[2] == host.lower():
            return None  # the page's own origin (http, or https behind a proxy)
        return f"Origin {origin!r} is not this page's origin nor an allowed one; {FIX}"


def guarded(path: str) -> bool:
    """The routes whose data a stranger's page must not read."""
    return path == "/ws" or path.startswith("/api/")


def middlewares(policy: Callable[[], AccessPolicy],
                queries: Mapping[str, frozenset[str]]) -> list[Middleware]:
    """aiohttp middlewares: clients that go away, then access, then query parameters.

    ``policy`` is called per request (the server knows its listen address only once started);
    ``queries`` maps a route to the query parameters it takes (routes not in it take any).
    """

    @web.middleware
    async def gone(request: web.Request, handler: Handler) -> web.StreamResponse:
        try:
            return await handler(request)
        except ConnectionError as exc:  # the client hung up: nothing to answer, nobody to tell
            log.debug("web: %s %s: the client went away (%s)", request.method, request.path,
                      exc)
            return web.Response(status=499)

    @web.middleware
    async def access(request: web.Request, handler: Handler) -> web.StreamResponse:
        if guarded(request.path):
            reason = policy().refusal(request.headers.get("Host"),
                                      request.headers.get("Origin"))
            if reason is not None:
                log.debug("web: refused %s %s: %s", request.method, request.path, reason)
                return web.json_response({"error": reason}, status=403)
        return await handler(request)

    @web.middleware
    async def query(request: web.Request, handler: Handler) -> web.StreamResponse:
        takes = queries.get(request.path)
        if takes is not None:
            for name in request.query:
                if name not in takes:
                    known = ", ".join(sorted(takes)) or "none"
                    return web.json_response(
                        {"error": f"unknown query parameter {name!r} for {request.path} "
                                  f"(it takes: {known})"}, status=400)
                if len(request.query.getall(name)) > 1:
                    return web.json_response(
                        {"error": f"query parameter {name!r} given more than once"},
                        status=400)
        return await handler(request)

    return [gone, access, query]
