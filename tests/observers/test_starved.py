"""A silence judged in the publisher's own time, on a simulated clock with a simulated scheduler.

The frequency observer's ``probe`` reads the publisher chain's run-queue wait
(``host.observers.starvation``); here a ``Chain`` plays it: it is *starved* (waiting for a CPU)
during given spells and otherwise runs or sleeps. A starved publisher sends nothing until its
spell ends; a hung one sleeps. ``Loaded`` (``tests.observers.loaded``) plays the hub, with a
daemon loop that may itself stall. No wall clock: the verdicts and their simulated times are the
result.
"""

from __future__ import annotations

import functools
import logging

import pytest

import host.atoms as A
from host.observers import FrequencyObserver, TopicMessage
from host.observers.base import Update
from host.observers.payload import encode
from host.observers.silence import CATCH_UP, JITTER_S, STARVED_CAP_S, ChainState
from host.observers.topics import DEFAULT_SILENCE, JITTER_FLOOR_S, WayIn
from tests.observers.loaded import Loaded, stalls

TOPIC = "/scan"
RATE = 40.0  # the Hokuyo's, as system.yaml observes it
WINDOW = 0.5
BOUND = DEFAULT_SILENCE / RATE + WINDOW  # the bound without a probe: silent however stalled


class Chain:
    """The publisher's processes: starved (runnable, waiting for a CPU) during ``spells``."""

    def __init__(self, spells: list[tuple[float, float]], share: float = 1.0) -> None:
        self.spells = spells
        self.share = share  # of a spell's wall time spent waiting (1: starved outright)
        self.now = 0.0
        self.readings = 0
        self.read_at: list[float] = []
        self.readable = True
        self.lagging = False

    def read(self) -> ChainState | None:
        self.readings += 1
        self.read_at.append(self.now)
        if not self.readable:
            return None
        t = self.now
        if self.lagging:  # as Linux: a wait is added when the thread gets the CPU
            wait = sum(b - a for a, b in self.spells if b <= t)
        else:
            wait = sum(max(0.0, min(b, t) - a) for a, b in self.spells)
        return ChainState(self.share * wait, int(self.lagging and self.starved(t)))

    def starved(self, t: float) -> bool:
        return any(a <= t < b for a, b in self.spells)


class Observed(FrequencyObserver):
    """The observer, with the chain's clock set to each input's and tick's time."""

    chain: Chain

    def feed(self, item: TopicMessage, now: float) -> list[Update]:
        self.chain.now = now
        return super().feed(item, now)

    def tick(self, now: float) -> list[Update]:
        self.chain.now = now
        return super().tick(now)


def scan(chain: Chain | None) -> Observed:
    """The /scan observer as ``system.yaml`` configures it: the default silence periods."""
    obs = Observed(TOPIC, rate=RATE, tolerance=10, window=WINDOW)
    obs.chain = chain or Chain([])
    obs.probe = chain
    return obs


def message(seq: int, stamp: float, arrival: float) -> TopicMessage:
    return TopicMessage(arrival, TOPIC, encode({"seq": seq, "stamp": stamp}))


def publisher(chain: Chain, start: float, end: float, *, resume_s: float = 0.005
              ) -> list[tuple[float, functools.partial[TopicMessage]]]:
    """A publisher at ``RATE`` that sends nothing while starved; a message due during a spell
    goes out ``resume_s`` (its own CPU time) after the spell ends, stamped when due, and the
    messages after it follow in order."""
    out: list[tuple[float, functools.partial[TopicMessage]]] = []
    k, sent = 0, 0.0
    while (due := start + k / RATE) < end:
        sent = max(sent, due)
        for a, b in chain.spells:
            if a <= due < b:
                sent = b + resume_s
        out.append((sent, functools.partial(message, k, due)))
        k += 1
    return out


def verdicts(sim: Loaded) -> list[tuple[bool | None, float]]:
    return sim.verdicts(str(A.ok(TOPIC)))


@pytest.mark.parametrize("lagging", [False, True])
def test_a_starved_publishers_gap_past_the_old_bound_is_no_silence(lagging: bool) -> None:
    # lagging: as Linux counts it — the wait is added when the thread gets the CPU; until
    # then the thread shows as stuck on the run queue
    spell = (10.0, 10.9)  # 0.9 s without a message: past BOUND (0.625 s)
    chain = Chain([spell])
    chain.lagging = lagging
    sim = Loaded(scan(chain), [])
    sim.run(publisher(chain, 0.0, 20.0), 20.0)
    assert [ok for ok, _ in verdicts(sim)] == [True]
    assert chain.readings > 0  # judged with the probe, not by luck
    # the same gap without a probe: the observer's bound calls it silent (the false alarm)
    before = Loaded(scan(None), [])
    before.run(publisher(Chain([spell]), 0.0, 20.0), 20.0)
    assert [ok for ok, _ in verdicts(before)] == [True, False, True]


@pytest.mark.parametrize("catch_up", [CATCH_UP, 0.0])
def test_a_starved_publisher_is_given_time_to_catch_up(
        catch_up: float, monkeypatch: pytest.MonkeyPatch) -> None:
    # starved 0.3 s, then 200 ms of its own time to send what it missed (an emulator playing
    # every device catches up on 30 frames): its own time passes the bare limit meanwhile
    monkeypatch.setattr("host.observers.silence.CATCH_UP", catch_up)
    chain = Chain([(10.0, 10.3)])
    sim = Loaded(scan(chain), [])
    sim.run(publisher(chain, 0.0, 20.0, resume_s=0.2), 20.0)
    # without the time to catch up it would be a false silence
    assert [ok for ok, _ in verdicts(sim)] == ([True] if catch_up else [True, False, True])


@pytest.mark.parametrize("seed", [3, 4])
def test_a_publisher_starved_again_and_again_gets_its_messages_out(seed: int) -> None:
    # spells of up to 0.8 s starved, 0.1-0.5 s apart: long gaps, never a silence
    spells = stalls(seed, 30.0, 0.8)
    chain = Chain(spells)
    sim = Loaded(scan(chain), [])
    sim.run(publisher(chain, 0.0, 30.0), 30.0)
    assert [ok for ok, _ in verdicts(sim)] == [True]


def test_a_hung_publisher_is_found_at_the_limit_plus_its_own_confirmation() -> None:
    chain = Chain([])
    obs = scan(chain)
    sim = Loaded(obs, [])
    sim.run(publisher(chain, 0.0, 5.0), 6.0)
    last = 5.0 - 1 / RATE
    assert verdicts(sim) == [(True, pytest.approx(1 / RATE)),
                             (False, pytest.approx(last + obs.max_gap + JITTER_S))]
    # faster than without a probe: no learned allowance, no floor
    assert last + obs.max_gap + JITTER_S < last + obs.max_gap + JITTER_FLOOR_S
    # a hung /scan within 4 periods (100 ms) and the confirmation of its last scan: the
    # 150 ms target from the fault, with room for the hub's scheduling and the inject
    assert obs.max_gap + JITTER_S == pytest.approx(0.120)


def test_a_hung_publisher_whose_chain_is_half_starved_is_found_in_its_own_time() -> None:
    # the hung driver sleeps; its device's process keeps waiting half the time (busy machine)
    chain = Chain([(0.0, 100.0)], share=0.5)
    obs = scan(chain)
    sim = Loaded(obs, [])
    sim.run(publisher(Chain([]), 0.0, 5.0), 6.0)
    got = verdicts(sim)
    last = 5.0 - 1 / RATE
    assert [ok for ok, _ in got] == [True, False]
    # counted from the first reading (half the limit), its own time runs at half the wall
    # clock, and what it needs grows by CATCH_UP times its wait (the work it would catch up
    # on): the rest of the limit and the confirmation take that much longer, and no longer
    # (ticks come as the own time could have got there, further apart the longer the gap)
    first = obs.max_gap / 2
    net = (1 - 0.5) - CATCH_UP * 0.5  # own time gained less need grown, per second
    due = last + first + (obs.max_gap - first + JITTER_S) / net
    assert due <= got[1][1] <= due + JITTER_S


def test_a_publisher_starved_for_seconds_is_silent_at_the_cap(
        caplog: pytest.LogCaptureFixture) -> None:
    chain = Chain([(5.0, 100.0)])
    obs = scan(chain)
    sim = Loaded(obs, [])
    with caplog.at_level(logging.WARNING, logger="host.observers.topics"):
        sim.run(publisher(chain, 0.0, 10.0), 10.0)
    got = verdicts(sim)
    last = 5.0 - 1 / RATE
    assert got == [(True, pytest.approx(1 / RATE)),
                   (False, pytest.approx(last + obs.max_gap + STARVED_CAP_S))]
    assert "at the cap" in caplog.text and "starved" in caplog.text
    # /proc is read a few dozen times in the 2 s gap, not every 10 ms
    assert len([t for t in chain.read_at if t > last]) <= 40


def test_an_unreadable_probe_falls_back_to_the_learned_allowance() -> None:
    chain = Chain([])
    chain.readable = False  # no pid known, another OS, another user's process
    obs = scan(chain)
    sim = Loaded(obs, [])
    sim.run(publisher(chain, 0.0, 5.0), 6.0)
    last = 5.0 - 1 / RATE
    assert verdicts(sim)[-1] == (False, pytest.approx(
        last + obs.max_gap + JITTER_FLOOR_S + JITTER_S))


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_stalled_daemon_loop_is_no_silence_and_a_hang_is_still_found(seed: int) -> None:
    # the consumer stalls up to 0.3 s (messages queue behind it); the publisher is fine
    chain = Chain([])
    obs = scan(chain)
    stalled = stalls(seed, 40.0, 0.3)
    sim = Loaded(obs, stalled)
    sim.run(publisher(chain, 0.0, 30.0), 40.0)
    got = verdicts(sim)
    assert [ok for ok, _ in got] == [True, False]
    last = 30.0 - 1 / RATE
    assert last + obs.max_gap <= got[1][1] <= sim.resumed(last + obs.max_gap + STARVED_CAP_S)


def test_only_a_silence_confirmed_in_the_publishers_own_time_is_a_confirmed_finding() -> None:
    # the repair service starts at once on a confirmed finding (``Observer.confirmed``)
    atom = str(A.ok(TOPIC))
    hung = scan(Chain([]))
    Loaded(hung, []).run(publisher(Chain([]), 0.0, 5.0), 6.0)
    assert hung.asserted[atom] is False and hung.confirmed(atom)
    starved = Chain([(5.0, 100.0)])  # silent at the cap: the publisher was starved
    capped = scan(starved)
    Loaded(capped, []).run(publisher(starved, 0.0, 10.0), 10.0)
    assert capped.asserted[atom] is False and not capped.confirmed(atom)
    blind = Chain([])
    blind.readable = False  # judged by the learned allowance: not in its own time
    allowed = scan(blind)
    Loaded(allowed, []).run(publisher(blind, 0.0, 5.0), 6.0)
    assert allowed.asserted[atom] is False and not allowed.confirmed(atom)
    # a message ends it: nothing abnormal stands
    hung.feed(message(999, 7.0, 7.0), 7.0)
    assert not hung.confirmed(atom)


class Beside(Observed):
    """The observer with a hub's ``WayIn``: fed its own arrivals and those of another topic
    (``others``, arrival times), as the hub feeds every topic's messages."""

    others: list[float]

    def _take(self, now: float) -> None:
        assert self.way_in is not None
        while self.others and self.others[0] <= now:
            self.way_in.arrived(self.others.pop(0))

    def feed(self, item: TopicMessage, now: float) -> list[Update]:
        self._take(now)
        assert self.way_in is not None
        self.way_in.arrived(now)
        return super().feed(item, now)

    def tick(self, now: float) -> list[Update]:
        self._take(now)
        return super().tick(now)


def beside(others: list[float]) -> Beside:
    obs = Beside(TOPIC, rate=RATE, tolerance=10, window=WINDOW)
    obs.chain = Chain([])
    obs.probe = obs.chain
    obs.way_in = WayIn()
    obs.others = others
    return obs


def imu(start: float, end: float, held: tuple[float, float] = (0.0, 0.0)) -> list[float]:
    """Arrivals of another topic at 100 Hz; those due while ``held`` arrive at its end."""
    return [held[1] if held[0] <= t < held[1] else t
            for t in (start + k / 100 for k in range(int((end - start) * 100)))]


def test_a_way_in_held_up_for_every_topic_is_no_silence() -> None:
    # ROS 2, a managed driver reconfigured: the daemon's source delivered nothing on any topic
    # for 0.3 s, its publishers never waited for a CPU (the run-queue wait says nothing)
    held = (10.0, 10.3)
    sim = Loaded(beside(imu(0.0, 20.0, held)), [], delayed=[held])
    sim.run(publisher(Chain([]), 0.0, 20.0), 20.0)
    assert [ok for ok, _ in verdicts(sim)] == [True]
    # judged without the way in, the same gap is a silence in the publisher's own time
    alone = Loaded(scan(Chain([])), [], delayed=[held])
    alone.run(publisher(Chain([]), 0.0, 20.0), 20.0)
    assert [ok for ok, _ in verdicts(alone)] == [True, False, True]


def test_a_hang_beside_a_flowing_topic_is_found_at_the_limit_and_a_total_stop_at_the_cap(
) -> None:
    flowing = beside(imu(0.0, 10.0))
    sim = Loaded(flowing, [])
    sim.run(publisher(Chain([]), 0.0, 5.0), 6.0)
    last = 5.0 - 1 / RATE
    assert verdicts(sim)[-1] == (False, pytest.approx(last + flowing.max_gap + JITTER_S))
    assert flowing.confirmed(str(A.ok(TOPIC)))
    # nothing else comes in either: excused as a stalled way in, silent at the cap all the same
    stopped = beside(imu(0.0, 5.0))
    sim = Loaded(stopped, [])
    sim.run(publisher(Chain([]), 0.0, 5.0), 8.0)
    assert verdicts(sim)[-1] == (False, pytest.approx(last + stopped.max_gap + STARVED_CAP_S))
    assert not stopped.confirmed(str(A.ok(TOPIC)))
