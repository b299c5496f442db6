"""One switched channel: its state machine, written as a table, and its protection rules.

Theory of operation. A channel is in one of six states (``ST_*`` of ``protocol.constants``):

    OFF ──on──► INRUSH ──window over──► ON
     ▲            │ trip                 │ trip (short / I²t)
     │            ▼                      ▼
     └──off── TRIPPED ◄─────────────────┘   (switch off, wait retry_ms[i], then INRUSH)
                  │ trip with no retry left
                  ▼
               LATCHED ──clear──► OFF        FAULTED (switch stuck) ──clear──► OFF

Inputs to the machine are commands (``X_ON``, ``X_OFF``, ``X_CLEAR``, ``X_SHED``) and
detections made by ``step`` every sampling tick (``X_INRUSH_END``, ``X_TRIP``,
``X_TRIP_LATCH``, ``X_RETRY``, ``X_STUCK_ON``, ``X_STUCK_OFF``). ``TRANSITIONS`` maps every
(state, input) pair that can occur to ``(new_state, error)``: an error other than 0 refuses the
command and leaves the channel as it was (switching a latched channel on gives ``E_LATCHED``).
A pair missing from the table is a bug in this module and raises ``KeyError``; ``step`` only
fires detections in the states where the table has them. Entering a state runs its entry
action (``_enter``): INRUSH drives the switch on and opens the inrush window, every other state
except ON drives it off. Self-transitions run no entry action.

Protection, per tick, from the integer current ``ma`` (no floating point on the hot path):
- INRUSH (``inrush_ms``): tolerates up to ``inrush_factor_x10``/10 x rated; above that for
  ``trip_samples`` samples it trips (``F_INRUSH``, handled like a short).
- ON: at or above ``trip_factor_x10``/10 x rated for ``trip_samples`` consecutive samples it
  trips at once (``F_SHORT``). Thermal model (I²t) with r = 100·I/Ir:
  ``heat += (r² - start²)·dt_ms``, clamped at 0, trip (``F_OVERLOAD``) at
  ``i2t_ms``·10⁴; with start = 110 and i2t_ms = 3100 that is ≈3 s at 1.5x, ≈1.1 s at 2x,
  ≈0.4 s at 3x (under the instant trip, 2.9x takes ≈0.43 s); heat cools in every other state.
  A *protected* channel is never switched off by the I²t model (its current may be a lying
  sensor's, and it feeds the computer that runs the host; its fuse guards the wiring): the
  heat is held at the limit and ``F_OVERLOAD`` is live (sticky, an EV_WARNING) until the heat
  falls to half the limit (an EV_WARNING with 0 flags). Only the instant trip switches it off.
- No reading (the HAL reads -1 for a channel whose sensor did not answer: a NACK, a bus held
  low, a wrong chip): ``F_SENSOR`` live and sticky with an EV_FAULT, the switch left as it is,
  every current rule (trips, I²t, open load, stuck on) suspended and the heat held, the
  reported current 0; when readings return, an EV_FAULT with 0 flags and ``F_SENSOR`` live
  cleared (unless an offset doubt below keeps it).
- A fast trip input (the HAL reads ``TRIPPED``: an INA3221's per-conversion CRITICAL limit,
  set through ``hal.set_trip_ma`` to the inrush limit in INRUSH and the trip limit in ON; a
  smart switch's fault level, its own protection having cut the load): in INRUSH or ON a sample
  at the limit for the instant trip (``trip_samples`` of them trip it, with the limit as the
  event's value), the reported current 0, the heat held; in the other states a current of at
  least the limit for the stuck-on rule (a switch stuck on into a short).
- Low, not measured (the HAL reads ``LOW``: below the sensing part's accurate range, as a smart
  switch's current sense is at small loads): the current counts as 0 and the open-load rule
  does not run on it (a small load is not an open one). ``F_LOW`` (not a fault: live only,
  never sticky) tells the host, with an ``EV_RANGE`` event (flags ``F_LOW``) at the first such
  reading, and an ``EV_RANGE`` with 0 flags once ``LOW_CLEAR_SAMPLES`` readings in a row were
  measured (a load at the edge of the range does not flood the event log).
- Retries: after an overload, retry after ``retry_ms[0]``, ``[1]``, ... then latch; after a
  short or inrush trip retry ``short_retries`` times (after ``retry_ms[0]``), then latch. Both
  counters reset after ``retry_reset_ms`` without a fault, or by ``clear``.
- Open load (warning only, ``F_OPEN_LOAD`` live while it lasts): ON with the current below
  ``open_load_ma`` (0: max(20 mA, 1 % of rated)) for ``open_load_ms``.
- Stuck on: not switched on (OFF, TRIPPED, LATCHED) and above ``stuck_on_ma`` for
  ``stuck_on_ms`` → FAULTED. Stuck off: INRUSH or ON and the switch reads back off for
  ``STUCK_OFF_SAMPLES`` samples → FAULTED. FAULTED keeps the switch off until ``clear``.
- A doubtful sensor on a *protected* channel (the computer that runs the host): current above
  ``stuck_on_ma`` for ``stuck_on_ms`` while the switch is off *and reads back open* is not
  a stuck switch but a sensor that lies. The channel is not latched off for it: ``F_SENSOR``
  (live and sticky, and an EV_FAULT) tells the host, the reading with the switch open is kept
  as the sensor's offset and taken off every reading protection uses from then on, and a trip
  or latch that the lying sensor caused is retried (``X_DOUBT``: LATCHED goes back to TRIPPED
  when the channel is wanted on). Reported currents stay the raw readings. ``clear`` forgets
  the offset. Other channels keep the stuck-on rule: off is their safe state.
- A noisy sensor (every channel): a load's current does not jump up and down by half its rating
  from one 10 ms sample to the next many times in a row; a sensor's noise does (``sensor_noise``
  in the emulator, a bad shunt contact). Each channel keeps its latest ``WINDOW`` samples and
  counts the *jumps* among them: two successive samples more than ``jump_ma`` = max(rated/2, 200
  mA) apart, in the direction opposite to the last such move (a swing back; a step is none, even
  one a sensing chip's averaging brings in over several samples, as the INA226 does with a
  short's onset); switching on starts the window anew. From ``SUSPECT_JUMPS`` jumps on,
  protection uses the window's median instead of the sample (the mean would not do: noise adds
  its variance to I², and a sensor that reads at least 0 biases the mean upwards; the median of
  symmetric noise is the true current) and the sample-by-sample instant trip rests (a spike is
  not a short; a real short still trips on the median's I²t: 10x in about 30 ms after the median
  rose, 16 samples; and the part's fast trip input, ``TRIPPED``, still trips at once). At
  ``NOISY_JUMPS`` jumps the sensor is doubtful: ``F_SENSOR`` live and sticky, an EV_FAULT; after
  ``CALM_MS`` with at most one jump in the window, an EV_FAULT with 0 flags and the live flag
  cleared. While the window jumps the stuck-on rule rests too (noise around 0 A would read as
  current through an open switch). A real overload or short is one jump (its onset): it is
  judged on the samples exactly as before, as fast as before. The one case a board cannot tell
  in two samples: when noise starts, its first two samples may both read above the instant trip
  and agree, as a short's do (2 of 300 onsets at 2.4 A on a 1 A channel); the channel trips
  once, and its retry comes with the noise known. Noise of up to 3x the rating (standard
  deviation) neither trips nor latches a channel (the median's own spread still heats the I²t
  model at more); a real 2x overload under it trips in 0.8-2 s.

``live`` faults are conditions present now; ``sticky`` faults accumulate until ``clear``.
"""

from array import array

from firmware.fast import (
    H_ARMED,
    H_AT,
    H_CUR,
    H_JUMP,
    H_OPEN,
    H_PHYS,
    H_RATED,
    H_START2,
    H_STUCK,
    H_TRIP,
    HOT,
)
from firmware.hal import LOW, TRIPPED
from protocol.compat import const
from protocol.constants import (
    E_LATCHED,
    E_SWITCH_FAULT,
    EV_FAULT,
    EV_RANGE,
    EV_STATE,
    EV_TRIP,
    EV_WARNING,
    F_DEADMAN,
    F_INRUSH,
    F_LOW,
    F_OPEN_LOAD,
    F_OVERLOAD,
    F_SENSOR,
    F_SHED_TOTAL,
    F_SHED_UV,
    F_SHORT,
    F_STUCK_OFF,
    F_STUCK_ON,
    ST_FAULTED,
    ST_INRUSH,
    ST_LATCHED,
    ST_OFF,
    ST_ON,
    ST_TRIPPED,
)

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from typing import Any

    from firmware.events import EventLog
    from firmware.hal import Hal

    ChannelConfig = dict[str, Any]  # one channel's entry of the configuration

# inputs of the state machine
X_ON = const(0)
X_OFF = const(1)
X_CLEAR = const(2)
X_SHED = const(3)
X_INRUSH_END = const(4)
X_TRIP = const(5)
X_TRIP_LATCH = const(6)
X_RETRY = const(7)
X_STUCK_ON = const(8)
X_STUCK_OFF = const(9)
X_DOUBT = const(10)  # protected channel: the sensor reads current with the switch open

STUCK_OFF_SAMPLES = const(2)
WINDOW = const(32)  # the latest samples each channel keeps (a power of two): 320 ms at 10 ms
WINDOW_MASK = const(31)
SUSPECT_JUMPS = const(2)  # jumps in the window from which protection takes the median
NOISY_JUMPS = const(12)  # jumps in the window that make the sensor doubtful (F_SENSOR)
CALM_MS = const(1000)  # at most one jump in the window this long: the noise is over
LOW_CLEAR_SAMPLES = const(50)  # measured readings in a row that end F_LOW (0.5 s at 10 ms)
RATIO_CAP = const(1000)  # r = 100·I/Ir is capped at 10x to keep r² a small int
TRIP_LIVE = F_SHORT | F_OVERLOAD | F_INRUSH | F_SHED_TOTAL | F_SHED_UV | F_DEADMAN

# (state, input) -> (new state, error code); 0 = accepted
TRANSITIONS = {
    (ST_OFF, X_ON): (ST_INRUSH, 0),
    (ST_OFF, X_OFF): (ST_OFF, 0),
    (ST_OFF, X_CLEAR): (ST_OFF, 0),
    (ST_OFF, X_SHED): (ST_OFF, 0),
    (ST_OFF, X_STUCK_ON): (ST_FAULTED, 0),
    (ST_INRUSH, X_ON): (ST_INRUSH, 0),
    (ST_INRUSH, X_OFF): (ST_OFF, 0),
    (ST_INRUSH, X_CLEAR): (ST_INRUSH, 0),
    (ST_INRUSH, X_SHED): (ST_OFF, 0),
    (ST_INRUSH, X_INRUSH_END): (ST_ON, 0),
    (ST_INRUSH, X_TRIP): (ST_TRIPPED, 0),
    (ST_INRUSH, X_TRIP_LATCH): (ST_LATCHED, 0),
    (ST_INRUSH, X_STUCK_OFF): (ST_FAULTED, 0),
    (ST_ON, X_ON): (ST_ON, 0),
    (ST_ON, X_OFF): (ST_OFF, 0),
    (ST_ON, X_CLEAR): (ST_ON, 0),
    (ST_ON, X_SHED): (ST_OFF, 0),
    (ST_ON, X_TRIP): (ST_TRIPPED, 0),
    (ST_ON, X_TRIP_LATCH): (ST_LATCHED, 0),
    (ST_ON, X_STUCK_OFF): (ST_FAULTED, 0),
    (ST_TRIPPED, X_ON): (ST_TRIPPED, 0),  # already wanted on: the retry will switch it
    (ST_TRIPPED, X_OFF): (ST_OFF, 0),  # cancels the retry
    (ST_TRIPPED, X_CLEAR): (ST_TRIPPED, 0),  # counters reset, the retry still comes
    (ST_TRIPPED, X_SHED): (ST_OFF, 0),
    (ST_TRIPPED, X_RETRY): (ST_INRUSH, 0),
    (ST_TRIPPED, X_STUCK_ON): (ST_FAULTED, 0),
    (ST_LATCHED, X_ON): (ST_LATCHED, E_LATCHED),
    (ST_LATCHED, X_OFF): (ST_LATCHED, 0),  # stays latched until cleared
    (ST_LATCHED, X_CLEAR): (ST_OFF, 0),
    (ST_LATCHED, X_SHED): (ST_LATCHED, 0),
    (ST_LATCHED, X_STUCK_ON): (ST_FAULTED, 0),
    (ST_FAULTED, X_ON): (ST_FAULTED, E_SWITCH_FAULT),
    (ST_FAULTED, X_OFF): (ST_FAULTED, 0),
    (ST_FAULTED, X_CLEAR): (ST_OFF, 0),
    (ST_FAULTED, X_SHED): (ST_FAULTED, 0),
    (ST_TRIPPED, X_DOUBT): (ST_TRIPPED, 0),  # the retry comes, with the offset taken off
    (ST_LATCHED, X_DOUBT): (ST_TRIPPED, 0),  # latched on a lying sensor: retry instead
}


class Channel:
    """One channel's configuration, state machine and protection. ``log`` is an EventLog."""

    def __init__(self, index: int, hal: "Hal", log: "EventLog", cfg: "ChannelConfig",
                 hot: "Any" = None, win: "Any" = None) -> None:
        # the fields the board's steady pass (firmware.fast.steady) reads and writes: HOT ints
        # and the window; the board hands in slices of its flat arrays, a lone channel owns them
        self.hot = hot if hot is not None else array("i", [0] * HOT)
        self.index = index
        self.hal = hal
        self.log = log
        self.boot_ms = 0
        self.state = ST_OFF
        self.commanded = False
        self.physical = False
        self.current_ma = 0
        self.live = 0
        self.sticky = 0
        self.trips = 0
        self.retries = 0  # overload retries used
        self.short_used = 0  # short retries used
        self.heat = 0
        self.over_n = 0
        self.mismatch_n = 0
        self.deadline = 0  # end of the inrush window, or time of the retry
        self.low_since = -1
        self.stuck_since = -1
        self.last_fault_ms = 0
        self.cycle_at = -1  # power-cycle: switch back on at this time
        self.offset_ma = 0  # protected channel: what the sensor reads with the switch open
        self.open_sum = 0  # readings with the switch open during the stuck-on window
        self.open_n = 0
        self.unread = False  # the sensor gives no readings (the HAL reads -1)
        # the latest samples (a ring; ``hot[H_AT]`` is the next slot)
        self.win = win if win is not None else array("i", [0] * WINDOW)
        self.jumped = bytearray(WINDOW)  # 1 where a sample jumped from the one before
        self.jumps = 0  # the 1s in ``jumped``
        self.fresh = True  # the next sample starts the window anew (no jump from before)
        self.swing = 0  # the way of the last move over jump_ma: 1 up, -1 down, 0 none yet
        self.noisy = False  # the sensor's samples jump: doubtful (F_SENSOR)
        self.calm_since = -1
        self.measured_n = 0  # readings measured in a row while F_LOW is live
        self.cfg = cfg
        self.apply(cfg)

    def apply(self, cfg: "ChannelConfig") -> None:
        """Take a (validated) configuration; precompute the integer limits of the hot path."""
        self.cfg = cfg
        rated = cfg["rated_ma"]
        self.rated = rated
        self.jump_ma = max(rated // 2, 200)
        self.inrush_ms = cfg["inrush_ms"]
        self.inrush_lim = rated * cfg["inrush_factor_x10"] // 10
        self.trip_lim = rated * cfg["trip_factor_x10"] // 10
        self.trip_samples = cfg["trip_samples"]
        s = cfg["overload_start_x100"]
        self.start2 = s * s
        self.heat_max = cfg["i2t_ms"] * 10000
        self.retry_ms = cfg["retry_ms"]
        self.short_retries = cfg["short_retries"]
        self.retry_reset_ms = cfg["retry_reset_ms"]
        ol = cfg["open_load_ma"]
        self.open_ma = ol if ol else max(20, rated // 100)
        self.open_ms = cfg["open_load_ms"]
        self.stuck_on_ma = cfg["stuck_on_ma"]
        self.stuck_on_ms = cfg["stuck_on_ms"]
        self.priority = cfg["priority"]
        self.protected = cfg["protected"]
        h = self.hot
        h[H_ARMED] = 0
        h[H_TRIP] = self.trip_lim
        h[H_RATED] = rated
        h[H_START2] = self.start2
        h[H_OPEN] = self.open_ma
        h[H_JUMP] = self.jump_ma
        h[H_STUCK] = self.stuck_on_ma
        if self.state == ST_ON:
            self._limit(self.trip_lim)

    @property
    def current_ma(self) -> int:
        """The latest reading (raw: no offset taken off), 0 for a code."""
        v: int = self.hot[H_CUR]
        return v

    @current_ma.setter
    def current_ma(self, ma: int) -> None:
        self.hot[H_CUR] = ma

    def arm(self) -> None:
        """After a step: whether the board's steady pass may take the next ones (``hot[H_ARMED]``,
        see ``firmware.fast.steady``): a state in which ``step`` changes nothing but the current
        and the window as long as the sample stays in the limits that pass checks. Anything
        else that changes the channel (``fire``, ``clear``, ``apply``) disarms it."""
        a = 0
        if not (self.unread or self.noisy or self.offset_ma or self.fresh or self.jumps
                or self.heat or self.retries or self.short_used or self.live & F_LOW) \
                and self.heat_max > 0:
            st = self.state
            if st == ST_ON:
                if self.physical and not (self.over_n or self.mismatch_n
                                          or self.live & F_OVERLOAD):
                    if self.low_since < 0:
                        a = 1
                    elif self.live & F_OPEN_LOAD:
                        a = 2
            elif (st == ST_OFF or st == ST_LATCHED or st == ST_FAULTED) \
                    and self.stuck_since < 0 and self.cycle_at < 0:  # noqa: SIM109 (no tuple)
                a = 3
        h = self.hot
        h[H_PHYS] = 1 if self.physical else 0
        h[H_ARMED] = a

    # --- the state machine ------------------------------------------------------------

    def refuses(self, x: int) -> int:
        """The error with which the table would refuse input ``x`` now (0: accepted)."""
        err: int = TRANSITIONS[(self.state, x)][1]
        return err

    def fire(self, x: int, now: int) -> int:
        """Apply input ``x``; returns 0 or the error code that refused it."""
        self.hot[H_ARMED] = 0
        old = self.state
        new, err = TRANSITIONS[(old, x)]
        if err:
            return err
        if new != old:
            self.state = new
            self._enter(new, now)
            self.log.put(EV_STATE, self.index, old, new, self.live,
                         self.current_ma, now - self.boot_ms)
        return 0

    def _enter(self, st: int, now: int) -> None:
        if st == ST_INRUSH:
            self.live &= ~TRIP_LIVE
            self.deadline = now + self.inrush_ms
            self.over_n = 0
            self.mismatch_n = 0
            self.cycle_at = -1
            self._fresh_window()
            self.hal.set_switch(self.index, True)
            self._limit(self.inrush_lim)
        elif st != ST_ON:
            self.hal.set_switch(self.index, False)
            self.low_since = -1
            self.stuck_since = -1
            if self.live & F_OPEN_LOAD:
                self.live &= ~F_OPEN_LOAD
        else:
            self.low_since = -1
            self._limit(self.trip_lim)

    def _limit(self, ma: int) -> None:
        """The current of the instant trip now, for a HAL with a fast trip input."""
        setter = getattr(self.hal, "set_trip_ma", None)
        if setter is not None:
            setter(self.index, ma)

    # --- faults -------------------------------------------------------------------------

    def _trip(self, now: int, flag: int, ma: int) -> None:
        self.trips += 1
        self.live |= flag
        self.sticky |= flag
        self.last_fault_ms = now
        x = X_TRIP_LATCH
        delay = 0
        if flag == F_OVERLOAD:
            if self.retries < len(self.retry_ms):
                delay = self.retry_ms[self.retries]
                self.retries += 1
                x = X_TRIP
        elif self.short_used < self.short_retries:
            delay = self.retry_ms[0] if self.retry_ms else 1000
            self.short_used += 1
            x = X_TRIP
        self.log.put(EV_TRIP, self.index, self.state,
                     ST_TRIPPED if x == X_TRIP else ST_LATCHED, flag, ma, now - self.boot_ms)
        self.fire(x, now)
        self.deadline = now + delay

    def _fault(self, now: int, x: int, flag: int) -> None:
        self.live |= flag
        self.sticky |= flag
        self.last_fault_ms = now
        self.log.put(EV_FAULT, self.index, self.state, ST_FAULTED,
                     flag, self.current_ma, now - self.boot_ms)
        self.fire(x, now)

    def clear(self, now: int) -> int:
        self.hot[H_ARMED] = 0
        err = self.fire(X_CLEAR, now)
        if not err:
            self.sticky = 0
            self.live &= ~(F_STUCK_ON | F_STUCK_OFF | TRIP_LIVE)
            self.retries = 0
            self.short_used = 0
            self.heat = 0
            self.offset_ma = 0
            self.unread = False  # still no readings: the next step tells it again
            self.noisy = False  # still noisy: the next jumps tell it again
            self.calm_since = -1
            self.live &= ~F_SENSOR
        return err

    def _doubt(self, now: int) -> None:
        """A protected channel's sensor reads current with the switch open: keep that as its
        offset, tell the host, and never leave the channel latched off for it."""
        self.offset_ma = self.open_sum // self.open_n if self.open_n else self.current_ma
        self.stuck_since = -1
        self.open_sum = self.open_n = 0
        if not self.live & F_SENSOR:
            self.live |= F_SENSOR
            self.sticky |= F_SENSOR
            self.log.put(EV_FAULT, self.index, self.state, self.state,
                         F_SENSOR, self.current_ma, now - self.boot_ms)
        if self.state == ST_LATCHED and self.commanded:
            self.fire(X_DOUBT, now)
            self.deadline = now + (self.retry_ms[0] if self.retry_ms else 1000)
        elif self.state == ST_TRIPPED:
            self.fire(X_DOUBT, now)

    # --- the protection step, every tick -------------------------------------------------

    def _blind(self, now: int, blind: bool) -> None:
        """The sensor stopped giving readings (``blind``) or gives them again: tell the host
        once each way (EV_FAULT with ``F_SENSOR``, then with 0 flags)."""
        self.unread = blind
        if blind:
            self.live |= F_SENSOR
            self.sticky |= F_SENSOR
            flags = F_SENSOR
        else:
            if not self.offset_ma and not self.noisy:  # a known offset keeps the doubt
                self.live &= ~F_SENSOR
            flags = 0
        self.log.put(EV_FAULT, self.index, self.state, self.state,
                     flags, 0, now - self.boot_ms)

    def _noisy(self, now: int, noisy: bool) -> None:
        """The sensor's samples jump (``noisy``) or have calmed down: tell the host once each
        way (EV_FAULT with ``F_SENSOR``, then with 0 flags)."""
        self.noisy = noisy
        self.calm_since = -1
        if noisy:
            self.live |= F_SENSOR
            self.sticky |= F_SENSOR
            flags = F_SENSOR
        else:
            if not self.offset_ma and not self.unread:
                self.live &= ~F_SENSOR
            flags = 0
        self.log.put(EV_FAULT, self.index, self.state, self.state,
                     flags, self.current_ma, now - self.boot_ms)

    def _sample(self, now: int, ma: int) -> bool:
        """Keep sample ``ma`` in the window and judge the sensor's noise; True when the window
        jumps (protection then uses its median)."""
        hot = self.hot
        at = hot[H_AT]
        d = ma - self.win[(at - 1) & WINDOW_MASK]
        j = 0
        if (d > self.jump_ma or -d > self.jump_ma) and not self.fresh:
            way = 1 if d > 0 else -1
            if self.swing and way != self.swing:
                j = 1  # a swing back: noise, not a step
            self.swing = way
        self.fresh = False
        self.jumps += j - self.jumped[at]
        self.jumped[at] = j
        self.win[at] = ma
        hot[H_AT] = (at + 1) & WINDOW_MASK
        n = self.jumps
        if n >= NOISY_JUMPS:
            self.calm_since = -1
            if not self.noisy:
                self._noisy(now, True)
        elif self.noisy:
            if n > 1:
                self.calm_since = -1
            elif self.calm_since < 0:
                self.calm_since = now
            elif now - self.calm_since >= CALM_MS:
                self._noisy(now, False)
        return self.noisy or n >= SUSPECT_JUMPS

    def _fresh_window(self) -> None:
        """Switched on: the jumps counted so far are forgotten, the next sample starts anew."""
        self.fresh = True
        self.swing = 0
        self.jumps = 0
        for i in range(WINDOW):
            self.jumped[i] = 0

    def _median(self) -> int:
        m: int = sorted(self.win)[WINDOW // 2]
        return m
    def _low(self, now: int, low: bool, ma: int) -> None:
        """The current fell below the sensing part's accurate range (``low``), or has been
        measured ``LOW_CLEAR_SAMPLES`` times in a row: ``F_LOW`` live or not, and an EV_RANGE."""
        if low:
            self.live |= F_LOW
        else:
            self.live &= ~F_LOW
        self.log.put(EV_RANGE, self.index, self.state, self.state,
                     F_LOW if low else 0, ma, now - self.boot_ms)

    def _overload(self, now: int, ma: int) -> None:
        """A protected channel's I²t model says overload: it is not switched off for it (the
        computer it feeds; its fuse guards the wiring): held at the limit and told once."""
        self.heat = self.heat_max
        if not self.live & F_OVERLOAD:
            self.live |= F_OVERLOAD
            self.sticky |= F_OVERLOAD
            self.log.put(EV_WARNING, self.index, self.state,
                         self.state, F_OVERLOAD, ma, now - self.boot_ms)

    def step(self, now: int, ma: int, sw: bool, dt: int) -> None:
        blind = False  # no reading: the sensor did not answer (see the module docstring)
        tripped = False  # the sensing part's fast trip input fired
        low = False  # below the sensing part's accurate range
        if ma < 0:
            if ma == TRIPPED:
                tripped = True
            elif ma == LOW:
                low = True
            else:
                blind = True  # NO_READING
            ma = 0
        if blind != self.unread:
            self._blind(now, blind)
        if low:
            self.measured_n = 0
            if not self.live & F_LOW:
                self._low(now, True, 0)
        elif self.live & F_LOW:
            self.measured_n += 1
            if self.measured_n >= LOW_CLEAR_SAMPLES:
                self._low(now, False, ma)
        self.current_ma = ma
        self.physical = sw
        if tripped:  # at least the limit the part compared with, for every rule below
            ma = self.inrush_lim if self.state == ST_INRUSH else self.trip_lim
        if self.offset_ma:  # protection uses the reading without the sensor's known offset
            ma = ma - self.offset_ma if ma > self.offset_ma else 0
        jumpy = False  # the window jumps: protection takes its median, no instant trip
        if not (blind or tripped or low):
            jumpy = self._sample(now, ma)
            if jumpy:
                ma = self._median()
        st = self.state
        if st == ST_ON or st == ST_INRUSH:  # noqa: SIM109 (no tuple built on the hot path)
            if not sw:
                self.mismatch_n += 1
                if self.mismatch_n >= STUCK_OFF_SAMPLES:
                    self._fault(now, X_STUCK_OFF, F_STUCK_OFF)
                    return
            else:
                self.mismatch_n = 0
            if blind or jumpy:
                self.over_n = 0
            elif ma >= (self.inrush_lim if st == ST_INRUSH else self.trip_lim):
                self.over_n += 1
                if self.over_n >= self.trip_samples:
                    self._trip(now, F_INRUSH if st == ST_INRUSH else F_SHORT, ma)
                    return
            else:
                self.over_n = 0
            if st == ST_INRUSH:
                if now >= self.deadline:
                    self.fire(X_INRUSH_END, now)
                return
            if blind or tripped:  # the thermal model holds its heat until readings come back
                return
            r = ma * 100 // self.rated
            if r > RATIO_CAP:
                r = RATIO_CAP
            h = self.heat + (r * r - self.start2) * dt
            self.heat = h if h > 0 else 0
            if h >= self.heat_max:
                if not self.protected:
                    self._trip(now, F_OVERLOAD, ma)
                    return
                self._overload(now, ma)
            elif self.live & F_OVERLOAD and h <= self.heat_max // 2:
                self.live &= ~F_OVERLOAD  # cooled: the warning is over
                self.log.put(EV_WARNING, self.index, st, st, 0,
                             ma, now - self.boot_ms)
            if low:
                self.low_since = -1  # low, not measured: no open-load judgement
            elif ma < self.open_ma:
                if self.low_since < 0:
                    self.low_since = now
                elif now - self.low_since >= self.open_ms and not self.live & F_OPEN_LOAD:
                    self.live |= F_OPEN_LOAD
                    self.sticky |= F_OPEN_LOAD
                    self.log.put(EV_WARNING, self.index, st, st,
                                 F_OPEN_LOAD, ma, now - self.boot_ms)
            elif self.low_since >= 0:
                self.low_since = -1
                if self.live & F_OPEN_LOAD:
                    self.live &= ~F_OPEN_LOAD
                    self.log.put(EV_FAULT, self.index, st, st, 0,
                                 ma, now - self.boot_ms)
        else:
            if self.heat:
                h = self.heat - self.start2 * dt
                self.heat = h if h > 0 else 0
            if st != ST_FAULTED:
                if jumpy:  # a noisy sensor cannot tell a switch stuck on: not judged
                    self.stuck_since = -1
                elif ma > self.stuck_on_ma:
                    if self.stuck_since < 0:
                        self.stuck_since = now
                        self.open_sum = self.open_n = 0
                    self.open_sum += self.current_ma
                    self.open_n += 1
                    if now - self.stuck_since >= self.stuck_on_ms:
                        if self.protected and not sw:
                            self._doubt(now)
                        else:
                            self._fault(now, X_STUCK_ON, F_STUCK_ON)
                            return
                else:
                    self.stuck_since = -1
                if st == ST_TRIPPED:
                    if now >= self.deadline:
                        self.fire(X_RETRY, now)
                    return
                if self.cycle_at >= 0 and now >= self.cycle_at:
                    self.cycle_at = -1
                    if st == ST_OFF:
                        self.commanded = True
                        self.fire(X_ON, now)
                    return
        if (self.retries or self.short_used) and now - self.last_fault_ms >= self.retry_reset_ms \
                and st != ST_LATCHED and st != ST_FAULTED:
            self.retries = 0
            self.short_used = 0
