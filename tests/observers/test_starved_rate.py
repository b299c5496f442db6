"""A low rate judged in the publisher's own time, on a simulated clock with a simulated scheduler.

Beside ``test_starved`` (a silence): a publisher that stamps a message when it *publishes* it
(hector_mapping, a teleop node; on ROS 2 every node that is not a driver) and is held on the run
queue publishes nothing while it waits and then its backlog in a burst, each message stamped as
it goes out. Until the burst is out the window holds the gap and too few messages: a rate drop
on the stamps, though the publisher only waited. With its chain's run-queue wait known
(``probe``), the window's span less that wait is its own time, and the rate there is judged.
A topic without stamps is judged on arrival times, and a spell in which nothing came in on any
topic (the daemon's source held up: ``WayIn``) is the way in's, not its publisher's. A
publisher that really slowed
down sleeps, and is still found within the window. No wall clock: verdicts and their
simulated times are the result.
"""

from __future__ import annotations

import functools

import pytest

import host.atoms as A
from host.observers import FrequencyObserver, TopicMessage
from host.observers.owntime import WindowWait
from host.observers.payload import encode
from host.observers.silence import STARVED_CAP_S, ChainState
from host.observers.topics import WayIn
from tests.observers.loaded import Loaded, Send, stalls
from tests.observers.test_starved import Beside, Chain, scan

RATE = 40.0
WINDOW = 0.5


def message(topic: str, seq: int, stamp: float | None, arrival: float) -> TopicMessage:
    values = {"seq": seq} if stamp is None else {"seq": seq, "stamp": stamp}
    return TopicMessage(arrival, topic, encode(values))


def publishing(chain: Chain, start: float, end: float, rate: float = RATE, *,
               stamped: bool = True, topic: str = "/scan", catch_up_s: float = 0.001
               ) -> list[Send]:
    """A publisher at ``rate`` that stamps each message when it publishes it: a message due
    while the chain is starved goes out after the spell, the backlog one every
    ``catch_up_s`` (its own CPU time per message), each stamped as it goes."""
    out: list[Send] = []
    k, sent = 0, 0.0
    while (due := start + k / rate) < end:
        sent = max(sent + catch_up_s, due)
        for a, b in chain.spells:
            if a <= due < b:
                sent = max(sent, b + catch_up_s)
        out.append((sent, functools.partial(message, topic, k, sent if stamped else None)))
        k += 1
    return out


def verdicts(sim: Loaded, topic: str = "/scan") -> list[tuple[bool | None, float]]:
    return sim.verdicts(str(A.ok(topic)))


@pytest.mark.parametrize("lagging", [False, True])
@pytest.mark.parametrize("spell", [(10.0, 10.12), (10.0, 10.2), (10.0, 10.45)])
def test_a_starved_burst_stamped_as_published_is_no_rate_drop(
        spell: tuple[float, float], lagging: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    # lagging: as Linux counts it — the wait is added when the thread gets the CPU
    chain = Chain([spell])
    chain.lagging = lagging
    sim = Loaded(scan(chain), [])
    sim.run(publishing(chain, 0.0, 20.0), 20.0)
    assert [ok for ok, _ in verdicts(sim)] == [True]
    # the rate judged on the stamps alone (the silence still in the publisher's own time):
    # the burst's head shows the gap with too few messages, the window after it the backlog
    # — the false rate verdicts of the ROS 2 run under the hog
    monkeypatch.setattr(FrequencyObserver, "_held_up", lambda self, now, span: False)
    chain = Chain([spell])
    chain.lagging = lagging
    before = Loaded(scan(chain), [])
    before.run(publishing(chain, 0.0, 20.0), 20.0)
    assert False in [ok for ok, _ in verdicts(before)]


@pytest.mark.parametrize("seed", [5, 6])
def test_a_publisher_starved_again_and_again_shows_no_rate_drop(seed: int) -> None:
    chain = Chain(stalls(seed, 30.0, 0.3, shortest=0.1))
    sim = Loaded(scan(chain), [])
    sim.run(publishing(chain, 0.0, 30.0), 30.0)
    assert [ok for ok, _ in verdicts(sim)] == [True]


@pytest.mark.parametrize("share", [0.0, 0.2])
def test_a_publisher_that_really_slowed_down_is_found_within_the_window(share: float) -> None:
    # from t = 10 it publishes at 20 Hz (it sleeps); its chain waits ``share`` of the wall
    # time all along (a busy machine): that wait is no excuse for half the rate
    chain = Chain([(0.0, 100.0)], share=share)
    sim = Loaded(scan(chain), [])
    sends = publishing(Chain([]), 0.0, 10.0) + publishing(Chain([]), 10.0, 20.0, rate=20.0)
    sim.run(sends, 20.0)
    got = verdicts(sim)
    assert [ok for ok, _ in got] == [True, False]
    assert 10.0 < got[1][1] <= 10.0 + WINDOW + 1 / 20.0


def test_a_wrong_rate_excused_for_seconds_is_said_at_the_cap() -> None:
    # from t = 10 the chain is stuck on the run queue for good (Linux counts no wait until the
    # thread runs), and its publisher gets out only 20 messages a second: excused as held up,
    # for STARVED_CAP_S, then said all the same
    chain = Chain([(10.0, 100.0)])
    chain.lagging = True
    sim = Loaded(scan(chain), [])
    sim.run(publishing(Chain([]), 0.0, 10.0) + publishing(Chain([]), 10.0, 20.0, rate=20.0),
            20.0)
    got = verdicts(sim)
    assert [ok for ok, _ in got] == [True, False]
    assert 10.0 + STARVED_CAP_S < got[1][1] <= 10.0 + STARVED_CAP_S + WINDOW + 1 / 20.0


def thermal(others: list[float]) -> Beside:
    """/thermal/image as system.yaml observes it (9 Hz; on ROS 2 a String: no stamp, judged
    on arrival times), beside another topic arriving at ``others``."""
    obs = Beside("/thermal/image", rate=9.0, tolerance=3.0, window=1.0)
    obs.chain = Chain([])  # its publisher never waits for a CPU
    obs.probe = obs.chain
    obs.way_in = WayIn()
    obs.others = others
    return obs


def held_up(held: tuple[float, float], rate: float, end: float, every: float = 0.0
            ) -> list[float]:
    """Arrivals at ``rate`` of which those due while the way in was ``held`` come in at its
    end, one every ``every`` s."""
    out: list[float] = []
    for due in (k / rate for k in range(int(end * rate))):
        at = held[1] if held[0] <= due < held[1] else due
        out.append(max(at, out[-1] + every) if out and at < out[-1] + every else at)
    return out


@pytest.mark.parametrize("held", [(9.89, 10.29), (9.95, 10.35)])
@pytest.mark.parametrize("every", [0.0, 0.005, 0.02])
def test_a_way_in_held_up_is_no_rate_fault_on_arrival_times(
        held: tuple[float, float], every: float) -> None:
    # ROS 2, the first lidar reconfigure: nothing came in on any topic for 0.3-0.4 s (no
    # silence yet: 4 periods of 9 Hz are 0.44 s), then the backlog; /thermal/image carries no
    # stamp. Its head shows too few messages, the window after it too many
    sends = [(t, functools.partial(message, "/thermal/image", k, None))
             for k, t in enumerate(held_up(held, 9.0, 20.0, every))]
    sim = Loaded(thermal(held_up(held, 100.0, 20.0)), [])
    sim.run(sends, 20.0)
    assert [ok for ok, _ in verdicts(sim, "/thermal/image")] == [True]
    # every other topic flowed: the backlog is the thermal camera's own, and said
    alone = Loaded(thermal(held_up((0.0, 0.0), 100.0, 20.0)), [])
    alone.run(sends, 20.0)
    assert False in [ok for ok, _ in verdicts(alone, "/thermal/image")]


def test_the_way_ins_quiet_spells_are_counted_within_a_window() -> None:
    way = WayIn()
    for t in (0.0, 0.01, 0.02, 0.3, 0.31, 0.35, 1.0):
        way.arrived(t)
    assert way.quiet(0.0, 1.0, 0.1) == pytest.approx(0.28 + 0.65)
    assert way.quiet(0.0, 1.0, 0.5) == pytest.approx(0.65)
    assert way.quiet(0.5, 0.8, 0.1) == pytest.approx(0.3)
    assert way.quiet(1.0, 2.0, 0.1) == 0.0


def test_the_wait_within_a_window_counts_from_the_last_reading_before_it() -> None:
    w = WindowWait(0.2)  # a reading due every 0.1 s
    assert w.due(0.0)
    w.add(0.0, ChainState(1.0, 0))
    assert not w.due(0.05) and w.due(0.1)
    for i in range(1, 10):
        w.add(i / 10, ChainState(1.0 + i / 100, 0))
    # window 0.55 .. 1.0: from the reading at 0.5 (0.05 waited so far) to 1.0 now, where
    # the wait grew by 0.11 in 0.1 s: no more than the time between counts
    assert w.within(0.55, 1.0, lambda: ChainState(1.2, 0)) == pytest.approx(0.04 + 0.1)
    # read already at that time: not again
    assert w.within(0.55, 1.0, lambda: None) == pytest.approx(0.14)
    # stuck on the run queue since the previous reading (at 1.0): all of it counted
    assert w.within(0.65, 1.1, lambda: ChainState(1.2, 1)) == pytest.approx(0.13 + 0.1)
    # never more than the window; and what happened before a window, for a backlog
    assert w.within(1.05, 1.1, lambda: ChainState(9.0, 0)) == pytest.approx(0.05)
    assert w.before(0.7, 1.0) == pytest.approx(0.12)
    # the probe unreadable: nothing known
    assert WindowWait(0.2).within(0.0, 1.0, lambda: None) == 0.0


def test_an_unreadable_probe_judges_the_rate_as_without_one() -> None:
    chain = Chain([(10.0, 10.2)])
    chain.readable = False
    sim = Loaded(scan(chain), [])
    sim.run(publishing(chain, 0.0, 20.0), 20.0)
    without = Loaded(scan(None), [])
    without.run(publishing(Chain([(10.0, 10.2)]), 0.0, 20.0), 20.0)
    assert verdicts(sim) == verdicts(without)
    assert False in [ok for ok, _ in verdicts(sim)]
    assert chain.readings > 0
