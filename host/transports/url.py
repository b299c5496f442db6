"""Board URLs: ``scheme://host:port/path?key=value``, parsed once and checked with a clear error.

A ``BoardUrl`` is what every transport receives. Each transport module documents its own
grammar in its header; this module only splits the text (``urllib.parse.urlsplit``), keeps the
query as a dict of single values, and offers typed accessors that turn a missing or malformed
part into ``BadUrl`` naming the URL, the part and an example of a good one. A bare ``HOST:PORT``
is read as ``tcp://HOST:PORT``, so the common case is short to type.
"""

from __future__ import annotations

import logging
import re
from dataclasses import dataclass, field
from urllib.parse import parse_qsl, urlsplit

from host.transports.errors import BadUrl

log = logging.getLogger(__name__)

_BARE = re.compile(r"^[A-Za-z0-9_.\-]+:\d+$|^\[[0-9A-Fa-f:]+\]:\d+$")


@dataclass(frozen=True)
class BoardUrl:
    """A parsed board URL (``text`` is what the user typed, for messages)."""

    text: str
    scheme: str
    host: str
    port: int | None
    path: str
    query: dict[str, str] = field(default_factory=dict)

    def need_host_port(self, example: str) -> tuple[str, int]:
        """``(host, port)``, or ``BadUrl`` with ``example`` as the fix."""
        if not self.host or self.port is None:
            raise BadUrl(f"{self.text!r} needs a host and a port", f"write it as {example}")
        return self.host, self.port

    def need_path(self, what: str, example: str) -> str:
        if not self.path or self.path == "/":
            raise BadUrl(f"{self.text!r} names no {what}", f"write it as {example}")
        return self.path

    def int_param(self, name: str, default: int, lo: int = 0, hi: int = 2**31) -> int:
        raw = self.query.get(name)
        if raw is None:
            return default
        try:
            value = int(raw, 0)
        except ValueError:
            value = lo - 1
        if not lo <= value <= hi:
            raise BadUrl(f"{self.text!r}: {name}={raw!r} is not a number in {lo}..{hi}",
                         f"for example ?{name}={default}")
        return value

    def str_param(self, name: str, default: str) -> str:
        return self.query.get(name, default)

    def check_params(self, allowed: tuple[str, ...]) -> None:
        """``BadUrl`` for a query parameter this transport does not know (a typo)."""
        for name in self.query:
            if name not in allowed:
                known = ", ".join(allowed) or "none"
                raise BadUrl(f"{self.text!r}: unknown parameter {name!r}",
                             f"this transport takes: {known}")


def parse(text: str) -> BoardUrl:
    """Split a board URL; ``BadUrl`` if it has no scheme or an unreadable port."""
    text = text.strip()
    if _BARE.match(text):
        text = "tcp://" + text
    if "://" not in text:
        raise BadUrl(f"{text!r} is not a board URL",
                      "write SCHEME://..., e.g. tcp://192.168.0.7:7000 or serial:///dev/ttyACM0")
    try:
        parts = urlsplit(text)
        port = parts.port
    except ValueError as exc:
        raise BadUrl(f"{text!r}: {exc}", "the port must be a number 1..65535") from None
    query: dict[str, str] = {}
    for key, value in parse_qsl(parts.query, keep_blank_values=True):
        if key in query:
            raise BadUrl(f"{text!r}: parameter {key!r} given twice", "give it once")
        query[key] = value
    return BoardUrl(text=text, scheme=parts.scheme.lower(), host=parts.hostname or "",
                    port=port, path=parts.path, query=query)
