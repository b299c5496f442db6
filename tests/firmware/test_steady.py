"""The tick's steady pass (``firmware.fast.steady``, viper on the board) against the full step:
two boards fed the same world, one ticking as shipped, the other with every channel stepped in
full (``Channel.step``); after every tick every channel's fields, window and counters, the
board's totals and its event log must be the same. Both interpreters (MicroPython runs the
viper code itself; CPython the same source as plain Python).

The world changes each channel's regime now and then (steady load, noise, overload, open load,
the HAL's codes, stuck-on current with the switch off, spikes), glitches a read-back, and sends
commands (on, off, power cycle, clear): what makes a channel leave the steady state and come
back. The pass must have taken a good share of the channel-ticks (the comparison is not empty),
and a pass with a planted fault (a sample not kept in the window) must be caught.
"""

import unittest

from firmware import board as board_mod
from firmware.board import Board
from firmware.fast import H_ARMED, H_AT
from firmware.hal.storage import MemStorage

FIELDS = ("state", "live", "sticky", "trips", "retries", "short_used", "heat", "over_n",
          "mismatch_n", "current_ma", "physical", "jumps", "swing", "fresh", "low_since",
          "stuck_since", "noisy", "calm_since", "measured_n", "deadline", "cycle_at",
          "offset_ma", "unread", "commanded", "open_sum", "open_n", "last_fault_ms")
N = 10
TICKS = 1500
SHIPPED = board_mod.steady


def full_step(hot, win, samples, sws, n, dt, acc):
    """No channel steady: every one to ``Channel.step`` (the sums as ``Board.tick`` needs)."""
    total = 0
    for i in range(n):
        if samples[i] > 0:
            total += samples[i]
    acc[0] = total
    acc[1] = 0
    return (1 << n) - 1


def forgetful(hot, win, samples, sws, n, dt, acc):
    """The shipped pass with a planted fault: channel 0's sample not kept in its window."""
    at = hot[H_AT]
    old = win[at]
    mask = SHIPPED(hot, win, samples, sws, n, dt, acc)
    if hot[H_ARMED] and not mask & 1:
        win[at] = old
    return mask


class Rng:
    """A small LCG: the same draws on both interpreters."""

    def __init__(self, seed):
        self.s = seed

    def r(self, n):
        self.s = (self.s * 1103515245 + 12345) & 0x7FFFFFFF
        return (self.s >> 8) % n


class World:
    """The HAL both boards read: currents, switches (a read-back may glitch), the rest fixed."""

    def __init__(self, batch):
        self.n_channels = N
        self.storage = MemStorage()
        self.sw = [False] * N
        self.cur = [0] * N
        self.glitch = [False] * N
        if batch:  # the target HAL's batch read; without it the board asks channel by channel
            self.read_switches = self._read_switches

    def ticks_ms(self):
        return 0

    def read_currents_ma(self, out):
        for i in range(N):
            out[i] = self.cur[i]

    def read_current_ma(self, ch):
        return self.cur[ch]

    def set_switch(self, ch, on):
        self.sw[ch] = on

    def read_switch(self, ch):
        return self.sw[ch] != self.glitch[ch]

    def _read_switches(self, out):
        for i in range(N):
            out[i] = 1 if self.read_switch(i) else 0

    def read_input_mv(self):
        return 24000

    def wdt_feed(self):
        pass

    def reset_cause(self):
        return 4

    def random_bytes(self, n):
        return bytes(n)

    def reboot(self):
        pass


def snapshot(b):
    out = [b.total_ma, b.flags, b.events.seq, b.events.read(0, 64)]
    for ch in b.channels:
        out.append([getattr(ch, f) for f in FIELDS]
                   + [ch.hot[H_AT], list(ch.win), list(ch.jumped)])
    return out


def rated(i):
    return 1000 + 500 * (i % 3)


def current(rng, mode, i, on):
    """Channel ``i``'s reading in regime ``mode``."""
    base = 300 + 100 * i
    if mode <= 2:  # steady load (most of the time)
        return base + rng.r(40) - 20 if on else rng.r(5)
    if mode == 3:  # noise
        return max(0, base + rng.r(3000) - 1500)
    if mode == 4:  # overload, 1.5 to 3 times rated
        return rated(i) * (15 + rng.r(15)) // 10 if on else 0
    if mode == 5:  # open load
        return rng.r(10)
    if mode == 6:  # the HAL's codes now and then
        return -1 - rng.r(3) if rng.r(3) == 0 else base
    if mode == 7:  # a current with the switch off (stuck on)
        return 800 + rng.r(100)
    return 40000 if rng.r(50) == 0 else base  # a spike now and then


def run(seed, batch, steady, ticks=TICKS):
    """(the first tick at which the two boards differ or -1, channel-ticks the pass took)."""
    rng = Rng(seed)
    cfg = {"channels": [{"name": "c%d" % i, "rated_ma": rated(i), "powerup": True,
                         "protected": i == N - 1} for i in range(N)],
           "board": {"powerup_spacing_ms": 0}}
    worlds = [World(batch), World(batch)]
    boards = [Board(w, cfg) for w in worlds]
    for b in boards:
        b.boot(0)
    mode = [0] * N
    taken = 0
    try:
        for t in range(ticks):
            for i in range(N):
                if rng.r(200) == 0:
                    mode[i] = rng.r(9)
                v = current(rng, mode[i], i, worlds[0].sw[i])
                g = rng.r(400) == 0
                for w in worlds:
                    w.cur[i] = v
                    w.glitch[i] = g
            if rng.r(100) == 0:  # a command, the same to both
                c, k = rng.r(N), rng.r(4)
                off_ms = 50 + rng.r(500)
                for b in boards:
                    if k == 0:
                        b.switch(c, True)
                    elif k == 1:
                        b.switch(c, False, force=True)
                    elif k == 2:
                        b.power_cycle(c, off_ms, force=True)
                    else:
                        b.clear(c)
            now = 10 * (t + 1)
            board_mod.steady = steady
            taken += sum(1 for ch in boards[0].channels if ch.hot[H_ARMED])
            boards[0].tick(now)
            board_mod.steady = full_step
            boards[1].tick(now)
            if snapshot(boards[0]) != snapshot(boards[1]):
                return t, taken
    finally:
        board_mod.steady = SHIPPED
    return -1, taken


class SteadyPassTest(unittest.TestCase):
    def test_the_steady_pass_leaves_every_channel_as_the_full_step_does(self):
        taken = 0
        for seed in (1, 2, 3):
            for batch in (True, False):
                differs, n = run(seed, batch, SHIPPED)
                self.assertEqual(differs, -1, "seed %d, batch %s: differs at tick %d"
                                 % (seed, batch, differs))
                taken += n
        # a good share of the channel-ticks went through the pass (a third: the world above
        # keeps channels out of the steady state much of the time), so the comparison is not
        # empty
        self.assertGreater(taken, 3 * 2 * TICKS * N // 5)

    def test_a_pass_that_forgets_a_sample_is_caught(self):
        differs, _ = run(1, True, forgetful, ticks=300)
        self.assertGreaterEqual(differs, 0)


if __name__ == "__main__":
    unittest.main()
