"""A fleet's cost on each robot: N daemons' metrics scraped by the real Prometheus every second.

    .venv/bin/python -m benchmarks.fleet [--robots N] [--seconds S] [--rate HZ]

Starts ``--robots`` (default 50) lightweight robots (``benchmarks/_rigs/robots.py``: the board
emulator and the daemon, no nodes; ``dxboard run --emulate --robot rover-N --site bench``,
free ports, journals in a temporary folder), waits until every board link is up, then measures
each daemon's CPU (user + system of the daemon process, from /proc via psutil; its emulator is
a child process and not counted) over windows of ``--seconds`` (default 60) in the order
quiet, scraped, quiet, scraped: "scraped" windows run the real Prometheus (Debian's 2.42)
scraping every daemon's ``/metrics`` at 1 s, "quiet" windows run none. The cost of serving the
metrics is the difference, per daemon, of its mean CPU in the scraped and the quiet windows
(% of one core), with the ratio scraped / quiet from the same run. Also: the scrape size per
robot (bytes and series of one ``/metrics``, and ``scrape_samples_scraped`` /
``scrape_duration_seconds`` as Prometheus saw them), the CPU of one ``render()`` in this
process for the same robot's status (a cross-check that does not depend on the machine's
noise), and the load average. It prints a Markdown section for benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import statistics
import sys
import tempfile
import time
import urllib.request
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import psutil

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the checkout before benchmarks/

from benchmarks._rigs.robots import lite_model
from host.launch.prometheus import prometheus, query
from host.launch.running import RunningDaemon
from host.launch.waiting import wait_until


def start(tmp: Path, i: int, rate: int) -> RunningDaemon:
    d = tmp / f"rover-{i}"
    d.mkdir()
    return RunningDaemon(d, lite_model(d), ("--middleware", "zenoh", "-q", "--rate", str(rate),
                                            "--robot", f"rover-{i}", "--site", "bench"))


@contextlib.contextmanager
def fleet(tmp: Path, n: int, rate: int) -> Iterator[list[RunningDaemon]]:
    """``n`` robots, started 8 at a time; every one that started is stopped on the way out,
    also when another failed or the run is interrupted (Ctrl-C) while they start."""
    pool = ThreadPoolExecutor(8)
    futures = [pool.submit(start, tmp, i, rate) for i in range(1, n + 1)]
    try:
        robots = [f.result() for f in futures]
        yield robots
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        started = [f.result() for f in futures
                   if f.done() and not f.cancelled() and f.exception() is None]
        with ThreadPoolExecutor(8) as closer:
            list(closer.map(lambda r: r.close(), started))


def cpu_s(procs: list[psutil.Process]) -> list[float]:
    out = []
    for p in procs:
        t = p.cpu_times()
        out.append(t.user + t.system)
    return out


def window(procs: list[psutil.Process], seconds: float) -> list[float]:
    """Each process's CPU over ``seconds`` of wall time, in % of one core."""
    before, t0 = cpu_s(procs), time.monotonic()
    time.sleep(seconds)
    after, t1 = cpu_s(procs), time.monotonic()
    return [100.0 * (a - b) / (t1 - t0) for a, b in zip(after, before, strict=True)]


def render_cost_us(robot: RunningDaemon) -> tuple[int, int, float]:
    """Bytes and series of one scrape, and the CPU µs of one render() of the same status in
    this process (prometheus-client, no HTTP)."""
    with urllib.request.urlopen(robot.urls["web"] + "metrics", timeout=30) as r:
        body = r.read()
    series = sum(1 for line in body.decode().splitlines() if line and line[0] != "#")
    from host.fleet.metrics import FleetMetrics, LagProbe
    from host.web import MemoryStatusSource
    from host.web.status import ChannelView, Status

    status = robot.status()
    source = MemoryStatusSource(Status(
        channels=tuple(ChannelView(c["id"], c["name"], c["on"], c["state"], c["current_ma"])
                       for c in status["channels"]),
        observations=status["observations"], robot="rover-1"))
    metrics = FleetMetrics(source, robot="rover-1", site="bench",
                           components=["hokuyo", "jaguar", "laser_alignment", "thermal_camera",
                                       "board"], protected=[2], lag=LagProbe())
    n = 500
    t0 = time.process_time()
    for _ in range(n):
        metrics.render()
    return len(body), series, 1e6 * (time.process_time() - t0) / n


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robots", type=int, default=50)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--rate", type=int, default=100, help="board readings per second")
    args = ap.parse_args()
    load = [os.getloadavg()[0]]
    with tempfile.TemporaryDirectory() as tmp_name, \
            fleet(Path(tmp_name), args.robots, args.rate) as robots:
        tmp = Path(tmp_name)
        for r in robots:
            r.wait_for(lambda s: s["board_link_up"], 300, "the board link")
        procs = [psutil.Process(r.proc.pid) for r in robots]
        targets = [r.urls["web"].removeprefix("http://").rstrip("/") for r in robots]
        size, series, render_us = render_cost_us(robots[0])
        quiet: list[list[float]] = []
        scraped: list[list[float]] = []
        seen: dict[str, float] = {}
        for k in range(2):
            print(f"quiet window {k + 1}", flush=True)
            quiet.append(window(procs, args.seconds))
            load.append(os.getloadavg()[0])
            with prometheus(tmp / f"prom{k}", targets, scrape_s=1.0) as url:
                wait_until(lambda u=url: len(query(u, "up == 1")) == len(targets), 300,
                           "every daemon scraped", interval=1.0)
                print(f"scraped window {k + 1}", flush=True)
                scraped.append(window(procs, args.seconds))
                load.append(os.getloadavg()[0])
                for name, q in (("samples", "avg(scrape_samples_scraped)"),
                                ("duration", "avg(avg_over_time(scrape_duration_seconds[30s]))"),
                                ("up", "sum(up)")):
                    seen[name] = float(query(url, q)[0]["value"][1])
    per_quiet = [statistics.fmean(x) for x in zip(*quiet, strict=True)]
    per_scraped = [statistics.fmean(x) for x in zip(*scraped, strict=True)]
    cost = [s - q for s, q in zip(per_scraped, per_quiet, strict=True)]
    mq, ms = statistics.fmean(per_quiet), statistics.fmean(per_scraped)
    lines = [
        "## Fleet: a daemon's metrics scraped every second",
        "",
        f"`.venv/bin/python -m benchmarks.fleet --robots {args.robots} --seconds "
        f"{args.seconds:g} --rate {args.rate}`: {args.robots} lightweight robots (board "
        "emulator + daemon, no nodes), each daemon's CPU from /proc (user + system, its "
        f"emulator not counted) over {args.seconds:g} s windows, quiet / scraped by Prometheus "
        "2.42 at 1 s / quiet / scraped. Load average (1 min) during the run: "
        f"{min(load):.1f} to {max(load):.1f} on {psutil.cpu_count()} cores.",
        "",
        "| figure | value |",
        "|---|---|",
        f"| scrape size per robot | {size:,} bytes, {series} series "
        f"(Prometheus: {seen.get('samples', 0):.0f} samples) |",
        f"| scrape duration seen by Prometheus (mean) | "
        f"{1000 * seen.get('duration', 0):.1f} ms |",
        f"| daemon CPU, quiet (mean of {len(per_quiet)}) | {mq:.2f} % of a core |",
        f"| daemon CPU, scraped at 1 s (mean) | {ms:.2f} % of a core |",
        f"| cost of serving the scrape (scraped - quiet): mean / median / max | "
        f"{statistics.fmean(cost):.2f} / {statistics.median(cost):.2f} / {max(cost):.2f} "
        "% of a core |",
        f"| ratio scraped / quiet | {ms / mq:.3f} |",
        f"| one render() in process (prometheus-client, no HTTP) | {render_us:.0f} µs CPU "
        f"= {render_us / 1e4:.3f} % of a core at 1 scrape/s |",
        "",
    ]
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
