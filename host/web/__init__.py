"""The daemon's web face: a live status page, a JSON API and Prometheus metrics (aiohttp).

``status`` defines what is shown (``Status``) and the interface the daemon implements
(``StatusSource``, with ``MemoryStatusSource`` a ready-made one); ``server`` serves the page,
``/api/status``, ``/api/journal``, ``/metrics`` (what the daemon gives it: ``host.fleet.metrics``)
and the ``/ws`` push channel; ``static/index.html`` is the page (plain JavaScript and CSS,
no build step, nothing fetched from the internet).
"""

from host.web.server import JournalView, WebServer, parse_listen
from host.web.status import (
    ChannelView,
    DiagnosisStatus,
    MemoryStatusSource,
    OutOfRepair,
    RepairStatus,
    Status,
    StatusSource,
)

__all__ = [
    "ChannelView",
    "DiagnosisStatus",
    "JournalView",
    "MemoryStatusSource",
    "OutOfRepair",
    "RepairStatus",
    "Status",
    "StatusSource",
    "WebServer",
    "parse_listen",
]
