"""The hardware observer's fast path says exactly what looking at every reading says.

Most readings show what the last one showed (the same switches, faults and current bands) while
every fact is settled: such a reading changes nothing and the observer does not look at it
further. ``Thorough`` is the same observer without that shortcut. Fed the same seeded random
streams — band crossings, switching, live faults, lying frames, trip and state events, STATEs,
link losses and reboots, ticks — both emit the same updates at the same times, and assert the
same literals.
"""

from __future__ import annotations

import random

import pytest

from host.board.types import (
    BoardEvent,
    BoardState,
    ChannelState,
    LinkDown,
    LinkUp,
    Reading,
    Rebooted,
)
from host.observers import Device, HardwareObserver, Retraction, Update
from protocol.constants import EV_STATE, EV_TRIP, ST_FAULTED, ST_LATCHED, ST_OFF, ST_ON, ST_TRIPPED

DEVICES = {"hokuyo": Device("hokuyo", 3, (0.2, 1.2)), "jaguar": Device("jaguar", 7, (0.5, 10.0)),
           "laser": Device("laser", 1, (0.1, 0.6)), "fan": Device("fan", 4)}
BANDS = {3: (200, 1200), 7: (500, 10000), 1: (100, 600), 4: (0, 100)}


class Thorough(HardwareObserver):
    """Looks at every reading in full: what each shows never equals the last."""

    def _shows(self, r: Reading) -> tuple[object, ...]:
        return (object(),)


def stream(seed: int, n: int) -> list[tuple[float, object]]:
    """A seeded mix of inputs over ``n`` steps of 10 ms, with long quiet stretches."""
    rng = random.Random(seed)
    on = {3: True, 7: True, 1: False, 4: True}
    fault = 0
    out: list[tuple[float, object]] = []
    t, seq = 0.0, 0
    for _ in range(n):
        t = round(t + rng.choice([0.01] * 20 + [0.3, 1.5]), 3)  # now and then a silence
        r = rng.random()
        if r < 0.02:
            on[rng.choice(list(on))] ^= True
        elif r < 0.03:
            fault ^= 1 << rng.choice([3, 7, 1])
        elif r < 0.035:
            ch = rng.choice([3, 7, 1, 9])
            new = rng.choice([ST_TRIPPED, ST_LATCHED, ST_FAULTED, ST_ON, ST_OFF])
            out.append((t, BoardEvent(t, 1, seq, seq * 10, rng.choice([EV_TRIP, EV_STATE]), ch,
                                      ST_ON, new, 0, 0, 0)))
            continue
        elif r < 0.037:
            chans = tuple(ChannelState(c, f"ch{c}", on.get(c, False), on.get(c, False),
                                       rng.choice([ST_ON, ST_OFF, ST_TRIPPED]), 500,
                                       fault >> c & 1, 0, 0, 0) for c in range(10))
            out.append((t, BoardState(t, 1, seq * 10, 12000, 500, 0, 0, 0, chans)))
            continue
        elif r < 0.038:
            out.append((t, rng.choice([LinkDown(t, "eof"), Rebooted(t, 1, 2, 0, "boot id")])))
            continue
        elif r < 0.039:
            out.append((t, "tick"))
            continue
        seq += 1
        currents = [0] * 10
        for ch, (lo, hi) in BANDS.items():
            if on[ch]:  # mostly in band, sometimes over or under
                currents[ch] = rng.choice([(lo + hi) // 2] * 30 + [hi + 50, max(lo - 50, 0)])
                currents[ch] += rng.randint(-3, 3)
        mask = sum(1 << ch for ch, v in on.items() if v)
        if rng.random() < 0.01:
            mask ^= 1 << rng.choice([3, 7])  # a lying frame
        out.append((t, Reading(t, t, 1, seq, seq * 10, 12000, mask, fault, tuple(currents))))
    return out


def run(h: HardwareObserver, inputs: list[tuple[float, object]]) -> list[tuple[str, float]]:
    said: list[tuple[str, float]] = []

    def note(updates: list[Update]) -> None:
        said.extend((u.atom if isinstance(u, Retraction) else str(u.literal), u.time)
                    for u in updates)

    for t, item in inputs:
        due = h.next_deadline()
        while due is not None and due <= t:
            note(h.tick(due))
            due = h.next_deadline()
        if item == "tick":
            note(h.tick(t))
        elif isinstance(item, LinkDown | Rebooted | BoardEvent | BoardState | Reading):
            note(h.feed(item, t))
    return said


@pytest.mark.parametrize("seed", range(8))
def test_the_fast_path_says_what_every_reading_says(seed: int) -> None:
    inputs = stream(seed, 4000)
    fast = HardwareObserver(DEVICES, link_timeout=0.25, settle=3)
    thorough = Thorough(DEVICES, link_timeout=0.25, settle=3)
    got = run(fast, inputs)
    assert got == run(thorough, inputs)
    assert fast.asserted == thorough.asserted and fast.bands == thorough.bands
    assert len({a for a, _ in got}) > 8  # the stream exercised the observer's rules


def test_the_fast_path_skips_what_changes_nothing() -> None:
    # once settled, a reading that shows nothing new is not looked at further, and says nothing
    h = HardwareObserver(DEVICES, link_timeout=0.25, settle=3)
    looked: list[object] = []
    device = h._device
    h._device = lambda *a: (looked.append(a), device(*a))  # type: ignore[method-assign]

    def reading(seq: int, hokuyo_ma: int) -> Reading:
        currents = (0, 0, 0, 700 + hokuyo_ma, 0, 0, 0, 0, 0, 0)
        return Reading(seq / 100, seq / 100, 1, seq, seq * 10, 12000, 1 << 3, 0, currents)

    for seq in range(1, 4):
        h.feed(reading(seq, seq), seq / 100)
    assert h.asserted["in_band(hokuyo)"] is True and len(looked) == 3 * len(DEVICES)
    assert h.feed(reading(4, 4), 0.04) == []  # settled: looking at it changes nothing...
    looked.clear()
    assert h.feed(reading(5, 9), 0.05) == []  # ...so one that shows the same (another
    assert looked == []  # current, the same band) is not looked at
    h.feed(reading(6, 900), 0.06)  # over the band: looked at until it settles
    assert len(looked) == len(DEVICES)


def test_a_link_up_notice_is_not_a_gap_to_learn() -> None:
    h = HardwareObserver(DEVICES, link_timeout=0.25, settle=3)
    info = None
    h.feed(Reading(0.0, 0.0, 1, 1, 10, 12000, 0, 0, (0,) * 10), 0.0)
    h.feed(LinkDown(0.1, "eof"), 0.1)
    h.feed(LinkUp(5.0, 4.9, info), 5.0)  # type: ignore[arg-type]
    h.feed(Reading(5.01, 5.01, 1, 1, 10, 12000, 0, 0, (0,) * 10), 5.01)
    assert h.link_limit == 0.25
