"""The fleet view: every robot a Prometheus knows, with its headline, on a page of dxboard's own.

``FleetView(prometheus_url)`` is a small aiohttp application for ``dxboard fleet``. Each request
asks Prometheus's HTTP API (``/api/v1/query``, instant queries) three questions — each robot's
headline (``HEADLINE``: the expression of the recording rule ``robot:dxboard_headline:max`` in
deploy/prometheus/dxboard-rules.yml, evaluated here so the page needs no rules loaded), the
components abnormal in each robot's best diagnosis, and the components out of automatic repair
— plus the robots whose daemon Prometheus cannot scrape (``up == 0``). It serves

- ``GET /`` — a table, one row a robot (site, robot, headline: healthy, repairing, needs a
  person or unreachable; the components behind it), worst first; plain HTML that refreshes
  itself every few seconds, no JavaScript;
- ``GET /api/fleet`` — the same rows as JSON.

A Prometheus that does not answer is a 502 saying which URL failed. Read-only, like the
robot's own page; it binds to 127.0.0.1 unless told otherwise.
"""

from __future__ import annotations

import html
import logging
from dataclasses import asdict, dataclass, field
from typing import Any

import aiohttp
from aiohttp import web

log = logging.getLogger(__name__)

HEADLINE = (
    "clamp_max("
    "2 * max by (robot, site) (dxboard_component_health >= bool 3)"
    " + max by (robot, site) (dxboard_component_health >= bool 1)"
    " + 2 * (1 - max by (robot, site) (dxboard_board_link_up)), 2)")
ABNORMAL = "dxboard_component_abnormal == 1"
OUT_OF_REPAIR = "dxboard_component_quarantined == 1 or dxboard_component_held == 1"
UNREACHABLE = 'up{job="dxboard"} == 0'
WORDS = {0: "healthy", 1: "repairing", 2: "needs a person"}
ORDER = {"unreachable": 0, "needs a person": 1, "repairing": 2, "healthy": 3}
REFRESH_S = 5
QUERY_TIMEOUT_S = 10.0


class PrometheusError(Exception):
    """Prometheus did not answer a query (its URL and why)."""


@dataclass
class RobotRow:
    robot: str
    site: str
    headline: str
    abnormal: list[str] = field(default_factory=list)
    out_of_repair: list[str] = field(default_factory=list)


class FleetView:
    def __init__(self, prometheus: str) -> None:
        self.prometheus = prometheus.rstrip("/")
        self.app = web.Application()
        self.app.router.add_get("/", self._page)
        self.app.router.add_get("/api/fleet", self._json)
        self._runner: web.AppRunner | None = None
        self.port = 0

    async def start(self, host: str, port: int) -> int:
        self._runner = web.AppRunner(self.app, access_log=None)
        await self._runner.setup()
        await web.TCPSite(self._runner, host, port).start()
        self.port = int(self._runner.addresses[0][1])
        return self.port

    async def close(self) -> None:
        if self._runner is not None:
            runner, self._runner = self._runner, None
            await runner.cleanup()

    # --- Prometheus -----------------------------------------------------------------------

    async def _query(self, session: aiohttp.ClientSession, promql: str) -> list[dict[str, Any]]:
        url = f"{self.prometheus}/api/v1/query"
        try:
            async with session.get(url, params={"query": promql}) as resp:
                body = await resp.json(content_type=None)
        except (aiohttp.ClientError, TimeoutError, ValueError) as exc:
            raise PrometheusError(f"{url}: {exc or type(exc).__name__}") from exc
        if not isinstance(body, dict) or body.get("status") != "success":
            raise PrometheusError(f"{url}: {body.get('error') if isinstance(body, dict) else body}")
        result: list[dict[str, Any]] = body["data"]["result"]
        return result

    async def rows(self) -> list[RobotRow]:
        """Every robot, worst headline first, then by site and name."""
        timeout = aiohttp.ClientTimeout(total=QUERY_TIMEOUT_S)
        async with aiohttp.ClientSession(timeout=timeout) as session:
            headline = await self._query(session, HEADLINE)
            abnormal = await self._query(session, ABNORMAL)
            out = await self._query(session, OUT_OF_REPAIR)
            down = await self._query(session, UNREACHABLE)
        rows: dict[tuple[str, str], RobotRow] = {}
        for s in headline:
            key = (s["metric"].get("robot", ""), s["metric"].get("site", ""))
            rows[key] = RobotRow(*key, WORDS.get(int(float(s["value"][1])), "unknown"))
        for s in down:
            key = (s["metric"].get("robot", s["metric"].get("instance", "")),
                   s["metric"].get("site", ""))
            rows[key] = RobotRow(*key, "unreachable")
        for samples, attr in ((abnormal, "abnormal"), (out, "out_of_repair")):
            for s in samples:
                row = rows.get((s["metric"].get("robot", ""), s["metric"].get("site", "")))
                if row is not None and row.headline != "unreachable":
                    getattr(row, attr).append(s["metric"].get("component", ""))
        for row in rows.values():
            row.abnormal.sort()
            row.out_of_repair = sorted(set(row.out_of_repair))
        return sorted(rows.values(), key=lambda r: (ORDER.get(r.headline, 0), r.site, r.robot))

    # --- handlers -------------------------------------------------------------------------

    async def _json(self, request: web.Request) -> web.Response:
        try:
            rows = await self.rows()
        except PrometheusError as exc:
            return web.json_response({"error": f"Prometheus did not answer: {exc}"}, status=502)
        return web.json_response({"prometheus": self.prometheus,
                                  "robots": [asdict(r) for r in rows]})

    async def _page(self, request: web.Request) -> web.Response:
        try:
            rows = await self.rows()
        except PrometheusError as exc:
            return web.Response(text=_html([], f"Prometheus did not answer: {exc}"),
                                content_type="text/html", status=502)
        return web.Response(text=_html(rows, ""), content_type="text/html")


def _html(rows: list[RobotRow], error: str) -> str:
    e = html.escape
    counts = {w: sum(1 for r in rows if r.headline == w) for w in ORDER}
    summary = ", ".join(f"{n} {w}" for w, n in counts.items() if n) or "no robots"
    body = "".join(
        f'<tr class="{e(r.headline.replace(" ", "-"))}"><td>{e(r.site)}</td>'
        f"<td>{e(r.robot)}</td><td>{e(r.headline)}</td>"
        f"<td>{e(', '.join(r.abnormal))}</td><td>{e(', '.join(r.out_of_repair))}</td></tr>"
        for r in rows)
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><meta http-equiv="refresh" content="{REFRESH_S}">
<title>dxboard fleet</title><style>
body {{ font-family: sans-serif; margin: 2em; }} table {{ border-collapse: collapse; }}
td, th {{ padding: .3em .8em; border-bottom: 1px solid #ddd; text-align: left; }}
.healthy td:nth-child(3) {{ color: #17803d; }} .repairing td:nth-child(3) {{ color: #b45f06; }}
.needs-a-person td:nth-child(3), .unreachable td:nth-child(3) {{ color: #b3261e;
  font-weight: bold; }} .error {{ color: #b3261e; }}
</style></head><body>
<h1>dxboard fleet</h1>
<p id="summary">{e(summary)}</p>
{f'<p class="error" id="error">{e(error)}</p>' if error else ""}
<table id="robots"><thead><tr><th>site</th><th>robot</th><th>headline</th>
<th>abnormal</th><th>out of repair</th></tr></thead>
<tbody>{body}</tbody></table>
</body></html>
"""
