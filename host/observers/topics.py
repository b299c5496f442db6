"""Topic observers: a topic's frequency (general observer) and input→output responses (multiple).

``FrequencyObserver`` is paper 000's general observer GObs: ``ok(t)`` iff the frequency
``f`` of topic ``t`` measured over a window ``ω`` satisfies ``|f - mu| < sigma`` (``rate`` mu,
``tolerance`` sigma, Hz). ``f`` is estimated from the messages inside the window as
(n - 1) / (t_last - t_first), which is unbiased before the window has filled. Silence is
judged on its own: once no message came for ``silence`` periods (``silence / mu`` seconds),
``¬ok(t)`` is emitted.

Judged by the messages' own timing, so a busy machine is not a rate drop (no flapping):

- where a message carries its publisher's stamp (``Message.stamp``: ``stamp``, ``t_ms`` or a
  ROS ``header.stamp``) the window and ``f`` are on those stamps: a burst of messages held up
  on its way (a stalled consumer, a descheduled transport thread) arrives bunched but still
  shows the rate it was sent at; a stamp going backwards (the publisher restarted) starts the
  window afresh;
- without stamps ``f`` is on arrival times, and a message that ends a gap (more than 1.5
  periods) may be the head of such a burst: its verdict waits for a tick at its own arrival
  time, which the hub runs after the messages already queued, so the whole burst is counted;
- where the daemon knows the publisher chain's run-queue wait (``probe``, below), a rate
  *too low* is judged again in the publisher's own time before it is said: the window's span
  less the chain's wait within it (``host.observers.owntime``: read ``READS`` times a window
  as messages come, and at the verdict). A publisher that stamps a message when it publishes
  it (hector, teleop, a real robot's nodes; on ROS 2 every node but a driver, whose messages
  carry their device's time) and was held on the run queue shows a gap and then a burst,
  not a slower rate; so does a topic judged on arrival times. A rate *too high* (the same
  publisher's backlog, in the window after its wait) is judged over the span plus the wait
  just before it; excused for ``STARVED_CAP_S`` (2 s) at most, as a silence. Judged on
  arrival times, a spell in which nothing came in on *any* observed
  topic (``WayIn``: the daemon's source held up, as by a ROS 2 lifecycle transition) counts
  as such a wait too: the backlog it lets in at once is the way in's, not the publisher's
  (one topic's own slowdown leaves the others flowing). Either way nothing is said; a
  publisher that really slowed down sleeps, its own time is the wall time, and it is found
  as before;
- a silence is a gap of ``silence / mu`` plus the delay on the way tolerated (``allowance``):
  twice the worst delay seen in the last minute — on stamps, how much later than the fastest
  message a message arrived; without, how much a gap exceeded one period — at least
  ``JITTER_FLOOR_S`` and at most ``ω``. A quiet machine keeps detection fast; on a busy one
  (a descheduled driver, the daemon's loop held up) the tolerance grows with what is seen;
- the gap is *noticed* at a tick at that limit and *confirmed* at a tick ``JITTER_S`` later
  that comes on time (at most ``JITTER_S`` late); a late tick means the loop itself was
  stalled (messages may be queued behind it), so the confirmation starts again. However
  stalled the loop, a gap of ``silence / mu + ω`` is judged silent at once: a silent or slow
  publisher is found within the window (``host.observers.silence``, shared with the board's
  link rule);
- where the daemon knows the processes the topic's messages depend on (``probe``: the nodes
  that publish it and its inputs, the process that feeds their devices, the daemon itself;
  ``host.observers.starvation``) the silence is judged in the *publisher's own time*
  instead, which tells a starved publisher from a hung one: the gap less the time those
  processes' most starved thread spent runnable but waiting for a CPU (Linux schedstat) must
  reach ``silence / mu + JITTER_S`` (plus ``CATCH_UP`` times the wait seen: what a starved
  chain has to catch up on), confirmed at a tick when none of their threads is stuck on the
  run queue; no learned allowance, no floor. While nothing came in on *any* observed topic for
  ``silence / mu`` (``WayIn``, the hub's: a source held up inside the daemon, the process
  feeding every device stalled) the time counts as waited too: one topic's hang leaves the
  others flowing (the hub shares it only when it observes two topics or more). A hung
  publisher sleeps, so it is found at that
  limit; a starved one is excused while it waits on the run queue, up to ``STARVED_CAP_S``
  (2 s) past ``silence / mu`` — a publisher starved for seconds is reported all the same, and
  the log line says which of the two it was. Where no process is known or ``/proc`` cannot
  be read, the gap is judged by the allowance above; ``own_time: false`` in ``system.yaml``
  asks for that.

``ResponseObserver`` is the multiple observer MObs: after a message on ``input``, a message on
``output`` must follow within ``within`` seconds; it emits ``ok(output)`` when one does and
``¬ok(output)`` at the deadline when none did (only the oldest unanswered input counts).

Detection latency (from the fault to the literal, plus the hub's scheduling delay):

- topic silent, judged in the publisher's own time: ``silence / mu + JITTER_S`` after the
  last message while the publisher is not starved (4 periods by default: 120 ms at /scan's
  40 Hz, 60 ms at 100 Hz), longer by the time it waits for a CPU, at most ``silence / mu +
  STARVED_CAP_S``;
- topic silent, judged without it: ``silence / mu + allowance + JITTER_S`` after the last
  message (on a quiet machine 160 ms at 100 Hz, 0.52 s at 10 Hz; at most ``silence / mu +
  ω``; the original engine needed 2 s);
- rate wrong but not zero: one message interval once the window holds only the new regime,
  at most ``ω`` plus an interval (while the publisher is held up the rate in its own time
  decides, and a wrong rate excused so is said ``STARVED_CAP_S`` after it was first seen);
- response missing: exactly ``within`` after the unanswered input; a response: at once.
"""

from __future__ import annotations

import logging
from collections import deque
from typing import Protocol

import host.atoms as A
from host.observers.base import DEFAULT_REFRESH, DEFAULT_VALIDITY, Observer
from host.observers.owntime import WindowWait
from host.observers.payload import TopicMessage
from host.observers.silence import (
    JITTER_GAIN,
    JITTER_MEMORY_S,
    STARVED_CAP_S,
    ChainState,
    Confirmation,
    OwnTime,
    SlidingExtreme,
)

log = logging.getLogger(__name__)

DEFAULT_SILENCE = 4.0  # periods without a message before a topic counts as silent
JITTER_FLOOR_S = 0.1  # the least delay tolerated on the way from a publisher to us
GAP = 1.5  # periods: a message after a longer gap may head a delayed burst
WAY_GAP_S = 0.03  # the way in's gaps kept: nothing on any topic for this long
WAY_MEMORY = 256  # the most of them kept


class ChainReader(Protocol):
    """A topic's publisher chain: its run-queue wait so far and its threads stuck on the run
    queue now, or None when it cannot be read (``host.observers.starvation.WaitProbe``)."""

    def read(self) -> ChainState | None: ...


class WayIn:
    """When a message of any observed topic last came in (the hub feeds it): a gap in which
    nothing came in on any topic is the way in's (the daemon's source held up, or every
    publisher at once), not one publisher's. The recent gaps of ``WAY_GAP_S`` or more are
    kept (``quiet``) for the rate of a topic judged on arrival times."""

    def __init__(self) -> None:
        self.last: float | None = None
        self.gaps: deque[tuple[float, float]] = deque(maxlen=WAY_MEMORY)

    def arrived(self, t: float) -> None:
        last = self.last
        if last is None or t > last:
            if last is not None and t - last >= WAY_GAP_S:
                self.gaps.append((last, t))
            self.last = t

    def quiet(self, start: float, end: float, longer: float) -> float:
        """How long nothing came in on any topic between ``start`` and ``end``, counting the
        gaps longer than ``longer`` seconds only."""
        total = 0.0
        for a, b in reversed(self.gaps):
            if b <= start:
                break
            if b - a >= longer:
                total += max(0.0, min(b, end) - max(a, start))
        return total


class TopicObserver(Observer[TopicMessage]):
    """An observer fed with the messages of ``topics``."""

    topics: tuple[str, ...] = ()


class FrequencyObserver(TopicObserver):
    kind = "frequency"
    needs_input = False

    def __init__(self, topic: str, rate: float, tolerance: float, window: float = 1.0,
                 silence: float = DEFAULT_SILENCE, atom: str | None = None, *,
                 name: str | None = None, validity: float = DEFAULT_VALIDITY,
                 refresh: float = DEFAULT_REFRESH, own_time: bool = True) -> None:
        super().__init__(name or f"frequency:{topic}", validity, refresh)
        if rate <= 0 or tolerance <= 0 or window * rate < 2 or silence <= 0:
            raise ValueError(f"{self.name}: need rate > 0, tolerance > 0, silence > 0 and "
                             "a window holding at least 2 messages (window * rate >= 2)")
        self.topics = (topic,)
        self.atom = atom or str(A.ok(topic))
        self.rate = rate
        self.tolerance = tolerance
        self.window = window
        self.max_gap = silence / rate
        self._times: deque[float] = deque()  # stamps, or arrival times without stamps
        self._stamped: bool | None = None  # which of the two ``_times`` holds
        self._arrived: float | None = None  # the last message's arrival
        self._start: float | None = None
        self._judge_at: float | None = None  # a verdict waiting for the rest of a burst
        self._confirm = Confirmation()  # of a silence gap, by an on-time tick
        self._fastest = SlidingExtreme(JITTER_MEMORY_S, greatest=False)  # arrival - stamp
        self._delays = SlidingExtreme(JITTER_MEMORY_S, greatest=True)  # delay beyond that
        self.frequency: float | None = None  # the last estimate, for journals and tests
        #: the publisher chain's run-queue wait (``host.observers.starvation.WaitProbe``), set
        #: by the daemon where it knows the publisher's processes; None: judged without it
        self.probe: ChainReader | None = None
        self.own_time = own_time  # False: never given a probe (system.yaml ``own_time``)
        self._own = OwnTime()  # a silence confirmed in the publisher's own time
        self._unprobed = False  # this gap: the probe could not be read, judged without it
        self._own_silence = False  # the silence now asserted was confirmed in own time
        #: messages of every observed topic (the hub's): while none came in for ``max_gap``,
        #: the gap is the way in's, counted as the chain's wait (None: not known)
        self.way_in: WayIn | None = None
        self._lever = WindowWait(window)  # the chain's wait in the window, for a low rate
        self._excused: float | None = None  # since when every wrong rate was excused

    def atoms(self) -> list[str]:
        return [self.atom]

    @property
    def lag(self) -> float:
        """How long after its publisher's input came back a verdict may still describe the
        time without it (``host.diagnosis.lags``): the window, and one message interval more
        at the slowest rate still ok (at most the silence limit). A rate is judged only when
        a message arrives, so the first verdict on the new regime comes with the first
        message after the old regime left the window: a map every 2 s, judged over 6 s, up
        to 11 s after the scan's return (held for the window alone, a map still judged not
        ok 6 s after it restarted a healthy hector_mapping)."""
        slowest = self.rate - self.tolerance
        return self.window + min(1.0 / slowest if slowest > 0 else self.max_gap, self.max_gap)

    def judge_s(self) -> dict[str, float]:
        """A rate is judged from two messages: up to two periods after the publisher starts
        (4 s for a 0.5 Hz map; nothing to speak of at 40 Hz)."""
        return {self.atom: 2.0 / self.rate}

    def confirmed(self, atom: str) -> bool:
        """A silence judged in the publisher's own time and confirmed there (not at the cap,
        starved; not by the allowance) is a hang, not a busy machine."""
        return atom == self.atom and self._own_silence and self.asserted.get(atom) is False

    @property
    def allowance(self) -> float:
        """The delay on the way tolerated before a gap counts as silence (see the module
        docstring): ``JITTER_GAIN`` times the worst seen lately, at least ``JITTER_FLOOR_S``,
        at most the window."""
        worst = self._delays.get() or 0.0
        return min(self.window, max(JITTER_FLOOR_S, JITTER_GAIN * worst))

    def _feed(self, item: TopicMessage, now: float) -> None:
        if self._start is None:
            self._start = now
        gap = None if self._arrived is None else now - self._arrived
        self._arrived = now
        self._confirm.reset()
        self._own.reset()
        self._unprobed = False
        self._own_silence = False
        stamp = item.stamp
        stamped = stamp is not None
        t = stamp if stamp is not None else now
        times = self._times
        if stamped != self._stamped or (times and t < times[-1]):
            times.clear()  # a new kind of timeline, or the publisher restarted
            self._fastest.clear()
            self._stamped = stamped
        times.append(t)
        while times[0] + self.window < t:
            times.popleft()
        self._learn_delay(now, stamp, gap)
        if self.probe is not None and self._lever.due(now):
            chain = self.probe.read()
            if chain is not None:
                self._lever.add(now, chain)
        if not stamped and gap is not None and gap * self.rate > GAP:
            self._judge_at = now  # maybe the head of a delayed burst: judge after it
        elif self._judge_at is None:
            self._judge(now)

    def _learn_delay(self, now: float, stamp: float | None, gap: float | None) -> None:
        """How late this message came: beyond the fastest one lately (stamped), or beyond
        one period after the previous one (not stamped)."""
        if stamp is not None:
            self._fastest.push(now, now - stamp)
            fastest = self._fastest.get()
            self._delays.push(now, now - stamp - (fastest if fastest is not None else 0.0))
        elif gap is not None:
            self._delays.push(now, max(0.0, gap - 1.0 / self.rate))

    def _judge(self, now: float) -> None:
        times = self._times
        if len(times) < 2:
            return  # one message says nothing about a rate; silence is judged by _check
        span = times[-1] - times[0]
        self.frequency = f = (len(times) - 1) / span if span > 0 else float("inf")
        ok = abs(f - self.rate) < self.tolerance
        if not ok and self.asserted.get(self.atom) is not False and self._held_up(now, span):
            return  # a publisher held up, not slowed down or sped up: nothing said
        if not ok and self._excused is not None:
            log.warning("%s: a wrong rate excused for %.3f s (its publisher held up): said "
                        "all the same", self.name, now - self._excused)
        self._excused = None
        self._say(self.atom, ok, now)

    def _held_up(self, now: float, span: float) -> bool:
        """Is the rate wrong over ``span`` right in the publisher's own time
        (``host.observers.owntime``)? Too low: the span less the time the publisher chain
        waited on the run queue in it; too high (its backlog after a wait): the span plus what
        it waited just before. Judged on arrival times, a spell in which nothing came in on
        any topic (``WayIn.quiet``, longer than ``GAP`` periods) counts as such a wait."""
        end = now if self._stamped else self._times[-1]
        start = end - span
        low = self.frequency is not None and self.frequency < self.rate
        a, b = (start, end) if low else (start - self.window, start)
        waited = 0.0
        if self.probe is not None and low:
            waited = self._lever.within(start, now, self.probe.read)
        elif self.probe is not None:
            waited = self._lever.before(a, b)
        if not self._stamped and self.way_in is not None:
            waited = max(waited, self.way_in.quiet(a, b, GAP / self.rate))
        if waited <= 0:
            return False
        n = len(self._times) - 1
        own = span - waited if low else span + waited
        if own > 0 and (n / own <= self.rate - self.tolerance if low
                        else n / own >= self.rate + self.tolerance):
            return False  # slower (faster) in its own time too
        if self._excused is None:
            self._excused = now
            log.warning("%s: %d messages in %.3f s, but its publisher was held up %.3f s "
                        "%s (its chain's run-queue wait, or nothing came in on any topic): "
                        "%s Hz in its own time, no rate verdict", self.name, n + 1, span,
                        waited, "in it" if low else "just before it",
                        f"{n / own:.1f}" if own > 0 else "any")
        return now - self._excused < STARVED_CAP_S  # held up for seconds: said all the same

    def _silent_since(self) -> float | None:
        return self._arrived if self._arrived is not None else self._start

    def _check(self, now: float) -> None:
        if self._start is None:
            self._start = now  # the first tick starts the clock for a topic never heard
        if self._judge_at is not None and now >= self._judge_at:
            self._judge_at = None
            self._judge(now)
        since = self._silent_since()
        if since is None or self.asserted.get(self.atom) is False:
            return
        if self._probed():
            start, need, cap = self._own_bounds(since)
            if now < start:
                return
            chain = self.probe.read() if self.probe is not None else None
            if chain is not None and self._way_quiet(now):
                chain = ChainState(chain.wait, chain.stuck + 1)  # excused as if starved
            if chain is not None:
                if self._own.silent(now, chain, since, need, cap):
                    self._say_why(now - since)
                    self._silent(now)
                    self._own_silence = not self._own.capped
                return
            self._unprobed = True  # no pid, or /proc unreadable: judged as without a probe
        if self._confirm.silent(now, since + self.max_gap + self.allowance,
                                since + self.max_gap + self.window):
            self._silent(now)

    def _way_quiet(self, now: float) -> bool:
        """Nothing came in on any observed topic for this topic's silence limit: the way in
        stalled (a source held up inside the daemon, the process feeding every device), or
        every publisher did — either way not this publisher's own silence."""
        last = None if self.way_in is None else self.way_in.last
        return last is not None and now - last >= self.max_gap

    def _own_bounds(self, since: float) -> tuple[float, float, float]:
        """For a gap judged in the publisher's own time: when to read the probe first (half
        the silence limit), the own time that is silence (the limit plus ``JITTER_S``), and
        the cap in wall time."""
        return (since + self.max_gap / 2, self.max_gap + self._own.confirm,
                since + self.max_gap + STARVED_CAP_S)

    def _say_why(self, gap: float) -> None:
        """Log a silence judged in the publisher's own time: confirmed, or at the cap."""
        own = self._own
        level = logging.WARNING if self._arrived is not None else logging.INFO  # once heard
        if not own.capped:
            log.log(level, "%s: silent, no message for %.3f s (%.3f s of it the publisher's "
                    "own time, %.3f s its run-queue wait)", self.name, gap, own.own,
                    own.starved)
        else:
            log.log(level, "%s: silent at the cap, no message for %.3f s although the "
                    "publisher was starved or nothing came in on any topic (%.3f s of it "
                    "excused so)", self.name,
                    gap, own.starved)

    def _probed(self) -> bool:
        """Is this gap judged in the publisher's own time?"""
        return self.probe is not None and not self._unprobed

    def _silent(self, now: float) -> None:
        self.frequency = 0.0
        self._say(self.atom, False, now)

    def _deadline(self) -> float | None:
        times = [] if self._judge_at is None else [self._judge_at]
        since = self._silent_since()
        if since is not None and self.asserted.get(self.atom) is not False:
            if self._probed():
                times.append(self._own.deadline(*self._own_bounds(since)))
            else:
                times.append(self._confirm.deadline(since + self.max_gap + self.allowance))
        return min(times) if times else None


class ResponseObserver(TopicObserver):
    kind = "response"
    needs_input = False

    def __init__(self, input: str, output: str, within: float, atom: str | None = None, *,
                 name: str | None = None, validity: float = DEFAULT_VALIDITY,
                 refresh: float = DEFAULT_REFRESH) -> None:
        super().__init__(name or f"response:{input}->{output}", validity, refresh)
        if within <= 0 or input == output:
            raise ValueError(f"{self.name}: need within > 0 and two different topics")
        self.topics = (input, output)
        self.input = input
        self.output = output
        self.within = within
        self.atom = atom or str(A.ok(output))
        self._pending: float | None = None  # time of the oldest unanswered input

    def atoms(self) -> list[str]:
        return [self.atom]

    def _feed(self, item: TopicMessage, now: float) -> None:
        self._check(now)
        if item.topic == self.input:
            if self._pending is None:
                self._pending = now
        elif item.topic == self.output and self._pending is not None:
            self._pending = None
            self._say(self.atom, True, now)

    def _check(self, now: float) -> None:
        if self._pending is not None and now >= self._pending + self.within:
            self._pending = None
            self._say(self.atom, False, now)

    def _deadline(self) -> float | None:
        return None if self._pending is None else self._pending + self.within
