"""The board: its channels, the board-level rules, the commands and the status.

``Board(hal, factory)`` then ``boot(now_ms)`` loads the configuration (``config``: the newest
good stored copy, else ``factory``, the configuration built into the firmware, so that a board
whose stored configuration is lost still powers and protects the computer it feeds), counts
watchdog resets (``bootlog``), logs ``EV_REBOOT`` and queues the power-up set.
``tick(now_ms)`` runs one protection step and never waits for anything: it samples every
channel's current and switch, steps each ``Channel`` (inrush, instant trip, I²t, retries,
open load, stuck switch), then the board rules:

- power-up and restore queue: channels switch on one at a time in priority order (lower
  ``priority`` first), ``powerup_spacing_ms`` apart; used at boot and after under-voltage.
- total current: above ``total_limit_ma`` (0 = off) for ``TOTAL_SAMPLES`` samples the
  non-protected channel with the highest ``priority`` number is shed (``F_SHED_TOTAL``), one per
  step until under the limit; shed channels stay off until commanded on again.
- input under-voltage, levels warn < shed < off (thresholds 0 = disabled): a level is entered
  after ``UV_SAMPLES`` samples below its threshold and left after ``UV_RECOVER_MS`` at or above
  threshold + ``uv_hyst_mv``. warn only warns; shed switches off every non-protected channel;
  off switches off everything, protected channels included (the battery comes first). Channels
  shed by under-voltage (``F_SHED_UV``) come back through the queue when the voltage recovers,
  and switching one on is refused with ``E_INHIBITED`` while the level forbids it.
- host dead-man (``deadman_ms`` > 0): without ``host_seen`` for that long, every channel that
  is neither protected nor in ``deadman_on_mask`` is switched off (``F_DEADMAN``).
- safe mode: after ``bootlog.SAFE_AFTER`` watchdog resets in a row only protected channels come
  on at power-up (``B_SAFE_MODE``, config status ``CFG_SAFE_MODE``).

Commands return ``(error, state, physical)`` for a channel (error 0 or an ``E_*``; a refused
command changes nothing) or an error code for the board. ``status()`` returns
``(board, channels)``: board = ``(input_mv, total_ma, uptime_ms, reset_cause, config_status,
board_flags)``, each channel = ``(commanded, physical, state, current_ma, live_faults,
sticky_faults, trips, retries)`` (indices ``S_*`` and ``C_*`` below). Events go to
``self.events`` (an ``EventLog``; see ``events.py`` for how front ends drain it).
"""

from array import array

from firmware import bootlog, config
from firmware.channel import WINDOW, X_OFF, X_ON, X_SHED, Channel
from firmware.events import EventLog
from firmware.fast import HOT, steady
from protocol.compat import const
from protocol.constants import (
    B_DEADMAN,
    B_OVER_TOTAL,
    B_SAFE_MODE,
    B_UV_OFF,
    B_UV_SHED,
    B_UV_WARN,
    BOARD_CHANNEL,
    CFG_SAFE_MODE,
    E_BAD_CHANNEL,
    E_BAD_VALUE,
    E_INHIBITED,
    E_LATCHED,
    E_PROTECTED,
    E_STORAGE,
    EV_REBOOT,
    EV_SHED,
    EV_WARNING,
    F_DEADMAN,
    F_SHED_TOTAL,
    F_SHED_UV,
    ST_INRUSH,
    ST_LATCHED,
    ST_OFF,
    ST_ON,
    ST_TRIPPED,
)
from protocol.settings import BOARD_WIRE_KEYS, merge

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from typing import Any

    from firmware.config import Config
    from firmware.hal import Hal

    Reply = tuple[int, int, bool]  # a channel command's (error, state, physical)
    BoardRow = tuple[int, int, int, int, int, int]  # board_status(), indices S_*
    ChannelRow = tuple[bool, bool, int, int, int, int, int, int]  # channel_status(), C_*

TOTAL_SAMPLES = const(2)
UV_SAMPLES = const(3)
UV_RECOVER_MS = const(1000)
MAX_CYCLE_MS = const(600000)
SHED_FLAGS = F_SHED_TOTAL | F_SHED_UV | F_DEADMAN

# indices into status() tuples
S_INPUT_MV = const(0)
S_TOTAL_MA = const(1)
S_UPTIME_MS = const(2)
S_RESET_CAUSE = const(3)
S_CONFIG_STATUS = const(4)
S_FLAGS = const(5)
C_COMMANDED = const(0)
C_PHYSICAL = const(1)
C_STATE = const(2)
C_CURRENT_MA = const(3)
C_LIVE = const(4)
C_STICKY = const(5)
C_TRIPS = const(6)
C_RETRIES = const(7)


class Board:
    def __init__(self, hal: "Hal", factory: "Config | None" = None,
                 log_size: int = 64) -> None:
        self.hal = hal
        self.n = hal.n_channels
        self.factory = factory
        self.events = EventLog(log_size)
        self.samples = array("i", [0] * self.n)
        self.sws = array("i", [0] * self.n)  # the switches read back, 1/0
        self.acc = array("i", [0, 0])  # the steady pass's sums: all samples, steady ON ones
        # every channel's hot fields and noise window, flat (firmware.fast.steady)
        self.hot = array("i", [0] * (HOT * self.n))
        self.win = array("i", [0] * (WINDOW * self.n))
        self.channels: "list[Channel]" = []
        self.cfg: "Config" = {}
        self.cfg_status = 0
        self.reset_cause = 0
        self.flags = 0
        self.boot_ms = 0
        self.now = 0
        self.last = 0
        self.input_mv = 0
        self.total_ma = 0
        self.wdt_resets = 0
        self.queue: "list[int]" = []
        self.queue_at = 0
        self.total_n = 0
        self.uv_level = 0
        self.uv_n = 0
        self.uv_since = -1
        self.host_ms = 0
        self.reboot_pending = False
        # the HAL's batch read of the switches, if it has one (looked up once, not per tick)
        self.hal_read_switches = getattr(hal, "read_switches", None)
        # and the two reads every tick makes, bound once: a method looked up on an object
        # with many attributes costs a miss in its attribute map first, at every call
        self.hal_read_currents = hal.read_currents_ma
        self.hal_read_input_mv = hal.read_input_mv
        # the board rules' settings as the tick reads them, from cfg["board"] (_board_rules:
        # at boot and by set_board_config, its only writers)
        self.total_limit_ma = 0
        self.uv_on = False
        self.deadman_ms = 0
        self.deadman_mask = 0
        self.halted = False
        self.boot_id = 0

    # --- boot -------------------------------------------------------------------------

    def boot(self, now: int) -> None:
        hal = self.hal
        self.boot_ms = self.now = self.last = self.host_ms = now
        cfg, status = config.load(hal.storage, self.n)
        if cfg is None:
            cfg = self.factory_config()
        self.cfg = cfg
        self._board_rules()
        self.cfg_status = status
        self.reset_cause = hal.reset_cause()
        self.boot_id = int.from_bytes(hal.random_bytes(4), "big")
        self.wdt_resets = bootlog.on_boot(hal.storage, self.reset_cause)
        safe = self.wdt_resets >= bootlog.SAFE_AFTER
        if safe:
            self.flags |= B_SAFE_MODE
            self.cfg_status = CFG_SAFE_MODE
        self.channels = []
        hot, win = memoryview(self.hot), memoryview(self.win)
        for i in range(self.n):
            ch = Channel(i, hal, self.events, cfg["channels"][i],
                         hot[i * HOT:(i + 1) * HOT], win[i * WINDOW:(i + 1) * WINDOW])
            ch.boot_ms = now
            hal.set_switch(i, False)
            self.channels.append(ch)
        self.events.put(EV_REBOOT, BOARD_CHANNEL, self.reset_cause, self.cfg_status,
                        self.flags, 0, 0)
        for ch in self.channels:
            if ch.protected if safe else ch.cfg["powerup"]:
                ch.commanded = True
                self._enqueue(ch.index)
        self.queue_at = now
        # what every tick reads, in one load (on the M0+ each attribute of an object of this
        # size costs some 180 instructions): fixed from here on (the channels are made above)
        self.tick_refs = (self.samples, self.hal_read_currents, self.sws,
                          self.hal_read_switches, self.acc, self.hot, self.win, self.n,
                          self.channels, self.hal_read_input_mv)

    def factory_config(self) -> "Config":
        """The configuration built into the firmware (``factory``: the one the board was
        flashed with, its key and its protected boot channel included), used when no good copy
        is stored; without one (or a bad one), the defaults of ``protocol.settings``."""
        if self.factory is not None:
            cfg: "Config | None" = merge(self.factory, self.n, config.VERSION)[0]
            if cfg is not None:
                return cfg
        return config.defaults(self.n)

    def _enqueue(self, i: int) -> None:
        if i in self.queue:
            return
        self.queue.append(i)
        chans = self.channels
        self.queue.sort(key=lambda j: chans[j].priority * 256 + j)

    # --- the protection step -----------------------------------------------------------

    def tick(self, now: int) -> None:
        if self.halted:
            return
        if self.reboot_pending:
            self.halted = True
            self.hal.reboot()
            return
        dt = now - self.last
        self.last = self.now = now
        (samples, read_currents, sws, read_switches, acc, hot, win, n, chans,
         read_input_mv) = self.tick_refs
        read_currents(samples)
        swl = None
        if read_switches is not None:  # 1/0 into sws, each as read_switch's bool
            read_switches(sws)
        else:  # a HAL without it: read_switch's values as they are, for the full step
            swl = self._read_switch_values(sws)
        # the steady channels in one pass (firmware.fast); the others in full, in order
        mask = steady(hot, win, samples, sws, n, dt, acc)
        total = acc[0]
        live = acc[1]  # the current of channels still switched on after this step
        i = 0
        while mask:
            if mask & 1:
                ch = chans[i]
                ma = samples[i]  # < 0: a code (no reading, tripped, low: firmware.hal)
                ch.step(now, ma, swl[i] if swl is not None else sws[i] != 0, dt)
                ch.arm()
                if ma > 0:
                    st = ch.state
                    if st == ST_ON or st == ST_INRUSH:  # noqa: SIM109 (no tuple)
                        live += ma
            mask >>= 1
            i += 1
        self.total_ma = total
        self.input_mv = read_input_mv()
        if self.queue and now >= self.queue_at:
            self._run_queue(now)
        limit = self.total_limit_ma
        # a channel that tripped in this step no longer counts; under the limit and not over
        # it last time (B_OVER_TOTAL: set while total_n counts), the rule has nothing to do:
        # the usual tick makes no call
        if limit and (live > limit or self.flags & B_OVER_TOTAL):
            self._total_rule(now, live, limit)
        if self.uv_on:
            self._uv_rule(now, self.input_mv, self.cfg["board"])
        dm = self.deadman_ms
        if dm and not self.flags & B_DEADMAN and now - self.host_ms >= dm:
            self._deadman(now, self.deadman_mask)
        if self.wdt_resets and now - self.boot_ms >= bootlog.STABLE_MS:
            self.wdt_resets = 0
            bootlog.mark_stable(self.hal.storage)

    def _read_switch_values(self, sws: "Any") -> "list[Any]":
        """Each switch as ``hal.read_switch`` reads it, and 1/0 into ``sws`` (a HAL without
        ``read_switches``). A method of its own: in ``tick``, the comprehension's use of
        ``read_switch`` made that a cell, allocated on the heap at every tick, on every HAL."""
        read_switch = self.hal.read_switch
        swl = [read_switch(i) for i in range(self.n)]
        for i in range(self.n):
            sws[i] = 1 if swl[i] else 0
        return swl

    def _board_rules(self) -> None:
        """The settings of the board rules the tick checks, from ``cfg["board"]``."""
        b = self.cfg["board"]
        self.total_limit_ma = b["total_limit_ma"]
        self.uv_on = bool(b["uv_warn_mv"] or b["uv_shed_mv"] or b["uv_off_mv"])
        self.deadman_ms = b["deadman_ms"]
        self.deadman_mask = b["deadman_on_mask"]

    def _run_queue(self, now: int) -> None:
        while self.queue:
            ch = self.channels[self.queue.pop(0)]
            if ch.state != ST_OFF or not ch.commanded or self._inhibited(ch):
                continue  # nothing to do for this one: take the next without waiting
            ch.fire(X_ON, now)
            self.queue_at = now + self.cfg["board"]["powerup_spacing_ms"]
            return

    def _shed(self, ch: "Channel", now: int, flag: int) -> None:
        ch.live |= flag
        ch.sticky |= flag
        self.events.put(EV_SHED, ch.index, ch.state, ST_OFF, flag, ch.current_ma,
                        now - self.boot_ms)
        ch.fire(X_SHED, now)

    def _total_rule(self, now: int, total: int, limit: int) -> None:
        if total <= limit:
            self.total_n = 0
            self.flags &= ~B_OVER_TOTAL
            return
        self.flags |= B_OVER_TOTAL
        self.total_n += 1
        if self.total_n < TOTAL_SAMPLES:
            return
        self.total_n = 0
        victim = None
        for ch in self.channels:
            if ch.protected or (ch.state != ST_ON and ch.state != ST_INRUSH):
                continue
            if victim is None or ch.priority >= victim.priority:
                victim = ch
        if victim is not None:
            self._shed(victim, now, F_SHED_TOTAL)

    def _uv_rule(self, now: int, mv: int, b: "Config") -> None:
        thr = (b["uv_warn_mv"], b["uv_shed_mv"], b["uv_off_mv"])
        bad = 0
        for i in range(3):
            if thr[i] and mv < thr[i]:
                bad = i + 1
        lvl = self.uv_level
        if bad > lvl:
            self.uv_since = -1
            self.uv_n += 1
            if self.uv_n >= UV_SAMPLES:
                self.uv_n = 0
                self._uv_enter(now, bad, mv)
            return
        self.uv_n = 0
        if lvl == 0:
            return
        good = 0
        hyst = b["uv_hyst_mv"]
        for i in range(3):
            if thr[i] and mv < thr[i] + hyst:
                good = i + 1
        if good >= lvl:
            self.uv_since = -1
            return
        if self.uv_since < 0:
            self.uv_since = now
        elif now - self.uv_since >= UV_RECOVER_MS:
            self.uv_since = -1
            self._uv_enter(now, good, mv)

    def _uv_enter(self, now: int, lvl: int, mv: int) -> None:
        self.uv_level = lvl
        self.flags &= ~(B_UV_WARN | B_UV_SHED | B_UV_OFF)
        if lvl >= 1:
            self.flags |= B_UV_WARN
        if lvl >= 2:
            self.flags |= B_UV_SHED
        if lvl >= 3:
            self.flags |= B_UV_OFF
        self.events.put(EV_WARNING, BOARD_CHANNEL, 0, 0, self.flags, mv, now - self.boot_ms)
        for ch in self.channels:
            if ch.state == ST_ON or ch.state == ST_INRUSH or ch.state == ST_TRIPPED:
                if lvl >= 3 or (lvl == 2 and not ch.protected):
                    self._shed(ch, now, F_SHED_UV)
            elif ch.state == ST_OFF and ch.live & F_SHED_UV and ch.commanded \
                    and not self._inhibited(ch):
                self._enqueue(ch.index)

    def _inhibited(self, ch: "Channel") -> bool:
        return self.uv_level >= 3 or (self.uv_level == 2 and not ch.protected)

    def _deadman(self, now: int, mask: int) -> None:
        self.flags |= B_DEADMAN
        self.events.put(EV_WARNING, BOARD_CHANNEL, 0, 0, self.flags, self.input_mv,
                        now - self.boot_ms)
        for ch in self.channels:
            if ch.protected or mask & (1 << ch.index) or ch.state == ST_OFF:
                continue
            if ch.state == ST_ON or ch.state == ST_INRUSH or ch.state == ST_TRIPPED:
                ch.commanded = False
                self._shed(ch, now, F_DEADMAN)

    # --- commands ----------------------------------------------------------------------

    def host_seen(self, now: int) -> None:
        """A front end got a valid, authenticated message from the host: restart the dead-man."""
        self.host_ms = now
        self.flags &= ~B_DEADMAN

    def _ch(self, ch: object) -> "Channel | None":
        if isinstance(ch, int) and not isinstance(ch, bool) and 0 <= ch < self.n:
            return self.channels[ch]
        return None

    def _reply(self, err: int, c: "Channel | None") -> "Reply":
        if c is None:
            return err, 0, False
        return err, c.state, self.hal.read_switch(c.index)

    def check_switch(self, ch: int, on: bool, force: bool = False) -> int:
        """The error ``switch`` would answer now (0: it would act); changes nothing, so that a
        command on several channels can be refused whole before any of them moves."""
        c = self._ch(ch)
        if c is None:
            return E_BAD_CHANNEL
        if not isinstance(on, bool):
            return E_BAD_VALUE
        if on:
            return E_INHIBITED if self._inhibited(c) else c.refuses(X_ON)
        if c.protected and not force and c.state != ST_OFF and c.state != ST_LATCHED:
            return E_PROTECTED
        return c.refuses(X_OFF)

    def switch(self, ch: int, on: bool, force: bool = False) -> "Reply":
        """Switch a channel on or off: ``(error, state, physical)``."""
        err = self.check_switch(ch, on, force)
        c = self._ch(ch)
        if err or c is None:
            return self._reply(err, c)
        if on:
            c.fire(X_ON, self.now)
            c.commanded = True
            c.cycle_at = -1
            c.live &= ~SHED_FLAGS
            return self._reply(0, c)
        c.fire(X_OFF, self.now)
        c.commanded = False
        c.cycle_at = -1
        c.live &= ~SHED_FLAGS
        if ch in self.queue:
            self.queue.remove(ch)
        return self._reply(0, c)

    def power_cycle(self, ch: int, off_ms: int, force: bool = False) -> "Reply":
        """Switch off now and on again ``off_ms`` later: ``(error, state, physical)``."""
        c = self._ch(ch)
        if c is None:
            return self._reply(E_BAD_CHANNEL, c)
        if not isinstance(off_ms, int) or isinstance(off_ms, bool) \
                or not 0 <= off_ms <= MAX_CYCLE_MS:
            return self._reply(E_BAD_VALUE, c)
        if c.protected and not force:
            return self._reply(E_PROTECTED, c)
        if c.state == ST_LATCHED:
            return self._reply(E_LATCHED, c)
        if self._inhibited(c):
            return self._reply(E_INHIBITED, c)
        err = c.fire(X_OFF, self.now)
        if not err:
            c.live &= ~SHED_FLAGS
            c.commanded = True
            c.cycle_at = self.now + off_ms
        return self._reply(err, c)

    def clear(self, ch: int) -> "Reply":
        """Clear a channel's sticky faults and retry counters; unlatch it: ``(error, ...)``."""
        if ch == BOARD_CHANNEL:
            for each in self.channels:
                each.clear(self.now)
            return self._reply(0, None)
        c = self._ch(ch)
        if c is None:
            return self._reply(E_BAD_CHANNEL, c)
        if c.state == ST_LATCHED:
            c.commanded = False
        return self._reply(c.clear(self.now), c)

    def get_channel_config(self, ch: int) -> "tuple[int, Any]":  # (error, None) or (0, Config)
        """``(error, fields)``: a copy of the channel's configuration."""
        c = self._ch(ch)
        if c is None:
            return E_BAD_CHANNEL, None
        return 0, dict(c.cfg)

    def set_channel_config(self, ch: int, fields: "Config") -> int:
        """Change some fields of a channel's configuration (in RAM; ``save_config`` persists)."""
        c = self._ch(ch)
        if c is None:
            return E_BAD_CHANNEL
        if config.check_channel(fields) is not None:
            return E_BAD_VALUE
        new = dict(c.cfg)
        new.update(fields)
        self.cfg["channels"][ch] = new
        c.apply(new)
        return 0

    def get_board_config(self) -> "Config":
        """A copy of the board configuration as BOARD_CONFIG carries it: never the key (which
        never leaves the board) nor the listen address."""
        b = self.cfg["board"]
        out = {}
        for name in BOARD_WIRE_KEYS:
            out[name] = b[name]
        out["modbus_allow"] = list(out["modbus_allow"])
        return out

    def set_board_config(self, fields: "Config") -> int:
        if config.check_board(fields) is not None:
            return E_BAD_VALUE
        self.cfg["board"].update(fields)
        self._board_rules()
        return 0

    def save_config(self) -> int:
        try:
            config.save(self.hal.storage, self.cfg)
        except OSError:
            return E_STORAGE
        return 0

    def request_reboot(self) -> int:
        """Reboot at the next tick (after the reply to this command has gone out)."""
        self.reboot_pending = True
        return 0

    # --- status ------------------------------------------------------------------------

    def board_status(self) -> "BoardRow":
        return (self.input_mv, self.total_ma, self.now - self.boot_ms, self.reset_cause,
                self.cfg_status, self.flags)

    def channel_status(self, ch: int) -> "ChannelRow":
        c = self.channels[ch]
        return (c.commanded, c.physical, c.state, c.current_ma, c.live, c.sticky, c.trips,
                c.retries + c.short_used)

    def status(self) -> "tuple[BoardRow, list[ChannelRow]]":
        return self.board_status(), [self.channel_status(i) for i in range(self.n)]

