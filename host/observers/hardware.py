"""The hardware observer (HObs): the board's readings, events and link, as literals.

Input: what ``BoardClient`` hands out (``host.board.types``): ``Reading`` (every channel's
switch read-back and current), ``BoardEvent`` (trips, state changes, faults), ``BoardState``
(the full channel states, which the daemon should feed after connecting and after every
``LinkUp``/``Rebooted``), ``LinkDown``/``LinkUp`` and ``Rebooted``. For each switchable device
``d`` (``Device``: its channel and current band from ``system.yaml``):

- ``on(d)``: the channel's switch reads back on (``Reading.on_mask``, ``ChannelState.physical``);
- ``in_band(d)``: while on, the current lies in the device's band ``[low, high]``; a change of
  band (nominal, over, under — kept in ``bands`` for journals) counts only after ``settle``
  consecutive readings agree, so one noisy sample or an inrush peak does not flip it; while off
  the atom is retracted (a switched-off device has no band to judge);
- ``tripped(d)``: the board's protection tripped, latched or (switch fault) faulted the channel
  (``BoardEvent`` kind trip, or a state change to tripped/latched/faulted; ``¬tripped`` on a
  change to off/inrush/on and from ``BoardState``);
- the link: ``link(board)`` (the atom is configurable, or None to leave it out) while readings
  arrive, ``¬link(board)`` on ``LinkDown`` or after ``link_timeout`` seconds without a reading.
  With the link gone every device literal is *retracted* at once — observations from a lost
  link are unknown, never stale truths — and come back with the next readings. A reboot
  retracts ``tripped`` (the board's channel states started anew) until events or a
  ``BoardState`` tell again.

Detection latency: ``on``/``tripped`` with the first reading or event that shows them (an event
is pushed at once by the board: one link round trip); ``in_band`` after ``settle`` readings
(30 ms at 100 Hz with the default 3); a dead link after ``link_timeout`` (default 0.25 s) or
at once on ``LinkDown``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

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
from host.observers.base import DEFAULT_REFRESH, DEFAULT_VALIDITY, Observer
from protocol.constants import (
    EV_TRIP,
    ST_FAULTED,
    ST_LATCHED,
    ST_TRIPPED,
)

BoardInput = StreamItem | BoardState
DEFAULT_LINK_ATOM = str(A.link("board"))
DEFAULT_LINK_TIMEOUT = 0.25
DEFAULT_SETTLE = 3
_BAD_STATES = (ST_TRIPPED, ST_LATCHED, ST_FAULTED)


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
                 name: str = "hardware", validity: float = DEFAULT_VALIDITY,
                 refresh: float = DEFAULT_REFRESH) -> None:
        super().__init__(name, validity, refresh)
        if link_timeout <= 0 or settle < 1:
            raise ValueError(f"{name}: need link_timeout > 0 and settle >= 1")
        self.devices = dict(devices)
        self.by_channel = {d.channel: d for d in self.devices.values()}
        self.link_timeout = link_timeout
        self.settle = settle
        self.link_atom = link_atom
        self.bands: dict[str, str] = {}  # device -> the settled band (nominal, over, under)
        self._pending: dict[str, tuple[str, int]] = {}  # device -> (candidate band, count)
        self._last_reading: float | None = None
        self._up = False

    def atoms(self) -> list[str]:
        out = [self.link_atom] if self.link_atom else []
        for d in self.devices.values():
            out += [str(A.on(d.name)), str(A.tripped(d.name))]
            if d.band is not None:
                out.append(str(A.in_band(d.name)))
        return out

    # -- inputs ----------------------------------------------------------------------------
    def _feed(self, item: BoardInput, now: float) -> None:
        if isinstance(item, Reading):
            self._reading(item, now)
        elif isinstance(item, BoardEvent):
            self._event(item, now)
        elif isinstance(item, BoardState):
            self._state(item, now)
        elif isinstance(item, LinkDown):
            self._link_lost(now)
        elif isinstance(item, LinkUp):
            self._link_up(now)
        elif isinstance(item, Rebooted):
            for d in self.devices.values():
                self._forget(str(A.tripped(d.name)), now)

    def _link_up(self, now: float) -> None:
        self._up = True
        self._last_reading = now
        if self.link_atom:
            self._say(self.link_atom, True, now)

    def _reading(self, r: Reading, now: float) -> None:
        self._link_up(now)
        for d in self.devices.values():
            if d.channel < len(r.currents_ma):
                self._device(d, bool(r.on_mask >> d.channel & 1), r.currents_ma[d.channel], now)

    def _state(self, s: BoardState, now: float) -> None:
        self._link_up(now)
        for ch in s.channels:
            d = self.by_channel.get(ch.channel)
            if d is not None:
                self._device(d, ch.physical, ch.current_ma, now)
                self._say(str(A.tripped(d.name)), ch.state in _BAD_STATES, now)

    def _device(self, d: Device, on: bool, current_ma: int, now: float) -> None:
        self._say(str(A.on(d.name)), on, now)
        if d.band is None:
            return
        atom = str(A.in_band(d.name))
        if not on:
            self._forget(atom, now)
            self.bands.pop(d.name, None)
            self._pending.pop(d.name, None)
            return
        band = d.classify(current_ma / 1000.0)
        if band == self.bands.get(d.name) and atom in self._said:
            self._pending.pop(d.name, None)
            return
        cand, count = self._pending.get(d.name, (band, 0))
        count = count + 1 if cand == band else 1
        if count >= self.settle:
            self._pending.pop(d.name, None)
            self.bands[d.name] = band
            self._say(atom, band == "nominal", now)
        else:
            self._pending[d.name] = (band, count)

    def _event(self, e: BoardEvent, now: float) -> None:
        d = self.by_channel.get(e.channel)
        if d is None:
            return
        if e.kind == EV_TRIP or e.new_state in _BAD_STATES:
            self._say(str(A.tripped(d.name)), True, now)
        elif e.new_state != e.old_state:  # a state change to off, inrush or on
            self._say(str(A.tripped(d.name)), False, now)

    # -- the link rule ---------------------------------------------------------------------
    def _link_lost(self, now: float) -> None:
        self._up = False
        for atom in list(self._said):
            if atom != self.link_atom:
                self._forget(atom, now)
        self.bands.clear()
        self._pending.clear()
        if self.link_atom:
            self._say(self.link_atom, False, now)

    def _check(self, now: float) -> None:
        if self._up and self._last_reading is not None and (
                now >= self._last_reading + self.link_timeout):
            self._link_lost(now)

    def _deadline(self) -> float | None:
        if self._up and self._last_reading is not None:
            return self._last_reading + self.link_timeout
        return None
