"""Show a fleet: ``dxboard fleet --prometheus URL [--web H:P]``.

Serves a page (``host.fleet.view``) listing every robot the Prometheus at ``URL`` scrapes (or
receives by remote-write), each with its headline — healthy, repairing, needs a person, or
unreachable — and the components behind it, read from Prometheus's HTTP API at every request;
``/api/fleet`` gives the same as JSON. For a team without Grafana. It prints ``fleet: URL`` and
runs until Ctrl-C. The page binds to 127.0.0.1:8090 unless ``--web`` says otherwise. How a
fleet's Prometheus is set up: docs/fleet.md.
"""

from __future__ import annotations

import argparse
import asyncio
import signal
import urllib.parse

from host.errors import UserError

NAME = "fleet"
HELP = "a page listing every robot of a fleet with its headline, from Prometheus"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--prometheus", metavar="URL", required=True,
                        help="the fleet's Prometheus, e.g. http://prometheus.example.org:9090")
    parser.add_argument("--web", metavar="H:P", default="127.0.0.1:8090",
                        help="the page's address (default 127.0.0.1:8090)")


def run(args: argparse.Namespace) -> int:
    from host.web.server import parse_listen

    url = urllib.parse.urlsplit(args.prometheus)
    if url.scheme not in ("http", "https") or not url.netloc:
        raise UserError(f"--prometheus {args.prometheus!r} is not an http(s) URL",
                        "give e.g. --prometheus http://127.0.0.1:9090")
    return asyncio.run(_main(args.prometheus, *parse_listen(args.web)))


async def _main(prometheus: str, host: str, port: int) -> int:
    from host.fleet.view import FleetView

    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, stop.set)
    view = FleetView(prometheus)
    try:
        bound = await view.start(host, port)
    except OSError as exc:
        raise UserError(f"cannot listen on {host}:{port} ({exc.strerror})",
                        "choose another address with --web HOST:PORT") from None
    try:
        print(f"fleet: http://{host}:{bound}/", flush=True)
        await stop.wait()
    finally:
        await view.close()
    return 0
