"""The real Prometheus and Alertmanager beside a fleet of daemons, started and always stopped.

For the tests and benchmarks of the fleet view. ``alertmanager(tmp)`` and ``prometheus(tmp,
targets, ...)`` are context managers that start Debian's binaries (``binary(name)``; a missing
one is a ``UserError`` saying how to install it) as ``host.launch.procs.Child`` on free
loopback ports (``host.launch.ports``; a port taken meanwhile by another process is retried on
a fresh one) with their data in ``tmp``, wait until the server says it is ready (``/-/ready``,
polled until a generous deadline), yield its base URL, and in a ``finally`` stop it (SIGTERM,
then SIGKILL if it hangs) whatever happened. The configurations
are the shipped ones in deploy/ (the Prometheus ones with the test's targets and intervals).
Alertmanager runs alone (no cluster port). Prometheus scrapes ``targets`` (``host:port`` of
daemons, keeping their ``robot`` and ``site`` labels) every ``scrape_s`` and evaluates
``rules`` as often; it sends alerts to ``alertmanager`` with a resend delay of one second, so a
test sees an alert and its end quickly. ``query(url, promql)`` is the instant query of
Prometheus's HTTP API.
"""

from __future__ import annotations

import contextlib
import json
import shutil
import signal
import urllib.parse
import urllib.request
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import yaml

from host.errors import UserError
from host.launch.ports import clashed, free_port
from host.launch.procs import Child

READY_S = 120.0  # a busy machine starts Prometheus in seconds; this only bounds a failure
STOP_GRACE_S = 30.0
DEPLOY = Path(__file__).resolve().parents[2] / "deploy"
NAMES = {"alertmanager": ("prometheus-alertmanager", "alertmanager")}  # Debian's, upstream's


def binary(name: str) -> str:
    """The path of ``promtool``, ``prometheus`` or ``alertmanager``."""
    for candidate in NAMES.get(name, (name,)):
        path = shutil.which(candidate)
        if path is not None:
            return path
    raise UserError(f"{name} is not installed",
                    "run scripts/ensure-prometheus (as root) or apt-get install prometheus "
                    "prometheus-alertmanager")


def get_json(url: str, timeout: float = 10.0) -> Any:
    with urllib.request.urlopen(url, timeout=timeout) as r:
        return json.load(r)


def query(url: str, promql: str) -> list[dict[str, Any]]:
    """The result vector of an instant query."""
    body = get_json(f"{url}/api/v1/query?" + urllib.parse.urlencode({"query": promql}))
    assert body["status"] == "success", body
    result: list[dict[str, Any]] = body["data"]["result"]
    return result


def _ready(url: str) -> bool:
    try:
        with urllib.request.urlopen(f"{url}/-/ready", timeout=5) as r:
            return bool(r.status == 200)
    except OSError:
        return False


def _answers(url: str) -> Callable[[Child], bool]:
    return lambda _child: _ready(url)


@contextlib.contextmanager
def _server(name: str, argv: Sequence[str], log: Path) -> Iterator[str]:
    """Start ``argv`` (with ``{port}`` filled in) until it gets a port; yield its URL."""
    child: Child | None = None
    try:
        for _ in range(5):
            port = free_port()
            url = f"http://127.0.0.1:{port}"
            child = Child([a.format(port=port) for a in argv], stderr=log, name=name)
            try:
                up = child.wait_ready(_answers(url), READY_S, poll_s=0.2)
            except TimeoutError:
                raise AssertionError(f"{name} not ready after {READY_S:g} s: "
                                     f"{log.read_text()[-2000:]}") from None
            if up and child.running():
                yield url
                return
            child.stop()
            if not clashed(log.read_text()):
                raise AssertionError(f"{name} exited: {log.read_text()[-2000:]}")
        raise AssertionError(f"{name}: no free port in 5 tries")
    finally:
        if child is not None:
            child.stop(signal.SIGTERM, STOP_GRACE_S)


@contextlib.contextmanager
def alertmanager(tmp: Path) -> Iterator[str]:
    """The shipped deploy/alertmanager/alertmanager.yml as it is (its webhooks lead nowhere
    here: notifications fail, the API still holds every alert)."""
    tmp.mkdir(parents=True, exist_ok=True)
    with _server("alertmanager", [
            binary("alertmanager"), f"--config.file={DEPLOY / 'alertmanager' / 'alertmanager.yml'}",
            f"--storage.path={tmp / 'data'}", "--web.listen-address=127.0.0.1:{port}",
            "--cluster.listen-address="], tmp / "alertmanager.log") as url:
        yield url


@contextlib.contextmanager
def prometheus(tmp: Path, targets: Sequence[str], *, rules: Sequence[Path] = (),
               alertmanager: str | None = None, scrape_s: float = 1.0,
               extra: Sequence[str] = ()) -> Iterator[str]:
    """The shipped deploy/prometheus/prometheus.yml with this test's intervals, targets, rule
    files and Alertmanager."""
    tmp.mkdir(parents=True, exist_ok=True)
    config: dict[str, Any] = yaml.safe_load((DEPLOY / "prometheus" / "prometheus.yml").read_text())
    config["global"].update(scrape_interval=f"{scrape_s:g}s", scrape_timeout=f"{scrape_s:g}s",
                            evaluation_interval=f"{scrape_s:g}s")
    config["rule_files"] = [str(r) for r in rules]
    config["scrape_configs"][0]["static_configs"] = [{"targets": list(targets)}]
    if alertmanager is not None:
        host = alertmanager.removeprefix("http://")
        config["alerting"] = {"alertmanagers": [{"static_configs": [{"targets": [host]}]}]}
    else:
        del config["alerting"]
    (tmp / "prometheus.yml").write_text(yaml.safe_dump(config))
    with _server("prometheus", [
            binary("prometheus"), f"--config.file={tmp / 'prometheus.yml'}",
            f"--storage.tsdb.path={tmp / 'data'}", "--web.listen-address=127.0.0.1:{port}",
            "--rules.alert.resend-delay=1s", *extra], tmp / "prometheus.log") as url:
        yield url


@contextlib.contextmanager
def prometheus_agent(tmp: Path, targets: Sequence[str], remote_write: str,
                     scrape_s: float = 1.0) -> Iterator[str]:
    """Prometheus in agent mode (as on a robot behind NAT): scrapes ``targets`` and
    remote-writes everything to ``remote_write`` (a receiver's ``/api/v1/write``)."""
    tmp.mkdir(parents=True, exist_ok=True)
    config: dict[str, Any] = yaml.safe_load(
        (DEPLOY / "prometheus" / "robot-agent.yml").read_text())  # the shipped one, adjusted
    config["global"].update(scrape_interval=f"{scrape_s:g}s", scrape_timeout=f"{scrape_s:g}s")
    config["scrape_configs"][0]["static_configs"] = [{"targets": list(targets)}]
    config["remote_write"][0].update(url=remote_write,
                                     queue_config={"batch_send_deadline": "1s"})
    (tmp / "agent.yml").write_text(yaml.safe_dump(config))
    with _server("prometheus agent", [
            binary("prometheus"), "--enable-feature=agent", f"--config.file={tmp / 'agent.yml'}",
            f"--storage.agent.path={tmp / 'data'}", "--web.listen-address=127.0.0.1:{port}"],
            tmp / "agent.log") as url:
        yield url
