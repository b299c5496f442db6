"""A noisy current sensor: readings that jump across a device's band, faster than any device.

A device's current changes band when the device changes: it hangs, draws too much, drops out —
a few times a second at most (the intermittent ``dropout`` fault: twice a second). A current
sensor that adds noise (``sensor_noise`` in the emulator; a loose shunt, interference on a real
board) makes the readings of a healthy device land inside and outside its band at random, many
times a second; three readings that agree now and then are enough for ``in_band(d)`` to turn
false, and a device that works was power-cycled for its sensor (issue 25, item 7: 30 false
repairs in the campaign).

``NoiseMeter`` counts, per device, the changes of the band the raw readings fall in
(``nominal``, ``over``, ``under``: ``Device.classify``) over the last ``WINDOW_S`` seconds. At
``NOISY_CHANGES`` or more the sensor is *noisy*: the hardware observer then leaves the device's
current unjudged (``in_band(d)`` retracted: unknown, as when the board itself doubts the
sensor) and says that the sensor, not the device, is suspect. It is quiet again after
``QUIET_S`` seconds with at most ``QUIET_CHANGES`` changes. Time is passed in.

Before the meter has counted enough to call the sensor noisy, the first noisy readings can
already agree three times in a row (``under, under, under`` between two ``over``), and
``in_band(d)`` would turn false for the moment it takes the meter to catch up (120 ms seen: a
diagnosis of the device that no repair followed, but a false one). So the readings are
``jumpy`` for ``JUMPY_S`` after one that crossed the whole band from the last (``under`` to
``over`` or back): no band verdict is made from them. A device's current does not do that
from one reading to the next; its own changes go between the band and one side of it (a
hang's or a drop-out's drop, an overload's rise, a spike and back), judged as before.
"""

from __future__ import annotations

from collections import deque

WINDOW_S = 1.0
NOISY_CHANGES = 10  # five times out of the band and back within a second
QUIET_S = 3.0
QUIET_CHANGES = 1
JUMPY_S = 0.2  # after a reading that crossed the whole band: no band verdict for this long


class NoiseMeter:
    def __init__(self, window_s: float = WINDOW_S, noisy: int = NOISY_CHANGES,
                 quiet_s: float = QUIET_S, quiet: int = QUIET_CHANGES) -> None:
        self.window_s = window_s
        self.noisy_changes = noisy
        self.quiet_s = quiet_s
        self.quiet_changes = quiet
        self.noisy = False
        self._since = 0.0  # when it turned noisy
        self._last: str | None = None
        self._crossed: float | None = None  # the latest reading that crossed the whole band
        self._changes: deque[float] = deque()

    def jumpy(self, now: float) -> bool:
        """The latest readings jump across the band (see the module): no verdict from them."""
        return self._crossed is not None and now - self._crossed <= JUMPY_S

    def add(self, band: str | None, now: float) -> bool | None:
        """One reading's raw band (None: not judged, the channel off); returns True when the
        sensor turns noisy, False when it turns quiet again, None when nothing changed."""
        if band is not None and self._last is not None and band != self._last:
            self._changes.append(now)
            if band != "nominal" and self._last != "nominal":  # under <-> over in one reading
                self._crossed = now
        if band is not None:
            self._last = band
        keep = self.quiet_s if self.noisy else self.window_s
        while self._changes and self._changes[0] < now - keep:
            self._changes.popleft()
        if not self.noisy and len(self._changes) >= self.noisy_changes:
            self.noisy, self._since = True, now
            return True
        if self.noisy and now - self._since >= self.quiet_s \
                and len(self._changes) <= self.quiet_changes:
            self.noisy = False
            self._changes.clear()
            return False
        return None
