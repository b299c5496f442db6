"""A tiny HAL for the firmware tests: a simulated clock and ideal electronics set by the test.

``load_ma[ch]`` is what the channel draws while its switch is on; ``offset_ma[ch]`` is added to
every reading (a faulty current sensor); ``blind[ch]`` makes the sensor give no reading (-1,
a chip that does not answer); ``noise_ma[ch]`` adds zero-mean Gaussian noise of that standard
deviation to every reading, which never reads below 0 (as the emulator's ``sensor_noise``;
a fixed seed: the same samples on every run); ``stuck[ch]`` forces the switch (None = follows the
command, True = stuck on, False = stuck off). The same file runs
under CPython and MicroPython. ``Rig`` boots an ``App`` on it and steps it on simulated time.
"""

from firmware.app import App
from firmware.hal.storage import MemStorage
from protocol.constants import RESET_POWER_ON


class TestHal:
    def __init__(self, n=10, storage=None, cause=RESET_POWER_ON):
        self.n_channels = n
        self.now = 0
        self.load_ma = [0] * n
        self.offset_ma = [0] * n  # a current sensor's error: read even with the switch open
        self.stuck = [None] * n
        self.blind = [False] * n
        self.noise_ma = [0] * n
        self.seed = 12345
        self.cmd = [False] * n
        self.switch_log = []  # (now, ch, on) for every change of a command
        self.input_mv = 24000
        self.feeds = 0
        self.cause = cause
        self.storage = storage if storage is not None else MemStorage()
        self.rebooted = False

    def ticks_ms(self):
        return self.now

    def _on(self, ch):
        s = self.stuck[ch]
        return self.cmd[ch] if s is None else s

    def read_currents_ma(self, out):
        for ch in range(self.n_channels):
            out[ch] = self.read_current_ma(ch)

    def read_current_ma(self, ch):
        if self.blind[ch]:
            return -1
        v = (self.load_ma[ch] if self._on(ch) else 0) + self.offset_ma[ch]
        if self.noise_ma[ch]:
            v = int(v + self.noise_ma[ch] * self._gauss())
            return v if v > 0 else 0
        return v

    def _gauss(self):
        """About N(0, 1): twelve uniforms of a fixed LCG, less 6 (Irwin-Hall)."""
        s = 0
        for _ in range(12):
            self.seed = (self.seed * 1103515245 + 12345) & 0x7FFFFFFF
            s += self.seed
        return s / 0x80000000 - 6.0

    def set_switch(self, ch, on):
        if self.cmd[ch] != on:
            self.switch_log.append((self.now, ch, on))
        self.cmd[ch] = on

    def read_switch(self, ch):
        return self._on(ch)

    def read_input_mv(self):
        return self.input_mv

    def wdt_feed(self):
        self.feeds += 1

    def reset_cause(self):
        return self.cause

    def random_bytes(self, n):
        return bytes(n)

    def reboot(self):
        self.rebooted = True


class Rig:
    """A booted App on a TestHal; ``run(ms)`` steps it tick by tick on simulated time."""

    def __init__(self, channels=None, board=None, n=10, storage=None, cause=RESET_POWER_ON,
                 save=True, factory=None):
        self.hal = TestHal(n, storage, cause)
        if channels or board:
            from firmware import config

            cfg = config.defaults(n)
            cfg["board"].update(board or {})
            for i, c in (channels or {}).items():
                cfg["channels"][i].update(c)
            if save:
                config.save(self.hal.storage, cfg)
        self.app = App(self.hal, factory)
        self.app.start()
        self.board = self.app.board
        self.cursor = 0

    def run(self, ms):
        end = self.hal.now + ms
        while self.hal.now < end:
            self.hal.now = self.app.next_ms if self.app.next_ms > self.hal.now else self.hal.now
            if self.hal.now > end:
                self.hal.now = end
                break
            self.app.step()

    def run_until(self, pred, limit_ms):
        """Step until ``pred()`` is true; returns the simulated ms it took, or -1."""
        start = self.hal.now
        while self.hal.now - start <= limit_ms:
            if pred():
                return self.hal.now - start
            self.run(self.board.cfg["board"]["tick_ms"])
        return -1

    def state(self, ch):
        return self.board.channels[ch].state

    def events(self):
        evs, self.cursor, _ = self.board.events.read(self.cursor, 1000)
        return evs


def config_text(storage):
    """The newest stored copy of the configuration, as bytes (for tests that look inside)."""
    from firmware import config

    best = b""
    top = -1
    for name in config.SLOTS:
        data = storage.read(name)
        if data is not None:
            seq = config.parse_seq(data, 16)[2]
            if seq > top:
                best, top = data, seq
    return best
