"""Simulated electronics of one board: a load, a switch and a current sensor per channel.

Faults enter here, at the seams, as per-channel hooks (STYLE.md 8); nothing in the firmware
knows about them:

- ``Load``: what the device draws. After switch-on it decays linearly from ``inrush_peak_ma``
  to ``nominal_ma`` over ``inrush_ms``, plus Gaussian noise; it is *ready* after ``boot_ms``.
  Faults: ``overcurrent`` (a step to ``amps``), ``short`` (``SHORT_MA``), ``open_load`` (0 mA),
  ``dropout`` (0 mA for the first ``duty`` of every ``period_s``), ``drift`` (+``amps_per_s``
  since injection), ``hang`` (draws ``idle_ma``, never ready; a power-cycle cures it unless
  ``permanent``).
- ``SimSwitch``: follows the command unless ``stuck_on`` / ``stuck_off``.
- ``Sensor``: reads ``true·gain + offset + noise``, at least 0; ``sensor_offset``,
  ``sensor_gain``, ``sensor_noise``, ``sensor_stuck`` (freezes the last reading).

Time is the emulator's clock in ms, passed in.
"""

from __future__ import annotations

import random
from typing import Any

from emulator.model import LoadSpec

SHORT_MA = 40000  # a dead short behind a 40 A-capable high-side switch and wiring


class Load:
    def __init__(self, spec: LoadSpec, rng: random.Random) -> None:
        self.spec = spec
        self.rng = rng
        self.faults: dict[str, tuple[int, dict[str, Any]]] = {}  # name -> (since_ms, params)
        self.powered = False
        self.on_since = 0
        self.hung = False
        self.hung_permanent = False

    def power(self, on: bool, now: int) -> None:
        if on and not self.powered:
            self.on_since = now
            if self.hung and not self.hung_permanent:
                self.hung = False
        self.powered = on

    def inject(self, fault: str, params: dict[str, Any], now: int) -> None:
        self.faults[fault] = (now, params)
        if fault == "hang":
            self.hung = True
            self.hung_permanent = bool(params.get("permanent", False))

    def clear(self, fault: str | None = None) -> None:
        if fault is None:
            self.faults.clear()
        else:
            self.faults.pop(fault, None)
        if fault in (None, "hang"):
            self.hung = False
            self.hung_permanent = False

    def ready(self, now: int) -> bool:
        return (self.powered and not self.hung and "open_load" not in self.faults
                and "short" not in self.faults and now - self.on_since >= self.spec.boot_ms)

    def current_ma(self, now: int) -> float:
        if not self.powered:
            return 0.0
        f = self.faults
        if "short" in f:
            return float(SHORT_MA)
        if "open_load" in f:
            return 0.0
        if "dropout" in f:
            since, p = f["dropout"]
            period = p["period_s"] * 1000.0
            if ((now - since) % period) < p["duty"] * period:
                return 0.0
        s = self.spec
        t = now - self.on_since
        if self.hung:
            base = float(s.hung_ma)
        elif "overcurrent" in f:
            base = f["overcurrent"][1]["amps"] * 1000.0
        elif s.inrush_ms and t < s.inrush_ms and s.inrush_peak_ma > s.nominal_ma:
            base = s.inrush_peak_ma + (s.nominal_ma - s.inrush_peak_ma) * t / s.inrush_ms
        else:
            base = float(s.nominal_ma)
        if "drift" in f:
            since, p = f["drift"]
            base += p["amps_per_s"] * (now - since)  # A/s x ms = mA
        if s.noise_ma:
            base += self.rng.gauss(0.0, s.noise_ma)
        return max(0.0, base)


class SimSwitch:
    def __init__(self) -> None:
        self.command = False
        self.stuck: bool | None = None

    @property
    def closed(self) -> bool:
        return self.command if self.stuck is None else self.stuck


class Sensor:
    def __init__(self, rng: random.Random) -> None:
        self.rng = rng
        self.offset_ma = 0.0
        self.gain = 1.0
        self.noise_ma = 0.0
        self.stuck = False
        self.last = 0

    def read(self, true_ma: float) -> int:
        if self.stuck:
            return self.last
        v = true_ma * self.gain + self.offset_ma
        if self.noise_ma:
            v += self.rng.gauss(0.0, self.noise_ma)
        self.last = max(0, int(v))
        return self.last

    def clear(self) -> None:
        self.offset_ma = 0.0
        self.gain = 1.0
        self.noise_ma = 0.0
        self.stuck = False


class Electronics:
    """All channels plus the supply; ``inject``/``clear`` route a fault to its seam."""

    def __init__(self, loads: list[LoadSpec], input_mv: int, seed: int) -> None:
        self.rng = random.Random(seed)
        self.loads = [Load(s, self.rng) for s in loads]
        self.switches = [SimSwitch() for _ in loads]
        self.sensors = [Sensor(self.rng) for _ in loads]
        self.nominal_mv = input_mv
        self.input_mv = input_mv

    def set_switch(self, ch: int, on: bool, now: int) -> None:
        self.switches[ch].command = on
        self.loads[ch].power(self.switches[ch].closed, now)

    def release_all(self, now: int) -> None:
        """The microcontroller is in reset: every enable line falls, every switch opens."""
        for ch in range(len(self.switches)):
            self.set_switch(ch, False, now)

    def true_ma(self, ch: int, now: int) -> float:
        return self.loads[ch].current_ma(now)

    def read_ma(self, ch: int, now: int) -> int:
        return self.sensors[ch].read(self.true_ma(ch, now))

    def inject(self, ch: int, fault: str, params: dict[str, Any], now: int) -> None:
        sw = self.switches[ch]
        se = self.sensors[ch]
        if fault in ("stuck_on", "stuck_off"):
            sw.stuck = fault == "stuck_on"
            self.loads[ch].power(sw.closed, now)
        elif fault == "sensor_offset":
            se.offset_ma = params["amps"] * 1000.0
        elif fault == "sensor_gain":
            se.gain = params["factor"]
        elif fault == "sensor_noise":
            se.noise_ma = params["amps"] * 1000.0
        elif fault == "sensor_stuck":
            se.stuck = True
        else:
            self.loads[ch].inject(fault, params, now)

    def clear(self, ch: int, now: int) -> None:
        self.switches[ch].stuck = None
        self.loads[ch].power(self.switches[ch].closed, now)
        self.sensors[ch].clear()
        self.loads[ch].clear()
