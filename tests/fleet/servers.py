"""The real Prometheus and Alertmanager, started for a test or a benchmark and always stopped.

``alertmanager(tmp)`` and ``prometheus(tmp, targets, ...)`` are context managers that start
Debian's binaries on free loopback ports (``host.launch.ports``; a port taken meanwhile by
another process is retried on a fresh one) with their data in ``tmp``, wait until the server
says it is ready (``/-/ready``, polled until a generous deadline), yield its base URL, and in a
``finally`` stop it (SIGTERM, then SIGKILL if it hangs) whatever happened. The configurations
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
import subprocess
import urllib.parse
import urllib.request
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import yaml

from host.launch.ports import free_port
from tests.fleet.tools import tool
from tests.ports import clashed
from tests.wait import wait_until

READY_S = 120.0  # a busy machine starts Prometheus in seconds; this only bounds a failure
DEPLOY = Path(__file__).resolve().parents[2] / "deploy"


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
            return r.status == 200
    except OSError:
        return False


@contextlib.contextmanager
def _server(name: str, argv: Sequence[str], log: Path) -> Iterator[str]:
    """Start ``argv`` (with ``{port}`` filled in) until it gets a port; yield its URL."""
    proc: subprocess.Popen[bytes] | None = None
    try:
        for _ in range(5):
            port = free_port()
            with log.open("ab") as out:
                proc = subprocess.Popen([a.format(port=port) for a in argv], stdout=out,
                                        stderr=subprocess.STDOUT, start_new_session=True)
            url = f"http://127.0.0.1:{port}"

            def up(p: subprocess.Popen[bytes] = proc, u: str = url) -> bool | None:
                return True if _ready(u) else (None if p.poll() is None else False)

            state = wait_until(lambda: up() is not None, READY_S, f"{name} to be ready",
                               interval=0.2, show=lambda: log.read_text()[-2000:])
            if state and up():
                yield url
                return
            if not clashed(log.read_text()):
                raise AssertionError(f"{name} exited: {log.read_text()[-2000:]}")
        raise AssertionError(f"{name}: no free port in 5 tries")
    finally:
        if proc is not None and proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()


@contextlib.contextmanager
def alertmanager(tmp: Path) -> Iterator[str]:
    """The shipped deploy/alertmanager/alertmanager.yml as it is (its webhooks lead nowhere
    here: notifications fail, the API still holds every alert)."""
    tmp.mkdir(parents=True, exist_ok=True)
    with _server("alertmanager", [
            tool("alertmanager"), f"--config.file={DEPLOY / 'alertmanager' / 'alertmanager.yml'}",
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
            tool("prometheus"), f"--config.file={tmp / 'prometheus.yml'}",
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
            tool("prometheus"), "--enable-feature=agent", f"--config.file={tmp / 'agent.yml'}",
            f"--storage.agent.path={tmp / 'data'}", "--web.listen-address=127.0.0.1:{port}"],
            tmp / "agent.log") as url:
        yield url
