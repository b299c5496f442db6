"""The hardware observer (HObs): the board's readings, events and link, as literals.

Input: what ``BoardClient`` hands out (``host.board.types``): ``Reading`` (every channel's
switch read-back, live-fault bit and current), ``BoardEvent`` (trips, state changes, faults),
``BoardState`` (the full channel states, which the daemon feeds after connecting and after every
``LinkUp``), ``LinkDown``/``LinkUp`` and ``Rebooted``. For each switchable device ``d``
(``Device``: its channel and current band from ``system.yaml``):

- ``on(d)``: the channel's switch reads back on (``Reading.on_mask``, ``ChannelState.physical``);
- ``in_band(d)``: while on, the current lies in the device's band ``[low, high]`` (the band —
  nominal, over, under — is kept in ``bands`` for journals); while off the atom is retracted (a
  switched-off device has no band to judge);
- ``tripped(d)``: the board's protection tripped, latched or (switch fault) faulted the channel;
- the link: ``link(board)`` (the atom is configurable, or None to leave it out) while readings
  arrive, ``¬link(board)`` on ``LinkDown`` or after ``link_limit`` seconds without a reading.
  With the link gone every device literal is *retracted* at once — observations from a lost
  link are unknown, never stale truths — and comes back with the next readings that agree. A
  reboot retracts ``tripped`` (the board's channel states started anew).

Late is not lost (a busy machine: the board's process or the daemon's loop descheduled, the
readings still stamped by the board every period). ``link_limit`` is ``link_timeout``, or twice
the longest gap between two readings seen in the last minute if that is longer (the gaps the
link survived without a reconnect), at most ``link_timeout + link_slack``; and a gap that
reached it is confirmed by a tick of an awake loop (``host.observers.silence``, as the
frequency observer does): a late tick means readings may be queued behind the stalled loop, so
the confirmation starts again. However stalled the loop, ``link_timeout + link_slack`` without
a reading is a lost link: a silent board is found within that bound.

Agreement before belief: a frame can lie with a valid checksum (a firmware bug, a corrupted
buffer), and one lie must not start a repair. So what readings show changes only after ``settle``
consecutive readings agree: the switch (``on``), the band (``in_band``) and the channel's health
(no live fault; off with a live fault; on with a live fault). A trip reported by an event (a trip,
or a state change to tripped, latched or faulted) is a *claim*: it counts once the settled
readings bear it out (a trip or a latch switches the channel off and leaves a live fault; a stuck
switch leaves a live fault whichever way it is stuck) and is dropped, with a warning, after
``settle`` readings that show no live fault. Readings without a live fault say ``¬tripped`` by
themselves (every bad state keeps a live fault), so ``tripped`` recovers with the first readings
after a silence, without waiting for a STATE. A state change to off, inrush or on says
``¬tripped`` at once, and a ``BoardState`` (a reply to the host's own request) is believed at once.

Cheap when nothing changes (a host watches ten boards at 100 Hz): a reading that shows what the
last one showed — the same switches and live faults, each switched-on device's current in the
same band — after looking at that one changed nothing and said nothing, would not either, and
is not looked at further (``tests/observers/test_steady.py`` proves that nothing said differs).

A noisy current sensor (``host.observers.noise``: the raw band changing ``NOISY_CHANGES`` times
within a second, faster than any device fault) is the sensor's fault, not the device's: while it
lasts ``in_band(d)`` is retracted (unknown) and every reading is looked at, as while the board
itself doubts the sensor (its ``sensor`` flag).

A current the board could not measure (its ``low`` flag, PROTOCOL.md section 10: below the
sensing part's accurate range, as a smart switch's current sense is at small loads; the
reading is 0) is *low, not measured*: from the range EVENT that says so (it comes before the
readings of that tick) or a STATE with ``low`` live, until the range EVENT that ends it, the
device's ``in_band(d)`` is retracted (unknown: not ``under`` its band, not an open load, not a
sensor fault) and its readings are not judged.

Detection latency (``settle`` readings, default 3): ``on`` after 3 readings (30 ms at 100 Hz,
20 ms more than believing the first); ``in_band`` after 3 readings; a trip 3 readings after the
board switched the channel off (the event itself comes first; at 100 Hz the trip counts about
30-40 ms after it, the read-back lagging one tick); a dead link after ``link_timeout`` (default
0.25 s) plus ``JITTER_S`` on a quiet machine, at most ``link_timeout + link_slack`` (default
1 s) on a busy one, or at once on ``LinkDown``.
"""

from __future__ import annotations

import logging
from collections.abc import Hashable, Mapping
from dataclasses import dataclass
from typing import Generic, TypeVar

import host.atoms as A
from host.board.types import (
    BoardEvent,
    BoardState,
    LinkDown,
    LinkUp,
    Reading,
    Rebooted,
    StreamItem,
)
from host.observers.base import DEFAULT_REFRESH, DEFAULT_VALIDITY, Observer, Update
from host.observers.noise import NoiseMeter
from host.observers.silence import JITTER_GAIN, JITTER_MEMORY_S, Confirmation, SlidingExtreme
from protocol.constants import (
    EV_FAULT,
    EV_RANGE,
    EV_TRIP,
    EV_WARNING,
    F_LOW,
    F_OVERLOAD,
    F_SENSOR,
    ST_FAULTED,
    ST_LATCHED,
    ST_TRIPPED,
)

log = logging.getLogger(__name__)

BoardInput = StreamItem | BoardState
DEFAULT_LINK_ATOM = str(A.link("board"))
DEFAULT_LINK_TIMEOUT = 0.25
DEFAULT_LINK_SLACK = 0.75  # the most the link limit grows on a busy machine
DEFAULT_SETTLE = 3
_BAD_STATES = (ST_TRIPPED, ST_LATCHED, ST_FAULTED)
# what one reading shows of a channel's health (every bad state keeps a live fault)
CLEAR, FAULT_OFF, FAULT_ON = "no live fault", "off with a live fault", "on with a live fault"

V = TypeVar("V", bound=Hashable)


class Settled(Generic[V]):
    """A value that changes only after ``n`` consecutive samples agree on a new one."""

    def __init__(self, n: int) -> None:
        self.n = n
        self.value: V | None = None
        self._cand: V | None = None
        self._count = 0

    def add(self, sample: V) -> bool:
        """Take one sample; True when the settled value changed."""
        if sample == self.value:
            self._cand, self._count = None, 0
            return False
        self._count = self._count + 1 if sample == self._cand else 1
        self._cand = sample
        if self._count < self.n:
            return False
        self.force(sample)
        return True

    def force(self, value: V | None) -> None:
        """Set the value at once (a source believed without agreement), or forget it (None)."""
        self.value, self._cand, self._count = value, None, 0

    def hold(self) -> None:
        """Keep the value, and start the agreement on a new one afresh."""
        self._cand, self._count = None, 0

    def state(self) -> tuple[object, ...]:
        return (self.value, self._cand, self._count)


def agrees(health: str | None, claim: int) -> bool:
    """Does a channel's settled health bear out an event's claim of bad state ``claim``?"""
    if claim == ST_FAULTED:  # a stuck switch: off (stuck off) or on (stuck on), fault live
        return health in (FAULT_OFF, FAULT_ON)
    return health == FAULT_OFF  # a trip or a latch switches the channel off


@dataclass
class _Evidence:
    """What the readings showed of one device's channel, and a trip claim waiting for them."""

    on: Settled[bool]
    band: Settled[str]
    health: Settled[str]
    claim: int | None = None  # the bad state an event claimed, not yet borne out
    clear_since_claim: int = 0  # readings with no live fault since the claim

    def state(self) -> tuple[object, ...]:
        return (*self.on.state(), *self.band.state(), *self.health.state(), self.claim,
                self.clear_since_claim)


@dataclass(frozen=True)
class Device:
    """A switchable device: its board channel and current band in amperes (None: no band)."""

    name: str
    channel: int
    band: tuple[float, float] | None = None

    def classify(self, amperes: float) -> str:
        if self.band is None or self.band[0] <= amperes <= self.band[1]:
            return "nominal"
        return "over" if amperes > self.band[1] else "under"


class HardwareObserver(Observer[BoardInput]):
    kind = "hardware"
    needs_input = False  # the link rule judges silence itself

    def __init__(self, devices: Mapping[str, Device], link_timeout: float = DEFAULT_LINK_TIMEOUT,
                 settle: int = DEFAULT_SETTLE, link_atom: str | None = DEFAULT_LINK_ATOM, *,
                 link_slack: float = DEFAULT_LINK_SLACK, name: str = "hardware",
                 validity: float = DEFAULT_VALIDITY, refresh: float = DEFAULT_REFRESH) -> None:
        super().__init__(name, validity, refresh)
        if link_timeout <= 0 or link_slack < 0 or settle < 1:
            raise ValueError(f"{name}: need link_timeout > 0, link_slack >= 0 and settle >= 1")
        self.devices = dict(devices)
        self.by_channel = {d.channel: d for d in self.devices.values()}
        # each device's atoms: on, tripped, in_band (built once, not per reading)
        self._atoms = {d.name: (str(A.on(d.name)), str(A.tripped(d.name)),
                                str(A.in_band(d.name))) for d in self.devices.values()}
        self._mask = sum(1 << d.channel for d in self.devices.values())
        self._banded = [(d.channel, *d.band) for d in self.devices.values() if d.band]
        # what the last reading showed, when looking at it changed nothing and said nothing:
        # a reading that shows the same would not either, and is not looked at (most of them)
        self._steady: tuple[object, ...] | None = None
        self.link_timeout = link_timeout
        self.link_slack = link_slack
        self.settle = settle
        self.link_atom = link_atom
        self.bands: dict[str, str] = {}  # device -> the settled band (nominal, over, under)
        self.doubted: set[str] = set()  # devices whose current sensor the board doubts
        self.noisy: set[str] = set()  # devices whose current sensor the readings show noisy
        self.low: set[str] = set()  # devices whose current is low, not measured (``low``)
        self._noise = {d.name: NoiseMeter() for d in self.devices.values() if d.band}
        self._ev = {d: self._fresh() for d in self.devices}
        self._last_reading: float | None = None  # the last sign of life (reading, STATE)
        self._prev_reading: float | None = None  # the last reading since a reconnect
        self._gaps = SlidingExtreme(JITTER_MEMORY_S, greatest=True)  # between readings
        self._confirm = Confirmation()  # of a gap that reached the link limit
        self._up = False

    def atoms(self) -> list[str]:
        out = [self.link_atom] if self.link_atom else []
        for d in self.devices.values():
            on, tripped, in_band = self._atoms[d.name]
            out += [on, tripped, in_band] if d.band is not None else [on, tripped]
        return out

    def confirmed(self, atom: str) -> bool:
        """A trip is said only once the settled readings (or the board's own state) bear it
        out: ``tripped(d)`` asserted is confirmed."""
        return self.asserted.get(atom) is True and any(
            atom == self._atoms[d][1] for d in self.devices)

    def stop(self, now: float) -> list[Update]:
        self._steady = None
        return super().stop(now)

    # -- inputs ----------------------------------------------------------------------------
    def feed(self, item: BoardInput, now: float) -> list[Update]:
        if type(item) is Reading:  # the common case, a hundred times a second: straight on
            self._fed_at = now
            self._reading(item, now)
            return self._flush()
        return super().feed(item, now)

    def _feed(self, item: BoardInput, now: float) -> None:
        if isinstance(item, Reading):
            self._reading(item, now)
            return
        self._steady = None  # anything else may change what a reading would say
        if isinstance(item, BoardEvent):
            self._event(item, now)
        elif isinstance(item, BoardState):
            self._state(item, now)
        elif isinstance(item, LinkDown):
            self._prev_reading = None  # a reconnect follows: its gap is no lateness
            self._link_lost(now)
        elif isinstance(item, LinkUp):
            self._prev_reading = None
            self._link_up(now)
        elif isinstance(item, Rebooted):
            for d in self.devices.values():
                ev = self._ev[d.name]
                ev.health.force(None)  # the new boot's readings tell again
                ev.claim = None
                self._forget(self._atoms[d.name][1], now)
                self._low(d, False, now)  # the new boot says it again

    def _fresh(self) -> _Evidence:
        return _Evidence(Settled(self.settle), Settled(self.settle), Settled(self.settle))

    def _link_up(self, now: float) -> None:
        self._up = True
        self._last_reading = now
        self._confirm.reset()
        if self.link_atom:
            self._say(self.link_atom, True, now)

    def _reading(self, r: Reading, now: float) -> None:
        prev, self._prev_reading = self._prev_reading, now
        if prev is not None and JITTER_GAIN * (now - prev) > self.link_timeout:
            self._gaps.push(now, now - prev)  # a shorter gap cannot raise the link limit
        self._link_up(now)
        shows = self._shows(r)
        if shows == self._steady and not self.noisy:  # a noisy sensor's quiet is looked for
            return  # (and jumpy readings never leave a steady view: see below)
        before, said = self._evidence(), len(self._out)
        for d in self.devices.values():
            if d.channel < len(r.currents_ma):
                self._device(d, bool(r.on_mask >> d.channel & 1),
                             bool(r.fault_mask >> d.channel & 1), r.currents_ma[d.channel], now)
        # looking at it again (or at one that shows the same) would be as idle as this was
        idle = len(self._out) == said and self._evidence() == before
        # ... unless the readings were jumpy: the same reading is judged once they are not
        jumpy = any(m.jumpy(now) for m in self._noise.values())
        self._steady = shows if idle and not jumpy else None

    def _evidence(self) -> tuple[object, ...]:
        """Everything a reading's rules read and write, but the literals said."""
        return (*[ev.state() for ev in self._ev.values()], *sorted(self.bands.items()))

    def _shows(self, r: Reading) -> tuple[object, ...]:
        """What a reading shows of the devices: all the rules below look at (switches, live
        faults, the band of each switched-on banded device's current)."""
        on, cur = r.on_mask & self._mask, r.currents_ma
        n = len(cur)
        shows: list[object] = [n, on, r.fault_mask & self._mask]
        for ch, low, high in self._banded:  # the partition of ``Device.classify``, inline
            if ch < n and on >> ch & 1:
                amperes = cur[ch] / 1000.0
                shows.append(0 if low <= amperes <= high else 1 if amperes > high else -1)
            else:
                shows.append(None)
        return tuple(shows)

    def _state(self, s: BoardState, now: float) -> None:
        """A STATE answers the host's own request: believed at once, no agreement needed."""
        self._link_up(now)
        for ch in s.channels:
            d = self.by_channel.get(ch.channel)
            if d is None:
                continue
            ev = self._ev[d.name]
            ev.on.force(ch.physical)
            ev.health.force(_health(ch.physical, bool(ch.live_faults)))
            ev.claim = None
            self._switch(d, ch.physical, now)
            self._say(self._atoms[d.name][1], ch.state in _BAD_STATES, now)
            self._doubt(d, bool(ch.live_faults & F_SENSOR), now)
            self._low(d, bool(ch.live_faults & F_LOW), now)

    def _device(self, d: Device, on: bool, fault: bool, current_ma: int, now: float) -> None:
        """One reading of one device's channel: each of its facts counts once it settled."""
        ev = self._ev[d.name]
        if ev.on.add(on) and ev.on.value is not None:
            self._switch(d, ev.on.value, now)
        band = d.classify(current_ma / 1000.0) if d.band is not None and on \
            and d.name not in self.low else None
        meter = self._noise.get(d.name)
        if meter is not None and (turned := meter.add(band, now)) is not None:
            self._noisy(d, turned, now)
        if band is not None and d.name not in self.doubted and d.name not in self.noisy:
            if meter is not None and meter.jumpy(now):
                ev.band.hold()  # jumping across the band: no verdict (host.observers.noise)
            else:
                ev.band.add(band)  # judged: on, sensed, and the sensor not noisy
            if ev.on.value and ev.band.value is not None:
                self.bands[d.name] = ev.band.value
                self._say(self._atoms[d.name][2], ev.band.value == "nominal", now)
        self._health(d, ev, _health(on, fault), now)

    def _switch(self, d: Device, on: bool, now: float) -> None:
        on_atom, _, in_band = self._atoms[d.name]
        self._say(on_atom, on, now)
        if not on:
            self._forget(in_band, now)
            self.bands.pop(d.name, None)
            self._ev[d.name].band.force(None)

    def _health(self, d: Device, ev: _Evidence, sample: str, now: float) -> None:
        ev.health.add(sample)
        atom = self._atoms[d.name][1]
        if ev.claim is None:
            if ev.health.value == CLEAR:
                self._say(atom, False, now)
            return
        if agrees(ev.health.value, ev.claim):
            ev.claim = None
            self._say(atom, True, now)
            return
        ev.clear_since_claim = ev.clear_since_claim + 1 if sample == CLEAR else 0
        if ev.clear_since_claim >= self.settle:
            log.warning("%s: the board reported %s tripped, but %d readings since show it "
                        "without a fault: not believed", self.name, d.name,
                        ev.clear_since_claim)
            ev.claim = None

    def _event(self, e: BoardEvent, now: float) -> None:
        d = self.by_channel.get(e.channel)
        if d is None:
            return
        ev = self._ev[d.name]
        if e.kind == EV_RANGE:  # how the board measures the current, not a state
            self._low(d, bool(e.faults & F_LOW), now)
            return
        if e.kind == EV_FAULT and e.old_state == e.new_state:  # about the sensor, not a state
            self._doubt(d, bool(e.faults & F_SENSOR), now)
            return
        if e.kind == EV_WARNING and e.faults & F_OVERLOAD:
            log.warning("%s: the board holds %s on through an overload (a protected channel "
                        "is never switched off for it): %s draws too much, or its current "
                        "sensor lies", self.name, d.name, d.name)
            return
        if e.kind == EV_TRIP or e.new_state in _BAD_STATES:
            claim = e.new_state if e.new_state in _BAD_STATES else ST_TRIPPED
            if agrees(ev.health.value, claim):  # the readings already show it
                ev.claim = None
                self._say(self._atoms[d.name][1], True, now)
            else:
                ev.claim, ev.clear_since_claim = claim, 0
        elif e.new_state != e.old_state:  # a state change to off, inrush or on
            ev.claim = None
            self._say(self._atoms[d.name][1], False, now)

    def _doubt(self, d: Device, doubted: bool, now: float) -> None:
        """The board doubts (or trusts again) the current sensor of ``d``'s channel: a fault of
        the sensor, not of ``d``, so ``d``'s current is not judged while it lasts
        (``in_band(d)`` retracted: unknown) and is judged afresh when readings return."""
        if doubted == (d.name in self.doubted):
            return
        in_band = self._atoms[d.name][2]
        self._ev[d.name].band.force(None)
        self.bands.pop(d.name, None)
        if doubted:
            self.doubted.add(d.name)
            self._forget(in_band, now)
            log.warning("%s: the board doubts the current sensor of %s's channel %d (sensor "
                        "flag: no reading, current with the switch open, or noise): the sensor is "
                        "suspect, not %s; its current is not judged until the sensor reads "
                        "again", self.name, d.name, d.channel, d.name)
        else:
            self.doubted.discard(d.name)
            log.info("%s: the current sensor of %s's channel %d reads again", self.name,
                     d.name, d.channel)

    def _low(self, d: Device, low: bool, now: float) -> None:
        """The board says ``d``'s current is low, not measured (or measured again): while it
        is, ``d``'s current is unknown (``in_band(d)`` retracted), judged afresh after."""
        if low == (d.name in self.low):
            return
        self._ev[d.name].band.force(None)
        self.bands.pop(d.name, None)
        if low:
            self.low.add(d.name)
            self._forget(self._atoms[d.name][2], now)
            log.info("%s: %s on channel %d draws less than the board's current sense can "
                     "measure: low, not measured (its current is unknown, not judged)",
                     self.name, d.name, d.channel)
        else:
            self.low.discard(d.name)
            log.info("%s: %s's current on channel %d is measured again", self.name, d.name,
                     d.channel)

    def _noisy(self, d: Device, noisy: bool, now: float) -> None:
        """The readings show ``d``'s current sensor noisy (``host.observers.noise``), or quiet
        again: while noisy, ``d``'s current is not judged (``in_band(d)`` unknown)."""
        if noisy:
            self.noisy.add(d.name)
            self._ev[d.name].band.force(None)
            self.bands.pop(d.name, None)
            self._forget(self._atoms[d.name][2], now)
            log.warning("%s: the current sensor of %s's channel %d is noisy (its readings "
                        "jump in and out of the band many times a second): a sensor fault, "
                        "not %s's; its current is not judged until the readings calm down",
                        self.name, d.name, d.channel, d.name)
        else:
            self.noisy.discard(d.name)
            log.info("%s: the current sensor of %s's channel %d is quiet again", self.name,
                     d.name, d.channel)

    # -- the link rule ---------------------------------------------------------------------
    @property
    def link_limit(self) -> float:
        """Seconds without a reading before the link counts as lost (see the module
        docstring): ``link_timeout``, or ``JITTER_GAIN`` times the longest gap seen lately,
        at most ``link_timeout + link_slack``."""
        worst = self._gaps.get(self._last_reading) or 0.0
        return min(self.link_timeout + self.link_slack,
                   max(self.link_timeout, JITTER_GAIN * worst))

    def _link_lost(self, now: float) -> None:
        self._up = False
        self._steady = None
        for atom in list(self._said):
            if atom != self.link_atom:
                self._forget(atom, now)
        self.bands.clear()
        self._ev = {d: self._fresh() for d in self.devices}
        if self.link_atom:
            self._say(self.link_atom, False, now)

    def _check(self, now: float) -> None:
        last = self._last_reading
        if self._up and last is not None and self._confirm.silent(
                now, last + self.link_limit, last + self.link_timeout + self.link_slack):
            self._link_lost(now)

    def _deadline(self) -> float | None:
        if self._up and self._last_reading is not None:
            return self._confirm.deadline(self._last_reading + self.link_limit)
        return None


def _health(on: bool, fault: bool) -> str:
    """What one reading shows of a channel's health."""
    if not fault:
        return CLEAR
    return FAULT_ON if on else FAULT_OFF
