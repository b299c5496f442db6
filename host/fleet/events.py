"""The fleet metrics that only the event stream knows: counters, histograms and the input voltage.

``EventMetrics(registry, robot, site)`` is a reader of the daemon's event stream
(``host.daemon.stream``) that updates prometheus-client counters and histograms in the
daemon's own ``CollectorRegistry``, every series labelled ``robot`` and ``site``:

- ``dxboard_repair_actions_started_total``, ``..._succeeded_total`` and ``..._failed_total``
  (a timeout counts as failed), by ``action`` and ``component`` (the action's first argument),
  from ``ActionRecord``;
- ``dxboard_channel_switches_total`` by ``channel``/``name``: the on flag of a channel changing
  between two ``ChannelSample`` (a protected channel's is alerted on);
- ``dxboard_time_to_diagnosis_seconds``: from the first observation that left its healthy value
  while the robot was diagnosed healthy, to the first diagnosis naming a component;
- ``dxboard_time_to_healthy_seconds``: from that first observation (or the first abnormal
  diagnosis, when no observation came first, as at power-up) to the next healthy diagnosis;
- the board's input voltage of the latest ``ChannelSample`` (``input_volts``, read by the
  snapshot collector in ``host.fleet.metrics``).

Times are the daemon's monotonic stamps (``Stamped.mono``), never read here.
"""

from __future__ import annotations

from prometheus_client import CollectorRegistry, Counter, Histogram

from host.events import (
    ActionRecord,
    ActionState,
    ChannelSample,
    DiagnosisRecord,
    Observation,
    RunStarted,
    Stamped,
)

LABELS = ("robot", "site")
# a fault is found in well under a second (observers' windows) up to a few seconds; a repair
# takes a device's boot time (seconds) up to many minutes when it needs a person
DIAGNOSIS_BUCKETS = (0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0, 30.0, 60.0)
HEALTHY_BUCKETS = (1.0, 2.5, 5.0, 10.0, 20.0, 30.0, 60.0, 120.0, 300.0, 600.0, 1800.0)


class EventMetrics:
    def __init__(self, registry: CollectorRegistry, robot: str, site: str) -> None:
        self.robot, self.site = robot, site
        action = (*LABELS, "action", "component")
        self.started = Counter("dxboard_repair_actions_started", "Repair actions started.",
                               action, registry=registry)
        self.succeeded = Counter("dxboard_repair_actions_succeeded",
                                 "Repair actions that succeeded (their effects verified).",
                                 action, registry=registry)
        self.failed = Counter("dxboard_repair_actions_failed",
                              "Repair actions that failed or timed out.", action,
                              registry=registry)
        self.switches = Counter("dxboard_channel_switches",
                                "Changes of a channel's on flag seen by the daemon.",
                                (*LABELS, "channel", "name"), registry=registry)
        self.to_diagnosis = Histogram(
            "dxboard_time_to_diagnosis_seconds",
            "From the first observation of a fault to the diagnosis naming a component.",
            LABELS, buckets=DIAGNOSIS_BUCKETS, registry=registry)
        self.to_healthy = Histogram(
            "dxboard_time_to_healthy_seconds",
            "From the first observation of a fault to the robot diagnosed healthy again.",
            LABELS, buckets=HEALTHY_BUCKETS, registry=registry)
        self.to_diagnosis.labels(robot, site)  # both exist (count 0) from the first scrape
        self.to_healthy.labels(robot, site)
        self.input_volts: float | None = None
        self._healthy: dict[str, bool] = {}
        self._on: dict[int, bool] = {}
        self._diagnosed_bad = False
        self._fault_since: float | None = None  # first unhealthy observation, robot healthy
        self._bad_since: float | None = None  # the fault of the current abnormal diagnosis

    def __call__(self, stamped: Stamped) -> None:
        e = stamped.event
        if isinstance(e, ChannelSample):
            self._sample(e)
        elif isinstance(e, ActionRecord):
            self._action(e)
        elif isinstance(e, Observation):
            if (not self._diagnosed_bad and self._fault_since is None and e.value is not None
                    and e.literal in self._healthy and e.value != self._healthy[e.literal]):
                self._fault_since = stamped.mono
        elif isinstance(e, DiagnosisRecord):
            self._diagnosis(e, stamped.mono)
        elif isinstance(e, RunStarted):
            self._healthy = dict(e.healthy)

    def _sample(self, e: ChannelSample) -> None:
        if e.input_mv is not None:
            self.input_volts = e.input_mv / 1000.0
        for c in e.channels:
            before = self._on.get(c.id)
            if before is not None and before != c.on:
                self.switches.labels(self.robot, self.site, str(c.id), c.name).inc()
            elif before is None:  # the series exists (at 0) from the first sample
                self.switches.labels(self.robot, self.site, str(c.id), c.name)
            self._on[c.id] = c.on

    def _action(self, e: ActionRecord) -> None:
        labels = (self.robot, self.site, e.action, e.args[0] if e.args else "")
        if e.state == ActionState.STARTED:
            self.started.labels(*labels).inc()
        elif e.state == ActionState.SUCCEEDED:
            self.succeeded.labels(*labels).inc()
        else:
            self.failed.labels(*labels).inc()

    def _diagnosis(self, e: DiagnosisRecord, now: float) -> None:
        bad = bool(e.diagnoses and e.diagnoses[0])
        if bad and not self._diagnosed_bad:
            since = self._fault_since if self._fault_since is not None else now
            if self._fault_since is not None:
                self.to_diagnosis.labels(self.robot, self.site).observe(now - since)
            self._bad_since = since
        elif not bad and self._diagnosed_bad and self._bad_since is not None:
            self.to_healthy.labels(self.robot, self.site).observe(now - self._bad_since)
        if not bad:
            self._bad_since = None
        self._fault_since = None
        self._diagnosed_bad = bad
