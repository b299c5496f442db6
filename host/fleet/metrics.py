"""The daemon's Prometheus metrics (``GET /metrics``), built with prometheus-client.

``FleetMetrics(source, robot=..., site=..., components=..., protected=..., journal=...)`` owns
one ``CollectorRegistry`` per daemon (never the process-global one, so two daemons in a process
or a test never share series). At every scrape a custom collector turns the latest ``Status``
snapshot (the page's projection, ``host.web.fold``, of the daemon's one ``EventFold``) into
gauges; ``EventMetrics`` (``host.fleet.events``) keeps the counters and histograms only the
stream knows. Every series carries ``robot`` (the model's name or ``dxboard run --robot``) and
``site`` labels, so a fleet's Prometheus can scrape many daemons (or receive them by
remote-write) without relabelling. Per component: ``dxboard_component_health`` (0 healthy, 1
suspect — in some minimal diagnosis, 2 abnormal — in the best one, 3 out of automatic repair:
needs a person), ``dxboard_component_abnormal`` (in the best diagnosis), ``..._quarantined`` and
``..._held`` (0 or 1 for every component of the model). Per channel: current in amperes, on, the
state as an enum, whether it is protected, switches. The board link, the input voltage in volts,
the journal's backlog (entries waiting for the disk), write failures and drops, the daemon's own
loop lag (``LagProbe``: how late a 0.5 s sleep wakes, the worst of the last ten), and the
running counters the page had before (observations, diagnosis runs and their durations, repairs
by outcome). ``render()`` returns the text exposition format 0.0.4 that Prometheus 2.x and
``promtool check metrics`` read. """

from __future__ import annotations

import asyncio
import logging
from collections import deque
from collections.abc import Iterable, Iterator, Sequence
from typing import Protocol

from prometheus_client import CollectorRegistry, disable_created_metrics, generate_latest
from prometheus_client.metrics_core import (
    CounterMetricFamily,
    GaugeMetricFamily,
    Metric,
    SummaryMetricFamily,
)
from prometheus_client.registry import Collector

from host.fleet.events import LABELS, EventMetrics
from host.journal.store import JournalReader
from host.web.status import CHANNEL_STATES, Status, StatusSource

log = logging.getLogger(__name__)

CONTENT_TYPE = "text/plain; version=0.0.4; charset=utf-8"

# no ``_created`` series beside every counter and histogram: they double a scrape for a value
# Prometheus 2.x ignores (process-wide, as prometheus-client offers it)
disable_created_metrics()  # type: ignore[no-untyped-call]

# dxboard_component_health levels
HEALTHY, SUSPECT, ABNORMAL, NEEDS_PERSON = 0, 1, 2, 3


class JournalStats(Protocol):
    """What the metrics read of the journal's writer (``host.journal.Journal`` is one)."""

    reader: JournalReader
    dropped: int
    write_failures: int
    recorded: int

    @property
    def pending(self) -> int:
        ...


class LagProbe:
    """How late the daemon's loop runs: a task sleeps ``interval_s`` again and again and keeps
    the overshoot of the last ``keep`` wakes, on the loop's own clock (the one its sleeps
    use); ``lag_s`` is the worst of them."""

    def __init__(self, interval_s: float = 0.5, keep: int = 10) -> None:
        self.interval_s = interval_s
        self._lags: deque[float] = deque([0.0], maxlen=keep)

    @property
    def lag_s(self) -> float:
        return max(self._lags)

    async def run(self) -> None:
        loop = asyncio.get_running_loop()
        while True:
            start = loop.time()
            await asyncio.sleep(self.interval_s)
            self._lags.append(max(0.0, loop.time() - start - self.interval_s))


class _Snapshot(Collector):
    def __init__(self, owner: FleetMetrics) -> None:
        self.owner = owner

    def collect(self) -> Iterable[Metric]:
        return self.owner.snapshot_metrics()


class FleetMetrics:
    def __init__(self, source: StatusSource, *, robot: str = "", site: str = "default",
                 components: Sequence[str] = (), protected: Iterable[int] = (),
                 journal: JournalStats | None = None, lag: LagProbe | None = None) -> None:
        self.source = source
        self.robot = robot or source.snapshot().robot or "robot"
        self.site = site
        self.components = tuple(components)
        self.protected = frozenset(protected)
        self.journal = journal
        self.lag = lag
        self.registry = CollectorRegistry(auto_describe=False)
        self.events = EventMetrics(self.registry, self.robot, self.site)
        self.registry.register(_Snapshot(self))

    def render(self) -> bytes:
        """The whole exposition, for one scrape."""
        return generate_latest(self.registry)

    # --- the snapshot's gauges ------------------------------------------------------------

    def snapshot_metrics(self) -> Iterator[Metric]:
        s = self.source.snapshot()
        base = (self.robot, self.site)
        yield from self._components(s, base)
        yield from self._channels(s, base)
        yield _one(GaugeMetricFamily, "dxboard_board_link_up",
                   "1 if the link to the board is up.", base, 1.0 if s.board_link_up else 0.0)
        if self.events.input_volts is not None:
            yield _one(GaugeMetricFamily, "dxboard_board_input_voltage_volts",
                       "The board's input (battery) voltage.", base, self.events.input_volts)
        yield from self._diagnosis(s, base)
        yield from self._journal(base)
        if self.lag is not None:
            yield _one(GaugeMetricFamily, "dxboard_daemon_lag_seconds",
                       "How late the daemon's event loop runs (worst of the last few "
                       "seconds).", base, self.lag.lag_s)
        info = GaugeMetricFamily("dxboard_run_info", "The daemon's current run (always 1).",
                                 labels=(*LABELS, "run_id"))
        info.add_metric((*base, s.run_id), 1.0)
        yield info

    def _components(self, s: Status, base: tuple[str, str]) -> Iterator[Metric]:
        best = set(s.diagnoses[0].bad) if s.diagnoses else set()
        some = {c for d in s.diagnoses for c in d.bad}
        names = sorted({*self.components, *some, *s.quarantined, *s.held})
        health = GaugeMetricFamily(
            "dxboard_component_health",
            "0 healthy, 1 suspect (in some minimal diagnosis), 2 abnormal (in the best "
            "diagnosis), 3 out of automatic repair (quarantined or held: needs a person).",
            labels=(*LABELS, "component"))
        abnormal = GaugeMetricFamily("dxboard_component_abnormal",
                                     "1 if the component is abnormal in the best diagnosis.",
                                     labels=(*LABELS, "component"))
        quarantined = GaugeMetricFamily(
            "dxboard_component_quarantined",
            "1 if the component is quarantined: out of automatic repair until a person clears "
            "it (dxboard quarantine clear).", labels=(*LABELS, "component"))
        held = GaugeMetricFamily(
            "dxboard_component_held",
            "1 if the component is held: no repair touches it until a person releases it "
            "(dxboard hold release).", labels=(*LABELS, "component"))
        for c in names:
            out = c in s.quarantined or c in s.held
            level = NEEDS_PERSON if out else ABNORMAL if c in best else \
                SUSPECT if c in some else HEALTHY
            health.add_metric((*base, c), float(level))
            abnormal.add_metric((*base, c), 1.0 if c in best else 0.0)
            quarantined.add_metric((*base, c), 1.0 if c in s.quarantined else 0.0)
            held.add_metric((*base, c), 1.0 if c in s.held else 0.0)
        yield from (health, abnormal, quarantined, held)

    def _channels(self, s: Status, base: tuple[str, str]) -> Iterator[Metric]:
        labels = (*LABELS, "channel", "name")
        current = GaugeMetricFamily("dxboard_channel_current_amperes",
                                    "Last measured current of each board channel.",
                                    labels=labels)
        on = GaugeMetricFamily("dxboard_channel_on", "1 if the channel is switched on.",
                               labels=labels)
        protected = GaugeMetricFamily(
            "dxboard_channel_protected",
            "1 if the channel is protected (the robot's computer: never switched by a repair).",
            labels=labels)
        state = GaugeMetricFamily("dxboard_channel_state",
                                  "1 for the channel's current state, 0 for the others.",
                                  labels=(*labels, "state"))
        states = list(CHANNEL_STATES) + sorted({c.state for c in s.channels}
                                               - set(CHANNEL_STATES))
        for c in s.channels:
            ch = (*base, str(c.id), c.name)
            current.add_metric(ch, c.current_ma / 1000.0)
            on.add_metric(ch, 1.0 if c.on else 0.0)
            protected.add_metric(ch, 1.0 if c.id in self.protected else 0.0)
            for name in states:
                state.add_metric((*ch, name), 1.0 if c.state == name else 0.0)
        yield from (current, on, protected, state)

    def _diagnosis(self, s: Status, base: tuple[str, str]) -> Iterator[Metric]:
        yield _one(CounterMetricFamily, "dxboard_observation_changes",
                   "Changes of observed literals since the daemon started.", base,
                   s.observation_changes)
        values = {"true": 0, "false": 0, "unknown": 0}
        for v in s.observations.values():
            values["unknown" if v is None else ("true" if v else "false")] += 1
        observations = GaugeMetricFamily("dxboard_observations",
                                         "Observed literals by their current value.",
                                         labels=(*LABELS, "value"))
        for k, n in values.items():
            observations.add_metric((*base, k), float(n))
        yield _one(GaugeMetricFamily, "dxboard_diagnoses", "Minimal diagnoses currently held.",
                   base, len(s.diagnoses))
        duration = SummaryMetricFamily("dxboard_diagnosis_duration_seconds",
                                       "Time the diagnoser took per run.", labels=LABELS)
        duration.add_metric(base, s.diagnosis_runs, s.diagnosis_latency_sum_s)
        repairs = CounterMetricFamily("dxboard_repairs", "Repairs ended, by outcome.",
                                      labels=(*LABELS, "outcome"))
        outcomes = {"succeeded": 0, "failed": 0, "timeout": 0, **s.repairs_by_outcome}
        for k, n in sorted(outcomes.items()):
            repairs.add_metric((*base, k), float(n))
        yield from (observations, duration, repairs)

    def _journal(self, base: tuple[str, str]) -> Iterator[Metric]:
        j = self.journal
        if j is None:
            return
        yield _one(GaugeMetricFamily, "dxboard_journal_backlog_entries",
                   "Journal entries waiting to be written to disk.", base, j.pending)
        yield _one(CounterMetricFamily, "dxboard_journal_write_failures",
                   "Journal commits that failed (each is retried).", base, j.write_failures)
        yield _one(CounterMetricFamily, "dxboard_journal_dropped_entries",
                   "Journal entries dropped: too many waited for the disk.", base, j.dropped)
        yield _one(CounterMetricFamily, "dxboard_journal_recorded_entries",
                   "Journal entries the daemon recorded (written, waiting or dropped).", base,
                   j.recorded)
        yield _one(GaugeMetricFamily, "dxboard_journal_bytes",
                   "Size of the journal file and its write-ahead log.", base,
                   j.reader.size_bytes())


def _one(kind: type[GaugeMetricFamily | CounterMetricFamily], name: str, help_text: str,
         base: tuple[str, str], value: float) -> Metric:
    """A family of one series labelled ``robot`` and ``site`` only."""
    family = kind(name, help_text, labels=LABELS)
    family.add_metric(base, float(value))
    return family
